// Sparse polynomial chaos (calibration/pce.*): orthonormality of the bases, the
// truncation sets, LARS, the hat-matrix LOO against brute-force refits, the correction
// factor of Blatman & Sudret (2011), the guards for N ≤ P and leverage → 1, and exact
// recovery of sparse polynomials.
#include "calibration/designs.hpp"
#include "calibration/pce.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

namespace rsw::calibration {
namespace {

constexpr double pi = 3.14159265358979323846;

TEST(Polynomials, LegendreAndHermiteAreOrthonormalUnderTheirWeights) {
  const int p = 8;
  // Legendre: uniform weight on s ∈ [0, 1], composite Simpson (exact to round-off here).
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(p + 1, p + 1);
  const int n = 20000;
  for (int i = 0; i <= n; ++i) {
    const double s = static_cast<double>(i) / n;
    const double weight = (i == 0 || i == n) ? 1 : (i % 2 == 1 ? 4 : 2);
    const Eigen::VectorXd psi = orthonormal_polynomials(PolynomialFamily::legendre, p, s);
    gram += weight / (3.0 * n) * psi * psi.transpose();
  }
  EXPECT_NEAR((gram - Eigen::MatrixXd::Identity(p + 1, p + 1)).cwiseAbs().maxCoeff(), 0, 1e-10);
  // Hermite: standard normal weight, trapezoid on [−14, 14] (spectrally accurate).
  gram.setZero();
  const double h = 0.01;
  for (double z = -14; z <= 14 + 1e-12; z += h) {
    const Eigen::VectorXd psi = orthonormal_polynomials(PolynomialFamily::hermite, p, z);
    gram += h * std::exp(-0.5 * z * z) / std::sqrt(2 * pi) * psi * psi.transpose();
  }
  EXPECT_NEAR((gram - Eigen::MatrixXd::Identity(p + 1, p + 1)).cwiseAbs().maxCoeff(), 0, 1e-10);
  // Closed forms: ψ_2 Legendre = √5 (3ξ² − 1)/2, ψ_3 Hermite = (z³ − 3z)/√6.
  EXPECT_NEAR(orthonormal_polynomials(PolynomialFamily::legendre, 3, 0.8)[2],
              std::sqrt(5.0) * (3 * 0.36 - 1) / 2, 1e-14);
  EXPECT_NEAR(orthonormal_polynomials(PolynomialFamily::hermite, 3, 1.7)[3],
              (1.7 * 1.7 * 1.7 - 3 * 1.7) / std::sqrt(6.0), 1e-14);
}

TEST(MultiIndices, TotalDegreeCountIsBinomialAndHyperbolicIsSmaller) {
  auto binomial = [](int n, int k) {
    double result = 1;
    for (int i = 1; i <= k; ++i) result = result * (n - k + i) / i;
    return static_cast<std::size_t>(std::lround(result));
  };
  EXPECT_EQ(truncated_multi_indices(6, 5).size(), binomial(11, 5));  // 462
  EXPECT_EQ(truncated_multi_indices(3, 12).size(), binomial(15, 12));
  const auto full = truncated_multi_indices(3, 4);
  EXPECT_EQ(full.front(), (MultiIndex{0, 0, 0}));
  for (std::size_t j = 1; j < full.size(); ++j) {
    int previous = 0, current = 0;
    for (int a : full[j - 1]) previous += a;
    for (int a : full[j]) current += a;
    EXPECT_LE(previous, current);  // ordered by total degree
  }
  const auto hyperbolic = truncated_multi_indices(3, 4, 0.5);
  EXPECT_LT(hyperbolic.size(), full.size());
  // q = 0.5, p = 4: (1 + 1)² = 4 keeps α = (1, 1, 0); (2, 1, 0) has (√2 + 1)² ≈ 5.8 > 4.
  EXPECT_NE(std::find(hyperbolic.begin(), hyperbolic.end(), MultiIndex{1, 1, 0}), hyperbolic.end());
  EXPECT_EQ(std::find(hyperbolic.begin(), hyperbolic.end(), MultiIndex{2, 1, 0}), hyperbolic.end());
  EXPECT_NE(std::find(hyperbolic.begin(), hyperbolic.end(), MultiIndex{0, 0, 4}), hyperbolic.end());
}

TEST(Pce, FastLooEqualsBruteForceRefits) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0, 0.1);
  const Eigen::MatrixXd points = latin_hypercube(40, 2, 3);
  const std::vector<PolynomialFamily> families(2, PolynomialFamily::legendre);
  const Eigen::MatrixXd psi = design_matrix(points, families, truncated_multi_indices(2, 3));
  Eigen::VectorXd y(40);
  for (Eigen::Index i = 0; i < 40; ++i) {
    y[i] = std::exp(points(i, 0)) * std::sin(3 * points(i, 1)) + noise(rng);
  }
  const LeastSquaresLoo fit = least_squares_loo(psi, y);
  ASSERT_TRUE(fit.valid) << fit.invalid_reason;
  double mean_square = 0;
  for (Eigen::Index i = 0; i < 40; ++i) {
    // Refit without point i, predict it.
    Eigen::MatrixXd psi_i(39, psi.cols());
    Eigen::VectorXd y_i(39);
    for (Eigen::Index r = 0, k = 0; r < 40; ++r) {
      if (r == i) continue;
      psi_i.row(k) = psi.row(r);
      y_i[k++] = y[r];
    }
    const Eigen::VectorXd c = psi_i.colPivHouseholderQr().solve(y_i);
    const double loo_residual = y[i] - psi.row(i).dot(c);
    EXPECT_NEAR(fit.loo_residuals[i], loo_residual, 1e-10 * (1 + std::abs(loo_residual))) << i;
    mean_square += loo_residual * loo_residual / 40;
  }
  const double variance = (y.array() - y.mean()).square().sum() / 39;
  EXPECT_NEAR(fit.loo_error, mean_square / variance, 1e-10 * fit.loo_error);
}

