// Quadtree invariants: 2:1 balance, hanging nodes at edge midpoints, interpolation
// across hanging edges, orientation under a mirroring map, boundary naming.
#include "fem/constraints.hpp"
#include "fem/dof_map.hpp"
#include "fem/quadtree.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

using namespace rsw;

namespace {
fem::Mesh refined_corner_mesh(const fem::Quadtree::Map& map) {
  fem::Quadtree tree(4, 3);
  tree.refine([](const fem::IndexBox& b) { return (b.x0 < 0.5 && b.y0 < 0.5) ? 3 : 0; });
  tree.balance();
  return tree.build("body", map, [](double, double, fem::Side s) -> std::string {
    return s == fem::Side::left ? "axis" : "outer";
  });
}
fem::Point identity(double x, double y) { return {x, y}; }
}  // namespace

TEST(Quadtree, BalancedMeshHasAtMostOneLevelJumpAcrossEdges) {
  const fem::Mesh mesh = refined_corner_mesh(identity);
  // Edge neighbours: cells sharing two nodes, or a cell edge containing a hanging node.
  std::map<std::pair<int, int>, std::vector<int>> edge_cells;
  for (int e = 0; e < mesh.n_cells(); ++e)
    for (int f = 0; f < 4; ++f) {
      int a = mesh.cells[e][f], b = mesh.cells[e][(f + 1) % 4];
      edge_cells[{std::min(a, b), std::max(a, b)}].push_back(e);
    }
  int max_jump = 0;
  for (const auto& h : mesh.hanging_nodes) {
    auto coarse = edge_cells[{std::min(h.parents[0], h.parents[1]), std::max(h.parents[0], h.parents[1])}];
    ASSERT_EQ(coarse.size(), 1u);
    for (int e = 0; e < mesh.n_cells(); ++e)
      for (int n : mesh.cells[e])
        if (n == h.node) max_jump = std::max(max_jump, mesh.cell_level[e] - mesh.cell_level[coarse[0]]);
  }
  EXPECT_EQ(max_jump, 1);
  EXPECT_GT(mesh.hanging_nodes.size(), 0u);
}

TEST(Quadtree, HangingNodeSitsAtMidpointOfItsCoarseEdge) {
  auto curved = [](double x, double y) { return fem::Point(x + 0.1 * std::sin(y), y + 0.05 * x * x); };
  const fem::Mesh mesh = refined_corner_mesh(curved);
  for (const auto& h : mesh.hanging_nodes) {
    const fem::Point mid = 0.5 * (mesh.nodes[h.parents[0]] + mesh.nodes[h.parents[1]]);
    EXPECT_LT((mesh.nodes[h.node] - mid).norm(), 1e-14);
  }
}

TEST(Quadtree, BilinearFieldIsExactAcrossHangingEdges) {
  // On axis-aligned cells f = a + b r + c z + d r z is linear along every edge, so the
  // hanging-node constraint (mean of the edge ends) must reproduce it exactly.
  const fem::Mesh mesh = refined_corner_mesh(identity);
  auto f = [](const fem::Point& p) { return 0.3 + 1.7 * p.x() - 0.4 * p.y() + 2.5 * p.x() * p.y(); };
  fem::DofMap dofs(mesh, 1);
  fem::Constraints c(dofs.n_dofs());
  c.add_hanging_nodes(mesh, dofs);
  c.close();
  Eigen::VectorXd full(mesh.n_nodes());
  for (int n = 0; n < mesh.n_nodes(); ++n) full[n] = f(mesh.nodes[n]);
  const Eigen::VectorXd back = c.distribute(c.restrict_to_free(full));
  for (const auto& h : mesh.hanging_nodes) EXPECT_NEAR(back[h.node], f(mesh.nodes[h.node]), 1e-14);
  EXPECT_LT((back - full).lpNorm<Eigen::Infinity>(), 1e-14);
}

TEST(Quadtree, MirroringMapKeepsCellsCounterClockwise) {
  const fem::Mesh mesh = refined_corner_mesh([](double x, double y) { return fem::Point(x, -y); });
  for (int e = 0; e < mesh.n_cells(); ++e) EXPECT_GT(fem::scaled_jacobian(mesh, e), 0.99);
  // The axis faces still lie on x = 0 after reorientation.
  for (const auto& f : mesh.boundary("body.axis")) {
    auto n = mesh.face_nodes(f);
    EXPECT_EQ(mesh.nodes[n[0]].x(), 0.0);
    EXPECT_EQ(mesh.nodes[n[1]].x(), 0.0);
  }
}

TEST(Quadtree, BoundaryFacesCoverTheOutlineOnce) {
  const fem::Mesh mesh = refined_corner_mesh(identity);
  double axis_length = 0, outer_length = 0;
  for (const auto& f : mesh.boundary("body.axis")) {
    auto n = mesh.face_nodes(f);
    axis_length += (mesh.nodes[n[1]] - mesh.nodes[n[0]]).norm();
  }
  for (const auto& f : mesh.boundary("body.outer")) {
    auto n = mesh.face_nodes(f);
    outer_length += (mesh.nodes[n[1]] - mesh.nodes[n[0]]).norm();
  }
  EXPECT_NEAR(axis_length, 3.0, 1e-14);
  EXPECT_NEAR(outer_length, 4.0 + 3.0 + 4.0, 1e-14);
}

TEST(Quadtree, RemovedBaseCellsLeaveAHoleWithABoundary) {
  fem::Quadtree tree(3, 3, [](int i, int j) { return !(i == 1 && j == 1); });
  EXPECT_EQ(tree.n_leaves(), 8);
  const fem::Mesh mesh = tree.build("ring", identity, [](double x, double y, fem::Side) -> std::string {
    return (x > 0.5 && x < 2.5 && y > 0.5 && y < 2.5) ? "hole" : "outside";
  });
  EXPECT_EQ(mesh.boundary("ring.hole").size(), 4u);
  EXPECT_EQ(mesh.boundary("ring.outside").size(), 12u);
}
