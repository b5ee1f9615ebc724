// Sparse PCE by hybrid LARS with the corrected leave-one-out error; see pce.hpp.
// Sources: Blatman & Sudret (2011) J. Comput. Phys. 230:2345 (hybrid LARS, corrected
// LOO with the factor of Chapelle et al. 2002); Efron et al. (2004) Ann. Statist.
// 32:407 (LARS).
#include "calibration/pce.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rsw::calibration {
namespace {

constexpr double infinity = std::numeric_limits<double>::infinity();

// Leverages this close to 1 make r_i / (1 − h_i) meaningless.
constexpr double max_leverage = 1 - 1e-8;

void compositions(std::size_t n_dimensions, int total, std::size_t position, MultiIndex& current,
                  std::vector<MultiIndex>& out) {
  if (position + 1 == n_dimensions) {
    current[position] = total;
    out.push_back(current);
    return;
  }
  for (int first = total; first >= 0; --first) {
    current[position] = first;
    compositions(n_dimensions, total - first, position + 1, current, out);
  }
}

double sample_variance(const Eigen::VectorXd& y) {
  const double mean = y.mean();
  return (y.array() - mean).square().sum() / static_cast<double>(y.size() - 1);
}

// ε_LOO relative to Var̂[Y]; an exactly constant y has error 0 when it is fitted exactly.
double relative_error(double mean_square, double variance) {
  if (variance > 0) return mean_square / variance;
  return mean_square == 0 ? 0 : infinity;
}

struct SupportScore {
  std::size_t n_terms = 0;
  bool valid = false;
  double loo_error = infinity;
  double corrected_loo_error = infinity;
};

// Scores the supports {0} ∪ order[0..k) for k = 0..order.size() with an updated QR
// factorisation (column 0 of psi is the constant). Stops at a column that is
// numerically dependent on the previous ones (that support and all larger are invalid).
std::vector<SupportScore> score_hybrid_supports(const Eigen::MatrixXd& psi, const Eigen::VectorXd& y,
                                                const std::vector<Eigen::Index>& order) {
  const Eigen::Index n = psi.rows();
  const auto n_max = static_cast<Eigen::Index>(order.size()) + 1;
  const double variance = sample_variance(y);
  Eigen::MatrixXd q(n, n_max);
  Eigen::MatrixXd r_inverse = Eigen::MatrixXd::Zero(n_max, n_max);
  Eigen::VectorXd leverage = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd residual = y;
  double trace = 0;  // tr((ΨᵀΨ)⁻¹) = ‖R⁻¹‖²_F
  std::vector<SupportScore> scores;

  for (Eigen::Index k = 0; k < n_max; ++k) {
    const Eigen::Index column = k == 0 ? 0 : order[static_cast<std::size_t>(k - 1)] + 1;
    Eigen::VectorXd v = psi.col(column);
    const double original_norm = v.norm();
    Eigen::VectorXd r_column = Eigen::VectorXd::Zero(k);
    for (int pass = 0; pass < 2; ++pass) {  // classical Gram–Schmidt, twice
      if (k == 0) break;
      const Eigen::VectorXd projection = q.leftCols(k).transpose() * v;
      v -= q.leftCols(k) * projection;
      r_column += projection;
    }
    const double rho = v.norm();
    if (!(rho > 1e-10 * original_norm)) break;  // dependent column: stop the path here
    q.col(k) = v / rho;
    // R⁻¹ of [[R, r], [0, ρ]] is [[R⁻¹, −R⁻¹ r / ρ], [0, 1/ρ]].
    if (k > 0) {
      r_inverse.col(k).head(k) =
          (r_inverse.topLeftCorner(k, k).triangularView<Eigen::Upper>() * r_column) / -rho;
    }
    r_inverse(k, k) = 1 / rho;
    trace += r_inverse.col(k).head(k + 1).squaredNorm();
    leverage += q.col(k).cwiseAbs2();
    residual -= q.col(k) * q.col(k).dot(residual);

    SupportScore score;
    score.n_terms = static_cast<std::size_t>(k + 1);
    const auto n_terms = static_cast<double>(k + 1);
    if (k + 1 < n && leverage.maxCoeff() < max_leverage) {
      const double mean_square =
          (residual.array() / (1 - leverage.array())).square().sum() / static_cast<double>(n);
      score.valid = true;
      score.loo_error = relative_error(mean_square, variance);
      const double factor = static_cast<double>(n) / (static_cast<double>(n) - n_terms) * (1 + trace);
      score.corrected_loo_error = score.loo_error * factor;
    }
    scores.push_back(score);
  }
  return scores;
}

}  // namespace

