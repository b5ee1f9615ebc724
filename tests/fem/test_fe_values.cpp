// Q1 values: Gauss rules, shape function derivatives against finite differences,
// the axisymmetric measure (volumes and areas of revolution), and the cached
// Gauss-point geometry of a mesh (fem::CellGeometry).
#include "fem/fe_values.hpp"
#include "fem/quadtree.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace rsw;

TEST(GaussLegendre, RuleOfNPointsIntegratesDegree2NMinus1Exactly) {
  for (int n = 1; n <= 5; ++n) {
    const auto rule = fem::gauss_legendre(n);
    for (int p = 0; p <= 2 * n - 1; ++p) {
      double sum = 0;
      for (int q = 0; q < n; ++q) sum += rule.weights[q] * std::pow(rule.points[q], p);
      const double exact = (p % 2) ? 0.0 : 2.0 / (p + 1);
      EXPECT_NEAR(sum, exact, 1e-14) << "n = " << n << ", degree " << p;
    }
  }
  EXPECT_THROW(fem::gauss_legendre(6), std::invalid_argument);
}

TEST(ShapeFunctions, PartitionOfUnityAndGradientsMatchFiniteDifferences) {
  const double xi = 0.3, eta = -0.55, d = 1e-6;
  const auto N = fem::shape_values(xi, eta);
  EXPECT_NEAR(N[0] + N[1] + N[2] + N[3], 1.0, 1e-15);
  const auto g = fem::shape_gradients_ref(xi, eta);
  const auto Nx = fem::shape_values(xi + d, eta), Nxm = fem::shape_values(xi - d, eta);
  const auto Ny = fem::shape_values(xi, eta + d), Nym = fem::shape_values(xi, eta - d);
  for (int a = 0; a < 4; ++a) {
    EXPECT_NEAR(g[a].x(), (Nx[a] - Nxm[a]) / (2 * d), 1e-9);
    EXPECT_NEAR(g[a].y(), (Ny[a] - Nym[a]) / (2 * d), 1e-9);
  }
}

namespace {
fem::Mesh one_cell(const std::array<fem::Point, 4>& x) {
  fem::Mesh m;
  m.nodes.assign(x.begin(), x.end());
  m.cells = {{0, 1, 2, 3}};
  m.cell_body = {0};
  m.cell_level = {0};
  m.node_body = {0, 0, 0, 0};
  m.body_names = {"cell"};
  return m;
}
}  // namespace

TEST(CellValues, PhysicalGradientsOfAffineFieldAreExactOnDistortedCell) {
  const fem::Mesh m = one_cell({fem::Point(0.1, 0.0), fem::Point(1.2, 0.2), fem::Point(1.0, 1.1), fem::Point(0.2, 0.8)});
  fem::CellValues fv(2);
  fv.reinit(m, 0);
  for (int q = 0; q < fv.n_q(); ++q) {
    Eigen::Vector2d g = Eigen::Vector2d::Zero();
    for (int a = 0; a < 4; ++a) g += (3.0 * m.nodes[a].x() - 2.0 * m.nodes[a].y()) * fv.grad_N(q, a);
    EXPECT_NEAR(g.x(), 3.0, 1e-13);
    EXPECT_NEAR(g.y(), -2.0, 1e-13);
  }
}

// The Gauss-point geometry cache holds what CellValues gives on the positions of its
// last update, and follows the positions when they change.
TEST(CellGeometry, HoldsTheCellValuesOfTheLastPositions) {
  const fem::Mesh m = one_cell({fem::Point(0.1, 0.0), fem::Point(1.2, 0.2), fem::Point(1.0, 1.1), fem::Point(0.2, 0.8)});
  fem::CellGeometry geometry(m, 2);
  ASSERT_EQ(geometry.n_q(), 4);
  std::vector<fem::Point> moved = m.nodes;
  for (auto& x : moved) x = 1.5 * x + fem::Point(0.3, -0.1);
  for (const auto& positions : {m.nodes, moved, moved}) {
    geometry.update(positions);
    fem::Mesh current = m;
    current.nodes = positions;
    fem::CellValues cv(2);
    cv.reinit(current, 0);
    EXPECT_EQ(geometry.current().nodes, positions);
    for (int q = 0; q < cv.n_q(); ++q) {
      EXPECT_EQ(geometry.JxW()[q], cv.JxW(q));
      for (int a = 0; a < 4; ++a) {
        EXPECT_EQ(geometry.grad()[4 * q + a], cv.grad_N(q, a));
        EXPECT_EQ(geometry.shape()[q][a], cv.N(q, a));
      }
    }
  }
}

