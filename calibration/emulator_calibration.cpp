// The emulator route's loop; algorithm, checks and sources in emulator_calibration.hpp.
#include "calibration/emulator_calibration.hpp"

#include "calibration/designs.hpp"
#include "calibration/posterior.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace rsw::calibration {

namespace {

using Clock = std::chrono::steady_clock;

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

std::string shortest(double value) {
  std::ostringstream out;
  out.precision(3);
  out << value;
  return out.str();
}

// The runs so far: successful points and features, failed points.
struct Runs {
  std::vector<Eigen::VectorXd> points;
  std::vector<Eigen::VectorXd> features;
  std::vector<Eigen::VectorXd> failed;
  int n_evaluations = 0;

  // Returns, per point, its row among the successful points (−1 if it failed).
  std::vector<Eigen::Index> add(const std::vector<Eigen::VectorXd>& thetas,
                                const std::vector<std::optional<Eigen::VectorXd>>& values, Eigen::Index n_features) {
    if (values.size() != thetas.size())
      throw std::runtime_error("emulator calibration: the evaluator returned " + std::to_string(values.size()) +
                               " results for " + std::to_string(thetas.size()) + " points");
    std::vector<Eigen::Index> rows;
    for (std::size_t k = 0; k < thetas.size(); ++k) {
      ++n_evaluations;
      if (values[k] && values[k]->size() == n_features && values[k]->allFinite()) {
        rows.push_back(static_cast<Eigen::Index>(points.size()));
        points.push_back(thetas[k]);
        features.push_back(*values[k]);
      } else {
        rows.push_back(-1);
        failed.push_back(thetas[k]);
      }
    }
    return rows;
  }

  Eigen::MatrixXd point_matrix() const { return stack(points); }
  Eigen::MatrixXd feature_matrix() const { return stack(features); }