PolynomialFamily polynomial_family(StandardSpace space) {
  return space == StandardSpace::standard_normal ? PolynomialFamily::hermite
                                                 : PolynomialFamily::legendre;
}

Eigen::VectorXd orthonormal_polynomials(PolynomialFamily family, int max_degree,
                                        double standard_value) {
  if (max_degree < 0) throw std::invalid_argument("polynomial degree must not be negative");
  Eigen::VectorXd values(max_degree + 1);
  if (family == PolynomialFamily::legendre) {
    // (n + 1) P_{n+1} = (2n + 1) ξ P_n − n P_{n−1}, ψ_n = √(2n + 1) P_n.
    const double xi = 2 * standard_value - 1;
    double previous = 1;
    double current = xi;
    values[0] = 1;
    if (max_degree >= 1) values[1] = std::sqrt(3.0) * xi;
    for (int n = 1; n < max_degree; ++n) {
      const double next = ((2 * n + 1) * xi * current - n * previous) / (n + 1);
      previous = current;
      current = next;
      values[n + 1] = std::sqrt(2.0 * (n + 1) + 1) * current;
    }
  } else {
    // He_{n+1} = z He_n − n He_{n−1}; ψ_n = He_n / √(n!), i.e.
    // ψ_{n+1} = (z ψ_n − √n ψ_{n−1}) / √(n + 1).
    const double z = standard_value;
    values[0] = 1;
    if (max_degree >= 1) values[1] = z;
    for (int n = 1; n < max_degree; ++n) {
      values[n + 1] = (z * values[n] - std::sqrt(static_cast<double>(n)) * values[n - 1]) /
                      std::sqrt(static_cast<double>(n + 1));
    }
  }
  return values;
}

std::vector<MultiIndex> truncated_multi_indices(std::size_t n_dimensions, int degree,
                                                double q_norm) {
  if (n_dimensions == 0) throw std::invalid_argument("multi-indices need at least one dimension");
  if (degree < 0) throw std::invalid_argument("polynomial degree must not be negative");
  if (!(q_norm > 0 && q_norm <= 1)) {
    throw std::invalid_argument("the q-norm of a hyperbolic truncation must lie in (0, 1]");
  }
  std::vector<MultiIndex> result;
  MultiIndex current(n_dimensions, 0);
  for (int total = 0; total <= degree; ++total) {
    std::vector<MultiIndex> level;
    compositions(n_dimensions, total, 0, current, level);
    for (auto& alpha : level) {
      if (q_norm < 1) {
        double sum = 0;
        for (int a : alpha) sum += std::pow(static_cast<double>(a), q_norm);
        if (std::pow(sum, 1 / q_norm) > degree * (1 + 1e-12)) continue;
      }
      result.push_back(std::move(alpha));
    }
  }
  return result;
}

Eigen::MatrixXd design_matrix(const Eigen::MatrixXd& points,
                              const std::vector<PolynomialFamily>& families,
                              const std::vector<MultiIndex>& multi_indices) {
  const auto n_dimensions = static_cast<Eigen::Index>(families.size());
  if (points.cols() != n_dimensions) {
    throw std::invalid_argument("design matrix: points have " + std::to_string(points.cols()) +
                                " columns for " + std::to_string(n_dimensions) + " dimensions");
  }
  std::vector<int> max_degree(families.size(), 0);
  for (const auto& alpha : multi_indices) {
    if (alpha.size() != families.size()) {
      throw std::invalid_argument("design matrix: multi-index of the wrong dimension");
    }
    for (std::size_t i = 0; i < alpha.size(); ++i) max_degree[i] = std::max(max_degree[i], alpha[i]);
  }
  // values[i](point, n) = ψ_n of dimension i at the point.
  std::vector<Eigen::MatrixXd> values(families.size());
  for (std::size_t i = 0; i < families.size(); ++i) {
    values[i].resize(points.rows(), max_degree[i] + 1);
    for (Eigen::Index p = 0; p < points.rows(); ++p) {
      values[i].row(p) = orthonormal_polynomials(families[i], max_degree[i],
                                                 points(p, static_cast<Eigen::Index>(i)))
                             .transpose();
    }
  }
  Eigen::MatrixXd psi(points.rows(), static_cast<Eigen::Index>(multi_indices.size()));
  for (std::size_t j = 0; j < multi_indices.size(); ++j) {
    Eigen::VectorXd column = Eigen::VectorXd::Ones(points.rows());
    for (std::size_t i = 0; i < families.size(); ++i) {
      const int a = multi_indices[j][i];
      if (a > 0) column.array() *= values[i].col(a).array();
    }
    psi.col(static_cast<Eigen::Index>(j)) = column;
  }
  return psi;
}

