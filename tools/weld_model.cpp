// WeldForwardModel: study parameters → weld case → run_weld → features; see weld_model.hpp.
#include "tools/weld_model.hpp"

#include "calibration/features.hpp"
#include "calibration/signal.hpp"
#include "fem/config.hpp"
#include "fem/temporary_folder.hpp"
#include "fem/units.hpp"
#include "physics/problem.hpp"
#include "physics/weld_simulation.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <unistd.h>

namespace rsw::tools {

namespace fs = std::filesystem;

WeldForwardModel::WeldForwardModel(const calibration::Study& study)
    : case_file_(study.case_file().string()), overrides_(study.model_overrides()),
      feature_names_(study.feature_names()) {
  if (case_file_.empty())
    throw fem::ConfigError(study.file().string() +
                           ": model: no model.case (a weld-case file) and no model.command (a program); a study "
                           "that runs needs one of them");
  const fem::ConfigSchema schema = physics::weld_case_schema();
  const auto& space = study.parameter_space();
  for (std::size_t i = 0; i < space.n_parameters(); ++i) {
    const auto& p = space.parameter(i);
    const fem::KeySpec* key = schema.find(p.config_key);
    if (!key || key->kind != fem::KeyKind::number)
      throw fem::ConfigError(study.file().string() + ": parameter '" + p.name + "': config key '" + p.config_key +
                             "' is not a number key of the weld case; see docs/CONFIG.md");
    if (!fem::units_convertible(p.unit, key->unit))
      throw fem::ConfigError(study.file().string() + ": parameter '" + p.name + "': unit '" + p.unit +
                             "' does not convert to the unit '" + key->unit + "' of '" + p.config_key + "'");
    parameter_names_.push_back(p.name);
    config_keys_.push_back(p.config_key);
    parameter_units_.push_back(p.unit);
    key_units_.push_back(key->unit);
  }
}

std::vector<std::string> WeldForwardModel::parameter_names() const { return parameter_names_; }
std::vector<std::string> WeldForwardModel::feature_names() const { return feature_names_; }

fem::Config WeldForwardModel::config_at(const Eigen::VectorXd& theta) const {
  fem::Config config = fem::load_config(physics::weld_case_schema(), case_file_, overrides_);
  for (std::size_t i = 0; i < config_keys_.size(); ++i)
    config.set_number(config_keys_[i], fem::convert_units(theta[i], parameter_units_[i], key_units_[i]),
                      "study parameter " + parameter_names_[i]);
  return config;
}

void WeldForwardModel::check_input(const Eigen::VectorXd& theta) const {
  const physics::Problem problem = physics::make_problem(config_at(theta));
  // The features a weld defines: the signals' and the nugget's, and a penetration per sheet.
  std::vector<std::string> known = calibration::known_feature_names();
  for (const auto& sheet : problem.geometry.sheets) known.push_back("penetration_" + sheet.name);
  for (const std::string& name : feature_names_) {
    if (std::find(known.begin(), known.end(), name) != known.end()) continue;
    std::string allowed;
    for (const std::string& k : known) allowed += (allowed.empty() ? "" : ", ") + k;
    throw fem::ConfigError("feature '" + name + "' is not one a weld defines; allowed: " + allowed);
  }
}

calibration::EvaluationResult WeldForwardModel::evaluate(const Eigen::VectorXd& theta) const {
  fs::path dir;
  try {
    physics::Problem problem = physics::make_problem(config_at(theta));
    problem.output.fields = false;
    dir = fem::make_temporary_folder("rsw-run-");  // a farm's workers: inside the farm's folder
    const auto run = physics::run_weld(problem, dir / "run");
    if (!run.success) {
      fs::remove_all(dir);
      return calibration::EvaluationResult::failure(run.message);
    }
    const auto& s = run.signals;
    const auto column = [&](const std::string& name) {
      const auto& v = s.columns.at(s.column(name));
      return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())).eval();
    };
    calibration::Signal signal(column("time"));
    signal.add_column("current", "A", column("current"));
    signal.add_column("voltage", "V", column("voltage"));
    signal.add_column("force", "N", column("force"));
    signal.add_column("displacement", "m", column("displacement"));
    signal.add_column("temperature", "degC", column("temperature"));
    const auto features = calibration::extract_features(signal, {}, run.nugget);
    fs::remove_all(dir);
    std::string warnings;
    for (const auto& w : run.warnings) warnings += (warnings.empty() ? "" : "; ") + w;
    return calibration::EvaluationResult::success(features.select(feature_names_), warnings);
  } catch (const std::exception& e) {
    if (!dir.empty()) fs::remove_all(dir);
    return calibration::EvaluationResult::failure(e.what());
  }
}

calibration::SignalOutput WeldForwardModel::simulate_signals(const Eigen::VectorXd& theta,
                                                             const fs::path& folder) const {
  try {
    physics::Problem problem = physics::make_problem(config_at(theta));
    problem.output.fields = false;
    if (folder.has_parent_path()) fs::create_directories(folder.parent_path());
    const auto run = physics::run_weld(problem, folder);
    if (!run.success) return calibration::SignalOutput::failure(run.message);
    return calibration::SignalOutput::written(folder / "signals.csv");
  } catch (const std::exception& e) {
    return calibration::SignalOutput::failure(e.what());
  }
}

std::unique_ptr<calibration::ForwardModel> make_weld_model(const calibration::Study& study) {
  return std::make_unique<WeldForwardModel>(study);
}

}  // namespace rsw::tools
