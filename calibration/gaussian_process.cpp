// Gaussian-process regression; equations and sources in gaussian_process.hpp.
#include "calibration/gaussian_process.hpp"

#include "calibration/optimizer.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

namespace rsw::calibration {

const char* kernel_name(KernelType kernel) {
  return kernel == KernelType::SquaredExponential ? "squared_exponential" : "matern52";
}

const char* trend_name(TrendType trend) {
  switch (trend) {
    case TrendType::Constant:
      return "constant";
    case TrendType::DiagonalQuadratic:
      return "diagonal_quadratic";
    case TrendType::FullQuadratic:
      return "full_quadratic";
  }
  return "unknown";
}

const char* nugget_name(NuggetMode mode) {
  switch (mode) {
    case NuggetMode::Off:
      return "off";
    case NuggetMode::Fixed:
      return "fixed";
    case NuggetMode::Estimated:
      return "estimated";
  }
  return "unknown";
}


namespace {

constexpr double kLogTwoPi = 1.8378770664093454835606594728112;
constexpr double kSqrt5 = 2.2360679774997896964091736687313;
constexpr Eigen::Index kPredictionChunk = 2048;

// Uniform on [0, 1) from the top 53 bits: the same stream on every platform.
double uniform01(std::mt19937_64& generator) { return static_cast<double>(generator() >> 11) * 0x1.0p-53; }

// c(r²) for the chosen kernel.
double correlation(KernelType kernel, double r2) {
  if (kernel == KernelType::SquaredExponential) return std::exp(-0.5 * r2);
  const double r = std::sqrt(r2);
  return (1.0 + kSqrt5 * r + 5.0 / 3.0 * r2) * std::exp(-kSqrt5 * r);
}

// g(r²) with ∂c/∂ln ℓ_j = g · (Δx_j/ℓ_j)².
double length_scale_factor(KernelType kernel, double r2) {
  if (kernel == KernelType::SquaredExponential) return std::exp(-0.5 * r2);
  const double r = std::sqrt(r2);
  return 5.0 / 3.0 * (1.0 + kSqrt5 * r) * std::exp(-kSqrt5 * r);
}

// σ² c(a_i, b_j) for rows a_i of A and b_j of B: |A| × |B|.
Eigen::MatrixXd covariance(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, const GaussianProcessHyperparameters& h,
                           KernelType kernel) {
  const Eigen::RowVectorXd inverse_scale = h.length_scales.cwiseInverse().transpose();
  const Eigen::MatrixXd as = a.array().rowwise() * inverse_scale.array();
  const Eigen::MatrixXd bs = b.array().rowwise() * inverse_scale.array();
  Eigen::MatrixXd k(a.rows(), b.rows());
  for (Eigen::Index j = 0; j < b.rows(); ++j)
    for (Eigen::Index i = 0; i < a.rows(); ++i)
      k(i, j) = h.signal_variance * correlation(kernel, (as.row(i) - bs.row(j)).squaredNorm());
  return k;
}

int n_trend_terms(TrendType trend, int d) {
  switch (trend) {
    case TrendType::Constant: return 1;
    case TrendType::DiagonalQuadratic: return 1 + 2 * d;
    case TrendType::FullQuadratic: return 1 + d + d * (d + 1) / 2;
  }
  return 1;
}

Eigen::MatrixXd trend_basis(const Eigen::MatrixXd& x, TrendType trend, const Eigen::VectorXd& center,
                            const Eigen::VectorXd& half_range) {
  const int d = static_cast<int>(x.cols());
  Eigen::MatrixXd h(x.rows(), n_trend_terms(trend, d));
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const Eigen::VectorXd u = (x.row(i).transpose() - center).cwiseQuotient(half_range);
    int c = 0;
    h(i, c++) = 1.0;
    if (trend == TrendType::Constant) continue;
    for (int j = 0; j < d; ++j) h(i, c++) = u(j);
    if (trend == TrendType::DiagonalQuadratic) {
      for (int j = 0; j < d; ++j) h(i, c++) = u(j) * u(j);
    } else {
      for (int j = 0; j < d; ++j)
        for (int k = j; k < d; ++k) h(i, c++) = u(j) * u(k);
    }
  }
  return h;
}

// Training box of the inputs: centre and half range (1 where the range is zero).
void training_box(const Eigen::MatrixXd& x, Eigen::VectorXd& center, Eigen::VectorXd& half_range) {
  const Eigen::VectorXd lo = x.colwise().minCoeff().transpose();
  const Eigen::VectorXd hi = x.colwise().maxCoeff().transpose();
  center = 0.5 * (lo + hi);
  half_range = 0.5 * (hi - lo);
  for (Eigen::Index j = 0; j < half_range.size(); ++j)
    if (!(half_range(j) > 0.0)) half_range(j) = 1.0;
}

// The requested trend if the data support it, else the constant trend.
TrendType supported_trend(const Eigen::MatrixXd& x, TrendType requested, const Eigen::VectorXd& center,
                          const Eigen::VectorXd& half_range) {
  if (requested == TrendType::Constant) return requested;
  const int p = n_trend_terms(requested, static_cast<int>(x.cols()));
  if (x.rows() < p + 2) return TrendType::Constant;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(trend_basis(x, requested, center, half_range));
  qr.setThreshold(1e-10);
  return qr.rank() == p ? requested : TrendType::Constant;
}

struct Conditioned {
  Eigen::MatrixXd cholesky;
  Eigen::MatrixXd whitened_trend;
  Eigen::MatrixXd trend_r;
  Eigen::VectorXd beta;
  Eigen::VectorXd alpha;
  double jitter = 0.0;
  double log_marginal_likelihood = 0.0;
};

// Factorises K (+ jitter) and computes β̂, α and ln p. Returns nothing if K cannot be
// factorised within the jitter cap or the whitened trend is rank deficient.
std::optional<Conditioned> condition(const Eigen::MatrixXd& k, const Eigen::MatrixXd& h, const Eigen::VectorXd& y,
                                     const GaussianProcessOptions& options) {
  const Eigen::Index n = k.rows();
  const double diagonal_mean = k.diagonal().mean();
  // A pivot L_ii² is the variance of point i given the points before it. Far below the
  // first jitter level it is round-off (a numerically duplicated point), not information,
  // so such a factorisation counts as failed even if Eigen reports success.
  const double smallest_pivot = 1e-2 * options.initial_jitter_relative * diagonal_mean;
  const auto factorised = [smallest_pivot](const Eigen::LLT<Eigen::MatrixXd>& llt) {
    return llt.info() == Eigen::Success &&
           (llt.matrixLLT().diagonal().array().square() > smallest_pivot).all();
  };
  Conditioned c;
  Eigen::LLT<Eigen::MatrixXd> llt(k);
  if (!factorised(llt)) {
    bool success = false;
    for (double jitter = options.initial_jitter_relative * diagonal_mean;
         jitter <= options.max_jitter_relative * diagonal_mean * (1.0 + 1e-12); jitter *= 10.0) {
      llt.compute(k + jitter * Eigen::MatrixXd::Identity(n, n));
      if (factorised(llt)) {
        c.jitter = jitter;
        success = true;
        break;
      }
    }
    if (!success) return std::nullopt;
  }
  c.cholesky = llt.matrixL();
  const auto lower = c.cholesky.triangularView<Eigen::Lower>();
  c.whitened_trend = lower.solve(h);
  const Eigen::VectorXd z = lower.solve(y);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(c.whitened_trend);
  const Eigen::Index p = h.cols();
  c.trend_r = qr.matrixQR().topLeftCorner(p, p).triangularView<Eigen::Upper>();
  const Eigen::VectorXd r_diagonal = c.trend_r.diagonal().cwiseAbs();
  if (!(r_diagonal.minCoeff() > 1e-12 * r_diagonal.maxCoeff())) return std::nullopt;
  c.beta = qr.solve(z);
  const Eigen::VectorXd residual = z - c.whitened_trend * c.beta;
  c.alpha = c.cholesky.transpose().triangularView<Eigen::Upper>().solve(residual);
  c.log_marginal_likelihood = -0.5 * residual.squaredNorm() - c.cholesky.diagonal().array().log().sum() -
                              0.5 * static_cast<double>(n) * kLogTwoPi;
  if (!std::isfinite(c.log_marginal_likelihood)) return std::nullopt;
  return c;
}

double noise_variance_of(const GaussianProcessOptions& options, double estimated) {
  switch (options.nugget_mode) {
    case NuggetMode::Off: return 0.0;
    case NuggetMode::Fixed: return options.fixed_noise_variance;
    case NuggetMode::Estimated: return estimated;
  }
  return 0.0;
}

void check_data(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const char* who) {
  if (x.rows() == 0 || x.cols() == 0) throw std::invalid_argument(std::string(who) + ": no training data");
  if (x.rows() != y.size())
    throw std::invalid_argument(std::string(who) + ": " + std::to_string(x.rows()) + " input rows but " +
                                std::to_string(y.size()) + " outputs");
  if (!x.allFinite() || !y.allFinite()) throw std::invalid_argument(std::string(who) + ": non-finite training data");
}

}  // namespace