  static Eigen::MatrixXd stack(const std::vector<Eigen::VectorXd>& rows) {
    if (rows.empty()) return {};
    Eigen::MatrixXd matrix(static_cast<Eigen::Index>(rows.size()), rows.front().size());
    for (std::size_t r = 0; r < rows.size(); ++r) matrix.row(static_cast<Eigen::Index>(r)) = rows[r].transpose();
    return matrix;
  }
};

std::vector<Eigen::VectorXd> rows_of(const Eigen::MatrixXd& matrix) {
  std::vector<Eigen::VectorXd> rows;
  for (Eigen::Index r = 0; r < matrix.rows(); ++r) rows.emplace_back(matrix.row(r).transpose());
  return rows;
}

// a(u) = Σ_j s_j²(u) / (v_j + τ_j²) at each point.
Eigen::VectorXd acquisition(const FeatureEmulator& emulator, const Eigen::MatrixXd& points,
                            const Eigen::VectorXd& irreducible) {
  const FeaturePrediction prediction = emulator.predict(points);
  return prediction.latent_variance * irreducible.cwiseInverse();
}

// batch_size points among the candidates, each the maximiser of a(u) after the points
// before it (and the failed runs) were believed into the emulators.
Eigen::MatrixXd choose_batch(FeatureEmulator emulator, const Eigen::MatrixXd& candidates,
                             const std::vector<Eigen::VectorXd>& failed, const Eigen::VectorXd& irreducible, int count) {
  for (const Eigen::VectorXd& point : failed) emulator = emulator.with_believed_point(point);
  Eigen::MatrixXd chosen(count, candidates.cols());
  for (int k = 0; k < count; ++k) {
    Eigen::Index best = 0;
    acquisition(emulator, candidates, irreducible).maxCoeff(&best);
    chosen.row(k) = candidates.row(best);
    if (k + 1 < count) emulator = emulator.with_believed_point(candidates.row(best).transpose());
  }
  return chosen;
}

// The Monte Carlo standard error of the emulators' influence (the largest quantile
// difference, in posterior sd, between two weightings of one pool): its spread over
// bootstrap resamples of the pool (Efron & Tibshirani 1993), 30 of them.
double influence_standard_error(const Eigen::MatrixXd& points, const Eigen::VectorXd& weights,
                                const Eigen::VectorXd& plug_weights, const Eigen::VectorXd& posterior_sd,
                                const std::vector<double>& probabilities, std::uint64_t seed) {
  constexpr int n_resamples = 30;
  const Eigen::Index n = points.rows();
  std::mt19937_64 generator(seed);
  std::uniform_int_distribution<Eigen::Index> pick(0, n - 1);
  Eigen::VectorXd influence(n_resamples);
  Eigen::VectorXd w(n), v(n), values(n);
  for (int b = 0; b < n_resamples; ++b) {
    std::vector<Eigen::Index> rows(static_cast<std::size_t>(n));
    for (auto& r : rows) r = pick(generator);
    for (Eigen::Index k = 0; k < n; ++k) {
      w(k) = weights(rows[static_cast<std::size_t>(k)]);
      v(k) = plug_weights(rows[static_cast<std::size_t>(k)]);
    }
    if (!(w.sum() > 0.0) || !(v.sum() > 0.0)) return not_a_number;
    w /= w.sum();
    v /= v.sum();
    double largest = 0.0;
    for (Eigen::Index i = 0; i < points.cols(); ++i) {
      for (Eigen::Index k = 0; k < n; ++k) values(k) = points(rows[static_cast<std::size_t>(k)], i);
      const Eigen::VectorXd difference =
          weighted_quantiles(values, v, probabilities) - weighted_quantiles(values, w, probabilities);
      largest = std::max(largest, difference.cwiseAbs().maxCoeff() / std::max(posterior_sd(i), 1e-12));
    }
    influence(b) = largest;
  }
  const double mean = influence.mean();
  return std::sqrt((influence.array() - mean).square().sum() / (n_resamples - 1));
}

// Near-duplicates of the `count` successful runs with the highest emulated
// log-likelihood: each `distance` away in a uniformly random direction, reflected
// into the unit cube.
std::vector<Eigen::VectorXd> noise_partners(const Eigen::MatrixXd& points, const Eigen::VectorXd& log_likelihood,
                                            int count, double distance, std::uint64_t seed,
                                            std::vector<Eigen::Index>& originals) {
  std::vector<Eigen::Index> order(static_cast<std::size_t>(points.rows()));
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<Eigen::Index>(k);
  std::stable_sort(order.begin(), order.end(),
                   [&](Eigen::Index a, Eigen::Index b) { return log_likelihood(a) > log_likelihood(b); });
  std::mt19937_64 generator(seed);
  std::normal_distribution<double> normal;
  std::vector<Eigen::VectorXd> partners;
  originals.clear();
  for (int k = 0; k < count && k < static_cast<int>(order.size()); ++k) {
    const Eigen::Index row = order[static_cast<std::size_t>(k)];
    Eigen::VectorXd direction(points.cols());
    for (Eigen::Index i = 0; i < direction.size(); ++i) direction(i) = normal(generator);
    Eigen::VectorXd partner = points.row(row).transpose() + distance * direction.normalized();
    for (Eigen::Index i = 0; i < partner.size(); ++i) {
      if (partner(i) < 0.0) partner(i) = -partner(i);
      if (partner(i) > 1.0) partner(i) = 2.0 - partner(i);
      partner(i) = std::clamp(partner(i), 0.0, 1.0);
    }
    partners.push_back(partner);
    originals.push_back(row);
  }
  return partners;
}

}  // namespace

GaussianProcessOptions EmulatorCalibrationOptions::default_gp() {
  GaussianProcessOptions gp;
  gp.kernel = KernelType::Matern52;
  gp.trend = TrendType::DiagonalQuadratic;
  gp.nugget_mode = NuggetMode::Estimated;
  gp.n_restarts = 2;
  return gp;
}

