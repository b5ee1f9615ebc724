// SIR posterior of a prior pool; equations and sources in posterior.hpp.
#include "calibration/posterior.hpp"

#include "calibration/optimizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace rsw::calibration {

namespace {

// Smallest value whose cumulative weight reaches probability (values sorted by order).
double weighted_quantile(const Eigen::VectorXd& values, const Eigen::VectorXd& weights,
                         const std::vector<Eigen::Index>& order, double probability) {
  double cumulative = 0.0;
  for (const Eigen::Index i : order) {
    cumulative += weights(i);
    if (cumulative >= probability) return values(i);
  }
  return values(order.back());
}

}  // namespace

Eigen::VectorXd weighted_quantiles(const Eigen::VectorXd& values, const Eigen::VectorXd& weights,
                                   const std::vector<double>& probabilities) {
  if (values.size() == 0 || values.size() != weights.size())
    throw std::invalid_argument("weighted_quantiles: values and weights must be non-empty and of one size");
  std::vector<Eigen::Index> order(static_cast<std::size_t>(values.size()));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return values(a) < values(b); });
  Eigen::VectorXd quantiles(static_cast<Eigen::Index>(probabilities.size()));
  for (std::size_t k = 0; k < probabilities.size(); ++k)
    quantiles(static_cast<Eigen::Index>(k)) = weighted_quantile(values, weights, order, probabilities[k]);
  return quantiles;
}

SirPosterior::SirPosterior(Eigen::MatrixXd pool, Eigen::VectorXd log_likelihoods, PosteriorOptions options,
                           std::function<double(const Eigen::VectorXd&)> log_density)
    : pool_(std::move(pool)),
      log_likelihoods_(std::move(log_likelihoods)),
      options_(options),
      log_density_(std::move(log_density)) {
  if (pool_.rows() == 0 || pool_.cols() == 0) throw std::invalid_argument("SirPosterior: empty pool");
  if (pool_.rows() != log_likelihoods_.size())
    throw std::invalid_argument("SirPosterior: " + std::to_string(pool_.rows()) + " pool points but " +
                                std::to_string(log_likelihoods_.size()) + " log-likelihood values");
  if ((log_likelihoods_.array().isNaN()).any() || (log_likelihoods_.array() == std::numeric_limits<double>::infinity()).any())
    throw std::invalid_argument("SirPosterior: log-likelihood values must be finite or -inf");
  if (!std::isfinite(log_likelihoods_.maxCoeff()))
    throw std::invalid_argument("SirPosterior: every pool point has zero likelihood");
  if (!(options_.credible_level > 0.0 && options_.credible_level < 1.0))
    throw std::invalid_argument("SirPosterior: credible_level must be in (0, 1)");
  if (options_.n_samples < 0) throw std::invalid_argument("SirPosterior: n_samples must be >= 0");
}

SirPosterior::SirPosterior(const SbalcResult& sbalc, PosteriorOptions options)
    : SirPosterior(sbalc.pool, sbalc.pool_mean, options) {
  if (sbalc.pool_log_weight.size() == pool_.rows()) log_pool_weights_ = sbalc.pool_log_weight;
  if (sbalc.surrogate) {
    const GaussianProcess gp = *sbalc.surrogate;
    log_density_ = [gp](const Eigen::VectorXd& theta) { return gp.predict(theta).mean(0); };
  }
}

SirPosterior::SirPosterior(Eigen::MatrixXd pool, Eigen::VectorXd log_likelihoods, Eigen::VectorXd log_pool_weights,
                           PosteriorOptions options, std::function<double(const Eigen::VectorXd&)> log_density)
    : SirPosterior(std::move(pool), std::move(log_likelihoods), options, std::move(log_density)) {
  if (log_pool_weights.size() != pool_.rows())
    throw std::invalid_argument("SirPosterior: " + std::to_string(pool_.rows()) + " pool points but " +
                                std::to_string(log_pool_weights.size()) + " pool weights");
  log_pool_weights_ = std::move(log_pool_weights);
}