// ---------------------------------------------------------------------------------------
// GaussianProcess

GaussianProcess::GaussianProcess(Eigen::MatrixXd inputs, Eigen::VectorXd outputs, GaussianProcessOptions options,
                                 GaussianProcessHyperparameters hyperparameters)
    : inputs_(std::move(inputs)),
      outputs_(std::move(outputs)),
      options_(std::move(options)),
      hyperparameters_(std::move(hyperparameters)) {
  check_data(inputs_, outputs_, "GaussianProcess");
  if (hyperparameters_.length_scales.size() != inputs_.cols())
    throw std::invalid_argument("GaussianProcess: " + std::to_string(hyperparameters_.length_scales.size()) +
                                " length scales for " + std::to_string(inputs_.cols()) + " input dimensions");
  if (!(hyperparameters_.length_scales.array() > 0.0).all() || !(hyperparameters_.signal_variance > 0.0) ||
      !(hyperparameters_.noise_variance >= 0.0))
    throw std::invalid_argument("GaussianProcess: length scales and signal variance must be positive, noise variance "
                                "non-negative");
  if (options_.nugget_mode == NuggetMode::Off) hyperparameters_.noise_variance = 0.0;
  if (options_.nugget_mode == NuggetMode::Fixed) hyperparameters_.noise_variance = options_.fixed_noise_variance;
  training_box(inputs_, trend_center_, trend_half_range_);
  trend_used_ = supported_trend(inputs_, options_.trend, trend_center_, trend_half_range_);
  const Eigen::Index n = inputs_.rows();
  const Eigen::MatrixXd k = covariance(inputs_, inputs_, hyperparameters_, options_.kernel) +
                            hyperparameters_.noise_variance * Eigen::MatrixXd::Identity(n, n);
  auto conditioned =
      condition(k, trend_basis(inputs_, trend_used_, trend_center_, trend_half_range_), outputs_, options_);
  if (!conditioned)
    throw std::runtime_error("GaussianProcess: covariance matrix not positive definite even with jitter " +
                             std::to_string(options_.max_jitter_relative) + " x mean diagonal");
  cholesky_ = std::move(conditioned->cholesky);
  whitened_trend_ = std::move(conditioned->whitened_trend);
  trend_r_ = std::move(conditioned->trend_r);
  beta_ = std::move(conditioned->beta);
  alpha_ = std::move(conditioned->alpha);
  jitter_ = conditioned->jitter;
  log_marginal_likelihood_ = conditioned->log_marginal_likelihood;
}

