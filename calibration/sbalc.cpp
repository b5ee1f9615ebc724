// SBALC with nugget; equations, stopping rule and sources in sbalc.hpp.
#include "calibration/sbalc.hpp"

#include "calibration/designs.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>

namespace rsw::calibration {

namespace {

constexpr double kMinusInfinity = -std::numeric_limits<double>::infinity();

double uniform01(std::mt19937_64& generator) { return static_cast<double>(generator() >> 11) * 0x1.0p-53; }

Eigen::MatrixXd prior_pool(int n, int d, std::uint64_t seed) {
  std::mt19937_64 generator(seed);
  Eigen::MatrixXd pool(n, d);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < d; ++j) pool(i, j) = uniform01(generator);
  return pool;
}

// Kish effective sample size of the weights ∝ exp(v).
double effective_sample_size(const Eigen::VectorXd& v) {
  const double total = log_sum_exp(v);
  if (!std::isfinite(total)) return 0.0;
  const Eigen::ArrayXd w = (v.array() - total).exp();
  return 1.0 / w.square().sum();
}

// The adaptive pool (sbalc.hpp): n points from q = α U[0,1]^d + (1 − α) N(μ, Σ)|box,
// with ln r = −ln q at each. μ, Σ from the old pool's weights ∝ exp(log_w).
void redraw_pool(const Eigen::MatrixXd& old_pool, const Eigen::VectorXd& log_w, double alpha, std::uint64_t seed,
                 Eigen::MatrixXd& pool, Eigen::VectorXd& log_r) {
  const Eigen::Index n = old_pool.rows(), d = old_pool.cols();
  const Eigen::VectorXd w = (log_w.array() - log_sum_exp(log_w)).exp().matrix();
  const Eigen::VectorXd mu = old_pool.transpose() * w;
  const Eigen::MatrixXd centred = old_pool.rowwise() - mu.transpose();
  Eigen::MatrixXd sigma = centred.transpose() * w.asDiagonal() * centred;
  const double spacing = std::pow(static_cast<double>(n), -1.0 / static_cast<double>(d));
  sigma = 4.0 * sigma + spacing * spacing * Eigen::MatrixXd::Identity(d, d);
  const Eigen::LLT<Eigen::MatrixXd> llt(sigma);
  const Eigen::MatrixXd L = llt.matrixL();
  const double log_det_l = L.diagonal().array().log().sum();
  std::mt19937_64 generator(seed);
  std::normal_distribution<double> normal;
  pool.resize(n, d);
  long gaussian_draws = 0, gaussian_inside = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (uniform01(generator) < alpha) {
      for (Eigen::Index j = 0; j < d; ++j) pool(i, j) = uniform01(generator);
      continue;
    }
    for (int attempt = 0;; ++attempt) {
      Eigen::VectorXd z(d);
      for (Eigen::Index j = 0; j < d; ++j) z(j) = normal(generator);
      const Eigen::VectorXd theta = mu + L * z;
      ++gaussian_draws;
      if ((theta.array() >= 0.0).all() && (theta.array() <= 1.0).all()) {
        ++gaussian_inside;
        pool.row(i) = theta.transpose();
        break;
      }
      if (attempt == 10000) {  // the Gaussian lies outside the box: a prior point instead
        for (Eigen::Index j = 0; j < d; ++j) pool(i, j) = uniform01(generator);
        break;
      }
    }
  }
  const double z_box = gaussian_draws > 0 ? std::max(static_cast<double>(gaussian_inside) / gaussian_draws, 1e-300) : 1.0;
  log_r.resize(n);
  const double log_norm = 0.5 * static_cast<double>(d) * std::log(2.0 * M_PI) + log_det_l + std::log(z_box);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::VectorXd z = L.triangularView<Eigen::Lower>().solve(pool.row(i).transpose() - mu);
    const double log_phi = -0.5 * z.squaredNorm() - log_norm;  // density of N(μ, Σ)/Z on the box
    const double q = alpha + (1.0 - alpha) * std::exp(log_phi);
    log_r(i) = -std::log(q);
  }
}

// ln LF = 2 ln s + m + b s + ln(1 − e^{−2bs}); −∞ where s = 0.
double log_learning_function(double m, double s, double b) {
  if (!(s > 0.0)) return kMinusInfinity;
  return 2.0 * std::log(s) + m + b * s + std::log(-std::expm1(-2.0 * b * s));
}

struct EvidenceEstimate {
  double log_evidence, log_upper, log_lower, ratio;
};

