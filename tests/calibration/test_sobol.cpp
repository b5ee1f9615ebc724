// Sobol' indices (calibration/sobol.*): from hand-built PCE coefficients against the
// closed-form sums of Sudret (2008); on the Ishigami function against its analytic
// indices (verification: a sparse PCE at a high degree cap matches them, at degree ≤ 5
// the LOO error shows the poor fit); and the Monte Carlo Saltelli/Jansen estimator
// against the PCE.
//
// Ishigami (Ishigami & Homma 1990), x_i uniform on [−π, π]:
//   f = sin x1 + a sin² x2 + b x3⁴ sin x1,  a = 7, b = 0.1
//   V = a²/8 + b π⁴/5 + b² π⁸/18 + 1/2,  V1 = (1 + b π⁴/5)²/2,  V2 = a²/8,  V3 = 0,
//   V13 = b² π⁸ (1/18 − 1/50) = 8 b² π⁸/225, all other partial variances 0;
//   S_i = V_i/V, S_T1 = (V1 + V13)/V, S_T2 = V2/V, S_T3 = V13/V, S_13 = V13/V.
#include "calibration/designs.hpp"
#include "calibration/pce.hpp"
#include "calibration/sobol.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <iostream>

namespace rsw::calibration {
namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double ishigami_a = 7;
constexpr double ishigami_b = 0.1;

struct IshigamiReference {
  double variance, s1, s2, s3, st1, st2, st3, s13;
};

IshigamiReference ishigami_reference() {
  const double a = ishigami_a, b = ishigami_b;
  const double pi4 = std::pow(pi, 4), pi8 = std::pow(pi, 8);
  const double v = a * a / 8 + b * pi4 / 5 + b * b * pi8 / 18 + 0.5;
  const double v1 = 0.5 * (1 + b * pi4 / 5) * (1 + b * pi4 / 5);
  const double v2 = a * a / 8;
  const double v13 = 8 * b * b * pi8 / 225;
  return {v, v1 / v, v2 / v, 0, (v1 + v13) / v, v2 / v, v13 / v, v13 / v};
}

// Ishigami of a point in the standardised space s ∈ (0, 1)³.
double ishigami(const Eigen::VectorXd& s) {
  const Eigen::Array3d x = -pi + 2 * pi * s.array();
  return std::sin(x[0]) + ishigami_a * std::sin(x[1]) * std::sin(x[1]) +
         ishigami_b * std::pow(x[2], 4) * std::sin(x[0]);
}

PolynomialChaosResult fit_ishigami(std::size_t n_points, int max_degree,
                                   std::vector<DegreeDiagnostics>* diagnostics = nullptr) {
  const Eigen::MatrixXd points = latin_hypercube(n_points, 3, 31415);
  Eigen::VectorXd y(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) y[i] = ishigami(points.row(i).transpose());
  PceOptions options;
  options.max_degree = max_degree;
  SparsePolynomialChaos chaos(points, y, std::vector<StandardSpace>(3, StandardSpace::unit_interval),
                              options);
  chaos.run();
  if (diagnostics != nullptr) *diagnostics = chaos.degree_diagnostics();
  return chaos.result();
}

void print_indices(const std::string& label, const SobolIndices& indices) {
  std::cout << "[ figures  ] " << label << std::fixed << std::setprecision(4)
            << ": S = (" << indices.first_order[0] << ", " << indices.first_order[1] << ", "
            << indices.first_order[2] << "), S_T = (" << indices.total_order[0] << ", "
            << indices.total_order[1] << ", " << indices.total_order[2] << ")";
  if (indices.second_order.size() > 0) std::cout << ", S_13 = " << indices.second_order(0, 2);
  std::cout << ", V = " << indices.variance << std::defaultfloat << "\n";
}

TEST(Sobol, IndicesFromHandBuiltCoefficientsMatchClosedForms) {
  PolynomialChaosResult chaos;
  chaos.families.assign(3, PolynomialFamily::legendre);
  chaos.multi_indices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 2},
                         {1, 1, 0}, {1, 0, 1}, {0, 2, 3}, {1, 1, 1}};
  chaos.coefficients = (Eigen::VectorXd(8) << 5, 2, -1, 0.5, 0.3, 0.7, -0.4, 0.2).finished();
  // D = Σ_{α≠0} c² = 4 + 1 + 0.25 + 0.09 + 0.49 + 0.16 + 0.04.
  const double d = 6.03;
  const SobolIndices indices = sobol_indices(chaos);
  const double tolerance = 1e-12;
  EXPECT_NEAR(chaos.mean(), 5, tolerance);
  EXPECT_NEAR(indices.variance, d, tolerance);
  EXPECT_NEAR(indices.first_order[0], 4 / d, tolerance);
  EXPECT_NEAR(indices.first_order[1], 1 / d, tolerance);
  EXPECT_NEAR(indices.first_order[2], 0.25 / d, tolerance);
  EXPECT_NEAR(indices.total_order[0], (4 + 0.09 + 0.49 + 0.04) / d, tolerance);
  EXPECT_NEAR(indices.total_order[1], (1 + 0.09 + 0.16 + 0.04) / d, tolerance);
  EXPECT_NEAR(indices.total_order[2], (0.25 + 0.49 + 0.16 + 0.04) / d, tolerance);
  EXPECT_NEAR(indices.second_order(0, 1), 0.09 / d, tolerance);
  EXPECT_NEAR(indices.second_order(0, 2), 0.49 / d, tolerance);
  EXPECT_NEAR(indices.second_order(1, 2), 0.16 / d, tolerance);
  EXPECT_EQ(indices.second_order(2, 1), indices.second_order(1, 2));
  EXPECT_EQ(indices.second_order(1, 1), 0);
  // Σ S_i + Σ S_ij + S_123 = 1.
  EXPECT_NEAR(indices.first_order.sum() + indices.second_order.sum() / 2 + 0.04 / d, 1, tolerance);
}

