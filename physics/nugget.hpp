// Nugget geometry measured on the interpolated peak-temperature field (docs/MODEL.md, "Outputs").
//
// The nugget at an isotherm is the part of the sheets where the peak temperature
// reached so far is at or above the isotherm temperature of the sheet's material
// (liquidus or solidus). The field is the finite-element interpolant of the nodal
// peak temperatures, so the measured sizes move continuously with the parameters
// — never by counting elements. Sizes come from the points where the isotherm
// crosses cell edges (linear along each edge) and from the nodes inside the region:
// on a bilinear cell the largest radius and the z-extremes of a super-level set lie
// on the cell boundary, so these points are enough.
//   diameter   2 · max r of the region in the faying planes (d_n, m): on the faces
//              of the sheet/sheet interfaces, where a standard measures a spot
//              weld's fused area (AWS D8.1M:2013, "fused area": the area of the
//              nugget at the faying surface); 0 if the region does not reach them.
//              A mesh without sheet/sheet interfaces: 2 · max r over the region.
//   height     the region's extent along the axis r = 0 (h_n, m): the nugget's
//              thickness where a lens-shaped nugget is thickest, as a cross-section
//              is measured at the weld centre. Melt at the sheet surface beside the
//              electrode face's edge is not counted: it is apart from the nugget on
//              a macrograph, and counting it makes h_n jump where that melt appears
//              (docs/MODEL.md, "Outputs"). 0 if the region does not reach the axis
//              (a ring-shaped melt).
//   extent     max z − min z over the whole region (m), surface melt included: the
//              plausibility guard's "taller than the stack"
//   penetration into sheet k: the region's z-extent inside sheet k / thickness of k
//              on the axis; above 1 where the region spans the sheet off the axis,
//              where the indented sheet is thicker than on it (a nugget through
//              the sheet)
//   t_unmolt   the smaller distance, on the axis, from the region to the outer
//              surfaces of the top and bottom sheets (m); the stack's thickness
//              there if the region does not reach the axis
// Positions are those of the deformed configuration passed in.
#pragma once

#include "fem/mesh.hpp"

#include <string>
#include <vector>

namespace rsw::physics {

struct NuggetSize {
  double diameter = 0;             // m
  double height = 0;               // m, on the axis
  double extent = 0;               // m, over the whole region
  std::vector<double> penetration; // per sheet, fraction of its thickness
  double unmolten_thickness = 0;   // m, t_unmolt (sheet stack thickness if no nugget)
  bool empty = true;
};

// `sheet_bodies`: body indices of the sheets, top to bottom. `isotherm[b]`: the
// isotherm temperature (°C) of body b (ignored for non-sheet bodies). `peak` is nodal.
NuggetSize measure_nugget(const fem::Mesh& mesh, const std::vector<fem::Point>& positions,
                          const std::vector<double>& peak, const std::vector<int>& sheet_bodies,
                          const std::vector<double>& isotherm);

}  // namespace rsw::physics
