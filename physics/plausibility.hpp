// Plausibility checks of a finished weld: results the solvers reached without
// complaint but that a welding engineer would question, reported as warnings
// (summary.json, results.h5, the study's run table), never as failures, so that a
// study or calibration keeps the run and its outputs stay continuous in the
// parameters. Each check compares one result with one physical bound:
//
//   nugget wider than the face      d_n,liq > the smaller electrode face diameter   [m]
//   melt taller than the stack      the liquidus region's whole height (nugget.hpp
//                                   `extent`, surface melt included) > the
//                                   undeformed sheet stack height                   [m]
//   penetration above 100 %         penetration of a sheet > 1 (nugget.hpp)         [1]
//   a sheet above boiling           a sheet's peak temperature > its material's
//                                   boiling point (melting.boiling_point, 1 atm)   [°C]
//
// The fifth guard, an electrode face at its solidus, is raised during the run where
// it first happens (weld_driver.cpp, solver.electrode_melting). A nugget wider than
// the face reaches beyond the pressed contact, where real welds risk expulsion (the
// default case's, 5.35 mm under a 5.5 mm face, stays inside this bound); a nugget
// through the whole stack or a boiling sheet is a burn-through. The model has no
// free surface, vapour or expulsion, so its outputs there are extrapolations
// (docs/MODEL.md, "Plausibility").
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace rsw::physics {

struct SheetPeak {
  std::string sheet;         // body name
  std::string material;      // material name
  double peak_temperature;   // °C, the sheet's highest temperature over the run
  double boiling_point;      // °C of its material; NaN: not known, not checked
};

struct WeldOutcome {
  double nugget_diameter = 0;   // m, d_n,liq
  double melt_extent = 0;       // m, the liquidus region's max z − min z
  std::vector<std::pair<std::string, double>> penetration;  // sheet name, fraction of its thickness
  std::vector<SheetPeak> sheets;
  double face_diameter = 0;     // m, the smaller of the two electrodes' faces
  double stack_height = 0;      // m, the undeformed sheets' total thickness
};

// One warning per bound the outcome passes, each naming the result, its value and
// the bound; empty for a plausible weld.
std::vector<std::string> plausibility_warnings(const WeldOutcome& outcome);

}  // namespace rsw::physics
