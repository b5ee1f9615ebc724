// The calibration run: SBALC batches through the evaluation farm with a θ-keyed
// evaluation cache, then the SIR posterior in physical units; see calibrate.hpp.
#include "calibration/calibrate.hpp"

#include "calibration/designs.hpp"
#include "calibration/features.hpp"

#include "fem/hdf5_file.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <ostream>
#include <regex>
#include <set>
#include <sstream>
#include <utility>

namespace rsw::calibration {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

// Thrown by the batch evaluator to stop the calibration. Sbalc::run() turns a
// std::exception of its evaluator into failed evaluations and goes on; an error of the
// farm (or an interrupt) must end the run instead, so this is deliberately not a
// std::exception. It never leaves Calibration::run().
struct AbortCalibration {
  std::string message;
  bool interrupted = false;
};

// A finished run found in the evaluation folder, or an initial run of a study.
struct CachedRun {
  bool ok = false;
  Eigen::VectorXd features;
  std::string failure_reason;
  std::string warnings;
  double wall_time = 0.0;
  bool from_study = false;
  Eigen::VectorXd theta;  // initial runs: θ as the study stored it
};

using ThetaKey = std::vector<double>;

ThetaKey key_of(const Eigen::VectorXd& theta) { return ThetaKey(theta.data(), theta.data() + theta.size()); }

std::string four_digits(std::size_t n) {
  char text[32];
  std::snprintf(text, sizeof text, "%04zu", n);
  return text;
}

const std::regex& run_file_pattern() {
  static const std::regex pattern(R"(runs_([0-9]+)\.h5)");
  return pattern;
}

// The runs_NNNN.h5 files of the folder, by number.
std::vector<std::pair<std::size_t, fs::path>> run_files(const fs::path& folder) {
  std::vector<std::pair<std::size_t, fs::path>> files;
  if (!fs::is_directory(folder)) return files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    std::smatch match;
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, match, run_file_pattern())) {
      files.emplace_back(static_cast<std::size_t>(std::stoull(match[1].str())), entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string format_theta(const ParameterSpace& parameters, const Eigen::VectorXd& theta) {
  std::ostringstream text;
  text.precision(4);
  for (std::size_t i = 0; i < parameters.n_parameters(); ++i) {
    text << (i ? ", " : "") << parameters.parameter(i).name << " = " << theta[static_cast<Eigen::Index>(i)];
  }
  return text.str();
}

// Why a run whose features are NaN (undefined for its signals' shape, features.hpp)
// has no likelihood: "feature R_beta undefined: <condition>", features with the same
// condition joined ("features R_beta, t_beta undefined: ..."), clauses by "; ".
// "" if every feature the likelihood uses is finite.
std::string undefined_features_reason(const std::vector<std::string>& names, const Eigen::VectorXd& values) {
  std::vector<std::pair<std::vector<std::string>, std::string>> groups;  // names, condition
  for (std::size_t j = 0; j < names.size(); ++j) {
    if (!std::isnan(values[static_cast<Eigen::Index>(j)])) continue;
    std::string condition = why_undefined(names[j]);
    if (condition.empty()) condition = "the model returned NaN";
    if (groups.empty() || groups.back().second != condition) groups.push_back({{}, condition});
    groups.back().first.push_back(names[j]);
  }
  std::string reason;
  for (const auto& [group, condition] : groups) {
    std::string joined;
    for (const auto& name : group) joined += (joined.empty() ? "" : ", ") + name;
    reason += (reason.empty() ? "" : "; ") + std::string(group.size() == 1 ? "feature " : "features ") + joined +
              " undefined: " + condition;
  }
  return reason;
}

std::string join_names(const std::vector<std::string>& names) {
  std::string text;
  for (const auto& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

// u → θ for the rows of a matrix.
Eigen::MatrixXd rows_to_physical(const ParameterSpace& parameters, const Eigen::MatrixXd& unit_points) {
  Eigen::MatrixXd physical(unit_points.rows(), unit_points.cols());
  for (Eigen::Index r = 0; r < unit_points.rows(); ++r) {
    physical.row(r) = unit_to_physical(parameters, unit_points.row(r).transpose()).transpose();
  }
  return physical;
}

}  // namespace

Eigen::VectorXd unit_to_physical(const ParameterSpace& parameters, const Eigen::VectorXd& unit_point) {
  constexpr double margin = 0x1.0p-53;
  const Eigen::VectorXd inside = unit_point.cwiseMax(margin).cwiseMin(1.0 - margin);
  Eigen::VectorXd clamped = unit_point;
  const std::vector<StandardSpace> spaces = parameters.standard_spaces();
  for (std::size_t i = 0; i < spaces.size(); ++i) {
    if (spaces[i] == StandardSpace::standard_normal) clamped[static_cast<Eigen::Index>(i)] = inside[static_cast<Eigen::Index>(i)];
  }
  return parameters.to_physical(parameters.unit_to_standard(clamped));
}

InitialRuns read_initial_runs(const fs::path& results_file, const StudyDesign& design) {
  InitialRuns initial;
  initial.file = results_file;
  const std::string prefix = "study results file '" + results_file.string() + "' ";
  StudyResults stored;
  try {
    stored = read_study_results(results_file);
  } catch (const FarmError& e) {
    throw CalibrationError(e.what());
  }
  const ParameterSpace& space = design.parameters;
  if (stored.parameter_names != space.names()) {
    throw CalibrationError(prefix + "has the parameters (" + join_names(stored.parameter_names) +
                           "), the calibration (" + join_names(space.names()) +
                           "); allowed: runs of the same parameters in the same order");
  }
  for (std::size_t j = 0; j < space.n_parameters(); ++j) {
    const Parameter& p = space.parameter(j);
    const std::string key = j < stored.parameter_config_keys.size() ? stored.parameter_config_keys[j] : "?";
    const std::string unit = j < stored.parameter_units.size() ? stored.parameter_units[j] : "?";
    if (key != p.config_key || unit != p.unit) {
      throw CalibrationError(prefix + "sets parameter '" + p.name + "' as " + key + " [" + unit +
                             "], the calibration as " + p.config_key + " [" + p.unit +
                             "]; allowed: the same config key and unit");
    }
  }
  if (stored.model != design.model) {
    throw CalibrationError(prefix + "holds runs of another forward model set-up: '" + stored.model +
                           "', the calibration's is '" + design.model +
                           "' (the weld case, its overrides or the command's script differ)");
  }
  std::vector<Eigen::Index> columns;
  std::vector<std::string> missing;
  for (const auto& name : design.feature_names) {
    const auto found = std::find(stored.feature_names.begin(), stored.feature_names.end(), name);
    if (found == stored.feature_names.end()) {
      missing.push_back(name);
    } else {
      columns.push_back(static_cast<Eigen::Index>(found - stored.feature_names.begin()));
    }
  }
  if (!missing.empty()) {
    throw CalibrationError(prefix + "has no feature " + join_names(missing) + " (it has " +
                           join_names(stored.feature_names) + "); allowed: runs that computed every feature of "
                           "the calibration");
  }

  // Priors that differ from the study's (the file describes them in /metadata/parameters).
  try {
    const fem::Hdf5File h5(results_file, fem::Hdf5Mode::read);
    const auto list = nlohmann::json::parse(h5.read_string("/metadata/parameters"));
    for (std::size_t j = 0; j < space.n_parameters() && j < list.size(); ++j) {
      const std::string theirs = list[j].value("description", "");
      const std::string ours = space.parameter(j).prior.describe();
      if (!theirs.empty() && theirs != ours) {
        initial.notes.push_back("the prior of " + space.parameter(j).name + " is " + ours + " here, " + theirs +
                                " in the study");
      }
    }
  } catch (const std::exception&) {
    // Descriptions are informative only.
  }

  std::size_t n_pending = 0, n_repeated = 0;
  std::vector<std::size_t> n_outside(space.n_parameters(), 0);
  std::size_t n_outside_total = 0;
  std::set<ThetaKey> seen;
  for (std::size_t i = 0; i < stored.n_points(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    if (stored.status[i] == StudyResults::Status::pending) {
      ++n_pending;
      continue;
    }
    const Eigen::VectorXd theta = stored.points.row(ii).transpose();
    bool inside = true;
    for (std::size_t j = 0; j < space.n_parameters(); ++j) {
      const Prior& prior = space.parameter(j).prior;
      const double x = theta[static_cast<Eigen::Index>(j)];
      if (!(x >= prior.lower() && x <= prior.upper())) {
        if (inside) ++n_outside[j];
        inside = false;
      }
    }
    if (!inside) {
      ++n_outside_total;
      continue;
    }
    if (!seen.insert(key_of(theta)).second) {
      ++n_repeated;
      continue;
    }
    InitialRun run;
    run.index = i;
    run.theta = theta;
    run.ok = stored.status[i] == StudyResults::Status::ok;
    run.features.resize(static_cast<Eigen::Index>(columns.size()));
    for (std::size_t k = 0; k < columns.size(); ++k)
      run.features[static_cast<Eigen::Index>(k)] = stored.features(ii, columns[k]);
    run.failure_reason = stored.failure_reasons[i];
    run.warnings = stored.warnings[i];
    run.wall_time = stored.wall_time[ii];
    initial.runs.push_back(std::move(run));
  }
  if (n_pending > 0) {
    initial.notes.push_back(std::to_string(n_pending) + " of the study's " + std::to_string(stored.n_points()) +
                            " runs not finished, skipped (finish them with rsw study run --resume)");
  }
  if (n_outside_total > 0) {
    std::string which;
    for (std::size_t j = 0; j < space.n_parameters(); ++j) {
      if (n_outside[j] == 0) continue;
      const Parameter& p = space.parameter(j);
      which += (which.empty() ? "" : ", ") + std::to_string(n_outside[j]) + " with " + p.name + " outside " +
               p.prior.describe();
    }
    initial.notes.push_back(std::to_string(n_outside_total) + " runs outside the calibration's prior box skipped (" +
                            which + ")");
  }
  if (n_repeated > 0) {
    initial.notes.push_back(std::to_string(n_repeated) + " runs repeat the θ of an earlier run, skipped");
  }
  if (initial.runs.empty()) {
    std::string why;
    for (const auto& note : initial.notes) why += "; " + note;
    throw CalibrationError(prefix + "has no usable run (of " + std::to_string(stored.n_points()) + why + ")");
  }
  return initial;
}

Calibration::Calibration(const ForwardModel& model, StudyDesign design, GaussianLikelihood likelihood,
                         CalibrationOptions options)
    : model_(model), design_(std::move(design)), likelihood_(std::move(likelihood)), options_(std::move(options)) {
  if (design_.parameters.n_parameters() == 0) throw CalibrationError("calibration: no parameters");
  if (likelihood_.feature_names() != design_.feature_names) {
    std::string observed, modelled;
    for (const auto& name : likelihood_.feature_names()) observed += (observed.empty() ? "" : ", ") + name;
    for (const auto& name : design_.feature_names) modelled += (modelled.empty() ? "" : ", ") + name;
    throw CalibrationError("calibration '" + design_.name + "': the observed features (" + observed +
                           ") differ from the model's (" + modelled + ")");
  }
  if (options_.evaluations_folder.empty()) throw CalibrationError("calibration: no evaluation folder");
  const std::size_t n_initial_runs = options_.initial_runs.runs.size();
  const auto n_design = static_cast<int>(std::max<std::size_t>(n_initial_runs, static_cast<std::size_t>(std::max(n_initial(), 0))));
  if (n_initial_runs > 0 && n_design >= max_evaluations()) {
    throw CalibrationError("calibration '" + design_.name + "': the initial design holds " + std::to_string(n_design) +
                           " runs (" + std::to_string(n_initial_runs) + " of " + options_.initial_runs.file.string() +
                           "), the evaluation cap is " + std::to_string(max_evaluations()) +
                           "; allowed: a cap above the initial design");
  }
}

int Calibration::n_initial() const {
  if (options_.method == CalibrationMethod::sbalc) return options_.sbalc.n_initial;
  const int n = options_.emulator.n_initial;
  return n > 0 ? n : 10 * static_cast<int>(design_.parameters.n_parameters());
}

int Calibration::max_evaluations() const {
  return options_.method == CalibrationMethod::sbalc ? options_.sbalc.max_evaluations : options_.emulator.max_evaluations;
}

CalibrationResult Calibration::run() const {
  const Clock::time_point start = Clock::now();
  const ParameterSpace& parameters = design_.parameters;
  const std::size_t d = parameters.n_parameters();
  const fs::path& folder = options_.evaluations_folder;
  const bool resume = options_.farm.resume;

  if (!resume && fs::exists(folder) && !fs::is_empty(folder)) {
    throw CalibrationError("calibration folder '" + folder.string() +
                           "' exists already; continue the calibration with --resume, or remove it to start again");
  }
  fs::create_directories(folder);

  // The evaluation cache: every finished run of every earlier session.
  std::map<ThetaKey, CachedRun> cache;
  std::size_t next_file = 0;
  for (const auto& [number, file] : run_files(folder)) {
    next_file = std::max(next_file, number + 1);
    if (!resume) continue;
    StudyResults stored;
    try {
      stored = read_study_results(file);
      StudyDesign probe = design_;
      probe.points = stored.points;
      check_same_design(stored, probe, file);
    } catch (const FarmError& e) {
      throw CalibrationError(std::string(e.what()) + "; the calibration folder '" + folder.string() +
                             "' holds runs of another set-up: remove it to start again");
    }
    for (std::size_t i = 0; i < stored.n_points(); ++i) {
      if (stored.status[i] == StudyResults::Status::pending) continue;
      CachedRun run;
      run.ok = stored.status[i] == StudyResults::Status::ok;
      run.features = stored.features.row(static_cast<Eigen::Index>(i)).transpose();
      run.failure_reason = stored.failure_reasons[i];
      run.warnings = stored.warnings[i];
      run.wall_time = stored.wall_time[static_cast<Eigen::Index>(i)];
      cache.emplace(key_of(stored.points.row(static_cast<Eigen::Index>(i)).transpose()), std::move(run));
    }
  }

  // Runs of an earlier study: the initial design in u (u_i = F_i(θ_i)), filled up with
  // Hammersley points to n_initial; SBALC finds them in the cache.
  std::optional<Eigen::MatrixXd> initial_design;
  if (!options_.initial_runs.runs.empty()) {
    const std::vector<InitialRun>& runs = options_.initial_runs.runs;
    const auto n_runs = static_cast<Eigen::Index>(runs.size());
    const Eigen::Index n_fill = std::max<Eigen::Index>(0, n_initial() - n_runs);
    Eigen::MatrixXd initial(n_runs + n_fill, static_cast<Eigen::Index>(d));
    for (Eigen::Index r = 0; r < n_runs; ++r) {
      const InitialRun& run = runs[static_cast<std::size_t>(r)];
      for (std::size_t j = 0; j < d; ++j) {
        initial(r, static_cast<Eigen::Index>(j)) = parameters.parameter(j).prior.cdf(run.theta[static_cast<Eigen::Index>(j)]);
      }
      CachedRun cached{run.ok, run.features, run.failure_reason, run.warnings, run.wall_time, true, run.theta};
      cache.insert_or_assign(key_of(unit_to_physical(parameters, initial.row(r).transpose())), std::move(cached));
    }
    if (n_fill > 0) initial.bottomRows(n_fill) = hammersley(static_cast<std::size_t>(n_fill), d);
    initial_design = initial;
  }

  if (options_.on_start) options_.on_start();

  CalibrationResult result;
  result.method = options_.method;
  result.parameter_names = parameters.names();
  for (std::size_t i = 0; i < d; ++i) result.parameter_units.push_back(parameters.parameter(i).unit);
  result.feature_names = design_.feature_names;
  std::size_t n_batches = 0;
  double best_log_likelihood = -std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_theta;

  // Runs a batch (or finds it in the cache), records every run in the result and
  // reports the batch; the two methods adapt what it returns.
  const auto evaluate_runs = [&](const std::vector<Eigen::VectorXd>& thetas_unit) -> std::vector<CalibrationEvaluation> {
    const std::size_t batch = n_batches++;
    const Clock::time_point batch_start = Clock::now();
    std::vector<CalibrationEvaluation> runs(thetas_unit.size());
    std::vector<std::size_t> missing;
    for (std::size_t k = 0; k < thetas_unit.size(); ++k) {
      CalibrationEvaluation& run = runs[k];
      run.batch = batch;
      run.theta_unit = thetas_unit[k];
      run.theta = unit_to_physical(parameters, thetas_unit[k]);
      const auto cached = cache.find(key_of(run.theta));
      if (cached == cache.end()) {
        missing.push_back(k);
        continue;
      }
      run.reused = !cached->second.from_study;
      run.from_study = cached->second.from_study;
      if (run.from_study) run.theta = cached->second.theta;
      run.ok = cached->second.ok;
      run.features = cached->second.features;
      run.failure_reason = cached->second.failure_reason;
      run.warnings = cached->second.warnings;
      run.wall_time = cached->second.wall_time;
    }

    std::size_t n_workers = 0;
    if (!missing.empty()) {
      StudyDesign design = design_;
      design.name = design_.name + "_runs_" + four_digits(next_file);
      design.kind = "sbalc";
      design.swept_parameter.clear();
      design.points.resize(static_cast<Eigen::Index>(missing.size()), static_cast<Eigen::Index>(d));
      for (std::size_t m = 0; m < missing.size(); ++m) {
        design.points.row(static_cast<Eigen::Index>(m)) = runs[missing[m]].theta.transpose();
      }
      const fs::path file = folder / ("runs_" + four_digits(next_file++) + ".h5");
      FarmOptions farm = options_.farm;
      farm.resume = false;
      farm.progress = nullptr;
      farm.distribution = FarmDistribution::local;
      FarmSummary summary;
      StudyResults stored;
      try {
        summary = EvaluationFarm(model_, design, file, farm).run();
        stored = read_study_results(file);
      } catch (const std::exception& e) {
        throw AbortCalibration{e.what(), false};
      }
      if (summary.interrupted) {
        throw AbortCalibration{"calibration '" + design_.name + "' interrupted in batch " + std::to_string(batch) +
                                   "; the finished runs are kept in " + folder.string(),
                               true};
      }
      n_workers = summary.n_workers;
      for (std::size_t m = 0; m < missing.size(); ++m) {
        CalibrationEvaluation& run = runs[missing[m]];
        run.ok = stored.status[m] == StudyResults::Status::ok;
        run.features = stored.features.row(static_cast<Eigen::Index>(m)).transpose();
        run.failure_reason = stored.failure_reasons[m];
        run.warnings = stored.warnings[m];
        run.wall_time = stored.wall_time[static_cast<Eigen::Index>(m)];
        cache.emplace(key_of(run.theta),
                      CachedRun{run.ok, run.features, run.failure_reason, run.warnings, run.wall_time, false, {}});
      }
    }

    std::size_t n_failed = 0;
    for (CalibrationEvaluation& run : runs) {
      run.log_likelihood = not_a_number;
      if (run.ok) {
        // A run that leaves a likelihood feature undefined (NaN) is a failed run for
        // the calibration: recorded with the reason, excluded from the GP.
        const std::string undefined = undefined_features_reason(design_.feature_names, run.features);
        if (!undefined.empty()) {
          run.ok = false;
          run.failure_reason = undefined;
        }
      }
      if (run.ok) {
        try {
          run.log_likelihood = likelihood_.log_likelihood(run.features);
        } catch (const std::invalid_argument& e) {
          run.ok = false;
          run.failure_reason = e.what();
        }
      }
      if (run.ok) {
        if (run.log_likelihood > best_log_likelihood) {
          best_log_likelihood = run.log_likelihood;
          best_theta = run.theta;
        }
      } else {
        ++n_failed;
      }
      if (run.reused) ++result.n_reused;
      if (run.from_study) ++result.n_from_study;
      result.evaluations.push_back(run);
    }
    result.n_failed += n_failed;
    if (options_.progress != nullptr) {
      const std::size_t n_new = missing.size();
      const auto n_study = static_cast<std::size_t>(
          std::count_if(runs.begin(), runs.end(), [](const CalibrationEvaluation& run) { return run.from_study; }));
      std::ostream& out = *options_.progress;
      out << "calibration " << design_.name << ": batch " << batch << ", " << runs.size() << " run"
          << (runs.size() == 1 ? "" : "s") << " (" << n_new << " new";
      if (n_new > 0) out << " on " << n_workers << " worker" << (n_workers == 1 ? "" : "s");
      if (n_study > 0) out << ", " << n_study << " from the study";
      out << ", " << runs.size() - n_new - n_study << " reused, " << n_failed << " failed) in "
          << format_duration(std::chrono::duration<double>(Clock::now() - batch_start).count()) << "; "
          << result.evaluations.size() << " runs so far";
      if (best_theta.size() > 0) {
        out.precision(6);
        out << "; best ln L " << best_log_likelihood << " at " << format_theta(parameters, best_theta);
      }
      out << "\n" << std::flush;
    }
    return runs;
  };

  PosteriorResult posterior;
  try {
    posterior = options_.method == CalibrationMethod::sbalc ? run_sbalc(evaluate_runs, initial_design, result)
                                                            : run_emulator(evaluate_runs, initial_design, result);
  } catch (const AbortCalibration& abort) {
    if (abort.interrupted) throw CalibrationInterrupted(abort.message);
    throw CalibrationError(abort.message);
  }
  summarise_posterior(posterior, result);
  result.elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

PosteriorResult Calibration::run_sbalc(const RunBatch& evaluate_runs, const std::optional<Eigen::MatrixXd>& initial_design,
                                       CalibrationResult& result) const {
  const ParameterSpace& parameters = design_.parameters;
  const std::size_t d = parameters.n_parameters();
  SbalcOptions sbalc_options = options_.sbalc;
  if (initial_design) sbalc_options.initial_design = *initial_design;
  const BatchLogLikelihoodFunction evaluate_batch = [&](const std::vector<Eigen::VectorXd>& thetas_unit) {
    std::vector<std::optional<double>> values;
    for (const CalibrationEvaluation& run : evaluate_runs(thetas_unit)) {
      values.push_back(run.ok ? std::optional<double>(run.log_likelihood) : std::nullopt);
    }
    return values;
  };
  const SbalcResult sbalc = Sbalc(static_cast<int>(d), evaluate_batch, sbalc_options).run();
  result.n_evaluations = result.evaluations.size();
  if (!sbalc.surrogate) {
    std::string reasons;
    for (const auto& run : result.evaluations) {
      if (!run.ok && reasons.size() < 400) reasons += "\n  " + format_theta(parameters, run.theta) + ": " + run.failure_reason;
    }
    throw CalibrationError("calibration '" + design_.name + "': " + sbalc.stop_reason +
                           "; a GP of the log-likelihood needs two or more" + reasons);
  }

  result.converged = sbalc.converged;
  result.stop_reason = sbalc.stop_reason;
  result.log_evidence = sbalc.log_evidence;
  result.log_evidence_lower = sbalc.log_evidence_lower;
  result.log_evidence_upper = sbalc.log_evidence_upper;
  result.ratio = sbalc.ratio;
  result.noise_ratio = sbalc.noise_ratio;
  result.noise_standard_deviation = sbalc.noise_standard_deviation;
  result.pool_ess = sbalc.pool_ess;
  result.pool_ess_threshold = sbalc.pool_ess_threshold;
  result.pool_relative_error = sbalc.pool_relative_error;
  result.warnings = sbalc.warnings;
  result.history = sbalc.history;
  result.hyperparameters = sbalc.surrogate->hyperparameters();
  result.trend_used = sbalc.surrogate->trend_used();
  result.design_unit = sbalc.design;
  result.design_log_likelihoods = sbalc.log_likelihoods;

  // SIR posterior of the pool.
  result.pool = sbalc.pool;
  result.pool_log_likelihood = sbalc.pool_mean;
  return SirPosterior(sbalc, options_.posterior).run();
}

InputMap log_product_map(const ParameterSpace& parameters,
                         const std::vector<EmulatorCalibrationOptions::LogProduct>& products) {
  // z = (Σ log10 θ_i(u) − Σ log10 a_i) / (Σ log10 b_i − Σ log10 a_i) over each product.
  std::vector<double> low, span;
  for (const auto& product : products) {
    double a = 0.0, b = 0.0;
    for (std::size_t i : product.parameters) {
      a += std::log10(parameters.parameter(i).prior.lower());
      b += std::log10(parameters.parameter(i).prior.upper());
    }
    low.push_back(a);
    span.push_back(b - a);
  }
  return [&parameters, products, low, span](const Eigen::MatrixXd& points) {
    const auto k = static_cast<Eigen::Index>(products.size());
    Eigen::MatrixXd mapped(points.rows(), points.cols() + k);
    mapped.leftCols(points.cols()) = points;
    for (Eigen::Index r = 0; r < points.rows(); ++r)
      for (Eigen::Index q = 0; q < k; ++q) {
        double sum = 0.0;
        for (std::size_t i : products[static_cast<std::size_t>(q)].parameters)
          sum += std::log10(parameters.parameter(i).prior.quantile(points(r, static_cast<Eigen::Index>(i))));
        mapped(r, points.cols() + q) = (sum - low[static_cast<std::size_t>(q)]) / span[static_cast<std::size_t>(q)];
      }
    return mapped;
  };
}

PosteriorResult Calibration::run_emulator(const RunBatch& evaluate_runs,
                                          const std::optional<Eigen::MatrixXd>& initial_design,
                                          CalibrationResult& result) const {
  const std::size_t d = design_.parameters.n_parameters();
  EmulatorCalibrationOptions emulator_options = options_.emulator;
  if (initial_design) emulator_options.initial_design = *initial_design;
  if (!emulator_options.log_products.empty())
    emulator_options.input_map = log_product_map(design_.parameters, emulator_options.log_products);
  if (options_.progress != nullptr) {
    std::ostream& out = *options_.progress;
    emulator_options.on_iteration = [&out, this](const EmulatorIteration& it) {
      const std::streamsize precision = out.precision(3);
      out << "calibration " << design_.name << ": emulators of " << it.n_points << " runs";
      if (it.n_focused > 0) out << " (" << it.n_focused << " plausible)";
      out << ": ln Z " << it.log_evidence
          << ", influence " << it.emulator_influence << " ± " << it.influence_standard_error << " sd" << (it.influence_settled ? " (settled)" : "")
          << ", variance ratio " << it.max_variance_ratio
          << ", quantile shift " << it.quantile_shift << " sd" << (it.quantiles_settled ? " (settled)" : "")
          << ", pool ESS " << static_cast<long>(it.pool_ess) << " (" << it.seconds << " s)\n"
          << std::flush;
      out.precision(precision);
    };
  }
  const BatchFeatureFunction evaluate_batch = [&](const std::vector<Eigen::VectorXd>& thetas_unit) {
    std::vector<std::optional<Eigen::VectorXd>> values;
    for (const CalibrationEvaluation& run : evaluate_runs(thetas_unit)) {
      values.push_back(run.ok ? std::optional<Eigen::VectorXd>(run.features) : std::nullopt);
    }
    return values;
  };
  EmulatorCalibrationResult emulated;
  try {
    emulated = EmulatorCalibration(static_cast<int>(d), evaluate_batch, likelihood_, emulator_options).run();
  } catch (const std::runtime_error& e) {
    if (dynamic_cast<const CalibrationError*>(&e) != nullptr) throw;
    std::string reasons;
    for (const auto& run : result.evaluations) {
      if (!run.ok && reasons.size() < 400)
        reasons += "\n  " + format_theta(design_.parameters, run.theta) + ": " + run.failure_reason;
    }
    throw CalibrationError("calibration '" + design_.name + "': " + e.what() + reasons);
  }
  result.n_evaluations = result.evaluations.size();
  result.converged = emulated.converged;
  result.stop_reason = emulated.stop_reason;
  result.log_evidence = emulated.log_evidence;
  const double e = emulated.evidence_relative_error;
  result.log_evidence_lower = e < 1.0 ? emulated.log_evidence + std::log1p(-e) : -std::numeric_limits<double>::infinity();
  result.log_evidence_upper = emulated.log_evidence + std::log1p(e);
  result.ratio = 2.0 * e;
  result.noise_ratio = 0.0;
  result.pool_ess = emulated.pool_ess;
  result.pool_ess_threshold = emulated.pool_ess_threshold;
  result.pool_relative_error = e;
  result.warnings = emulated.warnings;
  result.emulator_history = emulated.history;
  result.feature_noise_standard_deviations = emulated.history.back().noise_standard_deviations;
  result.design_unit = emulated.design;
  result.design_log_likelihoods.resize(emulated.design.rows());
  for (Eigen::Index r = 0; r < emulated.design.rows(); ++r)
    result.design_log_likelihoods(r) = likelihood_.log_likelihood(Eigen::VectorXd(emulated.design_features.row(r).transpose()));

  // SIR posterior of the importance pool; the MAP refined on the emulated likelihood.
  result.pool = emulated.pool;
  result.pool_log_likelihood = emulated.pool_log_likelihood;
  const FeatureEmulator emulator = *emulated.emulator;
  const EmulatedLikelihood likelihood(likelihood_);
  const auto log_density = [emulator, likelihood](const Eigen::VectorXd& u) {
    return likelihood.log_likelihood(emulator.predict(Eigen::MatrixXd(u.transpose())))(0);
  };
  return SirPosterior(emulated.pool, emulated.pool_log_likelihood, emulated.pool_log_weight, options_.posterior,
                      log_density)
      .run();
}

void Calibration::summarise_posterior(const PosteriorResult& posterior, CalibrationResult& result) const {
  const ParameterSpace& parameters = design_.parameters;
  const std::size_t d = parameters.n_parameters();
  // Contraction in the unit cube (prior variance 1/12), before the pool goes physical.
  result.contraction.resize(static_cast<Eigen::Index>(d));
  result.identification.clear();
  for (std::size_t i = 0; i < d; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const double mean = result.pool.col(ii).dot(posterior.weights);
    const double variance = (result.pool.col(ii).array() - mean).square().matrix().dot(posterior.weights);
    result.contraction(ii) = 1.0 - 12.0 * variance;
    result.identification.emplace_back(result.contraction(ii) >= 0.75   ? "identified"
                                       : result.contraction(ii) < 0.36 ? "not identified"
                                                                       : "weakly identified");
  }
  result.pool = rows_to_physical(parameters, result.pool);
  result.pool_weights = posterior.weights;
  result.samples = rows_to_physical(parameters, posterior.samples);
  result.mean = result.pool.transpose() * posterior.weights;
  const Eigen::MatrixXd centred = result.pool.rowwise() - result.mean.transpose();
  const Eigen::MatrixXd covariance = centred.transpose() * posterior.weights.asDiagonal() * centred;
  result.standard_deviation = covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  result.correlation = Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(d), static_cast<Eigen::Index>(d));
  for (Eigen::Index i = 0; i < covariance.rows(); ++i)
    for (Eigen::Index j = 0; j < covariance.cols(); ++j)
      if (i != j && result.standard_deviation(i) > 0.0 && result.standard_deviation(j) > 0.0)
        result.correlation(i, j) = covariance(i, j) / (result.standard_deviation(i) * result.standard_deviation(j));
  result.map_point = unit_to_physical(parameters, posterior.map_point);
  result.map_log_likelihood = posterior.map_log_density;
  result.credible_level = posterior.credible_level;
  Eigen::VectorXd lower(static_cast<Eigen::Index>(d)), upper(static_cast<Eigen::Index>(d));
  for (std::size_t i = 0; i < d; ++i) {
    lower[static_cast<Eigen::Index>(i)] = posterior.credible_intervals[i].lower;
    upper[static_cast<Eigen::Index>(i)] = posterior.credible_intervals[i].upper;
  }
  result.credible_lower = unit_to_physical(parameters, lower);
  result.credible_upper = unit_to_physical(parameters, upper);
  result.effective_sample_size = posterior.effective_sample_size;
  result.ess_threshold = posterior.ess_threshold;
  result.poorly_resolved = posterior.poorly_resolved;
  result.warning = posterior.warning;
  if (!posterior.warning.empty()) result.warnings.push_back("posterior: " + posterior.warning);
}

const char* calibration_method_name(CalibrationMethod method) {
  return method == CalibrationMethod::sbalc ? "sbalc" : "emulator";
}

}  // namespace rsw::calibration