GaussianProcessPrediction GaussianProcess::predict(const Eigen::MatrixXd& points) const {
  if (points.cols() != inputs_.cols())
    throw std::invalid_argument("GaussianProcess::predict: points have " + std::to_string(points.cols()) +
                                " columns, the GP " + std::to_string(inputs_.cols()));
  GaussianProcessPrediction prediction;
  prediction.noise_variance = hyperparameters_.noise_variance;
  prediction.mean.resize(points.rows());
  prediction.latent_variance.resize(points.rows());
  const auto lower = cholesky_.triangularView<Eigen::Lower>();
  for (Eigen::Index start = 0; start < points.rows(); start += kPredictionChunk) {
    const Eigen::Index m = std::min(kPredictionChunk, points.rows() - start);
    const Eigen::MatrixXd block = points.middleRows(start, m);
    const Eigen::MatrixXd k_star = covariance(inputs_, block, hyperparameters_, options_.kernel);  // n × m
    const Eigen::MatrixXd h_star = trend_basis(block, trend_used_, trend_center_, trend_half_range_);
    const Eigen::MatrixXd v = lower.solve(k_star);
    const Eigen::MatrixXd g = h_star.transpose() - whitened_trend_.transpose() * v;  // h* − HᵀK⁻¹k*
    const Eigen::MatrixXd u = trend_r_.triangularView<Eigen::Upper>().transpose().solve(g);  // R⁻ᵀ g
    prediction.mean.segment(start, m) = h_star * beta_ + k_star.transpose() * alpha_;
    const Eigen::VectorXd variance = (hyperparameters_.signal_variance - v.colwise().squaredNorm().array() +
                                      u.colwise().squaredNorm().array())
                                         .matrix()
                                         .transpose();
    prediction.latent_variance.segment(start, m) = variance.cwiseMax(0.0);
  }
  return prediction;
}

