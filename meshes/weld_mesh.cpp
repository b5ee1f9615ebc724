// Mapped quadtree meshes of electrodes and sheets; see weld_mesh.hpp.
#include "meshes/weld_mesh.hpp"

#include "fem/quadtree.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rsw::meshes {

namespace {

// Piecewise-uniform grid lines along one axis: segment k between breaks[k] and
// breaks[k+1] holds counts[k] equal cells. Index x in [0, n] maps to a coordinate.
struct GridLines {
  std::vector<double> breaks;
  std::vector<int> counts;

  GridLines(std::vector<double> points, double size) {
    std::sort(points.begin(), points.end());
    for (double p : points)
      if (breaks.empty() || p - breaks.back() > 1e-9) breaks.push_back(p);
    for (std::size_t k = 0; k + 1 < breaks.size(); ++k)
      counts.push_back(std::max(1, static_cast<int>(std::lround((breaks[k + 1] - breaks[k]) / size))));
  }
  int n() const {
    int s = 0;
    for (int c : counts) s += c;
    return s;
  }
  double coord(double x) const {
    double start = 0;
    for (std::size_t k = 0; k < counts.size(); ++k) {
      if (x <= start + counts[k] || k + 1 == counts.size())
        return breaks[k] + (x - start) / counts[k] * (breaks[k + 1] - breaks[k]);
      start += counts[k];
    }
    return breaks.back();
  }
};

double sagitta(double R, double r) { return R > 0 ? R - std::sqrt(R * R - r * r) : 0.0; }

double flank_slope(const ElectrodeGeometry& g) { return 1.0 / std::tan(0.5 * g.cone_angle); }

double bore_bottom(const ElectrodeGeometry& g) { return g.bore_diameter > 0 ? g.bore_depth : g.length; }

// Refinement level asked for a physical box. Boxes must overlap a cell by more than
// a nanometre: a box edge that coincides with a grid line (4.5 mm = 18 x 0.25 mm)
// must not refine the next cell because of rounding in the unit conversion.
int target_level(const std::vector<RefinementBox>& boxes, double r0, double r1, double z0, double z1) {
  constexpr double tol = 1e-9;  // m
  int level = 0;
  for (const auto& b : boxes)
    if (b.r_min < r1 - tol && r0 < b.r_max - tol && b.z_min < z1 - tol && z0 < b.z_max - tol)
      level = std::max(level, b.levels);
  return level;
}

std::function<int(const fem::IndexBox&)> refiner(const fem::Quadtree::Map& map,
                                                  const std::vector<RefinementBox>& boxes) {
  return [map, &boxes](const fem::IndexBox& b) {
    double r0 = 1e300, r1 = -1e300, z0 = 1e300, z1 = -1e300;
    for (double x : {b.x0, 0.5 * (b.x0 + b.x1), b.x1})
      for (double y : {b.y0, 0.5 * (b.y0 + b.y1), b.y1}) {
        const fem::Point p = map(x, y);
        r0 = std::min(r0, p.x());
        r1 = std::max(r1, p.x());
        z0 = std::min(z0, p.y());
        z1 = std::max(z1, p.y());
      }
    return target_level(boxes, r0, r1, z0, z1);
  };
}

}  // namespace

double electrode_profile(const ElectrodeGeometry& g, double r) {
  const double a = 0.5 * g.face_diameter;
  if (r <= a) return sagitta(g.face_radius, r);
  return sagitta(g.face_radius, a) + (r - a) * flank_slope(g);
}

double electrode_volume(const ElectrodeGeometry& g) {
  const double a = 0.5 * g.face_diameter, b = 0.5 * g.cap_diameter, R = g.face_radius;
  // ∫_0^a 2πr s(r) dr for the dome s(r) = R - sqrt(R^2 - r^2).
  const double dome = R > 0 ? M_PI * a * a * R - 2.0 * M_PI / 3.0 * (R * R * R - std::pow(R * R - a * a, 1.5)) : 0.0;
  // ∫_a^b 2πr (s(a) + m (r - a)) dr for the cone.
  const double s_a = sagitta(R, a), m = flank_slope(g);
  const double flank = 2.0 * M_PI * (s_a * (b * b - a * a) / 2 + m * (b * b * b - a * a * a) / 3 - m * a * (b * b - a * a) / 2);
  const double rb = 0.5 * g.bore_diameter;
  const double bore = g.bore_diameter > 0 ? M_PI * rb * rb * (g.length - g.bore_depth) : 0.0;
  return M_PI * b * b * g.length - dome - flank - bore;
}