TEST(CellValues, InvertedCellIsReportedByNumber) {
  const fem::Mesh m = one_cell({fem::Point(0, 0), fem::Point(0, 1), fem::Point(1, 1), fem::Point(1, 0)});
  fem::CellValues fv(2);
  try {
    fv.reinit(m, 0);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cell 0"), std::string::npos);
  }
}

// The unit square with its third corner pulled in to (0.45, 0.45), past the diagonal:
// an arrowhead whose bilinear map folds over that corner. Corner cross products
// (e_next × e_prev) are 1, 0.45, −0.10, 0.45; det J is linear in (ξ, η) with those
// corner values over 4, so at the 2×2 Gauss points it is positive (the one nearest
// the fold: (0.0447·1 + 0.1667·0.9 − 0.622·0.10)/4 > 0) and the quadrature does not
// notice. The scaled Jacobian does: −0.10/|(−0.45, 0.55)|² = −0.198.
TEST(CellValues, FoldedCornerPassesTheQuadraturePointsButNotTheScaledJacobian) {
  const fem::Mesh m = one_cell({fem::Point(0, 0), fem::Point(1, 0), fem::Point(0.45, 0.45), fem::Point(0, 1)});
  fem::CellValues fv(2, fem::CoordinateSystem::planar);
  EXPECT_NO_THROW(fv.reinit(m, 0));
  EXPECT_NEAR(fem::scaled_jacobian(m, 0), -0.10 / 0.505, 1e-14);
  EXPECT_NEAR(fem::scaled_jacobian(m.nodes, m.cells[0]), -0.10 / 0.505, 1e-14);
  // The same cell convex again (corner at (0.55, 0.55)): +0.10/0.505.
  std::vector<fem::Point> moved = m.nodes;
  moved[2] = fem::Point(0.55, 0.55);
  EXPECT_NEAR(fem::scaled_jacobian(moved, m.cells[0]), 0.10 / 0.505, 1e-14);
}

TEST(AxisymmetricMeasure, CylinderVolumeAndSurfaceAreExact) {
  // Cylinder R = 2, H = 3 on a refined quadtree: V = π R^2 H, lateral area 2π R H.
  fem::Quadtree tree(4, 6);
  tree.refine([](const fem::IndexBox& b) { return b.x0 >= 2 && b.y0 < 2 ? 2 : 0; });
  tree.balance();
  const fem::Mesh m = tree.build("cyl", [](double x, double y) { return fem::Point(0.5 * x, 0.5 * y); },
                                 [](double, double, fem::Side s) -> std::string {
                                   return s == fem::Side::right ? "lateral" : (s == fem::Side::left ? "axis" : "caps");
                                 });
  fem::CellValues cv(2);
  double volume = 0;
  for (int e = 0; e < m.n_cells(); ++e) {
    cv.reinit(m, e);
    for (int q = 0; q < cv.n_q(); ++q) volume += cv.JxW(q);
  }
  EXPECT_NEAR(volume, M_PI * 4 * 3, 1e-12);
  fem::FaceValues fv(2);
  double lateral = 0, axis = 0, caps = 0;
  for (const auto& [name, out] : {std::pair<const char*, double*>{"cyl.lateral", &lateral},
                                  {"cyl.axis", &axis}, {"cyl.caps", &caps}})
    for (const auto& f : m.boundary(name)) {
      fv.reinit(m, f.cell, f.face);
      for (int q = 0; q < fv.n_q(); ++q) *out += fv.JxW(q);
    }
  EXPECT_NEAR(lateral, 2 * M_PI * 2 * 3, 1e-12);
  EXPECT_NEAR(axis, 0.0, 1e-15);  // the axis has no area
  EXPECT_NEAR(caps, 2 * M_PI * 4, 1e-12);
}

TEST(FaceValues, OutwardNormalsPointAwayFromTheCell) {
  const fem::Mesh m = one_cell({fem::Point(1, 0), fem::Point(2, 0), fem::Point(2, 1), fem::Point(1, 1)});
  fem::FaceValues fv(2);
  const Eigen::Vector2d expected[4] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};
  for (int f = 0; f < 4; ++f) {
    fv.reinit(m, 0, f);
    EXPECT_NEAR((fv.normal(0) - expected[f]).norm(), 0.0, 1e-15) << "face " << f;
  }
}
