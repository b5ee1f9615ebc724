// The emulator route (calibration/feature_emulator.hpp, emulator_calibration.hpp):
//   - the emulated likelihood against the Gaussian likelihood and a hand value;
//   - a linear-Gaussian model in six dimensions, whose posterior and evidence are
//     derived in closed form below.
#include "calibration/designs.hpp"
#include "calibration/emulator_calibration.hpp"
#include "calibration/feature_emulator.hpp"
#include "calibration/likelihood.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <random>

namespace rsw::calibration {
namespace {

TEST(EmulatedLikelihood, EqualsTheGaussianLikelihoodWhenTheEmulatorIsExact) {
  Eigen::MatrixXd y(3, 2);
  y << 1.0, 10.0, 1.2, 11.0, 0.9, 9.5;
  const GaussianLikelihood likelihood({"a", "b"}, y, ObservationNoise::given({{"a", 0.1}, {"b", 0.7}}));
  FeaturePrediction prediction;
  prediction.mean.resize(2, 2);
  prediction.mean << 1.05, 10.3, 0.7, 12.0;
  prediction.latent_variance = Eigen::MatrixXd::Zero(2, 2);
  prediction.noise_variance = Eigen::MatrixXd::Zero(2, 2);
  const Eigen::VectorXd emulated = EmulatedLikelihood(likelihood).log_likelihood(prediction);
  for (int r = 0; r < 2; ++r) {
    EXPECT_NEAR(emulated(r), likelihood.log_likelihood(Eigen::VectorXd(prediction.mean.row(r).transpose())), 1e-10);
  }
}

TEST(EmulatedLikelihood, EmulatorAndNoiseVariancesAddToTheVarianceOfTheObservedMean) {
  // One replicate y = 2, σ = 0.2; m = 1.5, s² = 0.05, τ² = 0.01:
  // W = 0.04 + 0.05 + 0.01 = 0.1, ln L̃ = −(0.5)²/(2 · 0.1) − ½ ln(2π · 0.1).
  const GaussianLikelihood likelihood({"a"}, Eigen::MatrixXd::Constant(1, 1, 2.0),
                                      ObservationNoise::given({{"a", 0.2}}));
  FeaturePrediction prediction{Eigen::MatrixXd::Constant(1, 1, 1.5), Eigen::MatrixXd::Constant(1, 1, 0.05),
                               Eigen::MatrixXd::Constant(1, 1, 0.01)};
  const double expected = -0.25 / 0.2 - 0.5 * std::log(2.0 * M_PI * 0.1);
  EXPECT_NEAR(EmulatedLikelihood(likelihood).log_likelihood(prediction)(0), expected, 1e-12);
}

// M(u) = b + A u, p = 8 features of d = 6 parameters, one replicate y with known σ:
//     ℒ(u) = −½ (y − b − Au)ᵀ Σ⁻¹ (y − b − Au) − ½ ln det(2πΣ)
// is quadratic: ℒ(u) = ℒ(û) − ½ (u − û)ᵀ P (u − û), P = AᵀΣ⁻¹A, û = P⁻¹AᵀΣ⁻¹(y − b).
// The posterior is N(û, P⁻¹) truncated to the box, and with û more than 6 posterior
// standard deviations from every face the truncation is below 1e-8, so
//     ln Z = ℒ(û) + (d/2) ln 2π − ½ ln det P.
struct LinearProblem {
  int d = 6, p = 8;
  Eigen::MatrixXd a;
  Eigen::VectorXd b, sigma, y, mode, posterior_sd;
  double log_evidence = 0.0;

  explicit LinearProblem(std::uint64_t seed) {
    std::mt19937_64 generator(seed);
    std::normal_distribution<double> normal;
    a.resize(p, d);
    for (int i = 0; i < p; ++i)
      for (int j = 0; j < d; ++j) a(i, j) = (i == j ? 2.0 : 0.0) + 0.4 * normal(generator);
    b = Eigen::VectorXd::LinSpaced(p, 1.0, 2.0);
    sigma = Eigen::VectorXd::Constant(p, 0.03);
    Eigen::VectorXd truth(d);
    for (int j = 0; j < d; ++j) truth(j) = 0.4 + 0.2 * (j % 3) / 2.0;
    y = b + a * truth;
    for (int i = 0; i < p; ++i) y(i) += sigma(i) * normal(generator);
    const Eigen::MatrixXd weights = sigma.cwiseAbs2().cwiseInverse().asDiagonal();
    const Eigen::MatrixXd precision = a.transpose() * weights * a;
    mode = precision.ldlt().solve(a.transpose() * weights * (y - b));
    posterior_sd = precision.inverse().diagonal().cwiseSqrt();
    const Eigen::VectorXd r = y - b - a * mode;
    const double at_mode = -0.5 * r.dot(weights * r) - 0.5 * (2.0 * M_PI * sigma.cwiseAbs2()).array().log().sum();
    log_evidence = at_mode + 0.5 * d * std::log(2.0 * M_PI) - 0.5 * std::log(precision.determinant());
  }