// Pool averages with importance ratios r_i (ln r = log_r; all 0 for the prior pool).
EvidenceEstimate estimate_evidence(const Eigen::VectorXd& m, const Eigen::VectorXd& s, double b,
                                   const Eigen::VectorXd& log_r) {
  const double log_n = std::log(static_cast<double>(m.size()));
  EvidenceEstimate e;
  e.log_evidence = log_sum_exp(m + log_r) - log_n;
  e.log_upper = log_sum_exp(m + b * s + log_r) - log_n;
  e.log_lower = log_sum_exp(m - b * s + log_r) - log_n;
  e.ratio = std::exp(e.log_upper - e.log_evidence) - std::exp(e.log_lower - e.log_evidence);
  return e;
}

// Index of the largest ln LF over unused pool points, or −1 if none is finite. Ties
// go to the lowest index, so the choice is deterministic.
Eigen::Index best_candidate(const GaussianProcessPrediction& prediction, const std::vector<char>& used, double b,
                            const Eigen::VectorXd& log_r, double& log_lf) {
  Eigen::Index best = -1;
  log_lf = kMinusInfinity;
  for (Eigen::Index i = 0; i < prediction.mean.size(); ++i) {
    if (used[static_cast<std::size_t>(i)]) continue;
    const double value =
        log_learning_function(prediction.mean(i), std::sqrt(prediction.latent_variance(i)), b) + log_r(i);
    if (value > log_lf) {
      log_lf = value;
      best = i;
    }
  }
  return best;
}

}  // namespace

double log_sum_exp(const Eigen::VectorXd& values) {
  if (values.size() == 0) return kMinusInfinity;
  const double largest = values.maxCoeff();
  if (!std::isfinite(largest)) return largest;
  return largest + std::log((values.array() - largest).exp().sum());
}

double SbalcResult::evidence() const { return std::exp(log_evidence); }

Sbalc::Sbalc(int dimension, LogLikelihoodFunction log_likelihood, SbalcOptions options)
    : Sbalc(dimension,
            BatchLogLikelihoodFunction([f = std::move(log_likelihood)](const std::vector<Eigen::VectorXd>& thetas) {
              std::vector<std::optional<double>> values;
              values.reserve(thetas.size());
              for (const auto& theta : thetas) values.push_back(f(theta));
              return values;
            }),
            std::move(options)) {}

Sbalc::Sbalc(int dimension, BatchLogLikelihoodFunction batch_log_likelihood, SbalcOptions options)
    : dimension_(dimension), evaluate_(std::move(batch_log_likelihood)), options_(std::move(options)) {
  if (dimension_ < 1) throw std::invalid_argument("Sbalc: dimension must be >= 1");
  if (!evaluate_) throw std::invalid_argument("Sbalc: no log-likelihood function");
  if (options_.pool_size < 1) throw std::invalid_argument("Sbalc: pool_size must be >= 1");
  if (options_.batch_size < 1) throw std::invalid_argument("Sbalc: batch_size must be >= 1");
  if (options_.n_consecutive < 1) throw std::invalid_argument("Sbalc: n_consecutive must be >= 1");
  if (!(options_.tolerance > 0.0)) throw std::invalid_argument("Sbalc: tolerance must be > 0");
  if (!(options_.bound_width > 0.0)) throw std::invalid_argument("Sbalc: bound_width must be > 0");
  if (options_.initial_design) {
    const Eigen::MatrixXd& design = *options_.initial_design;
    if (design.rows() < 1 || design.cols() != dimension_)
      throw std::invalid_argument("Sbalc: initial_design must have rows of dimension " + std::to_string(dimension_));
    if ((design.array() < 0.0).any() || (design.array() > 1.0).any())
      throw std::invalid_argument("Sbalc: initial_design must lie in [0, 1]^d");
  } else if (options_.n_initial < 2) {
    throw std::invalid_argument("Sbalc: n_initial must be >= 2");
  }
}