GaussianProcessPrediction GaussianProcess::predict(const Eigen::VectorXd& point) const {
  return predict(Eigen::MatrixXd(point.transpose()));
}

GaussianProcess GaussianProcess::with_added_point(const Eigen::VectorXd& x, double y) const {
  Eigen::MatrixXd inputs(inputs_.rows() + 1, inputs_.cols());
  inputs << inputs_, x.transpose();
  Eigen::VectorXd outputs(outputs_.size() + 1);
  outputs << outputs_, y;
  GaussianProcessOptions options = options_;
  options.trend = trend_used_;
  return GaussianProcess(std::move(inputs), std::move(outputs), std::move(options), hyperparameters_);
}

// ---------------------------------------------------------------------------------------
// GaussianProcessRegression

GaussianProcessRegression::GaussianProcessRegression(Eigen::MatrixXd inputs, Eigen::VectorXd outputs,
                                                     GaussianProcessOptions options)
    : inputs_(std::move(inputs)), outputs_(std::move(outputs)), options_(std::move(options)) {
  check_data(inputs_, outputs_, "GaussianProcessRegression");
  if (inputs_.rows() < 2) throw std::invalid_argument("GaussianProcessRegression: at least two points are needed");
  if (options_.nugget_mode == NuggetMode::Fixed && !(options_.fixed_noise_variance >= 0.0))
    throw std::invalid_argument("GaussianProcessRegression: fixed noise variance must be non-negative");
  if (options_.n_restarts < 0) throw std::invalid_argument("GaussianProcessRegression: n_restarts must be >= 0");
  training_box(inputs_, trend_center_, trend_half_range_);
  trend_used_ = supported_trend(inputs_, options_.trend, trend_center_, trend_half_range_);
  trend_basis_ = trend_basis(inputs_, trend_used_, trend_center_, trend_half_range_);
  input_range_ = 2.0 * trend_half_range_;
  const double mean = outputs_.mean();
  const double variance = (outputs_.array() - mean).square().sum() / static_cast<double>(outputs_.size() - 1);
  output_variance_ = std::max(variance, 1e-12 * std::max(1.0, mean * mean));

  const int d = static_cast<int>(inputs_.cols());
  log_lower_.resize(n_hyperparameters());
  log_upper_.resize(n_hyperparameters());
  for (int j = 0; j < d; ++j) {
    log_lower_(j) = std::log(options_.length_scale_min_relative * input_range_(j));
    log_upper_(j) = std::log(options_.length_scale_max_relative * input_range_(j));
  }
  log_lower_(d) = std::log(options_.signal_variance_min_relative * output_variance_);
  log_upper_(d) = std::log(options_.signal_variance_max_relative * output_variance_);
  if (options_.nugget_mode == NuggetMode::Estimated) {
    double floor = std::max(options_.nugget_floor_relative * output_variance_, options_.nugget_floor_absolute);
    if (!(floor > 0.0)) floor = 1e-12 * output_variance_;
    const double ceiling = std::max(options_.nugget_ceiling_relative * output_variance_, 10.0 * floor);
    log_lower_(d + 1) = std::log(floor);
    log_upper_(d + 1) = std::log(ceiling);
  }
  if (!log_lower_.allFinite() || !log_upper_.allFinite() || (log_lower_.array() >= log_upper_.array()).any())
    throw std::invalid_argument("GaussianProcessRegression: empty or non-finite hyperparameter bounds; check the "
                                "relative bounds in GaussianProcessOptions");
}

