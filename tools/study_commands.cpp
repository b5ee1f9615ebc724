// `rsw study ...` and `rsw features FILE`: see study_commands.hpp. The run table
// <name>_runs.csv / .json (one row per design point: status, wall time, θ, features,
// failure reason, the undefined features of a successful run) is written whenever a
// study file is complete, after `run` or `merge`.
#include "tools/study_commands.hpp"
#include "tools/mpi_launcher.hpp"
#include "tools/plots.hpp"

#include "calibration/command_model.hpp"
#include "calibration/farm.hpp"
#include "calibration/features.hpp"
#include "calibration/sensitivity.hpp"
#include "calibration/signal.hpp"
#include "calibration/study.hpp"

#include "fem/config.hpp"
#include "fem/text.hpp"

#include "fem/units.hpp"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::tools {
namespace {

namespace fs = std::filesystem;
namespace cal = calibration;
using Json = nlohmann::ordered_json;

struct StudyOptions {
  std::string study_file;
  std::vector<std::string> overrides;
  std::string output_dir;
  std::size_t n_workers = 0;
  bool resume = false;
  std::string task;
  double run_timeout = 0;
  bool quiet = false;
  std::vector<std::string> parts;
  std::string format = "markdown";
  bool plots = true;
  bool overwrite = false;
};

cal::Study load_study(const StudyOptions& options) {
  cal::Study study = cal::Study::load(options.study_file, options.overrides);
  if (!options.output_dir.empty()) study.set_output_folder(options.output_dir);
  return study;
}



const char* const overwrite_help =
    "Write into a non-empty folder rsw did not make (rsw still removes and replaces only its own files)";

const char* status_name(cal::StudyResults::Status status) {
  switch (status) {
    case cal::StudyResults::Status::ok:
      return "ok";
    case cal::StudyResults::Status::failed:
      return "failed";
    case cal::StudyResults::Status::pending:
      return "pending";
  }
  return "unknown";
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write '" + path.string() + "'");
}

// Why feature `name` is NaN in a successful run (features.hpp, "Undefined features").
std::string undefined_feature_reason(const std::string& name) {
  const std::string why = cal::why_undefined(name);
  return why.empty() ? "the model returned NaN" : why;
}

// <name>_runs.csv and <name>_runs.json in the output folder. A successful run whose
// signal's shape leaves features undefined has them as nan (CSV) / null (JSON), their
// names in the CSV column undefined_features (space-separated) and names with reasons
// in the JSON object "undefined_features".
std::vector<fs::path> write_run_tables(const cal::Study& study, const cal::StudyResults& results,
                                       fem::OutputFolder& output) {
  const auto& names = results.parameter_names;
  const auto& features = results.feature_names;
  std::ostringstream csv;
  csv << "index,status,wall_time_s,rank";
  for (std::size_t j = 0; j < names.size(); ++j) {
    csv << "," << fem::csv_text(names[j] + " [" + study.parameter_space().parameter(j).unit + "]");
  }
  for (const auto& name : features) {
    const std::string unit = cal::describe_feature(name).unit;
    csv << "," << fem::csv_text(unit.empty() ? name : name + " [" + unit + "]");
  }
  csv << ",failure_reason,undefined_features,warnings\n";
  Json runs = Json::array();
  for (std::size_t i = 0; i < results.n_points(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    csv << i << "," << status_name(results.status[i]) << "," << fem::number_text(results.wall_time[ii]) << ","
        << results.rank[i];
    Json theta = Json::object(), y = Json::object(), undefined = Json::object();
    std::string undefined_names;
    for (std::size_t j = 0; j < names.size(); ++j) {
      csv << "," << fem::number_text(results.points(ii, static_cast<Eigen::Index>(j)));
      theta[names[j]] = results.points(ii, static_cast<Eigen::Index>(j));
    }
    for (std::size_t k = 0; k < features.size(); ++k) {
      const double value = results.features(ii, static_cast<Eigen::Index>(k));
      csv << "," << fem::number_text(value);
      y[features[k]] = std::isfinite(value) ? Json(value) : Json(nullptr);
      if (results.status[i] == cal::StudyResults::Status::ok && std::isnan(value)) {
        undefined_names += (undefined_names.empty() ? "" : " ") + features[k];
        undefined[features[k]] = undefined_feature_reason(features[k]);
      }
    }
    csv << "," << fem::csv_text(results.failure_reasons[i]) << "," << fem::csv_text(undefined_names) << ","
        << fem::csv_text(results.warnings[i]) << "\n";
    Json run = {{"index", i}, {"status", status_name(results.status[i])}, {"theta", theta}, {"features", y}};
    run["wall_time"] = std::isfinite(results.wall_time[ii]) ? Json(results.wall_time[ii]) : Json(nullptr);
    if (results.status[i] == cal::StudyResults::Status::failed) run["failure_reason"] = results.failure_reasons[i];
    if (!undefined.empty()) run["undefined_features"] = undefined;
    if (!results.warnings[i].empty()) run["warnings"] = results.warnings[i];
    if (!results.swept_parameter.empty()) {
      const int swept = results.swept_parameter[i];
      run["swept_parameter"] = swept < 0 ? Json(nullptr) : Json(names[static_cast<std::size_t>(swept)]);
    }
    runs.push_back(run);
  }
  Json root = {{"study", study.name()}, {"parameters", names}, {"features", features}, {"runs", runs}};
  const fs::path folder = output.path();
  const fs::path csv_path = folder / (study.name() + "_runs.csv");
  const fs::path json_path = folder / (study.name() + "_runs.json");
  output.check({csv_path.filename().string(), json_path.filename().string()});
  output.record(csv_path.filename().string());
  output.record(json_path.filename().string());
  write_text(csv_path, csv.str());
  write_text(json_path, root.dump(2) + "\n");
  return {csv_path, json_path};
}

// The failed runs with their reasons, then per feature the successful runs that leave
// it undefined (NaN), e.g. "  R_beta undefined in 7 ok runs (the dynamic resistance ...)".
void print_failures(const cal::StudyResults& results) {
  for (std::size_t i = 0; i < results.n_points(); ++i) {
    if (results.status[i] == cal::StudyResults::Status::failed) {
      std::cout << "  failed run " << i << ": " << results.failure_reasons[i] << "\n";
    }
  }
  for (std::size_t i = 0; i < results.n_points(); ++i) {
    if (!results.warnings[i].empty()) std::cout << "  run " << i << " warns: " << results.warnings[i] << "\n";
  }
  for (std::size_t k = 0; k < results.feature_names.size(); ++k) {
    std::size_t n_undefined = 0;
    for (std::size_t i = 0; i < results.n_points(); ++i) {
      if (results.status[i] == cal::StudyResults::Status::ok &&
          std::isnan(results.features(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)))) {
        ++n_undefined;
      }
    }
    if (n_undefined > 0) {
      const std::string& name = results.feature_names[k];
      std::cout << "  " << name << " undefined in " << n_undefined << " ok run" << (n_undefined == 1 ? "" : "s")
                << " (" << undefined_feature_reason(name) << ")\n";
    }
  }
}

void run_study(const StudyOptions& options, const ForwardModelFactory& factory) {
  const cal::Study study = load_study(options);
  cal::FarmOptions farm_options;
  farm_options.n_workers = options.n_workers;
  farm_options.resume = options.resume;
  if (!options.task.empty()) farm_options.task = cal::TaskPartition::parse(options.task);
  farm_options.run_timeout = options.run_timeout;
  farm_options.progress = options.quiet ? nullptr : &std::cerr;
  farm_options.started_by_mpi_launcher = started_by_mpi_launcher();
  const std::unique_ptr<cal::ForwardModel> model = make_forward_model(study, factory);
  const cal::StudyDesign design = study.design();
  study.check_model_inputs(*model, design.points);
  const fs::path file = cal::task_results_file(study.results_file(), farm_options.task);
  fem::OutputFolder output = claim_study_folder(study, "study", options.overwrite, {file.filename().string()});
  output.check({file.filename().string()});
  output.record(file.filename().string());
  cal::EvaluationFarm farm(*model, design, file, farm_options);
  const cal::FarmSummary summary = farm.run();
  if (!summary.writer) return;  // other MPI ranks: rank 0 reports

  std::cout << "study " << study.name() << (farm_options.task.is_whole() ? "" : " task " + farm_options.task.describe())
            << ": " << summary.n_ok + summary.n_failed << "/" << summary.n_assigned << " runs done ("
            << summary.n_evaluated << " now, " << summary.n_done_before << " before), " << summary.n_failed
            << " failed, " << cal::format_duration(summary.elapsed) << " on " << summary.n_workers << " worker"
            << (summary.n_workers == 1 ? "" : "s") << (summary.n_ranks > 1 ? " over " + std::to_string(summary.n_ranks) + " MPI ranks" : "")
            << "\n  results: " << file.string() << "\n";
  const cal::StudyResults results = cal::read_study_results(file);
  print_failures(results);
  if (summary.interrupted) {
    throw std::runtime_error("study '" + study.name() + "' interrupted; continue it with: rsw study run " +
                             options.study_file + " --resume" + (options.task.empty() ? "" : " --task " + options.task));
  }
  if (!summary.complete) return;
  if (farm_options.task.is_whole()) {
    for (const auto& table : write_run_tables(study, results, output))
      std::cout << "  table: " << table.string() << "\n";
    if (summary.n_ok == 0 && summary.n_failed > 0)
      throw std::runtime_error("study '" + study.name() + "': every one of its " + std::to_string(summary.n_failed) +
                               " runs failed (reasons above and in the run table)");
  } else {
    std::cout << "  when every task is done: rsw study merge " << options.study_file << " "
              << cal::task_results_file(study.results_file(), cal::TaskPartition{0, farm_options.task.count}).string()
              << " ...\n";
  }
}

void merge_study(const StudyOptions& options) {
  const cal::Study study = load_study(options);
  std::vector<fs::path> parts(options.parts.begin(), options.parts.end());
  fem::OutputFolder output = claim_study_folder(study, "study", options.overwrite);
  output.check({study.results_file().filename().string()});
  output.record(study.results_file().filename().string());
  const cal::MergeSummary summary = cal::merge_study_files(study.design(), study.results_file(), parts);
  std::cout << "study " << study.name() << ": merged " << parts.size() << " file" << (parts.size() == 1 ? "" : "s")
            << " into " << study.results_file().string() << ": " << summary.n_added << " runs added, "
            << summary.n_duplicates << " already present; " << summary.n_ok << " ok, " << summary.n_failed
            << " failed, " << summary.n_pending << " not run\n";
  const cal::StudyResults results = cal::read_study_results(study.results_file());
  print_failures(results);
  if (summary.n_pending == 0) {
    for (const auto& table : write_run_tables(study, results, output))
      std::cout << "  table: " << table.string() << "\n";
  }
}

void study_sensitivity(const StudyOptions& options) {
  const cal::Study study = load_study(options);
  const cal::StudyResults results = cal::read_study_results(study.results_file());
  // Earlier tables go first: an analysis that fails leaves none that look current.
  fem::OutputFolder output = claim_study_folder(study, "sensitivity", options.overwrite);
  const std::vector<std::string> tables = cal::sensitivity_table_names(study.name());
  output.clear(tables);
  for (const auto& table : tables) output.record(table);
  const cal::SensitivityReport report = cal::analyse_sensitivity(study.design(), results, study.pce_options());
  std::cout << cal::format_sensitivity_summary(report);
  std::string json;
  for (const auto& table : cal::write_sensitivity_tables(report, output.path(), study.name())) {
    std::cout << "table: " << table.string() << "\n";
    if (table.extension() == ".json") json = table.string();
  }
  std::cout.flush();
  // Sobol heatmaps, features x parameters (tools/plot_study.py, paper Figs. 4-5).
  if (options.plots && !json.empty()) rsw::tools::run_plot_script("plot_study.py", {"sobol", json});
}

void show_study(const StudyOptions& options) {
  const cal::Study study = load_study(options);
  const cal::StudyDesign design = study.design();
  std::cout << study.config().to_yaml();
  std::cout << "# design: " << design.kind << ", " << design.points.rows() << " runs of "
            << design.parameters.n_parameters() << " parameters, " << design.feature_names.size() << " features\n"
            << "# results: " << study.results_file().string() << "\n";
  if (!study.case_file().empty()) std::cout << "# weld case: " << study.case_file().string() << "\n";
  if (study.model_kind() == cal::ModelKind::command) {
    std::cout << "# command:";
    for (const auto& word : study.command()) std::cout << " " << word;
    std::cout << "\n";
  }
}

// --- features ----------------------------------------------------------------------

// Units to print features in (JSON keeps SI).
std::string display_unit(const cal::FeatureInfo& info) {
  if (info.unit == "ohm") return "uohm";
  if (info.unit == "ohm/s") return "uohm/ms";
  if (info.unit == "s") return "ms";
  if (info.unit == "m") return info.group == "displacement" ? "um" : "mm";
  if (info.unit == "m/s") return "mm/s";
  return info.unit;
}

struct FeaturesOptions {
  std::string signal_file;
  std::string json_file;
};

// A signal file that cannot be read or has no weld in it is bad input (exit code 2).
void print_features(const FeaturesOptions& options) {
  std::vector<std::string> warnings;
  cal::Signal signal(Eigen::VectorXd{});
  try {
    signal = cal::read_signal_csv(options.signal_file, warnings);
  } catch (const cal::SignalError& e) {
    throw fem::ConfigError(e.what());
  }
  for (const auto& warning : warnings) std::fprintf(stderr, "rsw: warning: %s\n", warning.c_str());
  const cal::FeatureSettings settings;
  cal::FeatureValues values;
  cal::WeldStage stage;
  try {
    stage = cal::find_weld_stage(signal, settings.weld_current_fraction);
    values = cal::extract_features(signal, settings);
  } catch (const cal::FeatureError& e) {
    throw fem::ConfigError(options.signal_file + ": " + e.what());
  } catch (const cal::SignalError& e) {
    throw fem::ConfigError(options.signal_file + ": " + e.what());
  }
  std::printf("features of %s\n", options.signal_file.c_str());
  std::printf("  weld stage %.2f .. %.2f ms, peak current %.3f kA\n", stage.start * 1e3, stage.end * 1e3,
              stage.peak_current * 1e-3);
  const double raw_step = cal::median_step(signal.time());
  std::printf("  feature grid %g ms (signal sampled every %g ms)%s\n", settings.resample_step * 1e3, raw_step * 1e3,
              raw_step > 1.5 * settings.resample_step
                  ? ": coarser than the grid, so what lies between samples (a resistance peak) is lost"
                  : "");
  Json features = Json::object();
  for (std::size_t k = 0; k < values.size(); ++k) {
    const std::string& name = values.names()[k];
    const double value = values.values()[k];
    const cal::FeatureInfo info = cal::describe_feature(name);
    const std::string reason = values.undefined_reason(name);
    if (!reason.empty()) {
      // The signal is valid but its shape leaves this feature undefined (features.hpp).
      std::printf("  %-12s %-13s undefined (%s)\n", name.c_str(), info.group.c_str(), reason.c_str());
      features[name] = {{"value", nullptr}, {"unit", info.unit}, {"group", info.group}, {"reason", reason}};
      continue;
    }
    const std::string shown_unit = display_unit(info);
    const double shown = info.unit.empty() ? value : fem::convert_units(value, info.unit, shown_unit);
    std::printf("  %-12s %-13s %14.6g %s\n", name.c_str(), info.group.c_str(), shown, shown_unit.c_str());
    features[name] = {{"value", value}, {"unit", info.unit}, {"group", info.group}};
  }
  if (options.json_file.empty()) return;
  Json root = {{"file", options.signal_file},
               {"weld_stage", {{"start", stage.start}, {"end", stage.end}, {"peak_current", stage.peak_current}}},
               {"feature_grid_step", settings.resample_step},
               {"signal_step", raw_step},
               {"units", "SI (temperatures in degC); times from the weld start, weld_stage on the record's clock"},
               {"features", features}};
  const fs::path json_path(options.json_file);
  if (json_path.has_parent_path()) fs::create_directories(json_path.parent_path());
  write_text(json_path, root.dump(2) + "\n");
  std::printf("  written: %s\n", options.json_file.c_str());
}

}  // namespace

