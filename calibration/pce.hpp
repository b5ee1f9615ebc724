// Sparse polynomial chaos expansion (PCE) by hybrid least-angle regression, after
// Blatman & Sudret (2011), with LARS from Efron, Hastie, Johnstone & Tibshirani (2004).
//
//   Y ≈ M̂(s) = Σ_{α ∈ A} c_α Ψ_α(s),   Ψ_α(s) = Π_i ψ^(i)_{α_i}(s_i)
//
// s is the standardised input (ParameterSpace): ψ^(i) are the orthonormal Legendre
// polynomials ψ_n(ξ) = √(2n + 1) P_n(ξ), ξ = 2s − 1, for a parameter uniform on
// [0, 1], and the orthonormal probabilists' Hermite polynomials ψ_n(z) = He_n(z)/√(n!)
// for a standard-normal one, so E[Ψ_α Ψ_β] = δ_αβ, mean = c_0, variance = Σ_{α≠0} c_α².
//
// Algorithm (construct → run() → result(), as in OpenTURNS):
// for each degree p = min_degree..max_degree
//   1. candidates: the multi-indices with (Σ_i α_i^q)^{1/q} ≤ p (q = 1: total degree;
//      q < 1: hyperbolic truncation, fewer interaction terms);
//   2. LARS on the non-constant candidate columns (centred, unit-norm; response centred):
//      move along the equiangular direction of the active columns until an inactive
//      column is as correlated with the residual as the active ones, add it, repeat;
//      the entering order ranks the terms;
//   3. hybrid LARS: for k = 0, 1, ... ordinary least squares on the constant plus the
//      first k LARS terms, each scored by the corrected leave-one-out error
//        ε_LOO  = (1/N) Σ_i (r_i / (1 − h_i))² / Var̂[Y],
//                 r_i the residual, h_i the diagonal of the hat matrix Ψ(ΨᵀΨ)⁻¹Ψᵀ,
//        ε*_LOO = ε_LOO · T,  T = N/(N − P) · (1 + tr((ΨᵀΨ)⁻¹))  (P terms, N points);
//      a support with P ≥ N, a rank-deficient Ψ or a leverage h_i → 1 is marked invalid
//      (scored +∞), never a crash;
// and the best-scoring support over all degrees is refitted and returned. The degree
// loop stops early once ε*_LOO has not improved for n_degrees_without_improvement
// consecutive degrees. Scores below exact_fit_error count as equal (an exact fit up to
// round-off), so among exact fits the sparsest, lowest-degree one is kept.
//
// The supports of step 3 are evaluated with an updated QR factorisation (one column at
// a time, Gram–Schmidt with re-orthogonalisation; h_i, residuals and tr((ΨᵀΨ)⁻¹) =
// ‖R⁻¹‖²_F updated), so a whole path costs about as much as one least-squares fit.
#pragma once

#include "calibration/parameter_space.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace rsw::calibration {

enum class PolynomialFamily { legendre, hermite };

// Legendre for unit-interval parameters, Hermite for standard-normal ones.
PolynomialFamily polynomial_family(StandardSpace space);

// ψ_0..ψ_max_degree at one standardised value (s ∈ [0, 1] for Legendre, z for Hermite).
Eigen::VectorXd orthonormal_polynomials(PolynomialFamily family, int max_degree, double standard_value);

using MultiIndex = std::vector<int>;

// All α ∈ ℕ^n_dimensions with (Σ α_i^q)^{1/q} ≤ degree, q ∈ (0, 1]; ordered by total
// degree, the constant first.
std::vector<MultiIndex> truncated_multi_indices(std::size_t n_dimensions, int degree,
                                                double q_norm = 1.0);

// Ψ_ij = Ψ_{α_j}(point i); points are rows in standardised space.
Eigen::MatrixXd design_matrix(const Eigen::MatrixXd& points,
                              const std::vector<PolynomialFamily>& families,
                              const std::vector<MultiIndex>& multi_indices);

// LARS entering order of the columns of `regressors` (without a constant column) for
// response y, at most max_steps columns. Columns that are constant over the points or
// collinear with the active ones never enter. The path stops when the residual is
// uncorrelated with every remaining column.
std::vector<Eigen::Index> lars_order(const Eigen::MatrixXd& regressors, const Eigen::VectorXd& y,
                                     std::size_t max_steps);

// Ordinary least squares Ψc ≈ y and its leave-one-out error from the hat matrix.
struct LeastSquaresLoo {
  bool valid = false;
  std::string invalid_reason;      // why not valid: "N <= P", "rank deficient", "leverage -> 1"
  Eigen::VectorXd coefficients;    // when the fit exists (also for leverage → 1)
  Eigen::VectorXd loo_residuals;   // r_i / (1 − h_i), when valid
  Eigen::VectorXd leverages;       // h_i
  double loo_error = 0;            // ε_LOO (relative to the sample variance of y)
  double correction_factor = 0;    // T
  double corrected_loo_error = 0;  // ε*_LOO = T ε_LOO
};
LeastSquaresLoo least_squares_loo(const Eigen::MatrixXd& psi, const Eigen::VectorXd& y);

struct PceOptions {
  int min_degree = 1;
  int max_degree = 5;                           // degree cap p_max
  double q_norm = 1.0;                          // 1: total degree; < 1: hyperbolic
  int n_degrees_without_improvement = 2;        // early stop of the degree loop; 0: never
  double exact_fit_error = 1e-20;               // ε*_LOO below this count as equal
};

// A fitted expansion; can also be built by hand from coefficients.
struct PolynomialChaosResult {
  std::vector<PolynomialFamily> families;  // per input dimension
  std::vector<MultiIndex> multi_indices;   // the selected terms
  Eigen::VectorXd coefficients;            // c_α, same order
  int degree = 0;                          // candidate degree the terms were selected from
  std::size_t n_samples = 0;               // N of the fit
  double loo_error = 0;                    // ε_LOO of the refit
  double corrected_loo_error = 0;          // ε*_LOO of the refit

  std::size_t n_dimensions() const { return families.size(); }
  double mean() const;      // c_0 (0 if the constant is not among the terms)
  double variance() const;  // Σ_{α≠0} c_α²
  double evaluate(const Eigen::VectorXd& standard_point) const;
  Eigen::VectorXd evaluate_points(const Eigen::MatrixXd& standard_points) const;  // rows
};

// Per candidate degree: the best support found and its score.
struct DegreeDiagnostics {
  int degree = 0;
  std::size_t n_candidates = 0;  // size of the truncated basis, constant included
  std::size_t n_terms = 0;       // terms of the best support, constant included
  bool valid = false;            // some support of this degree was valid
  double loo_error = 0;
  double corrected_loo_error = 0;
};

class SparsePolynomialChaos {
 public:
  // points: N × d in standardised space (rows), outputs: N values, spaces: per column.
  // Throws std::invalid_argument for mismatched sizes, N < 2 or non-finite data.
  SparsePolynomialChaos(Eigen::MatrixXd points, Eigen::VectorXd outputs,
                        std::vector<StandardSpace> spaces, PceOptions options = {});

  void run();
  // Throws std::logic_error before run().
  const PolynomialChaosResult& result() const;
  const std::vector<DegreeDiagnostics>& degree_diagnostics() const { return diagnostics_; }

 private:
  Eigen::MatrixXd points_;
  Eigen::VectorXd outputs_;
  std::vector<PolynomialFamily> families_;
  PceOptions options_;
  bool done_ = false;
  PolynomialChaosResult result_;
  std::vector<DegreeDiagnostics> diagnostics_;
};

}  // namespace rsw::calibration
