// SBALC with nugget; equations, stopping rule and sources in sbalc.hpp.
#include "calibration/sbalc.hpp"

#include "calibration/designs.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
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

// SE(X)/X of the pool average X = (1/N) Σ e^{v_i} (v includes ln r): with the Kish ESS
// of the weights ∝ e^{v}, √((N/ESS − 1)/(N − 1)) (sbalc.hpp); +∞ for N < 2 or no weight.
double relative_standard_error(const Eigen::VectorXd& v) {
  const double n = static_cast<double>(v.size());
  const double ess = effective_sample_size(v);
  if (n < 2.0 || !(ess > 0.0)) return std::numeric_limits<double>::infinity();
  return std::sqrt(std::max(n / ess - 1.0, 0.0) / (n - 1.0));
}

struct EvidenceEstimate {
  double log_evidence, log_upper, log_lower, ratio;
  double gp_ratio;        // (c_upper,GP − c_lower,GP)/ĉ, the paper's ratio
  double relative_error;  // SE(ĉ)/ĉ (0 when the pool's error is left out)
};

// Pool averages with importance ratios r_i (ln r = log_r; all 0 for the prior pool). With
// pool_error, the bounds hold the pool's Monte Carlo error in quadrature (sbalc.hpp):
//     c_upper/ĉ = 1 + √((u − 1)² + (b δ_u u)²),   c_lower/ĉ = max(0, 1 − √((1 − l)² + (b δ_l l)²)),
// u = c_upper,GP/ĉ ≥ 1, l = c_lower,GP/ĉ ≤ 1, δ the relative standard errors of those averages.
EvidenceEstimate estimate_evidence(const Eigen::VectorXd& m, const Eigen::VectorXd& s, double b,
                                   const Eigen::VectorXd& log_r, bool pool_error) {
  const double log_n = std::log(static_cast<double>(m.size()));
  EvidenceEstimate e{};
  const Eigen::VectorXd v = m + log_r, v_upper = m + b * s + log_r, v_lower = m - b * s + log_r;
  e.log_evidence = log_sum_exp(v) - log_n;
  double upper = std::exp(log_sum_exp(v_upper) - log_n - e.log_evidence);
  double lower = std::exp(log_sum_exp(v_lower) - log_n - e.log_evidence);
  e.gp_ratio = upper - lower;
  if (pool_error) {
    e.relative_error = relative_standard_error(v);
    const double delta_upper = relative_standard_error(v_upper), delta_lower = relative_standard_error(v_lower);
    if (std::isfinite(upper)) upper = 1.0 + std::hypot(upper - 1.0, b * delta_upper * upper);
    const double lower_half_width = std::hypot(1.0 - lower, lower > 0.0 ? b * delta_lower * lower : 0.0);
    lower = std::isfinite(lower_half_width) ? std::max(0.0, 1.0 - lower_half_width) : 0.0;
  }
  e.log_upper = e.log_evidence + std::log(upper);
  e.log_lower = lower > 0.0 ? e.log_evidence + std::log(lower) : kMinusInfinity;
  e.ratio = upper - lower;
  return e;
}

// S of the peak-spread guard (sbalc.hpp): ℒ_max − min ℒ_i over the evaluations within
// h_d of ℒ_max if there are at least d + 1 of them, else h_d.
double evaluated_peak_spread(const std::vector<double>& values, int d) {
  const double h = peak_band_height(d);
  const double top = *std::max_element(values.begin(), values.end());
  int in_band = 0;
  double lowest = top;
  for (const double v : values) {
    if (v >= top - h) {
      ++in_band;
      lowest = std::min(lowest, v);
    }
  }
  return in_band >= d + 1 ? top - lowest : h;
}

std::string format_number(double value, int digits = 3) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
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

