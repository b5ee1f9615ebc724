// SBALC: Streamlined Bayesian Active Learning Cubature (Li et al. 2025), with a nugget
// for deterministic numerical noise (paper §2.5, §3.3; docs/CALIBRATION.md, "SBALC",
// "The nugget").
//
// Works in the standardised parameter space where the prior is uniform on [0, 1]^d
// (callers map θ_std to physical values through the inverse prior CDFs). The evidence
//     c = ∫ L(θ) f(θ) dθ = E_prior[exp ℒ(θ)]
// is estimated from a GP surrogate of the log-likelihood ℒ (gaussian_process.hpp)
// with latent mean m(θ) and latent standard deviation s(θ) after n evaluations:
//     ĉ          = E_prior[exp(m)]              (paper eq. 9)
//     c_upper,GP = E_prior[exp(m + b s)],   c_lower,GP = E_prior[exp(m − b s)],   b = 1,
// (the paper's bounds; the reported c_upper, c_lower also hold the pool's Monte Carlo
// error, below), each a Monte Carlo mean over a seeded pool of N_M prior samples
// (default 2·10⁴), evaluated as log-sum-exp minus ln N_M, so nothing overflows however
// large |ℒ| is.
// The next evaluation maximises over the pool the learning function (paper eq. 10)
//     LF = s² (e^{m + b s} − e^{m − b s}),
//     ln LF = 2 ln s + m + b s + ln(1 − e^{−2 b s})          (s > 0; LF = 0 at s = 0),
// skipping pool points already chosen (evaluated or failed).
//
// Monte Carlo error of the pool (our extension). Each pool average is an importance-
// sampling estimate with a standard error of its own. For an average X = (1/N_M) Σ a_i,
// a_i = r_i e^{v_i}, with normalised weights w_i = a_i / Σ_k a_k,
//     SE(X)² = Σ_i (a_i − X)² / (N_M (N_M − 1)) = X² (N_M Σ_i w_i² − 1)/(N_M − 1),
// so SE(X)/X = √((N_M/ESS − 1)/(N_M − 1)) ≈ √(1/ESS − 1/N_M), with the Kish effective
// sample size ESS = 1/Σ w_i² of those weights (Owen 2013, "Monte Carlo theory, methods
// and examples", §9.3). The GP bounds and the pool's error add in quadrature:
//     c_upper = ĉ + √((c_upper,GP − ĉ)² + (b SE(c_upper,GP))²),
//     c_lower = max(0, ĉ − √((ĉ − c_lower,GP)² + (b SE(c_lower,GP))²)),
// where c_upper,GP = E_pool[e^{m + b s}] and c_lower,GP = E_pool[e^{m − b s}] are the
// paper's bounds (eq. 9 with ±b s) and the SEs are theirs. (c_lower = 0 is reported as
// ln c_lower = −∞.) The ratio below is formed from these bounds, so a pool too small to
// resolve the posterior keeps them apart however well the GP has learnt ℒ; the relative
// error of ĉ itself, SE(ĉ)/ĉ, is reported as pool_relative_error. With ESS = 400 the
// pool alone contributes about 2b/√ESS = 0.1 to the ratio.
//
// Stopping rule. Iterations stop with converged = true when, on n_consecutive (2)
// counted iterations in a row,
//     ratio = (c_upper − c_lower)/ĉ < tolerance_used       (tolerance 0.1; see "Nugget")
// and the guards below hold. An iteration is counted only if it comes after the initial
// design and its GP holds more data than the previous iteration's (it added a run; an
// iteration whose every new run failed and was excluded neither counts nor resets the
// count). So the GP of the initial design alone never contributes, and convergence
// always rests on at least n_consecutive GPs that include points chosen by SBALC.
// Guards (each failing one refuses the iteration, resets the count and is recorded in
// SbalcIteration::refusal; at the end they become the result's warnings):
//   - Pool effective sample size: ESS of the weights w_i ∝ r_i e^{m_i} at least
//     max(min_pool_ess, min_pool_ess_fraction · N_M) (defaults 100 and 1 %, the
//     posterior's own threshold, posterior.hpp). Below it the evidence and the posterior
//     rest on a handful of pool points, whose Monte Carlo error is itself poorly
//     estimated (measured: a narrow likelihood in the prior's tail, ESS 1.7, ln ĉ 16
//     units off while the ratio was below the tolerance).
//   - Noise within the peak: with a nugget, τ must not exceed the peak spread S of the
//     evaluated log-likelihoods near their maximum. The evaluations "near the maximum"
//     are those inside the band ℒ_i ≥ ℒ_max − h_d, h_d = ½ χ²_d(0.99): for a Gaussian
//     posterior this is the log-density drop that bounds its 99 % highest-posterior-
//     density region (Wilson–Hilferty approximation of the χ² quantile, within 1 % for
//     every d). With at least d + 1 evaluations in the band (a simplex, the fewest that
//     locate a peak in d dimensions), S = ℒ_max − min_band ℒ_i, the spread they
//     actually show; with fewer, the data do not resolve the peak's shape and S = h_d,
//     the height of the band. Why this choice: the evidence is carried by the top h_d
//     units of ℒ; a noise τ > S says that everything the evaluations show of the peak
//     is within the noise, so the GP may treat the peak as noise and lower it (measured:
//     τ = 6.4 against h_1 = 3.3 on the tail problem, ln ĉ ≈ −55 against −12.96 and a
//     posterior equal to the prior). Then the noise allowance is not applied
//     (tolerance_used = tolerance) and the iteration is refused. A noise τ ≤ tolerance/2
//     passes whatever S is (S = 0 for a flat log-likelihood): a latent peak lowered by
//     about τ changes ĉ by a factor of about e^τ, within the tolerance.
//   - Noise allowance capped: tolerance_used ≤ max_noise_tolerance_factor · tolerance
//     (default 3). A noise-limited ratio above the cap is refused with the value needed,
//     so a result never claims convergence at many times the requested tolerance
//     without the caller having asked for that tolerance.
// When the evaluation cap is reached first (or no pool point is left), converged =
// false. A result that is not converged always carries at least one warning (the reason
// and what to do); SbalcResult::warnings holds them, in the order: failed runs left out
// of the GP (failed_runs = exclude, converged or not), the guards that failed in the last
// iteration, then the stop.
// The initial design is n_0 = 5 Hammersley points kept off the faces of the box
// (calibration/designs.hpp).
//
// Nugget extension (docs/CALIBRATION.md, "The nugget"). The FE log-likelihood carries reproducible
// discretisation noise; an interpolating GP chases it, its s never shrinks between
// points and SBALC does not converge (paper §3.3). With gp.nugget_mode = Estimated (or
// Fixed) the GP separates a smooth latent ℒ from noise of variance τ² (Gramacy & Lee
// 2012). Then:
//   - ĉ, the bounds, LF and the ratio use the latent m and s only; τ² never enters them,
//     so the noise does not keep the bounds apart. ĉ is the evidence of the smooth
//     latent log-likelihood.
//   - The tolerance accounts for the noise. The latent variance splits as
//         s² = s₀² + s_τ²,
//     where s₀² is the latent variance the same GP (same hyperparameters) would have
//     with noise-free observations at the same design points (the gaps in the design),
//     and s_τ² = s² − s₀² ≥ 0 is what the noise in the observations adds (only
//     averaging over more nearby points reduces it, like τ·√(df/n)). With
//         ratio_τ = (E[e^{m + b s_τ}] − E[e^{m − b s_τ}]) / ĉ,
//     the noise-induced spread of the bounds, the stopping test is
//         ratio < tolerance_used = min(√(tolerance² + ratio_τ²), F · tolerance),
//     F = max_noise_tolerance_factor, unless τ exceeds the peak spread S (guards above;
//     then tolerance_used = tolerance).
//     For small s the ratio is ≈ 2b E_post[s], and s² = s₀² + s_τ², so this asks the
//     part of the spread due to gaps in the design, ≈ √(ratio² − ratio_τ²), to be below
//     the tolerance, while the part caused by the noise is accepted and reported
//     (ratio_τ per iteration, so the noise-limited accuracy is visible). Without a nugget, s_τ = 0 and the test is the
//     paper's. (Requiring ratio < tolerance alone would demand n ∝ τ²/tolerance²
//     evaluations once the noise dominates, which for FE noise means no convergence.)
//     Option noise_aware_tolerance = false restores the plain test (so does an
//     iteration whose noise-free matrix cannot be factorised within the jitter cap).
//   - Diagnostics report the noise standard deviation τ = √τ² in log-likelihood units.
//
// Batches: with batch_size = q > 1 each iteration picks q points by the kriging
// believer (Ginsbourger et al. 2010): after choosing a point, the GP is conditioned on
// its own mean there (hyperparameters kept), which leaves m unchanged and shrinks s
// nearby, and the next point maximises LF of that GP. The q points go to the batch
// evaluator together, so a caller can run them in parallel.
//
// Failures: an evaluation that returns no value (or a non-finite one, or throws) is
// recorded with its point and reason; its pool point is never proposed again, and it
// counts towards the cap. What the GP does with it is `failed_runs`:
//   - impute_minimum (default): the failed point enters the GP — for the evidence, the
//     bounds, the ratio and the learning function — with the lowest log-likelihood of
//     the successful evaluations so far (our choice). A simulator fails where it cannot
//     represent the experiment (e.g. a weld whose electrode melts); the observed data
//     are then among the least likely outcomes, and a region of failures is learnt
//     like a region of poor fit: its mass leaves ĉ and LF stops proposing it. Without
//     this, a failing region next to the posterior keeps the GP mean extrapolated high
//     there and SBALC spends its budget on failures (measured: 88 of 100 runs on the
//     three-parameter twin of validation/twin).
//   - exclude: the failed point stays out of the GP. For choosing points (only) the GP
//     is conditioned on each failed point at its own mean (kriging believer), which
//     leaves m unchanged and removes s near failures; ĉ, the bounds and the ratio use
//     the successful evaluations only, so a failing region with posterior mass keeps
//     the ratio open.
// Adaptive pool (option adaptive_pool, our extension). The prior pool resolves a
// posterior only if many of its N_M points fall inside it; a likelihood from several
// replicates can be orders of magnitude narrower than the prior (measured: the
// three-parameter weld twin, effective sample size ≈ 1 of 20 000). When the pool's
// effective sample size under the weights w_i ∝ e^{m_i} r_i falls below
// adaptive_pool_ess_fraction · N_M, the pool is redrawn from a defensive mixture
//     q(θ) = α + (1 − α) φ(θ; μ, Σ)/Z   on [0,1]^d   (Hesterberg 1995),
// α = adaptive_pool_prior_fraction, μ and Σ the weighted mean and covariance of the old
// pool (Σ inflated fourfold and widened by the old pool's spacing N_M^{−1/d} so that a
// single dominant point still gives a proper proposal), Z = P(N(μ, Σ) ∈ [0,1]^d)
// estimated by the rejection sampling that draws it. Each point carries the
// importance ratio r = f/q = 1/q (bounded by 1/α), and every pool average above
// becomes a weighted one: ĉ = (1/N_M) Σ r_i e^{m_i}, the bounds likewise, and ln LF
// gains ln r_i (a point's share of the evidence uncertainty). The pool zooms in over
// the iterations as the GP learns the posterior. Off, the pool is the paper's.
//
// Log-likelihood floor (option log_likelihood_range = Δ, our extension, after the lower
// threshold of Acerbi's VBMC, 2018): the GP sees max(ℒ_i, ℒ_max − Δ), ℒ_max the largest
// evaluated ℒ. A log-likelihood from several replicates spans thousands of units over
// the prior but only the top few tens matter for the evidence (a region below
// ℒ_max − Δ contributes at most e^{−Δ} of the prior mass times e^{ℒ_max}, against
// e^{ℒ_max} times the posterior's share of the prior); a stationary GP asked to fit the
// whole range chases the cliffs and estimates a large noise. Δ = 50 by default; 0
// disables the floor.
//
// Defaults. SbalcOptions{} is the paper's algorithm (prior pool, interpolating GP, one
// point per iteration) with the guards above; it suits cheap, noise-free log-likelihoods
// evaluated one at a time (the analytic problems of the tests). `rsw calibrate` uses
// simulator_sbalc_options() instead (the defaults of a study's calibration.sbalc keys,
// calibration_study.hpp), which differ on purpose in three places, for a finite-element
// forward model: adaptive_pool = true (a likelihood from several replicates is much
// narrower than the prior), gp.nugget_mode = Estimated (the FE log-likelihood carries
// discretisation noise) and batch_size = 4 (runs go to parallel worker processes).
// Everything else, including the guards and their thresholds, is the same.
//
// Deterministic for a fixed seed: pool, GP restarts and tie breaks derive from it.
#pragma once