std::vector<Eigen::Index> lars_order(const Eigen::MatrixXd& regressors, const Eigen::VectorXd& y,
                                     std::size_t max_steps) {
  const Eigen::Index n = regressors.rows();
  const Eigen::Index m = regressors.cols();
  if (y.size() != n) throw std::invalid_argument("LARS: regressors and response differ in length");
  std::vector<Eigen::Index> active;
  if (n < 2 || m == 0 || max_steps == 0) return active;

  const Eigen::VectorXd y_centred = y.array() - y.mean();
  Eigen::MatrixXd x = regressors.rowwise() - regressors.colwise().mean();
  std::vector<bool> available(static_cast<std::size_t>(m), true);
  for (Eigen::Index j = 0; j < m; ++j) {
    const double norm = x.col(j).norm();
    const double scale = regressors.col(j).norm();
    if (!(norm > 1e-12 * scale) || scale == 0) {
      available[static_cast<std::size_t>(j)] = false;  // constant over the points
    } else {
      x.col(j) /= norm;
    }
  }
  const double y_norm = y_centred.norm();
  if (!(y_norm > 0)) return active;

  Eigen::VectorXd correlation = x.transpose() * y_centred;  // c = Xᵀ(y − μ)
  Eigen::MatrixXd cholesky = Eigen::MatrixXd::Zero(0, 0);  // L Lᵀ = X_Aᵀ X_A
  std::vector<bool> is_active(static_cast<std::size_t>(m), false);

  // Adds column j to the active set (Cholesky update); false if it is collinear.
  auto try_add = [&](Eigen::Index j) {
    const auto k = static_cast<Eigen::Index>(active.size());
    Eigen::VectorXd g(k);
    for (Eigen::Index i = 0; i < k; ++i) g[i] = x.col(active[static_cast<std::size_t>(i)]).dot(x.col(j));
    Eigen::VectorXd l = g;
    if (k > 0) cholesky.topLeftCorner(k, k).triangularView<Eigen::Lower>().solveInPlace(l);
    const double pivot = 1 - l.squaredNorm();
    if (!(pivot > 1e-10)) return false;
    Eigen::MatrixXd grown = Eigen::MatrixXd::Zero(k + 1, k + 1);
    grown.topLeftCorner(k, k) = cholesky;
    grown.row(k).head(k) = l.transpose();
    grown(k, k) = std::sqrt(pivot);
    cholesky = std::move(grown);
    active.push_back(j);
    is_active[static_cast<std::size_t>(j)] = true;
    return true;
  };

  // First entering column: the one most correlated with y.
  while (active.empty()) {
    Eigen::Index best = -1;
    for (Eigen::Index j = 0; j < m; ++j) {
      if (available[static_cast<std::size_t>(j)] &&
          (best < 0 || std::abs(correlation[j]) > std::abs(correlation[best]))) {
        best = j;
      }
    }
    if (best < 0 || !(std::abs(correlation[best]) > 1e-12 * y_norm)) return active;
    if (!try_add(best)) available[static_cast<std::size_t>(best)] = false;
  }

  while (active.size() < max_steps) {
    const auto k = static_cast<Eigen::Index>(active.size());
    Eigen::VectorXd signs(k);
    double c_max = 0;
    for (Eigen::Index i = 0; i < k; ++i) {
      const double c = correlation[active[static_cast<std::size_t>(i)]];
      signs[i] = c >= 0 ? 1 : -1;
      c_max = std::max(c_max, std::abs(c));
    }
    if (!(c_max > 1e-12 * y_norm)) break;  // residual already explained
    // Equiangular direction: u = A_A X_A G⁻¹ s, A_A = (sᵀ G⁻¹ s)^(−1/2), G = X_AᵀX_A.
    Eigen::VectorXd g_inverse_s = signs;
    cholesky.triangularView<Eigen::Lower>().solveInPlace(g_inverse_s);
    cholesky.transpose().triangularView<Eigen::Upper>().solveInPlace(g_inverse_s);
    const double a_a = 1 / std::sqrt(signs.dot(g_inverse_s));
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
    for (Eigen::Index i = 0; i < k; ++i) u += x.col(active[static_cast<std::size_t>(i)]) * g_inverse_s[i];
    u *= a_a;
    const Eigen::VectorXd a = x.transpose() * u;

    // Step to the next entering column: min⁺ over inactive j of
    // (C − c_j)/(A_A − a_j) and (C + c_j)/(A_A + a_j).
    double gamma = infinity;
    Eigen::Index entering = -1;
    for (Eigen::Index j = 0; j < m; ++j) {
      if (!available[static_cast<std::size_t>(j)] || is_active[static_cast<std::size_t>(j)]) continue;
      for (const double candidate : {(c_max - correlation[j]) / (a_a - a[j]),
                                     (c_max + correlation[j]) / (a_a + a[j])}) {
        if (candidate > 1e-14 * (c_max / a_a) && candidate < gamma) {
          gamma = candidate;
          entering = j;
        }
      }
    }
    // At γ = C/A_A the active correlations vanish: the least-squares fit on the active
    // set; a later "entry" would only chase round-off.
    if (entering < 0 || gamma >= (c_max / a_a) * (1 - 1e-10)) break;
    correlation -= gamma * a;
    if (!try_add(entering)) available[static_cast<std::size_t>(entering)] = false;
  }
  return active;
}

