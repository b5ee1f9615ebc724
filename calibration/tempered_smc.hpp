// Sampling a posterior on the unit cube, and its evidence, when the log-likelihood is
// cheap (an emulator's, emulator_calibration.hpp): sequential Monte Carlo with adaptive
// tempering, then importance sampling from a kernel density of its particles.
//
// Target. The prior is uniform on [0,1]^d (the standardised space of ParameterSpace,
// where u_i is the prior CDF value of θ_i); ℓ(u) is a log-likelihood, −∞ allowed:
//     π(u) = e^{ℓ(u)} 1_box(u) / Z,   Z = ∫_box e^{ℓ(u)} du   (the evidence).
//
// 1. Tempered SMC (Del Moral, Doucet & Jasra 2006, "Sequential Monte Carlo samplers";
//    the temperature rule of Jasra, Stephens, Doucet & Tsagaris 2011; in engineering
//    model updating known as TMCMC, Ching & Chen 2007). N particles from the prior walk
//    through π_β ∝ e^{β ℓ} 1_box, 0 = β_0 < β_1 < … < β_T = 1:
//      - β_{t+1} is the largest β ≤ 1 whose incremental weights w_i = e^{(β − β_t) ℓ_i}
//        keep the Kish effective sample size (Σ w)²/Σ w² at ess_fraction · N (bisection);
//      - the evidence gathers ln Z += ln((1/N) Σ_i w_i) (the particles are equally
//        weighted after each resampling), a consistent estimate of ln Z;
//      - the particles are resampled (systematic) by w, then moved by random-walk
//        Metropolis steps targeting π_{β_{t+1}}: proposal u' = u + c L z, z ~ N(0, I),
//        L Lᵀ the weighted covariance of the particles before resampling, c = 2.38/√d
//        (Roberts, Gelman & Gilks 1997) scaled each stage by exp(a − 0.25), a the last
//        stage's acceptance rate; a proposal outside the box is rejected (prior 0).
//        The number of sweeps is min(max_moves, max(min_moves, ⌈ln(1 − p)/ln(1 − a₁)⌉)),
//        a₁ the acceptance rate of the first sweep: enough for a particle to have moved
//        at least once with probability p (the rule of PyMC's SMC sampler).
//    Result: N equally weighted particles of π and ln Z_SMC.
// 2. Importance sampling (defensive mixture, Hesterberg 1995): M points from
//        q(u) = α 1_box(u) + (1 − α) (1/K) Σ_k N(u; x_k, h² Σ),
//    the x_k K of the particles, Σ their covariance, h Silverman's bandwidth
//    (4/((d + 2) K))^{1/(d+4)} (Silverman 1986, eq. 4.14). The Gaussian kernels reach
//    outside the box; such points have prior density 0 and weight 0, so q needs no
//    truncation constant and the estimate stays unbiased:
//        Ẑ = (1/M) Σ_i e^{ℓ(u_i)} 1_box(u_i) / q(u_i),
//    with the relative standard error √((M/ESS − 1)/(M − 1)) of the normalised weights
//    (Owen 2013, §9.3). The weighted points are the posterior handed to SirPosterior
//    (their ln(prior/q) as pool weights). Where the particles describe π well, the
//    importance weights are nearly even and Ẑ is far more precise than ln Z_SMC; where
//    they do not, the effective sample size says so.
// Deterministic for a fixed seed (std::mt19937_64).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <vector>

namespace rsw::calibration {

// ℓ at the rows of `points` (m × d, inside or outside the box); −∞ where zero.
using BatchLogDensity = std::function<Eigen::VectorXd(const Eigen::MatrixXd& points)>;

struct TemperedSmcOptions {
  int n_particles = 1000;
  double ess_fraction = 0.5;      // of N, kept by each temperature step
  int min_moves = 2;              // Metropolis sweeps per stage
  int max_moves = 15;
  double move_probability = 0.9;  // p of the sweep-count rule
  int max_stages = 500;
  std::uint64_t seed = 1;
};

struct TemperedSmcResult {
  Eigen::MatrixXd particles;       // N × d, equally weighted draws of π
  Eigen::VectorXd log_likelihoods; // ℓ at the particles
  double log_evidence = 0.0;       // ln Z_SMC
  std::vector<double> temperatures;  // β_0 = 0 … β_T = 1
  double mean_acceptance = 0.0;    // over all sweeps
  long n_density_evaluations = 0;  // points at which ℓ was evaluated
};

// Throws std::invalid_argument for bad options, std::runtime_error if every prior draw
// has ℓ = −∞ or the stage cap is reached.
TemperedSmcResult sample_tempered(int dimension, const BatchLogDensity& log_likelihood,
                                  const TemperedSmcOptions& options = {});

struct ImportanceOptions {
  int n_samples = 20000;       // M
  double prior_fraction = 0.1; // α
  int n_kernels = 500;         // K, the particles (evenly spaced in their order) that carry kernels
  std::uint64_t seed = 1;
};

struct ImportanceResult {
  Eigen::MatrixXd points;            // the draws of q inside the box (M_in × d; those outside have weight 0)
  Eigen::VectorXd log_likelihoods;   // ℓ at the points
  Eigen::VectorXd log_prior_over_proposal;  // ln(1/q) at the points
  double log_evidence = 0.0;         // ln Ẑ
  double relative_error = 0.0;       // SE(Ẑ)/Ẑ
  double effective_sample_size = 0.0;  // Kish ESS of the normalised weights
};

// Throws std::invalid_argument for bad options or a particle set of fewer than two points.
ImportanceResult importance_sample(const Eigen::MatrixXd& particles, const BatchLogDensity& log_likelihood,
                                   const ImportanceOptions& options = {});

}  // namespace rsw::calibration