EmulatorCalibration::EmulatorCalibration(int dimension, BatchFeatureFunction evaluate, GaussianLikelihood likelihood,
                                         EmulatorCalibrationOptions options)
    : dimension_(dimension), evaluate_(std::move(evaluate)), likelihood_(std::move(likelihood)),
      options_(std::move(options)) {
  if (dimension_ < 1) throw std::invalid_argument("EmulatorCalibration: dimension must be >= 1");
  if (!evaluate_) throw std::invalid_argument("EmulatorCalibration: no evaluator");
  if (options_.batch_size < 1) throw std::invalid_argument("EmulatorCalibration: batch_size must be >= 1");
  if (options_.n_consecutive < 1) throw std::invalid_argument("EmulatorCalibration: n_consecutive must be >= 1");
  if (!(options_.influence_tolerance > 0.0) || !(options_.quantile_tolerance > 0.0))
    throw std::invalid_argument("EmulatorCalibration: tolerances must be positive");
  if (options_.noise_pairs < 0 || !(options_.noise_pair_distance > 0.0 && options_.noise_pair_distance < 0.5))
    throw std::invalid_argument("EmulatorCalibration: noise_pairs must be >= 0 and noise_pair_distance in (0, 0.5)");
  if (options_.focus && (!(options_.focus_cutoff > 0.0) || !(options_.focus_training_cutoff >= options_.focus_cutoff) ||
                         options_.focus_min_runs < 0))
    throw std::invalid_argument(
        "EmulatorCalibration: a focus needs 0 < focus_cutoff <= focus_training_cutoff and focus_min_runs >= 0");
  if (options_.initial_design && options_.initial_design->cols() != dimension_)
    throw std::invalid_argument("EmulatorCalibration: the initial design has " +
                                std::to_string(options_.initial_design->cols()) + " columns, the problem " +
                                std::to_string(dimension_) + " dimensions");
}