void check_electrode(const ElectrodeGeometry& g, const char* which) {
  const std::string w = which;
  const double a = 0.5 * g.face_diameter, b = 0.5 * g.cap_diameter;
  if (!(a > 0 && a < b))
    throw std::invalid_argument(w + " electrode: face diameter must be > 0 and below the cap diameter");
  if (g.face_radius != 0 && g.face_radius < a)
    throw std::invalid_argument(w + " electrode: face radius must be at least half the face diameter (or 0 for flat)");
  if (!(g.cone_angle > 0 && g.cone_angle < M_PI))
    throw std::invalid_argument(w + " electrode: cone angle must lie in (0, 180) deg");
  if (g.bore_diameter < 0 || g.bore_diameter >= g.cap_diameter)
    throw std::invalid_argument(w + " electrode: bore diameter must be >= 0 and below the cap diameter");
  if (g.bore_diameter > 0 && !(g.bore_depth > 0 && g.bore_depth < g.length))
    throw std::invalid_argument(w + " electrode: bore depth must lie between 0 and the electrode length");
  if (!(electrode_profile(g, b) < bore_bottom(g)))
    throw std::invalid_argument(w + " electrode: the flank reaches " + std::to_string(electrode_profile(g, b) * 1e3) +
                                " mm from the face, beyond the bore bottom / length " +
                                std::to_string(bore_bottom(g) * 1e3) + " mm");
}

std::vector<RefinementBox> refinement_boxes(const StackGeometry& stack, const MeshSettings& settings) {
  const double half = 0.5 * stack.stack_height() + settings.weld_zone_electrode_depth;
  std::vector<RefinementBox> boxes{{0.0, settings.weld_zone_radius, -half, half, settings.weld_zone_levels}};
  boxes.insert(boxes.end(), settings.extra_boxes.begin(), settings.extra_boxes.end());
  return boxes;
}

// The contact surface of an electrode is its dome and the first millimetre of its flank
// (measured radially from the face edge): late in a weld the indentation can carry the
// sheet around the face edge, and a surface that ended there would let the sheet pass
// into the flank unseen, while the contact points of the edge cycle between sheet
// segments (design point 30 of the paper-mesh Table I study then stalls in the
// mechanics at 143 ms; docs/MECHANICS.md, "Contact"). Flank points out of contact
// carry nothing.
constexpr double flank_contact_width = 1e-3;  // m

fem::Mesh electrode_mesh(const ElectrodeGeometry& g, const std::string& body, double z_apex, int direction,
                         const MeshSettings& settings, const std::vector<RefinementBox>& boxes) {
  check_electrode(g, body.c_str());
  const double h = settings.base_size;
  const double a = 0.5 * g.face_diameter, b = 0.5 * g.cap_diameter, rb = 0.5 * g.bore_diameter;
  const double zb = bore_bottom(g);
  std::vector<double> r_points{0.0, a, b};
  if (rb > 0) r_points.push_back(rb);
  const GridLines radial(r_points, h);
  const GridLines axial(rb > 0 ? std::vector<double>{0.0, zb, g.length} : std::vector<double>{0.0, g.length}, h);

  auto local = [&](double x, double y) {
    const double rho = radial.coord(x), zeta = axial.coord(y);
    if (zeta >= zb) return fem::Point(rho, zeta);
    const double low = electrode_profile(g, rho);
    return fem::Point(rho, low + zeta * (1.0 - low / zb));
  };
  const fem::Quadtree::Map map = [&](double x, double y) {
    const fem::Point p = local(x, y);
    return fem::Point(p.x(), z_apex + direction * p.y());
  };
  auto in_bore = [&](double rho, double zeta) { return rb > 0 && rho < rb && zeta > zb; };

  fem::Quadtree tree(radial.n(), axial.n(), [&](int i, int j) {
    return !in_bore(radial.coord(i + 0.5), axial.coord(j + 0.5));
  });
  tree.refine(refiner(map, boxes));
  tree.balance();

  const double x_max = radial.n(), y_max = axial.n();
  return tree.build(body, map, [&](double x, double y, fem::Side side) -> std::string {
    switch (side) {
      case fem::Side::bottom: return radial.coord(x) < a + flank_contact_width ? "contact_face" : "flank";
      case fem::Side::right: return x >= x_max - 1e-9 ? "side" : "cooling_bore";
      case fem::Side::top: return y >= y_max - 1e-9 ? "end_face" : "cooling_bore";
      case fem::Side::left: return x <= 1e-9 ? "axis" : "cooling_bore";
    }
    return "";
  });
}

