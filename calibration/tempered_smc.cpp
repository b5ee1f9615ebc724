// Tempered SMC and kernel-density importance sampling on the unit cube; equations and
// sources in tempered_smc.hpp.
#include "calibration/tempered_smc.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace rsw::calibration {

namespace {

constexpr double minus_infinity = -std::numeric_limits<double>::infinity();

double uniform01(std::mt19937_64& generator) { return static_cast<double>(generator() >> 11) * 0x1.0p-53; }

bool inside_box(const Eigen::Ref<const Eigen::RowVectorXd>& point) {
  return (point.array() >= 0.0).all() && (point.array() <= 1.0).all();
}

// ℓ at the rows inside the box, −∞ at the others; `count` gathers the evaluations.
Eigen::VectorXd evaluate_in_box(const BatchLogDensity& log_likelihood, const Eigen::MatrixXd& points, long& count) {
  std::vector<Eigen::Index> inside;
  for (Eigen::Index r = 0; r < points.rows(); ++r)
    if (inside_box(points.row(r))) inside.push_back(r);
  Eigen::VectorXd values = Eigen::VectorXd::Constant(points.rows(), minus_infinity);
  if (inside.empty()) return values;
  Eigen::MatrixXd chosen(static_cast<Eigen::Index>(inside.size()), points.cols());
  for (std::size_t k = 0; k < inside.size(); ++k) chosen.row(static_cast<Eigen::Index>(k)) = points.row(inside[k]);
  const Eigen::VectorXd computed = log_likelihood(chosen);
  if (computed.size() != chosen.rows())
    throw std::runtime_error("log density returned " + std::to_string(computed.size()) + " values for " +
                             std::to_string(chosen.rows()) + " points");
  for (std::size_t k = 0; k < inside.size(); ++k) {
    const double value = computed(static_cast<Eigen::Index>(k));
    values(inside[k]) = std::isnan(value) || value == std::numeric_limits<double>::infinity() ? minus_infinity : value;
  }
  count += chosen.rows();
  return values;
}

// Weights e^{step (ℓ_i − max ℓ)} (0 where ℓ = −∞).
Eigen::VectorXd tempering_weights(const Eigen::VectorXd& log_likelihoods, double step, double max_log_likelihood) {
  Eigen::VectorXd weights(log_likelihoods.size());
  for (Eigen::Index i = 0; i < weights.size(); ++i) {
    weights(i) = std::isfinite(log_likelihoods(i)) ? std::exp(step * (log_likelihoods(i) - max_log_likelihood)) : 0.0;
  }
  return weights;
}

double kish_ess(const Eigen::VectorXd& weights) {
  const double sum = weights.sum(), squares = weights.squaredNorm();
  return squares > 0.0 ? sum * sum / squares : 0.0;
}

// Lower Cholesky factor of the sample covariance of the rows, with a small ridge so that
// a collapsed coordinate still gives a proper proposal.
Eigen::MatrixXd covariance_factor(const Eigen::MatrixXd& points, double scale) {
  const Eigen::RowVectorXd mean = points.colwise().mean();
  const Eigen::MatrixXd centred = points.rowwise() - mean;
  Eigen::MatrixXd covariance = centred.transpose() * centred / static_cast<double>(std::max<Eigen::Index>(points.rows() - 1, 1));
  const double ridge = 1e-10 + 1e-8 * covariance.trace() / static_cast<double>(covariance.rows());
  covariance.diagonal().array() += ridge;
  Eigen::LLT<Eigen::MatrixXd> factor(scale * scale * covariance);
  if (factor.info() != Eigen::Success) throw std::runtime_error("particle covariance is not positive definite");
  return factor.matrixL();
}

Eigen::MatrixXd standard_normals(std::mt19937_64& generator, Eigen::Index rows, Eigen::Index cols) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd z(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index c = 0; c < cols; ++c) z(r, c) = normal(generator);
  return z;
}

