// `rsw calibrate STUDY`: see calibrate_command.hpp. The calibration itself is
// calibration::Calibration; this file loads the study and its observations, runs the
// posterior-predictive runs through the farm and writes the result files.
//
// Posterior-predictive runs go through the evaluation farm too (in parallel, each in
// its own process, recorded in <name>_calibration/predictive.h5 and resumable): the
// farm evaluates a small adapter model whose parameters are θ and the run's number and
// whose one "feature" says whether the model wrote signals (1) or has none (0); the
// adapter calls ForwardModel::simulate_signals(θ, predictive/<run>/).
#include "tools/calibrate_command.hpp"
#include "tools/mpi_launcher.hpp"
#include "tools/plots.hpp"

#include "calibration/calibrate.hpp"
#include "calibration/calibration_study.hpp"
#include "calibration/farm.hpp"
#include "calibration/study.hpp"

#include "fem/hdf5_file.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::tools {
namespace {

namespace fs = std::filesystem;
namespace cal = calibration;
using Json = nlohmann::ordered_json;

constexpr int calibration_format_version = 1;
const char* const calibration_format = "rsw calibration results";
const char* const signals_written_feature = "signals_written";

struct CalibrateOptions {
  std::string study_file;
  std::vector<std::string> overrides;
  std::string output_dir;
  std::size_t n_workers = 0;
  bool resume = false;
  double run_timeout = 0;
  bool quiet = false;
  bool plots = true;
};

// --- text helpers ------------------------------------------------------------------

std::string number_text(double value, int precision = 17) {
  if (!std::isfinite(value)) return "nan";
  std::ostringstream out;
  out << std::setprecision(precision) << value;
  return out.str();
}

std::string csv_text(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write '" + path.string() + "'");
}

Json finite_or_null(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

Json vector_json(const Eigen::VectorXd& values) {
  Json array = Json::array();
  for (Eigen::Index i = 0; i < values.size(); ++i) array.push_back(finite_or_null(values[i]));
  return array;
}

std::vector<double> to_std(const Eigen::VectorXd& values) { return {values.data(), values.data() + values.size()}; }

fem::RowMajorMatrix to_row_major(const Eigen::MatrixXd& matrix) {
  fem::RowMajorMatrix out;
  out.n_rows = static_cast<std::size_t>(matrix.rows());
  out.n_cols = static_cast<std::size_t>(matrix.cols());
  out.values.reserve(out.n_rows * out.n_cols);
  for (Eigen::Index i = 0; i < matrix.rows(); ++i)
    for (Eigen::Index j = 0; j < matrix.cols(); ++j) out.values.push_back(matrix(i, j));
  return out;
}

const char* kernel_name(cal::KernelType kernel) {
  return kernel == cal::KernelType::SquaredExponential ? "squared_exponential" : "matern52";
}

const char* trend_name(cal::TrendType trend) {
  switch (trend) {
    case cal::TrendType::Constant:
      return "constant";
    case cal::TrendType::DiagonalQuadratic:
      return "diagonal_quadratic";
    case cal::TrendType::FullQuadratic:
      return "full_quadratic";
  }
  return "unknown";
}

const char* nugget_name(cal::NuggetMode mode) {
  switch (mode) {
    case cal::NuggetMode::Off:
      return "off";
    case cal::NuggetMode::Fixed:
      return "fixed";
    case cal::NuggetMode::Estimated:
      return "estimated";
  }
  return "unknown";
}

const char* noise_kind_name(cal::ObservationNoise::Kind kind) {
  switch (kind) {
    case cal::ObservationNoise::Kind::GivenStandardDeviations:
      return "standard_deviations";
    case cal::ObservationNoise::Kind::RelativeToObservedMean:
      return "relative";
    case cal::ObservationNoise::Kind::ReplicateScatter:
      return "replicate_scatter";
  }
  return "unknown";
}

// --- posterior-predictive runs -----------------------------------------------------

struct PredictiveRun {
  std::string name;         // "posterior_mean", "posterior_sample_1", ...
  Eigen::VectorXd theta;    // physical
  fs::path folder;
  std::string status;       // "ok", "failed", "no_signals"
  std::string failure_reason;
  fs::path signal_file;     // folder/signals.csv when ok
};

// θ' = (θ, run number) → simulate_signals(θ, folders[run]); the feature is 1 if
// signals were written, 0 if the model has none.
class PredictiveModel : public cal::ForwardModel {
 public:
  PredictiveModel(const cal::ForwardModel& model, std::vector<fs::path> folders)
      : model_(model), folders_(std::move(folders)) {}

  std::vector<std::string> parameter_names() const override {
    std::vector<std::string> names = model_.parameter_names();
    names.push_back("predictive_run");
    return names;
  }
  std::vector<std::string> feature_names() const override { return {signals_written_feature}; }

  cal::EvaluationResult evaluate(const Eigen::VectorXd& theta) const override {
    const Eigen::Index d = theta.size() - 1;
    const auto run = static_cast<std::size_t>(std::lround(theta[d]));
    if (run >= folders_.size()) return cal::EvaluationResult::failure("no predictive run " + std::to_string(run));
    const cal::SignalOutput output = model_.simulate_signals(theta.head(d), folders_[run]);
    if (!output.has_signals) return cal::EvaluationResult::success(Eigen::VectorXd::Zero(1));
    if (!output.ok) return cal::EvaluationResult::failure(output.failure_reason);
    return cal::EvaluationResult::success(Eigen::VectorXd::Ones(1));
  }

 private:
  const cal::ForwardModel& model_;
  std::vector<fs::path> folders_;
};

std::vector<PredictiveRun> run_predictive(const cal::Study& study, const cal::ForwardModel& model,
                                          const cal::CalibrationResult& result, const cal::CalibrationSettings& settings,
                                          const fs::path& calibration_folder, const cal::FarmOptions& farm_options) {
  std::vector<PredictiveRun> runs;
  runs.push_back({"posterior_mean", result.mean, {}, {}, {}, {}});
  const Eigen::Index n_samples = result.samples.rows();
  const int k = settings.n_predictive_samples;
  for (int j = 0; j < k && n_samples > 0; ++j) {
    // Evenly spread over the resampled draws (whose order is the pool's random order).
    const auto row = static_cast<Eigen::Index>((static_cast<double>(j) + 0.5) * static_cast<double>(n_samples) / k);
    runs.push_back({"posterior_sample_" + std::to_string(j + 1), result.samples.row(row).transpose(), {}, {}, {}, {}});
  }
  const fs::path predictive_folder = calibration_folder / "predictive";
  std::vector<fs::path> folders;
  for (auto& run : runs) {
    run.folder = predictive_folder / run.name;
    folders.push_back(run.folder);
  }

  cal::StudyDesign design;
  design.name = study.name() + "_predictive";
  design.kind = "posterior_predictive";
  design.parameters = study.parameter_space();
  design.parameters.add({"predictive_run", "calibration.predictive_run", "1",
                         cal::Prior::uniform(-0.5, static_cast<double>(runs.size()) - 0.5)});
  design.feature_names = {signals_written_feature};
  design.description = study.config().to_yaml();
  design.model = study.model_fingerprint();
  const auto d = static_cast<Eigen::Index>(study.parameter_space().n_parameters());
  design.points.resize(static_cast<Eigen::Index>(runs.size()), d + 1);
  for (std::size_t r = 0; r < runs.size(); ++r) {
    design.points.row(static_cast<Eigen::Index>(r)).head(d) = runs[r].theta.transpose();
    design.points(static_cast<Eigen::Index>(r), d) = static_cast<double>(r);
  }

  // A predictive file of another posterior (a calibration continued with more runs) is
  // replaced; one of the same posterior is resumed.
  const fs::path file = calibration_folder / "predictive.h5";
  bool resume = false;
  if (fs::exists(file)) {
    try {
      cal::check_same_design(cal::read_study_results(file), design, file);
      resume = true;
    } catch (const cal::FarmError&) {
      fs::remove(file);
      fs::remove_all(predictive_folder);
    }
  }
  const PredictiveModel predictive(model, folders);
  cal::FarmOptions options = farm_options;
  options.resume = resume;
  options.progress = nullptr;
  options.distribution = cal::FarmDistribution::local;
  options.on_result = nullptr;
  const cal::FarmSummary summary = cal::EvaluationFarm(predictive, design, file, options).run();
  if (summary.interrupted) {
    throw std::runtime_error("posterior-predictive runs interrupted; continue with: rsw calibrate " +
                             study.file().string() + " --resume");
  }
  const cal::StudyResults stored = cal::read_study_results(file);
  for (std::size_t r = 0; r < runs.size(); ++r) {
    if (stored.status[r] == cal::StudyResults::Status::failed) {
      runs[r].status = "failed";
      runs[r].failure_reason = stored.failure_reasons[r];
    } else if (stored.features(static_cast<Eigen::Index>(r), 0) > 0.5) {
      runs[r].status = "ok";
      runs[r].signal_file = runs[r].folder / "signals.csv";
    } else {
      runs[r].status = "no_signals";
    }
  }
  return runs;
}

// --- result files --------------------------------------------------------------------

struct OutputFiles {
  fs::path h5, posterior_csv, diagnostics_csv, json;
};

OutputFiles output_files(const cal::Study& study) {
  const fs::path folder = study.output_folder();
  const std::string name = study.name();
  return {folder / (name + "_calibration.h5"), folder / (name + "_posterior.csv"),
          folder / (name + "_diagnostics.csv"), folder / (name + "_calibration.json")};
}

std::string unit_label(const std::string& name, const std::string& unit) {
  return unit.empty() ? name : name + " [" + unit + "]";
}

void write_posterior_csv(const fs::path& path, const cal::CalibrationResult& result) {
  std::ostringstream csv;
  csv << "sample";
  for (std::size_t i = 0; i < result.parameter_names.size(); ++i) {
    csv << "," << csv_text(unit_label(result.parameter_names[i], result.parameter_units[i]));
  }
  csv << "\n";
  for (Eigen::Index s = 0; s < result.samples.rows(); ++s) {
    csv << s;
    for (Eigen::Index i = 0; i < result.samples.cols(); ++i) csv << "," << number_text(result.samples(s, i));
    csv << "\n";
  }
  write_text(path, csv.str());
}

// Columns of the emulator route's diagnostics table, then one variance ratio per feature.
const std::vector<std::string> emulator_diagnostics_columns = {
    "iteration", "n_points", "n_evaluations", "log_evidence", "evidence_relative_error", "smc_log_evidence",
    "n_temperatures", "pool_ess", "emulator_influence", "plug_in_ess", "quantile_shift", "influence_settled",
    "quantiles_settled", "counted", "max_variance_ratio", "n_chosen", "seconds"};

Eigen::MatrixXd emulator_diagnostics_table(const cal::CalibrationResult& result) {
  const auto p = static_cast<Eigen::Index>(result.feature_names.size());
  const auto n_fixed = static_cast<Eigen::Index>(emulator_diagnostics_columns.size());
  Eigen::MatrixXd table(static_cast<Eigen::Index>(result.emulator_history.size()), n_fixed + p);
  for (std::size_t k = 0; k < result.emulator_history.size(); ++k) {
    const cal::EmulatorIteration& it = result.emulator_history[k];
    const auto r = static_cast<Eigen::Index>(k);
    table.row(r).head(n_fixed) << static_cast<double>(k), it.n_points, it.n_evaluations, it.log_evidence,
        it.evidence_relative_error, it.smc_log_evidence, it.n_temperatures, it.pool_ess, it.emulator_influence,
        it.plug_in_ess, it.quantile_shift, it.influence_settled ? 1.0 : 0.0, it.quantiles_settled ? 1.0 : 0.0,
        it.counted ? 1.0 : 0.0, it.max_variance_ratio, static_cast<double>(it.chosen_points.rows()), it.seconds;
    table.row(r).tail(p) = it.variance_ratios.transpose();
  }
  return table;
}

// Columns of the diagnostics table (CSV and /diagnostics/table), then one length scale
// per parameter (u units).
const std::vector<std::string> diagnostics_columns = {
    "iteration", "n_points", "n_evaluations", "log_evidence", "log_evidence_lower", "log_evidence_upper", "ratio",
    "noise_ratio", "tolerance_used", "noise_standard_deviation", "signal_variance", "jitter",
    "log_learning_function", "n_chosen", "n_imputed", "pool_ess", "gp_ratio", "pool_relative_error", "peak_spread",
    "counted"};

Eigen::MatrixXd diagnostics_table(const cal::CalibrationResult& result) {
  if (result.method == cal::CalibrationMethod::emulator) return emulator_diagnostics_table(result);
  const auto d = static_cast<Eigen::Index>(result.parameter_names.size());
  const auto n_columns = static_cast<Eigen::Index>(diagnostics_columns.size()) + d;
  Eigen::MatrixXd table(static_cast<Eigen::Index>(result.history.size()), n_columns);
  for (std::size_t k = 0; k < result.history.size(); ++k) {
    const cal::SbalcIteration& it = result.history[k];
    const auto r = static_cast<Eigen::Index>(k);
    table.row(r).head(static_cast<Eigen::Index>(diagnostics_columns.size())) << static_cast<double>(k),
        it.n_points, it.n_evaluations, it.log_evidence, it.log_evidence_lower, it.log_evidence_upper, it.ratio,
        it.noise_ratio, it.tolerance_used, it.noise_standard_deviation, it.hyperparameters.signal_variance, it.jitter,
        it.chosen_points.rows() > 0 ? it.log_learning_function : std::numeric_limits<double>::quiet_NaN(),
        static_cast<double>(it.chosen_points.rows()), static_cast<double>(it.n_imputed), it.pool_ess, it.gp_ratio,
        it.pool_relative_error, it.peak_spread, it.counted ? 1.0 : 0.0;
    for (Eigen::Index j = 0; j < d; ++j) {
      table(r, static_cast<Eigen::Index>(diagnostics_columns.size()) + j) =
          j < it.hyperparameters.length_scales.size() ? it.hyperparameters.length_scales[j]
                                                      : std::numeric_limits<double>::quiet_NaN();
    }
  }
  return table;
}

std::vector<std::string> diagnostics_header(const cal::CalibrationResult& result) {
  if (result.method == cal::CalibrationMethod::emulator) {
    std::vector<std::string> header = emulator_diagnostics_columns;
    for (const auto& name : result.feature_names) header.push_back("variance_ratio:" + name);
    return header;
  }
  std::vector<std::string> header = diagnostics_columns;
  for (const auto& name : result.parameter_names) header.push_back("length_scale:" + name);
  return header;
}

void write_diagnostics_csv(const fs::path& path, const cal::CalibrationResult& result) {
  const Eigen::MatrixXd table = diagnostics_table(result);
  const std::vector<std::string> header = diagnostics_header(result);
  std::ostringstream csv;
  for (std::size_t c = 0; c < header.size(); ++c) csv << (c ? "," : "") << csv_text(header[c]);
  csv << "\n";
  for (Eigen::Index r = 0; r < table.rows(); ++r) {
    for (Eigen::Index c = 0; c < table.cols(); ++c) {
      const bool count = c < 3;
      csv << (c ? "," : "") << (count ? std::to_string(static_cast<long long>(table(r, c))) : number_text(table(r, c)));
    }
    csv << "\n";
  }
  write_text(path, csv.str());
}

Json parameters_json(const cal::Study& study, const cal::CalibrationResult& result) {
  Json parameters = Json::array();
  const cal::ParameterSpace& space = study.parameter_space();
  for (std::size_t i = 0; i < space.n_parameters(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const cal::Parameter& p = space.parameter(i);
    parameters.push_back({{"name", p.name},
                          {"config_key", p.config_key},
                          {"unit", p.unit},
                          {"prior", prior_kind_name(p.prior.kind())},
                          {"prior_description", p.prior.describe()},
                          {"prior_lower", finite_or_null(p.prior.lower())},
                          {"prior_upper", finite_or_null(p.prior.upper())},
                          {"mean", result.mean[ii]},
                          {"standard_deviation", result.standard_deviation[ii]},
                          {"map", result.map_point[ii]},
                          {"credible_lower", result.credible_lower[ii]},
                          {"credible_upper", result.credible_upper[ii]},
                          {"contraction", result.contraction[ii]},
                          {"identification", result.identification[i]}});
  }
  return parameters;
}

std::size_t n_iterations(const cal::CalibrationResult& result) {
  return result.method == cal::CalibrationMethod::emulator ? result.emulator_history.size() : result.history.size();
}

// The emulator route's settings and last iteration (null for SBALC).
Json emulator_json(const cal::CalibrationResult& result, const cal::CalibrationSettings& settings) {
  if (result.method != cal::CalibrationMethod::emulator || result.emulator_history.empty()) return nullptr;
  const cal::EmulatorIteration& last = result.emulator_history.back();
  Json features = Json::array();
  for (std::size_t j = 0; j < result.feature_names.size(); ++j) {
    const auto jj = static_cast<Eigen::Index>(j);
    features.push_back({{"name", result.feature_names[j]},
                        {"variance_ratio", last.variance_ratios[jj]},
                        {"noise_standard_deviation", last.noise_standard_deviations[jj]}});
  }
  return {{"influence_tolerance", settings.emulator.influence_tolerance},
          {"quantile_tolerance", settings.emulator.quantile_tolerance},
          {"trend", trend_name(settings.emulator.gp.trend)},
          {"emulator_influence", last.emulator_influence},
          {"plug_in_ess", last.plug_in_ess},
          {"max_variance_ratio", last.max_variance_ratio},
          {"quantile_shift", finite_or_null(last.quantile_shift)},
          {"smc_log_evidence", last.smc_log_evidence},
          {"features", features}};
}

Json noise_json(const cal::GaussianLikelihood& likelihood, const cal::CalibrationSettings& settings,
                const cal::Observations& observations) {
  Json features = Json::array();
  for (int j = 0; j < likelihood.n_features(); ++j) {
    const std::string& name = likelihood.feature_names()[static_cast<std::size_t>(j)];
    const double measurement = likelihood.measurement_variances()[j];
    const double total = likelihood.variances()[j];
    features.push_back({{"name", name},
                        {"unit", cal::describe_feature(name).unit},
                        {"observed_mean", observations.values.col(j).mean()},
                        {"measurement_standard_deviation", std::sqrt(measurement)},
                        {"discrepancy_standard_deviation", std::sqrt(std::max(0.0, total - measurement))},
                        {"total_standard_deviation", std::sqrt(total)}});
  }
  return {{"kind", noise_kind_name(settings.noise.kind)},
          {"n_replicates", likelihood.n_replicates()},
          {"features", features}};
}

void write_h5(const fs::path& path, const cal::Study& study, const cal::CalibrationResult& result,
              const cal::CalibrationSettings& settings, const cal::GaussianLikelihood& likelihood,
              const cal::Observations& observations, const std::vector<PredictiveRun>& predictive,
              const Json& summary) {
  fem::Hdf5File h5(path, fem::Hdf5Mode::truncate);
  h5.set_attribute("/", "format", calibration_format);
  h5.set_attribute("/", "format_version", static_cast<double>(calibration_format_version));
  h5.set_attribute("/", "study", study.name());
  h5.write_string("/metadata/study", study.config().to_yaml());
  h5.write_string("/metadata/summary", summary.dump(2));
  h5.write_string("/metadata/parameters", Json(result.parameter_names).dump());
  h5.write_string("/metadata/parameter_units", Json(result.parameter_units).dump());
  h5.write_string("/metadata/features", Json(result.feature_names).dump());

  // Posterior (physical units).
  h5.write("/posterior/samples", to_row_major(result.samples));
  h5.write("/posterior/pool", to_row_major(result.pool));
  h5.write("/posterior/weights", to_std(result.pool_weights));
  h5.write("/posterior/pool_log_likelihood", to_std(result.pool_log_likelihood));
  h5.write("/posterior/mean", to_std(result.mean));
  h5.write("/posterior/standard_deviation", to_std(result.standard_deviation));
  h5.write("/posterior/correlation", to_row_major(result.correlation));
  h5.write("/posterior/map", to_std(result.map_point));
  h5.write("/posterior/credible_lower", to_std(result.credible_lower));
  h5.write("/posterior/credible_upper", to_std(result.credible_upper));
  h5.set_attribute("/posterior", "credible_level", result.credible_level);
  h5.set_attribute("/posterior", "effective_sample_size", result.effective_sample_size);
  h5.set_attribute("/posterior", "ess_threshold", result.ess_threshold);
  h5.set_attribute("/posterior", "map_log_likelihood", result.map_log_likelihood);
  h5.set_attribute("/posterior", "warning", result.warning);

  // Evidence.
  h5.write("/evidence/log_evidence", std::vector<double>{result.log_evidence});
  h5.write("/evidence/log_evidence_lower", std::vector<double>{result.log_evidence_lower});
  h5.write("/evidence/log_evidence_upper", std::vector<double>{result.log_evidence_upper});
  h5.set_attribute("/evidence", "ratio", result.ratio);
  h5.set_attribute("/evidence", "noise_ratio", result.noise_ratio);
  h5.set_attribute("/evidence", "converged", result.converged ? 1.0 : 0.0);
  h5.set_attribute("/evidence", "stop_reason", result.stop_reason);
  h5.set_attribute("/evidence", "pool_relative_error", result.pool_relative_error);
  h5.set_attribute("/evidence", "pool_effective_sample_size", result.pool_ess);
  h5.set_attribute("/evidence", "pool_ess_threshold", result.pool_ess_threshold);
  h5.write_string("/evidence/warnings", Json(result.warnings).dump(1));

  // Diagnostics per iteration, and the points each iteration chose (physical θ).
  h5.write("/diagnostics/table", to_row_major(diagnostics_table(result)));
  h5.set_attribute("/diagnostics/table", "columns", Json(diagnostics_header(result)).dump());
  Json refusals = Json::object();  // by iteration, the stopping guards that failed (sbalc.hpp)
  for (std::size_t k = 0; k < result.history.size(); ++k)
    if (!result.history[k].refusal.empty()) refusals[std::to_string(k)] = result.history[k].refusal;
  h5.write_string("/diagnostics/refusals", refusals.dump(1));
  const auto d = static_cast<Eigen::Index>(result.parameter_names.size());
  std::vector<Eigen::VectorXd> chosen_rows;
  const std::size_t n_iterations =
      result.method == cal::CalibrationMethod::emulator ? result.emulator_history.size() : result.history.size();
  for (std::size_t k = 0; k < n_iterations; ++k) {
    const Eigen::MatrixXd& chosen = result.method == cal::CalibrationMethod::emulator
                                        ? result.emulator_history[k].chosen_points
                                        : result.history[k].chosen_points;
    for (Eigen::Index r = 0; r < chosen.rows(); ++r) {
      Eigen::VectorXd row(d + 1);
      row << static_cast<double>(k), cal::unit_to_physical(study.parameter_space(), chosen.row(r).transpose());
      chosen_rows.push_back(row);
    }
  }
  Eigen::MatrixXd chosen(static_cast<Eigen::Index>(chosen_rows.size()), d + 1);
  for (std::size_t r = 0; r < chosen_rows.size(); ++r) chosen.row(static_cast<Eigen::Index>(r)) = chosen_rows[r].transpose();
  h5.write("/diagnostics/chosen_points", to_row_major(chosen));
  h5.set_attribute("/diagnostics/chosen_points", "columns", "iteration, then theta in parameter units");

  h5.set_attribute("/", "method", cal::calibration_method_name(result.method));
  if (result.method == cal::CalibrationMethod::emulator) {
    // The runs the feature emulators learnt from (u in [0,1]^d), ln L of each, and each
    // feature's numerical noise tau_j (SI feature units).
    h5.write("/emulator/design_unit", to_row_major(result.design_unit));
    h5.write("/emulator/log_likelihoods", to_std(result.design_log_likelihoods));
    h5.write("/emulator/feature_noise_standard_deviation", to_std(result.feature_noise_standard_deviations));
    h5.set_attribute("/emulator", "trend", trend_name(settings.emulator.gp.trend));
  } else {
  // GP of the log-likelihood (inputs u in [0,1]^d).
  h5.write("/gp/length_scales", to_std(result.hyperparameters.length_scales));
  h5.write("/gp/signal_variance", std::vector<double>{result.hyperparameters.signal_variance});
  h5.write("/gp/noise_variance", std::vector<double>{result.hyperparameters.noise_variance});
  h5.write("/gp/design_unit", to_row_major(result.design_unit));
  h5.write("/gp/log_likelihoods", to_std(result.design_log_likelihoods));
  h5.set_attribute("/gp", "kernel", kernel_name(settings.sbalc.gp.kernel));
  h5.set_attribute("/gp", "trend_used", trend_name(result.trend_used));
  h5.set_attribute("/gp", "nugget", nugget_name(settings.sbalc.gp.nugget_mode));
  h5.set_attribute("/gp", "noise_standard_deviation", result.noise_standard_deviation);
  }

  // Observations and noise estimate (SI feature units).
  h5.write("/observations/values", to_row_major(observations.values));
  h5.write_string("/observations/sources", Json(observations.replicate_sources).dump());
  Eigen::VectorXd measurement = likelihood.measurement_variances().cwiseSqrt();
  Eigen::VectorXd total = likelihood.variances().cwiseSqrt();
  h5.write("/noise/measurement_standard_deviation", to_std(measurement));
  h5.write("/noise/total_standard_deviation", to_std(total));
  h5.write("/noise/discrepancy_standard_deviation",
           to_std((likelihood.variances() - likelihood.measurement_variances()).cwiseMax(0.0).cwiseSqrt()));
  h5.set_attribute("/noise", "kind", noise_kind_name(settings.noise.kind));
  h5.set_attribute("/noise", "log_likelihood_noise_standard_deviation", result.noise_standard_deviation);

  // Every run SBALC asked for, in order.
  const auto p = static_cast<Eigen::Index>(result.feature_names.size());
  Eigen::MatrixXd runs(static_cast<Eigen::Index>(result.evaluations.size()), 6 + 2 * d + p);
  Json reasons = Json::object(), warnings = Json::object();
  for (std::size_t r = 0; r < result.evaluations.size(); ++r) {
    const cal::CalibrationEvaluation& e = result.evaluations[r];
    runs.row(static_cast<Eigen::Index>(r)) << static_cast<double>(e.batch), e.ok ? 1.0 : 0.0, e.reused ? 1.0 : 0.0,
        e.wall_time, e.log_likelihood, e.theta_unit.transpose(), e.theta.transpose(), e.features.transpose(),
        e.from_study ? 1.0 : 0.0;
    if (!e.ok) reasons[std::to_string(r)] = e.failure_reason;
    if (!e.warnings.empty()) warnings[std::to_string(r)] = e.warnings;
  }
  Json columns = {"batch", "ok", "reused", "wall_time", "log_likelihood"};
  for (const auto& name : result.parameter_names) columns.push_back("u:" + name);
  for (const auto& name : result.parameter_names) columns.push_back("theta:" + name);
  for (const auto& name : result.feature_names) columns.push_back("y:" + name);
  columns.push_back("from_study");
  h5.write("/evaluations/table", to_row_major(runs));
  h5.set_attribute("/evaluations/table", "columns", columns.dump());
  h5.write_string("/evaluations/failure_reasons", reasons.dump(1));
  h5.write_string("/evaluations/warnings", warnings.dump(1));  // by row, runs that warned

  // Posterior-predictive runs.
  Eigen::MatrixXd predictive_points(static_cast<Eigen::Index>(predictive.size()), d);
  Json predictive_names = Json::array();
  for (std::size_t r = 0; r < predictive.size(); ++r) {
    predictive_points.row(static_cast<Eigen::Index>(r)) = predictive[r].theta.transpose();
    predictive_names.push_back(predictive[r].name);
  }
  h5.write("/predictive/points", to_row_major(predictive_points));
  h5.write_string("/predictive/names", predictive_names.dump());
  h5.close();
}

// --- the command -------------------------------------------------------------------------

cal::StudyDesign calibration_design(const cal::Study& study) {
  cal::StudyDesign design;
  design.name = study.name();
  design.kind = "sbalc";
  design.parameters = study.parameter_space();
  design.feature_names = study.feature_names();
  for (const auto& name : design.feature_names) design.feature_info.push_back(cal::describe_feature(name));
  design.description = study.config().to_yaml();
  design.model = study.model_fingerprint();
  return design;
}

void run_calibrate(const CalibrateOptions& options, const ForwardModelFactory& factory) {
  cal::Study study = cal::Study::load(options.study_file, options.overrides);
  if (!options.output_dir.empty()) study.set_output_folder(options.output_dir);
  if (started_by_mpi_launcher()) {
    throw std::runtime_error("rsw calibrate runs its batches on worker processes of one machine; start it without "
                             "mpirun (use --workers N)");
  }
  const cal::CalibrationSettings settings = cal::read_calibration_settings(study);
  const cal::Observations observations = cal::load_observations(study, settings);
  const cal::GaussianLikelihood likelihood = cal::make_likelihood(study, settings, observations);
  const std::unique_ptr<cal::ForwardModel> model = make_forward_model(study, factory);

  const fs::path output = study.output_folder();
  const fs::path calibration_folder = output / (study.name() + "_calibration");
  cal::CalibrationOptions calibration_options;
  calibration_options.method = settings.method;
  calibration_options.sbalc = settings.sbalc;
  calibration_options.emulator = settings.emulator;
  calibration_options.posterior = settings.posterior;
  calibration_options.evaluations_folder = calibration_folder / "evaluations";
  calibration_options.farm.n_workers = options.n_workers;
  calibration_options.farm.resume = options.resume;
  calibration_options.farm.run_timeout = options.run_timeout;
  calibration_options.progress = options.quiet ? nullptr : &std::cerr;
  calibration_options.initial_runs = cal::load_initial_runs(study, settings);
  if (!options.resume && fs::exists(calibration_folder) && !fs::is_empty(calibration_folder)) {
    throw std::runtime_error("calibration folder '" + calibration_folder.string() +
                             "' exists already; continue the calibration with --resume, or remove it to start again");
  }
  if (!options.quiet) {
    std::cerr << "calibration " << study.name() << ": " << observations.values.rows() << " replicate"
              << (observations.values.rows() == 1 ? "" : "s") << " of " << observations.values.cols() << " feature"
              << (observations.values.cols() == 1 ? "" : "s") << " ("
              << (settings.observation_source == cal::ObservationSource::features_file ? "features file"
                                                                                       : "signal files")
              << "), noise " << noise_kind_name(settings.noise.kind) << "; ";
    if (settings.method == cal::CalibrationMethod::sbalc) {
      std::cerr << "SBALC pool " << settings.sbalc.pool_size << ", " << settings.sbalc.n_initial
                << " initial points, batches of " << settings.sbalc.batch_size << ", at most "
                << settings.sbalc.max_evaluations << " runs, nugget " << nugget_name(settings.sbalc.gp.nugget_mode)
                << "\n";
    } else {
      std::cerr << "feature emulators, " << cal::initial_points(settings, study.parameter_space().n_parameters())
                << " initial points, batches of " << settings.emulator.batch_size << ", at most "
                << settings.emulator.max_evaluations << " runs\n";
    }
  }
  const cal::InitialRuns& initial = calibration_options.initial_runs;
  if (!initial.runs.empty() && !options.quiet) {
    const auto n_ok = std::count_if(initial.runs.begin(), initial.runs.end(), [](const cal::InitialRun& r) { return r.ok; });
    std::cerr << "calibration " << study.name() << ": initial design from " << initial.file.string() << ": "
              << initial.runs.size() << " runs (" << n_ok << " ok, " << initial.runs.size() - n_ok << " failed)";
    const int n_initial = cal::initial_points(settings, study.parameter_space().n_parameters());
    if (static_cast<int>(initial.runs.size()) < n_initial)
      std::cerr << " and " << n_initial - static_cast<int>(initial.runs.size()) << " Hammersley points";
    std::cerr << "\n";
    for (const auto& note : initial.notes) std::cerr << "  note: " << note << "\n";
  }

  const cal::CalibrationResult result =
      cal::Calibration(*model, calibration_design(study), likelihood, calibration_options).run();

  if (!options.quiet) {
    std::cerr << "calibration " << study.name() << ": posterior-predictive runs (posterior mean and "
              << settings.n_predictive_samples << " posterior samples)\n";
  }
  const std::vector<PredictiveRun> predictive =
      run_predictive(study, *model, result, settings, calibration_folder, calibration_options.farm);

  // Summary.
  const OutputFiles files = output_files(study);
  Json predictive_json = Json::array();
  for (const auto& run : predictive) {
    Json entry = {{"name", run.name}, {"theta", vector_json(run.theta)}, {"status", run.status},
                  {"folder", run.folder.string()}};
    if (run.status == "ok") entry["signal_file"] = run.signal_file.string();
    if (run.status == "failed") entry["failure_reason"] = run.failure_reason;
    predictive_json.push_back(entry);
  }
  Json observed_files = Json::array();
  for (const auto& file : settings.signal_files) observed_files.push_back(file.string());
  Json summary = {
      {"study", study.name()},
      {"study_file", fs::absolute(study.file()).lexically_normal().string()},
      {"method", cal::calibration_method_name(result.method)},
      {"warnings", result.warnings},
      {"converged", result.converged},
      {"stop_reason", result.stop_reason},
      {"evidence",
       {{"log_evidence", result.log_evidence},
        {"log_evidence_lower", finite_or_null(result.log_evidence_lower)},
        {"log_evidence_upper", finite_or_null(result.log_evidence_upper)},
        {"ratio", finite_or_null(result.ratio)},
        {"noise_ratio", result.noise_ratio},
        {"tolerance", result.method == cal::CalibrationMethod::sbalc ? Json(settings.sbalc.tolerance) : Json(nullptr)},
        {"tolerance_used", result.history.empty() ? Json(nullptr) : Json(result.history.back().tolerance_used)},
        {"pool_relative_error", finite_or_null(result.pool_relative_error)},
        {"pool_effective_sample_size", result.pool_ess},
        {"pool_ess_threshold", result.pool_ess_threshold}}},
      {"n_evaluations", result.n_evaluations},
      {"n_reused", result.n_reused},
      {"n_from_study", result.n_from_study},
      {"n_failed", result.n_failed},
      {"n_warned", std::count_if(result.evaluations.begin(), result.evaluations.end(),
                                 [](const cal::CalibrationEvaluation& e) { return !e.warnings.empty(); })},
      {"n_iterations", n_iterations(result)},
      {"parameters", parameters_json(study, result)},
      {"credible_level", result.credible_level},
      {"effective_sample_size", result.effective_sample_size},
      {"ess_threshold", result.ess_threshold},
      {"pool_size", result.pool.rows()},
      {"warning", result.warning},
      {"map_log_likelihood", result.map_log_likelihood},
      {"emulator", emulator_json(result, settings)},
      {"gp",
       {{"kernel", kernel_name(settings.sbalc.gp.kernel)},
        {"trend_used", trend_name(result.trend_used)},
        {"nugget", nugget_name(settings.sbalc.gp.nugget_mode)},
        {"length_scales", vector_json(result.hyperparameters.length_scales)},
        {"signal_variance", result.hyperparameters.signal_variance},
        {"log_likelihood_noise_standard_deviation", result.noise_standard_deviation}}},
      {"noise", noise_json(likelihood, settings, observations)},
      {"observations",
       {{"source", settings.observation_source == cal::ObservationSource::features_file ? "features_file"
                                                                                          : "signal_files"},
        {"features_file", settings.features_file.string()},
        {"signal_files", observed_files},
        {"values", Json::array()}}},
      {"predictive", predictive_json},
      {"initial_runs",
       {{"file", initial.file.string()}, {"n_runs", initial.runs.size()}, {"notes", initial.notes}}},
      {"files",
       {{"h5", files.h5.string()},
        {"posterior_csv", files.posterior_csv.string()},
        {"diagnostics_csv", files.diagnostics_csv.string()},
        {"json", files.json.string()},
        {"calibration_folder", calibration_folder.string()}}},
      {"units", "parameters in their study units; features in SI (temperatures in degC)"},
      {"elapsed", result.elapsed}};
  for (Eigen::Index r = 0; r < observations.values.rows(); ++r) {
    summary["observations"]["values"].push_back(vector_json(observations.values.row(r).transpose()));
  }

  fs::create_directories(output);
  write_h5(files.h5, study, result, settings, likelihood, observations, predictive, summary);
  write_posterior_csv(files.posterior_csv, result);
  write_diagnostics_csv(files.diagnostics_csv, result);
  write_text(files.json, summary.dump(2) + "\n");

  // Report: the warnings first, before any "converged".
  for (const auto& warning : result.warnings)
    std::printf("calibration %s: warning: %s\n", study.name().c_str(), warning.c_str());
  const std::string from_study =
      result.n_from_study > 0 ? std::to_string(result.n_from_study) + " from the study, " : std::string();
  std::printf("calibration %s: %s after %zu runs (%s%zu reused, %zu failed), %zu iterations, %s\n",
              study.name().c_str(), result.converged ? "converged" : "NOT converged", result.n_evaluations,
              from_study.c_str(), result.n_reused, result.n_failed, n_iterations(result),
              cal::format_duration(result.elapsed).c_str());
  std::printf("  %s\n", result.stop_reason.c_str());
  for (std::size_t r = 0; r < result.evaluations.size(); ++r)
    if (!result.evaluations[r].warnings.empty() && !result.evaluations[r].reused)
      std::printf("  run %zu warns: %s\n", r, result.evaluations[r].warnings.c_str());
  if (result.method == cal::CalibrationMethod::sbalc) {
    std::printf("  evidence ln c = %.6g, bounds [%.6g, %.6g] (pool Monte Carlo error %.2g %%, pool ESS %.1f), ratio "
                "%.3g (noise part %.3g); log-likelihood noise tau = %.3g\n",
                result.log_evidence, result.log_evidence_lower, result.log_evidence_upper,
                100.0 * result.pool_relative_error, result.pool_ess, result.ratio, result.noise_ratio,
                result.noise_standard_deviation);
  } else if (!result.emulator_history.empty()) {
    const cal::EmulatorIteration& last = result.emulator_history.back();
    std::printf("  evidence ln Z = %.6g (Monte Carlo error %.2g %%, pool ESS %.1f); emulators' influence %.3g sd "
                "(tolerance %.3g), quantile shift %.3g sd (tolerance %.3g), variance ratio %.3g\n",
                result.log_evidence, 100.0 * result.pool_relative_error, result.pool_ess, last.emulator_influence,
                settings.emulator.influence_tolerance, last.quantile_shift, settings.emulator.quantile_tolerance,
                last.max_variance_ratio);
  }
  const int percent = static_cast<int>(std::lround(100 * result.credible_level));
  for (std::size_t i = 0; i < result.parameter_names.size(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    std::printf("  %-24s mean %-12.6g sd %-12.6g MAP %-12.6g %d %% interval [%.6g, %.6g] %s (%s, contraction %.2f)\n",
                result.parameter_names[i].c_str(), result.mean[ii], result.standard_deviation[ii],
                result.map_point[ii], percent, result.credible_lower[ii], result.credible_upper[ii],
                result.parameter_units[i] == "1" ? "" : result.parameter_units[i].c_str(),
                result.identification[i].c_str(), result.contraction[ii]);
  }
  std::printf("  effective sample size %.1f of a pool of %lld\n", result.effective_sample_size,
              static_cast<long long>(result.pool.rows()));
  for (const auto& run : predictive) {
    if (run.status == "ok") std::printf("  predictive %s: %s\n", run.name.c_str(), run.signal_file.string().c_str());
    if (run.status == "failed") std::printf("  predictive %s failed: %s\n", run.name.c_str(), run.failure_reason.c_str());
  }
  for (const auto& file : {files.h5, files.posterior_csv, files.diagnostics_csv, files.json}) {
    std::printf("  written: %s\n", file.string().c_str());
  }
  std::fflush(stdout);
  // Corner plot, convergence history and predictive overlay (tools/plot_calibration.py).
  if (options.plots) rsw::tools::run_plot_script("plot_calibration.py", {files.json.string()});
}

}  // namespace

void add_calibrate_command(CLI::App& app, ForwardModelFactory model_factory) {
  auto options = std::make_shared<CalibrateOptions>();
  auto factory = std::make_shared<ForwardModelFactory>(std::move(model_factory));
  CLI::App* calibrate = app.add_subcommand(
      "calibrate", "Bayesian calibration of a study's parameters against its observations (SBALC or feature emulators)");
  calibrate->add_option("study", options->study_file, "Study file (YAML) with a calibration section")->required();
  calibrate->add_option("--set", options->overrides, "Override a study key: --set key=value (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  calibrate->add_option("-o,--output", options->output_dir, "Output folder (default: study.output of the study file)");
  calibrate->add_option("--workers", options->n_workers, "Worker processes per batch; 0: one per core")
      ->capture_default_str();
  calibrate->add_flag("--resume", options->resume,
                      "Continue a calibration: reuse every finished run in <name>_calibration/");
  calibrate->add_option("--timeout", options->run_timeout,
                        "Time limit per run in seconds (0: none); a run over it is recorded as failed")
      ->check(CLI::NonNegativeNumber);
  calibrate->add_flag("-q,--quiet", options->quiet, "No progress lines");
  calibrate->add_flag("!--no-plots", options->plots,
                      "Do not draw the corner, convergence and predictive plots (tools/plot_calibration.py)");
  calibrate->callback([options, factory]() {
    try {
      run_calibrate(*options, *factory);
    } catch (const cal::CalibrationInterrupted& e) {
      throw std::runtime_error(std::string(e.what()) + "; continue it with: rsw calibrate " + options->study_file +
                               " --resume");
    }
  });
}

}  // namespace rsw::tools
