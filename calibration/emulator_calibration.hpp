// The emulator route of the calibration (docs/CALIBRATION.md, "Two routes"): emulate
// each feature, sample the posterior the emulators imply, add runs where that posterior
// lives and the emulators are least sure, until both are settled.
//
// Works in the unit cube u ∈ [0,1]^d where the prior is uniform (as SBALC does). With
// the runs so far (successful ones: points U, features F):
//   1. fit the feature emulators (feature_emulator.hpp; optionally each feature warped
//      about its observed mean, warping_width standard errors wide) and form the emulated
//      log-likelihood ln L̃(u), which carries each emulator's variance s_j²(u) and nugget
//      τ_j² beside the measurement variance;
//   2. sample π̃(u) ∝ L̃(u) by tempered SMC and importance sampling (tempered_smc.hpp):
//      the evidence ln Z̃ with its Monte Carlo error, and a weighted pool of points;
//   3. two checks, both required on n_consecutive counted iterations in a row (an
//      iteration counts if it follows the initial design and holds more runs than the
//      previous one):
//      - emulator influence: the posterior of the plug-in likelihood (the emulators'
//        means with s_j² = 0), importance-weighted on the same pool, has its 5 %, 50 % and
//        95 % quantiles of every u_i within influence_tolerance (0.2) posterior standard
//        deviations of the pool's, and an effective sample size above the threshold
//        below: what the emulators do not yet know no longer moves the answer (in the
//        manner of the GP-uncertainty stopping rules of Järvenpää et al. 2019, "Efficient
//        acquisition rules for model-based approximate Bayesian computation");
//      - stable quantiles: the same quantiles moved by at most quantile_tolerance (0.2)
//        posterior standard deviations since the previous iteration: the answer a user
//        reads no longer changes with more runs;
//      and the importance pool's effective sample size at least
//      max(min_pool_ess, min_pool_ess_fraction · pool_size), so that the figures rest on
//      enough points (the same guard as SBALC's). Reported beside them, not a check: the
//      variance ratio r_j = E_π̃[s_j²(u)] / (v_j + τ_j²) of each feature, the emulator's
//      own variance over the posterior against the variance no run removes (the data's
//      mean, v_j, and the model's noise τ_j²);
//   4. otherwise choose batch_size new points among the SMC particles (draws of π̃), each
//      maximising a(u) = Σ_j s_j²(u) / (v_j + τ_j²) of emulators conditioned on the
//      points chosen before it at their own means (kriging believer: the variance shrinks
//      there, the mean stays), run them and go to 1.
// The initial design is a maximin Latin hypercube of n_initial points (default 10 d,
// the rule of Loeppky, Sacks & Welch 2009, "Choosing the sample size of a computer
// experiment"), or the given points. A failed run stays out of the emulators; its point
// is believed into them for step 4 only, so no later batch returns to it.
// Noise pairs (optional, noise_pairs > 0): a rough feature (reproducible numerical
// noise at scales no design resolves) gets a nugget of at least the variance its
// near-duplicate runs show, instead of an interpolating GP that stays uncertain.
// Warnings (with what to do) name: a stop without convergence and the check that
// failed, a feature whose numerical noise τ_j exceeds the data's standard error √(v_j)
// (the posterior then shows the model's noise, and is wider than the data alone allow),
// a pool whose effective sample size is below the threshold, failed runs.
// Deterministic for a fixed seed.
#pragma once

#include "calibration/feature_emulator.hpp"
#include "calibration/gaussian_process.hpp"
#include "calibration/likelihood.hpp"
#include "calibration/tempered_smc.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace rsw::calibration {

// The features at several unit-cube points (e.g. runs in parallel), one entry per point;
// no value for a failed run.
using BatchFeatureFunction =
    std::function<std::vector<std::optional<Eigen::VectorXd>>(const std::vector<Eigen::VectorXd>& thetas_unit)>;

struct EmulatorIteration;

