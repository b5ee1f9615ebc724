// Global sensitivity analysis of a finished study (docs/CALIBRATION.md, "Sensitivity
// analysis"; paper §2.3, §3.2):
// for each feature y_k, a sparse PCE by hybrid LARS (calibration/pce.hpp) is fitted on
// the successful runs in standardised space, s = T(θ) (ParameterSpace), and the Sobol
// indices follow from its coefficients (calibration/sobol.hpp):
//   S_i, S_T,i, S_ij  with the surrogate's ε_LOO and corrected ε*_LOO beside them,
// so a poor fit is visible. Failed runs are excluded and counted (paper: 90 runs, one
// failed, 88 used), never silently dropped; a run whose feature is not finite is
// excluded for that feature only. A feature that does not vary over the runs has
// undefined indices and is reported as not analysed, with the reason.
//
// Tables (write_sensitivity_tables):
//   <stem>_sobol.csv                feature, group, unit, parameter, first_order,
//                                   total_order, loo_error, corrected_loo_error,
//                                   n_runs, degree, n_terms
//   <stem>_sobol_second_order.csv   feature, parameter_i, parameter_j, second_order
//   <stem>_sensitivity.json         everything, arrays aligned with "parameters"
//                                   (read by tools/plot_study.py)
// Undefined values are "nan" in CSV and null in JSON.
#pragma once

#include "calibration/farm.hpp"
#include "calibration/pce.hpp"
#include "calibration/sobol.hpp"

#include <filesystem>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace rsw::calibration {

struct FeatureSensitivity {
  std::string feature;
  FeatureInfo info;
  bool analysed = false;
  std::string reason;             // why not analysed (empty when analysed)
  std::size_t n_runs = 0;         // runs the PCE was fitted on
  int degree = 0;                 // selected candidate degree
  std::size_t n_terms = 0;        // selected terms, constant included
  double mean = std::numeric_limits<double>::quiet_NaN();
  SobolIndices indices;           // with loo_error and corrected_loo_error
};

struct SensitivityReport {
  std::string study;
  std::vector<std::string> parameter_names;
  std::size_t n_runs = 0;       // design points
  std::size_t n_ok = 0;
  std::size_t n_failed = 0;     // excluded, listed in failures
  std::size_t n_pending = 0;    // not run yet (excluded)
  std::vector<std::pair<std::size_t, std::string>> failures;  // (point index, reason)
  PceOptions options;
  std::vector<FeatureSensitivity> features;
};

// Throws std::invalid_argument for a one-at-a-time design (not a sample of the prior)
// or when the results file holds another design (FarmError).
SensitivityReport analyse_sensitivity(const StudyDesign& design, const StudyResults& results,
                                      const PceOptions& options);

std::string sensitivity_json(const SensitivityReport& report);

// The names of the three tables of `stem`, in the order write_sensitivity_tables writes them.
std::vector<std::string> sensitivity_table_names(const std::string& stem);

// Writes the three tables into `folder` (created if missing); returns their paths.
std::vector<std::filesystem::path> write_sensitivity_tables(const SensitivityReport& report,
                                                            const std::filesystem::path& folder,
                                                            const std::string& stem);

// A plain-text summary: runs used and failed, then S_i and S_T per feature and
// parameter with the LOO error, for the terminal.
std::string format_sensitivity_summary(const SensitivityReport& report);

}  // namespace rsw::calibration