  GaussianLikelihood likelihood() const {
    std::vector<std::string> names;
    std::map<std::string, double> sds;
    for (int i = 0; i < p; ++i) {
      names.push_back("f" + std::to_string(i));
      sds[names.back()] = sigma(i);
    }
    return GaussianLikelihood(names, y.transpose(), ObservationNoise::given(sds));
  }

  // The weighted pool's mean and sd of each u_i within 0.1 posterior sd of the closed form.
  void expect_posterior_moments(const EmulatorCalibrationResult& result) const {
    Eigen::VectorXd weights = (result.pool_log_likelihood + result.pool_log_weight).array().exp().matrix();
    weights /= weights.sum();
    const Eigen::VectorXd mean = result.pool.transpose() * weights;
    for (int j = 0; j < d; ++j) {
      const double variance = (result.pool.col(j).array() - mean(j)).square().matrix().dot(weights);
      EXPECT_NEAR(mean(j), mode(j), 0.1 * posterior_sd(j)) << "parameter " << j;
      EXPECT_NEAR(std::sqrt(variance), posterior_sd(j), 0.1 * posterior_sd(j)) << "parameter " << j;
    }
  }

  BatchFeatureFunction model() const {
    return [this](const std::vector<Eigen::VectorXd>& points) {
      std::vector<std::optional<Eigen::VectorXd>> values;
      for (const auto& u : points) values.emplace_back(Eigen::VectorXd(b + a * u));
      return values;
    };
  }
};

TEST(EmulatorCalibration, RecoversTheClosedFormPosteriorAndEvidenceOfALinearModelInSixDimensions) {
  const LinearProblem problem(11);
  std::printf("posterior sd:");
  for (int j = 0; j < problem.d; ++j) std::printf(" %.4f", problem.posterior_sd(j));
  std::printf("\n");
  for (int j = 0; j < problem.d; ++j) {
    ASSERT_GT(std::min(problem.mode(j), 1.0 - problem.mode(j)), 6.0 * problem.posterior_sd(j));
  }
  EmulatorCalibrationOptions options;
  options.max_evaluations = 100;
  const EmulatorCalibrationResult result =
      EmulatorCalibration(problem.d, problem.model(), problem.likelihood(), options).run();
  std::printf("linear 6-D: %d runs, converged %d, ln Z %.4f (closed form %.4f), relative error %.4f, ESS %.0f\n",
              result.n_evaluations, result.converged, result.log_evidence, problem.log_evidence,
              result.evidence_relative_error, result.pool_ess);
  for (const auto& it : result.history)
    std::printf("  %d runs: ln Z %.3f (SMC %.3f), %d temperatures, variance ratio %.3g, quantile shift %.3g, ESS %.0f, %.1f s\n",
                it.n_evaluations, it.log_evidence, it.smc_log_evidence, it.n_temperatures, it.max_variance_ratio,
                it.quantile_shift, it.pool_ess, it.seconds);
  for (const auto& warning : result.warnings) std::printf("  warning: %s\n", warning.c_str());
  EXPECT_TRUE(result.converged);
  EXPECT_NEAR(result.log_evidence, problem.log_evidence, std::log(1.05));
  for (const auto& it : result.history) {  // the influence is its largest per-parameter part
    ASSERT_EQ(it.parameter_influence.size(), problem.d);
    EXPECT_EQ(it.parameter_influence.maxCoeff(), it.emulator_influence);
  }
  problem.expect_posterior_moments(result);
}


// Focusing. y(u) = exp(15 u_0) + u_1 spans 1 to 3.3·10⁶ over the unit square; observed
// 20.6 (u_0 ≈ 0.2) with σ = 1. Without a nugget (τ = 0) the plausible runs are exactly
// those with |y_r − 20.6| ≤ 9 σ, and a prediction is the focused one where the global
// emulator's I(u) = |20.6 − m(u)| / √(σ² + s²(u)) is at most 3, the global one elsewhere.
TEST(FeatureEmulator, FocusLearnsThePlausibleRunsAndPredictsWithThemWhereThePointIsPlausible) {
  const auto model = [](const Eigen::MatrixXd& u) {
    return Eigen::VectorXd((15.0 * u.col(0).array()).exp() + u.col(1).array());
  };
  const Eigen::MatrixXd inputs = latin_hypercube(200, 2, 5);
  const Eigen::MatrixXd features = model(inputs);
  GaussianProcessOptions gp = EmulatorCalibrationOptions::default_gp();
  gp.nugget_mode = NuggetMode::Off;
  FeatureFocus focus;
  focus.observed_mean = Eigen::VectorXd::Constant(1, 20.6);
  focus.mean_variances = Eigen::VectorXd::Constant(1, 1.0);
  focus.min_runs = 5;
  const FeatureEmulator focused(inputs, features, gp, nullptr, {}, {}, focus);
  const FeatureEmulator global(inputs, features, gp);
  ASSERT_NE(focused.focused(), nullptr);
  std::vector<Eigen::Index> plausible;
  for (Eigen::Index r = 0; r < features.rows(); ++r)
    if (std::abs(features(r) - 20.6) <= 9.0) plausible.push_back(r);
  EXPECT_EQ(focused.focused_rows(), plausible);
  ASSERT_GE(plausible.size(), 5u);

  // Points along u_0 through the plausible band, at u_1 = 0.5.
  Eigen::MatrixXd points(41, 2);
  for (Eigen::Index k = 0; k < points.rows(); ++k) points.row(k) << 0.15 + 0.1 * k / 40.0, 0.5;
  const FeaturePrediction with_focus = focused.predict(points), without = global.predict(points);
  const FeaturePrediction local = focused.focused()->predict(points);
  const Eigen::VectorXd implausibility = focused.implausibility(points);
  const Eigen::VectorXd truth = model(points);
  double error_focused = 0.0, error_global = 0.0;
  int n_plausible = 0;
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    const double expected_i =
        std::abs(20.6 - without.mean(k, 0)) / std::sqrt(1.0 + without.latent_variance(k, 0));
    EXPECT_NEAR(implausibility(k), expected_i, 1e-9 * (1.0 + expected_i));
    const FeaturePrediction& source = implausibility(k) <= 3.0 ? local : without;
    EXPECT_EQ(with_focus.mean(k, 0), source.mean(k, 0)) << "point " << k;
    EXPECT_EQ(with_focus.latent_variance(k, 0), source.latent_variance(k, 0)) << "point " << k;
    n_plausible += implausibility(k) <= 3.0 ? 1 : 0;
    if (implausibility(k) <= 3.0 && std::abs(truth(k) - 20.6) <= 6.0) {  // inside the learned band
      error_focused = std::max(error_focused, std::abs(with_focus.mean(k, 0) - truth(k)));
      error_global = std::max(error_global, std::abs(without.mean(k, 0) - truth(k)));
    }
  }
  std::printf("%d plausible points; inside the band largest error focused %.3g, global %.3g (sigma 1)\n",
              n_plausible, error_focused, error_global);
  EXPECT_GE(n_plausible, 5);
  // The global GP's signal variance is set by the 10⁶ of the far corner; the focused one
  // fits the band to a fraction of σ.
  EXPECT_LT(error_focused, 0.3);
  EXPECT_LT(error_focused, 0.1 * error_global);

