// Bayesian calibration of a forward model against observed features (paper §2.4–2.5,
// docs/CALIBRATION.md): construct → run() → CalibrationResult.
//
//   posterior  f(θ | Y) = L(θ) f(θ) / c,   c = ∫ L(θ) f(θ) dθ   (the evidence)
//   ln L(θ)    = −½ Σ_k r_kᵀ Σ⁻¹ r_k − (N_obs/2) ln det(2πΣ),  r_k = Y^(k) − M(θ)   (likelihood.hpp)
//
// SBALC (Li et al. 2025; sbalc.hpp) learns a GP surrogate of ln L in the unit cube
// u ∈ [0,1]^d, where the prior is uniform: u_i is the prior CDF value of θ_i (for a
// normal prior, θ_i = μ + σ Φ⁻¹(u_i)), so c = E_u[L(θ(u))] for every kind of prior.
// Each batch of points SBALC asks for is mapped u → θ (physical, ParameterSpace) and
// run through the EvaluationFarm (farm.hpp: worker processes in parallel, each result
// appended to an HDF5 file as it finishes, failures recorded with their reason and
// returned to SBALC as failed evaluations). A run that succeeds but leaves a feature of
// the likelihood undefined (NaN: its signals lack the shape the feature needs, e.g. no
// interior resistance peak; features.hpp) has no likelihood value: it is treated as a
// failed run, recorded with the reason "feature R_beta undefined: <condition>", and
// handed to SBALC as a failed evaluation (sbalc.hpp, "Failures"). The posterior is
// then the SIR resample of SBALC's prior pool with weights ∝ exp m(u) (Smith &
// Gelfand 1992; posterior.hpp), reported in physical units: weighted mean and
// standard deviation of θ, equal-tailed credible intervals (the u-quantiles mapped
// through the monotone u → θ_i), the MAP
// (the largest surrogate posterior density in u, i.e. the surrogate's maximum
// likelihood in the prior box for uniform-type priors), the effective sample size and
// its warning.
//
// The evaluation cache (resume). Every farm call writes its own study results file
// <evaluations_folder>/runs_NNNN.h5 (NNNN counts the calls, also across resumed
// sessions), so the folder holds every finished run of every session, including those
// of a session killed mid-batch. With resume, all finished runs in the folder are read
// into a cache keyed by the exact bits of θ. SBALC is deterministic for a fixed seed,
// pool, design and observations, so a resumed calibration asks for the same θ, finds
// them in the cache without running the model, and continues bit for bit where the
// killed one stopped; only θ not in the cache are evaluated. A larger evaluation cap
// than before continues a calibration that did not converge. Files of another model
// set-up (parameters, config keys, units, features, the model fingerprint) are refused
// with the first difference; without resume an existing folder is never reused.
//
// Runs of an earlier study (initial runs). The finished runs of a study results file of
// the same model and parameters (an `rsw study run` of a sensitivity design, say) can
// stand in for SBALC's Hammersley initial design: each run's θ is mapped into the unit
// cube through the priors' CDFs, u_i = F_i(θ_i), and the run enters the first GP as it
// was recorded (a failed run as a failed evaluation), without running the model again.
// If fewer than SbalcOptions::n_initial runs are usable, Hammersley points fill the
// design up to n_initial. Usable: finished, θ inside the calibration's prior box
// (the priors may be narrower than the study's), and not a repeat of an earlier θ;
// the others are skipped with a note. The file must name the same parameters in the
// same order with the same config keys and units, the same model set-up (fingerprint)
// and every feature of the calibration (it may have more).
#pragma once

#include "calibration/emulator_calibration.hpp"
#include "calibration/farm.hpp"
#include "calibration/forward_model.hpp"
#include "calibration/likelihood.hpp"
#include "calibration/posterior.hpp"
#include "calibration/sbalc.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::calibration {

class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// SIGINT/SIGTERM stopped a batch; the finished runs are in the evaluation folder.
class CalibrationInterrupted : public CalibrationError {
 public:
  using CalibrationError::CalibrationError;
};

// A finished run of a study results file, as an initial run of the calibration.
struct InitialRun {
  std::size_t index = 0;        // its point in the study
  Eigen::VectorXd theta;        // physical θ as stored
  bool ok = false;
  Eigen::VectorXd features;     // the calibration's features, SI; NaN unless ok
  std::string failure_reason;
  std::string warnings;
  double wall_time = 0.0;
};

