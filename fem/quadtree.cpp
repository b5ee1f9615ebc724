// Quadtree refinement, 2:1 balance and mesh construction; see quadtree.hpp.
#include "fem/quadtree.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <unordered_map>

namespace rsw::fem {

namespace {
constexpr int M = Quadtree::max_level;
constexpr std::int64_t fine(int level) { return std::int64_t{1} << (M - level); }
}  // namespace

Quadtree::Key Quadtree::key(int level, std::int64_t i, std::int64_t j) {
  return (static_cast<Key>(level) << 56) | (static_cast<Key>(i) << 28) | static_cast<Key>(j);
}

void Quadtree::unpack(Key k, int& level, std::int64_t& i, std::int64_t& j) {
  level = static_cast<int>(k >> 56);
  i = static_cast<std::int64_t>((k >> 28) & 0xFFFFFFF);
  j = static_cast<std::int64_t>(k & 0xFFFFFFF);
}

Quadtree::Quadtree(int n_x, int n_y, const std::function<bool(int, int)>& keep)
    : n_x_(n_x), n_y_(n_y) {
  if (n_x < 1 || n_y < 1 || (std::int64_t{n_x} << M) >= (1 << 28) || (std::int64_t{n_y} << M) >= (1 << 28))
    throw std::invalid_argument("Quadtree: base grid " + std::to_string(n_x) + " x " +
                                std::to_string(n_y) + " is empty or too large");
  for (int i = 0; i < n_x; ++i)
    for (int j = 0; j < n_y; ++j)
      if (!keep || keep(i, j)) leaves_.insert(key(0, i, j));
  if (leaves_.empty()) throw std::invalid_argument("Quadtree: every base cell was removed");
}

IndexBox Quadtree::box(Key k) const {
  int l;
  std::int64_t i, j;
  unpack(k, l, i, j);
  const double s = 1.0 / static_cast<double>(std::int64_t{1} << l);
  return {i * s, (i + 1) * s, j * s, (j + 1) * s};
}

bool Quadtree::find_leaf(std::int64_t X, std::int64_t Y, Key& leaf) const {
  if (X < 0 || Y < 0 || X >= (std::int64_t{n_x_} << M) || Y >= (std::int64_t{n_y_} << M)) return false;
  for (int l = 0; l <= M; ++l) {
    const Key k = key(l, X >> (M - l), Y >> (M - l));
    if (leaves_.count(k)) {
      leaf = k;
      return true;
    }
  }
  return false;
}

void Quadtree::split(Key k) {
  int l;
  std::int64_t i, j;
  unpack(k, l, i, j);
  if (l >= M) throw std::invalid_argument("Quadtree: refinement beyond level " + std::to_string(M));
  leaves_.erase(k);
  for (int di = 0; di < 2; ++di)
    for (int dj = 0; dj < 2; ++dj) leaves_.insert(key(l + 1, 2 * i + di, 2 * j + dj));
}

void Quadtree::refine(const std::function<int(const IndexBox&)>& target_level) {
  std::vector<Key> work(leaves_.begin(), leaves_.end());
  while (!work.empty()) {
    const Key k = work.back();
    work.pop_back();
    int l;
    std::int64_t i, j;
    unpack(k, l, i, j);
    if (l >= target_level(box(k))) continue;
    split(k);
    for (int di = 0; di < 2; ++di)
      for (int dj = 0; dj < 2; ++dj) work.push_back(key(l + 1, 2 * i + di, 2 * j + dj));
  }
}

void Quadtree::balance() {
  std::vector<Key> work(leaves_.begin(), leaves_.end());
  while (!work.empty()) {
    const Key k = work.back();
    work.pop_back();
    if (!leaves_.count(k)) continue;
    int l;
    std::int64_t i, j;
    unpack(k, l, i, j);
    const std::int64_t s = fine(l), X = i * s, Y = j * s;
    // One probe per side suffices: a neighbour coarser than this leaf spans the side.
    const std::int64_t probes[4][2] = {{X, Y - 1}, {X + s, Y}, {X, Y + s}, {X - 1, Y}};
    for (const auto& p : probes) {
      Key n;
      if (!find_leaf(p[0], p[1], n)) continue;
      int ln;
      std::int64_t in, jn;
      unpack(n, ln, in, jn);
      if (ln < l - 1) {
        split(n);
        for (int di = 0; di < 2; ++di)
          for (int dj = 0; dj < 2; ++dj) work.push_back(key(ln + 1, 2 * in + di, 2 * jn + dj));
        work.push_back(k);  // re-check this leaf against the new, finer neighbour
        break;
      }
    }
  }
}

Mesh Quadtree::build(const std::string& body, const Map& map, const BoundaryNamer& namer) const {
  // Deterministic order: leaves sorted by their lower-left fine corner, then level.
  struct Leaf {
    int level;
    std::int64_t X, Y, s;
  };
  std::vector<Leaf> leaves;
  leaves.reserve(leaves_.size());
  for (Key k : leaves_) {
    int l;
    std::int64_t i, j;
    unpack(k, l, i, j);
    leaves.push_back({l, i * fine(l), j * fine(l), fine(l)});
  }
  std::sort(leaves.begin(), leaves.end(), [](const Leaf& a, const Leaf& b) {
    return a.Y != b.Y ? a.Y < b.Y : a.X != b.X ? a.X < b.X : a.level < b.level;
  });

  Mesh mesh;
  mesh.body_names = {body};
  std::unordered_map<Key, int> node_id;  // fine-grid corner -> node
  auto corner_key = [](std::int64_t X, std::int64_t Y) { return key(0, X, Y); };
  std::vector<std::array<std::int64_t, 2>> node_fine;
  auto node_at = [&](std::int64_t X, std::int64_t Y) {
    auto [it, inserted] = node_id.emplace(corner_key(X, Y), static_cast<int>(node_fine.size()));
    if (inserted) node_fine.push_back({X, Y});
    return it->second;
  };
  for (const auto& c : leaves) {
    mesh.cells.push_back({node_at(c.X, c.Y), node_at(c.X + c.s, c.Y), node_at(c.X + c.s, c.Y + c.s),
                          node_at(c.X, c.Y + c.s)});
    mesh.cell_level.push_back(c.level);
    mesh.cell_body.push_back(0);
  }
  const int n_nodes = static_cast<int>(node_fine.size());
  mesh.node_body.assign(n_nodes, 0);

  // Hanging nodes: the midpoint of a leaf edge that is a node of a finer neighbour.
  // With 2:1 balance their parents are never hanging themselves, but positions are
  // still computed coarse edge first so that any chain would resolve.
  std::vector<std::int64_t> hang_edge(n_nodes, 0);
  for (std::size_t e = 0; e < leaves.size(); ++e) {
    const auto& c = leaves[e];
    if (c.s < 2) continue;
    const auto& nodes = mesh.cells[e];
    for (int f = 0; f < 4; ++f) {
      const auto& a = node_fine[nodes[f]];
      const auto& b = node_fine[nodes[(f + 1) % 4]];
      auto it = node_id.find(corner_key((a[0] + b[0]) / 2, (a[1] + b[1]) / 2));
      if (it == node_id.end() || hang_edge[it->second]) continue;
      hang_edge[it->second] = c.s;
      mesh.hanging_nodes.push_back({it->second, {nodes[f], nodes[(f + 1) % 4]}});
    }
  }
  std::sort(mesh.hanging_nodes.begin(), mesh.hanging_nodes.end(),
            [&](const HangingNode& a, const HangingNode& b) {
              return hang_edge[a.node] != hang_edge[b.node] ? hang_edge[a.node] > hang_edge[b.node]
                                                            : a.node < b.node;
            });

  const double to_index = 1.0 / static_cast<double>(fine(0));
  mesh.nodes.resize(n_nodes);
  for (int n = 0; n < n_nodes; ++n)
    if (!hang_edge[n]) mesh.nodes[n] = map(node_fine[n][0] * to_index, node_fine[n][1] * to_index);
  for (const auto& h : mesh.hanging_nodes)
    mesh.nodes[h.node] = 0.5 * (mesh.nodes[h.parents[0]] + mesh.nodes[h.parents[1]]);

  // Boundary faces: sides with no leaf beyond them. Local face f = side f before any
  // reorientation.
  std::map<std::string, std::vector<BoundaryFace>> faces;
  for (std::size_t e = 0; e < leaves.size(); ++e) {
    const auto& c = leaves[e];
    const std::int64_t probes[4][2] = {{c.X, c.Y - 1}, {c.X + c.s, c.Y}, {c.X, c.Y + c.s}, {c.X - 1, c.Y}};
    const double mids[4][2] = {{c.X + 0.5 * c.s, double(c.Y)},
                               {double(c.X + c.s), c.Y + 0.5 * c.s},
                               {c.X + 0.5 * c.s, double(c.Y + c.s)},
                               {double(c.X), c.Y + 0.5 * c.s}};
    for (int f = 0; f < 4; ++f) {
      Key n;
      if (find_leaf(probes[f][0], probes[f][1], n)) continue;
      const std::string name = namer(mids[f][0] * to_index, mids[f][1] * to_index, static_cast<Side>(f));
      if (!name.empty()) faces[body + "." + name].push_back({static_cast<int>(e), f});
    }
  }

  // Keep cells counter-clockwise in physical space: a mirroring map flips them.
  std::vector<char> flipped(mesh.cells.size(), 0);
  for (std::size_t e = 0; e < mesh.cells.size(); ++e) {
    auto& c = mesh.cells[e];
    double area2 = 0;
    for (int k = 0; k < 4; ++k) {
      const Point& p = mesh.nodes[c[k]];
      const Point& q = mesh.nodes[c[(k + 1) % 4]];
      area2 += p.x() * q.y() - q.x() * p.y();
    }
    if (area2 < 0) {
      c = {c[0], c[3], c[2], c[1]};
      flipped[e] = 1;
    }
  }
  for (auto& [name, list] : faces)
    for (auto& f : list)
      if (flipped[f.cell]) f.face = 3 - f.face;  // old side s is now face 3 - s
  mesh.boundaries = std::move(faces);
  return mesh;
}

}  // namespace rsw::fem
