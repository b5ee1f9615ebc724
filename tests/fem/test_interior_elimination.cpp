// Exact elimination of interior unknowns (fem::InteriorElimination) and the bordered
// Cholesky factor behind it (fem::BorderedCholesky), against dense linear algebra:
// the Schur complement A_BB − A_BI A_II⁻¹ A_IB and the solution of K y = r.
#include "fem/interior_elimination.hpp"
#include "fem/linear_solver.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>
#include <vector>

namespace rsw::fem {
namespace {

// The stiffness-like matrix of an nx × ny grid of nodes (5-point coupling, random
// positive weights) plus a diagonal shift: symmetric positive definite.
SparseMatrix grid_matrix(int nx, int ny, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> weight(0.5, 2.0);
  const int n = nx * ny;
  std::vector<Eigen::Triplet<double>> t;
  auto couple = [&](int a, int b) {
    const double w = weight(rng);
    t.emplace_back(a, a, w);
    t.emplace_back(b, b, w);
    t.emplace_back(a, b, -w);
    t.emplace_back(b, a, -w);
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int k = i + nx * j;
      if (i + 1 < nx) couple(k, k + 1);
      if (j + 1 < ny) couple(k, k + nx);
      t.emplace_back(k, k, 0.1);
    }
  SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

TEST(BorderedCholesky, TrailingBlockIsTheSchurComplementOfTheLeadingBlock) {
  const SparseMatrix A = grid_matrix(9, 7, 1);
  const int n = static_cast<int>(A.rows()), nb = 9, ni = n - nb;
  BorderedCholesky factor;
  ASSERT_TRUE(factor.factorize(A, nb));
  const Eigen::MatrixXd D(A);
  const Eigen::MatrixXd expected = D.bottomRightCorner(nb, nb) - D.bottomLeftCorner(nb, ni) *
                                                                     D.topLeftCorner(ni, ni).ldlt().solve(
                                                                         D.topRightCorner(ni, nb));
  EXPECT_LT((factor.schur_complement() - expected).norm(), 1e-12 * expected.norm());

  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(ni, -1.0, 2.0);
  Eigen::VectorXd x(ni);
  factor.solve_leading(b.data(), x.data());
  const Eigen::VectorXd y = D.topLeftCorner(ni, ni).ldlt().solve(b);
  EXPECT_LT((x - y).norm(), 1e-12 * y.norm());
  factor.solve_leading(b.data(), x.data());  // the second factorisation reuses the analysis
  ASSERT_TRUE(factor.factorize(SparseMatrix(2.0 * A), nb));
  factor.solve_leading(b.data(), x.data());
  EXPECT_LT((x - 0.5 * y).norm(), 1e-12 * y.norm());
}

TEST(BorderedCholesky, ReportsAMatrixThatIsNotPositiveDefinite) {
  SparseMatrix A = grid_matrix(5, 5, 2);
  A.coeffRef(3, 3) = -1.0;
  BorderedCholesky factor;
  EXPECT_FALSE(factor.factorize(A, 4));
}

// K over an 8 × 8 grid: the interior is the nodes of the first five columns but the
// last of them; the rest of K gets an unsymmetric part (as a friction tangent).
struct System {
  SparseMatrix K;
  std::vector<char> interior;
};
System make_system(unsigned seed) {
  System s;
  s.K = grid_matrix(8, 8, seed);
  s.interior.assign(64, 0);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 4; ++i) s.interior[i + 8 * j] = 1;
  for (int k = 0; k < s.K.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(s.K, k); it; ++it)
      if (!s.interior[it.row()] && !s.interior[it.col()] && it.row() < it.col()) it.valueRef() *= 1.3;
  return s;
}

// y from the elimination (the reduced system solved densely), for K y = r.
Eigen::VectorXd solve_by_elimination(InteriorElimination& e, const SparseMatrix& K, const Eigen::VectorXd& r) {
  EXPECT_TRUE(e.prepare(K));
  const Eigen::MatrixXd S(e.reduced());
  const Eigen::VectorXd y_A = S.partialPivLu().solve(e.reduce(r));
  return e.expand(r, y_A);
}

TEST(InteriorElimination, SolvesTheWholeSystem) {
  System s = make_system(3);
  InteriorElimination e(s.interior);
  const Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(64, 1.0, -3.0);
  const Eigen::VectorXd y = solve_by_elimination(e, s.K, r);
  EXPECT_LT((s.K * y - r).norm(), 1e-12 * r.norm());
  EXPECT_EQ(e.n_interior(), 32);
  EXPECT_EQ(e.n_reduced(), 32);
  EXPECT_EQ(e.n_border(), 8);  // the fifth column of the grid
  EXPECT_EQ(e.n_condensations(), 1);
}

TEST(InteriorElimination, CondensesAgainOnlyWhenTheInteriorChanges) {
  System s = make_system(4);
  InteriorElimination e(s.interior);
  const Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(64, -2.0, 1.0);
  solve_by_elimination(e, s.K, r);
  // A new value outside the interior's rows and columns: the condensation is reused.
  s.K.coeffRef(63, 63) *= 3.0;
  Eigen::VectorXd y = solve_by_elimination(e, s.K, r);
  EXPECT_LT((s.K * y - r).norm(), 1e-12 * r.norm());
  EXPECT_EQ(e.n_condensations(), 1);
  EXPECT_EQ(e.n_reuses(), 1);
  // A new interior value (kept symmetric): condensed afresh.
  s.K.coeffRef(0, 0) *= 2.0;
  y = solve_by_elimination(e, s.K, r);
  EXPECT_LT((s.K * y - r).norm(), 1e-12 * r.norm());
  EXPECT_EQ(e.n_condensations(), 2);
}

TEST(InteriorElimination, GivesUpOnAnInteriorThatChangesEveryTime) {
  System s = make_system(5);
  InteriorElimination e(s.interior);
  EXPECT_TRUE(e.prepare(s.K));  // the first interior
  s.K.coeffRef(9, 9) *= 1.5;
  EXPECT_TRUE(e.prepare(s.K));  // the second in a row that differs from the one before
  s.K.coeffRef(9, 9) *= 1.5;
  EXPECT_FALSE(e.prepare(s.K));  // the third
  EXPECT_TRUE(e.prepare(s.K));   // the same interior twice: condensed again
  EXPECT_TRUE(e.prepare(s.K));   // and reused
  EXPECT_EQ(e.n_condensations(), 3);
  EXPECT_EQ(e.n_reuses(), 1);
}

TEST(InteriorElimination, RefusesAnUnsymmetricOrIndefiniteInterior) {
  System s = make_system(6);
  s.K.coeffRef(0, 1) *= 1.01;
  InteriorElimination unsymmetric(s.interior);
  EXPECT_FALSE(unsymmetric.prepare(s.K));
  System t = make_system(7);
  t.K.coeffRef(0, 0) = -5.0;
  InteriorElimination indefinite(t.interior);
  EXPECT_FALSE(indefinite.prepare(t.K));
}

TEST(InteriorElimination, ReducedMatrixOfASurrogateUsesTheSameCorrection) {
  System s = make_system(8);
  InteriorElimination e(s.interior);
  ASSERT_TRUE(e.prepare(s.K));
  SparseMatrix M = s.K;
  M.coeffRef(60, 61) += 0.25;  // outside the interior's rows and columns
  const Eigen::MatrixXd difference = Eigen::MatrixXd(e.reduce_matrix(M)) - Eigen::MatrixXd(e.reduced());
  EXPECT_DOUBLE_EQ(difference.cwiseAbs().sum(), 0.25);
}

TEST(InteriorElimination, NeglectsOnlyAnInteriorResidualBelowTheGivenBound) {
  System s = make_system(9);
  InteriorElimination e(s.interior);
  ASSERT_TRUE(e.prepare(s.K));
  Eigen::VectorXd r = Eigen::VectorXd::Zero(64);
  r[0] = 1e-3;   // interior
  r[63] = 1.0;   // the rest
  const Eigen::VectorXd kept = e.reduce(r), dropped = e.reduce(r, 2e-3);
  EXPECT_EQ(dropped[31], 1.0);
  EXPECT_EQ((dropped.array() != 0).count(), 1);
  EXPECT_GT((kept - dropped).norm(), 0.0);
  EXPECT_EQ(e.reduce(r, 0.5e-3), kept);
}

}  // namespace
}  // namespace rsw::fem
