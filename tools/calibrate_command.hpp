// `rsw calibrate STUDY [--workers N] [--resume] [--timeout S] [-o DIR] [--overwrite] [--set key=value] [-q]`:
// Bayesian calibration of the study's parameters against the observations of its
// `calibration:` section (calibration/calibration_study.hpp): Gaussian likelihood,
// SBALC evidence with batches of runs on the evaluation farm, SIR posterior
// (calibration/calibrate.hpp; Li et al. 2025, Smith & Gelfand 1992), then
// posterior-predictive runs of the forward model at the posterior mean and at
// calibration.posterior.n_predictive posterior samples. In the study's output folder:
//   <name>_calibration.h5     posterior samples, pool and weights, evidence and bounds,
//                             per-iteration diagnostics, GP hyperparameters, noise
//                             estimates, observations, every run
//   <name>_posterior.csv      posterior draws, physical units
//   <name>_diagnostics.csv    one row per SBALC iteration
//   <name>_calibration.json   summary: warnings, evidence, convergence, runs, mean, MAP,
//                             credible intervals, ESS, predictive runs, file names, the
//                             initial runs taken from a study (calibration.initial_runs)
//   <name>_calibration/       the evaluation cache (runs_NNNN.h5, one study results file
//                             per batch), predictive.h5 and predictive/<run>/ (for the
//                             weld: signals.csv, results.h5, summary.json)
// The report on standard output starts with the result's warnings (SBALC's stopping
// guards, why it did not converge, a poorly resolved posterior; calibrate.hpp), one line
// each, before the line that says whether the calibration converged; the same warnings
// are the summary's "warnings" list and /evidence/warnings of the HDF5 file.
// tools/plot_calibration.py draws them. Input errors propagate as fem::ConfigError,
// the rest as std::exception for main() to report.
#pragma once

#include "tools/study_commands.hpp"

#include <CLI/CLI.hpp>

namespace rsw::tools {

// Adds `calibrate`. `model_factory` is called once per run, before any worker starts.
void add_calibrate_command(CLI::App& app, ForwardModelFactory model_factory);

}  // namespace rsw::tools