// Systematic resampling: N indices drawn with probabilities weights/Σ weights.
std::vector<Eigen::Index> systematic_resample(const Eigen::VectorXd& weights, std::mt19937_64& generator) {
  const Eigen::Index n = weights.size();
  const double total = weights.sum();
  std::vector<Eigen::Index> indices(static_cast<std::size_t>(n));
  const double offset = uniform01(generator);
  double cumulative = weights(0) / total;
  Eigen::Index source = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double position = (static_cast<double>(k) + offset) / static_cast<double>(n);
    while (cumulative < position && source < n - 1) cumulative += weights(++source) / total;
    indices[static_cast<std::size_t>(k)] = source;
  }
  return indices;
}

// The next temperature: the largest β ≤ 1 keeping the incremental ESS at `target`.
double next_temperature(const Eigen::VectorXd& log_likelihoods, double beta, double target, double max_log_likelihood) {
  if (kish_ess(tempering_weights(log_likelihoods, 1.0 - beta, max_log_likelihood)) >= target) return 1.0;
  double low = beta, high = 1.0;
  for (int k = 0; k < 60; ++k) {
    const double middle = 0.5 * (low + high);
    if (kish_ess(tempering_weights(log_likelihoods, middle - beta, max_log_likelihood)) >= target) {
      low = middle;
    } else {
      high = middle;
    }
  }
  return low > beta ? low : high;
}

struct MoveStats {
  long accepted = 0;
  long proposed = 0;
};

// One random-walk Metropolis sweep of every particle targeting e^{β ℓ} 1_box.
double metropolis_sweep(Eigen::MatrixXd& particles, Eigen::VectorXd& log_likelihoods, double beta,
                        const Eigen::MatrixXd& step_factor, const BatchLogDensity& log_likelihood,
                        std::mt19937_64& generator, long& n_evaluations) {
  const Eigen::Index n = particles.rows(), d = particles.cols();
  const Eigen::MatrixXd proposals = particles + standard_normals(generator, n, d) * step_factor.transpose();
  const Eigen::VectorXd proposed = evaluate_in_box(log_likelihood, proposals, n_evaluations);
  long accepted = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double u = uniform01(generator);
    if (!std::isfinite(proposed(i))) continue;
    if (std::log(std::max(u, 1e-300)) < beta * (proposed(i) - log_likelihoods(i))) {
      particles.row(i) = proposals.row(i);
      log_likelihoods(i) = proposed(i);
      ++accepted;
    }
  }
  return static_cast<double>(accepted) / static_cast<double>(n);
}

double log_sum_exp_vector(const Eigen::VectorXd& values) {
  const double top = values.maxCoeff();
  if (!std::isfinite(top)) return top;
  return top + std::log((values.array() - top).exp().sum());
}

}  // namespace

