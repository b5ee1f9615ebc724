// Geometry and mesh settings of a spot-weld stack-up, in SI units (m, rad).
//
// Coordinate system: r >= 0 radial, z axial; z = 0 is the mid-height of the sheet
// stack, the upper electrode sits above (z > 0), the lower one below. All bodies
// start touching at the axis: the dome apex of each electrode touches the outer
// sheet surface at r = 0.
//
// Electrode profile (measured from the face apex, along the electrode axis, away
// from the sheets): spherical dome of radius `face_radius` for r <= face_diameter/2
// (sagitta s(r) = R - sqrt(R^2 - r^2)), then a conical flank whose included angle is
// `cone_angle` (120 deg: the flank rises 30 deg above the face plane) up to
// r = cap_diameter/2, then the cylindrical side up to `length`. A flat face has
// face_radius = 0 (read as infinite). The water-cooling bore is a cylinder of
// `bore_diameter` from `bore_depth` behind the face apex to the end face; a bore of
// diameter 0 means none. Defaults (paper §2.1, Verkens et al. 2024): cap 15.8 mm,
// face 5.5 mm, R30 dome, 120 deg cone, length 20 mm, bore 10 mm at 8 mm.
#pragma once

#include <string>
#include <vector>

namespace rsw::meshes {

struct ElectrodeGeometry {
  std::string material = "CuCrZr";
  double cap_diameter = 15.8e-3;   // m
  double face_diameter = 5.5e-3;   // m
  double face_radius = 30e-3;      // m, radius of curvature of the dome; 0 = flat face
  double cone_angle = 2.0943951023931953;  // rad, included angle of the flank cone (120 deg)
  double length = 20e-3;           // m, face apex to end face
  double bore_diameter = 10e-3;    // m, 0 = no cooling bore
  double bore_depth = 8e-3;        // m, face apex to bore bottom
};

struct Sheet {
  std::string name;                // body name, e.g. "sheet_1"
  std::string material = "DP1200";
  double thickness = 1e-3;         // m
};

// Cells whose (physical) bounding box overlaps the box are refined `levels` times
// below the base size.
struct RefinementBox {
  double r_min = 0, r_max = 0, z_min = 0, z_max = 0;  // m
  int levels = 0;
};

struct StackGeometry {
  std::vector<Sheet> sheets;       // top to bottom, 2 or 3 sheets
  double sheet_radius = 15e-3;     // m
  ElectrodeGeometry upper;
  ElectrodeGeometry lower;
  double stack_height() const {
    double h = 0;
    for (const auto& s : sheets) h += s.thickness;
    return h;
  }
};

struct MeshSettings {
  double base_size = 0.25e-3;      // m, edge of a level-0 cell
  // The weld zone box: r in [0, weld_zone_radius], z from `weld_zone_electrode_depth`
  // inside the lower electrode to the same depth inside the upper one. The paper
  // (§2.1) refines "a bounding box around the weld zone" without giving its size;
  // 3.5 mm reaches 0.6 mm beyond the widest nugget of the Table I prior (d_n,sol ≤
  // 5.8 mm) and 0.75 mm beyond the electrode face. On the paper's case the features
  // change by at most 0.07 % against a 4.5 mm × 1 mm box, while a 3 mm radius moves
  // S_end by 1.5 % (docs/MESHES.md, "The weld-zone box").
  double weld_zone_radius = 3.5e-3;           // m
  double weld_zone_electrode_depth = 0.5e-3;  // m
  int weld_zone_levels = 2;
  std::vector<RefinementBox> extra_boxes;     // further boxes, in stack coordinates
};

}  // namespace rsw::meshes
