// Nugget sizes from edge crossings of the isotherm; see nugget.hpp.
#include "physics/nugget.hpp"

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

  auto take = [&](int k, const fem::Point& p) {
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
      if (f1 >= 0) take(k, x[n1]);
      if ((f1 >= 0) != (f2 >= 0)) {  // the isotherm crosses this edge
        const double s = f1 / (f1 - f2);
        take(k, (1 - s) * x[n1] + s * x[n2]);
      }
    }
  }
  out.penetration.assign(n_sheets, 0.0);
  if (r_max == -inf) {
    out.empty = true;
  } else {
    out.empty = false;
    out.diameter = 2 * r_max;
    out.height = z_max - z_min;
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
  if (out.empty)
    out.unmolten_thickness = top.front() - bottom.back();
  else
    out.unmolten_thickness = std::max(0.0, std::min(top.front() - z_max, z_min - bottom.back()));
  return out;
}

}  // namespace rsw::physics