TemperedSmcResult sample_tempered(int dimension, const BatchLogDensity& log_likelihood, const TemperedSmcOptions& options) {
  if (dimension < 1) throw std::invalid_argument("sample_tempered: dimension must be >= 1");
  if (options.n_particles < 10) throw std::invalid_argument("sample_tempered: at least 10 particles are needed");
  if (!(options.ess_fraction > 0.0 && options.ess_fraction < 1.0))
    throw std::invalid_argument("sample_tempered: ess_fraction must be in (0, 1)");
  if (options.min_moves < 1 || options.max_moves < options.min_moves)
    throw std::invalid_argument("sample_tempered: need 1 <= min_moves <= max_moves");
  if (!(options.move_probability > 0.0 && options.move_probability < 1.0))
    throw std::invalid_argument("sample_tempered: move_probability must be in (0, 1)");

  std::mt19937_64 generator(options.seed);
  const Eigen::Index n = options.n_particles, d = dimension;
  TemperedSmcResult result;
  Eigen::MatrixXd particles(n, d);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < d; ++j) particles(i, j) = uniform01(generator);
  Eigen::VectorXd values = evaluate_in_box(log_likelihood, particles, result.n_density_evaluations);

  double beta = 0.0, log_evidence = 0.0, scale = 2.38 / std::sqrt(static_cast<double>(d));
  double acceptance_sum = 0.0;
  long n_sweeps = 0;
  result.temperatures.push_back(0.0);
  while (beta < 1.0) {
    if (static_cast<int>(result.temperatures.size()) > options.max_stages)
      throw std::runtime_error("sample_tempered: no convergence of the temperature within " +
                               std::to_string(options.max_stages) + " stages");
    const auto n_finite = static_cast<double>((values.array() > minus_infinity).count());
    if (n_finite == 0.0) throw std::runtime_error("sample_tempered: every particle has zero likelihood");
    const double top = values.maxCoeff();
    const double next = next_temperature(values, beta, options.ess_fraction * n_finite, top);
    const Eigen::VectorXd weights = tempering_weights(values, next - beta, top);
    log_evidence += (next - beta) * top + std::log(weights.sum() / static_cast<double>(n));

    const std::vector<Eigen::Index> picked = systematic_resample(weights, generator);
    Eigen::MatrixXd resampled(n, d);
    Eigen::VectorXd resampled_values(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      resampled.row(i) = particles.row(picked[static_cast<std::size_t>(i)]);
      resampled_values(i) = values(picked[static_cast<std::size_t>(i)]);
    }
    particles = std::move(resampled);
    values = std::move(resampled_values);
    beta = next;
    result.temperatures.push_back(beta);

    const Eigen::MatrixXd step = covariance_factor(particles, scale);
    const double first = metropolis_sweep(particles, values, beta, step, log_likelihood, generator,
                                          result.n_density_evaluations);
    int sweeps = options.max_moves;
    if (first >= 1.0) {
      sweeps = options.min_moves;
    } else if (first > 0.0) {
      const double needed = std::ceil(std::log(1.0 - options.move_probability) / std::log(1.0 - first));
      sweeps = static_cast<int>(std::clamp(needed, static_cast<double>(options.min_moves), static_cast<double>(options.max_moves)));
    }
    double stage_acceptance = first;
    for (int s = 1; s < sweeps; ++s) {
      stage_acceptance += metropolis_sweep(particles, values, beta, step, log_likelihood, generator,
                                           result.n_density_evaluations);
    }
    acceptance_sum += stage_acceptance;
    n_sweeps += sweeps;
    const double mean_acceptance = stage_acceptance / sweeps;
    scale = std::clamp(scale * std::exp(mean_acceptance - 0.25), 0.01, 3.0);
  }
  result.particles = std::move(particles);
  result.log_likelihoods = std::move(values);
  result.log_evidence = log_evidence;
  result.mean_acceptance = n_sweeps > 0 ? acceptance_sum / static_cast<double>(n_sweeps) : 0.0;
  return result;
}

