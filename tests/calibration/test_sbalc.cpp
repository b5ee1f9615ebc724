// SBALC (calibration/sbalc.hpp) against evidences known independently of it:
//   - a linear-Gaussian model, whose evidence is derived in closed form below;
//   - a banana-shaped posterior, whose evidence is computed by midpoint quadrature on a
//     2000 × 2000 grid;
//   - the linear-Gaussian log-likelihood plus deterministic high-frequency noise, the
//     situation in which the paper's SBALC did not converge (paper §3.3), handled by the
//     estimated nugget (docs/CALIBRATION.md, "The nugget").
// All problems live in the standardised space with the uniform prior on [0,1]², so the
// evidence is c = ∫_{[0,1]²} exp ℒ(θ) dθ. Each test prints evidence errors and
// evaluation counts.
#include "calibration/likelihood.hpp"
#include "calibration/posterior.hpp"
#include "calibration/sbalc.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <set>

namespace rsw::calibration {
namespace {

// Linear model M(θ) = b + Aθ with three features, two replicates and known σ_j:
//     ℒ(θ) = −½ Σ_k (y_k − M(θ))ᵀ Σ⁻¹ (y_k − M(θ)) − (N/2) ln det(2πΣ)
// is exactly quadratic, ℒ(θ) = ℒ(θ̂) − ½ (θ − θ̂)ᵀ P (θ − θ̂) with P = N AᵀΣ⁻¹A and
// θ̂ = P⁻¹ AᵀΣ⁻¹ Σ_k (y_k − b). With the prior density 1 on the box and θ̂ many
// posterior standard deviations from its faces,
//     c = ∫ exp ℒ dθ = exp ℒ(θ̂) · 2π / √det P · (1 − ε),
// where the truncated mass ε ≤ Σ_j erfc(d_j / (√2 sd_j)), d_j the distance of θ̂_j to
// the nearer face, is checked below to be negligible.
struct LinearGaussianProblem {
  Eigen::Matrix<double, 3, 2> a;
  Eigen::Vector3d b;
  GaussianLikelihood likelihood;
  Eigen::Vector2d mode;
  Eigen::Matrix2d precision;
  double log_evidence = 0.0;
  double truncated_mass_bound = 0.0;

  static LinearGaussianProblem make() {
    Eigen::Matrix<double, 3, 2> a;
    a << 1.0, 0.4, 0.3, 1.2, 0.8, -0.9;
    const Eigen::Vector3d b(0.5, 0.2, 0.1);
    const Eigen::Vector3d sd(0.12, 0.12, 0.15);
    const Eigen::Vector2d theta_true(0.5, 0.5);
    const Eigen::Vector3d truth = b + a * theta_true;
    Eigen::Matrix<double, 2, 3> y;
    y.row(0) = (truth + Eigen::Vector3d(0.05, -0.03, 0.04)).transpose();
    y.row(1) = (truth + Eigen::Vector3d(-0.02, 0.06, -0.05)).transpose();
    GaussianLikelihood likelihood({"f1", "f2", "f3"}, y,
                                  ObservationNoise::given({{"f1", sd(0)}, {"f2", sd(1)}, {"f3", sd(2)}}));
    LinearGaussianProblem problem{a, b, likelihood, {}, {}, 0.0, 0.0};
    const Eigen::Matrix3d sigma_inverse = sd.cwiseAbs2().cwiseInverse().asDiagonal();
    problem.precision = 2.0 * a.transpose() * sigma_inverse * a;
    const Eigen::Vector3d residual_sum = y.row(0).transpose() + y.row(1).transpose() - 2.0 * b;
    problem.mode = problem.precision.ldlt().solve(a.transpose() * sigma_inverse * residual_sum);
    problem.log_evidence =
        problem.log_likelihood(problem.mode) + std::log(2.0 * M_PI) - 0.5 * std::log(problem.precision.determinant());
    const Eigen::Matrix2d covariance = problem.precision.inverse();
    for (int j = 0; j < 2; ++j) {
      const double distance = std::min(problem.mode(j), 1.0 - problem.mode(j));
      problem.truncated_mass_bound += std::erfc(distance / std::sqrt(2.0 * covariance(j, j)));
    }
    return problem;
  }