TEST(Sobol, ConstantModelHasUndefinedIndices) {
  PolynomialChaosResult chaos;
  chaos.families.assign(2, PolynomialFamily::hermite);
  chaos.multi_indices = {{0, 0}};
  chaos.coefficients = Eigen::VectorXd::Constant(1, 3.0);
  const SobolIndices indices = sobol_indices(chaos);
  EXPECT_EQ(indices.variance, 0);
  EXPECT_TRUE(std::isnan(indices.first_order[0]));
  EXPECT_TRUE(std::isnan(indices.total_order[1]));
}

TEST(Sobol, IshigamiIndicesWithinTolerance) {
  const IshigamiReference reference = ishigami_reference();
  std::vector<DegreeDiagnostics> diagnostics;
  const PolynomialChaosResult chaos = fit_ishigami(400, 12, &diagnostics);
  const SobolIndices indices = sobol_indices(chaos);
  print_indices("Ishigami exact", SobolIndices{
      (Eigen::VectorXd(3) << reference.s1, reference.s2, reference.s3).finished(),
      (Eigen::VectorXd(3) << reference.st1, reference.st2, reference.st3).finished(),
      (Eigen::MatrixXd(3, 3) << 0, 0, reference.s13, 0, 0, 0, reference.s13, 0, 0).finished(),
      reference.variance});
  print_indices("Ishigami PCE N=400, degree cap 12", indices);
  std::cout << "[ figures  ] selected degree " << chaos.degree << ", " << chaos.multi_indices.size()
            << " terms, LOO error " << chaos.loo_error << ", corrected " << chaos.corrected_loo_error
            << "\n";
  for (const auto& d : diagnostics) {
    std::cout << "[ figures  ]   degree " << d.degree << ": " << d.n_terms << " of " << d.n_candidates
              << " terms, corrected LOO " << d.corrected_loo_error << "\n";
  }
  const double tolerance = 0.005;
  EXPECT_NEAR(indices.first_order[0], reference.s1, tolerance);
  EXPECT_NEAR(indices.first_order[1], reference.s2, tolerance);
  EXPECT_NEAR(indices.first_order[2], reference.s3, tolerance);
  EXPECT_NEAR(indices.total_order[0], reference.st1, tolerance);
  EXPECT_NEAR(indices.total_order[1], reference.st2, tolerance);
  EXPECT_NEAR(indices.total_order[2], reference.st3, tolerance);
  EXPECT_NEAR(indices.second_order(0, 2), reference.s13, tolerance);
  EXPECT_NEAR(indices.second_order(0, 1), 0, tolerance);
  EXPECT_NEAR(indices.second_order(1, 2), 0, tolerance);
  EXPECT_NEAR(chaos.variance(), reference.variance, 0.005 * reference.variance);
  EXPECT_NEAR(chaos.mean(), ishigami_a / 2, 0.01);
  EXPECT_LT(chaos.corrected_loo_error, 1e-4);
  EXPECT_EQ(indices.corrected_loo_error, chaos.corrected_loo_error);
}

