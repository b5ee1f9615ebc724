// A study file: what to vary, how to sample it, what to measure, which forward model
// to run and where to write (docs/STUDIES.md; the key reference docs/STUDY_CONFIG.md is
// generated from study_schema()).
//
//   study:      name, description, output folder (relative to the study file)
//   parameters: a list; each item names a parameter θ_i, the weld-case config key it
//               sets, the unit θ_i is handed to the forward model in, and its prior:
//                 uniform [lower, upper]          log10_uniform [lower, upper] (0 < lower)
//                 normal (mean, standard_deviation)
//                 truncated_normal (mean, standard_deviation) on [lower, upper]
//               Bounds, mean and standard deviation are quantities with a unit
//               ("1e-4 mm", "35 W/(m*K)"); a bare number is in the parameter's unit.
//               `nominal` is the value at the centre of one-at-a-time sweeps (default:
//               the prior median F⁻¹(1/2)).
//   design:     lhs (n_points, seed, maximin_swaps, centred), hammersley (n_points), or
//               oat: the nominal point, then for each parameter n_levels points at the
//               prior quantiles F⁻¹((k + 1/2)/n_levels), k = 0..n_levels − 1, with every
//               other parameter nominal (1 + d·n_levels runs).
//   features:   a list of feature names (docs/STUDIES.md, "The features"), the forward model's outputs.
//   model:      the weld-case file (relative to the study file) and extra config
//               overrides for every run; or instead a command, an external program
//               run once per point (command_model.hpp): then parameters need no
//               config key and features may have any name.
//   sensitivity: degree range and q-norm of the sparse PCE (calibration/pce.hpp).
//   calibration: observations, noise model, SBALC and posterior settings of
//               `rsw calibrate` (declared and read by calibration/calibration_study.hpp).
//
// The design is built in the unit cube (calibration/designs.hpp) and mapped through the
// priors' inverse CDFs (ParameterSpace), so θ is physical in each parameter's unit.
// Every input error is a fem::ConfigError naming the file, line and column, the key,
// the value and what is allowed.
#pragma once

#include "calibration/farm.hpp"
#include "calibration/parameter_space.hpp"
#include "calibration/pce.hpp"

#include "fem/config.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace rsw::calibration {

// The keys of a study file, with units, ranges and docs.
fem::ConfigSchema study_schema();

enum class DesignKind { lhs, hammersley, oat };

// What runs each point: the weld case (model.case) or an external program (model.command).
enum class ModelKind { weld, command };

struct DesignSettings {
  DesignKind kind = DesignKind::lhs;
  std::size_t n_points = 0;        // lhs, hammersley
  std::uint64_t seed = 0;          // lhs
  std::size_t maximin_swaps = 0;   // lhs
  bool centred = false;            // lhs
  std::size_t n_levels = 0;        // oat: points per parameter
};

// Group and unit of the features (docs/STUDIES.md, "The features") ("resistance", "ohm"); group "other"
// and an empty unit for any other name.
FeatureInfo describe_feature(const std::string& name);
// Every feature name the weld forward model can produce, in the groups' order.
std::vector<std::string> known_feature_names();

class Study {
 public:
  // Reads a study file with `--set key=value` overrides of study keys; throws
  // fem::ConfigError for every input error (see the header comment).
  static Study load(const std::filesystem::path& file, const std::vector<std::string>& overrides = {});

  const std::string& name() const { return name_; }
  const std::filesystem::path& file() const { return file_; }
  const fem::Config& config() const { return config_; }
  const ParameterSpace& parameter_space() const { return parameters_; }
  const std::vector<std::string>& feature_names() const { return features_; }
  const DesignSettings& design_settings() const { return design_; }
  // θ of the nominal point (physical), used by one-at-a-time designs.
  const Eigen::VectorXd& nominal_point() const { return nominal_; }

  ModelKind model_kind() const { return model_kind_; }
  // The words of model.command: a word that names a file or folder relative to the study
  // file's folder is its absolute path; the first word may still be a bare program name
  // (looked up on PATH by the caller). Empty unless model_kind() == command.
  const std::vector<std::string>& command() const { return command_; }

  // The weld-case file (absolute; empty if the study names none) and the overrides
  // "key=value" applied to it for every run, before θ.
  const std::filesystem::path& case_file() const { return case_file_; }
  const std::vector<std::string>& model_overrides() const { return model_overrides_; }

  // Folder of the results (absolute); the results file is <output>/<name>.h5.
  const std::filesystem::path& output_folder() const { return output_folder_; }
  void set_output_folder(const std::filesystem::path& folder);
  std::filesystem::path results_file() const;

  PceOptions pce_options() const { return pce_options_; }

  // "case <FNV-1a 64 hash of the case file's bytes>; set key=value, ..." or, for a
  // command, "command <its words as written>; <word> fnv1a64:<hash>, ..." with the hash
  // of each word that names a file of the study's folder (the model's script) — identifies
  // the forward model's set-up in results files, independent of where the files lie.
  std::string model_fingerprint() const;

  // The design points and names, ready for the farm (resolved study YAML as description,
  // model_fingerprint() as model).
  StudyDesign design() const;

  // The dry check before a study or calibration spends runs: `model`'s check_input at
  // the prior's ends, each parameter in turn at its lowest and highest value (the
  // (1e-9, 1 − 1e-9) quantiles) with the others at their medians, and at every row of
  // `points` (physical θ, e.g. the design). Throws fem::ConfigError naming the study,
  // the parameter values and the model's reason; nothing has run then.
  void check_model_inputs(const ForwardModel& model, const Eigen::MatrixXd& points = {}) const;

 private:
  Study(fem::Config config, std::filesystem::path file);

  fem::Config config_;
  std::filesystem::path file_;
  std::string name_;
  ParameterSpace parameters_;
  Eigen::VectorXd nominal_;
  std::vector<std::string> features_;
  DesignSettings design_;
  ModelKind model_kind_ = ModelKind::weld;
  std::vector<std::string> command_words_;  // as written
  std::vector<std::string> command_;        // files of the study's folder made absolute
  std::vector<std::size_t> command_files_;  // the words that name regular files there
  std::filesystem::path case_file_;
  std::vector<std::string> model_overrides_;
  std::filesystem::path output_folder_;
  PceOptions pce_options_;
};

}  // namespace rsw::calibration