fem::Mesh sheet_mesh(const Sheet& sheet, double sheet_radius, double z_bottom, double z_top,
                     const std::vector<double>& radial_breaks, const MeshSettings& settings,
                     const std::vector<RefinementBox>& boxes) {
  std::vector<double> r_points{0.0, sheet_radius};
  for (double r : radial_breaks)
    if (r > 0 && r < sheet_radius) r_points.push_back(r);
  const GridLines radial(r_points, settings.base_size);
  const GridLines axial({z_bottom, z_top}, settings.base_size);
  const fem::Quadtree::Map map = [&](double x, double y) { return fem::Point(radial.coord(x), axial.coord(y)); };
  fem::Quadtree tree(radial.n(), axial.n());
  tree.refine(refiner(map, boxes));
  tree.balance();
  return tree.build(sheet.name, map, [](double, double, fem::Side side) -> std::string {
    switch (side) {
      case fem::Side::bottom: return "bottom";
      case fem::Side::right: return "edge";
      case fem::Side::top: return "top";
      case fem::Side::left: return "axis";
    }
    return "";
  });
}

fem::Mesh weld_mesh(const StackGeometry& stack, const MeshSettings& settings) {
  if (stack.sheets.size() < 2 || stack.sheets.size() > 3)
    throw std::invalid_argument("weld_mesh: a stack has 2 or 3 sheets, got " + std::to_string(stack.sheets.size()));
  if (!(settings.base_size > 0)) throw std::invalid_argument("weld_mesh: base size must be positive");
  const auto boxes = refinement_boxes(stack, settings);
  const double top = 0.5 * stack.stack_height();

  fem::Mesh mesh = electrode_mesh(stack.upper, "upper_electrode", top, +1, settings, boxes);
  const std::vector<double> breaks{0.5 * stack.upper.face_diameter, 0.5 * stack.lower.face_diameter};
  double z = top;
  std::vector<Sheet> sheets = stack.sheets;
  for (std::size_t k = 0; k < sheets.size(); ++k) {
    if (sheets[k].name.empty()) sheets[k].name = "sheet_" + std::to_string(k + 1);
    mesh.append(sheet_mesh(sheets[k], stack.sheet_radius, z - sheets[k].thickness, z, breaks, settings, boxes));
    z -= sheets[k].thickness;
  }
  mesh.append(electrode_mesh(stack.lower, "lower_electrode", -top, -1, settings, boxes));

  mesh.interfaces["es_upper"] = {"upper_electrode.contact_face", sheets.front().name + ".top",
                                 interface_kind::electrode_sheet};
  for (std::size_t k = 0; k + 1 < sheets.size(); ++k)
    mesh.interfaces["ss_" + std::to_string(k + 1) + "_" + std::to_string(k + 2)] = {
        sheets[k].name + ".bottom", sheets[k + 1].name + ".top", interface_kind::sheet_sheet};
  mesh.interfaces["es_lower"] = {"lower_electrode.contact_face", sheets.back().name + ".bottom",
                                 interface_kind::electrode_sheet};
  return mesh;
}

std::vector<int> mirror_bodies(const StackGeometry& stack, const fem::Mesh& mesh) {
  const auto same_electrode = [](const ElectrodeGeometry& a, const ElectrodeGeometry& b) {
    return a.material == b.material && a.cap_diameter == b.cap_diameter && a.face_diameter == b.face_diameter &&
           a.face_radius == b.face_radius && a.cone_angle == b.cone_angle && a.length == b.length &&
           a.bore_diameter == b.bore_diameter && a.bore_depth == b.bore_depth;
  };
  // Two sheets only: the interface laws treat the upper sheet of a sheet/sheet pair as
  // the slave side, so the two interfaces of three sheets are not each other's mirror
  // (slave and master swap), and the whole three-sheet stack is not symmetric.
  if (!same_electrode(stack.upper, stack.lower) || stack.sheets.size() != 2) return {};
  const std::size_t n = stack.sheets.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Sheet& a = stack.sheets[k];
    const Sheet& b = stack.sheets[n - 1 - k];
    if (a.material != b.material || a.thickness != b.thickness) return {};
  }
  std::vector<int> mirror(mesh.n_bodies());
  mirror[mesh.body_index("upper_electrode")] = mesh.body_index("lower_electrode");
  mirror[mesh.body_index("lower_electrode")] = mesh.body_index("upper_electrode");
  const auto name = [&](std::size_t k) {  // as weld_mesh names an unnamed sheet
    return stack.sheets[k].name.empty() ? "sheet_" + std::to_string(k + 1) : stack.sheets[k].name;
  };
  for (std::size_t k = 0; k < n; ++k) mirror[mesh.body_index(name(k))] = mesh.body_index(name(n - 1 - k));
  return mirror;
}

}  // namespace rsw::meshes
