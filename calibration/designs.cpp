// Latin hypercube (with Morris–Mitchell maximin swaps), Hammersley and one-at-a-time
// designs; see designs.hpp.
#include "calibration/designs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace rsw::calibration {
namespace {

// Uniform in the open interval (0, 1): the 53 high bits of one draw, offset by half a
// unit in the last place.
double open_unit(std::mt19937_64& rng) {
  return (static_cast<double>(rng() >> 11) + 0.5) * 0x1p-53;
}

// Uniform integer in [0, bound), Lemire's multiply-and-reject method (no modulo bias).
std::uint64_t uniform_index(std::mt19937_64& rng, std::uint64_t bound) {
  unsigned __int128 product = static_cast<unsigned __int128>(rng()) * bound;
  auto low = static_cast<std::uint64_t>(product);
  if (low < bound) {
    const std::uint64_t threshold = (0 - bound) % bound;
    while (low < threshold) {
      product = static_cast<unsigned __int128>(rng()) * bound;
      low = static_cast<std::uint64_t>(product);
    }
  }
  return static_cast<std::uint64_t>(product >> 64);
}

// log Σ exp(terms), stable.
double log_sum_exp(const std::vector<double>& terms) {
  const double largest = *std::max_element(terms.begin(), terms.end());
  if (!std::isfinite(largest)) return largest;
  double sum = 0;
  for (double term : terms) sum += std::exp(term - largest);
  return largest + std::log(sum);
}

// Swaps proposed at random, accepted when φ_p decreases. Only the distances of the two
// swapped rows change, so the comparison involves 2(n − 2) terms, each d^−p handled
// through its logarithm −(p/2)·log d² (nearly coincident points would overflow d^−p).
void improve_maximin(Eigen::MatrixXd& points, std::mt19937_64& rng, std::size_t n_swaps,
                     double exponent) {
  const Eigen::Index n = points.rows();
  const Eigen::Index d = points.cols();
  if (n < 3) return;
  std::vector<double> old_terms;
  std::vector<double> new_terms;
  auto log_term = [&](double squared_distance) {
    return -0.5 * exponent * std::log(std::max(squared_distance, 1e-300));
  };
  for (std::size_t swap = 0; swap < n_swaps; ++swap) {
    const auto column = static_cast<Eigen::Index>(uniform_index(rng, static_cast<std::uint64_t>(d)));
    const auto a = static_cast<Eigen::Index>(uniform_index(rng, static_cast<std::uint64_t>(n)));
    auto b = static_cast<Eigen::Index>(uniform_index(rng, static_cast<std::uint64_t>(n - 1)));
    if (b >= a) ++b;
    Eigen::RowVectorXd row_a = points.row(a);
    Eigen::RowVectorXd row_b = points.row(b);
    std::swap(row_a[column], row_b[column]);
    old_terms.clear();
    new_terms.clear();
    for (Eigen::Index k = 0; k < n; ++k) {
      if (k == a || k == b) continue;
      old_terms.push_back(log_term((points.row(a) - points.row(k)).squaredNorm()));
      old_terms.push_back(log_term((points.row(b) - points.row(k)).squaredNorm()));
      new_terms.push_back(log_term((row_a - points.row(k)).squaredNorm()));
      new_terms.push_back(log_term((row_b - points.row(k)).squaredNorm()));
    }
    if (log_sum_exp(new_terms) < log_sum_exp(old_terms)) {
      points.row(a) = row_a;
      points.row(b) = row_b;
    }
  }
}

}  // namespace

Eigen::MatrixXd latin_hypercube(std::size_t n_points, std::size_t n_dimensions,
                                std::uint64_t seed, const LatinHypercubeOptions& options) {
  if (n_points == 0 || n_dimensions == 0) {
    throw std::invalid_argument("a Latin hypercube needs at least one point and one dimension");
  }
  if (!(options.maximin_exponent > 0)) {
    throw std::invalid_argument("the maximin exponent p must be positive");
  }
  std::mt19937_64 rng(seed);
  const auto n = static_cast<Eigen::Index>(n_points);
  const auto d = static_cast<Eigen::Index>(n_dimensions);
  Eigen::MatrixXd points(n, d);
  std::vector<Eigen::Index> permutation(n_points);
  for (Eigen::Index j = 0; j < d; ++j) {
    for (Eigen::Index i = 0; i < n; ++i) permutation[static_cast<std::size_t>(i)] = i;
    for (std::size_t i = n_points - 1; i > 0; --i) {  // Fisher–Yates
      std::swap(permutation[i], permutation[uniform_index(rng, i + 1)]);
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      const double offset = options.centred ? 0.5 : open_unit(rng);
      points(i, j) = (static_cast<double>(permutation[static_cast<std::size_t>(i)]) + offset) /
                     static_cast<double>(n);
    }
  }
  improve_maximin(points, rng, options.n_maximin_swaps, options.maximin_exponent);
  return points;
}