// The result's warnings (sbalc.hpp): failed runs left out of the GP; if it did not
// converge, the guards that failed in the last iteration, then the stop; each with what
// to do. Option names are given with the study key of `rsw calibrate` in parentheses.
void add_warnings(SbalcResult& result, const SbalcOptions& options) {
  if (options.failed_runs == FailedRunPolicy::exclude && !result.failures.empty()) {
    result.warnings.push_back(
        std::to_string(result.failures.size()) + " of " + std::to_string(result.n_evaluations) +
        " evaluations failed and were left out of the GP (failed_runs = exclude, calibration.sbalc.failed_runs): "
        "the evidence and the posterior extrapolate the GP over the region where the model fails. With "
        "impute_minimum that region is learnt as poor fit instead.");
  }
  if (result.converged) return;
  if (!result.history.empty()) {
    const SbalcIteration& last = result.history.back();
    if (last.pool_ess_too_low) {
      result.warnings.push_back(
          "pool effective sample size " + format_number(last.pool_ess) + " is below " +
          format_number(result.pool_ess_threshold) + " (max of min_pool_ess and min_pool_ess_fraction of the pool of " +
          std::to_string(options.pool_size) +
          "): the evidence and the posterior rest on a few pool points, whose Monte Carlo error is itself "
          "poorly estimated. " +
          (options.adaptive_pool
               ? "The adaptive pool has not resolved the posterior yet: allow more evaluations (max_evaluations, "
                 "calibration.sbalc.max_evaluations) or a larger pool (pool_size)."
               : "Use the adaptive pool (adaptive_pool, calibration.sbalc.pool: adaptive) or a larger pool "
                 "(pool_size)."));
    }
    if (last.noise_exceeds_peak_spread) {
      result.warnings.push_back(
          "the GP's log-likelihood noise tau = " + format_number(last.noise_standard_deviation) +
          " exceeds the spread " + format_number(last.peak_spread) +
          " of the evaluated log-likelihoods near their maximum (those within h_d = " +
          format_number(peak_band_height(static_cast<int>(result.design.cols()))) +
          " of the best): the nugget can absorb the likelihood's peak, so the noise allowance was not applied "
          "and convergence was refused. If the log-likelihood is smooth, turn the nugget off (gp.nugget_mode, "
          "calibration.sbalc.nugget: off) or fix it at the known noise (nugget: fixed); otherwise allow more "
          "evaluations so that the peak is sampled more densely.");
    }
    if (last.noise_allowance_capped) {
      result.warnings.push_back(
          "the log-likelihood noise alone spreads the evidence bounds by " + format_number(last.noise_ratio) +
          "; the ratio " + format_number(last.ratio) + " is within the noise allowance but above its cap of " +
          format_number(options.max_noise_tolerance_factor) + " x tolerance = " +
          format_number(last.tolerance_used) + ": the evidence is noise-limited. Accept that accuracy with a "
          "tolerance of at least " + format_number(last.ratio / options.max_noise_tolerance_factor) +
          " (tolerance, calibration.sbalc.tolerance), or make the log-likelihood less noisy.");
    }
  }
  std::string stop = "not converged: " + result.stop_reason;
  if (result.stop_reason.rfind("evaluation cap", 0) == 0) {
    if (!result.history.empty())
      stop += " (last ratio " + format_number(result.ratio) + ", tolerance " +
              format_number(result.history.back().tolerance_used) + ")";
    stop += ". The evidence and the posterior are not reliable; allow more evaluations (max_evaluations, "
            "calibration.sbalc.max_evaluations; rsw calibrate --resume continues with the runs so far).";
  } else if (result.stop_reason.rfind("no pool point", 0) == 0) {
    stop += ". The evidence and the posterior are not reliable; use a larger pool (pool_size).";
  } else {
    stop += ". There is no evidence or posterior; see why the evaluations failed.";
  }
  result.warnings.push_back(stop);
}

}  // namespace

double log_sum_exp(const Eigen::VectorXd& values) {
  if (values.size() == 0) return kMinusInfinity;
  const double largest = values.maxCoeff();
  if (!std::isfinite(largest)) return largest;
  return largest + std::log((values.array() - largest).exp().sum());
}

double SbalcResult::evidence() const { return std::exp(log_evidence); }

SbalcOptions simulator_sbalc_options() {
  SbalcOptions options;
  options.adaptive_pool = true;
  options.gp.nugget_mode = NuggetMode::Estimated;
  options.batch_size = 4;
  return options;
}