  double log_likelihood(const Eigen::VectorXd& theta) const {
    return likelihood.log_likelihood(Eigen::Vector3d(b + a * theta));
  }
};

// Banana: x = 4θ − 2 ∈ [−2, 2]², ℒ = −½ (x₁/0.6)² − ½ ((x₂ − 1.5 x₁² + 0.6)/0.3)².
double banana_log_likelihood(const Eigen::VectorXd& theta) {
  const double x1 = 4.0 * theta(0) - 2.0, x2 = 4.0 * theta(1) - 2.0;
  const double u = x1 / 0.6, v = (x2 - 1.5 * x1 * x1 + 0.6) / 0.3;
  return -0.5 * u * u - 0.5 * v * v;
}

// ln ∫_{[0,1]²} exp ℒ by the midpoint rule on an n × n grid.
double log_evidence_by_quadrature(double (*log_likelihood)(const Eigen::VectorXd&), int n) {
  double sum = 0.0;
  Eigen::Vector2d theta;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      theta << (i + 0.5) / n, (j + 0.5) / n;
      sum += std::exp(log_likelihood(theta));
    }
  return std::log(sum / (static_cast<double>(n) * n));
}

void print_history(const char* name, const SbalcResult& result) {
  for (const SbalcIteration& it : result.history)
    std::printf("  %s n=%2d ln c=%9.4f [%9.4f, %9.4f] ratio=%.3e (gp %.3e) tol=%.3f tau=%.2e S=%.2f ESS=%.0f mc=%.3f "
                "l=(%.3f, %.3f)%s%s\n",
                name, it.n_points, it.log_evidence, it.log_evidence_lower, it.log_evidence_upper, it.ratio,
                it.gp_ratio, it.tolerance_used, it.noise_standard_deviation, it.peak_spread, it.pool_ess,
                it.pool_relative_error, it.hyperparameters.length_scales(0), it.hyperparameters.length_scales(1),
                it.counted ? " counted" : "",
                it.refusal.empty() ? "" : (" refused: " + it.refusal).c_str());
}

TEST(Sbalc, LinearGaussianEvidenceWithinTenPercent) {
  const LinearGaussianProblem problem = LinearGaussianProblem::make();
  ASSERT_LT(problem.truncated_mass_bound, 1e-6);
  SbalcOptions options;
  options.max_evaluations = 60;
  const SbalcResult result =
      Sbalc(2, [&](const Eigen::VectorXd& theta) { return std::optional<double>(problem.log_likelihood(theta)); },
            options)
          .run();
  print_history("linear", result);
  const double error = std::exp(result.log_evidence - problem.log_evidence) - 1.0;
  std::printf("linear-Gaussian: ln c exact %.5f, SBALC %.5f, relative error %+.2f %%, %d evaluations, %s\n",
              problem.log_evidence, result.log_evidence, 100.0 * error, result.n_evaluations,
              result.stop_reason.c_str());
  EXPECT_TRUE(result.converged) << result.stop_reason;
  EXPECT_LT(std::abs(error), 0.1);
  EXPECT_LE(result.n_evaluations, 40);
  // The bounds bracket the estimate and the final ratio is below the tolerance.
  EXPECT_LE(result.log_evidence_lower, result.log_evidence);
  EXPECT_GE(result.log_evidence_upper, result.log_evidence);
  EXPECT_LT(result.ratio, 0.1);
}

TEST(Sbalc, BananaEvidenceMatchesQuadrature) {
  const double reference = log_evidence_by_quadrature(banana_log_likelihood, 2000);
  SbalcOptions options;
  options.max_evaluations = 80;
  const SbalcResult result =
      Sbalc(2, [](const Eigen::VectorXd& theta) { return std::optional<double>(banana_log_likelihood(theta)); },
            options)
          .run();
  print_history("banana", result);
  const double error = std::exp(result.log_evidence - reference) - 1.0;
  std::printf("banana: ln c quadrature %.5f, SBALC %.5f, relative error %+.2f %%, %d evaluations, %s\n", reference,
              result.log_evidence, 100.0 * error, result.n_evaluations, result.stop_reason.c_str());
  EXPECT_TRUE(result.converged) << result.stop_reason;
  EXPECT_LT(std::abs(error), 0.1);
  // 59 runs with the paper's ratio; the pool's Monte Carlo error in the bounds (1.6 %,
  // ESS ≈ 3000) and counting only iterations after the initial design cost two more.
  EXPECT_LE(result.n_evaluations, 65);
}

TEST(Sbalc, IdenticalSeedsGiveIdenticalResults) {
  SbalcOptions options;
  options.pool_size = 5000;
  options.max_evaluations = 30;
  const auto f = [](const Eigen::VectorXd& theta) { return std::optional<double>(banana_log_likelihood(theta)); };
  const SbalcResult first = Sbalc(2, f, options).run();
  const SbalcResult second = Sbalc(2, f, options).run();
  ASSERT_EQ(first.design.rows(), second.design.rows());
  EXPECT_EQ(first.design, second.design);
  EXPECT_EQ(first.log_evidence, second.log_evidence);
  EXPECT_EQ(first.history.size(), second.history.size());
  options.seed = 2;
  const SbalcResult other = Sbalc(2, f, options).run();
  EXPECT_NE(first.pool, other.pool);
  EXPECT_NE(first.log_evidence, other.log_evidence);
}

// A broad Gaussian log-likelihood (sd 0.2 and 0.16, correlation 0.4, mode (0.5, 0.45),
// so the prior box truncates it and the reference is by quadrature) plus reproducible
// noise ε(θ) = 0.3 [sin(200 θ₁) + sin(170 θ₂)] (standard deviation 0.3 log-likelihood
// units over the box), like the FE model's discretisation noise (paper Fig. 6). The
// reference is the evidence of the smooth part. At amplitudes of 0.05–0.1 on this
// problem the interpolating GP is not yet troubled (both variants converge), so the
// test uses 0.3. On seeds 1–6 with the nugget every run converges in 21–26
// evaluations (error within 10 % on five, 13 % on one: the accepted noise-limited
// spread, reported as noise_ratio); without it none converges within 60. The test pins
// the default seed.
double smooth_log_likelihood(const Eigen::VectorXd& theta) {
  const double sd = 0.2, rho = 0.4;
  Eigen::Matrix2d covariance;
  covariance << sd * sd, rho * sd * 0.8 * sd, rho * sd * 0.8 * sd, 0.64 * sd * sd;
  const Eigen::Vector2d r = theta - Eigen::Vector2d(0.5, 0.45);
  return 3.0 - 0.5 * r.dot(covariance.inverse() * r);
}

TEST(Sbalc, NuggetHandlesDeterministicHighFrequencyNoise) {
  const double reference = log_evidence_by_quadrature(smooth_log_likelihood, 1000);
  const auto noisy = [](const Eigen::VectorXd& theta) {
    return std::optional<double>(smooth_log_likelihood(theta) +
                                 0.3 * (std::sin(200.0 * theta(0)) + std::sin(170.0 * theta(1))));
  };
  SbalcOptions options;
  options.max_evaluations = 60;
  options.gp.nugget_mode = NuggetMode::Estimated;
  const SbalcResult with_nugget = Sbalc(2, noisy, options).run();
  print_history("nugget", with_nugget);
  const double error = std::exp(with_nugget.log_evidence - reference) - 1.0;
  std::printf("noisy Gaussian with nugget: relative error %+.2f %% (vs the smooth evidence), %d evaluations, "
              "noise sd %.4f (injected 0.3), noise ratio %.3f, %s\n",
              100.0 * error, with_nugget.n_evaluations, with_nugget.noise_standard_deviation,
              with_nugget.noise_ratio, with_nugget.stop_reason.c_str());
  EXPECT_TRUE(with_nugget.converged) << with_nugget.stop_reason;
  EXPECT_LE(with_nugget.n_evaluations, 40);
  EXPECT_LT(std::abs(error), 0.1);
  EXPECT_GT(with_nugget.noise_standard_deviation, 0.05);
  EXPECT_LT(with_nugget.noise_standard_deviation, 0.6);
  for (const SbalcIteration& it : with_nugget.history) EXPECT_GE(it.tolerance_used, options.tolerance);

  // The interpolating GP chases the noise and does not converge within the cap, as the
  // paper found on the FE model.
  options.gp.nugget_mode = NuggetMode::Off;
  const SbalcResult without_nugget = Sbalc(2, noisy, options).run();
  std::printf("noisy Gaussian without nugget: converged %d after %d evaluations, final ratio %.3f, "
              "relative error %+.2f %%\n",
              without_nugget.converged, without_nugget.n_evaluations, without_nugget.ratio,
              100.0 * (std::exp(without_nugget.log_evidence - reference) - 1.0));
  EXPECT_FALSE(without_nugget.converged);
  EXPECT_EQ(without_nugget.n_evaluations, options.max_evaluations);
  EXPECT_EQ(without_nugget.noise_ratio, 0.0);
}

TEST(Sbalc, BatchesOfPointsGoToTheBatchEvaluatorTogether) {
  const LinearGaussianProblem problem = LinearGaussianProblem::make();
  std::vector<std::size_t> batch_sizes;
  std::set<std::pair<double, double>> seen;
  bool repeated = false;
  const BatchLogLikelihoodFunction batch = [&](const std::vector<Eigen::VectorXd>& thetas) {
    batch_sizes.push_back(thetas.size());
    std::vector<std::optional<double>> values;
    for (const auto& theta : thetas) {
      repeated = repeated || !seen.insert({theta(0), theta(1)}).second;
      values.push_back(problem.log_likelihood(theta));
    }
    return values;
  };
  SbalcOptions options;
  options.batch_size = 4;
  options.max_evaluations = 60;
  const SbalcResult result = Sbalc(2, batch, options).run();
  const double error = std::exp(result.log_evidence - problem.log_evidence) - 1.0;
  std::printf("batches of 4: %zu evaluator calls, %d evaluations, relative error %+.2f %%\n", batch_sizes.size(),
              result.n_evaluations, 100.0 * error);
  ASSERT_GE(batch_sizes.size(), 2u);
  EXPECT_EQ(batch_sizes.front(), 5u);  // the initial design in one call
  for (std::size_t i = 1; i < batch_sizes.size(); ++i) EXPECT_EQ(batch_sizes[i], 4u);
  EXPECT_FALSE(repeated);
  EXPECT_TRUE(result.converged) << result.stop_reason;
  EXPECT_LT(std::abs(error), 0.1);
}

TEST(Sbalc, FailedEvaluationsAreRecordedAndNeverReproposed) {
  // The "simulator" fails for θ₁ > 0.8, a region of negligible likelihood.
  const LinearGaussianProblem problem = LinearGaussianProblem::make();
  std::set<std::pair<double, double>> seen;
  bool repeated = false;
  const auto f = [&](const Eigen::VectorXd& theta) -> std::optional<double> {
    repeated = repeated || !seen.insert({theta(0), theta(1)}).second;
    if (theta(0) > 0.8) return std::nullopt;
    return problem.log_likelihood(theta);
  };
  SbalcOptions options;
  options.max_evaluations = 60;
  const SbalcResult result = Sbalc(2, f, options).run();
  const double error = std::exp(result.log_evidence - problem.log_evidence) - 1.0;
  std::printf("with failures: %zu failed of %d evaluations, relative error %+.2f %%, %s\n", result.failures.size(),
              result.n_evaluations, 100.0 * error, result.stop_reason.c_str());
  EXPECT_FALSE(repeated);
  EXPECT_GE(result.failures.size(), 1u);  // the Hammersley point (0.9, ·) fails
  EXPECT_LE(result.failures.size(), 5u);  // and SBALC does not keep sampling the failing region
  for (const auto& failure : result.failures) EXPECT_GT(failure.theta(0), 0.8);
  EXPECT_EQ(result.design.rows() + static_cast<Eigen::Index>(result.failures.size()), result.n_evaluations);
  EXPECT_LT(std::abs(error), 0.1);
}

TEST(Sbalc, FailingRegionNextToThePosteriorIsLearntAsPoorFitWhenImputed) {
  // The "simulator" fails for θ₁ > θ̂₁ + 1 sd: a failing region that cuts through the
  // posterior (as a melting electrode cuts through the contact-parameter prior). With
  // failed runs imputed at the lowest ℒ seen, the failing region leaves the evidence,
  // which is then the integral of exp ℒ over the part of the box where the model runs
  // (computed here by midpoint quadrature), and SBALC stops proposing it.
  const LinearGaussianProblem problem = LinearGaussianProblem::make();
  const double cut = problem.mode(0) + std::sqrt(problem.precision.inverse()(0, 0));
  const auto f = [&](const Eigen::VectorXd& theta) -> std::optional<double> {
    if (theta(0) > cut) return std::nullopt;
    return problem.log_likelihood(theta);
  };
  double sum = 0.0;
  const int n = 2000;
  Eigen::Vector2d theta;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      theta << (i + 0.5) / n, (j + 0.5) / n;
      if (theta(0) <= cut) sum += std::exp(problem.log_likelihood(theta));
    }
  const double reference = std::log(sum / (static_cast<double>(n) * n));

