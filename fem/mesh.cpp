// Mesh look-ups, merging and quality figures; see mesh.hpp.
#include "fem/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rsw::fem {

namespace {
std::string join_keys(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}
}  // namespace

int Mesh::body_index(const std::string& name) const {
  auto it = std::find(body_names.begin(), body_names.end(), name);
  if (it == body_names.end())
    throw std::out_of_range("unknown body '" + name + "'; bodies are: " + join_keys(body_names));
  return static_cast<int>(it - body_names.begin());
}

const std::vector<BoundaryFace>& Mesh::boundary(const std::string& name) const {
  auto it = boundaries.find(name);
  if (it == boundaries.end()) {
    std::vector<std::string> names;
    for (const auto& [k, v] : boundaries) names.push_back(k);
    throw std::out_of_range("unknown boundary '" + name + "'; boundaries are: " + join_keys(names));
  }
  return it->second;
}

std::array<int, 2> Mesh::face_nodes(const BoundaryFace& f) const {
  const auto& c = cells[f.cell];
  return {c[f.face], c[(f.face + 1) % 4]};
}

std::vector<int> Mesh::boundary_nodes(const std::string& name) const {
  std::vector<int> out;
  for (const auto& f : boundary(name)) {
    auto n = face_nodes(f);
    out.push_back(n[0]);
    out.push_back(n[1]);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void Mesh::append(const Mesh& other) {
  for (const auto& b : other.body_names)
    if (std::find(body_names.begin(), body_names.end(), b) != body_names.end())
      throw std::invalid_argument("Mesh::append: body '" + b + "' exists already");
  const int node_offset = n_nodes();
  const int cell_offset = n_cells();
  const int body_offset = n_bodies();
  nodes.insert(nodes.end(), other.nodes.begin(), other.nodes.end());
  for (auto c : other.cells) {
    for (auto& n : c) n += node_offset;
    cells.push_back(c);
  }
  for (int b : other.cell_body) cell_body.push_back(b + body_offset);
  cell_level.insert(cell_level.end(), other.cell_level.begin(), other.cell_level.end());
  for (int b : other.node_body) node_body.push_back(b + body_offset);
  body_names.insert(body_names.end(), other.body_names.begin(), other.body_names.end());
  for (auto h : other.hanging_nodes) {
    h.node += node_offset;
    h.parents[0] += node_offset;
    h.parents[1] += node_offset;
    hanging_nodes.push_back(h);
  }
  for (const auto& [name, faces] : other.boundaries) {
    if (boundaries.count(name))
      throw std::invalid_argument("Mesh::append: boundary '" + name + "' exists already");
    auto& dst = boundaries[name];
    for (auto f : faces) dst.push_back({f.cell + cell_offset, f.face});
  }
  for (const auto& [name, pair] : other.interfaces) interfaces[name] = pair;
}

double scaled_jacobian(const std::vector<Point>& positions, const std::array<int, 4>& cell) {
  double worst = 1.0;
  for (int k = 0; k < 4; ++k) {
    const Point& p = positions[cell[k]];
    const Point e_next = positions[cell[(k + 1) % 4]] - p;
    const Point e_prev = positions[cell[(k + 3) % 4]] - p;
    const double cross = e_next.x() * e_prev.y() - e_next.y() * e_prev.x();
    worst = std::min(worst, cross / (e_next.norm() * e_prev.norm()));
  }
  return worst;
}

double scaled_jacobian(const Mesh& mesh, int cell) { return scaled_jacobian(mesh.nodes, mesh.cells[cell]); }

MeshStats mesh_stats(const Mesh& mesh, int body) {
  MeshStats s;
  s.min_edge = s.min_scaled_jacobian = s.min_angle_deg = 1e300;
  s.max_edge = s.max_angle_deg = 0;
  std::vector<char> used(mesh.nodes.size(), 0);
  for (int e = 0; e < mesh.n_cells(); ++e) {
    if (body >= 0 && mesh.cell_body[e] != body) continue;
    ++s.n_cells;
    const auto& c = mesh.cells[e];
    for (int k = 0; k < 4; ++k) {
      used[c[k]] = 1;
      const Point& p = mesh.nodes[c[k]];
      const Point e_next = mesh.nodes[c[(k + 1) % 4]] - p;
      const Point e_prev = mesh.nodes[c[(k + 3) % 4]] - p;
      const double len = e_next.norm();
      s.min_edge = std::min(s.min_edge, len);
      s.max_edge = std::max(s.max_edge, len);
      const double cross = e_next.x() * e_prev.y() - e_next.y() * e_prev.x();
      const double angle = std::atan2(cross, e_next.dot(e_prev)) * 180.0 / M_PI;
      s.min_angle_deg = std::min(s.min_angle_deg, angle);
      s.max_angle_deg = std::max(s.max_angle_deg, angle < 0 ? 360.0 + angle : angle);
    }
    s.min_scaled_jacobian = std::min(s.min_scaled_jacobian, scaled_jacobian(mesh, e));
  }
  for (char u : used) s.n_nodes += u;
  for (const auto& h : mesh.hanging_nodes)
    if (body < 0 || mesh.node_body[h.node] == body) ++s.n_hanging;
  if (s.n_cells == 0) s.min_edge = s.min_scaled_jacobian = s.min_angle_deg = 0;
  return s;
}

}  // namespace rsw::fem
