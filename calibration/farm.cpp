// The evaluation farm (see farm.hpp): the run loop over the design's points, with
// progress, interrupts and the summary. Its parts: the messages between processes
// (farm_protocol), the local worker processes (worker_pool), the MPI ranks behind one
// interface (mpi_ranks; the only place that knows whether rsw has MPI) and the results
// file (study_results_file).
#include "calibration/farm.hpp"

#include "calibration/farm_detail.hpp"
#include "calibration/mpi_ranks.hpp"
#include "calibration/study_results_file.hpp"
#include "calibration/worker_pool.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

namespace rsw::calibration {

using namespace farm_detail;

namespace {

// --- interrupts ----------------------------------------------------------------------

volatile std::sig_atomic_t interrupt_signal = 0;

extern "C" void note_interrupt(int signal) { interrupt_signal = signal; }

// SIGINT/SIGTERM set a flag for the farm's loop while it runs; SIGPIPE is ignored (a
// dead worker must not kill the farm). The previous handlers come back afterwards.
class InterruptScope {
 public:
  explicit InterruptScope(bool catch_interrupts) : active_(catch_interrupts) {
    interrupt_signal = 0;
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &ignore, &old_pipe_);
    if (!active_) return;
    struct sigaction note {};
    note.sa_handler = note_interrupt;
    sigemptyset(&note.sa_mask);
    note.sa_flags = 0;  // no SA_RESTART: poll() returns at once
    sigaction(SIGINT, &note, &old_int_);
    sigaction(SIGTERM, &note, &old_term_);
  }
  ~InterruptScope() {
    sigaction(SIGPIPE, &old_pipe_, nullptr);
    if (!active_) return;
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  bool interrupted() const { return interrupt_signal != 0; }

 private:
  bool active_;
  struct sigaction old_pipe_ {};
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

// --- progress ------------------------------------------------------------------------

class Progress {
 public:
  Progress(std::ostream* out, double interval, std::size_t n_total, std::size_t n_done_before)
      : out_(out), n_total_(n_total), n_done_before_(n_done_before), start_(Clock::now()) {
    in_place_ = out_ == &std::cerr && ::isatty(STDERR_FILENO);
    interval_ = interval >= 0 ? interval : (in_place_ ? 0.5 : 10.0);
    last_ = start_ - std::chrono::hours(1);
  }

  void update(std::size_t n_evaluated, std::size_t n_failed, bool final_line) {
    if (out_ == nullptr) return;
    if (!final_line && (n_evaluated == 0 || seconds_since(last_) < interval_)) return;
    last_ = Clock::now();
    const double elapsed = seconds_since(start_);
    const std::size_t n_done = n_done_before_ + n_evaluated;
    std::ostringstream line;
    line << "runs " << n_done << "/" << n_total_ << ", " << n_failed << " failed, elapsed "
         << format_duration(elapsed);
    if (n_done < n_total_) {
      line << ", ETA ";
      if (n_evaluated == 0) {
        line << "--";
      } else {
        line << format_duration(elapsed / static_cast<double>(n_evaluated) *
                                static_cast<double>(n_total_ - n_done));
      }
    }
    if (in_place_) {
      *out_ << "\r" << line.str() << "\033[K" << (final_line ? "\n" : "") << std::flush;
    } else {
      *out_ << line.str() << "\n" << std::flush;
    }
  }

  double elapsed() const { return seconds_since(start_); }

 private:
  std::ostream* out_;
  std::size_t n_total_;
  std::size_t n_done_before_;
  Clock::time_point start_;
  Clock::time_point last_;
  bool in_place_ = false;
  double interval_ = 10;
};

// Counts of one run of the farm, kept by the writer.
struct Tally {
  std::size_t n_evaluated = 0;
  std::size_t n_failed = 0;
};

void check_model_matches(const ForwardModel& model, const StudyDesign& design) {
  const auto parameters = model.parameter_names();
  const auto features = model.feature_names();
  if (parameters != design.parameters.names()) {
    throw FarmError("study '" + design.name + "': the forward model takes parameters (" +
                    join(parameters, ", ") + "), the study varies (" +
                    join(design.parameters.names(), ", ") + ")");
  }
  if (features != design.feature_names) {
    throw FarmError("study '" + design.name + "': the forward model returns features (" +
                    join(features, ", ") + "), the study asks for (" + join(design.feature_names, ", ") +
                    ")");
  }
}

}  // namespace

// ---------------------------------------------------------------------------------
// Small public helpers

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--";
  const auto total = static_cast<long long>(std::llround(seconds));
  const long long hours = total / 3600, minutes = (total % 3600) / 60, secs = total % 60;
  std::ostringstream out;
  if (hours > 0) {
    out << hours << "h" << std::setw(2) << std::setfill('0') << minutes << "m";
  } else if (minutes > 0) {
    out << minutes << "m" << std::setw(2) << std::setfill('0') << secs << "s";
  } else {
    out << secs << "s";
  }
  return out.str();
}

TaskPartition TaskPartition::parse(const std::string& text) {
  const auto slash = text.find('/');
  const auto bad = [&text](const std::string& why) {
    return FarmError("--task '" + text + "': " + why + "; expected i/n with 0 <= i < n, e.g. 3/10");
  };
  if (slash == std::string::npos) throw bad("no '/'");
  const std::string i_text = text.substr(0, slash), n_text = text.substr(slash + 1);
  const auto is_count = [](const std::string& s) {
    return !s.empty() && s.size() <= 9 && s.find_first_not_of("0123456789") == std::string::npos;
  };
  if (!is_count(i_text) || !is_count(n_text)) throw bad("i and n must be whole numbers");
  TaskPartition task;
  task.index = std::stoul(i_text);
  task.count = std::stoul(n_text);
  if (task.count == 0) throw bad("n must be at least 1");
  if (task.index >= task.count) throw bad("i must be less than n");
  return task;
}

std::string TaskPartition::describe() const {
  return std::to_string(index) + "/" + std::to_string(count);
}

fs::path task_results_file(const fs::path& study_file, const TaskPartition& task) {
  if (task.is_whole()) return study_file;
  fs::path part = study_file;
  part.replace_filename(study_file.stem().string() + ".task-" + std::to_string(task.index) + "-of-" +
                        std::to_string(task.count) + study_file.extension().string());
  return part;
}

void check_design(const StudyDesign& design) {
  const std::string study = "study '" + design.name + "': ";
  if (design.parameters.n_parameters() == 0) throw FarmError(study + "no parameters");
  if (design.feature_names.empty()) throw FarmError(study + "no features");
  if (design.points.rows() == 0) throw FarmError(study + "the design has no points");
  if (static_cast<std::size_t>(design.points.cols()) != design.parameters.n_parameters()) {
    throw FarmError(study + "the design has " + std::to_string(design.points.cols()) + " columns for " +
                    std::to_string(design.parameters.n_parameters()) + " parameters");
  }
  if (!design.points.allFinite()) throw FarmError(study + "the design has a non-finite point");
  if (!design.swept_parameter.empty() &&
      design.swept_parameter.size() != static_cast<std::size_t>(design.points.rows())) {
    throw FarmError(study + "swept_parameter needs one entry per design point");
  }
  if (!design.feature_info.empty() && design.feature_info.size() != design.feature_names.size()) {
    throw FarmError(study + "feature_info needs one entry per feature");
  }
  for (std::size_t k = 0; k < design.feature_names.size(); ++k) {
    for (std::size_t l = 0; l < k; ++l) {
      if (design.feature_names[k] == design.feature_names[l]) {
        throw FarmError(study + "feature '" + design.feature_names[k] + "' is listed twice");
      }
    }
  }
}

// ---------------------------------------------------------------------------------
// The farm

EvaluationFarm::EvaluationFarm(const ForwardModel& model, StudyDesign design, fs::path results_file,
                               FarmOptions options)
    : model_(model), design_(std::move(design)), results_file_(std::move(results_file)),
      options_(std::move(options)) {
  check_design(design_);
}

FarmSummary EvaluationFarm::run() {
  check_model_matches(model_, design_);
  bool use_mpi = false;
  switch (options_.distribution) {
    case FarmDistribution::automatic:
      use_mpi = built_with_mpi() && options_.started_by_mpi_launcher;
      break;
    case FarmDistribution::local:
      break;
    case FarmDistribution::mpi:
      use_mpi = true;
      break;
  }
  const std::unique_ptr<RankGroup> ranks = use_mpi ? mpi_ranks(design_) : local_ranks();
  const std::size_t n_points = static_cast<std::size_t>(design_.points.rows());
  FarmSummary summary;
  summary.n_points = n_points;
  summary.results_file = results_file_;
  InterruptScope interrupts(options_.stop_on_interrupt);

  const int rank = ranks->rank(), n_ranks = ranks->size();
  summary.n_ranks = n_ranks;
  summary.writer = rank == 0;
  const std::size_t n_local_workers =
      options_.n_workers > 0 ? options_.n_workers : (use_mpi ? 1 : default_worker_count());

  // The writer: open the file and find the points still to evaluate.
  std::optional<ResultsFile> file;
  std::vector<std::size_t> pending;
  std::string open_error;
  if (rank == 0) {
    try {
      file.emplace(results_file_, design_, options_.task, options_.resume);
      for (std::size_t i = 0; i < n_points; ++i) {
        if (!options_.task.owns(i)) continue;
        ++summary.n_assigned;
        if (file->is_done(i)) {
          ++summary.n_done_before;
        } else {
          pending.push_back(i);
        }
      }
    } catch (const std::exception& e) {
      open_error = e.what();
    }
  }
  ranks->share_open_error(open_error);
  if (!open_error.empty()) throw FarmError(open_error);

  // Every worker slot over all ranks, for the summary.
  const std::vector<unsigned long> slots_per_rank = ranks->gather_slots(n_local_workers);

  if (rank != 0) {
    // A worker rank: evaluate what rank 0 sends.
    const Clock::time_point start = Clock::now();
    WorkerPool pool(model_, design_, n_local_workers, options_.run_timeout, rank, fs::path());
    ranks->serve(pool, [&interrupts]() { return interrupts.interrupted(); }, summary);
    summary.elapsed = seconds_since(start);
    return summary;
  }

  // The writer: local workers (and the other ranks' slots).
  std::size_t n_remote_slots = 0;
  for (std::size_t r = 1; r < slots_per_rank.size(); ++r) n_remote_slots += slots_per_rank[r];
  // Local workers: none are started if there is nothing to do.
  const std::size_t n_start = std::min(n_local_workers, pending.size());
  summary.n_workers = n_start + n_remote_slots;
  Progress progress(options_.progress, options_.progress_interval, summary.n_assigned, summary.n_done_before);
  const auto failed_so_far = [&file]() { return file->records().count(StudyResults::Status::failed); };
  std::size_t next = 0;
  Tally tally;
  const auto record_result = [&](const RunRecord& record) {
    file->append(record);
    ++tally.n_evaluated;
    if (!record.ok) ++tally.n_failed;
    if (options_.on_result) options_.on_result(record);
    progress.update(tally.n_evaluated, failed_so_far(), false);
  };
  const auto next_point = [&]() -> std::optional<std::pair<std::size_t, Eigen::VectorXd>> {
    if (next >= pending.size()) return std::nullopt;
    const std::size_t index = pending[next++];
    return std::make_pair(index, Eigen::VectorXd(design_.points.row(static_cast<Eigen::Index>(index)).transpose()));
  };
  if (options_.progress != nullptr) {
    *options_.progress << "study " << design_.name << ": " << summary.n_assigned << " runs"
                       << (options_.task.is_whole() ? "" : " (task " + options_.task.describe() + ")") << ", "
                       << summary.n_done_before << " done before, " << pending.size() << " to evaluate on "
                       << summary.n_workers << " worker process" << (summary.n_workers == 1 ? "" : "es")
                       << (n_ranks > 1 ? " over " + std::to_string(n_ranks) + " MPI ranks" : "") << "\n"
                       << std::flush;
  }
  try {
    WorkerPool pool(model_, design_, n_start, options_.run_timeout, rank, results_file_);
    while (next < pending.size() || pool.any_busy() || ranks->remote_active()) {
      if (interrupts.interrupted()) {
        summary.interrupted = true;
        break;
      }
      while (pool.n_idle() > 0 && next < pending.size()) {
        const auto point = next_point();
        pool.submit(point->first, point->second);
      }
      ranks->exchange(next_point, record_result);
      for (const RunRecord& record : pool.wait(ranks->remote_active() ? 2 : 200)) record_result(record);
      progress.update(tally.n_evaluated, failed_so_far(), false);
    }
    pool.shutdown(summary.interrupted);
    if (summary.interrupted) ranks->abort_all();
  } catch (...) {
    // The other ranks stop too; the file keeps every result written so far.
    ranks->abort_all();
    throw;
  }
  file->finish();
  summary.n_evaluated = tally.n_evaluated;
  summary.n_ok = file->records().count(StudyResults::Status::ok);
  summary.n_failed = failed_so_far();
  std::size_t n_pending_in_task = 0;
  for (std::size_t i = 0; i < n_points; ++i) {
    if (options_.task.owns(i) && !file->is_done(i)) ++n_pending_in_task;
  }
  summary.complete = n_pending_in_task == 0;
  file->close();
  progress.update(tally.n_evaluated, summary.n_failed, true);
  summary.elapsed = progress.elapsed();
  return summary;
}

}  // namespace rsw::calibration