TEST(Pce, LooCorrectionFactor) {
  const Eigen::MatrixXd points = latin_hypercube(25, 3, 9);
  const std::vector<PolynomialFamily> families(3, PolynomialFamily::legendre);
  const Eigen::MatrixXd psi = design_matrix(points, families, truncated_multi_indices(3, 2));
  Eigen::VectorXd y = points.col(0).array().square() + points.col(1).array() * points.col(2).array();
  y += 0.05 * Eigen::VectorXd::LinSpaced(25, -1, 1).array().sin().matrix();
  const LeastSquaresLoo fit = least_squares_loo(psi, y);
  ASSERT_TRUE(fit.valid);
  const double n = 25, p = static_cast<double>(psi.cols());  // P = 10
  const double trace = (psi.transpose() * psi).inverse().trace();
  const double expected = n / (n - p) * (1 + trace);
  EXPECT_NEAR(fit.correction_factor, expected, 1e-10 * expected);
  EXPECT_NEAR(fit.corrected_loo_error, fit.loo_error * expected, 1e-10 * fit.corrected_loo_error);
  std::cout << "[ figures  ] N = 25, P = 10: T = " << fit.correction_factor
            << " (orthonormal limit N/(N-P)(1+P/N) = " << n / (n - p) * (1 + p / n) << ")\n";
}