TEST(Sobol, IshigamiDegreeFiveLooErrorFlagsThePoorFit) {
  // Degree ≤ 5 cannot represent sin and x⁴ sin on [−π, π]: the LOO error says so,
  // while the degree-12 fit's is orders of magnitude smaller.
  const PolynomialChaosResult low = fit_ishigami(400, 5);
  const PolynomialChaosResult high = fit_ishigami(400, 12);
  std::cout << "[ figures  ] Ishigami N=400: LOO error at degree cap 5: " << low.loo_error
            << " (corrected " << low.corrected_loo_error << "); at cap 12: " << high.loo_error
            << " (corrected " << high.corrected_loo_error << ")\n";
  EXPECT_GT(low.loo_error, 1e-2);
  EXPECT_LT(high.corrected_loo_error, 1e-3 * low.corrected_loo_error);
}

TEST(Sobol, JansenMonteCarloAgreesWithPceOnIshigami) {
  const SobolIndices pce = sobol_indices(fit_ishigami(400, 12));
  const SobolIndices monte_carlo = monte_carlo_sobol(
      ishigami, std::vector<StandardSpace>(3, StandardSpace::unit_interval), 100000, 2718);
  print_indices("Ishigami Monte Carlo N=1e5 (Saltelli S, Jansen S_T)", monte_carlo);
  const IshigamiReference reference = ishigami_reference();
  EXPECT_NEAR(monte_carlo.variance, reference.variance, 0.02 * reference.variance);
  for (Eigen::Index i = 0; i < 3; ++i) {
    EXPECT_NEAR(monte_carlo.first_order[i], pce.first_order[i], 0.02) << "S_" << i + 1;
    EXPECT_NEAR(monte_carlo.total_order[i], pce.total_order[i], 0.02) << "S_T" << i + 1;
  }
}

TEST(Sobol, MonteCarloOnAdditiveNormalModelMatchesVarianceShares) {
  // y = 3 z1 + z2 with standard normal inputs: S = S_T = (0.9, 0.1).
  const SobolIndices indices = monte_carlo_sobol(
      [](const Eigen::VectorXd& z) { return 3 * z[0] + z[1]; },
      std::vector<StandardSpace>(2, StandardSpace::standard_normal), 20000, 1);
  EXPECT_NEAR(indices.first_order[0], 0.9, 0.02);
  EXPECT_NEAR(indices.first_order[1], 0.1, 0.02);
  EXPECT_NEAR(indices.total_order[0], 0.9, 0.02);
  EXPECT_NEAR(indices.total_order[1], 0.1, 0.02);
  EXPECT_NEAR(indices.variance, 10, 0.3);
}

}  // namespace
}  // namespace rsw::calibration
