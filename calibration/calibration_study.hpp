// The `calibration:` section of a study file (`rsw calibrate STUDY`, paper §2.4–2.5,
// docs/CALIBRATION.md): what was measured, how noisy it is, and how SBALC and the
// posterior are run. The parameters, priors, features and forward model are the
// study's own (study.hpp).
//
//   calibration:
//     observations:            one of
//       features_file: obs.csv             a CSV of feature vectors, one replicate per
//                                          row, header = feature names ("R_gamma [uohm]")
//       signal_files: [{file: weld_1.csv}] measured signal files (signal.hpp), whose
//                                          features come from the one extractor
//                                          (features.hpp) the simulator's signals go through
//     noise:                   Σ = diag(σ_j² + δ_j²) of the Gaussian likelihood (likelihood.hpp)
//       kind: standard_deviations | relative | replicate_scatter
//       standard_deviations: [{feature: R_gamma, value: 2 uohm}]   σ_j, every feature
//       fraction: 0.02                     relative: σ_j = fraction · |mean of Y_j|
//                                          replicate_scatter: σ_j = sample sd (N_obs ≥ 2)
//       discrepancy: [{feature: R_gamma, standard_deviation: 3 uohm}]
//                                          δ_j, a fixed model-discrepancy spread
//                                          (Kennedy & O'Hagan 2001), 0 where not given
//     method: sbalc | emulator               which route learns the posterior (calibrate.hpp)
//     emulator: {initial_points, batch_size, max_evaluations, influence_tolerance,
//                quantile_tolerance, pool_size, particles, seed, trend}   (emulator_calibration.hpp)
//     sbalc: {pool_size, initial_points, batch_size, max_evaluations, tolerance,
//             nugget: off | fixed | estimated, nugget_standard_deviation, seed,
//             kernel: matern52 | squared_exponential, trend}       (sbalc.hpp; Li et al. 2025)
//     posterior: {n_samples, credible_level, n_predictive}          (posterior.hpp; SIR,
//                                                                    Smith & Gelfand 1992)
//     initial_runs: results/sens.h5 or sens.yaml   the finished runs of an earlier study of
//                                          the same model and parameters become SBALC's
//                                          initial design (calibrate.hpp, "Runs of an
//                                          earlier study"); a study file stands for its
//                                          results file (this study's own file: in the
//                                          output folder of this calibration, -o included)
//
// Spreads (σ_j, δ_j) are quantities in any unit of the feature's kind; a bare number is
// in the feature's SI unit (ohm, m, s, degC). A spread of a temperature is a
// difference: "2 K" and "2 degC" are the same. Feature values in a features file are
// converted to SI with their offsets ("T_max [K]" → °C). Relative file names are relative
// to the study file's folder. Every error is a fem::ConfigError naming the file and
// line, the key, the value and what is allowed; a bad observation file names its own
// line and column too.
#pragma once

#include "calibration/calibrate.hpp"
#include "calibration/features.hpp"
#include "calibration/likelihood.hpp"
#include "calibration/posterior.hpp"
#include "calibration/sbalc.hpp"
#include "calibration/study.hpp"

#include "fem/config.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::calibration {

// Declares the keys under `calibration.` (units, ranges, docs); study_schema() calls it.
void declare_calibration_keys(fem::ConfigSchema& schema);

enum class ObservationSource { features_file, signal_files };

struct CalibrationSettings {
  ObservationSource observation_source = ObservationSource::features_file;
  std::filesystem::path features_file;              // absolute, features_file source
  std::vector<std::filesystem::path> signal_files;  // absolute, signal_files source
  ObservationNoise noise;                           // σ_j, SI feature units
  std::map<std::string, double> discrepancy_variances;  // δ_j², SI feature units²
  CalibrationMethod method = CalibrationMethod::sbalc;
  SbalcOptions sbalc;
  EmulatorCalibrationOptions emulator;
  PosteriorOptions posterior;  // n_samples, seed, credible_level
  int n_predictive_samples = 4;  // posterior samples run for predictive signals (besides the mean)
  std::filesystem::path initial_runs;  // a study results file, absolute; empty: none
};

// The method's initial design size (the emulator's 0 resolved to ten per parameter) and
// evaluation cap.
int initial_points(const CalibrationSettings& settings, std::size_t n_parameters);
int max_evaluations(const CalibrationSettings& settings);

// Reads and checks the calibration section of a loaded study (observation files are
// not opened here); throws fem::ConfigError.
CalibrationSettings read_calibration_settings(const Study& study);

// An error in an observation file (file, line, column, what is allowed).
class ObservationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Observed replicates of the study's features, SI units (temperatures in °C).
struct Observations {
  std::vector<std::string> feature_names;
  Eigen::MatrixXd values;                  // N_obs × p, column j is feature_names[j]
  std::vector<std::string> replicate_sources;  // per row: "file:line" or the signal file
  std::vector<std::string> warnings;  // implausible units in signal files (read_signal_csv), to print
};

// A CSV of feature vectors: '#' comment lines and blank lines skipped; a header of
// "name" or "name [unit]" entries; then one replicate per row. Every name in
// feature_names needs a column (other columns are ignored). Throws ObservationError.
Observations read_features_file(const std::filesystem::path& file, const std::vector<std::string>& feature_names);

// The features of each signal file (read_signal_csv, extract_features with `settings`),
// one replicate per file. Throws ObservationError naming the file and the feature a file
// cannot give (nugget features, say, are not in signals) or leaves undefined (its shape,
// e.g. no interior resistance peak, with the reason).
Observations features_of_signal_files(const std::vector<std::filesystem::path>& files,
                                      const std::vector<std::string>& feature_names,
                                      const FeatureSettings& settings = {});

// The study's observations; an ObservationError becomes a fem::ConfigError that also
// names the study key and where it was set.
Observations load_observations(const Study& study, const CalibrationSettings& settings);

// The usable runs of calibration.initial_runs for a calibration of `study`
// (read_initial_runs; empty if the key is not given). A file of another set-up, without
// a usable run, or an initial design that leaves no room under
// calibration.sbalc.max_evaluations is a fem::ConfigError naming the key, where it was
// set, its value and the difference.
InitialRuns load_initial_runs(const Study& study, const CalibrationSettings& settings);

// The Gaussian likelihood of the study's features; an inconsistent noise model (a zero
// variance, replicate scatter of a single replicate) is a fem::ConfigError naming
// calibration.noise.kind.
GaussianLikelihood make_likelihood(const Study& study, const CalibrationSettings& settings,
                                   const Observations& observations);

}  // namespace rsw::calibration
