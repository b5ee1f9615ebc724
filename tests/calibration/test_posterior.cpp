// SIR posterior of a prior pool (calibration/posterior.hpp): moments, intervals and
// correlation of a Gaussian posterior well inside [0,1]², and the small-sample warning
// when the posterior sits in a corner of the pool.
#include "calibration/posterior.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

namespace rsw::calibration {
namespace {

Eigen::MatrixXd uniform_pool(int n, int d, std::uint64_t seed) {
  std::mt19937_64 generator(seed);
  Eigen::MatrixXd x(n, d);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < d; ++j) x(i, j) = static_cast<double>(generator() >> 11) * 0x1.0p-53;
  return x;
}

// Log density of N(mean, covariance) (up to a constant) at the pool points.
Eigen::VectorXd gaussian_log_density(const Eigen::MatrixXd& pool, const Eigen::Vector2d& mean,
                                     const Eigen::Matrix2d& covariance) {
  const Eigen::Matrix2d precision = covariance.inverse();
  Eigen::VectorXd l(pool.rows());
  for (Eigen::Index i = 0; i < pool.rows(); ++i) {
    const Eigen::Vector2d r = pool.row(i).transpose() - mean;
    l(i) = -0.5 * r.dot(precision * r) - 40.0;  // an offset: SIR must not care
  }
  return l;
}

TEST(Posterior, SirMomentsMatchLinearGaussian) {
  // A linear-Gaussian posterior: N(μ, C), sd (0.08, 0.06), correlation 0.6, μ ± 5 sd
  // inside the prior box so truncation is negligible. Pool of 2·10⁴: ESS ≈ 10³, so the
  // Monte Carlo error of the mean is ≈ sd/√ESS ≈ 0.003.
  const Eigen::Vector2d mu(0.45, 0.55);
  const Eigen::Vector2d sd(0.08, 0.06);
  const double rho = 0.6;
  Eigen::Matrix2d covariance;
  covariance << sd(0) * sd(0), rho * sd(0) * sd(1), rho * sd(0) * sd(1), sd(1) * sd(1);
  const Eigen::MatrixXd pool = uniform_pool(20000, 2, 17);
  const PosteriorResult result = SirPosterior(pool, gaussian_log_density(pool, mu, covariance)).run();
  std::printf("ESS %.0f (threshold %.0f); mean (%.4f, %.4f) vs (%.4f, %.4f); sd (%.4f, %.4f) vs (%.4f, %.4f); "
              "correlation %.3f vs %.3f\n",
              result.effective_sample_size, result.ess_threshold, result.mean(0), result.mean(1), mu(0), mu(1),
              result.standard_deviation(0), result.standard_deviation(1), sd(0), sd(1), result.correlation(0, 1), rho);
  EXPECT_FALSE(result.poorly_resolved) << result.warning;
  EXPECT_TRUE(result.warning.empty());
  for (int j = 0; j < 2; ++j) {
    EXPECT_NEAR(result.mean(j), mu(j), 0.01);
    EXPECT_NEAR(result.standard_deviation(j), sd(j), 0.1 * sd(j));
    // Equal-tailed 95 % interval of a Gaussian marginal: μ ± 1.95996 sd.
    EXPECT_NEAR(result.credible_intervals[j].lower, mu(j) - 1.959964 * sd(j), 0.2 * sd(j));
    EXPECT_NEAR(result.credible_intervals[j].upper, mu(j) + 1.959964 * sd(j), 0.2 * sd(j));
  }
  EXPECT_NEAR(result.correlation(0, 1), rho, 0.06);
  EXPECT_DOUBLE_EQ(result.correlation(0, 1), result.correlation(1, 0));
  // The resampled draws carry the same moments.
  ASSERT_EQ(result.samples.rows(), 20000);
  const Eigen::Vector2d sample_mean = result.samples.colwise().mean().transpose();
  EXPECT_NEAR(sample_mean(0), result.mean(0), 0.005);
  EXPECT_NEAR(sample_mean(1), result.mean(1), 0.005);
  // MAP: the best pool point is near the mode.
  EXPECT_LT((result.map_point - mu).norm(), 0.03);
}

TEST(Posterior, MapIsRefinedOnTheLogDensity) {
  const Eigen::Vector2d mu(0.3, 0.7);
  const Eigen::Matrix2d covariance = Eigen::Vector2d(0.01, 0.02).asDiagonal();
  const Eigen::MatrixXd pool = uniform_pool(2000, 2, 3);
  const auto log_density = [&](const Eigen::VectorXd& theta) {
    const Eigen::Vector2d r = theta - mu;
    return -0.5 * r.dot(covariance.inverse() * r);
  };
  const PosteriorResult result = SirPosterior(pool, gaussian_log_density(pool, mu, covariance) +
                                                        Eigen::VectorXd::Constant(2000, 40.0),
                                              {}, log_density)
                                     .run();
  EXPECT_TRUE(result.map_refined);
  EXPECT_LT((result.map_point - mu).norm(), 1e-4);
}

TEST(Posterior, TailPosteriorTriggersSmallSampleWarning) {
  // The likelihood peaks at the corner (0.995, 0.995) with sd 0.01: about
  // 2·10⁴ · π/4 · 0.01² ≈ 2 pool points carry the weight. The result must say so.
  const Eigen::MatrixXd pool = uniform_pool(20000, 2, 17);
  const Eigen::Matrix2d covariance = Eigen::Vector2d(1e-4, 1e-4).asDiagonal();
  const PosteriorResult result =
      SirPosterior(pool, gaussian_log_density(pool, Eigen::Vector2d(0.995, 0.995), covariance)).run();
  std::printf("corner posterior: ESS %.1f, threshold %.0f\n", result.effective_sample_size, result.ess_threshold);
  EXPECT_TRUE(result.poorly_resolved);
  EXPECT_LT(result.effective_sample_size, 100.0);
  EXPECT_DOUBLE_EQ(result.ess_threshold, 200.0);  // max(100, 1 % of 2·10⁴)
  EXPECT_NE(result.warning.find("effective sample size"), std::string::npos) << result.warning;
}

}  // namespace
}  // namespace rsw::calibration
