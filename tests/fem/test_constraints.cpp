// The constraints object: chain resolution, cycles, double constraints, the stored
// constraint table of a small hanging-node mesh, and distribute/condense duality.
#include "fem/constraints.hpp"
#include "fem/quadtree.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

using namespace rsw;

TEST(Constraints, ChainedConstraintsResolveToFreeDofs) {
  // x3 = (x1 + x2)/2, x2 = (x0 + x4)/2, x0 = 2  =>  x3 = 0.5 x1 + 0.25 x4 + 0.5
  fem::Constraints c(5);
  c.add_line(3, {{1, 0.5}, {2, 0.5}});
  c.add_line(2, {{0, 0.5}, {4, 0.5}});
  c.constrain(0, 2.0);
  c.close();
  EXPECT_EQ(c.n_free(), 2);
  EXPECT_EQ(c.table(), "0: 2\n2: 1 + 0.5*x4\n3: 0.5 + 0.5*x1 + 0.25*x4\n");
  Eigen::VectorXd y(2);
  y << 10.0, 20.0;  // x1, x4
  const Eigen::VectorXd x = c.distribute(y);
  EXPECT_DOUBLE_EQ(x[0], 2.0);
  EXPECT_DOUBLE_EQ(x[2], 11.0);
  EXPECT_DOUBLE_EQ(x[3], 0.5 * 10 + 0.5 * 11);
}

TEST(Constraints, CycleIsAnError) {
  fem::Constraints c(3);
  c.add_line(0, {{1, 1.0}});
  c.add_line(1, {{0, 1.0}});
  EXPECT_THROW(c.close(), std::logic_error);
}

TEST(Constraints, ConstrainingADofTwiceIsAnErrorUnlessSameValue) {
  fem::Constraints c(3);
  c.constrain(1, 5.0);
  EXPECT_NO_THROW(c.constrain(1, 5.0));
  EXPECT_THROW(c.constrain(1, 6.0), std::logic_error);
  EXPECT_THROW(c.add_line(1, {{0, 1.0}}), std::logic_error);
}

TEST(Constraints, CondenseIsTheTransposeOfDistribute) {
  fem::Constraints c(4);
  c.add_line(2, {{0, 0.5}, {1, 0.5}});
  c.constrain(3, 1.0);
  c.close();
  // <P y, r> == <y, P^T r> for the homogeneous part.
  Eigen::VectorXd y(2), r(4);
  y << 0.7, -1.3;
  r << 1.0, 2.0, 3.0, 4.0;
  EXPECT_NEAR(c.distribute(y, true).dot(r), y.dot(c.condense(r)), 1e-14);
}

// Two base cells side by side, the right one refined once: one hanging node on the
// shared edge, the midpoint of nodes at (1, 0) and (1, 1). The expected table was
// derived by hand (node numbers follow the build order: leaves sorted by their
// lower-left corner) and is stored in tests/data.
TEST(Constraints, TableOfSmallHangingNodeMeshMatchesStoredFile) {
  fem::Quadtree tree(2, 1);
  tree.refine([](const fem::IndexBox& b) { return b.x0 >= 1 ? 1 : 0; });
  const fem::Mesh mesh = tree.build("m", [](double x, double y) { return fem::Point(x, y); },
                                    [](double, double, fem::Side) -> std::string { return "b"; });
  ASSERT_EQ(mesh.n_cells(), 5);
  fem::DofMap dofs(mesh, 2);
  fem::Constraints c(dofs.n_dofs());
  c.add_hanging_nodes(mesh, dofs);
  c.close();
  std::ostringstream nodes;
  for (int n = 0; n < mesh.n_nodes(); ++n) nodes << n << " " << mesh.nodes[n].x() << " " << mesh.nodes[n].y() << "\n";
  std::ifstream in(std::string(RSW_SOURCE_DIR) + "/tests/data/constraints_two_cells.txt");
  ASSERT_TRUE(in) << "missing tests/data/constraints_two_cells.txt";
  std::stringstream stored;
  stored << in.rdbuf();
  EXPECT_EQ("nodes:\n" + nodes.str() + "constraints:\n" + c.table(), stored.str());
}