ImportanceResult importance_sample(const Eigen::MatrixXd& particles, const BatchLogDensity& log_likelihood,
                                   const ImportanceOptions& options) {
  if (particles.rows() < 2 || particles.cols() < 1)
    throw std::invalid_argument("importance_sample: at least two particles are needed");
  if (options.n_samples < 2) throw std::invalid_argument("importance_sample: at least two samples are needed");
  if (!(options.prior_fraction > 0.0 && options.prior_fraction < 1.0))
    throw std::invalid_argument("importance_sample: prior_fraction must be in (0, 1)");
  if (options.n_kernels < 1) throw std::invalid_argument("importance_sample: n_kernels must be >= 1");

  const Eigen::Index d = particles.cols(), m = options.n_samples;
  const Eigen::Index k = std::min<Eigen::Index>(options.n_kernels, particles.rows());
  Eigen::MatrixXd centres(k, d);
  for (Eigen::Index c = 0; c < k; ++c) centres.row(c) = particles.row(c * particles.rows() / k);
  const double bandwidth =
      std::pow(4.0 / ((static_cast<double>(d) + 2.0) * static_cast<double>(k)), 1.0 / (static_cast<double>(d) + 4.0));
  const Eigen::MatrixXd factor = covariance_factor(particles, bandwidth);  // L, L Lᵀ = h² Σ

  std::mt19937_64 generator(options.seed);
  Eigen::MatrixXd points(m, d);
  for (Eigen::Index i = 0; i < m; ++i) {
    if (uniform01(generator) < options.prior_fraction) {
      for (Eigen::Index j = 0; j < d; ++j) points(i, j) = uniform01(generator);
    } else {
      const auto c = static_cast<Eigen::Index>(generator() % static_cast<std::uint64_t>(k));
      points.row(i) = centres.row(c) + (factor * standard_normals(generator, d, 1)).transpose();
    }
  }

  // ln of the kernel mixture at every point, in blocks (whitened squared distances).
  const auto lower = factor.triangularView<Eigen::Lower>();
  const Eigen::MatrixXd white_centres = lower.solve(centres.transpose());  // d × k
  const Eigen::RowVectorXd centre_norms = white_centres.colwise().squaredNorm();
  const double log_det = factor.diagonal().array().log().sum();
  const double log_kernel_constant = -0.5 * static_cast<double>(d) * std::log(2.0 * M_PI) - log_det -
                                     std::log(static_cast<double>(k));
  Eigen::VectorXd log_mixture(m);
  constexpr Eigen::Index block = 1000;
  for (Eigen::Index start = 0; start < m; start += block) {
    const Eigen::Index rows = std::min(block, m - start);
    const Eigen::MatrixXd white = lower.solve(points.middleRows(start, rows).transpose());  // d × rows
    Eigen::MatrixXd distances = -2.0 * white.transpose() * white_centres;              // rows × k
    distances.colwise() += white.colwise().squaredNorm().transpose();
    distances.rowwise() += centre_norms;
    for (Eigen::Index r = 0; r < rows; ++r) {
      const Eigen::VectorXd exponents = -0.5 * distances.row(r).transpose().cwiseMax(0.0);
      log_mixture(start + r) = log_kernel_constant + log_sum_exp_vector(exponents);
    }
  }

  long n_evaluations = 0;
  const Eigen::VectorXd values = evaluate_in_box(log_likelihood, points, n_evaluations);
  const double log_alpha = std::log(options.prior_fraction), log_rest = std::log1p(-options.prior_fraction);
  std::vector<Eigen::Index> inside;
  Eigen::VectorXd log_weights = Eigen::VectorXd::Constant(m, minus_infinity);
  Eigen::VectorXd log_ratio = Eigen::VectorXd::Constant(m, minus_infinity);
  for (Eigen::Index i = 0; i < m; ++i) {
    if (!inside_box(points.row(i))) continue;
    inside.push_back(i);
    const double a = log_alpha, b = log_rest + log_mixture(i);
    const double log_q = std::max(a, b) + std::log1p(std::exp(-std::abs(a - b)));
    log_ratio(i) = -log_q;
    log_weights(i) = values(i) - log_q;
  }
  ImportanceResult result;
  const double log_total = log_sum_exp_vector(log_weights);
  if (!std::isfinite(log_total)) throw std::runtime_error("importance_sample: every draw has zero weight");
  result.log_evidence = log_total - std::log(static_cast<double>(m));
  const Eigen::VectorXd normalised = (log_weights.array() - log_total).exp().matrix();
  result.effective_sample_size = 1.0 / normalised.squaredNorm();
  result.relative_error = std::sqrt(std::max(0.0, (static_cast<double>(m) / result.effective_sample_size - 1.0) /
                                                      (static_cast<double>(m) - 1.0)));
  const auto n_inside = static_cast<Eigen::Index>(inside.size());
  result.points.resize(n_inside, d);
  result.log_likelihoods.resize(n_inside);
  result.log_prior_over_proposal.resize(n_inside);
  for (Eigen::Index r = 0; r < n_inside; ++r) {
    const Eigen::Index i = inside[static_cast<std::size_t>(r)];
    result.points.row(r) = points.row(i);
    result.log_likelihoods(r) = values(i);
    result.log_prior_over_proposal(r) = log_ratio(i);
  }
  return result;
}

}  // namespace rsw::calibration
