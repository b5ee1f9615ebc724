// SBALC is never confidently wrong (calibration/sbalc.hpp, "Stopping rule" and guards):
// on problems with known evidence it either reports the evidence within 5 %
// (|ln ĉ − ln c| ≤ ln 1.05) and claims convergence, or it does not claim convergence
// and says why in SbalcResult::warnings. Each problem runs with the library defaults
// (SbalcOptions{}: prior pool, interpolating GP, one point per iteration) and with the
// defaults of `rsw calibrate` (simulator_sbalc_options(): adaptive pool, estimated
// nugget, batches of 4). The exact evidences, all in the standardised space where the
// prior is uniform on [0,1]^d, c = ∫_{[0,1]^d} exp ℒ(u) du:
//
// (a) Tail: prior θ ~ N(0, 1), mapped from u ∈ [0,1] by θ = Φ⁻¹(u); one observation
//     y = 5 of θ with noise N(0, 0.2²): ℒ = ln N(5; θ, 0.2²). The evidence is the
//     convolution of two Gaussians,
//         c = ∫ N(θ; 0, 1) N(5; θ, 0.04) dθ = N(5; 0, 1.04),
//         ln c = −½ ln(2π · 1.04) − 25/(2 · 1.04) = −12.958,
//     and the posterior is N(5/1.04, 0.04/1.04): mean 4.8077, sd 0.19612. The likelihood
//     sits five prior standard deviations out, in u within 2·10⁻⁶ of 1: a prior pool of
//     2·10⁴ points holds almost none of it.
// (b) Six narrow Gaussians: ℒ = Σ_j ln N(u_j; μ_j, σ²), σ = 0.05, μ_j ∈ [0.35, 0.65], so
//         c = Π_j [Φ((1 − μ_j)/σ) − Φ(−μ_j/σ)],
//     which differs from 1 by less than 6 · 2Φ(−7) ≈ 3·10⁻¹¹ (ln c = 0 to that accuracy);
//     computed from erfc below. The posterior holds ~4·10⁻⁶ of the prior volume.
// (c) Bimodal 1-D mixture: ℒ = ln(0.3 N(u; 0.2, 0.03²) + 0.7 N(u; 0.72, 0.05²)), so
//         c = 0.3 [Φ(0.8/0.03) − Φ(−0.2/0.03)] + 0.7 [Φ(0.28/0.05) − Φ(−0.72/0.05)]
//     (1 − 8·10⁻⁹). The initial design (0.1, 0.3, …, 0.9) falls between the narrow
//     mode's points.
// (d) Banana (Rosenbrock-type): x = 4u − 2 ∈ [−2, 2]²,
//         ℒ = −½ (x₁/0.7)² − ½ ((x₂ − 1.2 x₁² + 1)/0.2)²,
//     a curved ridge along x₂ = 1.2 x₁² − 1; c by the midpoint rule on a 2000 × 2000
//     grid (the ridge, 0.05 wide in u, spans 100 grid cells).
//
// Φ(z) = ½ erfc(−z/√2) throughout. All runs are seeded; each prints its figures (with
// SBALC_HISTORY set in the environment, every iteration too). "Without the guards"
// figures were measured with the same problems, seeds and options on the SBALC before
// the guards.
#include "calibration/parameter_space.hpp"
#include "calibration/posterior.hpp"
#include "calibration/sbalc.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>

