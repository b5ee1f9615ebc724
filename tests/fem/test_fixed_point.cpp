// Anderson-accelerated fixed-point iteration (fem/fixed_point): fixed points known in
// closed form, reached also where plain iteration diverges.
#include "fem/fixed_point.hpp"

#include <gtest/gtest.h>

#include <cmath>

using rsw::fem::FixedPointSettings;
using rsw::fem::solve_fixed_point;

namespace {

// G(u) = A u + b with the eigenvalues of A given: fixed point u* = (I − A)⁻¹ b.
struct LinearMap {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  explicit LinearMap(const Eigen::VectorXd& eigenvalues) {
    const int n = static_cast<int>(eigenvalues.size());
    // A = Q diag(λ) Qᵀ with a fixed orthogonal Q (QR of a deterministic matrix).
    Eigen::MatrixXd M(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) M(i, j) = std::sin(1.0 + 3 * i + 7 * j);
    const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(M).householderQ();
    A = Q * eigenvalues.asDiagonal() * Q.transpose();
    b = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0);
  }
  Eigen::VectorXd fixed_point() const {
    return (Eigen::MatrixXd::Identity(A.rows(), A.cols()) - A).partialPivLu().solve(b);
  }
};

}  // namespace

TEST(FixedPoint, ScalarCosineReachesTheDottieNumber) {
  // u = cos u has the single root 0.739085133215160641655... (the Dottie number).
  Eigen::VectorXd u = Eigen::VectorXd::Zero(1);
  FixedPointSettings s;
  s.tolerance = 1e-13;
  const auto report = solve_fixed_point(
      [](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
        g = x.array().cos();
        return true;
      },
      u, s);
  ASSERT_TRUE(report.converged) << report.message;
  EXPECT_NEAR(u[0], 0.7390851332151607, 1e-12);
  EXPECT_LT(report.iterations, 15);  // plain iteration needs ~75 for 1e-13
}

TEST(FixedPoint, ContractionConvergesToTheLinearFixedPoint) {
  Eigen::VectorXd eigenvalues(6);
  eigenvalues << 0.9, 0.5, -0.3, 0.1, 0.0, 0.7;
  const LinearMap map(eigenvalues);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(6);
  FixedPointSettings s;
  s.tolerance = 1e-12;
  const auto report = solve_fixed_point(
      [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
        g = map.A * x + map.b;
        return true;
      },
      u, s);
  ASSERT_TRUE(report.converged) << report.message;
  EXPECT_LT((u - map.fixed_point()).lpNorm<Eigen::Infinity>(), 1e-10);
}

TEST(FixedPoint, AndersonFindsAFixedPointThatPlainIterationRunsAwayFrom) {
  // One mode with gain 1.2: plain iteration diverges along it; Anderson acceleration
  // (a multisecant method: GMRES-like on linear maps) converges.
  Eigen::VectorXd eigenvalues(5);
  eigenvalues << 1.2, 0.5, 0.2, -0.4, 0.1;
  const LinearMap map(eigenvalues);
  auto G = [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    g = map.A * x + map.b;
    return true;
  };
  FixedPointSettings plain;
  plain.depth = 0;
  plain.tolerance = 1e-10;
  plain.max_iterations = 60;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(5);
  EXPECT_FALSE(solve_fixed_point(G, u, plain).converged);

  FixedPointSettings anderson = plain;
  anderson.depth = 5;
  u.setZero();
  const auto report = solve_fixed_point(G, u, anderson);
  ASSERT_TRUE(report.converged) << report.message;
  EXPECT_LT((u - map.fixed_point()).lpNorm<Eigen::Infinity>(), 1e-8);
  EXPECT_LE(report.iterations, 15);
}

TEST(FixedPoint, AMapThatFailsStopsTheIterationWithItsReason) {
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3);
  int calls = 0;
  const auto report = solve_fixed_point(
      [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
        if (++calls == 3) throw std::runtime_error("thermal solve failed");
        g = 0.5 * x + Eigen::VectorXd::Ones(3);
        return true;
      },
      u, FixedPointSettings{});
  EXPECT_FALSE(report.converged);
  EXPECT_EQ(report.message, "thermal solve failed");
  EXPECT_EQ(calls, 3);
}

// G(u) = 2 − u has gain −1: plain iteration cycles between u₀ and 2 − u₀ for ever.
// With damping β the update is u ← (1 − β) u + β (2 − u) = u + β (2 − 2u), which
// for β = 1/2 lands on the fixed point 1 in one step.
TEST(FixedPoint, DampingStopsThePlainIterationFromCycling) {
  const auto reflect = [](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    g = 2.0 - x.array();
    return true;
  };
  FixedPointSettings s;
  s.depth = 0;
  s.max_iterations = 20;
  s.tolerance = 1e-12;
  Eigen::VectorXd u = Eigen::VectorXd::Constant(1, 0.3);
  EXPECT_FALSE(solve_fixed_point(reflect, u, s).converged);
  s.damping = 0.5;
  u = Eigen::VectorXd::Constant(1, 0.3);
  const auto report = solve_fixed_point(reflect, u, s);
  ASSERT_TRUE(report.converged) << report.message;
  EXPECT_NEAR(u[0], 1.0, 1e-12);
  EXPECT_LE(report.iterations, 3);
}