Eigen::MatrixXd random_unit_points(std::size_t n_points, std::size_t n_dimensions,
                                   std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Eigen::MatrixXd points(static_cast<Eigen::Index>(n_points), static_cast<Eigen::Index>(n_dimensions));
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    for (Eigen::Index j = 0; j < points.cols(); ++j) points(i, j) = open_unit(rng);
  }
  return points;
}

double minimum_distance(const Eigen::MatrixXd& points) {
  double smallest = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    for (Eigen::Index k = i + 1; k < points.rows(); ++k) {
      smallest = std::min(smallest, (points.row(i) - points.row(k)).squaredNorm());
    }
  }
  return std::sqrt(smallest);
}

double radical_inverse(std::uint64_t index, std::uint64_t base) {
  if (base < 2) throw std::invalid_argument("radical inverse needs a base of at least 2");
  double result = 0;
  double digit_value = 1.0 / static_cast<double>(base);
  while (index > 0) {
    result += static_cast<double>(index % base) * digit_value;
    index /= base;
    digit_value /= static_cast<double>(base);
  }
  return result;
}

std::vector<std::uint64_t> first_primes(std::size_t n) {
  std::vector<std::uint64_t> primes;
  for (std::uint64_t candidate = 2; primes.size() < n; ++candidate) {
    const bool is_prime = std::all_of(primes.begin(), primes.end(), [&](std::uint64_t p) {
      return p * p > candidate || candidate % p != 0;
    });
    if (is_prime) primes.push_back(candidate);
  }
  return primes;
}

Eigen::MatrixXd hammersley(std::size_t n_points, std::size_t n_dimensions) {
  if (n_points == 0 || n_dimensions == 0) {
    throw std::invalid_argument("a Hammersley set needs at least one point and one dimension");
  }
  const auto n = static_cast<Eigen::Index>(n_points);
  Eigen::MatrixXd points(n, static_cast<Eigen::Index>(n_dimensions));
  for (Eigen::Index i = 0; i < n; ++i) {
    points(i, 0) = (static_cast<double>(i) + 0.5) / static_cast<double>(n);
  }
  const std::vector<std::uint64_t> bases = first_primes(n_dimensions - 1);
  for (std::size_t j = 1; j < n_dimensions; ++j) {
    const std::uint64_t base = bases[j - 1];
    // b^−K with b^K ≥ n: the grid spacing of the radical inverses of 0..n−1.
    double spacing = 1;
    for (std::uint64_t power = 1; power < n_points; power *= base) spacing /= static_cast<double>(base);
    for (Eigen::Index i = 0; i < n; ++i) {
      points(i, static_cast<Eigen::Index>(j)) =
          radical_inverse(static_cast<std::uint64_t>(i), base) + 0.5 * spacing;
    }
  }
  return points;
}

OneAtATimeDesign one_at_a_time(const Eigen::VectorXd& nominal,
                               const std::vector<std::size_t>& dimensions,
                               const std::vector<Eigen::VectorXd>& levels) {
  if (dimensions.size() != levels.size()) {
    throw std::invalid_argument("one-at-a-time design: " + std::to_string(dimensions.size()) +
                                " swept dimensions but " + std::to_string(levels.size()) +
                                " level lists");
  }
  Eigen::Index n_rows = 0;
  for (std::size_t k = 0; k < dimensions.size(); ++k) {
    if (dimensions[k] >= static_cast<std::size_t>(nominal.size())) {
      throw std::invalid_argument("one-at-a-time design: dimension " +
                                  std::to_string(dimensions[k]) + " of a " +
                                  std::to_string(nominal.size()) + "-dimensional point");
    }
    n_rows += levels[k].size();
  }
  OneAtATimeDesign design;
  design.points.resize(n_rows, nominal.size());
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < dimensions.size(); ++k) {
    for (Eigen::Index level = 0; level < levels[k].size(); ++level, ++row) {
      design.points.row(row) = nominal.transpose();
      design.points(row, static_cast<Eigen::Index>(dimensions[k])) = levels[k][level];
      design.swept_dimension.push_back(dimensions[k]);
    }
  }
  return design;
}

Eigen::VectorXd centred_levels(std::size_t n_levels) {
  Eigen::VectorXd levels(static_cast<Eigen::Index>(n_levels));
  for (Eigen::Index k = 0; k < levels.size(); ++k) {
    levels[k] = (static_cast<double>(k) + 0.5) / static_cast<double>(n_levels);
  }
  return levels;
}

}  // namespace rsw::calibration