  SbalcOptions options;
  options.max_evaluations = 100;
  // Imputation alone: the log-likelihood floor (on by default) would put the imputed
  // value at ℒ_max − 50 instead of the lowest ℒ seen; the cliff it leaves at the cut
  // then drives the length scale to its bound and SBALC needs more than 150 runs.
  options.log_likelihood_range = 0.0;
  const SbalcResult imputed = Sbalc(2, f, options).run();
  print_history("imputed", imputed);
  const double error = std::exp(imputed.log_evidence - reference) - 1.0;
  options.failed_runs = FailedRunPolicy::exclude;
  const SbalcResult excluded = Sbalc(2, f, options).run();
  const double error_excluded = std::exp(excluded.log_evidence - reference) - 1.0;
  std::printf("failing region through the posterior: imputed %zu failed of %d, evidence error %+.2f %%, %s; "
              "excluded %zu failed of %d, evidence error %+.2f %%, %s\n",
              imputed.failures.size(), imputed.n_evaluations, 100.0 * error, imputed.stop_reason.c_str(),
              excluded.failures.size(), excluded.n_evaluations, 100.0 * error_excluded,
              excluded.stop_reason.c_str());
  // The imputed evidence is right; whether SBALC also claims convergence depends on the
  // cliff at the failure boundary, where the GP alternates between two length scales
  // and the paper's ratio between 0.09 and 0.25 (measured up to 150 runs); with the
  // pool's Monte Carlo error (ESS ≈ 800, 3.4 %) in the bounds it does not converge
  // within 150 runs. Not converged, it must say so.
  EXPECT_LT(std::abs(error), 0.1);
  if (!imputed.converged) {
    EXPECT_FALSE(imputed.warnings.empty()) << imputed.stop_reason;
  }
  // The cliff takes many points to resolve, but few of them fail.
  EXPECT_LT(7 * imputed.failures.size(), static_cast<std::size_t>(imputed.n_evaluations));
  EXPECT_GT(imputed.history.back().n_imputed, 0);
  EXPECT_EQ(imputed.design.rows() + static_cast<Eigen::Index>(imputed.failures.size()), imputed.n_evaluations);
  // Excluded, the failing region is extrapolated over by the GP (its evidence is not the
  // reference's), and the result says so even when it converges.
  ASSERT_FALSE(excluded.failures.empty());
  ASSERT_FALSE(excluded.warnings.empty());
  EXPECT_NE(excluded.warnings.front().find("left out of the GP"), std::string::npos) << excluded.warnings.front();
}

