// Fixed points u = G(u) (fem/fixed_point): Anderson-accelerated iteration and
// Newton–Krylov, at fixed points known in closed form, also where plain iteration
// diverges.
#include "fem/fixed_point.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

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

// A scalar contraction G(u) = u* + θ (u − u*), θ = 0.05, u* = 1, from u_0 = 11 (plain
// iteration): the changes are c_k = (1 − θ) θ^k 10 = 9.5, 0.475, 0.02375, 0.0011875,
// 5.9e-5, ... With tolerance 10⁻³ the change test stops at the fifth evaluation (c_4 =
// 5.9e-5), the contraction estimate at the fourth: after c_3 = 1.1875e-3 > 10⁻³ with
// θ = 0.05 twice in a row, it puts G(u_3) at θ c_3/(1 − θ) = 6.25e-5 from u*, which for
// a linear map is exact (G(u_3) − u* = 10 θ⁴).
TEST(FixedPoint, ContractionEstimateSavesTheConfirmingEvaluation) {
  const double theta = 0.05;
  const auto G = [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    g = Eigen::VectorXd::Constant(1, 1.0 + theta * (x[0] - 1.0));
    return true;
  };
  FixedPointSettings s;
  s.depth = 0;
  s.tolerance = 1e-3;
  Eigen::VectorXd u = Eigen::VectorXd::Constant(1, 11.0);
  const auto plain = solve_fixed_point(G, u, s);
  ASSERT_TRUE(plain.converged) << plain.message;
  EXPECT_EQ(plain.iterations, 5);
  EXPECT_FALSE(plain.estimated);

  s.estimate_error = true;
  u = Eigen::VectorXd::Constant(1, 11.0);
  const auto estimated = solve_fixed_point(G, u, s);
  ASSERT_TRUE(estimated.converged) << estimated.message;
  EXPECT_TRUE(estimated.estimated);
  EXPECT_EQ(estimated.iterations, 4);
  EXPECT_NEAR(estimated.change, 1.1875e-3, 1e-12);
  // u is the last point evaluated, u_3 = 1 + 10 θ³; its map value G(u_3) is within the
  // tolerance of the fixed point.
  EXPECT_NEAR(u[0], 1.0 + 10 * theta * theta * theta, 1e-12);
  EXPECT_LT(std::abs(1.0 + theta * (u[0] - 1.0) - 1.0), s.tolerance);

  // A slow contraction (θ = 0.9) never trusts the estimate: the change test stops it.
  const auto slow = [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    g = Eigen::VectorXd::Constant(1, 1.0 + 0.9 * (x[0] - 1.0));
    return true;
  };
  u = Eigen::VectorXd::Constant(1, 11.0);
  s.max_iterations = 200;
  const auto slow_report = solve_fixed_point(slow, u, s);
  ASSERT_TRUE(slow_report.converged) << slow_report.message;
  EXPECT_FALSE(slow_report.estimated);
}

// Newton–Krylov on a linear map whose modes expand (gains 3, −2.5) or contract: the
// Jacobian of F(u) = G(u) − u is A − I, so one Newton step whose GMRES solve spans the
// five modes (five products, each an evaluation of G) lands on u* up to the forcing
// 10⁻⁶ and the difference quotients; a second step and the final check end it.
TEST(FixedPointNewton, LinearMapWithExpandingModesIsSolvedInTwoNewtonSteps) {
  Eigen::VectorXd eigenvalues(5);
  eigenvalues << 3.0, -2.5, 0.5, 0.2, -0.4;
  const LinearMap map(eigenvalues);
  Eigen::VectorXd last;
  auto G = [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    g = map.A * x + map.b;
    last = x;
    return true;
  };
  rsw::fem::NewtonKrylovSettings s;
  s.tolerance = 1e-9;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(5);
  const auto report = rsw::fem::solve_fixed_point_newton(G, u, s);
  ASSERT_TRUE(report.converged) << report.message;
  EXPECT_LT((u - map.fixed_point()).lpNorm<Eigen::Infinity>(), 1e-8);
  EXPECT_LE(report.change, s.tolerance);
  // Each step: F at the iterate and at most 5 products; then the final check.
  EXPECT_LE(report.iterations, 2 * (1 + 5) + 2);
  EXPECT_EQ(last, u);  // the returned point is the last one G was evaluated at
}

// u = G(u) = u − 10 atan(u − c) componentwise, c_i in [1, 2]: at the fixed point u* = c
// the gain is 1 − 10 = −9, so plain iteration runs away. Newton's method on atan from
// |u − c| above 1.39 overshoots ever further (1.39 solves 2x = (1 + x²) atan x); from
// u = 0 the line search shortens those steps.
TEST(FixedPointNewton, LineSearchReachesAFixedPointThatPlainIterationRunsAwayFrom) {
  const Eigen::VectorXd c = Eigen::VectorXd::LinSpaced(4, 1.0, 2.0);
  auto G = [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    g = x.array() - 10.0 * (x - c).array().atan();
    return true;
  };
  FixedPointSettings plain;
  plain.depth = 0;
  plain.max_iterations = 60;
  plain.tolerance = 1e-10;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(4);
  EXPECT_FALSE(solve_fixed_point(G, u, plain).converged);

  rsw::fem::NewtonKrylovSettings s;
  s.tolerance = 1e-10;
  u.setZero();
  const auto report = rsw::fem::solve_fixed_point_newton(G, u, s);
  ASSERT_TRUE(report.converged) << report.message;
  EXPECT_LT((u - c).lpNorm<Eigen::Infinity>(), 1e-10);
  EXPECT_LE(report.iterations, s.max_evaluations);
}

// A map without a fixed point (G(u) = u + 1 + 0.5 sin u: F = 1 + 0.5 sin u ≥ 0.5) uses
// at most its budget of evaluations and is reported as not converged; a map that
// fails ends the solve with the map's reason.
TEST(FixedPointNewton, NoFixedPointOrAFailingMapEndsWithinTheBudgetAndSaysWhy) {
  int calls = 0;
  auto none = [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    ++calls;
    g = x.array() + 1.0 + 0.5 * x.array().sin();
    return true;
  };
  rsw::fem::NewtonKrylovSettings s;
  s.max_evaluations = 30;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3);
  const auto report = rsw::fem::solve_fixed_point_newton(none, u, s);
  EXPECT_FALSE(report.converged);
  EXPECT_FALSE(report.message.empty());
  EXPECT_LE(calls, s.max_evaluations);
  EXPECT_EQ(report.iterations, calls);

  calls = 0;
  auto failing = [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    if (++calls == 4) throw std::runtime_error("thermal solve failed");
    g = 0.5 * x + Eigen::VectorXd::Ones(3);
    return true;
  };
  u.setZero();
  const auto failed = rsw::fem::solve_fixed_point_newton(failing, u, s);
  EXPECT_FALSE(failed.converged);
  EXPECT_EQ(failed.message, "thermal solve failed");
}
