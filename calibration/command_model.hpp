// An external program as the forward model (docs/STUDIES.md, "A command as the forward
// model"): a study's `model.command` lets `rsw study run` and `rsw calibrate` drive any
// solver that can read a JSON file of parameter values and write a JSON file of
// features. It knows nothing about welding.
//
// One evaluation at θ:
//   1. a fresh folder <parent>/rsw-command-XXXXXX (mkdtemp; the program passes the
//      parent, rsw its temporary folder) becomes the run folder;
//   2. parameters.json is written there: {"a": 0.3, "b": 0.6}, one entry per parameter,
//      the value in the parameter's unit, shortest round-trip decimal text;
//   3. the program runs with the run folder as its working folder, the argument vector
//      as given (fork and execv: no shell, so no expansion, pipes or redirections),
//      stdin /dev/null, stdout and stderr into stdout.txt and stderr.txt there; the
//      environment is rsw's, and the program is killed (SIGKILL) if the process that
//      started it dies, so a farm worker stopped at the run time limit takes its
//      command with it;
//   4. features.json is read: an object {"feature": value, ...}. A feature of the study
//      that is missing, null or NaN is undefined for this run (the run stays ok, as a
//      weld feature whose signal lacks the shape it needs); ±Infinity is returned as
//      is, and the evaluation farm records such a run as failed; other names are
//      ignored. Python's json module writes NaN and Infinity as bare words; they are
//      accepted.
//   5. the run folder is removed.
// A failed run is returned as EvaluationResult::failure with its reason, never thrown:
// the program could not be started, exited with a non-zero code or was ended by a
// signal (with the last lines of its stderr), or wrote no features.json or one that is
// not such an object.
#pragma once

#include "calibration/forward_model.hpp"

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::calibration {

// Splits a command line into words without a shell: blanks (space, tab) separate words;
// '...' keeps its text literally; "..." too, except that \" and \\ stand for " and \.
// Throws std::invalid_argument for an unbalanced quote, for no word at all, and for an
// unquoted character a shell would interpret (| & ; < > ( ) $ ` \ * ?, and ~ or # at
// the start of a word), since nothing here would interpret it.
std::vector<std::string> split_command_line(const std::string& text);

class CommandModel : public ForwardModel {
 public:
  // `arguments[0]` is the program (absolute path of an executable file); the rest are
  // passed to it unchanged. Run folders are made in `run_folder_parent` (empty: the
  // temporary directory at run time, which a farm's workers have in the farm's own
  // folder, removed with it). Throws
  // std::invalid_argument for an empty argument list or a relative program path.
  CommandModel(std::vector<std::string> arguments, std::vector<std::string> parameter_names,
               std::vector<std::string> feature_names, std::filesystem::path run_folder_parent);

  std::vector<std::string> parameter_names() const override { return parameter_names_; }
  std::vector<std::string> feature_names() const override { return feature_names_; }
  // Steps 1-5 above; safe to call from several threads at once.
  EvaluationResult evaluate(const Eigen::VectorXd& theta) const override;

  const std::vector<std::string>& arguments() const { return arguments_; }

 private:
  std::vector<std::string> arguments_;
  std::vector<std::string> parameter_names_;
  std::vector<std::string> feature_names_;
  std::filesystem::path run_folder_parent_;
};

}  // namespace rsw::calibration