TEST(Sbalc, AdaptivePoolResolvesAPosteriorMuchNarrowerThanThePriorPool) {
  // ℒ(θ) = −½ Σ_j ((θ_j − μ_j)/σ_j)² with σ = (0.002, 0.004): c = 2π σ₁σ₂ (the box holds
  // the whole Gaussian). A prior pool of 20 000 points has about 20 000 · (4σ₁)(4σ₂) ≈ 2.6
  // points inside ±2σ, too few to estimate c or the posterior; the adaptive pool zooms in.
  const Eigen::Vector2d mu(0.37, 0.61), sigma(0.002, 0.004);
  const auto f = [&](const Eigen::VectorXd& theta) -> std::optional<double> {
    return -0.5 * ((theta - mu).array() / sigma.array()).square().sum();
  };
  const double reference = std::log(2.0 * M_PI * sigma(0) * sigma(1));
  SbalcOptions options;
  options.gp.trend = TrendType::FullQuadratic;
  // The prior pool cannot resolve it: its effective sample size stays near 3, below the
  // stopping guard's 200, so it runs to its cap (40 here, to keep the test short).
  options.max_evaluations = 40;
  const SbalcResult prior = Sbalc(2, f, options).run();
  options.max_evaluations = 80;
  options.adaptive_pool = true;
  const SbalcResult adaptive = Sbalc(2, f, options).run();
  PosteriorOptions posterior_options;
  posterior_options.credible_level = 0.9;
  const PosteriorResult posterior = SirPosterior(adaptive, posterior_options).run();
  const PosteriorResult posterior_prior = SirPosterior(prior, posterior_options).run();
  const double error = std::exp(adaptive.log_evidence - reference) - 1.0;
  std::printf("narrow posterior: adaptive pool %d runs, %s, evidence error %+.2f %%, ESS %.0f, mean (%.5f, %.5f), "
              "sd (%.5f, %.5f); prior pool: %s, evidence error %+.2f %%, ESS %.1f\n",
              adaptive.n_evaluations, adaptive.stop_reason.c_str(), 100.0 * error, posterior.effective_sample_size,
              posterior.mean(0), posterior.mean(1), posterior.standard_deviation(0), posterior.standard_deviation(1),
              prior.stop_reason.c_str(), 100.0 * (std::exp(prior.log_evidence - reference) - 1.0),
              posterior_prior.effective_sample_size);
  EXPECT_TRUE(adaptive.converged) << adaptive.stop_reason;
  EXPECT_LT(std::abs(error), 0.1);
  EXPECT_GT(posterior.effective_sample_size, 1000.0);
  EXPECT_LT(posterior_prior.effective_sample_size, 20.0);
  EXPECT_FALSE(prior.converged) << prior.stop_reason;
  EXPECT_TRUE(prior.history.back().pool_ess_too_low);
  for (int j = 0; j < 2; ++j) {
    EXPECT_NEAR(posterior.mean(j), mu(j), 0.2 * sigma(j));
    EXPECT_NEAR(posterior.standard_deviation(j), sigma(j), 0.15 * sigma(j));
  }
}

