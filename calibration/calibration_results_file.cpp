// The result files of a calibration; what each holds: calibration_results_file.hpp and
// docs/CALIBRATION.md, "`rsw calibrate`".
#include "calibration/calibration_results_file.hpp"

#include "calibration/features.hpp"
#include "calibration/study_results_file.hpp"

#include "fem/hdf5_file.hpp"
#include "fem/text.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rsw::calibration {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

constexpr int calibration_format_version = 1;
const char* const calibration_format = "rsw calibration results";

// --- text helpers ------------------------------------------------------------------




Json finite_or_null(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

Json vector_json(const Eigen::VectorXd& values) {
  Json array = Json::array();
  for (Eigen::Index i = 0; i < values.size(); ++i) array.push_back(finite_or_null(values[i]));
  return array;
}

std::vector<double> to_std(const Eigen::VectorXd& values) { return {values.data(), values.data() + values.size()}; }






// --- result files --------------------------------------------------------------------

}  // namespace

CalibrationFiles calibration_files(const Study& study) {
  const fs::path folder = study.output_folder();
  const std::string name = study.name();
  return {folder / (name + "_calibration.h5"), folder / (name + "_posterior.csv"),
          folder / (name + "_diagnostics.csv"), folder / (name + "_calibration.json")};
}

namespace {

std::string unit_label(const std::string& name, const std::string& unit) {
  return unit.empty() ? name : name + " [" + unit + "]";
}

void write_posterior_csv(const fs::path& path, const CalibrationResult& result) {
  std::ostringstream csv;
  csv << "sample";
  for (std::size_t i = 0; i < result.parameter_names.size(); ++i) {
    csv << "," << fem::csv_text(unit_label(result.parameter_names[i], result.parameter_units[i]));
  }
  csv << "\n";
  for (Eigen::Index s = 0; s < result.samples.rows(); ++s) {
    csv << s;
    for (Eigen::Index i = 0; i < result.samples.cols(); ++i) csv << "," << fem::number_text(result.samples(s, i));
    csv << "\n";
  }
  fem::write_text_file(path, csv.str());
}

// Columns of the emulator route's diagnostics table, then one variance ratio per feature.
const std::vector<std::string> emulator_diagnostics_columns = {
    "iteration", "n_points", "n_evaluations", "log_evidence", "evidence_relative_error", "smc_log_evidence",
    "n_temperatures", "pool_ess", "emulator_influence", "influence_standard_error", "plug_in_ess", "quantile_shift", "influence_settled",
    "quantiles_settled", "counted", "max_variance_ratio", "n_focused", "focused_weight", "n_chosen", "seconds"};

Eigen::MatrixXd emulator_diagnostics_table(const CalibrationResult& result) {
  const auto p = static_cast<Eigen::Index>(result.feature_names.size());
  const auto n_fixed = static_cast<Eigen::Index>(emulator_diagnostics_columns.size());
  const auto d = static_cast<Eigen::Index>(result.parameter_names.size());
  Eigen::MatrixXd table(static_cast<Eigen::Index>(result.emulator_history.size()), n_fixed + p + d);
  for (std::size_t k = 0; k < result.emulator_history.size(); ++k) {
    const EmulatorIteration& it = result.emulator_history[k];
    const auto r = static_cast<Eigen::Index>(k);
    table.row(r).head(n_fixed) << static_cast<double>(k), it.n_points, it.n_evaluations, it.log_evidence,
        it.evidence_relative_error, it.smc_log_evidence, it.n_temperatures, it.pool_ess, it.emulator_influence,
        it.influence_standard_error, it.plug_in_ess, it.quantile_shift, it.influence_settled ? 1.0 : 0.0, it.quantiles_settled ? 1.0 : 0.0,
        it.counted ? 1.0 : 0.0, it.max_variance_ratio, static_cast<double>(it.n_focused), it.focused_weight,
        static_cast<double>(it.chosen_points.rows()), it.seconds;
    table.row(r).segment(n_fixed, p) = it.variance_ratios.transpose();
    table.row(r).tail(d) = it.parameter_influence.size() == d
                               ? Eigen::RowVectorXd(it.parameter_influence.transpose())
                               : Eigen::RowVectorXd::Constant(d, std::numeric_limits<double>::quiet_NaN());
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

Eigen::MatrixXd diagnostics_table(const CalibrationResult& result) {
  if (result.method == CalibrationMethod::emulator) return emulator_diagnostics_table(result);
  const auto d = static_cast<Eigen::Index>(result.parameter_names.size());
  const auto n_columns = static_cast<Eigen::Index>(diagnostics_columns.size()) + d;
  Eigen::MatrixXd table(static_cast<Eigen::Index>(result.history.size()), n_columns);
  for (std::size_t k = 0; k < result.history.size(); ++k) {
    const SbalcIteration& it = result.history[k];
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

std::vector<std::string> diagnostics_header(const CalibrationResult& result) {
  if (result.method == CalibrationMethod::emulator) {
    std::vector<std::string> header = emulator_diagnostics_columns;
    for (const auto& name : result.feature_names) header.push_back("variance_ratio:" + name);
    for (const auto& name : result.parameter_names) header.push_back("influence:" + name);
    return header;
  }
  std::vector<std::string> header = diagnostics_columns;
  for (const auto& name : result.parameter_names) header.push_back("length_scale:" + name);
  return header;
}

void write_diagnostics_csv(const fs::path& path, const CalibrationResult& result) {
  const Eigen::MatrixXd table = diagnostics_table(result);
  const std::vector<std::string> header = diagnostics_header(result);
  std::ostringstream csv;
  for (std::size_t c = 0; c < header.size(); ++c) csv << (c ? "," : "") << fem::csv_text(header[c]);
  csv << "\n";
  for (Eigen::Index r = 0; r < table.rows(); ++r) {
    for (Eigen::Index c = 0; c < table.cols(); ++c) {
      const bool count = c < 3;
      csv << (c ? "," : "") << (count ? std::to_string(static_cast<long long>(table(r, c))) : fem::number_text(table(r, c)));
    }
    csv << "\n";
  }
  fem::write_text_file(path, csv.str());
}

Json parameters_json(const Study& study, const CalibrationResult& result) {
  Json parameters = Json::array();
  const ParameterSpace& space = study.parameter_space();
  for (std::size_t i = 0; i < space.n_parameters(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const Parameter& p = space.parameter(i);
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

}  // namespace

std::size_t n_iterations(const CalibrationResult& result) {
  return result.method == CalibrationMethod::emulator ? result.emulator_history.size() : result.history.size();
}

namespace {

// The emulator route's settings and last iteration (null for SBALC).
Json emulator_json(const CalibrationResult& result, const CalibrationSettings& settings) {
  if (result.method != CalibrationMethod::emulator || result.emulator_history.empty()) return nullptr;
  const EmulatorIteration& last = result.emulator_history.back();
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

Json noise_json(const GaussianLikelihood& likelihood, const CalibrationSettings& settings,
                const Observations& observations) {
  Json features = Json::array();
  for (int j = 0; j < likelihood.n_features(); ++j) {
    const std::string& name = likelihood.feature_names()[static_cast<std::size_t>(j)];
    const double measurement = likelihood.measurement_variances()[j];
    const double total = likelihood.variances()[j];
    features.push_back({{"name", name},
                        {"unit", describe_feature(name).unit},
                        {"observed_mean", observations.values.col(j).mean()},
                        {"measurement_standard_deviation", std::sqrt(measurement)},
                        {"discrepancy_standard_deviation", std::sqrt(std::max(0.0, total - measurement))},
                        {"total_standard_deviation", std::sqrt(total)}});
  }
  return {{"kind", noise_kind_name(settings.noise.kind)},
          {"n_replicates", likelihood.n_replicates()},
          {"features", features}};
}

void write_h5(const fs::path& path, const Study& study, const CalibrationResult& result,
              const CalibrationSettings& settings, const GaussianLikelihood& likelihood,
              const Observations& observations, const std::vector<PredictiveRun>& predictive,
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
  h5.write("/posterior/samples", farm_detail::to_row_major(result.samples));
  h5.write("/posterior/pool", farm_detail::to_row_major(result.pool));
  h5.write("/posterior/weights", to_std(result.pool_weights));
  h5.write("/posterior/pool_log_likelihood", to_std(result.pool_log_likelihood));
  h5.write("/posterior/mean", to_std(result.mean));
  h5.write("/posterior/standard_deviation", to_std(result.standard_deviation));
  h5.write("/posterior/correlation", farm_detail::to_row_major(result.correlation));
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
  h5.write("/diagnostics/table", farm_detail::to_row_major(diagnostics_table(result)));
  h5.set_attribute("/diagnostics/table", "columns", Json(diagnostics_header(result)).dump());
  Json refusals = Json::object();  // by iteration, the stopping guards that failed (sbalc.hpp)
  for (std::size_t k = 0; k < result.history.size(); ++k)
    if (!result.history[k].refusal.empty()) refusals[std::to_string(k)] = result.history[k].refusal;
  h5.write_string("/diagnostics/refusals", refusals.dump(1));
  const auto d = static_cast<Eigen::Index>(result.parameter_names.size());
  std::vector<Eigen::VectorXd> chosen_rows;
  const std::size_t n_iterations =
      result.method == CalibrationMethod::emulator ? result.emulator_history.size() : result.history.size();
  for (std::size_t k = 0; k < n_iterations; ++k) {
    const Eigen::MatrixXd& chosen = result.method == CalibrationMethod::emulator
                                        ? result.emulator_history[k].chosen_points
                                        : result.history[k].chosen_points;
    for (Eigen::Index r = 0; r < chosen.rows(); ++r) {
      Eigen::VectorXd row(d + 1);
      row << static_cast<double>(k), unit_to_physical(study.parameter_space(), chosen.row(r).transpose());
      chosen_rows.push_back(row);
    }
  }
  Eigen::MatrixXd chosen(static_cast<Eigen::Index>(chosen_rows.size()), d + 1);
  for (std::size_t r = 0; r < chosen_rows.size(); ++r) chosen.row(static_cast<Eigen::Index>(r)) = chosen_rows[r].transpose();
  h5.write("/diagnostics/chosen_points", farm_detail::to_row_major(chosen));
  h5.set_attribute("/diagnostics/chosen_points", "columns", "iteration, then theta in parameter units");

  h5.set_attribute("/", "method", calibration_method_name(result.method));
  if (result.method == CalibrationMethod::emulator) {
    // The runs the feature emulators learnt from (u in [0,1]^d), ln L of each, and each
    // feature's numerical noise tau_j (SI feature units).
    h5.write("/emulator/design_unit", farm_detail::to_row_major(result.design_unit));
    h5.write("/emulator/log_likelihoods", to_std(result.design_log_likelihoods));
    h5.write("/emulator/feature_noise_standard_deviation", to_std(result.feature_noise_standard_deviations));
    h5.set_attribute("/emulator", "trend", trend_name(settings.emulator.gp.trend));
  } else {
  // GP of the log-likelihood (inputs u in [0,1]^d).
  h5.write("/gp/length_scales", to_std(result.hyperparameters.length_scales));
  h5.write("/gp/signal_variance", std::vector<double>{result.hyperparameters.signal_variance});
  h5.write("/gp/noise_variance", std::vector<double>{result.hyperparameters.noise_variance});
  h5.write("/gp/design_unit", farm_detail::to_row_major(result.design_unit));
  h5.write("/gp/log_likelihoods", to_std(result.design_log_likelihoods));
  h5.set_attribute("/gp", "kernel", kernel_name(settings.sbalc.gp.kernel));
  h5.set_attribute("/gp", "trend_used", trend_name(result.trend_used));
  h5.set_attribute("/gp", "nugget", nugget_name(settings.sbalc.gp.nugget_mode));
  h5.set_attribute("/gp", "noise_standard_deviation", result.noise_standard_deviation);
  }

  // Observations and noise estimate (SI feature units).
  h5.write("/observations/values", farm_detail::to_row_major(observations.values));
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
    const CalibrationEvaluation& e = result.evaluations[r];
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
  h5.write("/evaluations/table", farm_detail::to_row_major(runs));
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
  h5.write("/predictive/points", farm_detail::to_row_major(predictive_points));
  h5.write_string("/predictive/names", predictive_names.dump());
  h5.close();
}

}  // namespace

CalibrationFiles write_calibration_results(const Study& study, const CalibrationResult& result,
                                           const CalibrationSettings& settings, const GaussianLikelihood& likelihood,
                                           const Observations& observations, const std::vector<PredictiveRun>& predictive,
                                           const InitialRuns& initial, const fs::path& calibration_folder) {
  const fs::path output = study.output_folder();
  // Summary.
  const CalibrationFiles files = calibration_files(study);
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
      {"method", calibration_method_name(result.method)},
      {"warnings", result.warnings},
      {"converged", result.converged},
      {"stop_reason", result.stop_reason},
      {"evidence",
       {{"log_evidence", result.log_evidence},
        {"log_evidence_lower", finite_or_null(result.log_evidence_lower)},
        {"log_evidence_upper", finite_or_null(result.log_evidence_upper)},
        {"ratio", finite_or_null(result.ratio)},
        {"noise_ratio", result.noise_ratio},
        {"tolerance", result.method == CalibrationMethod::sbalc ? Json(settings.sbalc.tolerance) : Json(nullptr)},
        {"tolerance_used", result.history.empty() ? Json(nullptr) : Json(result.history.back().tolerance_used)},
        {"pool_relative_error", finite_or_null(result.pool_relative_error)},
        {"pool_effective_sample_size", result.pool_ess},
        {"pool_ess_threshold", result.pool_ess_threshold}}},
      {"n_evaluations", result.n_evaluations},
      {"n_reused", result.n_reused},
      {"n_from_study", result.n_from_study},
      {"n_failed", result.n_failed},
      {"n_warned", std::count_if(result.evaluations.begin(), result.evaluations.end(),
                                 [](const CalibrationEvaluation& e) { return !e.warnings.empty(); })},
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
       {{"source", settings.observation_source == ObservationSource::features_file ? "features_file"
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
  fem::write_text_file(files.json, summary.dump(2) + "\n");
  return files;
}

}  // namespace rsw::calibration