int GaussianProcessRegression::n_hyperparameters() const {
  return static_cast<int>(inputs_.cols()) + 1 + (options_.nugget_mode == NuggetMode::Estimated ? 1 : 0);
}

Eigen::VectorXd GaussianProcessRegression::to_log_vector(const GaussianProcessHyperparameters& h) const {
  const Eigen::Index d = inputs_.cols();
  Eigen::VectorXd eta(n_hyperparameters());
  eta.head(d) = h.length_scales.array().log().matrix();
  eta(d) = std::log(h.signal_variance);
  if (options_.nugget_mode == NuggetMode::Estimated) eta(d + 1) = std::log(h.noise_variance);
  return eta;
}

GaussianProcessHyperparameters GaussianProcessRegression::from_log_vector(const Eigen::VectorXd& eta) const {
  const Eigen::Index d = inputs_.cols();
  if (eta.size() != n_hyperparameters())
    throw std::invalid_argument("GaussianProcessRegression: hyperparameter vector of wrong size");
  GaussianProcessHyperparameters h;
  h.length_scales = eta.head(d).array().exp().matrix();
  h.signal_variance = std::exp(eta(d));
  h.noise_variance = noise_variance_of(options_, options_.nugget_mode == NuggetMode::Estimated ? std::exp(eta(d + 1))
                                                                                                : 0.0);
  return h;
}

