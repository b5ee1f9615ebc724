// `rsw calibrate STUDY`: see calibrate_command.hpp. The calibration itself is
// calibration::Calibration; this file loads the study and its observations, runs the
// posterior-predictive runs through the farm, has the result files written
// (calibration/calibration_results_file.hpp) and prints the report.
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
#include "calibration/calibration_results_file.hpp"
#include "calibration/calibration_study.hpp"
#include "calibration/farm.hpp"
#include "calibration/study.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::tools {
namespace {

namespace fs = std::filesystem;
namespace cal = calibration;

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
  bool overwrite = false;
};

// --- posterior-predictive runs -----------------------------------------------------

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

std::vector<cal::PredictiveRun> run_predictive(const cal::Study& study, const cal::ForwardModel& model,
                                          const cal::CalibrationResult& result, const cal::CalibrationSettings& settings,
                                          fem::OutputFolder& calibration_folder,
                                          const cal::FarmOptions& farm_options) {
  std::vector<cal::PredictiveRun> runs;
  runs.push_back({"posterior_mean", result.mean, {}, {}, {}, {}});
  const Eigen::Index n_samples = result.samples.rows();
  const int k = settings.n_predictive_samples;
  for (int j = 0; j < k && n_samples > 0; ++j) {
    // Evenly spread over the resampled draws (whose order is the pool's random order).
    const auto row = static_cast<Eigen::Index>((static_cast<double>(j) + 0.5) * static_cast<double>(n_samples) / k);
    runs.push_back({"posterior_sample_" + std::to_string(j + 1), result.samples.row(row).transpose(), {}, {}, {}, {}});
  }
  const fs::path predictive_folder = calibration_folder.path() / "predictive";
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
  const fs::path file = calibration_folder.path() / "predictive.h5";
  bool resume = false;
  if (fs::exists(file)) {
    try {
      cal::check_same_design(cal::read_study_results(file), design, file);
      resume = true;
    } catch (const cal::FarmError&) {
      calibration_folder.clear({file.filename().string(), predictive_folder.filename().string()});
    }
  }
  calibration_folder.record(file.filename().string());
  calibration_folder.record(predictive_folder.filename().string());
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
  for (const auto& warning : observations.warnings)
    std::printf("calibration %s: warning: %s\n", study.name().c_str(), warning.c_str());
  const cal::GaussianLikelihood likelihood = cal::make_likelihood(study, settings, observations);
  const std::unique_ptr<cal::ForwardModel> model = make_forward_model(study, factory);
  study.check_model_inputs(*model);  // the runs go anywhere in the prior

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
  // The output folder (shared with the study's runs), then this calibration's own folder
  // (exclusive: a second calibration into it is refused at once). The result files of
  // an earlier session go when the calibration starts (not when it is refused at its
  // start): one that fails then leaves none that look current.
  fem::OutputFolder output_folder = claim_study_folder(study, "calibrate", options.overwrite);
  const cal::CalibrationFiles result_files = cal::calibration_files(study);
  std::vector<std::string> own_names = {calibration_folder.filename().string()};
  for (const auto& file : {result_files.h5, result_files.posterior_csv, result_files.diagnostics_csv, result_files.json})
    own_names.push_back(file.filename().string());
  output_folder.check(own_names);
  const auto holds_runs = [&] {  // anything but the marker
    if (!fs::is_directory(calibration_folder)) return false;
    for (const auto& entry : fs::directory_iterator(calibration_folder))
      if (entry.path().filename() != fem::OutputFolder::marker_name) return true;
    return false;
  };
  if (!options.resume && holds_runs()) {
    throw std::runtime_error("calibration folder '" + calibration_folder.string() +
                             "' exists already; continue the calibration with --resume, or remove it to start again");
  }
  output_folder.record(own_names.front());
  fem::OutputFolderOptions own_options;
  own_options.kind = "calibrate";
  own_options.overwrite = options.overwrite;
  own_options.evidence = {"evaluations", "predictive", "predictive.h5"};  // of a version before the marker
  fem::OutputFolder own_folder(calibration_folder, own_options);
  own_folder.record("evaluations");
  calibration_options.on_start = [&] {
    output_folder.clear({own_names.begin() + 1, own_names.end()});
    for (auto name = own_names.begin() + 1; name != own_names.end(); ++name) output_folder.record(*name);
  };
  if (!options.quiet) {
    std::cerr << "calibration " << study.name() << ": " << observations.values.rows() << " replicate"
              << (observations.values.rows() == 1 ? "" : "s") << " of " << observations.values.cols() << " feature"
              << (observations.values.cols() == 1 ? "" : "s") << " ("
              << (settings.observation_source == cal::ObservationSource::features_file ? "features file"
                                                                                       : "signal files")
              << "), noise " << cal::noise_kind_name(settings.noise.kind) << "; ";
    if (settings.method == cal::CalibrationMethod::sbalc) {
      std::cerr << "SBALC pool " << settings.sbalc.pool_size << ", " << settings.sbalc.n_initial
                << " initial points, batches of " << settings.sbalc.batch_size << ", at most "
                << settings.sbalc.max_evaluations << " runs, nugget " << cal::nugget_name(settings.sbalc.gp.nugget_mode)
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
  const std::vector<cal::PredictiveRun> predictive =
      run_predictive(study, *model, result, settings, own_folder, calibration_options.farm);

  const cal::CalibrationFiles files = cal::write_calibration_results(study, result, settings, likelihood, observations,
                                                                     predictive, initial, calibration_folder);

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
  calibrate->add_option("-o,--output", options->output_dir,
                        "Output folder (default: study.output of the study file): new, empty, or one rsw made before");
  calibrate->add_flag("--overwrite", options->overwrite,
                      "Write into a non-empty folder rsw did not make (rsw still removes and replaces only its own "
                      "files)");
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