namespace rsw::calibration {
namespace {

const double tolerance_5_percent = std::log(1.05);

double normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

double log_normal_density(double x, double mean, double sd) {
  const double z = (x - mean) / sd;
  return -0.5 * z * z - std::log(sd * std::sqrt(2.0 * M_PI));
}

// The library's defaults, or those of `rsw calibrate`, with the evaluation cap given.
SbalcOptions library_defaults(int max_evaluations) {
  SbalcOptions options;
  options.max_evaluations = max_evaluations;
  return options;
}

SbalcOptions calibrate_defaults(int max_evaluations) {
  SbalcOptions options = simulator_sbalc_options();
  options.max_evaluations = max_evaluations;
  return options;
}

void print_result(const char* problem, const char* setting, const SbalcResult& result, double exact) {
  char exact_text[32] = "-";
  if (std::isfinite(exact)) std::snprintf(exact_text, sizeof exact_text, "%.4f", exact);
  std::printf("%s, %s: ln c exact %s, SBALC %.4f [%.4f, %.4f], %d runs, %s, %s; pool ESS %.1f (threshold %.0f), "
              "MC error %.3f, tau %.3g, peak spread %.3g\n",
              problem, setting, exact_text, result.log_evidence, result.log_evidence_lower, result.log_evidence_upper,
              result.n_evaluations, result.converged ? "converged" : "NOT converged", result.stop_reason.c_str(),
              result.pool_ess, result.pool_ess_threshold, result.pool_relative_error,
              result.noise_standard_deviation, result.peak_spread);
  for (const std::string& warning : result.warnings) std::printf("    warning: %s\n", warning.c_str());
  if (std::getenv("SBALC_HISTORY"))
    for (const SbalcIteration& it : result.history)
      std::printf("  n=%3d ln c=%9.4f [%9.4f, %9.4f] ratio=%.3e (gp %.3e, noise %.3e) tol=%.3f tau=%.2e S=%.2f "
                  "ESS=%.0f%s mc=%.3f%s%s\n",
                  it.n_points, it.log_evidence, it.log_evidence_lower, it.log_evidence_upper, it.ratio, it.gp_ratio,
                  it.noise_ratio, it.tolerance_used, it.noise_standard_deviation, it.peak_spread, it.pool_ess,
                  it.pool_redrawn ? " (redrawn)" : "", it.pool_relative_error, it.counted ? " counted" : "",
                  it.refusal.empty() ? "" : (" refused: " + it.refusal).c_str());
}

// Right within 5 %, or flagged: not converged and at least one warning.
void expect_right_or_flagged(const SbalcResult& result, double exact) {
  if (result.converged) {
    EXPECT_LE(std::abs(result.log_evidence - exact), tolerance_5_percent)
        << "converged with ln c " << result.log_evidence << " against " << exact;
    EXPECT_TRUE(result.warnings.empty());
  } else {
    ASSERT_FALSE(result.warnings.empty()) << "not converged without a warning: " << result.stop_reason;
    EXPECT_NE(result.warnings.back().find("not converged"), std::string::npos) << result.warnings.back();
  }
}

// (a) The likelihood in the prior's tail.
double tail_theta(double u) {
  constexpr double margin = 0x1.0p-53;  // as calibration/calibrate.cpp: Φ⁻¹ stays finite
  return standard_normal_quantile(std::clamp(u, margin, 1.0 - margin));
}

void run_tail_problem(const char* setting, const SbalcOptions& options) {
  const double exact = -0.5 * std::log(2.0 * M_PI * 1.04) - 25.0 / (2.0 * 1.04);
  const double posterior_mean = 5.0 / 1.04, posterior_sd = std::sqrt(0.04 / 1.04);
  const auto f = [](const Eigen::VectorXd& u) {
    return std::optional<double>(log_normal_density(5.0, tail_theta(u(0)), 0.2));
  };
  const SbalcResult result = Sbalc(1, f, options).run();
  print_result("tail", setting, result, exact);
  expect_right_or_flagged(result, exact);
  if (result.converged) {
    const PosteriorResult posterior = SirPosterior(result).run();
    double mean = 0.0;
    for (Eigen::Index i = 0; i < result.pool.rows(); ++i) mean += posterior.weights(i) * tail_theta(result.pool(i, 0));
    std::printf("    posterior mean %.4f (exact %.4f)\n", mean, posterior_mean);
    EXPECT_NEAR(mean, posterior_mean, 0.25 * posterior_sd);
  }
}

// Without the guards the library defaults claimed convergence after 46 runs with
// ln ĉ = −29.5 (pool ESS 1.7); the cap of 50 lies beyond that.
TEST(SbalcGuards, LikelihoodInThePriorsTailIsRightOrFlaggedWithLibraryDefaults) {
  run_tail_problem("library defaults", library_defaults(50));
}

// Without the guards the `rsw calibrate` defaults claimed convergence after 61 runs with
// ln ĉ = −54.7 (the estimated nugget, τ ≈ 6, absorbed the peak); the cap of 65 lies
// beyond that.
TEST(SbalcGuards, LikelihoodInThePriorsTailIsRightOrFlaggedWithCalibrateDefaults) {
  run_tail_problem("rsw calibrate defaults", calibrate_defaults(65));
}

// (b) Six narrow Gaussians.
void run_six_dimensional_problem(const char* setting, const SbalcOptions& options) {
  const double sd = 0.05;
  Eigen::VectorXd mu(6);
  mu << 0.35, 0.6, 0.45, 0.55, 0.4, 0.65;
  double exact = 0.0;
  for (int j = 0; j < 6; ++j) exact += std::log(normal_cdf((1.0 - mu(j)) / sd) - normal_cdf(-mu(j) / sd));
  ASSERT_LT(std::abs(exact), 1e-10);
  const auto f = [&](const Eigen::VectorXd& u) {
    double sum = 0.0;
    for (int j = 0; j < 6; ++j) sum += log_normal_density(u(j), mu(j), sd);
    return std::optional<double>(sum);
  };
  const SbalcResult result = Sbalc(6, f, options).run();
  print_result("6-D narrow", setting, result, exact);
  expect_right_or_flagged(result, exact);
}

// Without the guards the prior pool claimed convergence after 33 runs with ln ĉ = 0.95
// (pool ESS 1.0); the cap of 40 lies beyond that.
TEST(SbalcGuards, SixDimensionalNarrowPosteriorIsRightOrFlaggedWithLibraryDefaults) {
  run_six_dimensional_problem("library defaults", library_defaults(40));
}

// Within 60 runs the GP has not learnt the six-dimensional peak (ratio > 10) and the
// redrawn pool's ESS is about 20: it must say that it has not converged.
TEST(SbalcGuards, SixDimensionalNarrowPosteriorIsRightOrFlaggedWithCalibrateDefaults) {
  run_six_dimensional_problem("rsw calibrate defaults", calibrate_defaults(60));
}

// The count of consecutive iterations starts after the initial design. ℒ(u) = −u on
// [0, 1], c = ∫₀¹ e^{−u} du = 1 − e^{−1}: the GP of the five initial points already has
// a ratio far below the tolerance, so SBALC stops as soon as the rule allows: after
// n_consecutive = 2 iterations that each added a run (7 runs; the rule that counted the
// initial design's iteration stopped after 6).
TEST(SbalcGuards, ConvergenceCountsOnlyIterationsAfterTheInitialDesign) {
  const SbalcResult result =
      Sbalc(1, [](const Eigen::VectorXd& u) { return std::optional<double>(-u(0)); }).run();
  print_result("ln L = -u", "library defaults", result, std::log(1.0 - std::exp(-1.0)));
  ASSERT_TRUE(result.converged) << result.stop_reason;
  EXPECT_EQ(result.n_evaluations, 7);
  ASSERT_EQ(result.history.size(), 3u);
  EXPECT_LT(result.history[0].ratio, 0.1);
  EXPECT_FALSE(result.history[0].counted);
  EXPECT_TRUE(result.history[1].counted);
  EXPECT_TRUE(result.history[2].counted);
  EXPECT_LE(std::abs(result.log_evidence - std::log(1.0 - std::exp(-1.0))), tolerance_5_percent);
}

// (c) A bimodal mixture in one dimension.
TEST(SbalcGuards, BimodalMixtureIsRightOrFlagged) {
  const double exact = std::log(0.3 * (normal_cdf(0.8 / 0.03) - normal_cdf(-0.2 / 0.03)) +
                                0.7 * (normal_cdf(0.28 / 0.05) - normal_cdf(-0.72 / 0.05)));
  const auto f = [](const Eigen::VectorXd& u) {
    const double a = std::log(0.3) + log_normal_density(u(0), 0.2, 0.03);
    const double b = std::log(0.7) + log_normal_density(u(0), 0.72, 0.05);
    const double top = std::max(a, b);
    return std::optional<double>(top + std::log(std::exp(a - top) + std::exp(b - top)));
  };
  for (const auto& [setting, options] : {std::pair{"library defaults", library_defaults(100)},
                                         std::pair{"rsw calibrate defaults", calibrate_defaults(100)}}) {
    SCOPED_TRACE(setting);
    const SbalcResult result = Sbalc(1, f, options).run();
    print_result("bimodal", setting, result, exact);
    expect_right_or_flagged(result, exact);
    // Convergence rests on iterations after the initial design, each adding a run.
    EXPECT_FALSE(result.history.front().counted);
    int counted = 0;
    for (const SbalcIteration& it : result.history) counted += it.counted ? 1 : 0;
    if (result.converged) {
      EXPECT_EQ(counted, options.n_consecutive);
    }
  }
}

// (d) A Rosenbrock-type banana.
double rosenbrock_banana(const Eigen::Vector2d& u) {
  const double x1 = 4.0 * u(0) - 2.0, x2 = 4.0 * u(1) - 2.0;
  const double a = x1 / 0.7, r = (x2 - 1.2 * x1 * x1 + 1.0) / 0.3;
  return -0.5 * a * a - 0.5 * r * r;
}

void run_banana_problem(const char* setting, const SbalcOptions& options) {
  const int n = 2000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) sum += std::exp(rosenbrock_banana(Eigen::Vector2d((i + 0.5) / n, (j + 0.5) / n)));
  const double exact = std::log(sum / (static_cast<double>(n) * n));
  const auto f = [](const Eigen::VectorXd& u) { return std::optional<double>(rosenbrock_banana(u)); };
  const SbalcResult result = Sbalc(2, f, options).run();
  print_result("banana", setting, result, exact);
  expect_right_or_flagged(result, exact);
}

TEST(SbalcGuards, RosenbrockBananaIsRightOrFlaggedWithLibraryDefaults) {
  run_banana_problem("library defaults", library_defaults(100));
}

// Batches of 4 need more runs here than one point at a time (measured: converged after
// 97 runs, ln ĉ 3.4 % above the quadrature, the pool's Monte Carlo error 1.6 %); the cap
// of 60 keeps the test short, so it pins the flagged branch.
TEST(SbalcGuards, RosenbrockBananaIsRightOrFlaggedWithCalibrateDefaults) {
  run_banana_problem("rsw calibrate defaults", calibrate_defaults(60));
}

// The band of the peak-spread guard, h_d = ½ χ²_d(0.99), against closed forms:
// χ²_1(0.99) = Φ⁻¹(0.995)² = 2.5758293035489² and χ²_2(0.99) = −2 ln 0.01 (the χ²₂
// distribution is exponential with mean 2). Wilson–Hilferty is within 1 % of both.
TEST(SbalcGuards, PeakBandIsHalfTheChiSquareQuantile) {
  const double h1 = 0.5 * 2.5758293035489 * 2.5758293035489, h2 = -std::log(0.01);
  EXPECT_NEAR(peak_band_height(1), h1, 0.01 * h1);
  EXPECT_NEAR(peak_band_height(2), h2, 0.01 * h2);
}

// The pool's Monte Carlo error and the widened bounds, recomputed from the last GP's
// m and s at the pool points with the textbook formulas (sbalc.hpp): for an average
// X = (1/N) Σ a_i, SE(X) = √(Σ (a_i − X)² / (N (N − 1))), and
//     c_upper/ĉ = 1 + √((u − 1)² + (b SE_u/ĉ)²),   c_lower/ĉ = 1 − √((1 − l)² + (b SE_l/ĉ)²),
// u = c_upper,GP/ĉ, l = c_lower,GP/ĉ, b = 1. The a_i are scaled by e^{−max m} (every
// ratio is unchanged by a common factor).
TEST(SbalcGuards, BoundsHoldThePoolsStandardError) {
  SbalcOptions options;
  options.pool_size = 3000;
  options.max_evaluations = 12;
  const SbalcResult result =
      Sbalc(2, [](const Eigen::VectorXd& u) { return std::optional<double>(rosenbrock_banana(u)); }, options).run();
  const Eigen::ArrayXd m = result.pool_mean.array(), s = result.pool_latent_sd.array();
  const double top = m.maxCoeff(), n = static_cast<double>(m.size());
  const auto mean_and_se = [n](const Eigen::ArrayXd& a) {
    const double mean = a.mean();
    return std::pair{mean, std::sqrt((a - mean).square().sum() / (n * (n - 1.0)))};
  };
  const auto [c, se] = mean_and_se((m - top).exp());
  const auto [c_up, se_up] = mean_and_se((m + s - top).exp());
  const auto [c_lo, se_lo] = mean_and_se((m - s - top).exp());
  const double upper = 1.0 + std::hypot(c_up / c - 1.0, se_up / c);
  const double lower = std::max(0.0, 1.0 - std::hypot(1.0 - c_lo / c, se_lo / c));
  std::printf("pool 3000 after %d runs: SE(c)/c %.4f, bounds/c [%.4f, %.4f], GP bounds/c [%.4f, %.4f]\n",
              result.n_evaluations, se / c, lower, upper, c_lo / c, c_up / c);
  EXPECT_NEAR(result.pool_relative_error, se / c, 1e-9 * se / c);
  EXPECT_NEAR(std::exp(result.log_evidence_upper - result.log_evidence), upper, 1e-9 * upper);
  if (lower > 0.0) {
    EXPECT_NEAR(std::exp(result.log_evidence_lower - result.log_evidence), lower, 1e-9);
  } else {
    EXPECT_EQ(result.log_evidence_lower, -std::numeric_limits<double>::infinity());
  }
  EXPECT_NEAR(result.ratio, upper - lower, 1e-9 * (upper - lower));
  EXPECT_GT(upper, c_up / c);  // the pool's error widens the paper's bounds
  EXPECT_NEAR(result.history.back().gp_ratio, (c_up - c_lo) / c, 1e-9 * (c_up - c_lo) / c);
}

// The noise allowance of the tolerance is capped. The smooth Gaussian of test_sbalc.cpp
// (mode (0.5, 0.45), sd 0.2 and 0.16, correlation 0.4, peak 3) plus reproducible noise
// 0.3 [sin(200 u₁) + sin(170 u₂)]: with the estimated nugget the noise part of the ratio
// is about 0.16 (test_sbalc.cpp), so a cap of 1.2 × tolerance = 0.12 binds; the result
// must then not converge and name the tolerance that would accept the noise-limited ratio.
TEST(SbalcGuards, NoiseAllowanceIsCappedAndTheWarningNamesTheToleranceNeeded) {
  const auto noisy = [](const Eigen::VectorXd& u) {
    const double sd = 0.2, rho = 0.4;
    Eigen::Matrix2d covariance;
    covariance << sd * sd, rho * sd * 0.8 * sd, rho * sd * 0.8 * sd, 0.64 * sd * sd;
    const Eigen::Vector2d r = u - Eigen::Vector2d(0.5, 0.45);
    return std::optional<double>(3.0 - 0.5 * r.dot(covariance.inverse() * r) +
                                 0.3 * (std::sin(200.0 * u(0)) + std::sin(170.0 * u(1))));
  };
  SbalcOptions options;
  options.max_evaluations = 40;
  options.gp.nugget_mode = NuggetMode::Estimated;
  options.max_noise_tolerance_factor = 1.2;
  const SbalcResult result = Sbalc(2, noisy, options).run();
  print_result("noise allowance capped at 1.2 x tolerance", "nugget", result, std::nan(""));  // no exact value
  for (const SbalcIteration& it : result.history) EXPECT_LE(it.tolerance_used, 1.2 * options.tolerance + 1e-15);
  bool capped = false;
  for (const SbalcIteration& it : result.history) capped = capped || it.noise_allowance_capped;
  EXPECT_TRUE(capped);
  EXPECT_FALSE(result.converged);
  EXPECT_TRUE(result.history.back().noise_allowance_capped);
  bool named = false;
  for (const std::string& w : result.warnings) named = named || w.find("tolerance of at least") != std::string::npos;
  EXPECT_TRUE(named);
}

}  // namespace
}  // namespace rsw::calibration