  // Too few plausible runs: no focused emulator.
  focus.min_runs = static_cast<int>(plausible.size()) + 1;
  EXPECT_EQ(FeatureEmulator(inputs, features, gp, nullptr, {}, {}, focus).focused(), nullptr);
}

// The linear problem above with a far kink in one feature: f_0 += 10⁴ (u_0 − 0.8)²₊.
// The posterior lies more than 6 sd below u_0 = 0.8 (asserted), where the kink is zero,
// so its closed form is unchanged; the feature now spans 400 times its range without
// the kink, which the emulators of all runs must fit, while the focused ones learn the
// plausible runs only.
TEST(EmulatorCalibration, FocusKeepsTheClosedFormPosteriorOfALinearModelWithAFarKink) {
  const LinearProblem problem(11);
  for (int j = 0; j < problem.d; ++j) ASSERT_LT(problem.mode(j) + 6.0 * problem.posterior_sd(j), 0.8);
  const BatchFeatureFunction linear = problem.model();
  const BatchFeatureFunction kinked = [&](const std::vector<Eigen::VectorXd>& points) {
    std::vector<std::optional<Eigen::VectorXd>> values = linear(points);
    for (std::size_t k = 0; k < points.size(); ++k) {
      const double beyond = std::max(0.0, points[k](0) - 0.8);
      (*values[k])(0) += 1e4 * beyond * beyond;
    }
    return values;
  };
  EmulatorCalibrationOptions options;
  options.max_evaluations = 100;
  options.focus = true;
  const EmulatorCalibrationResult result = EmulatorCalibration(problem.d, kinked, problem.likelihood(), options).run();
  std::printf("kinked linear 6-D with focus: %d runs, converged %d, ln Z %.4f (closed form %.4f), ESS %.0f\n",
              result.n_evaluations, result.converged, result.log_evidence, problem.log_evidence, result.pool_ess);
  for (const auto& it : result.history)
    std::printf("  %d runs (%d plausible, weight %.3f): ln Z %.3f, variance ratio %.3g, influence %.3g, shift %.3g\n",
                it.n_evaluations, it.n_focused, it.focused_weight, it.log_evidence, it.max_variance_ratio,
                it.emulator_influence, it.quantile_shift);
  EXPECT_TRUE(result.converged);
  EXPECT_GT(result.history.back().n_focused, 0);
  EXPECT_GT(result.history.back().focused_weight, 0.95);
  EXPECT_NEAR(result.log_evidence, problem.log_evidence, std::log(1.05));
  problem.expect_posterior_moments(result);
}


// A rough feature: y = 1 + 2 u_0 + a h(u), h a hash of u's bits, uniform on [−1, 1] and
// independent between distinct points (variance 1/3), beside a smooth one y = 1 + 2 u_1.
// For a pair of points δ apart, E[(y_a − y_b)²]/2 = a²/3 + O(δ²), so the noise pairs
// bound the rough feature's nugget near a²/3 and the smooth one's near δ².
double hash_noise(const Eigen::VectorXd& u) {
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    std::uint64_t bits = 0;
    const double value = u(i);
    std::memcpy(&bits, &value, sizeof bits);
    state ^= bits + 0x9E3779B97F4A7C15ull + (state << 6) + (state >> 2);
  }
  std::mt19937_64 generator(state);
  return std::uniform_real_distribution<double>(-1.0, 1.0)(generator);
}

