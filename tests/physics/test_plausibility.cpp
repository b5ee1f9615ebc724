// The plausibility guard of a finished weld (physics/plausibility.hpp): each bound
// warns exactly when it is passed, naming the result, its value and the bound.
#include "physics/plausibility.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {
using rsw::physics::plausibility_warnings;
using rsw::physics::WeldOutcome;

// The default case's geometry (5.5 mm faces, two 1 mm sheets) with a sound nugget:
// 5.6 mm wide on the paper's mesh would be implausible, 5.0 mm is not.
WeldOutcome sound_weld() {
  WeldOutcome o;
  o.nugget_diameter = 5.0e-3;
  o.melt_extent = 1.8e-3;
  o.penetration = {{"sheet_1", 0.9}, {"sheet_2", 0.9}};
  o.sheets = {{"sheet_1", "DP1200", 2300, 2861}, {"sheet_2", "DP1200", 2300, 2861}};
  o.face_diameter = 5.5e-3;
  o.stack_height = 2.0e-3;
  return o;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }
}  // namespace

TEST(Plausibility, ASoundWeldRaisesNoWarning) { EXPECT_TRUE(plausibility_warnings(sound_weld()).empty()); }

TEST(Plausibility, ANuggetWiderThanTheFaceWarnsWithBothDiameters) {
  WeldOutcome o = sound_weld();
  o.nugget_diameter = 5.51e-3;
  const auto w = plausibility_warnings(o);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_TRUE(contains(w[0], "wider than the electrode face")) << w[0];
  EXPECT_TRUE(contains(w[0], "5.51 mm")) << w[0];
  EXPECT_TRUE(contains(w[0], "5.50 mm")) << w[0];
  o.nugget_diameter = 5.5e-3;  // as wide as the face: still held
  EXPECT_TRUE(plausibility_warnings(o).empty());
}

TEST(Plausibility, AMeltTallerThanTheStackWarns) {
  WeldOutcome o = sound_weld();
  o.melt_extent = 2.14e-3;
  const auto w = plausibility_warnings(o);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_TRUE(contains(w[0], "taller than the sheet stack (2.00 mm)")) << w[0];
  EXPECT_TRUE(contains(w[0], "2.14 mm")) << w[0];
}

TEST(Plausibility, PenetrationAboveOneHundredPercentWarnsPerSheet) {
  WeldOutcome o = sound_weld();
  o.penetration = {{"sheet_1", 1.35}, {"sheet_2", 1.0}};
  const auto w = plausibility_warnings(o);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_TRUE(contains(w[0], "penetrates sheet_1 by 135 %")) << w[0];
}

TEST(Plausibility, ASheetAboveItsBoilingPointWarnsAndAnUnknownBoilingPointIsNotChecked) {
  WeldOutcome o = sound_weld();
  o.sheets[1].peak_temperature = 2875;
  auto w = plausibility_warnings(o);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_TRUE(contains(w[0], "sheet_2 reaches 2875 degC")) << w[0];
  EXPECT_TRUE(contains(w[0], "2861 degC, DP1200")) << w[0];
  o.sheets[1].boiling_point = std::nan("");
  EXPECT_TRUE(plausibility_warnings(o).empty());
}

TEST(Plausibility, EveryPassedBoundWarnsOnceInAFixedOrder) {
  WeldOutcome o = sound_weld();
  o.nugget_diameter = 8.04e-3;
  o.melt_extent = 2.14e-3;
  o.penetration = {{"sheet_1", 1.35}, {"sheet_2", 1.35}};
  o.sheets[0].peak_temperature = o.sheets[1].peak_temperature = 5215;
  const auto w = plausibility_warnings(o);
  ASSERT_EQ(w.size(), 6u);
  EXPECT_TRUE(contains(w[0], "wider"));
  EXPECT_TRUE(contains(w[1], "taller"));
  EXPECT_TRUE(contains(w[2], "sheet_1 by"));
  EXPECT_TRUE(contains(w[3], "sheet_2 by"));
  EXPECT_TRUE(contains(w[4], "sheet_1 reaches"));
  EXPECT_TRUE(contains(w[5], "sheet_2 reaches"));
  for (const auto& text : w) EXPECT_EQ(text.rfind("plausibility: ", 0), 0u) << text;
}
