// Sobol' indices from PCE coefficients (Sudret 2008) and by Monte Carlo (Saltelli et
// al. 2010 first order, Jansen 1999 total order); see sobol.hpp.
#include "calibration/sobol.hpp"

#include "calibration/designs.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace rsw::calibration {

SobolIndices sobol_indices(const PolynomialChaosResult& chaos) {
  const auto d = static_cast<Eigen::Index>(chaos.n_dimensions());
  SobolIndices indices;
  indices.first_order = Eigen::VectorXd::Zero(d);
  indices.total_order = Eigen::VectorXd::Zero(d);
  indices.second_order = Eigen::MatrixXd::Zero(d, d);
  indices.variance = chaos.variance();
  indices.loo_error = chaos.loo_error;
  indices.corrected_loo_error = chaos.corrected_loo_error;

  for (std::size_t j = 0; j < chaos.multi_indices.size(); ++j) {
    const MultiIndex& alpha = chaos.multi_indices[j];
    if (static_cast<Eigen::Index>(alpha.size()) != d) {
      throw std::invalid_argument("Sobol indices: a multi-index has the wrong dimension");
    }
    const double c = chaos.coefficients[static_cast<Eigen::Index>(j)];
    std::vector<Eigen::Index> active;  // the inputs this term depends on
    for (Eigen::Index i = 0; i < d; ++i) {
      if (alpha[static_cast<std::size_t>(i)] > 0) active.push_back(i);
    }
    for (Eigen::Index i : active) indices.total_order[i] += c * c;
    if (active.size() == 1) indices.first_order[active[0]] += c * c;
    if (active.size() == 2) {
      indices.second_order(active[0], active[1]) += c * c;
      indices.second_order(active[1], active[0]) += c * c;
    }
  }
  const double variance = indices.variance;
  const double scale = variance > 0 ? 1 / variance : std::numeric_limits<double>::quiet_NaN();
  indices.first_order *= scale;
  indices.total_order *= scale;
  indices.second_order *= scale;
  return indices;
}

SobolIndices monte_carlo_sobol(const StandardFunction& f, const std::vector<StandardSpace>& spaces,
                               std::size_t n_samples, std::uint64_t seed) {
  if (n_samples < 2 || spaces.empty()) {
    throw std::invalid_argument("Monte Carlo Sobol indices need at least two samples and one "
                                "parameter");
  }
  const auto d = static_cast<Eigen::Index>(spaces.size());
  const auto n = static_cast<Eigen::Index>(n_samples);
  // Columns 0..d−1 form A, d..2d−1 form B.
  Eigen::MatrixXd sample = random_unit_points(n_samples, 2 * spaces.size(), seed);
  for (Eigen::Index i = 0; i < d; ++i) {
    if (spaces[static_cast<std::size_t>(i)] != StandardSpace::standard_normal) continue;
    for (Eigen::Index r = 0; r < n; ++r) {
      sample(r, i) = standard_normal_quantile(sample(r, i));
      sample(r, d + i) = standard_normal_quantile(sample(r, d + i));
    }
  }
  const Eigen::MatrixXd a = sample.leftCols(d);
  const Eigen::MatrixXd b = sample.rightCols(d);

  Eigen::VectorXd f_a(n);
  Eigen::VectorXd f_b(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    f_a[r] = f(a.row(r).transpose());
    f_b[r] = f(b.row(r).transpose());
  }
  const double mean = 0.5 * (f_a.mean() + f_b.mean());
  f_a.array() -= mean;
  f_b.array() -= mean;
  const double variance =
      (f_a.squaredNorm() + f_b.squaredNorm()) / static_cast<double>(2 * n - 1);

  SobolIndices indices;
  indices.first_order.resize(d);
  indices.total_order.resize(d);
  indices.variance = variance;
  const double scale = variance > 0 ? 1 / variance : std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd f_ab(n);
  for (Eigen::Index i = 0; i < d; ++i) {
    for (Eigen::Index r = 0; r < n; ++r) {
      Eigen::VectorXd point = a.row(r).transpose();
      point[i] = b(r, i);
      f_ab[r] = f(point) - mean;
    }
    indices.first_order[i] = f_b.dot(f_ab - f_a) / static_cast<double>(n) * scale;
    indices.total_order[i] = (f_a - f_ab).squaredNorm() / static_cast<double>(2 * n) * scale;
  }
  return indices;
}

}  // namespace rsw::calibration