std::unique_ptr<cal::ForwardModel> make_forward_model(const cal::Study& study, const ForwardModelFactory& factory) {
  if (study.model_kind() != cal::ModelKind::command) {
    std::unique_ptr<cal::ForwardModel> model = factory(study);
    if (!model) throw std::runtime_error("study '" + study.name() + "': no forward model");
    return model;
  }
  std::vector<std::string> arguments = study.command();
  if (!fs::path(arguments[0]).is_absolute()) {
    const char* path = std::getenv("PATH");
    const std::string directories = path ? path : "";
    std::string found;
    std::size_t start = 0;
    while (found.empty() && start <= directories.size()) {
      const std::size_t colon = std::min(directories.find(':', start), directories.size());
      const std::string directory = directories.substr(start, colon - start);
      const fs::path candidate = fs::path(directory.empty() ? "." : directory) / arguments[0];
      std::error_code error;
      if (fs::is_regular_file(candidate, error) && ::access(candidate.c_str(), X_OK) == 0)
        found = fs::absolute(candidate).string();
      start = colon + 1;
    }
    if (found.empty()) {
      study.config().fail("model.command", "no program '" + arguments[0] +
                                               "' in the study file's folder or on PATH (" + directories +
                                               "); allowed: an executable file (relative to the study file's "
                                               "folder, or absolute), or a program on PATH, then its arguments");
    }
    arguments[0] = found;
  }
  return std::make_unique<cal::CommandModel>(std::move(arguments), study.parameter_space().names(),
                                             study.feature_names(), fs::path{});  // TMPDIR at run time
}

