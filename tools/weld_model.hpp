// The weld simulator as a calibration::ForwardModel: θ (physical values of a study's
// parameters) → the study's features. Each evaluation loads the study's weld case
// with its overrides, writes θ into the parameters' config keys, runs the weld
// (physics::run_weld, no field files, in a private temporary folder), turns the
// signals into a calibration::Signal and extracts the features with the same
// extractor that reads measured signal files. A failed simulation or an undefined
// feature is returned as a failure with its reason, never thrown.
//
// For posterior-predictive runs (rsw calibrate), simulate_signals() runs the same
// case at θ into a given folder and keeps what `rsw simulate` writes there
// (signals.csv, results.h5, summary.json; no field files).
#pragma once

#include "calibration/forward_model.hpp"
#include "calibration/study.hpp"

#include "fem/config.hpp"

#include <memory>
#include <string>
#include <vector>

namespace rsw::tools {

class WeldForwardModel : public calibration::ForwardModel {
 public:
  // Checks every parameter's config key (a number key of the weld schema whose unit
  // converts from the parameter's) and every feature name; throws ConfigError.
  explicit WeldForwardModel(const calibration::Study& study);

  std::vector<std::string> parameter_names() const override;
  std::vector<std::string> feature_names() const override;
  calibration::EvaluationResult evaluate(const Eigen::VectorXd& theta) const override;
  // The case with its overrides and θ builds a weld problem (every key in its range,
  // the geometry consistent); no mesh, no run.
  void check_input(const Eigen::VectorXd& theta) const override;
  // Writes <folder>/signals.csv (and results.h5, summary.json); a failed run leaves
  // <folder>/failure.txt and is returned as a failure.
  calibration::SignalOutput simulate_signals(const Eigen::VectorXd& theta,
                                             const std::filesystem::path& folder) const override;

 private:
  // The case with its overrides and θ written into the parameters' keys.
  fem::Config config_at(const Eigen::VectorXd& theta) const;

  std::string case_file_;
  std::vector<std::string> overrides_;
  std::vector<std::string> parameter_names_, config_keys_, parameter_units_, key_units_;
  std::vector<std::string> feature_names_;
};

std::unique_ptr<calibration::ForwardModel> make_weld_model(const calibration::Study& study);

}  // namespace rsw::tools