#include "calibration/gaussian_process.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace rsw::calibration {

// ℒ(θ_std), or no value for a failed evaluation.
using LogLikelihoodFunction = std::function<std::optional<double>(const Eigen::VectorXd& theta_std)>;
// ℒ at several points (e.g. run in parallel by the caller), one entry per point in order.
using BatchLogLikelihoodFunction =
    std::function<std::vector<std::optional<double>>(const std::vector<Eigen::VectorXd>& thetas_std)>;

// ln Σ_i exp(v_i), stable for any magnitude; −∞ for an empty vector or all −∞.
double log_sum_exp(const Eigen::VectorXd& values);

enum class FailedRunPolicy { impute_minimum, exclude };  // see "Failures" above

struct SbalcOptions {
  int n_initial = 5;              // n_0 Hammersley points (ignored with initial_design)
  int pool_size = 20000;          // N_M prior samples
  std::uint64_t seed = 1;
  double bound_width = 1.0;       // b
  double tolerance = 0.1;         // on (c_upper − c_lower)/ĉ
  int n_consecutive = 2;
  int max_evaluations = 100;      // cap on all evaluations, initial design and failures included
  int batch_size = 1;             // q points per iteration (kriging believer)
  bool noise_aware_tolerance = true;  // tolerance_used = √(tolerance² + ratio_τ²) (with a nugget)
  double max_noise_tolerance_factor = 3.0;  // tolerance_used ≤ this · tolerance
  double min_pool_ess = 100.0;              // convergence needs pool ESS ≥ max(min_pool_ess,
  double min_pool_ess_fraction = 0.01;      //   min_pool_ess_fraction · pool_size)
  FailedRunPolicy failed_runs = FailedRunPolicy::impute_minimum;
  double log_likelihood_range = 50.0;         // Δ of the log-likelihood floor (0: none)
  bool adaptive_pool = false;                 // see "Adaptive pool" above
  double adaptive_pool_ess_fraction = 0.02;   // redraw when ESS < this · pool_size
  double adaptive_pool_prior_fraction = 0.1;  // α, the prior share of the proposal
  GaussianProcessOptions gp;      // kernel, trend, nugget; its seed is replaced by one derived from `seed`
  std::optional<Eigen::MatrixXd> initial_design;  // rows in [0,1]^d, replaces the Hammersley design
};

