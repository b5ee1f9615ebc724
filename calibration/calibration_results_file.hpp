// The result files of a calibration (`rsw calibrate`; docs/CALIBRATION.md,
// "`rsw calibrate`"), written into the study's output folder:
//   <name>_calibration.json   summary: method, evidence and convergence, runs, posterior
//                             per parameter (mean, sd, MAP, interval, contraction and
//                             identification), warnings, the method's state, noise
//                             model, observations, predictive runs, initial runs;
//   <name>_calibration.h5     all of it, with the weighted pool, the per-iteration
//                             diagnostics, the chosen points and every run;
//   <name>_posterior.csv      the resampled posterior draws, parameter units;
//   <name>_diagnostics.csv    one row per iteration of the method.
// The study results files of the runs themselves are study_results_file.hpp's.
#pragma once

#include "calibration/calibrate.hpp"
#include "calibration/calibration_study.hpp"
#include "calibration/study.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace rsw::calibration {

// A posterior-predictive run (the posterior mean or a posterior draw run through the
// model for its signals).
struct PredictiveRun {
  std::string name;         // "posterior_mean", "posterior_sample_1", ...
  Eigen::VectorXd theta;    // physical
  std::filesystem::path folder;
  std::string status;       // "ok", "failed", "no_signals"
  std::string failure_reason;
  std::filesystem::path signal_file;     // folder/signals.csv when ok
};

struct CalibrationFiles {
  std::filesystem::path h5, posterior_csv, diagnostics_csv, json;
};

// The four files' paths for `study` (its output folder and name).
CalibrationFiles calibration_files(const Study& study);

// Iterations of the result's method.
std::size_t n_iterations(const CalibrationResult& result);

// Writes the four files (creating the output folder); returns their paths. Throws
// std::runtime_error if a file cannot be written.
CalibrationFiles write_calibration_results(const Study& study, const CalibrationResult& result,
                                           const CalibrationSettings& settings, const GaussianLikelihood& likelihood,
                                           const Observations& observations, const std::vector<PredictiveRun>& predictive,
                                           const InitialRuns& initial, const std::filesystem::path& calibration_folder);

}  // namespace rsw::calibration
