// Tempered SMC and kernel-density importance sampling (calibration/tempered_smc.hpp)
// against evidences and moments known independently of them:
//   - a Gaussian log-likelihood well inside the unit cube, whose evidence is its
//     constant (the mass outside the box is below 1e-20);
//   - a banana in 2-D, whose evidence comes from midpoint quadrature on a 2000² grid;
//   - a likelihood that is zero on half of the box.
#include "calibration/tempered_smc.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace rsw::calibration {
namespace {

// ℓ(u) = c + Σ_i ln N(u_i; μ_i, s_i²): Z = e^c · Π_i P(0 ≤ U_i ≤ 1) = e^c (to 1e-20).
struct GaussianInBox {
  Eigen::VectorXd mean, sd;
  double constant;
  Eigen::VectorXd operator()(const Eigen::MatrixXd& points) const {
    Eigen::VectorXd values(points.rows());
    for (Eigen::Index r = 0; r < points.rows(); ++r) {
      double value = constant;
      for (Eigen::Index i = 0; i < mean.size(); ++i) {
        const double z = (points(r, i) - mean(i)) / sd(i);
        value += -0.5 * z * z - std::log(std::sqrt(2.0 * M_PI) * sd(i));
      }
      values(r) = value;
    }
    return values;
  }
};

TEST(TemperedSmc, RecoversTheEvidenceAndMomentsOfAGaussianInsideTheBox) {
  const GaussianInBox target{Eigen::Vector3d(0.4, 0.5, 0.6), Eigen::Vector3d(0.05, 0.08, 0.03), -2.0};
  const TemperedSmcResult smc = sample_tempered(3, target);
  std::printf("SMC: ln Z %.4f (exact -2), %zu temperatures, acceptance %.2f, %ld evaluations\n", smc.log_evidence,
              smc.temperatures.size(), smc.mean_acceptance, smc.n_density_evaluations);
  EXPECT_NEAR(smc.log_evidence, -2.0, 0.15);
  EXPECT_DOUBLE_EQ(smc.temperatures.back(), 1.0);
  const Eigen::RowVectorXd mean = smc.particles.colwise().mean();
  const Eigen::MatrixXd centred = smc.particles.rowwise() - mean;
  const Eigen::VectorXd sd = (centred.array().square().colwise().sum() / (smc.particles.rows() - 1.0)).sqrt();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(mean(i), target.mean(i), 0.15 * target.sd(i));  // 2000 correlated draws
    EXPECT_NEAR(sd(i), target.sd(i), 0.15 * target.sd(i));
  }

  const ImportanceResult is = importance_sample(smc.particles, target);
  std::printf("importance sampling: ln Z %.4f, relative error %.4f, ESS %.0f of 20000\n", is.log_evidence,
              is.relative_error, is.effective_sample_size);
  EXPECT_NEAR(is.log_evidence, -2.0, 3.0 * is.relative_error + 1e-3);
  EXPECT_LT(is.relative_error, 0.02);
  EXPECT_GT(is.effective_sample_size, 5000.0);
}

// ℓ(u) = −½ ((u1 − 0.5)/0.1)² − ½ ((u2 − 0.3 − 3 (u1 − 0.5)²)/0.04)²: a curved ridge.
Eigen::VectorXd banana(const Eigen::MatrixXd& points) {
  Eigen::VectorXd values(points.rows());
  for (Eigen::Index r = 0; r < points.rows(); ++r) {
    const double a = (points(r, 0) - 0.5) / 0.1;
    const double b = (points(r, 1) - 0.3 - 3.0 * (points(r, 0) - 0.5) * (points(r, 0) - 0.5)) / 0.04;
    values(r) = -0.5 * a * a - 0.5 * b * b;
  }
  return values;
}

TEST(TemperedSmc, ImportanceEvidenceOfABananaMatchesQuadrature) {
  const int n = 2000;
  double sum = 0.0;
  Eigen::MatrixXd row(n, 2);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) row(j, 0) = (i + 0.5) / n, row(j, 1) = (j + 0.5) / n;
    sum += banana(row).array().exp().sum();
  }
  const double exact = std::log(sum / (static_cast<double>(n) * n));
  const TemperedSmcResult smc = sample_tempered(2, banana);
  const ImportanceResult is = importance_sample(smc.particles, banana);
  std::printf("banana: ln Z quadrature %.5f, SMC %.5f, importance %.5f (relative error %.4f, ESS %.0f)\n", exact,
              smc.log_evidence, is.log_evidence, is.relative_error, is.effective_sample_size);
  EXPECT_NEAR(smc.log_evidence, exact, 0.15);
  EXPECT_NEAR(is.log_evidence, exact, std::max(3.0 * is.relative_error, 0.005));
  EXPECT_LT(is.relative_error, 0.03);
}

TEST(TemperedSmc, ParticlesStayWhereTheLikelihoodIsNotZero) {
  // ℓ = 0 for u1 < 0.5, −∞ elsewhere: Z = 1/2, every particle in the left half.
  const BatchLogDensity half = [](const Eigen::MatrixXd& points) {
    Eigen::VectorXd values(points.rows());
    for (Eigen::Index r = 0; r < points.rows(); ++r)
      values(r) = points(r, 0) < 0.5 ? 0.0 : -std::numeric_limits<double>::infinity();
    return values;
  };
  const TemperedSmcResult smc = sample_tempered(2, half);
  EXPECT_NEAR(smc.log_evidence, std::log(0.5), 0.05);
  EXPECT_LT(smc.particles.col(0).maxCoeff(), 0.5);
  EXPECT_GE(smc.particles.minCoeff(), 0.0);
  EXPECT_LE(smc.particles.maxCoeff(), 1.0);
  const ImportanceResult is = importance_sample(smc.particles, half);
  EXPECT_NEAR(is.log_evidence, std::log(0.5), 3.0 * is.relative_error);
  EXPECT_LT(is.points.col(0).maxCoeff(), 1.0);
}

TEST(TemperedSmc, RejectsBadOptions) {
  const GaussianInBox target{Eigen::VectorXd::Constant(1, 0.5), Eigen::VectorXd::Constant(1, 0.1), 0.0};
  TemperedSmcOptions options;
  options.n_particles = 5;
  EXPECT_THROW(sample_tempered(1, target, options), std::invalid_argument);
  options = {};
  options.ess_fraction = 1.0;
  EXPECT_THROW(sample_tempered(1, target, options), std::invalid_argument);
  EXPECT_THROW(sample_tempered(0, target), std::invalid_argument);
  EXPECT_THROW(importance_sample(Eigen::MatrixXd::Zero(1, 1), target), std::invalid_argument);
}

}  // namespace
}  // namespace rsw::calibration