SbalcResult Sbalc::run() const {
  const int d = dimension_;
  const double b = options_.bound_width;
  SbalcResult result;
  result.pool = prior_pool(options_.pool_size, d, options_.seed);
  result.pool_log_weight = Eigen::VectorXd::Zero(options_.pool_size);
  std::vector<char> used(static_cast<std::size_t>(options_.pool_size), 0);

  std::vector<Eigen::VectorXd> points;
  std::vector<double> values;
  const auto evaluate = [&](const std::vector<Eigen::VectorXd>& batch) {
    std::vector<std::optional<double>> outcome;
    std::string error;
    try {
      outcome = evaluate_(batch);
    } catch (const std::exception& exception) {
      error = exception.what();
    }
    if (error.empty() && outcome.size() != batch.size())
      throw std::runtime_error("Sbalc: the batch evaluator returned " + std::to_string(outcome.size()) +
                               " values for " + std::to_string(batch.size()) + " points");
    for (std::size_t i = 0; i < batch.size(); ++i) {
      ++result.n_evaluations;
      if (!error.empty()) {
        result.failures.push_back({batch[i], "evaluator threw: " + error});
      } else if (!outcome[i]) {
        result.failures.push_back({batch[i], "evaluation failed"});
      } else if (!std::isfinite(*outcome[i])) {
        result.failures.push_back({batch[i], "non-finite log-likelihood " + std::to_string(*outcome[i])});
      } else {
        points.push_back(batch[i]);
        values.push_back(*outcome[i]);
      }
    }
  };

  // Initial design; pool points that coincide with it are never proposed.
  const Eigen::MatrixXd initial = options_.initial_design ? *options_.initial_design
                                                          : hammersley(static_cast<std::size_t>(options_.n_initial),
                                                                       static_cast<std::size_t>(d));
  std::vector<Eigen::VectorXd> batch;
  for (Eigen::Index i = 0; i < initial.rows(); ++i) batch.push_back(initial.row(i).transpose());
  if (static_cast<int>(batch.size()) > options_.max_evaluations) batch.resize(std::max(options_.max_evaluations, 0));
  for (Eigen::Index p = 0; p < result.pool.rows(); ++p)
    for (const auto& x : batch)
      if ((result.pool.row(p).transpose() - x).cwiseAbs().maxCoeff() < 1e-14) used[static_cast<std::size_t>(p)] = 1;
  evaluate(batch);

  std::optional<GaussianProcessHyperparameters> previous;
  int consecutive = 0;
  for (int iteration = 0;; ++iteration) {
    const int n = static_cast<int>(points.size());
    if (n < 2) {
      result.stop_reason = "fewer than two successful evaluations (" + std::to_string(n) + " of " +
                           std::to_string(result.n_evaluations) + ")";
      break;
    }
    // The GP's data: the successful evaluations, and with impute_minimum the failed
    // ones at the lowest successful ℒ so far.
    const bool impute = options_.failed_runs == FailedRunPolicy::impute_minimum;
    const int n_imputed = impute ? static_cast<int>(result.failures.size()) : 0;
    // The floor ℒ_max − Δ (sbalc.hpp) bounds what the GP must fit.
    const double floor = options_.log_likelihood_range > 0.0
                             ? *std::max_element(values.begin(), values.end()) - options_.log_likelihood_range
                             : kMinusInfinity;
    const double imputed_value = std::max(*std::min_element(values.begin(), values.end()), floor);
    Eigen::MatrixXd x(n + n_imputed, d);
    Eigen::VectorXd y(n + n_imputed);
    for (int i = 0; i < n; ++i) {
      x.row(i) = points[static_cast<std::size_t>(i)].transpose();
      y(i) = std::max(values[static_cast<std::size_t>(i)], floor);
    }
    for (int i = 0; i < n_imputed; ++i) {
      x.row(n + i) = result.failures[static_cast<std::size_t>(i)].theta.transpose();
      y(n + i) = imputed_value;
    }
    GaussianProcessOptions gp_options = options_.gp;
    gp_options.seed = options_.seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(iteration) + 1;
    GaussianProcessRegression regression(x, y, gp_options);
    if (previous) regression.set_warm_start(*previous);
    GaussianProcess gp = regression.run();
    previous = gp.hyperparameters();
    GaussianProcessPrediction prediction = gp.predict(result.pool);
    double pool_ess = effective_sample_size(prediction.mean + result.pool_log_weight);
    bool pool_redrawn = false;
    if (options_.adaptive_pool && pool_ess < options_.adaptive_pool_ess_fraction * options_.pool_size) {
      Eigen::MatrixXd pool;
      Eigen::VectorXd log_r;
      redraw_pool(result.pool, prediction.mean + result.pool_log_weight, options_.adaptive_pool_prior_fraction,
                  options_.seed * 0xD1B54A32D192ED03ULL + static_cast<std::uint64_t>(iteration) + 7, pool, log_r);
      result.pool = std::move(pool);
      result.pool_log_weight = std::move(log_r);
      std::fill(used.begin(), used.end(), 0);
      prediction = gp.predict(result.pool);
      pool_ess = effective_sample_size(prediction.mean + result.pool_log_weight);
      pool_redrawn = true;
    }
    const Eigen::VectorXd s = prediction.latent_variance.cwiseSqrt();
    const EvidenceEstimate evidence = estimate_evidence(prediction.mean, s, b, result.pool_log_weight);

    SbalcIteration record;
    record.n_points = n;
    record.n_imputed = n_imputed;
    record.pool_ess = pool_ess;
    record.pool_redrawn = pool_redrawn;
    record.imputed_value = n_imputed > 0 ? imputed_value : 0.0;
    record.n_evaluations = result.n_evaluations;
    record.log_evidence = evidence.log_evidence;
    record.log_evidence_upper = evidence.log_upper;
    record.log_evidence_lower = evidence.log_lower;
    record.ratio = evidence.ratio;
    record.hyperparameters = gp.hyperparameters();
    record.noise_standard_deviation = std::sqrt(gp.hyperparameters().noise_variance);
    record.jitter = gp.jitter();
    record.trend_used = gp.trend_used();
    record.tolerance_used = options_.tolerance;
    if (options_.noise_aware_tolerance && gp.hyperparameters().noise_variance > 0.0) {
      // s₀²: the same GP conditioned on the same points as if they were noise-free.
      GaussianProcessOptions interpolating = gp_options;
      interpolating.nugget_mode = NuggetMode::Off;
      interpolating.trend = gp.trend_used();
      try {
        const GaussianProcess noise_free(x, y, interpolating, gp.hyperparameters());
        const Eigen::VectorXd s_noise =
            (prediction.latent_variance - noise_free.predict(result.pool).latent_variance).cwiseMax(0.0).cwiseSqrt();
        record.noise_ratio = estimate_evidence(prediction.mean, s_noise, b, result.pool_log_weight).ratio;
        record.tolerance_used = std::hypot(options_.tolerance, record.noise_ratio);
      } catch (const std::runtime_error&) {
        // Clustered points can make the noise-free matrix unfactorisable within the
        // jitter cap; then this iteration keeps the plain (stricter) tolerance.
      }
    }
    consecutive = evidence.ratio < record.tolerance_used ? consecutive + 1 : 0;

    result.log_evidence = evidence.log_evidence;
    result.log_evidence_upper = evidence.log_upper;
    result.log_evidence_lower = evidence.log_lower;
    result.ratio = evidence.ratio;
    result.noise_ratio = record.noise_ratio;
    result.noise_standard_deviation = record.noise_standard_deviation;
    result.pool_mean = prediction.mean;
    result.pool_latent_sd = s;
    result.design = x.topRows(n);
    result.log_likelihoods = Eigen::Map<const Eigen::VectorXd>(values.data(), n);  // unfloored
    result.surrogate = gp;

    if (consecutive >= options_.n_consecutive) {
      result.converged = true;
      result.stop_reason = "ratio below tolerance on " + std::to_string(options_.n_consecutive) +
                           " consecutive iterations";
      result.history.push_back(std::move(record));
      break;
    }
    const int remaining = options_.max_evaluations - result.n_evaluations;
    if (remaining <= 0) {
      result.stop_reason = "evaluation cap of " + std::to_string(options_.max_evaluations) + " reached";
      result.history.push_back(std::move(record));
      break;
    }

    // Choose q points; for q > 1 by the kriging believer. Failed points enter the
    // selection GP at its own mean there: m is unchanged, s vanishes near them.
    batch.clear();
    const int q = std::min(options_.batch_size, remaining);
    GaussianProcess believer = gp;
    if (!impute && !result.failures.empty()) {
      const Eigen::Index n_failed = static_cast<Eigen::Index>(result.failures.size());
      Eigen::MatrixXd failed(n_failed, d);
      for (Eigen::Index i = 0; i < n_failed; ++i)
        failed.row(i) = result.failures[static_cast<std::size_t>(i)].theta.transpose();
      Eigen::MatrixXd x_believed(n + n_failed, d);
      x_believed << x, failed;
      Eigen::VectorXd y_believed(n + n_failed);
      y_believed << y, gp.predict(failed).mean;
      GaussianProcessOptions believer_options = gp_options;
      believer_options.trend = gp.trend_used();
      believer = GaussianProcess(std::move(x_believed), std::move(y_believed), believer_options, gp.hyperparameters());
      prediction = believer.predict(result.pool);
    }
    for (int k = 0; k < q; ++k) {
      double log_lf = kMinusInfinity;
      const Eigen::Index index = best_candidate(prediction, used, b, result.pool_log_weight, log_lf);
      if (index < 0) break;
      if (k == 0) record.log_learning_function = log_lf;
      used[static_cast<std::size_t>(index)] = 1;
      const Eigen::VectorXd theta = result.pool.row(index).transpose();
      batch.push_back(theta);
      if (k + 1 < q) {
        believer = believer.with_added_point(theta, prediction.mean(index));
        prediction = believer.predict(result.pool);
      }
    }
    record.chosen_points.resize(static_cast<Eigen::Index>(batch.size()), d);
    for (std::size_t k = 0; k < batch.size(); ++k) record.chosen_points.row(static_cast<Eigen::Index>(k)) = batch[k];
    result.history.push_back(std::move(record));
    if (batch.empty()) {
      result.stop_reason = "no pool point left with positive learning function";
      break;
    }
    evaluate(batch);
  }
  return result;
}

}  // namespace rsw::calibration