TEST(Sbalc, PosteriorFromSbalcMatchesLinearGaussianMoments) {
  const LinearGaussianProblem problem = LinearGaussianProblem::make();
  const SbalcResult sbalc =
      Sbalc(2, [&](const Eigen::VectorXd& theta) { return std::optional<double>(problem.log_likelihood(theta)); })
          .run();
  const PosteriorResult posterior = SirPosterior(sbalc).run();
  const Eigen::Matrix2d covariance = problem.precision.inverse();
  std::printf("posterior mean (%.4f, %.4f) exact (%.4f, %.4f); sd (%.4f, %.4f) exact (%.4f, %.4f); ESS %.0f\n",
              posterior.mean(0), posterior.mean(1), problem.mode(0), problem.mode(1), posterior.standard_deviation(0),
              posterior.standard_deviation(1), std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1)),
              posterior.effective_sample_size);
  EXPECT_FALSE(posterior.poorly_resolved);
  for (int j = 0; j < 2; ++j) {
    EXPECT_NEAR(posterior.mean(j), problem.mode(j), 0.01);
    EXPECT_NEAR(posterior.standard_deviation(j), std::sqrt(covariance(j, j)), 0.15 * std::sqrt(covariance(j, j)));
  }
  EXPECT_TRUE(posterior.map_refined);
  EXPECT_LT((posterior.map_point - problem.mode).norm(), 0.02);
}

}  // namespace
}  // namespace rsw::calibration