struct SbalcIteration {
  int n_points = 0;        // successful evaluations in the GP
  int n_imputed = 0;       // failed evaluations in the GP at the imputed value (impute_minimum)
  double pool_ess = 0.0;   // effective sample size of the pool's posterior weights (after any redraw)
  bool pool_redrawn = false;  // the adaptive pool was redrawn in this iteration
  double imputed_value = 0.0;  // that value: the lowest successful ℒ so far (not below the floor)
  int n_evaluations = 0;   // all evaluations so far
  double log_evidence = 0.0;        // ln ĉ
  double log_evidence_upper = 0.0;  // ln c_upper
  double log_evidence_lower = 0.0;  // ln c_lower
  double ratio = 0.0;               // (c_upper − c_lower)/ĉ, the pool's Monte Carlo error included
  double gp_ratio = 0.0;            // (c_upper,GP − c_lower,GP)/ĉ, the paper's ratio (GP only)
  double noise_ratio = 0.0;         // ratio_τ, the spread due to the noise (0 without nugget)
  double tolerance_used = 0.0;      // min(√(tolerance² + ratio_τ²), cap), or tolerance
  double pool_relative_error = 0.0;  // SE(ĉ)/ĉ, the pool's Monte Carlo error
  double peak_spread = 0.0;          // S, spread of the evaluated ℒ near their maximum
  bool counted = false;              // counted towards n_consecutive (ratio below, guards held)
  bool pool_ess_too_low = false;     // guard: pool_ess below the threshold
  bool noise_exceeds_peak_spread = false;  // guard: τ > peak_spread (no noise allowance)
  bool noise_allowance_capped = false;     // guard: ratio within √(tol² + ratio_τ²) but above the cap
  std::string refusal;               // the guards that failed in this iteration, in words; empty if none
  GaussianProcessHyperparameters hyperparameters;
  double noise_standard_deviation = 0.0;  // τ, log-likelihood units
  double jitter = 0.0;
  TrendType trend_used = TrendType::Constant;
  Eigen::MatrixXd chosen_points;     // rows; empty on the last iteration
  double log_learning_function = 0.0;  // ln LF of the first chosen point
};