TEST(FeatureEmulator, NoisePairsBoundEachNuggetByHalfTheirMeanSquaredDifference) {
  // Four points, two pairs; standardised outputs o = (y − ȳ)/sd(y) with y = (0, 1, 2, 4):
  // ȳ = 7/4, sd² = (49 + 9 + 1 + 81)/16/3 = 35/12; pairs (0,1), (2,3): differences 1 and 2
  // in y, so the floor is ((1 + 4)/2)/2 / (35/12) = 3/7 in o units².
  Eigen::MatrixXd inputs(4, 1);
  inputs << 0.1, 0.4, 0.6, 0.9;
  const Eigen::MatrixXd features = (Eigen::MatrixXd(4, 1) << 0.0, 1.0, 2.0, 4.0).finished();
  const FeatureEmulator emulator(inputs, features, EmulatorCalibrationOptions::default_gp(), nullptr, {},
                                 {{0, 1}, {2, 3}});
  const double floor = (0.5 * (1.0 + 4.0) / 2.0) / (35.0 / 12.0);
  EXPECT_GE(emulator.processes()[0].hyperparameters().noise_variance, floor * (1 - 1e-9));
  EXPECT_THROW(FeatureEmulator(inputs, features, EmulatorCalibrationOptions::default_gp(), nullptr, {}, {{0, 4}}),
               std::invalid_argument);
}

TEST(EmulatorCalibration, NoisePairsGiveARoughFeatureTheNuggetItsRoughnessImplies) {
  const double amplitude = 0.1;
  const BatchFeatureFunction model = [&](const std::vector<Eigen::VectorXd>& points) {
    std::vector<std::optional<Eigen::VectorXd>> values;
    for (const Eigen::VectorXd& u : points)
      values.emplace_back(Eigen::Vector2d(1.0 + 2.0 * u(0) + amplitude * hash_noise(u), 1.0 + 2.0 * u(1)));
    return values;
  };
  const Eigen::MatrixXd y = (Eigen::MatrixXd(1, 2) << 1.8, 2.2).finished();
  const GaussianLikelihood likelihood({"rough", "smooth"}, y, ObservationNoise::given({{"rough", 0.05}, {"smooth", 0.05}}));
  EmulatorCalibrationOptions options;
  options.n_initial = 40;
  options.noise_pairs = 30;
  options.max_evaluations = 40 + 4 + 30;  // stops after the first batch and its pairs
  const EmulatorCalibrationResult result = EmulatorCalibration(2, model, likelihood, options).run();
  const EmulatorIteration& last = result.history.back();
  EXPECT_EQ(last.n_noise_pairs, 30);
  const double expected = amplitude / std::sqrt(3.0);  // relative sampling error of the variance about √(2/30) = 0.26
  std::printf("noise sd: rough %.4g (expected %.4g), smooth %.4g\n", last.noise_standard_deviations(0), expected,
              last.noise_standard_deviations(1));
  EXPECT_GT(last.noise_standard_deviations(0), 0.7 * expected);
  EXPECT_LT(last.noise_standard_deviations(0), 1.4 * expected);
  // The smooth feature's pairs differ by its gradient: 2 δ v_1, v a random unit vector in
  // two dimensions (E v_1² = 1/2), so E[(y_a − y_b)²]/2 = δ² and its τ is about δ.
  EXPECT_NEAR(last.noise_standard_deviations(1), options.noise_pair_distance, 0.5 * options.noise_pair_distance);
}

}  // namespace
}  // namespace rsw::calibration