TEST(Pce, FewerPointsThanTermsDoesNotCrash) {
  // Direct least squares: N ≤ P and a leverage of one are reported, not thrown.
  const Eigen::MatrixXd points = latin_hypercube(5, 3, 1);
  const std::vector<PolynomialFamily> families(3, PolynomialFamily::legendre);
  const Eigen::MatrixXd psi = design_matrix(points, families, truncated_multi_indices(3, 2));
  const Eigen::VectorXd y = points.col(0) + points.col(1).cwiseAbs2();
  const LeastSquaresLoo too_few = least_squares_loo(psi, y);
  EXPECT_FALSE(too_few.valid);
  EXPECT_NE(too_few.invalid_reason.find("N <= P"), std::string::npos);
  Eigen::MatrixXd spike(6, 2);  // the second column only sees point 3: h_3 = 1
  spike << 1, 0, 1, 0, 1, 0, 1, 1, 1, 0, 1, 0;
  const LeastSquaresLoo leverage = least_squares_loo(spike, Eigen::VectorXd::LinSpaced(6, 0, 1));
  EXPECT_FALSE(leverage.valid);
  EXPECT_NE(leverage.invalid_reason.find("leverage"), std::string::npos) << leverage.invalid_reason;

  // The whole algorithm on 5 points with up to 35 candidate terms.
  PceOptions options;
  options.max_degree = 4;
  options.n_degrees_without_improvement = 0;
  SparsePolynomialChaos chaos(points, y, std::vector<StandardSpace>(3, StandardSpace::unit_interval),
                              options);
  ASSERT_NO_THROW(chaos.run());
  EXPECT_LT(chaos.result().multi_indices.size(), 5u);
  EXPECT_TRUE(std::isfinite(chaos.result().corrected_loo_error));
  EXPECT_EQ(chaos.degree_diagnostics().size(), 4u);

  // Two points: only the constant is possible.
  SparsePolynomialChaos two(points.topRows(2), y.head(2),
                            std::vector<StandardSpace>(3, StandardSpace::unit_interval));
  ASSERT_NO_THROW(two.run());
  EXPECT_EQ(two.result().multi_indices.size(), 1u);
  EXPECT_NEAR(two.result().mean(), y.head(2).mean(), 1e-14);
  EXPECT_THROW(SparsePolynomialChaos(points.topRows(1), y.head(1),
                                     std::vector<StandardSpace>(3, StandardSpace::unit_interval)),
               std::invalid_argument);
}

TEST(Lars, OrthogonalColumnsEnterInOrderOfCorrelation) {
  // Columns orthonormal and orthogonal to the constant: LARS then enters them by |Xᵀy|.
  std::mt19937_64 rng(17);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd raw(30, 6);
  for (Eigen::Index i = 0; i < raw.size(); ++i) raw.data()[i] = normal(rng);
  raw.col(0).setOnes();
  const Eigen::MatrixXd q = raw.householderQr().householderQ() * Eigen::MatrixXd::Identity(30, 6);
  const Eigen::MatrixXd x = q.rightCols(5);
  const Eigen::VectorXd weights = (Eigen::VectorXd(5) << 0.3, -2.0, 0.05, 1.1, -0.7).finished();
  Eigen::VectorXd y = x * weights;
  y.array() += 4;
  const std::vector<Eigen::Index> order = lars_order(x, y, 10);
  EXPECT_EQ(order, (std::vector<Eigen::Index>{1, 3, 4, 0, 2}));
  EXPECT_EQ(lars_order(x, y, 2).size(), 2u);
}

