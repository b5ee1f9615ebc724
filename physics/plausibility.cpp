// Plausibility checks of a finished weld; see plausibility.hpp.
#include "physics/plausibility.hpp"

#include <cmath>
#include <cstdio>

namespace rsw::physics {

namespace {
std::string format(const char* pattern, double a, double b) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, a, b);
  return text;
}
}  // namespace

std::vector<std::string> plausibility_warnings(const WeldOutcome& o) {
  std::vector<std::string> warnings;
  const std::string lead = "plausibility: ";
  if (o.nugget_diameter > o.face_diameter)
    warnings.push_back(lead + format("the nugget (d_n_liq %.2f mm) is wider than the electrode face (%.2f mm), "
                                     "where real welds risk expulsion (not modelled)",
                                     o.nugget_diameter * 1e3, o.face_diameter * 1e3));
  if (o.melt_extent > o.stack_height)
    warnings.push_back(lead + format("the melt (%.2f mm high, surface melt included) is taller than the sheet stack "
                                     "(%.2f mm)",
                                     o.melt_extent * 1e3, o.stack_height * 1e3));
  for (const auto& [sheet, fraction] : o.penetration)
    if (fraction > 1.0)
      warnings.push_back(lead + "the nugget penetrates " + sheet +
                         format(" by %.0f %% of its thickness (at most %.0f %%)", fraction * 100, 100.0));
  for (const SheetPeak& s : o.sheets)
    if (!std::isnan(s.boiling_point) && s.peak_temperature > s.boiling_point)
      warnings.push_back(lead + s.sheet +
                         format(" reaches %.0f degC, above the boiling point of its material (%.0f degC, ",
                                s.peak_temperature, s.boiling_point) +
                         s.material + "); the model has no evaporation");
  return warnings;
}

}  // namespace rsw::physics
