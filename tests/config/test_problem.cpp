// The weld case (physics/problem.hpp): the shipped paper cases load with the
// documented values in SI, overrides reach scalars, list items and tables, every
// relation between keys is checked with a message naming the key the user set, and
// docs/CONFIG.md is the current generated reference.
#include "physics/electro_thermal_step.hpp"
#include "physics/mechanics.hpp"
#include "physics/problem.hpp"
#include "physics/squeeze.hpp"
#include "physics/thermal.hpp"
#include "physics/weld_simulation.hpp"

#include "tests/config/test_files.hpp"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace rsw::physics {
namespace {

constexpr double pi = 3.14159265358979323846;
const std::string source_dir = RSW_SOURCE_DIR;
const std::string paper_case = source_dir + "/validation/paper_case/weld.yaml";
const std::string paper_nominal = source_dir + "/validation/paper_nominal/weld.yaml";

std::string write_case(const std::string& text) { return rsw::test::write_test_file("weld_case.yaml", text); }

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

template <class Action>
std::string error_of(Action action) {
  try {
    action();
  } catch (const fem::ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ConfigError thrown";
  return "";
}

std::string problem_error(const std::string& yaml, const std::vector<std::string>& sets = {}) {
  const std::string path = write_case(yaml);
  return error_of([&] { load_problem(path, sets); });
}

#define EXPECT_HAS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "missing '" << (part) << "' in: " << (text)

void expect_paper_electrode(const meshes::ElectrodeGeometry& e) {
  EXPECT_EQ(e.material, "CuCrZr");
  EXPECT_DOUBLE_EQ(e.cap_diameter, 15.8e-3);
  EXPECT_DOUBLE_EQ(e.face_diameter, 5.5e-3);
  EXPECT_DOUBLE_EQ(e.face_radius, 30e-3);
  EXPECT_NEAR(e.cone_angle, 2 * pi / 3, 1e-15);
  EXPECT_DOUBLE_EQ(e.length, 20e-3);
  EXPECT_DOUBLE_EQ(e.bore_diameter, 10e-3);
  EXPECT_DOUBLE_EQ(e.bore_depth, 8e-3);
}

TEST(Problem, PaperCaseGivesDocumentedValuesInSi) {
  const Problem p = load_problem(paper_case, {});
  EXPECT_EQ(p.name, "paper_case");

  ASSERT_EQ(p.geometry.sheets.size(), 2u);
  for (const auto& sheet : p.geometry.sheets) {
    EXPECT_EQ(sheet.material, "DP1200");
    EXPECT_DOUBLE_EQ(sheet.thickness, 1.0e-3);
  }
  EXPECT_DOUBLE_EQ(p.geometry.sheet_radius, 15e-3);
  expect_paper_electrode(p.geometry.upper);
  expect_paper_electrode(p.geometry.lower);

  EXPECT_DOUBLE_EQ(p.mesh.base_size, 0.25e-3);
  EXPECT_DOUBLE_EQ(p.mesh.weld_zone_radius, 3.5e-3);
  EXPECT_DOUBLE_EQ(p.mesh.weld_zone_electrode_depth, 0.5e-3);
  EXPECT_EQ(p.mesh.weld_zone_levels, 2);
  EXPECT_TRUE(p.mesh.extra_boxes.empty());

  EXPECT_EQ(p.schedule.current.time, (std::vector<double>{0.0, 0.010, 0.140, 0.150}));
  EXPECT_EQ(p.schedule.current.value, (std::vector<double>{0.0, 8000.0, 8000.0, 0.0}));
  EXPECT_EQ(p.schedule.force.time, (std::vector<double>{0.0, 0.160}));
  EXPECT_EQ(p.schedule.force.value, (std::vector<double>{3000.0, 3000.0}));
  EXPECT_DOUBLE_EQ(p.schedule.cool_time, 0.010);
  EXPECT_DOUBLE_EQ(p.schedule.end_time(), 0.160);

  for (const InterfaceContact& c : {p.contact.electrode_sheet, p.contact.sheet_sheet}) {
    EXPECT_DOUBLE_EQ(c.film_thickness, 7.0710678e-6);
    EXPECT_NEAR(c.film_thickness, std::sqrt(1e-7 * 5e-4), 1e-14 * 2);  // centre of [1e-4, 0.5] mm
    EXPECT_DOUBLE_EQ(c.coating_resistivity, 2.1e-6);
    EXPECT_DOUBLE_EQ(c.htc_p1, 1e-2);
  }
  EXPECT_DOUBLE_EQ(p.contact.htc_p2, 1e-6);
  EXPECT_DOUBLE_EQ(p.contact.htc_p3, 1.0);
  EXPECT_DOUBLE_EQ(p.contact.htc_p4, 1.0);
  EXPECT_DOUBLE_EQ(p.contact.friction_coefficient, 0.3);

  EXPECT_DOUBLE_EQ(p.thermal.initial_temperature, 20.0);
  EXPECT_DOUBLE_EQ(p.thermal.water_htc, 4e4);
  EXPECT_DOUBLE_EQ(p.thermal.water_temperature, 20.0);
  EXPECT_DOUBLE_EQ(p.thermal.air_htc, 20.0);
  EXPECT_DOUBLE_EQ(p.thermal.ambient_temperature, 20.0);
  EXPECT_DOUBLE_EQ(p.thermal.melt_conductivity, 117.5);

  EXPECT_EQ(p.output.directory, "results");
  EXPECT_DOUBLE_EQ(p.output.interval, 0.0);  // every step
  EXPECT_DOUBLE_EQ(p.output.field_interval, 0.005);
  EXPECT_TRUE(p.output.fields);
}

// Resource guards before anything is allocated. Cells: the weld zone's r–z area
// R (h_stack + 2 d) = 3.5 mm × 3 mm over the square of its edge 0.01 mm / 2⁴,
// 10.5 / (6.25e-4)² = 2.688e7, plus the rest of the sheets' (15 mm × 2 mm) and the
// caps' (2 × 7.9 mm × 20 mm) rectangles, 346 − 10.5 = 335.5 mm², over (0.01 mm)²:
// 3.355e6, in all 3.02e7, far above the default limit of 1e5; the message names the
// limit's key and the memory. Steps: output every 1e-6 ms over the 160 ms weld stage
// adds 1.6e8 to the 80 + 140 steps of the step sizes; the output interval is blamed.
TEST(Problem, CaseBeyondTheCellOrStepLimitIsRefusedNamingTheLimitKey) {
  const std::string cells = error_of([] {
    load_problem(paper_case, {"mesh.base_size=0.01 mm", "mesh.weld_zone.levels=4"});
  });
  EXPECT_HAS(cells, "about 3.02e+07 cells");
  EXPECT_HAS(cells, "solver.max_cells = 100000");
  EXPECT_HAS(cells, "GB of memory");
  EXPECT_NO_THROW(load_problem(paper_case, {"mesh.base_size=0.01 mm", "mesh.weld_zone.levels=4", "solver.max_cells=100000000"}));
  const std::string steps = error_of([] { load_problem(paper_case, {"output.interval=1e-6 ms"}); });
  EXPECT_EQ(steps.rfind("--set: output.interval", 0), 0u) << steps;
  EXPECT_HAS(steps, "up to 1.6e+08 time steps");
  EXPECT_HAS(steps, "solver.max_steps = 100000");
}

TEST(Problem, PaperCaseSpellsOutTheSchemaDefaults) {
  const std::string path = write_case("case: {name: paper_case}\n");
  EXPECT_EQ(load_problem(paper_case).resolved_config, load_problem(path).resolved_config);
}

// A key reaches its solver under one name with one default: the solver settings that
// mirror a key start at the schema's default, so a solver built without a case runs
// with the same value as the default case.
TEST(Problem, SolverSettingsMirroringAKeyStartAtItsSchemaDefault) {
  const physics::Problem defaults = physics::make_problem(fem::Config(physics::weld_case_schema()));
  const physics::MechanicsSettings mechanics;
  EXPECT_EQ(physics::case_default("solver.friction_penalty_ratio"), 0.1);
  EXPECT_EQ(mechanics.friction_penalty_ratio, defaults.solver.friction_penalty_ratio);
  EXPECT_EQ(mechanics.friction_coefficient, defaults.contact.friction_coefficient);
  EXPECT_EQ(mechanics.contact_penalty_factor, defaults.solver.contact_penalty_factor);
  EXPECT_EQ(mechanics.contact_smoothing, defaults.solver.contact_smoothing);
  EXPECT_EQ(mechanics.mechanics_tolerance, defaults.solver.mechanics_tolerance);
  EXPECT_EQ(mechanics.mechanics_error_estimate, defaults.solver.mechanics_error_estimate);
  const physics::ThermalSettings thermal;
  EXPECT_EQ(thermal.initial_temperature, defaults.thermal.initial_temperature);
  EXPECT_EQ(thermal.water_htc, defaults.thermal.water_htc);
  EXPECT_EQ(thermal.water_temperature, defaults.thermal.water_temperature);
  EXPECT_EQ(thermal.air_htc, defaults.thermal.air_htc);
  EXPECT_EQ(thermal.ambient_temperature, defaults.thermal.ambient_temperature);
  EXPECT_EQ(thermal.melt_conductivity, defaults.thermal.melt_conductivity);
  EXPECT_EQ(thermal.melt_conductivity_band, defaults.thermal.melt_conductivity_band);
  const physics::CouplingSettings coupling;
  EXPECT_EQ(coupling.acceleration_depth, defaults.solver.coupling_acceleration_depth);
  EXPECT_EQ(coupling.tolerance, defaults.solver.coupling_tolerance);
  EXPECT_EQ(coupling.max_iterations, defaults.solver.max_coupling_iterations);
  const physics::SqueezeSettings squeeze;
  EXPECT_EQ(squeeze.seat_step, defaults.solver.seat_step);
  EXPECT_EQ(squeeze.squeeze_force_steps, defaults.solver.squeeze_force_steps);
}

TEST(Problem, PaperNominalUsesThePapersContactValues) {
  const Problem p = load_problem(paper_nominal);
  EXPECT_EQ(p.name, "paper_nominal");
  for (const InterfaceContact& c : {p.contact.electrode_sheet, p.contact.sheet_sheet}) {
    EXPECT_DOUBLE_EQ(c.film_thickness, 1e-8);
    EXPECT_DOUBLE_EQ(c.coating_resistivity, 2.1e-6);
    EXPECT_DOUBLE_EQ(c.htc_p1, 5e-4);
  }
  EXPECT_DOUBLE_EQ(p.thermal.melt_conductivity, 35.0);
  expect_paper_electrode(p.geometry.upper);
  EXPECT_DOUBLE_EQ(p.schedule.current.at(0.075), 8000.0);
}

TEST(Problem, SheetsAreNamedTopToBottom) {
  const Problem p = load_problem(
      write_case("stack:\n  sheets:\n    - {material: DP600, thickness: 0.8 mm}\n"
                 "    - {thickness: 1.5 mm}\n    - {material: DX54, thickness: 0.7 mm}\n"));
  ASSERT_EQ(p.geometry.sheets.size(), 3u);
  EXPECT_EQ(p.geometry.sheets[0].name, "sheet_1");
  EXPECT_EQ(p.geometry.sheets[0].material, "DP600");
  EXPECT_EQ(p.geometry.sheets[1].name, "sheet_2");
  EXPECT_EQ(p.geometry.sheets[1].material, "DP1200");
  EXPECT_EQ(p.geometry.sheets[2].name, "sheet_3");
  EXPECT_DOUBLE_EQ(p.geometry.stack_height(), 3.0e-3);
}

TEST(Problem, ScheduleIsPiecewiseLinearAndHeldOutside) {
  const Problem p = load_problem(paper_case);
  EXPECT_NEAR(p.schedule.current.at(0.005), 4000.0, 1e-9);
  EXPECT_NEAR(p.schedule.current.at(0.145), 4000.0, 1e-9);
  EXPECT_DOUBLE_EQ(p.schedule.current.at(0.155), 0.0);
  EXPECT_DOUBLE_EQ(p.schedule.force.at(0.5), 3000.0);
}

// The step schedule of the paper's case (breakpoints at the 10 and 140 ms ramp ends
// and every 5 ms output): without an early phase 160 steps of 1 ms; with the default
// early phase of 0.25 ms steps to 20 ms, 20 / 0.25 = 80 steps there and 140 of 1 ms
// after, 220 in all.
TEST(Problem, EarlyPhaseHasItsOwnLargestStepAndEndsOnAStep) {
  const auto steps_of = [](const std::vector<double>& times, double from, double to, double& longest) {
    int n = 0;
    longest = 0;
    for (std::size_t k = 1; k < times.size(); ++k)
      if (times[k] > from + 1e-12 && times[k] <= to + 1e-12) {
        ++n;
        longest = std::max(longest, times[k] - times[k - 1]);
      }
    return n;
  };
  double longest = 0;
  EXPECT_EQ(weld_step_times(load_problem(paper_case, {"solver.early_phase_end=0 ms"})).size(), 161u);
  const auto times = weld_step_times(load_problem(paper_case));
  ASSERT_EQ(times.size(), 221u);
  EXPECT_EQ(steps_of(times, 0, 0.020, longest), 80);
  EXPECT_NEAR(longest, 0.25e-3, 1e-12);
  EXPECT_EQ(steps_of(times, 0.020, 0.160, longest), 140);
  EXPECT_NEAR(longest, 1e-3, 1e-12);
  EXPECT_NE(std::find_if(times.begin(), times.end(), [](double t) { return std::abs(t - 0.020) < 1e-12; }),
            times.end());
}

// The film breaks down over a band of the hotter side's temperature: 20-700 degC
// and switched on by default; a band that ends below its start is refused by key.
TEST(Problem, FilmBreakdownBandDefaultsAndAnInvertedBandIsRejected) {
  const Problem p = load_problem(paper_case);
  EXPECT_TRUE(p.contact.film_breakdown);
  EXPECT_DOUBLE_EQ(p.contact.film_breakdown_start, 20.0);
  EXPECT_DOUBLE_EQ(p.contact.film_breakdown_end, 700.0);
  EXPECT_FALSE(load_problem(paper_case, {"contact.film_breakdown=false"}).contact.film_breakdown);
  const std::string message = error_of([] {
    load_problem(paper_case, {"contact.film_breakdown_start=800 degC", "contact.film_breakdown_end=700 degC"});
  });
  EXPECT_HAS(message, "contact.film_breakdown_end");
  EXPECT_HAS(message, "contact.film_breakdown_start");
}

TEST(Problem, EarlyStepLongerThanTheStepIsRejectedNamingBoth) {
  const std::string message = error_of([] {
    load_problem(paper_case, {"solver.early_time_step=1 ms", "solver.time_step=0.5 ms", "solver.early_phase_end=20 ms"});
  });
  EXPECT_HAS(message, "solver.early_time_step");
  EXPECT_HAS(message, "solver.time_step");
}

TEST(Problem, SetOverridesScalarListItemAndTable) {
  const Problem p = load_problem(
      paper_case, {"stack.sheets[1].thickness=1.2 mm", "mesh.refinement_boxes[0].levels=3",
                   "schedule.current=[[0 ms, 0 kA], [10 ms, 9 kA], [190 ms, 9 kA], [200 ms, 0 kA]]",
                   "thermal.melt_conductivity=35", "electrodes.lower.face_radius=40 mm"});
  EXPECT_DOUBLE_EQ(p.geometry.sheets[1].thickness, 1.2e-3);
  EXPECT_DOUBLE_EQ(p.geometry.sheets[0].thickness, 1.0e-3);
  ASSERT_EQ(p.mesh.extra_boxes.size(), 1u);
  EXPECT_EQ(p.mesh.extra_boxes[0].levels, 3);
  EXPECT_DOUBLE_EQ(p.mesh.extra_boxes[0].r_max, 1e-3);
  EXPECT_DOUBLE_EQ(p.schedule.current.at(0.1), 9000.0);
  EXPECT_DOUBLE_EQ(p.schedule.end_time(), 0.210);
  EXPECT_DOUBLE_EQ(p.thermal.melt_conductivity, 35.0);
  EXPECT_DOUBLE_EQ(p.geometry.lower.face_radius, 40e-3);
  EXPECT_DOUBLE_EQ(p.geometry.upper.face_radius, 30e-3);
}

TEST(Problem, ResolvedConfigEchoesEveryKeyInDisplayUnits) {
  const Problem p = load_problem(paper_case, {"stack.sheets[1].thickness=1.2 mm"});
  EXPECT_HAS(p.resolved_config, "name: paper_case");
  EXPECT_HAS(p.resolved_config, "thickness: 1.2 mm");
  EXPECT_HAS(p.resolved_config, "cone_angle: 120 deg");
  EXPECT_HAS(p.resolved_config, "current: [[0 ms, 0 kA], [10 ms, 8 kA], [140 ms, 8 kA], [150 ms, 0 kA]]");
  EXPECT_HAS(p.resolved_config, "water_htc: 40000 W/(m^2*K)");
  EXPECT_HAS(p.resolved_config, "htc_p2: 1 um");
}

TEST(Problem, ResolvedConfigLoadsBackAsTheSameCase) {
  const Problem p = load_problem(paper_nominal, {"stack.sheets[2].thickness=0.7 mm",
                                                 "electrodes.lower.cone_angle=100 deg"});
  const Problem back = load_problem(write_case(p.resolved_config));
  EXPECT_EQ(back.resolved_config, p.resolved_config);
  EXPECT_EQ(back.contact.electrode_sheet.film_thickness, p.contact.electrode_sheet.film_thickness);
  EXPECT_EQ(back.geometry.lower.cone_angle, p.geometry.lower.cone_angle);
  EXPECT_EQ(back.geometry.sheets.size(), 3u);
}

// --- bad input through the weld schema ---------------------------------------------

TEST(Problem, FourSheetsAreRejectedWithCountAndLimits) {
  const std::string message =
      problem_error("stack:\n  sheets:\n    - {}\n    - {}\n    - {}\n    - {}\n");
  EXPECT_HAS(message, "weld_case.yaml:3:5: stack.sheets: 4 items given; allowed: 2 to 3 items");
}

TEST(Problem, SheetThicknessOutOfRangeNamesRange) {
  EXPECT_HAS(problem_error("stack:\n  sheets: [{thickness: 7 mm}, {}]\n"),
             "weld_case.yaml:2:24: stack.sheets[0].thickness: '7 mm' is out of range; allowed: [0.1, 5] mm");
}

TEST(Problem, CurrentInWrongUnitsNamesKinds) {
  EXPECT_HAS(problem_error("schedule:\n  current: [[0 ms, 0 kA], [10 ms, 8 kN]]\n"),
             "schedule.current[1][1] (current): '8 kN' is a force, not an electric current");
}

TEST(Problem, NonMonotoneScheduleNamesRow) {
  EXPECT_HAS(problem_error("schedule:\n  current: [[0 ms, 0 kA], [10 ms, 8 kA], [5 ms, 0 kA]]\n"),
             "weld_case.yaml:2:43: schedule.current[2][0] (time): '5 ms' does not come after the "
             "previous row's 10 ms; time must be strictly increasing");
}

TEST(Problem, ScheduleNotStartingAtZeroIsRejected) {
  EXPECT_HAS(problem_error("schedule:\n  force: [[5 ms, 3 kN], [160 ms, 3 kN]]\n"),
             "weld_case.yaml:2:11: schedule.force[0] = [5 ms, 3 kN]: the table must start at time 0 ms");
}

TEST(Problem, CurrentNotEndingAtZeroIsRejected) {
  EXPECT_HAS(problem_error("", {"schedule.current=[[0 ms, 0 kA], [10 ms, 8 kA]]"}),
             "--set: schedule.current[1] = [10 ms, 8 kA]: the current table must end at 0 kA");
}

TEST(Problem, FaceLargerThanCapNamesBothKeys) {
  const std::string message =
      problem_error("electrodes:\n  upper:\n    face_diameter: 16 mm\n");
  EXPECT_HAS(message, "weld_case.yaml:3:20: electrodes.upper.face_diameter = 16 mm: the face "
                      "diameter must be smaller than the cap diameter; "
                      "electrodes.upper.cap_diameter = 15.8 mm (default)");
}

TEST(Problem, CapShrunkBelowFaceBlamesTheKeyTheUserSet) {
  const std::string message = problem_error("", {"electrodes.lower.cap_diameter=5 mm"});
  EXPECT_HAS(message, "--set: electrodes.lower.cap_diameter = 5 mm: the face diameter must be "
                      "smaller than the cap diameter; electrodes.lower.face_diameter = 5.5 mm (default)");
}

TEST(Problem, BoreWiderThanCapIsRejected) {
  EXPECT_HAS(problem_error("", {"electrodes.upper.bore_diameter=16 mm", "electrodes.upper.cap_diameter=16 mm"}),
             "electrodes.upper.bore_diameter = 16 mm: the bore diameter must be smaller than the cap diameter");
}

TEST(Problem, BoreDeeperThanLengthIsRejected) {
  EXPECT_HAS(problem_error("", {"electrodes.upper.bore_depth=25 mm"}),
             "--set: electrodes.upper.bore_depth = 25 mm: the bore bottom must lie before the end face");
}

TEST(Problem, FlankTopBehindBoreBottomIsRejected) {
  const std::string message = problem_error("", {"electrodes.upper.cone_angle=60 deg"});
  EXPECT_HAS(message, "--set: electrodes.upper.cone_angle = 60 deg: the flank top lies 9.046 mm "
                      "behind the face apex (dome sagitta 0.1263 mm + cone rise 8.92 mm)");
  EXPECT_HAS(message, "the bore bottom must lie behind it; electrodes.upper.bore_depth = 8 mm (default)");
}

TEST(Problem, FlatFaceAndNoBoreAreAllowed) {
  const Problem p = load_problem(paper_case, {"electrodes.upper.face_radius=0", "electrodes.upper.bore_diameter=0",
                                              "electrodes.upper.cone_angle=60 deg"});
  EXPECT_DOUBLE_EQ(p.geometry.upper.face_radius, 0.0);
  EXPECT_DOUBLE_EQ(p.geometry.upper.bore_diameter, 0.0);
}

TEST(Problem, DomeRadiusBelowHalfFaceDiameterIsRejected) {
  EXPECT_HAS(problem_error("", {"electrodes.upper.face_radius=2 mm"}),
             "--set: electrodes.upper.face_radius = 2 mm: the dome radius must be 0 (flat face) or at "
             "least half the face diameter (2.75 mm)");
}

TEST(Problem, SheetRadiusInsideCapIsRejected) {
  EXPECT_HAS(problem_error("stack:\n  sheet_radius: 7 mm\n"),
             "weld_case.yaml:2:17: stack.sheet_radius = 7 mm: the sheet radius must be larger than "
             "the cap radius (7.9 mm)");
}

TEST(Problem, RefinementBoxWithEmptyRangeIsRejected) {
  const std::string message =
      problem_error("mesh:\n  refinement_boxes:\n    - {r_min: 2 mm, r_max: 1 mm}\n");
  EXPECT_HAS(message, "weld_case.yaml:3:15: mesh.refinement_boxes[0].r_min = 2 mm: r_min must be "
                      "smaller than r_max; mesh.refinement_boxes[0].r_max = 1 mm (");
  EXPECT_HAS(message, "weld_case.yaml:3:28)");
}

TEST(Problem, UnknownSectionKeySuggestsDeclaredKey) {
  EXPECT_HAS(problem_error("contact:\n  electrode_sheet:\n    film_thicknes: 1e-3 mm\n"),
             "weld_case.yaml:3:5: contact.electrode_sheet.film_thicknes: unknown key; did you mean "
             "'contact.electrode_sheet.film_thickness'?");
}

TEST(Problem, BadMaterialNameIsRejected) {
  EXPECT_HAS(problem_error("electrodes:\n  lower: {material: Cu/Cr}\n"),
             "electrodes.lower.material: 'Cu/Cr' is not a name");
}

TEST(Problem, EmptyOutputDirectoryIsRejected) {
  EXPECT_HAS(problem_error("output: {directory: ''}\n"),
             "output.directory = '': the output directory must not be empty");
}

// --- the generated reference -----------------------------------------------------

TEST(ConfigDocs, ReferenceIsUpToDate) {
  const std::string path = source_dir + "/docs/CONFIG.md";
  const std::string expected = weld_case_schema().to_markdown();
  const std::string actual = read_file(path);
  if (actual == expected) return;
  // Point at the first line that differs.
  std::istringstream want(expected);
  std::istringstream have(actual);
  std::string want_line;
  std::string have_line;
  int line = 1;
  while (std::getline(want, want_line)) {
    if (!std::getline(have, have_line) || have_line != want_line) break;
    ++line;
  }
  ADD_FAILURE() << path << " differs from the weld-case schema (first at line " << line
                << ": expected \"" << want_line << "\"); regenerate it with\n"
                << "    rsw config schema --format markdown > docs/CONFIG.md";
}

TEST(ConfigDocs, JsonSchemaDeclaresEveryKeyWithDoc) {
  const auto json = nlohmann::json::parse(weld_case_schema().to_json());
  ASSERT_GT(json["keys"].size(), 50u);
  for (const auto& key : json["keys"]) {
    EXPECT_FALSE(key["doc"].get<std::string>().empty()) << key["path"];
    EXPECT_TRUE(key.contains("default")) << key["path"];
  }
}

}  // namespace
}  // namespace rsw::physics