struct EmulatorCalibrationOptions {
  int n_initial = 0;               // 0: 10 d
  int batch_size = 4;
  int max_evaluations = 150;       // all runs, initial design and failures included
  double influence_tolerance = 0.2;  // posterior sd
  double quantile_tolerance = 0.2;   // posterior sd
  int n_consecutive = 2;
  int pool_size = 20000;           // importance samples
  double min_pool_ess = 100.0;
  double min_pool_ess_fraction = 0.01;
  TemperedSmcOptions smc;          // its seed is replaced by one derived from `seed`
  GaussianProcessOptions gp = default_gp();  // per feature
  // Each feature's GP learns asinh((y − Ȳ_j)/w_j), w_j = warping_width · √(v_j)
  // (feature_emulator.hpp, "Warping"); 0: the features themselves.
  double warping_width = 0.0;
  // After the initial design, this many near-duplicates of the best runs so far (by the
  // emulated likelihood), each noise_pair_distance away in a random direction, are run
  // with the first batch; their differences bound each feature's nugget from below
  // (feature_emulator.hpp, NoisePairs). 0: none.
  int noise_pairs = 0;
  double noise_pair_distance = 0.005;  // in the unit cube
  // Focusing (feature_emulator.hpp): a second set of emulators learns the plausible runs
  // (all features within focus_training_cutoff data standard errors) and predicts where
  // the emulators of all runs find a point plausible (within focus_cutoff), once
  // focus_min_runs runs are plausible (0: 2 d + 3, the diagonal quadratic trend's
  // 2 d + 1 terms and two more). false: the emulators of all runs only.
  // Derived inputs of the GPs: log10 of a product of parameters each (their indices),
  // scaled to [0, 1] over the prior box and appended to the unit-cube point; the
  // calibration that knows the priors sets input_map from them (log_product_map in
  // calibrate.hpp). Empty: the unit-cube points.
  struct LogProduct {
    std::string name;
    std::vector<std::size_t> parameters;
  };
  std::vector<LogProduct> log_products;
  InputMap input_map;
  bool focus = false;
  double focus_cutoff = 3.0;
  double focus_training_cutoff = 9.0;
  int focus_min_runs = 0;
  std::uint64_t seed = 1;
  std::optional<Eigen::MatrixXd> initial_design;  // rows in [0,1]^d, replaces the Latin hypercube
  std::function<void(const EmulatorIteration&)> on_iteration;  // progress, after each iteration's checks

  // Matérn 5/2, a diagonal quadratic trend, an estimated nugget, two random restarts.
  static GaussianProcessOptions default_gp();
};

struct EmulatorIteration {
  int n_points = 0;          // successful runs in the emulators
  int n_failed = 0;          // failed runs so far
  int n_evaluations = 0;     // all runs so far
  int n_noise_pairs = 0;     // noise pairs that bound the nuggets
  int n_focused = 0;         // plausible runs in the focused emulators (0: none fitted)
  double focused_weight = 0.0;  // posterior weight of the pool where the focused emulators predict
  double log_evidence = 0.0;            // ln Z̃ (importance sampling)
  double evidence_relative_error = 0.0; // SE(Z̃)/Z̃
  double smc_log_evidence = 0.0;        // ln Z̃ of the tempered SMC, a check
  int n_temperatures = 0;
  double pool_ess = 0.0;
  Eigen::VectorXd variance_ratios;      // r_j per feature
  double max_variance_ratio = 0.0;
  Eigen::VectorXd noise_standard_deviations;  // τ_j per feature, feature units
  Eigen::MatrixXd quantiles;            // d × 3: 5 %, 50 %, 95 % of each u_i
  Eigen::VectorXd posterior_sd;         // of each u_i
  double quantile_shift = 0.0;          // NaN on the first iteration
  double emulator_influence = 0.0;      // largest quantile difference plug-in vs pool, posterior sd
  Eigen::VectorXd parameter_influence;  // the same per parameter (its largest of the three quantiles)
  double influence_standard_error = 0.0;  // of emulator_influence, by resampling the pool (Monte Carlo error)
  double plug_in_ess = 0.0;             // effective sample size of the plug-in weights
  bool influence_settled = false;
  bool quantiles_settled = false;
  bool pool_ess_sufficient = false;
  bool counted = false;
  Eigen::MatrixXd chosen_points;        // rows; empty on the last iteration
  double seconds = 0.0;                 // emulators, sampling and choice
};

struct EmulatorFailedRun {
  Eigen::VectorXd theta_unit;
};

struct EmulatorCalibrationResult {
  bool converged = false;
  std::string stop_reason;
  std::vector<std::string> warnings;
  int n_evaluations = 0;
  Eigen::MatrixXd design;            // successful runs, rows in [0,1]^d
  Eigen::MatrixXd design_features;   // their features
  std::vector<EmulatorFailedRun> failures;
  std::vector<EmulatorIteration> history;
  std::optional<FeatureEmulator> emulator;  // the last one
  // The last iteration's importance pool: points inside the box, ln L̃ there, ln(prior/q).
  Eigen::MatrixXd pool;
  Eigen::VectorXd pool_log_likelihood;
  Eigen::VectorXd pool_log_weight;
  double log_evidence = 0.0;
  double evidence_relative_error = 0.0;
  double pool_ess = 0.0;
  double pool_ess_threshold = 0.0;
  Eigen::MatrixXd particles;         // the last SMC particles, equally weighted draws of π̃
};

class EmulatorCalibration {
 public:
  // `likelihood` gives the observations and their noise (its features in the order the
  // batch function returns them).
  EmulatorCalibration(int dimension, BatchFeatureFunction evaluate, GaussianLikelihood likelihood,
                      EmulatorCalibrationOptions options = {});

  // Throws std::runtime_error if fewer than two runs succeed in the initial design.
  EmulatorCalibrationResult run() const;

 private:
  int dimension_;
  BatchFeatureFunction evaluate_;
  GaussianLikelihood likelihood_;
  EmulatorCalibrationOptions options_;
};

}  // namespace rsw::calibration
