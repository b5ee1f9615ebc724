// Coverage of the emulator route (calibration/emulator_calibration.hpp) on cheap
// analytic problems: over 50 synthetic data sets each of a 3-D and a 6-D nonlinear
// model with narrow posteriors (posterior sd about 5 % of the prior width), the 90 %
// credible intervals must hold the truth 80–97 % of the time.
//
// Models, in the unit cube where the prior is uniform (indices cyclic, i = 1 … d):
//     y_i = u_i + 0.3 u_{i+1}²,   y_{d+1} = ½ Σ_i u_i,
// one replicate per data set with known noise σ = 0.06 on every feature, so each u_i is
// informed mainly by y_i and the posterior sd is about σ/√(1 + 0.09 … + ¼) ≈ 0.05.
// Each data set draws its truth uniformly in [0.2, 0.8]^d (at least 3 posterior sd from
// every face) and its noise, from a seeded generator. For a calibrated posterior the
// chance that an interval holds the truth is 0.9; with 150 (3-D) or 300 (6-D)
// intervals, correlated within a data set, the band 80–97 % is wider than three
// binomial standard deviations (2.4 % and 1.7 %) on either side.
#include "calibration/emulator_calibration.hpp"
#include "calibration/likelihood.hpp"
#include "calibration/posterior.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>

namespace rsw::calibration {
namespace {

Eigen::VectorXd model(const Eigen::VectorXd& u) {
  const Eigen::Index d = u.size();
  Eigen::VectorXd y(d + 1);
  for (Eigen::Index i = 0; i < d; ++i) {
    const double next = u((i + 1) % d);
    y(i) = u(i) + 0.3 * next * next;
  }
  y(d) = 0.5 * u.sum();
  return y;
}

struct Coverage {
  int inside = 0, intervals = 0, converged = 0, data_sets = 0;
  double runs = 0.0;
};

Coverage coverage(int d, int n_data_sets, std::uint64_t seed) {
  constexpr double sigma = 0.06;
  std::mt19937_64 generator(seed);
  std::uniform_real_distribution<double> truth_draw(0.2, 0.8);
  std::normal_distribution<double> noise(0.0, sigma);
  const BatchFeatureFunction evaluate = [](const std::vector<Eigen::VectorXd>& points) {
    std::vector<std::optional<Eigen::VectorXd>> values;
    for (const auto& u : points) values.emplace_back(model(u));
    return values;
  };
  std::vector<std::string> names;
  std::map<std::string, double> sds;
  for (int j = 0; j <= d; ++j) {
    names.push_back("y" + std::to_string(j));
    sds[names.back()] = sigma;
  }
  Coverage result;
  for (int set = 0; set < n_data_sets; ++set) {
    Eigen::VectorXd truth(d);
    for (int i = 0; i < d; ++i) truth(i) = truth_draw(generator);
    Eigen::VectorXd observed = model(truth);
    for (Eigen::Index j = 0; j < observed.size(); ++j) observed(j) += noise(generator);
    const GaussianLikelihood likelihood(names, observed.transpose(), ObservationNoise::given(sds));
    EmulatorCalibrationOptions options;
    options.seed = seed + static_cast<std::uint64_t>(set);
    options.max_evaluations = 20 * d;
    options.pool_size = 5000;
    options.smc.n_particles = 500;
    const EmulatorCalibrationResult calibrated = EmulatorCalibration(d, evaluate, likelihood, options).run();
    PosteriorOptions posterior_options;
    posterior_options.credible_level = 0.9;
    posterior_options.refine_map = false;
    posterior_options.n_samples = 10;
    const PosteriorResult posterior = SirPosterior(calibrated.pool, calibrated.pool_log_likelihood,
                                                   calibrated.pool_log_weight, posterior_options)
                                          .run();
    for (int i = 0; i < d; ++i) {
      const CredibleInterval& interval = posterior.credible_intervals[static_cast<std::size_t>(i)];
      result.inside += interval.lower <= truth(i) && truth(i) <= interval.upper ? 1 : 0;
      ++result.intervals;
    }
    result.converged += calibrated.converged ? 1 : 0;
    result.runs += calibrated.n_evaluations;
    ++result.data_sets;
  }
  result.runs /= n_data_sets;
  return result;
}

void check(const Coverage& c, int d) {
  const double share = static_cast<double>(c.inside) / c.intervals;
  std::printf("%d-D: %d of %d intervals hold the truth (%.1f %%); %d of %d calibrations converged, %.1f runs on "
              "average\n",
              d, c.inside, c.intervals, 100.0 * share, c.converged, c.data_sets, c.runs);
  EXPECT_GE(share, 0.80);
  EXPECT_LE(share, 0.97);
  EXPECT_GE(c.converged, c.data_sets * 9 / 10);
}

TEST(EmulatorCoverage, NinetyPercentIntervalsHoldTheTruthAsOftenAsTheyClaimInThreeDimensions) {
  check(coverage(3, 50, 3000), 3);
}

TEST(EmulatorCoverage, NinetyPercentIntervalsHoldTheTruthAsOftenAsTheyClaimInSixDimensions) {
  check(coverage(6, 50, 6000), 6);
}

}  // namespace
}  // namespace rsw::calibration