struct InitialRuns {
  std::filesystem::path file;     // the study results file; empty: no initial runs
  std::vector<InitialRun> runs;   // the usable runs, in the file's order
  std::vector<std::string> notes; // what was skipped and why, priors that differ
};

// Reads the usable runs of `results_file` for a calibration of `design` (see "Runs of
// an earlier study" above). Throws CalibrationError naming the file and the first
// difference (parameters, config keys, units, model set-up, a missing feature), or a
// file that is not a study results file.
InitialRuns read_initial_runs(const std::filesystem::path& results_file, const StudyDesign& design);

// Which algorithm learns the posterior (docs/CALIBRATION.md, "Two routes"): SBALC, a
// GP of the log-likelihood (the paper's method, sbalc.hpp), or the emulator route, GPs
// of the features with tempered SMC on the posterior they imply (emulator_calibration.hpp).
enum class CalibrationMethod { sbalc, emulator };

const char* calibration_method_name(CalibrationMethod method);

struct CalibrationOptions {
  CalibrationMethod method = CalibrationMethod::sbalc;
  SbalcOptions sbalc;
  EmulatorCalibrationOptions emulator;
  PosteriorOptions posterior;
  // The evaluation cache, one study results file per farm call (see above).
  std::filesystem::path evaluations_folder;
  // Workers, resume, run time limit, on_result (tests) of every farm call; its
  // `progress` and `distribution` are not used (batches run on local worker processes;
  // one line per batch goes to `progress` below).
  FarmOptions farm;
  std::ostream* progress = nullptr;
  // Runs of an earlier study that make up the initial design (read_initial_runs).
  InitialRuns initial_runs;
  // Called once the evaluation cache has been read and checked, before the first run:
  // a calibration refused at its start (runs of another set-up) has not called it.
  std::function<void()> on_start;
};

// One forward-model run asked for by the method, in the order asked.
struct CalibrationEvaluation {
  std::size_t batch = 0;          // SBALC's evaluator call (0: the initial design)
  Eigen::VectorXd theta_unit;     // u ∈ [0,1]^d
  Eigen::VectorXd theta;          // physical θ, parameter units
  bool ok = false;                // the run succeeded and every likelihood feature is defined
  Eigen::VectorXd features;       // SI; all NaN if the run failed, some NaN if it left features undefined
  double log_likelihood = 0.0;    // ln L(θ); NaN unless ok
  std::string failure_reason;     // empty when ok; "feature X undefined: ..." for undefined features
  std::string warnings;           // what the model warned of in a run that succeeded; empty if nothing
  double wall_time = 0.0;         // [s] of the run
  bool reused = false;            // found in the evaluation cache (resume)
  bool from_study = false;        // an initial run, taken from the study results file
};

struct CalibrationResult {
  std::vector<std::string> parameter_names;
  std::vector<std::string> parameter_units;
  std::vector<std::string> feature_names;

  CalibrationMethod method = CalibrationMethod::sbalc;

  // Evidence and convergence (the last iteration). The emulator route has no GP of the
  // log-likelihood: its bounds are ln(Z̃ (1 ∓ e)), e = SE(Z̃)/Z̃ (the pool's Monte Carlo
  // error, also pool_relative_error), ratio = 2e, noise_ratio = 0, and the numerical
  // noise is per feature (feature_noise_standard_deviations).
  bool converged = false;
  std::string stop_reason;
  double log_evidence = 0.0;        // ln ĉ
  double log_evidence_lower = 0.0;  // ln c_lower
  double log_evidence_upper = 0.0;  // ln c_upper
  double ratio = 0.0;               // (c_upper − c_lower)/ĉ
  double noise_ratio = 0.0;         // the part of the ratio due to the log-likelihood noise
  double noise_standard_deviation = 0.0;  // τ of the GP nugget, log-likelihood units
  double pool_ess = 0.0;                  // ESS of SBALC's pool (its stopping guard, sbalc.hpp)
  double pool_ess_threshold = 0.0;
  double pool_relative_error = 0.0;       // Monte Carlo error SE(ĉ)/ĉ of the pool
  std::vector<SbalcIteration> history;    // SBALC's iterations; chosen points in u
  std::vector<EmulatorIteration> emulator_history;  // the emulator route's iterations
  Eigen::VectorXd feature_noise_standard_deviations;  // emulator route: τ_j of the last emulators, SI
  GaussianProcessHyperparameters hyperparameters;  // of the last GP (length scales in u)
  TrendType trend_used = TrendType::Constant;
  Eigen::MatrixXd design_unit;      // successful points of the GP, u
  Eigen::VectorXd design_log_likelihoods;