LeastSquaresLoo least_squares_loo(const Eigen::MatrixXd& psi, const Eigen::VectorXd& y) {
  LeastSquaresLoo fit;
  const Eigen::Index n = psi.rows();
  const Eigen::Index p = psi.cols();
  if (y.size() != n) throw std::invalid_argument("least squares: psi and y differ in length");
  if (n <= p) {
    fit.invalid_reason = "N <= P (" + std::to_string(n) + " points for " + std::to_string(p) + " terms)";
    fit.loo_error = fit.corrected_loo_error = infinity;
    return fit;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(psi);
  if (qr.rank() < p) {
    fit.invalid_reason = "rank deficient (rank " + std::to_string(qr.rank()) + " of " +
                         std::to_string(p) + " terms)";
    fit.loo_error = fit.corrected_loo_error = infinity;
    return fit;
  }
  fit.coefficients = qr.solve(y);
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, p);
  fit.leverages = q.rowwise().squaredNorm();
  const Eigen::VectorXd residual = y - psi * fit.coefficients;
  if (fit.leverages.maxCoeff() >= max_leverage) {
    fit.invalid_reason = "leverage -> 1 (max h_i = " + std::to_string(fit.leverages.maxCoeff()) + ")";
    fit.loo_error = fit.corrected_loo_error = infinity;
    return fit;
  }
  fit.loo_residuals = residual.array() / (1 - fit.leverages.array());
  fit.loo_error = relative_error(fit.loo_residuals.squaredNorm() / static_cast<double>(n),
                                 sample_variance(y));
  // tr((ΨᵀΨ)⁻¹) = ‖R⁻¹‖²_F (the column permutation does not change the trace).
  const Eigen::MatrixXd r = qr.matrixR().topLeftCorner(p, p).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd r_inverse =
      r.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(p, p));
  fit.correction_factor = static_cast<double>(n) / static_cast<double>(n - p) *
                          (1 + r_inverse.squaredNorm());
  fit.corrected_loo_error = fit.loo_error * fit.correction_factor;
  fit.valid = true;
  return fit;
}

double PolynomialChaosResult::mean() const {
  for (std::size_t j = 0; j < multi_indices.size(); ++j) {
    if (std::all_of(multi_indices[j].begin(), multi_indices[j].end(), [](int a) { return a == 0; })) {
      return coefficients[static_cast<Eigen::Index>(j)];
    }
  }
  return 0;
}

double PolynomialChaosResult::variance() const {
  double sum = 0;
  for (std::size_t j = 0; j < multi_indices.size(); ++j) {
    if (std::any_of(multi_indices[j].begin(), multi_indices[j].end(), [](int a) { return a > 0; })) {
      sum += coefficients[static_cast<Eigen::Index>(j)] * coefficients[static_cast<Eigen::Index>(j)];
    }
  }
  return sum;
}

double PolynomialChaosResult::evaluate(const Eigen::VectorXd& standard_point) const {
  return evaluate_points(standard_point.transpose())[0];
}

Eigen::VectorXd PolynomialChaosResult::evaluate_points(const Eigen::MatrixXd& standard_points) const {
  return design_matrix(standard_points, families, multi_indices) * coefficients;
}

