// Variance-based (Sobol') sensitivity indices (Sobol 2001; paper eqs. 5–6):
//   S_i   = Var[E(Y | θ_i)] / Var(Y)            first order
//   S_T,i = 1 − Var[E(Y | θ_∼i)] / Var(Y)       total order
//   S_ij  = Var[E(Y | θ_i, θ_j)]/Var(Y) − S_i − S_j   second order (pure interaction)
//
// From a polynomial chaos expansion (Sudret 2008, Reliab. Eng. Syst. Saf. 93:964): with
// orthonormal Ψ_α, Var(Y) = D = Σ_{α≠0} c_α² and
//   S_i   = Σ_{α: α_i>0, α_k=0 (k≠i)} c_α² / D
//   S_T,i = Σ_{α: α_i>0} c_α² / D
//   S_ij  = Σ_{α: α_i>0, α_j>0, α_k=0 (k≠i,j)} c_α² / D
// at no extra model cost. Report them beside the PCE's LOO error, so a poor surrogate
// is visible (docs/CALIBRATION.md, "Sensitivity analysis").
//
// Independent Monte Carlo check for cheap functions: two independent N × d samples A,
// B of the standardised inputs and A_B^(i) (A with column i from B), N(d + 2)
// evaluations; with f centred by the mean of f(A) and f(B),
//   V_i  = (1/N)  Σ_j f(B)_j (f(A_B^(i))_j − f(A)_j)    (Saltelli et al. 2010)
//   V_Ti = (1/2N) Σ_j (f(A)_j − f(A_B^(i))_j)²          (Jansen 1999)
// S_i = V_i / V, S_T,i = V_Ti / V, V the sample variance of f over A and B.
// Sampling errors decay like N^(−1/2).
//
// A model whose output does not vary (D = 0) has undefined indices: they are NaN.
#pragma once

#include "calibration/parameter_space.hpp"
#include "calibration/pce.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace rsw::calibration {

struct SobolIndices {
  Eigen::VectorXd first_order;   // S_i
  Eigen::VectorXd total_order;   // S_T,i
  Eigen::MatrixXd second_order;  // S_ij, symmetric, zero diagonal (empty for Monte Carlo)
  double variance = 0;           // Var(Y)
  // The surrogate's ε_LOO and ε*_LOO, to be reported beside the indices (NaN for the
  // Monte Carlo estimator, which has no surrogate).
  double loo_error = std::numeric_limits<double>::quiet_NaN();
  double corrected_loo_error = std::numeric_limits<double>::quiet_NaN();
};

SobolIndices sobol_indices(const PolynomialChaosResult& chaos);

// f of one point in standardised space (s ∈ (0, 1) or z, per `spaces`).
using StandardFunction = std::function<double(const Eigen::VectorXd&)>;

// Saltelli/Jansen estimates with n_samples rows in A and B (n_samples·(d + 2) calls
// of f, in a fixed order, single-threaded). Throws std::invalid_argument for
// n_samples < 2 or no parameters.
SobolIndices monte_carlo_sobol(const StandardFunction& f, const std::vector<StandardSpace>& spaces,
                               std::size_t n_samples, std::uint64_t seed);

}  // namespace rsw::calibration
