// The forward model as the calibration library sees it: a black box
//     M : θ (physical parameter values) → y (named scalar features)
// that either returns the feature values or fails with a reason.
//
// Everything in calibration/ (designs, sensitivity analysis, likelihood, SBALC) knows
// the simulator only through this interface; the simulator side implements it.
// A failed run (no convergence, a feature that cannot be extracted) is an ordinary
// value, not an exception, so that a design of many runs records each failure with
// its reason and excludes it visibly (paper §2.3: one of 90 runs failed, 88 used).
//
// Units: θ in the units of ParameterSpace (SI), features in SI (temperatures in °C),
// both ordered as parameter_names() / feature_names().
//
// Optional extension, for posterior-predictive runs (rsw calibrate): a model that
// produces time signals (the weld: current, voltage, displacement, ...) overrides
// simulate_signals() to run at θ and write them into a folder; the default writes
// nothing and reports that the model has no signals, so other models need nothing.
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rsw::calibration {

class EvaluationResult {
 public:
  // `warnings`: what a successful run wants its user to know (empty: nothing), e.g. a
  // weld whose electrode passed its solidus; studies record it beside the run.
  static EvaluationResult success(Eigen::VectorXd feature_values, std::string warnings = {}) {
    EvaluationResult result;
    result.ok_ = true;
    result.features_ = std::move(feature_values);
    result.warnings_ = std::move(warnings);
    return result;
  }
  static EvaluationResult failure(std::string reason) {
    EvaluationResult result;
    result.ok_ = false;
    result.failure_reason_ = std::move(reason);
    return result;
  }

  bool ok() const { return ok_; }

  // Feature values in the order of ForwardModel::feature_names(); only for ok() results.
  const Eigen::VectorXd& features() const {
    if (!ok_) {
      throw std::logic_error("EvaluationResult::features() called on a failed evaluation (" +
                             failure_reason_ + ")");
    }
    return features_;
  }

  // Why the evaluation failed; empty for ok() results.
  const std::string& failure_reason() const { return failure_reason_; }
  // Warnings of an ok() result; empty if none.
  const std::string& warnings() const { return warnings_; }

 private:
  EvaluationResult() = default;
  bool ok_ = false;
  Eigen::VectorXd features_;
  std::string failure_reason_;
  std::string warnings_;
};

// What simulate_signals() did: nothing (the model has no signals), wrote a signal file,
// or failed with a reason.
struct SignalOutput {
  bool has_signals = false;           // false: the model produces no signals (the default)
  bool ok = false;                    // the run succeeded and signal_file was written
  std::filesystem::path signal_file;  // <folder>/signals.csv, one "name [unit]" per header column
  std::string failure_reason;         // when has_signals && !ok

  static SignalOutput none() { return {}; }
  static SignalOutput written(std::filesystem::path file) { return {true, true, std::move(file), {}}; }
  static SignalOutput failure(std::string reason) { return {true, false, {}, std::move(reason)}; }
};

class ForwardModel {
 public:
  virtual ~ForwardModel() = default;

  virtual std::vector<std::string> parameter_names() const = 0;
  virtual std::vector<std::string> feature_names() const = 0;

  // θ in physical units, one entry per parameter name. Must not throw for a failed
  // run: failures are returned as EvaluationResult::failure. Calls may come from
  // several threads at once; an implementation that cannot run concurrently must
  // serialise internally.
  virtual EvaluationResult evaluate(const Eigen::VectorXd& theta_physical) const = 0;

  // Checks, without running it, that the model takes θ (physical) as input: throws
  // fem::ConfigError naming what is wrong (a key's range, an invalid case). The default
  // takes every θ. Studies and calibrations call it before their first run.
  virtual void check_input(const Eigen::VectorXd& theta_physical) const {}

  // Runs the model at θ (physical) and writes its signals as <folder>/signals.csv
  // (comma-separated, a "name [unit]" header, rows in time order), and whatever else a
  // run produces, into `folder` (created; an existing folder is replaced). Must not
  // throw for a failed run. The default: no signals, nothing written.
  virtual SignalOutput simulate_signals(const Eigen::VectorXd& theta_physical,
                                        const std::filesystem::path& folder) const {
    return SignalOutput::none();
  }
};

}  // namespace rsw::calibration