double peak_band_height(int dimension) {
  // Wilson & Hilferty (1931): χ²_p(d) ≈ d (1 − 2/(9d) + z_p √(2/(9d)))³, z_0.99 = Φ⁻¹(0.99).
  const double d = static_cast<double>(dimension), z = 2.3263478740408408;
  const double a = 2.0 / (9.0 * d);
  return 0.5 * d * std::pow(1.0 - a + z * std::sqrt(a), 3);
}

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
  if (!(options_.max_noise_tolerance_factor >= 1.0))
    throw std::invalid_argument("Sbalc: max_noise_tolerance_factor must be >= 1");
  if (!(options_.min_pool_ess >= 0.0)) throw std::invalid_argument("Sbalc: min_pool_ess must be >= 0");
  if (!(options_.min_pool_ess_fraction >= 0.0 && options_.min_pool_ess_fraction <= 1.0))
    throw std::invalid_argument("Sbalc: min_pool_ess_fraction must be in [0, 1]");
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
  int previous_data_size = 0;
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
    const EvidenceEstimate evidence = estimate_evidence(prediction.mean, s, b, result.pool_log_weight, true);

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
    record.gp_ratio = evidence.gp_ratio;
    record.pool_relative_error = evidence.relative_error;
    record.hyperparameters = gp.hyperparameters();
    record.noise_standard_deviation = std::sqrt(gp.hyperparameters().noise_variance);
    record.jitter = gp.jitter();
    record.trend_used = gp.trend_used();
    record.tolerance_used = options_.tolerance;
    record.peak_spread = evaluated_peak_spread(values, d);
    record.noise_exceeds_peak_spread = record.noise_standard_deviation > record.peak_spread &&
                                       record.noise_standard_deviation > 0.5 * options_.tolerance;
    double noise_allowance = options_.tolerance;  // √(tolerance² + ratio_τ²), before the cap
    if (options_.noise_aware_tolerance && gp.hyperparameters().noise_variance > 0.0) {
      // s₀²: the same GP conditioned on the same points as if they were noise-free.
      GaussianProcessOptions interpolating = gp_options;
      interpolating.nugget_mode = NuggetMode::Off;
      interpolating.trend = gp.trend_used();
      try {
        const GaussianProcess noise_free(x, y, interpolating, gp.hyperparameters());
        const Eigen::VectorXd s_noise =
            (prediction.latent_variance - noise_free.predict(result.pool).latent_variance).cwiseMax(0.0).cwiseSqrt();
        record.noise_ratio = estimate_evidence(prediction.mean, s_noise, b, result.pool_log_weight, false).ratio;
        noise_allowance = std::hypot(options_.tolerance, record.noise_ratio);
        // A noise that can swallow the peak earns no allowance (sbalc.hpp, guards).
        if (!record.noise_exceeds_peak_spread)
          record.tolerance_used =
              std::min(noise_allowance, options_.max_noise_tolerance_factor * options_.tolerance);
      } catch (const std::runtime_error&) {
        // Clustered points can make the noise-free matrix unfactorisable within the
        // jitter cap; then this iteration keeps the plain (stricter) tolerance.
      }
    }

    // Guards and the count of consecutive iterations (sbalc.hpp, stopping rule).
    const double ess_threshold =
        std::max(options_.min_pool_ess, options_.min_pool_ess_fraction * static_cast<double>(options_.pool_size));
    record.pool_ess_too_low = pool_ess < ess_threshold;
    record.noise_allowance_capped = !record.noise_exceeds_peak_spread && evidence.ratio >= record.tolerance_used &&
                                    evidence.ratio < noise_allowance;
    std::string refusal;
    const auto refuse = [&refusal](const std::string& why) { refusal += (refusal.empty() ? "" : "; ") + why; };
    if (record.pool_ess_too_low)
      refuse("pool effective sample size " + format_number(pool_ess) + " below " + format_number(ess_threshold));
    if (record.noise_exceeds_peak_spread)
      refuse("log-likelihood noise tau " + format_number(record.noise_standard_deviation) +
             " exceeds the peak spread " + format_number(record.peak_spread));
    if (record.noise_allowance_capped)
      refuse("ratio " + format_number(evidence.ratio) + " within the noise allowance " +
             format_number(noise_allowance) + " but above its cap " + format_number(record.tolerance_used));
    record.refusal = refusal;
    const int data_size = n + n_imputed;
    const bool added_run = iteration > 0 && data_size > previous_data_size;
    previous_data_size = data_size;
    if (added_run) {
      record.counted = evidence.ratio < record.tolerance_used && refusal.empty();
      consecutive = record.counted ? consecutive + 1 : 0;
    }

    result.log_evidence = evidence.log_evidence;
    result.log_evidence_upper = evidence.log_upper;
    result.log_evidence_lower = evidence.log_lower;
    result.ratio = evidence.ratio;
    result.noise_ratio = record.noise_ratio;
    result.noise_standard_deviation = record.noise_standard_deviation;
    result.pool_ess = pool_ess;
    result.pool_ess_threshold = ess_threshold;
    result.pool_relative_error = evidence.relative_error;
    result.peak_spread = record.peak_spread;
    result.pool_mean = prediction.mean;
    result.pool_latent_sd = s;
    result.design = x.topRows(n);
    result.log_likelihoods = Eigen::Map<const Eigen::VectorXd>(values.data(), n);  // unfloored
    result.surrogate = gp;

    if (consecutive >= options_.n_consecutive) {
      result.converged = true;
      result.stop_reason = "ratio below tolerance on " + std::to_string(options_.n_consecutive) +
                           " consecutive iterations after the initial design";
      result.history.push_back(std::move(record));
      break;
    }
    const int remaining = options_.max_evaluations - result.n_evaluations;
    if (remaining <= 0) {
      result.stop_reason = "evaluation cap of " + std::to_string(options_.max_evaluations) + " reached";
      if (!record.refusal.empty()) result.stop_reason += "; convergence refused: " + record.refusal;
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
  add_warnings(result, options_);
  return result;
}

}  // namespace rsw::calibration
