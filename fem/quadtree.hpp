// Quadtree of a rectangular grid of base cells, refined locally, 2:1 balanced across
// edges, turned into an fem::Mesh through a caller-supplied mapping.
//
// Index space: base cell (i, j) covers [i, i+1] x [j, j+1]; a cell of level l is one
// of the 4^l children of a base cell, of edge 2^-l. `keep` removes base cells (holes,
// such as an electrode's cooling bore). `refine` splits leaves until each reaches the
// level its caller asks for; `balance` then splits leaves until edge neighbours differ
// by at most one level, so every hanging node is the midpoint of one coarse edge.
//
// `build` maps index space to physical (r, z) space: regular nodes go through the
// map; a hanging node is placed at the midpoint of the straight coarse edge it hangs
// on (so the coarse cell and its fine neighbours share a conforming edge, and the
// constraint u_h = (u_a + u_b)/2 reproduces every field that is linear along the
// edge). Cells are stored counter-clockwise in physical space whatever the map's
// orientation. Boundary faces (faces with no neighbour in the domain) are named by a
// caller-supplied function of the face's index-space midpoint and outward side.
#pragma once

#include "fem/mesh.hpp"

#include <cstdint>
#include <functional>
#include <string>
#include <unordered_set>
#include <vector>

namespace rsw::fem {

// Outward side of a face in index space.
enum class Side : int { bottom = 0, right = 1, top = 2, left = 3 };

// Axis-aligned box in index space (units of base cells).
struct IndexBox {
  double x0, x1, y0, y1;
};

class Quadtree {
 public:
  static constexpr int max_level = 8;

  Quadtree(int n_x, int n_y, const std::function<bool(int i, int j)>& keep = {});

  // Splits every leaf whose level is below target_level(leaf box); repeats on the
  // children. Levels above max_level are an error.
  void refine(const std::function<int(const IndexBox&)>& target_level);
  // Splits leaves until edge neighbours differ by at most one level.
  void balance();

  int n_leaves() const { return static_cast<int>(leaves_.size()); }
  int n_x() const { return n_x_; }
  int n_y() const { return n_y_; }

  using Map = std::function<Point(double x, double y)>;
  using BoundaryNamer = std::function<std::string(double x, double y, Side side)>;
  // One body: nodes, cells, levels, hanging nodes and boundaries named
  // "<body>.<name>" (faces whose namer returns "" stay unnamed).
  Mesh build(const std::string& body, const Map& map, const BoundaryNamer& namer) const;

 private:
  using Key = std::uint64_t;
  static Key key(int level, std::int64_t i, std::int64_t j);
  static void unpack(Key k, int& level, std::int64_t& i, std::int64_t& j);
  IndexBox box(Key k) const;
  // Leaf containing the finest-level unit cell whose lower-left corner is (X, Y);
  // returns false where (X, Y) is outside the domain.
  bool find_leaf(std::int64_t X, std::int64_t Y, Key& leaf) const;
  void split(Key k);

  int n_x_, n_y_;
  std::unordered_set<Key> leaves_;
};

}  // namespace rsw::fem