TEST(Lars, RecoversSupportAndCoefficientsOfSparsePolynomial) {
  const std::vector<MultiIndex> truth = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {1, 0, 2}, {0, 0, 3}};
  const Eigen::VectorXd coefficients = (Eigen::VectorXd(5) << 2.0, 1.5, -0.8, 0.6, 0.3).finished();
  const std::vector<PolynomialFamily> families(3, PolynomialFamily::legendre);
  const Eigen::MatrixXd points = latin_hypercube(80, 3, 123);
  const Eigen::VectorXd y = design_matrix(points, families, truth) * coefficients;

  const auto candidates = truncated_multi_indices(3, 4);
  const Eigen::MatrixXd psi = design_matrix(points, families, candidates);
  const std::vector<Eigen::Index> order = lars_order(psi.rightCols(psi.cols() - 1), y, 78);
  ASSERT_GE(order.size(), 4u);
  std::vector<MultiIndex> first_four;
  for (std::size_t k = 0; k < 4; ++k) first_four.push_back(candidates[static_cast<std::size_t>(order[k] + 1)]);
  for (std::size_t k = 1; k < truth.size(); ++k) {
    EXPECT_NE(std::find(first_four.begin(), first_four.end(), truth[k]), first_four.end())
        << "term " << k << " not among the first four LARS entries";
  }

  PceOptions options;
  options.min_degree = 4;
  options.max_degree = 4;
  SparsePolynomialChaos chaos(points, y, std::vector<StandardSpace>(3, StandardSpace::unit_interval),
                              options);
  chaos.run();
  const PolynomialChaosResult& result = chaos.result();
  ASSERT_EQ(result.multi_indices.size(), truth.size());
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const auto it = std::find(result.multi_indices.begin(), result.multi_indices.end(), truth[k]);
    ASSERT_NE(it, result.multi_indices.end()) << "term " << k << " missing";
    EXPECT_NEAR(result.coefficients[it - result.multi_indices.begin()], coefficients[static_cast<Eigen::Index>(k)], 1e-12);
  }
  EXPECT_NEAR(result.mean(), 2.0, 1e-12);
  EXPECT_NEAR(result.variance(), coefficients.tail(4).squaredNorm(), 1e-12);
  EXPECT_LT(result.loo_error, 1e-20);
  const Eigen::Vector3d x(0.3, 0.9, 0.1);
  const std::vector<MultiIndex> support = result.multi_indices;
  EXPECT_NEAR(result.evaluate(x), (design_matrix(x.transpose(), families, truth) * coefficients)[0], 1e-12);
}

TEST(Pce, HermiteBasisRecoversPolynomialOfNormalInputs) {
  // y = z1² + z1 z2 = √2 ψ_2(z1) + ψ_1(z1) ψ_1(z2) + 1: mean 1, variance 2 + 1.
  const std::vector<StandardSpace> spaces(2, StandardSpace::standard_normal);
  Eigen::MatrixXd points = latin_hypercube(60, 2, 77);
  for (Eigen::Index i = 0; i < points.size(); ++i) {
    points.data()[i] = standard_normal_quantile(points.data()[i]);
  }
  const Eigen::VectorXd y =
      points.col(0).array().square() + points.col(0).array() * points.col(1).array();
  PceOptions options;
  options.max_degree = 3;
  SparsePolynomialChaos chaos(points, y, spaces, options);
  chaos.run();
  EXPECT_NEAR(chaos.result().mean(), 1, 1e-12);
  EXPECT_NEAR(chaos.result().variance(), 3, 1e-11);
  EXPECT_EQ(chaos.result().multi_indices.size(), 3u);
  EXPECT_EQ(chaos.result().families[0], PolynomialFamily::hermite);
}

TEST(Pce, DegreeLoopPicksTheDegreeOfASmoothFunction) {
  // A quadratic with noise-free data: degree 2 fits exactly, higher degrees cannot do
  // better, so the early stop ends the loop at degree 4 and degree 2 is kept.
  const Eigen::MatrixXd points = latin_hypercube(50, 2, 4);
  const Eigen::VectorXd y = (points.col(0).array() - 0.3).square() + points.col(1).array();
  PceOptions options;
  options.max_degree = 8;
  SparsePolynomialChaos chaos(points, y, std::vector<StandardSpace>(2, StandardSpace::unit_interval),
                              options);
  chaos.run();
  EXPECT_EQ(chaos.result().degree, 2);
  EXPECT_EQ(chaos.degree_diagnostics().size(), 4u);
  EXPECT_THROW(SparsePolynomialChaos(points, y, {StandardSpace::unit_interval}), std::invalid_argument);
  SparsePolynomialChaos not_run(points, y, std::vector<StandardSpace>(2, StandardSpace::unit_interval));
  EXPECT_THROW(not_run.result(), std::logic_error);
}

}  // namespace
}  // namespace rsw::calibration