EmulatorCalibrationResult EmulatorCalibration::run() const {
  const int d = dimension_;
  const Eigen::Index p = likelihood_.n_features();
  const EmulatedLikelihood emulated(likelihood_);
  EmulatorCalibrationResult result;
  result.pool_ess_threshold =
      std::max(options_.min_pool_ess, options_.min_pool_ess_fraction * static_cast<double>(options_.pool_size));

  Eigen::MatrixXd initial;
  if (options_.initial_design) {
    initial = *options_.initial_design;
  } else {
    LatinHypercubeOptions lhs;
    lhs.n_maximin_swaps = 2000;
    const int n = options_.n_initial > 0 ? options_.n_initial : 10 * d;
    initial = latin_hypercube(static_cast<std::size_t>(n), static_cast<std::size_t>(d), options_.seed, lhs);
  }
  if (initial.rows() >= options_.max_evaluations)
    throw std::invalid_argument("EmulatorCalibration: the initial design of " + std::to_string(initial.rows()) +
                                " runs leaves no room under the cap of " + std::to_string(options_.max_evaluations));
  Runs runs;
  {
    const std::vector<Eigen::VectorXd> thetas = rows_of(initial);
    runs.add(thetas, evaluate_(thetas), p);
  }
  if (runs.points.size() < 2)
    throw std::runtime_error("emulator calibration: " + std::to_string(runs.points.size()) + " of " +
                             std::to_string(initial.rows()) +
                             " runs of the initial design succeeded; the emulators need two or more");

  FeatureWarping warping;
  if (options_.warping_width > 0.0) {
    warping.centre = likelihood_.observations().colwise().mean().transpose();
    warping.width = options_.warping_width * emulated.mean_variances().cwiseSqrt();
  }
  std::optional<FeatureFocus> focus;
  if (options_.focus) {
    focus = FeatureFocus{};
    focus->observed_mean = likelihood_.observations().colwise().mean().transpose();
    focus->mean_variances = emulated.mean_variances();
    focus->cutoff = options_.focus_cutoff;
    focus->training_cutoff = options_.focus_training_cutoff;
    focus->min_runs = options_.focus_min_runs > 0 ? options_.focus_min_runs : 2 * d + 3;
  }
  std::optional<FeatureEmulator> emulator;
  NoisePairs noise_pairs;
  int consecutive = 0, previous_points = 0;
  const std::vector<double> probabilities{0.05, 0.5, 0.95};
  for (int iteration = 0;; ++iteration) {
    const Clock::time_point start = Clock::now();
    EmulatorIteration it;
    it.n_points = static_cast<int>(runs.points.size());
    it.n_failed = static_cast<int>(runs.failed.size());
    it.n_evaluations = runs.n_evaluations;
    GaussianProcessOptions gp = options_.gp;
    gp.seed = options_.seed * 7919 + static_cast<std::uint64_t>(iteration) * 104729;
    it.n_noise_pairs = static_cast<int>(noise_pairs.size());
    emulator = FeatureEmulator(runs.point_matrix(), runs.feature_matrix(), gp, emulator ? &*emulator : nullptr, warping,
                               noise_pairs, focus, options_.input_map);
    const FeatureEmulator& current = *emulator;
    it.n_focused = current.focused() != nullptr ? static_cast<int>(current.focused_rows().size()) : 0;
    const BatchLogDensity log_likelihood = [&](const Eigen::MatrixXd& points) {
      return emulated.log_likelihood(current.predict(points));
    };

    TemperedSmcOptions smc = options_.smc;
    smc.seed = options_.seed * 31 + static_cast<std::uint64_t>(iteration);
    const TemperedSmcResult sampled = sample_tempered(d, log_likelihood, smc);
    ImportanceOptions importance;
    importance.n_samples = options_.pool_size;
    importance.seed = options_.seed * 37 + static_cast<std::uint64_t>(iteration);
    const ImportanceResult pool = importance_sample(sampled.particles, log_likelihood, importance);

    it.log_evidence = pool.log_evidence;
    it.evidence_relative_error = pool.relative_error;
    it.smc_log_evidence = sampled.log_evidence;
    it.n_temperatures = static_cast<int>(sampled.temperatures.size());
    it.pool_ess = pool.effective_sample_size;
    const Eigen::VectorXd log_weights = pool.log_likelihoods + pool.log_prior_over_proposal;
    const double top = log_weights.maxCoeff();
    Eigen::VectorXd weights = (log_weights.array() - top).exp().matrix();
    weights /= weights.sum();
    it.quantiles.resize(d, 3);
    it.posterior_sd.resize(d);
    for (int i = 0; i < d; ++i) {
      const Eigen::VectorXd values = pool.points.col(i);
      it.quantiles.row(i) = weighted_quantiles(values, weights, probabilities).transpose();
      const double mean = values.dot(weights);
      it.posterior_sd(i) = std::sqrt(std::max(0.0, (values.array() - mean).square().matrix().dot(weights)));
    }
    // Emulator influence: the posterior of the plug-in likelihood (the emulators' means,
    // no emulator variance), importance-weighted on the same pool, against the pool's.
    {
      FeaturePrediction plug_in = current.predict(pool.points);
      plug_in.latent_variance.setZero();
      const Eigen::VectorXd plug_log = emulated.log_likelihood(plug_in) + pool.log_prior_over_proposal;
      Eigen::VectorXd plug_weights = (plug_log.array() - plug_log.maxCoeff()).exp().matrix();
      plug_weights /= plug_weights.sum();
      it.plug_in_ess = 1.0 / plug_weights.squaredNorm();
      it.parameter_influence.resize(d);
      for (int i = 0; i < d; ++i) {
        const Eigen::VectorXd values = pool.points.col(i);
        const Eigen::VectorXd plug_quantiles = weighted_quantiles(values, plug_weights, probabilities);
        const double sd = std::max(it.posterior_sd(i), 1e-12);
        it.parameter_influence(i) = (plug_quantiles - it.quantiles.row(i).transpose()).cwiseAbs().maxCoeff() / sd;
      }
      it.emulator_influence = it.parameter_influence.maxCoeff();
      it.influence_standard_error =
          influence_standard_error(pool.points, weights, plug_weights, it.posterior_sd, probabilities,
                                   options_.seed * 43 + static_cast<std::uint64_t>(iteration));
    }
    if (current.focused() != nullptr) {
      const Eigen::VectorXd implausible = current.implausibility(pool.points);
      for (Eigen::Index r = 0; r < implausible.size(); ++r)
        if (implausible(r) <= options_.focus_cutoff) it.focused_weight += weights(r);
    }
    const FeaturePrediction at_particles = current.predict(sampled.particles);
    const Eigen::VectorXd noise_at_particles = at_particles.noise_variance.colwise().mean().transpose();
    const Eigen::VectorXd irreducible = emulated.mean_variances() + noise_at_particles;
    it.variance_ratios = at_particles.latent_variance.colwise().mean().transpose().cwiseQuotient(irreducible);
    it.max_variance_ratio = it.variance_ratios.maxCoeff();
    it.noise_standard_deviations = noise_at_particles.cwiseSqrt();
    it.quantile_shift = not_a_number;
    if (!result.history.empty()) {
      const EmulatorIteration& before = result.history.back();
      double shift = 0.0;
      for (int i = 0; i < d; ++i) {
        const double sd = std::max(it.posterior_sd(i), 1e-12);
        shift = std::max(shift, (it.quantiles.row(i) - before.quantiles.row(i)).cwiseAbs().maxCoeff() / sd);
      }
      it.quantile_shift = shift;
    }
    it.influence_settled =
        it.emulator_influence <= options_.influence_tolerance && it.plug_in_ess >= result.pool_ess_threshold;
    it.quantiles_settled = std::isfinite(it.quantile_shift) && it.quantile_shift <= options_.quantile_tolerance;
    it.pool_ess_sufficient = it.pool_ess >= result.pool_ess_threshold;
    const bool adds_data = iteration > 0 && it.n_points > previous_points;
    if (adds_data) {
      it.counted = it.influence_settled && it.quantiles_settled && it.pool_ess_sufficient;
      consecutive = it.counted ? consecutive + 1 : 0;
    }
    previous_points = it.n_points;

    result.pool = pool.points;
    result.pool_log_likelihood = pool.log_likelihoods;
    result.pool_log_weight = pool.log_prior_over_proposal;
    result.log_evidence = pool.log_evidence;
    result.evidence_relative_error = pool.relative_error;
    result.pool_ess = pool.effective_sample_size;
    result.particles = sampled.particles;

    const int room = options_.max_evaluations - runs.n_evaluations;
    if (consecutive >= options_.n_consecutive || room <= 0) {
      result.converged = consecutive >= options_.n_consecutive;
      result.stop_reason = result.converged
                               ? "converged: the emulators' influence and the posterior quantiles settled on " +
                                     std::to_string(options_.n_consecutive) + " iterations in a row"
                               : "the cap of " + std::to_string(options_.max_evaluations) + " runs was reached";
      it.seconds = std::chrono::duration<double>(Clock::now() - start).count();
      if (options_.on_iteration) options_.on_iteration(it);
      result.history.push_back(std::move(it));
      break;
    }
    it.chosen_points = choose_batch(current, sampled.particles, runs.failed, irreducible,
                                    std::min(options_.batch_size, room));
    // Noise pairs, once, with the first batch.
    std::vector<Eigen::Index> originals;
    if (iteration == 0 && options_.noise_pairs > 0) {
      const int count = std::min(options_.noise_pairs, room - static_cast<int>(it.chosen_points.rows()));
      const Eigen::MatrixXd points = runs.point_matrix();
      FeaturePrediction at_runs = current.predict(points);
      at_runs.latent_variance.setZero();
      const std::vector<Eigen::VectorXd> partners =
          noise_partners(points, emulated.log_likelihood(at_runs), count, options_.noise_pair_distance,
                         options_.seed * 41 + 7, originals);
      if (!partners.empty()) {
        const Eigen::Index n_chosen = it.chosen_points.rows();
        it.chosen_points.conservativeResize(n_chosen + static_cast<Eigen::Index>(partners.size()), Eigen::NoChange);
        for (std::size_t k = 0; k < partners.size(); ++k)
          it.chosen_points.row(n_chosen + static_cast<Eigen::Index>(k)) = partners[k].transpose();
      }
    }
    it.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (options_.on_iteration) options_.on_iteration(it);
    result.history.push_back(it);
    const std::vector<Eigen::VectorXd> thetas = rows_of(it.chosen_points);
    const std::vector<Eigen::Index> rows = runs.add(thetas, evaluate_(thetas), p);
    const std::size_t first_partner = thetas.size() - originals.size();
    for (std::size_t k = 0; k < originals.size(); ++k) {
      if (rows[first_partner + k] >= 0) noise_pairs.emplace_back(originals[k], rows[first_partner + k]);
    }
  }

  result.n_evaluations = runs.n_evaluations;
  result.design = runs.point_matrix();
  result.design_features = runs.feature_matrix();
  for (const Eigen::VectorXd& point : runs.failed) result.failures.push_back({point});
  result.emulator = std::move(emulator);

  // Warnings, with what to do.
  const EmulatorIteration& last = result.history.back();
  if (!runs.failed.empty())
    result.warnings.push_back(std::to_string(runs.failed.size()) + " of " + std::to_string(runs.n_evaluations) +
                              " runs failed and are left out of the emulators");
  for (Eigen::Index j = 0; j < p; ++j) {
    const double data_se = std::sqrt(emulated.mean_variances()(j));
    if (last.noise_standard_deviations(j) > data_se) {
      result.warnings.push_back("feature " + likelihood_.feature_names()[static_cast<std::size_t>(j)] +
                                ": the model's numerical noise (tau = " + shortest(last.noise_standard_deviations(j)) +
                                ") exceeds the standard error of the observed mean (" + shortest(data_se) +
                                "); the posterior is wider than the measurement noise alone allows");
    }
  }
  if (!result.converged) {
    std::string failing;
    if (!last.influence_settled)
      failing += "the emulators' influence " + shortest(last.emulator_influence) + " posterior sd > " +
                 shortest(options_.influence_tolerance) + " (plug-in pool ESS " + shortest(last.plug_in_ess) + ")";
    if (!last.quantiles_settled)
      failing += std::string(failing.empty() ? "" : "; ") + "the quantile shift " + shortest(last.quantile_shift) +
                 " posterior sd > " + shortest(options_.quantile_tolerance);
    if (!last.pool_ess_sufficient)
      failing += std::string(failing.empty() ? "" : "; ") + "the pool's effective sample size " +
                 shortest(last.pool_ess) + " < " + shortest(result.pool_ess_threshold);
    if (failing.empty()) failing = "the checks held on fewer than " + std::to_string(options_.n_consecutive) +
                                   " counted iterations in a row";
    result.warnings.push_back("not converged after " + std::to_string(runs.n_evaluations) + " runs (" + failing +
                              "); continue with a larger evaluation cap and --resume");
  } else if (!last.pool_ess_sufficient) {
    result.warnings.push_back("the pool's effective sample size " + shortest(last.pool_ess) + " is below " +
                              shortest(result.pool_ess_threshold));
  }
  return result;
}

}  // namespace rsw::calibration