PosteriorResult SirPosterior::run() const {
  const Eigen::Index n = pool_.rows();
  const Eigen::Index d = pool_.cols();
  PosteriorResult result;

  // Importance weights: likelihood times the pool's prior/proposal ratio.
  const Eigen::VectorXd log_weights =
      log_pool_weights_.size() == n ? Eigen::VectorXd(log_likelihoods_ + log_pool_weights_) : log_likelihoods_;
  const double log_total = log_sum_exp(log_weights);
  result.weights = (log_weights.array() - log_total).exp().matrix();
  result.weights /= result.weights.sum();
  result.effective_sample_size = 1.0 / result.weights.squaredNorm();
  result.ess_threshold = std::max(options_.ess_min_absolute, options_.ess_min_fraction * static_cast<double>(n));
  if (result.effective_sample_size < result.ess_threshold) {
    result.poorly_resolved = true;
    std::ostringstream message;
    message << "effective sample size " << result.effective_sample_size << " of a pool of " << n
            << " is below " << result.ess_threshold
            << ": the posterior is concentrated on a few pool points (narrow, or in a corner or at an edge of the "
               "prior box); its moments, intervals and samples are poorly resolved. Use a larger pool or "
               "resample locally.";
    result.warning = message.str();
  }

  // Weighted moments.
  result.mean = pool_.transpose() * result.weights;
  const Eigen::MatrixXd centred = pool_.rowwise() - result.mean.transpose();
  const Eigen::MatrixXd covariance = centred.transpose() * result.weights.asDiagonal() * centred;
  result.standard_deviation = covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  result.correlation = Eigen::MatrixXd::Identity(d, d);
  for (Eigen::Index i = 0; i < d; ++i)
    for (Eigen::Index j = 0; j < d; ++j)
      if (i != j && result.standard_deviation(i) > 0.0 && result.standard_deviation(j) > 0.0)
        result.correlation(i, j) = covariance(i, j) / (result.standard_deviation(i) * result.standard_deviation(j));

  // Equal-tailed credible intervals.
  result.credible_level = options_.credible_level;
  const double tail = 0.5 * (1.0 - options_.credible_level);
  std::vector<Eigen::Index> order(static_cast<std::size_t>(n));
  for (Eigen::Index j = 0; j < d; ++j) {
    const Eigen::VectorXd values = pool_.col(j);
    std::iota(order.begin(), order.end(), Eigen::Index{0});
    std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return values(a) < values(b); });
    result.credible_intervals.push_back(
        {weighted_quantile(values, result.weights, order, tail), weighted_quantile(values, result.weights, order, 1.0 - tail)});
  }

  // MAP: best pool point, optionally refined on the log density.
  Eigen::Index best = 0;
  result.map_log_density = log_likelihoods_.maxCoeff(&best);
  result.map_point = pool_.row(best).transpose();
  if (options_.refine_map && log_density_) {
    const ObjectiveFunction objective = [this](const Eigen::VectorXd& theta, Eigen::VectorXd*) {
      return -log_density_(theta);
    };
    OptimizerOptions optimizer_options;
    optimizer_options.method = OptimizerMethod::DerivativeFree;
    const OptimizerResult refined =
        BoundedMinimizer(objective, Eigen::VectorXd::Zero(d), Eigen::VectorXd::Ones(d), optimizer_options)
            .run({result.map_point});
    if (refined.found && -refined.value > result.map_log_density) {
      result.map_point = refined.x;
      result.map_log_density = -refined.value;
      result.map_refined = true;
    }
  }

  // Systematic resampling: one uniform offset, n_samples equally spaced positions.
  const Eigen::Index n_samples = options_.n_samples > 0 ? options_.n_samples : n;
  std::mt19937_64 generator(options_.seed);
  const double offset = static_cast<double>(generator() >> 11) * 0x1.0p-53;
  result.samples.resize(n_samples, d);
  double cumulative = result.weights(0);
  Eigen::Index i = 0;
  for (Eigen::Index k = 0; k < n_samples; ++k) {
    const double position = (static_cast<double>(k) + offset) / static_cast<double>(n_samples);
    while (position > cumulative && i + 1 < n) cumulative += result.weights(++i);
    result.samples.row(k) = pool_.row(i);
  }
  return result;
}

}  // namespace rsw::calibration