SparsePolynomialChaos::SparsePolynomialChaos(Eigen::MatrixXd points, Eigen::VectorXd outputs,
                                             std::vector<StandardSpace> spaces, PceOptions options)
    : points_(std::move(points)), outputs_(std::move(outputs)), options_(options) {
  if (points_.rows() != outputs_.size()) {
    throw std::invalid_argument("PCE: " + std::to_string(points_.rows()) + " points but " +
                                std::to_string(outputs_.size()) + " outputs");
  }
  if (points_.cols() != static_cast<Eigen::Index>(spaces.size()) || spaces.empty()) {
    throw std::invalid_argument("PCE: points have " + std::to_string(points_.cols()) +
                                " columns for " + std::to_string(spaces.size()) + " parameters");
  }
  if (points_.rows() < 2) throw std::invalid_argument("PCE needs at least two points");
  if (!points_.allFinite() || !outputs_.allFinite()) {
    throw std::invalid_argument("PCE: points and outputs must be finite (exclude failed runs)");
  }
  if (options_.min_degree < 1 || options_.max_degree < options_.min_degree) {
    throw std::invalid_argument("PCE: need 1 <= min_degree <= max_degree");
  }
  for (StandardSpace space : spaces) families_.push_back(polynomial_family(space));
}

void SparsePolynomialChaos::run() {
  const Eigen::Index n = points_.rows();
  diagnostics_.clear();
  double best_score = infinity;
  std::vector<MultiIndex> best_support;
  int best_degree = options_.min_degree;
  int n_without_improvement = 0;
  auto effective = [&](double error) { return std::max(error, options_.exact_fit_error); };

  for (int degree = options_.min_degree; degree <= options_.max_degree; ++degree) {
    const std::vector<MultiIndex> candidates =
        truncated_multi_indices(families_.size(), degree, options_.q_norm);
    const Eigen::MatrixXd psi = design_matrix(points_, families_, candidates);
    // Supports larger than N − 1 terms are invalid, so LARS need not go further.
    const auto max_steps = static_cast<std::size_t>(std::max<Eigen::Index>(n - 2, 0));
    const std::vector<Eigen::Index> order =
        lars_order(psi.rightCols(psi.cols() - 1), outputs_, max_steps);
    const std::vector<SupportScore> scores = score_hybrid_supports(psi, outputs_, order);

    DegreeDiagnostics diagnostics;
    diagnostics.degree = degree;
    diagnostics.n_candidates = candidates.size();
    diagnostics.loo_error = diagnostics.corrected_loo_error = infinity;
    const SupportScore* best_here = nullptr;
    for (const auto& score : scores) {
      if (score.valid && (best_here == nullptr ||
                          effective(score.corrected_loo_error) < effective(best_here->corrected_loo_error))) {
        best_here = &score;
      }
    }
    if (best_here != nullptr) {
      diagnostics.valid = true;
      diagnostics.n_terms = best_here->n_terms;
      diagnostics.loo_error = best_here->loo_error;
      diagnostics.corrected_loo_error = best_here->corrected_loo_error;
      if (effective(best_here->corrected_loo_error) < effective(best_score)) {
        best_score = best_here->corrected_loo_error;
        best_degree = degree;
        best_support.assign(1, candidates[0]);
        for (std::size_t k = 0; k + 1 < best_here->n_terms; ++k) {
          best_support.push_back(candidates[static_cast<std::size_t>(order[k] + 1)]);
        }
        n_without_improvement = 0;
      } else {
        ++n_without_improvement;
      }
    } else {
      ++n_without_improvement;
    }
    diagnostics_.push_back(diagnostics);
    if (options_.n_degrees_without_improvement > 0 &&
        n_without_improvement >= options_.n_degrees_without_improvement) {
      break;
    }
  }

  // N ≥ 2 always leaves the constant-only support valid, so a support was found.
  result_ = PolynomialChaosResult();
  result_.families = families_;
  result_.multi_indices = best_support;
  result_.degree = best_degree;
  result_.n_samples = static_cast<std::size_t>(n);
  const LeastSquaresLoo fit =
      least_squares_loo(design_matrix(points_, families_, best_support), outputs_);
  if (fit.coefficients.size() == 0) {
    throw std::runtime_error("PCE: the refit of the selected support failed (" +
                             fit.invalid_reason + ")");
  }
  result_.coefficients = fit.coefficients;
  result_.loo_error = fit.loo_error;
  result_.corrected_loo_error = fit.corrected_loo_error;
  done_ = true;
}

const PolynomialChaosResult& SparsePolynomialChaos::result() const {
  if (!done_) throw std::logic_error("SparsePolynomialChaos::result() called before run()");
  return result_;
}

}  // namespace rsw::calibration
