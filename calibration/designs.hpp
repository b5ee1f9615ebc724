// Designs of experiments in the unit cube (0, 1)^d (docs/CALIBRATION.md, "Designs"); map them to
// the parameters with ParameterSpace::unit_points_to_standard / to_physical. Points are
// rows of the returned matrices.
//
// - Latin hypercube (McKay, Beckman & Conover 1979): for each dimension j an
//   independent random permutation π_j of 0..n−1, x_ij = (π_j(i) + v_ij)/n with v_ij
//   uniform in (0, 1) (or 1/2 for the centred variant), so every one of the n strata
//   of every dimension holds exactly one point. Optional maximin improvement: random
//   swaps of two points' coordinates in one dimension (which keeps the Latin property),
//   accepted when they lower the Morris–Mitchell criterion φ_p = (Σ_{i<k} d_ik^−p)^{1/p}
//   (Morris & Mitchell 1995; p → ∞ is maximin, the smallest distance d_ik).
//   Randomness: std::mt19937_64 from the seed, with our own integer and real draws
//   (the std distributions differ between standard libraries), so a seed gives the
//   same design everywhere.
// - Hammersley set (Hammersley 1960): x_i1 = (i + 1/2)/n and x_ij = φ_b(i) + b^−K/2
//   for j ≥ 2, φ_b the radical inverse in the (j−1)-th prime base b and K the number of
//   base-b digits of n − 1 (b^K ≥ n). The half-cell shift keeps every coordinate in
//   [b^−K/2, 1 − b^−K/2], strictly inside (0, 1), so inverse CDFs stay finite.
// - Random points: independent uniform coordinates (plain Monte Carlo).
// - One-at-a-time sweeps: every other coordinate at the nominal point, one coordinate
//   stepped through given levels (the paper's §3.1 studies and its Fig. 6 sweep).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace rsw::calibration {

struct LatinHypercubeOptions {
  bool centred = false;             // stratum midpoints instead of random points in them
  std::size_t n_maximin_swaps = 0;  // swap proposals of the maximin improvement (0: none)
  double maximin_exponent = 50;     // p of φ_p
};

// n_points × n_dimensions; throws std::invalid_argument for zero sizes.
Eigen::MatrixXd latin_hypercube(std::size_t n_points, std::size_t n_dimensions,
                                std::uint64_t seed, const LatinHypercubeOptions& options = {});

// Plain Monte Carlo sample: independent uniform coordinates in the open interval
// (0, 1), reproducible from the seed on every standard library.
Eigen::MatrixXd random_unit_points(std::size_t n_points, std::size_t n_dimensions,
                                   std::uint64_t seed);

// Smallest Euclidean distance between two rows (+∞ for fewer than two rows).
double minimum_distance(const Eigen::MatrixXd& points);

// Radical inverse φ_b(i) = Σ_k d_k b^−(k+1) of i = Σ_k d_k b^k.
double radical_inverse(std::uint64_t index, std::uint64_t base);

// The first n primes 2, 3, 5, ...
std::vector<std::uint64_t> first_primes(std::size_t n);

Eigen::MatrixXd hammersley(std::size_t n_points, std::size_t n_dimensions);

struct OneAtATimeDesign {
  Eigen::MatrixXd points;                  // one row per run
  std::vector<std::size_t> swept_dimension;  // per row: the coordinate that was changed
};

// For each dimensions[k], one row per entry of levels[k] (nominal elsewhere). Works in
// any space (unit, standardised or physical) — the levels are taken as given.
// Throws std::invalid_argument for a dimension out of range or mismatched lists.
OneAtATimeDesign one_at_a_time(const Eigen::VectorXd& nominal,
                               const std::vector<std::size_t>& dimensions,
                               const std::vector<Eigen::VectorXd>& levels);

// (k + 1/2)/n, k = 0..n−1: n levels strictly inside (0, 1).
Eigen::VectorXd centred_levels(std::size_t n_levels);

}  // namespace rsw::calibration