double GaussianProcessRegression::log_marginal_likelihood(const Eigen::VectorXd& eta, Eigen::VectorXd* gradient) const {
  const GaussianProcessHyperparameters h = from_log_vector(eta);
  const Eigen::Index n = inputs_.rows();
  const Eigen::Index d = inputs_.cols();
  const Eigen::MatrixXd signal = covariance(inputs_, inputs_, h, options_.kernel);
  const Eigen::MatrixXd k = signal + h.noise_variance * Eigen::MatrixXd::Identity(n, n);
  const auto conditioned = condition(k, trend_basis_, outputs_, options_);
  if (!conditioned) return -std::numeric_limits<double>::infinity();
  if (gradient == nullptr) return conditioned->log_marginal_likelihood;

  // W = ααᵀ − K⁻¹, then ∂ ln p/∂η_j = ½ Σ_ab W_ab (∂K/∂η_j)_ab.
  const auto lower = conditioned->cholesky.triangularView<Eigen::Lower>();
  Eigen::MatrixXd k_inverse = lower.solve(Eigen::MatrixXd::Identity(n, n));
  k_inverse = conditioned->cholesky.transpose().triangularView<Eigen::Upper>().solve(k_inverse);
  const Eigen::MatrixXd w = conditioned->alpha * conditioned->alpha.transpose() - k_inverse;

  gradient->setZero(n_hyperparameters());
  const Eigen::RowVectorXd inverse_scale = h.length_scales.cwiseInverse().transpose();
  const Eigen::MatrixXd scaled = inputs_.array().rowwise() * inverse_scale.array();
  for (Eigen::Index b = 0; b < n; ++b) {
    for (Eigen::Index a = b + 1; a < n; ++a) {
      const Eigen::RowVectorXd delta = scaled.row(a) - scaled.row(b);
      const double factor = 2.0 * w(a, b) * h.signal_variance * length_scale_factor(options_.kernel, delta.squaredNorm());
      gradient->head(d) += factor * delta.cwiseAbs2().transpose();  // symmetric pair counted twice
    }
  }
  (*gradient)(d) = (w.array() * signal.array()).sum();
  if (options_.nugget_mode == NuggetMode::Estimated) (*gradient)(d + 1) = h.noise_variance * w.trace();
  *gradient *= 0.5;
  return conditioned->log_marginal_likelihood;
}

GaussianProcess GaussianProcessRegression::run() const {
  const int d = static_cast<int>(inputs_.cols());
  const int n_eta = n_hyperparameters();
  std::vector<Eigen::VectorXd> starts;

  Eigen::VectorXd heuristic(n_eta);
  for (int j = 0; j < d; ++j) heuristic(j) = std::log(0.3 * input_range_(j));
  heuristic(d) = std::log(output_variance_);
  if (options_.nugget_mode == NuggetMode::Estimated) heuristic(d + 1) = std::log(1e-2 * output_variance_);
  starts.push_back(heuristic.cwiseMax(log_lower_).cwiseMin(log_upper_));
  if (warm_start_.length_scales.size() == d && (warm_start_.length_scales.array() > 0.0).all() &&
      warm_start_.signal_variance > 0.0) {
    GaussianProcessHyperparameters warm = warm_start_;
    if (options_.nugget_mode == NuggetMode::Estimated)
      warm.noise_variance = std::max(warm.noise_variance, std::exp(log_lower_(d + 1)));  // the log needs τ² > 0
    starts.push_back(to_log_vector(warm).cwiseMax(log_lower_).cwiseMin(log_upper_));
  }
  std::mt19937_64 generator(options_.seed);
  for (int r = 0; r < options_.n_restarts; ++r) {
    Eigen::VectorXd start(n_eta);
    for (int j = 0; j < n_eta; ++j) start(j) = log_lower_(j) + uniform01(generator) * (log_upper_(j) - log_lower_(j));
    starts.push_back(start);
  }

  const ObjectiveFunction objective = [this](const Eigen::VectorXd& eta, Eigen::VectorXd* gradient) {
    const double value = log_marginal_likelihood(eta, gradient);
    if (gradient != nullptr) *gradient = -*gradient;
    return -value;
  };
  const OptimizerResult optimum = BoundedMinimizer(objective, log_lower_, log_upper_).run(starts);
  if (!optimum.found)
    throw std::runtime_error("GaussianProcessRegression: no hyperparameter start gave a factorisable covariance "
                             "matrix");
  GaussianProcessOptions options = options_;
  options.trend = trend_used_;
  GaussianProcess gp(inputs_, outputs_, options, from_log_vector(optimum.x));
  gp.options_.trend = options_.trend;
  gp.fit_report_.n_starts = static_cast<int>(starts.size());
  gp.fit_report_.n_evaluations = optimum.n_evaluations;
  gp.fit_report_.best_start = optimum.best_start;
  gp.fit_report_.optimizer_message = optimum.message;
  return gp;
}

}  // namespace rsw::calibration