fem::OutputFolder claim_study_folder(const cal::Study& study, const std::string& kind, bool overwrite,
                                     const std::vector<std::string>& evidence) {
  const std::string name = study.name();
  fem::OutputFolderOptions options;
  options.kind = kind;
  options.overwrite = overwrite;
  options.shared = true;
  options.evidence = {name + ".h5", name + "_runs.csv", name + "_runs.json", name + "_calibration",
                      name + "_calibration.json"};
  for (const auto& table : cal::sensitivity_table_names(name)) options.evidence.push_back(table);
  options.evidence.insert(options.evidence.end(), evidence.begin(), evidence.end());
  return fem::OutputFolder(study.output_folder(), options);
}

void add_study_commands(CLI::App& app, ForwardModelFactory model_factory) {
  auto options = std::make_shared<StudyOptions>();
  auto factory = std::make_shared<ForwardModelFactory>(std::move(model_factory));
  CLI::App* study = app.add_subcommand("study", "Designs, sweeps and sensitivity studies of the forward model");
  study->require_subcommand(1);

  const auto add_study_file = [options](CLI::App* command) {
    command->add_option("study", options->study_file, "Study file (YAML)")->required();
    command->add_option("--set", options->overrides, "Override a study key: --set key=value (repeatable)")
        ->take_all()
        ->allow_extra_args(false);
    command->add_option("-o,--output", options->output_dir,
                        "Output folder (default: study.output of the study file): new, empty, or one rsw made before");
  };

  CLI::App* run = study->add_subcommand("run", "Evaluate the study's design (parallel, resumable; MPI under mpirun)");
  add_study_file(run);
  run->add_option("--workers", options->n_workers,
                  "Worker processes (per MPI rank under mpirun); 0: one per core, one per rank under MPI")
      ->capture_default_str();
  run->add_flag("--resume", options->resume, "Continue an existing results file without repeating finished runs");
  run->add_option("--task", options->task, "Array-job task i/n: evaluate the points with index % n == i into a partial file");
  run->add_option("--timeout", options->run_timeout, "Time limit per run in seconds (0: none); a run over it is recorded as failed")
      ->check(CLI::NonNegativeNumber);
  run->add_flag("-q,--quiet", options->quiet, "No progress lines");
  run->add_flag("--overwrite", options->overwrite, overwrite_help);
  run->callback([options, factory]() { run_study(*options, *factory); });

  CLI::App* merge = study->add_subcommand("merge", "Merge the partial files of array-job tasks into the study file");
  add_study_file(merge);
  merge->add_option("parts", options->parts, "Partial results files (.task-i-of-n.h5)")->required();
  merge->add_flag("--overwrite", options->overwrite, overwrite_help);
  merge->callback([options]() { merge_study(*options); });

  CLI::App* sensitivity =
      study->add_subcommand("sensitivity", "Sparse PCE and Sobol indices per feature of a finished study; CSV/JSON tables");
  add_study_file(sensitivity);
  sensitivity->add_flag("!--no-plots", options->plots, "Do not draw the Sobol heatmaps (tools/plot_study.py)");
  sensitivity->add_flag("--overwrite", options->overwrite, overwrite_help);
  sensitivity->callback([options]() { study_sensitivity(*options); });

  CLI::App* show = study->add_subcommand("show", "Print the resolved study file and the size of its design");
  add_study_file(show);
  show->callback([options]() { show_study(*options); });

  CLI::App* schema = study->add_subcommand("schema", "Print every study key with default, unit, range and doc");
  schema->add_option("--format", options->format, "Output format")
      ->check(CLI::IsMember({"markdown", "json", "json-schema"}))
      ->capture_default_str();
  schema->callback([options]() {
    const fem::ConfigSchema s = cal::study_schema();
    std::cout << (options->format == "json"          ? s.to_json()
                  : options->format == "json-schema" ? s.to_json_schema()
                                                     : s.to_markdown());
  });
}

void add_features_command(CLI::App& app) {
  auto options = std::make_shared<FeaturesOptions>();
  CLI::App* features = app.add_subcommand(
      "features", "Print the calibration features of a signal file (docs/STUDIES.md, 'The features')");
  features->add_option("file", options->signal_file, "Signal file: CSV with 'time [ms], current [kA], ...' header")
      ->required();
  features->add_option("-o,--output", options->json_file, "Also write the features as JSON (SI units) to this file");
  features->callback([options]() { print_features(*options); });
}

}  // namespace rsw::tools