struct SbalcFailedEvaluation {
  Eigen::VectorXd theta;
  std::string reason;
};

struct SbalcResult {
  bool converged = false;
  std::string stop_reason;
  double log_evidence = 0.0;  // ln ĉ of the last GP
  double log_evidence_upper = 0.0;
  double log_evidence_lower = 0.0;
  double ratio = 0.0;
  double noise_ratio = 0.0;               // ratio_τ of the last GP
  double noise_standard_deviation = 0.0;  // τ of the last GP, log-likelihood units
  double pool_ess = 0.0;                  // ESS of the last pool's posterior weights
  double pool_ess_threshold = 0.0;        // max(min_pool_ess, min_pool_ess_fraction · pool_size)
  double pool_relative_error = 0.0;       // SE(ĉ)/ĉ of the last pool
  double peak_spread = 0.0;               // S of the last iteration
  std::vector<std::string> warnings;      // what is wrong and what to do; at least one unless converged
  int n_evaluations = 0;                  // all, failed included
  Eigen::MatrixXd design;                 // successful points, rows in [0,1]^d
  Eigen::VectorXd log_likelihoods;        // ℒ at design rows
  std::vector<SbalcFailedEvaluation> failures;
  std::vector<SbalcIteration> history;
  std::optional<GaussianProcess> surrogate;  // last GP (absent if fewer than two successes)
  Eigen::MatrixXd pool;                      // N_M × d samples (prior, or the adaptive proposal)
  Eigen::VectorXd pool_log_weight;           // ln r = ln(prior/proposal) per pool point (0: prior pool)
  Eigen::VectorXd pool_mean;                 // m at the pool points (last GP)
  Eigen::VectorXd pool_latent_sd;            // s at the pool points (last GP)

  double evidence() const;  // exp(log_evidence); may under/overflow, prefer the log
};

// The defaults of `rsw calibrate` (see "Defaults" above): SbalcOptions{} with
// adaptive_pool = true, gp.nugget_mode = Estimated and batch_size = 4.
SbalcOptions simulator_sbalc_options();

// h_d = ½ χ²_d(0.99), the log-density drop bounding the 99 % highest-density region of
// a d-dimensional Gaussian (Wilson–Hilferty); the band of the peak-spread guard.
double peak_band_height(int dimension);

class Sbalc {
 public:
  Sbalc(int dimension, LogLikelihoodFunction log_likelihood, SbalcOptions options = {});
  Sbalc(int dimension, BatchLogLikelihoodFunction batch_log_likelihood, SbalcOptions options = {});

  SbalcResult run() const;

 private:
  int dimension_;
  BatchLogLikelihoodFunction evaluate_;
  SbalcOptions options_;
};

}  // namespace rsw::calibration
