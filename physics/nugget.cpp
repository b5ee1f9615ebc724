// Nugget sizes from edge crossings of the isotherm; see nugget.hpp.
#include "physics/nugget.hpp"

#include "meshes/weld_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rsw::physics {

NuggetSize measure_nugget(const fem::Mesh& mesh, const std::vector<fem::Point>& x, const std::vector<double>& peak,
                          const std::vector<int>& sheet_bodies, const std::vector<double>& isotherm) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  NuggetSize out;
  const int n_sheets = static_cast<int>(sheet_bodies.size());
  std::vector<double> z_lo(n_sheets, inf), z_hi(n_sheets, -inf);
  double r_max = -inf, z_min = inf, z_max = -inf;
  double axis_min = inf, axis_max = -inf;  // the region's ends on the axis
  const auto on_axis = [&](int n) { return mesh.nodes[n].x() == 0.0; };

  auto take = [&](int k, const fem::Point& p, bool axis) {
    if (axis) {
      axis_min = std::min(axis_min, p.y());
      axis_max = std::max(axis_max, p.y());
    }
    r_max = std::max(r_max, p.x());
    z_min = std::min(z_min, p.y());
    z_max = std::max(z_max, p.y());
    z_lo[k] = std::min(z_lo[k], p.y());
    z_hi[k] = std::max(z_hi[k], p.y());
  };
  for (int e = 0; e < mesh.n_cells(); ++e) {
    const int body = mesh.cell_body[e];
    const auto it = std::find(sheet_bodies.begin(), sheet_bodies.end(), body);
    if (it == sheet_bodies.end()) continue;
    const int k = static_cast<int>(it - sheet_bodies.begin());
    const double iso = isotherm[body];
    const auto& c = mesh.cells[e];
    for (int a = 0; a < 4; ++a) {
      const int n1 = c[a], n2 = c[(a + 1) % 4];
      const double f1 = peak[n1] - iso, f2 = peak[n2] - iso;
      // An edge on the axis (both ends at r = 0 in the reference) is the only kind a
      // point of the axial height can lie on; the axis is a boundary, so it carries
      // no hanging node and both its ends are taken here.
      const bool axis_edge = on_axis(n1) && on_axis(n2);
      if (f1 >= 0) take(k, x[n1], axis_edge);
      if (axis_edge && f2 >= 0) take(k, x[n2], true);
      if ((f1 >= 0) != (f2 >= 0)) {  // the isotherm crosses this edge
        const double s = f1 / (f1 - f2);
        take(k, (1 - s) * x[n1] + s * x[n2], axis_edge);
      }
    }
  }
  // The diameter in the faying planes: the faces of both sides of every sheet/sheet
  // interface, the region's largest radius on them (nodes and crossings).
  double r_faying = -inf;
  bool faying_planes = false;
  for (const auto& [name, pair] : mesh.interfaces) {
    if (pair.kind != meshes::interface_kind::sheet_sheet) continue;
    faying_planes = true;
    for (const std::string& side : {pair.first, pair.second})
      for (const fem::BoundaryFace& face : mesh.boundary(side)) {
        const auto [n1, n2] = mesh.face_nodes(face);
        const double iso = isotherm[mesh.cell_body[face.cell]];
        const double f1 = peak[n1] - iso, f2 = peak[n2] - iso;
        if (f1 >= 0) r_faying = std::max(r_faying, x[n1].x());
        if (f2 >= 0) r_faying = std::max(r_faying, x[n2].x());
        if ((f1 >= 0) != (f2 >= 0)) r_faying = std::max(r_faying, x[n1].x() + f1 / (f1 - f2) * (x[n2].x() - x[n1].x()));
      }
  }
  out.penetration.assign(n_sheets, 0.0);
  if (r_max == -inf) {
    out.empty = true;
  } else {
    out.empty = false;
    out.diameter = faying_planes ? (r_faying > -inf ? 2 * r_faying : 0.0) : 2 * r_max;
    out.extent = z_max - z_min;
    out.height = axis_max > -inf ? axis_max - axis_min : 0.0;
  }

  // Sheet thicknesses and outer surfaces on the axis (deformed).
  std::vector<double> top(n_sheets, -inf), bottom(n_sheets, inf);
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const auto it = std::find(sheet_bodies.begin(), sheet_bodies.end(), mesh.node_body[n]);
    if (it == sheet_bodies.end() || mesh.nodes[n].x() != 0.0) continue;
    const int k = static_cast<int>(it - sheet_bodies.begin());
    top[k] = std::max(top[k], x[n].y());
    bottom[k] = std::min(bottom[k], x[n].y());
  }
  for (int k = 0; k < n_sheets; ++k)
    if (z_hi[k] > -inf) out.penetration[k] = (z_hi[k] - z_lo[k]) / (top[k] - bottom[k]);
  if (axis_max == -inf)  // no region on the axis: the whole stack there is solid
    out.unmolten_thickness = top.front() - bottom.back();
  else
    out.unmolten_thickness = std::max(0.0, std::min(top.front() - axis_max, axis_min - bottom.back()));
  return out;
}

}  // namespace rsw::physics
