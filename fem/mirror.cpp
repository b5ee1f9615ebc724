// Mirror symmetry about z = 0: node and cell images, constraints, term weights; see
// mirror.hpp.
#include "fem/mirror.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>

namespace rsw::fem {

int MirrorSymmetry::n_images() const {
  int n = 0;
  for (std::size_t i = 0; i < image_of.size(); ++i) n += is_image(static_cast<int>(i));
  return n;
}

double MirrorSymmetry::weight(const std::vector<int>& nodes) const {
  if (empty()) return 1.0;
  bool source = false, image = false;
  for (int n : nodes) {
    if (image_of[n] < 0) source = true;
    else if (image_of[n] != n) image = true;
  }
  if (!source && !image) return 0.5;  // on the plane only: its own mirror
  return !image ? 1.0 : !source ? 0.0 : 0.5;
}

MirrorSymmetry find_mirror_symmetry(const Mesh& mesh, const std::vector<int>& body_mirror, double tolerance) {
  if (static_cast<int>(body_mirror.size()) != mesh.n_bodies())
    throw std::invalid_argument("find_mirror_symmetry: one mirror body per body expected");
  for (int b = 0; b < mesh.n_bodies(); ++b)
    if (body_mirror[b] < 0 || body_mirror[b] >= mesh.n_bodies() || body_mirror[body_mirror[b]] != b)
      throw std::invalid_argument("find_mirror_symmetry: body_mirror must pair the bodies");
  if (!(tolerance > 0)) throw std::invalid_argument("find_mirror_symmetry: the tolerance must be positive");

  // Nodes by body and position, on a grid of the tolerance.
  using Key = std::tuple<int, long long, long long>;
  std::map<Key, std::vector<int>> grid;
  auto cell_of = [tolerance](double v) { return std::llround(v / tolerance); };
  std::vector<double> z_sum(mesh.n_bodies(), 0.0);
  std::vector<int> count(mesh.n_bodies(), 0);
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const Point& x = mesh.nodes[n];
    grid[{mesh.node_body[n], cell_of(x.x()), cell_of(x.y())}].push_back(n);
    z_sum[mesh.node_body[n]] += x.y();
    ++count[mesh.node_body[n]];
  }
  auto find = [&](int body, const Point& x) {
    for (long long i = -1; i <= 1; ++i)
      for (long long j = -1; j <= 1; ++j) {
        auto it = grid.find({body, cell_of(x.x()) + i, cell_of(x.y()) + j});
        if (it == grid.end()) continue;
        for (int m : it->second)
          if ((mesh.nodes[m] - x).lpNorm<Eigen::Infinity>() <= tolerance) return m;
      }
    return -1;
  };

  MirrorSymmetry s;
  s.image_of.assign(mesh.n_nodes(), -1);
  std::vector<int> image_count(mesh.n_nodes(), 0);
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const int b = mesh.node_body[n];
    const int m = body_mirror[b];
    const Point& x = mesh.nodes[n];
    const bool lower_body = m != b && z_sum[b] * count[m] < z_sum[m] * count[b];  // lower mean z
    if (m == b && std::abs(x.y()) <= tolerance) {
      s.image_of[n] = n;
    } else if (lower_body || (m == b && x.y() < 0)) {
      const int source = find(m, Point(x.x(), -x.y()));
      if (source < 0) return {};
      s.image_of[n] = source;
      ++image_count[source];
    }
  }
  // A bijection: every node of an upper body is the source of exactly one image.
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    if (s.image_of[n] >= 0) continue;
    const int b = mesh.node_body[n];
    if (image_count[n] != 1 && (body_mirror[b] != b || mesh.nodes[n].y() > tolerance)) return {};
  }
  // Hanging nodes: the source of a hanging image hangs between the parents' sources.
  std::vector<int> hanging_index(mesh.n_nodes(), -1);
  for (std::size_t i = 0; i < mesh.hanging_nodes.size(); ++i) hanging_index[mesh.hanging_nodes[i].node] = static_cast<int>(i);
  auto source_of = [&](int n) { return s.image_of[n] >= 0 ? s.image_of[n] : n; };
  for (const auto& h : mesh.hanging_nodes) {
    if (!s.is_image(h.node)) continue;
    const int i = hanging_index[s.image_of[h.node]];
    if (i < 0) return {};
    const auto& parents = mesh.hanging_nodes[i].parents;
    if (std::set<int>{source_of(h.parents[0]), source_of(h.parents[1])} != std::set<int>{parents[0], parents[1]})
      return {};
  }
  // Cells: the mirror images of a cell's nodes are the nodes of one cell (of the cell
  // itself where the plane cuts it).
  std::vector<int> mirror_of(mesh.n_nodes());
  for (int n = 0; n < mesh.n_nodes(); ++n) mirror_of[n] = source_of(n);
  for (int n = 0; n < mesh.n_nodes(); ++n)
    if (s.is_image(n)) mirror_of[s.image_of[n]] = n;
  std::map<std::array<int, 4>, int> cell_by_nodes;
  for (int c = 0; c < mesh.n_cells(); ++c) {
    std::array<int, 4> key = mesh.cells[c];
    std::sort(key.begin(), key.end());
    cell_by_nodes[key] = c;
  }
  s.cell_source.assign(mesh.n_cells(), -1);
  for (int c = 0; c < mesh.n_cells(); ++c) {
    std::array<int, 4> key;
    for (int a = 0; a < 4; ++a) key[a] = mirror_of[mesh.cells[c][a]];
    std::sort(key.begin(), key.end());
    auto it = cell_by_nodes.find(key);
    if (it == cell_by_nodes.end()) return {};
    if (s.weight({mesh.cells[c].begin(), mesh.cells[c].end()}) == 0.0) s.cell_source[c] = it->second;
  }
  return s;
}

bool are_images(const MirrorSymmetry& mirror, const std::vector<int>& images, const std::vector<int>& sources) {
  if (mirror.empty() || images.size() != sources.size()) return false;
  for (int n : images)
    if (!mirror.is_image(n) || !std::binary_search(sources.begin(), sources.end(), mirror.image_of[n])) return false;
  return true;  // an injective map between sets of one size
}

void add_mirror_constraints(Constraints& constraints, const Mesh& mesh, const DofMap& dofs,
                            const MirrorSymmetry& mirror, const std::vector<double>& sign) {
  if (mirror.empty()) return;
  if (static_cast<int>(sign.size()) != dofs.n_components())
    throw std::invalid_argument("add_mirror_constraints: one sign per field component expected");
  std::vector<char> hanging(mesh.n_nodes(), 0);
  for (const auto& h : mesh.hanging_nodes) hanging[h.node] = 1;
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const int source = mirror.image_of[n];
    if (source < 0 || hanging[n]) continue;
    for (int k = 0; k < dofs.n_components(); ++k) {
      if (source == n) {
        if (sign[k] < 0) constraints.constrain(dofs.dof(n, k), 0.0);
      } else {
        constraints.add_line(dofs.dof(n, k), {{dofs.dof(source, k), sign[k]}});
      }
    }
  }
}

}  // namespace rsw::fem