  // Runs.
  std::vector<CalibrationEvaluation> evaluations;
  std::size_t n_evaluations = 0;    // runs asked for by SBALC (reused included)
  std::size_t n_reused = 0;         // taken from the evaluation cache
  std::size_t n_from_study = 0;     // initial runs taken from a study results file
  std::size_t n_failed = 0;

  // Posterior, physical units.
  Eigen::MatrixXd pool;             // N_M × d prior pool, θ
  Eigen::VectorXd pool_weights;     // normalised importance weights
  Eigen::VectorXd pool_log_likelihood;  // GP mean m at the pool points
  Eigen::MatrixXd samples;          // n_samples × d resampled draws, θ
  Eigen::VectorXd mean;
  Eigen::VectorXd standard_deviation;
  Eigen::MatrixXd correlation;
  Eigen::VectorXd map_point;
  double map_log_likelihood = 0.0;  // surrogate ln L at the MAP
  double credible_level = 0.0;
  Eigen::VectorXd credible_lower;
  Eigen::VectorXd credible_upper;
  double effective_sample_size = 0.0;
  double ess_threshold = 0.0;
  bool poorly_resolved = false;
  std::string warning;              // empty unless poorly_resolved
  // What the data say of each parameter, in the unit cube where the prior is uniform
  // (variance 1/12): the posterior contraction 1 − Var_post(u_i)/Var_prior(u_i)
  // (Betancourt 2018, "Towards a principled Bayesian workflow") and its reading:
  // "identified" when the posterior sd is at most half the prior's (contraction ≥ 0.75),
  // "not identified" when it is above 0.8 of it (contraction < 0.36): the posterior is
  // close to the prior; "weakly identified" in between.
  Eigen::VectorXd contraction;
  std::vector<std::string> identification;

  // Every warning of the result: SBALC's (sbalc.hpp: failed runs left out of the GP, the
  // stopping guards that failed, why it did not converge), then the posterior's `warning`.
  // Empty for a converged calibration with a well-resolved posterior.
  std::vector<std::string> warnings;

  double elapsed = 0.0;             // [s]
};

// u ∈ [0,1]^d → physical θ through the priors' inverse CDFs (u kept off 0 and 1 by
// 2⁻⁵³ so that normal priors stay finite).
Eigen::VectorXd unit_to_physical(const ParameterSpace& parameters, const Eigen::VectorXd& unit_point);

// The emulators' input map of log products: each unit-cube point with, per product,
// z = (Σ log10 θ_i − Σ log10 a_i) / (Σ log10 b_i − Σ log10 a_i) appended, θ_i = F_i⁻¹(u_i)
// and [a_i, b_i] the prior's bounds (positive). For log10-uniform priors z is linear in u.
// `parameters` must outlive the map.
InputMap log_product_map(const ParameterSpace& parameters,
                         const std::vector<EmulatorCalibrationOptions::LogProduct>& products);

class Calibration {
 public:
  // `design` names the study, its parameters (priors), features and the model
  // fingerprint (its points are not used). The model must outlive run().
  Calibration(const ForwardModel& model, StudyDesign design, GaussianLikelihood likelihood,
              CalibrationOptions options);

  // Throws CalibrationError: an existing evaluation folder without resume, cache files
  // of another set-up, a farm error, an interrupt (SIGINT/SIGTERM; the runs so far are
  // kept for resume), or fewer than two successful runs.
  CalibrationResult run() const;

 private:
  using RunBatch = std::function<std::vector<CalibrationEvaluation>(const std::vector<Eigen::VectorXd>&)>;
  int n_initial() const;
  int max_evaluations() const;
  // Each fills the method's part of the result and the unit-cube pool (result.pool,
  // result.pool_log_likelihood) and returns the SIR posterior of that pool.
  PosteriorResult run_sbalc(const RunBatch& evaluate_runs, const std::optional<Eigen::MatrixXd>& initial_design,
                            CalibrationResult& result) const;
  PosteriorResult run_emulator(const RunBatch& evaluate_runs, const std::optional<Eigen::MatrixXd>& initial_design,
                               CalibrationResult& result) const;
  // Physical pool and samples, moments, MAP, intervals, contraction, posterior warning.
  void summarise_posterior(const PosteriorResult& posterior, CalibrationResult& result) const;

  const ForwardModel& model_;
  StudyDesign design_;
  GaussianLikelihood likelihood_;
  CalibrationOptions options_;
};

}  // namespace rsw::calibration
