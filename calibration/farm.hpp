// The evaluation farm: runs every point of a design through a ForwardModel, in parallel,
// and keeps each result in the study's HDF5 file the moment it is known
// (docs/STUDIES.md; docs/ARCHITECTURE.md, "Data flow of a study").
//
// Parallelism. On one machine the farm forks N worker processes (default: one per
// core), each evaluating one point at a time with OpenMP and Eigen limited to one
// thread. Processes, not threads: a simulator that crashes (a segmentation fault, an
// abort in a library), hangs or leaks memory takes down one worker, which the farm
// records as a failed run ("worker ended by signal 11 (Segmentation fault)") and
// replaces; the study goes on. Points are handed out one at a time to whichever worker
// is idle (dynamic scheduling, so long and short runs balance). Workers talk to the
// parent through a Unix socket pair each; only the parent touches the HDF5 file.
//
// Beyond one machine:
// - MPI (when built with MPI and started by mpirun): rank 0 is the writer and the
//   dispatcher. Every rank, rank 0 included, runs its own pool of worker processes
//   (default one per rank: start one rank per core); rank 0 hands out points
//   dynamically to free worker slots on any rank and appends their results to the
//   file as they arrive. Other ranks never open the file.
// - Array tasks: TaskPartition i/n makes the farm evaluate only the points with
//   index % n == i, into a partial file; merge_study_files() gathers the partial files
//   into the study file after checking that every file holds the same design.
//
// Results file (readable with h5py; see docs/STUDIES.md for the full layout):
//   /design/points            n_points × n_parameters, physical θ
//   /runs/records             appendable, one row per finished run, in finishing order:
//                             [committed, index, ok, wall_time, rank, θ..., y...]
//   /runs/failure_reasons/run_<index>   the reason of each failed run
//   /runs/warnings/run_<index>          the warnings of an ok run that has any
//   /results/status, /results/features, /results/wall_time   the same, by point index
// A row is appended and flushed as soon as its run finishes, so a killed study loses
// only the runs that were in flight. `resume` reads the rows back, checks that the
// file holds the requested design (parameter names, feature names, every θ), and
// evaluates only the missing points. The /results arrays are ordered by point index
// and hold only values computed by the model, so a serial, parallel, resumed, MPI or
// merged study gives identical arrays.
//
// Failures are values: a model failure, an exception thrown by evaluate(), an infinite
// feature value, a crashed worker and a run that exceeds the time limit are all
// recorded with their reason. A NaN feature value is not a failure: it is a feature
// that this run's signals leave undefined (features.hpp, "Undefined features"; e.g. no
// interior resistance peak), so the run is ok, the NaN is stored as is (HDF5 NaN), and
// each analysis uses the runs where the feature it needs is finite.
// Errors of the study itself (a file holding another design, an unwritable file) throw
// FarmError.
#pragma once

#include "calibration/forward_model.hpp"
#include "calibration/parameter_space.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::calibration {

class FarmError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How a feature is grouped and measured, for tables and plots ("resistance", "ohm").
struct FeatureInfo {
  std::string group;
  std::string unit;
};

// What a study evaluates: the parameters and features by name, and the points.
struct StudyDesign {
  std::string name;                        // the study's name
  std::string kind;                        // "lhs", "hammersley", "oat", ... (informative)
  ParameterSpace parameters;               // θ names, config keys, units, priors
  std::vector<std::string> feature_names;  // y names, in the model's order
  std::vector<FeatureInfo> feature_info;   // per feature, or empty (group "other")
  Eigen::MatrixXd points;                  // one row of physical θ per run
  std::vector<int> swept_parameter;        // one-at-a-time designs: per row the swept
                                           // parameter, −1 for the nominal point; else empty
  std::string description;                 // echoed into the file (the resolved study file)
  // What identifies the forward model's set-up (e.g. a hash of the weld case and the
  // overrides); a results file with another one is not resumed or merged.
  std::string model;
};

// Throws FarmError if the names, sizes or points are inconsistent or not finite.
void check_design(const StudyDesign& design);

// Array-job partition: this task evaluates the points with index % count == index.
struct TaskPartition {
  std::size_t index = 0;
  std::size_t count = 1;

  // "3/10" → {3, 10}; throws FarmError unless 0 ≤ i < n.
  static TaskPartition parse(const std::string& text);
  bool is_whole() const { return count == 1; }
  bool owns(std::size_t point) const { return point % count == index; }
  std::string describe() const;  // "3/10"
};

// One finished run.
struct RunRecord {
  std::size_t index = 0;           // row of the design
  bool ok = false;
  Eigen::VectorXd theta;           // physical θ
  Eigen::VectorXd features;        // y (size n_features; NaN when !ok, or undefined when ok)
  std::string failure_reason;      // empty when ok
  std::string warnings;            // of an ok run (EvaluationResult::warnings), empty if none
  double wall_time = 0;            // [s] of the evaluation in its worker
  int rank = 0;                    // MPI rank that evaluated it (0 without MPI)
};

enum class FarmDistribution {
  automatic,  // MPI when built with MPI and started by mpirun, else local processes
  local,      // worker processes on this machine only
  mpi,        // MPI ranks; throws FarmError if rsw was built without MPI
};

struct FarmOptions {
  // Worker processes on this machine (with MPI: on each rank); 0 = one per core
  // without MPI, one per rank with MPI.
  std::size_t n_workers = 0;
  bool resume = false;     // continue an existing results file; without it the file must not exist
  TaskPartition task;      // evaluate only this task's share of the points
  double run_timeout = 0;  // [s] per run; a worker over the limit is killed, the run recorded
                           // as failed. 0: no limit
  FarmDistribution distribution = FarmDistribution::automatic;
  // Set by the program when mpirun/mpiexec started this process (the library reads no
  // environment): `automatic` then spreads the runs over the MPI ranks.
  bool started_by_mpi_launcher = false;
  // Progress lines "runs 37/90, 1 failed, elapsed 1m12s, ETA 1m50s" go here (nullptr:
  // none), at most every progress_interval seconds and once at the end. A negative
  // interval picks 0.5 s on a terminal (the line is rewritten in place) and 10 s
  // otherwise (one line each, for log files).
  std::ostream* progress = nullptr;
  double progress_interval = -1;
  // Called on the writer after each result has been flushed to the file.
  std::function<void(const RunRecord&)> on_result;
  // SIGINT/SIGTERM stop the study cleanly: in-flight runs are abandoned, the file is
  // closed consistent, summary.interrupted is set; resume continues it.
  bool stop_on_interrupt = true;
};

struct FarmSummary {
  bool writer = true;              // false on MPI ranks other than 0 (they hold no totals)
  std::size_t n_points = 0;        // points of the design
  std::size_t n_assigned = 0;      // points of this task
  std::size_t n_done_before = 0;   // found finished in the file (resume)
  std::size_t n_evaluated = 0;     // evaluated now (on this rank, for writer == false)
  std::size_t n_ok = 0;            // over the task: successes so far
  std::size_t n_failed = 0;        // over the task: failures so far
  std::size_t n_workers = 0;       // worker processes over all ranks
  int n_ranks = 1;
  bool complete = false;           // every assigned point has a result
  bool interrupted = false;        // stopped by SIGINT/SIGTERM
  double elapsed = 0;              // [s]
  std::filesystem::path results_file;
};

class EvaluationFarm {
 public:
  // The model must outlive the farm. results_file is the study file, or the task's
  // partial file (see task_results_file). Throws FarmError for an inconsistent design.
  EvaluationFarm(const ForwardModel& model, StudyDesign design,
                 std::filesystem::path results_file, FarmOptions options = {});

  // Evaluates the missing points; see the header comment. Throws FarmError if the
  // model's parameter or feature names differ from the design's, if the file exists
  // without resume, or if it holds another design.
  FarmSummary run();

 private:
  const ForwardModel& model_;
  StudyDesign design_;
  std::filesystem::path results_file_;
  FarmOptions options_;
};

// "<stem>.task-<i>-of-<n>.h5" next to the study file; the study file itself for a
// whole task.
std::filesystem::path task_results_file(const std::filesystem::path& study_file,
                                        const TaskPartition& task);

// A results file read back (whole study, partial file, or a killed study).
struct StudyResults {
  std::vector<std::string> parameter_names;
  std::vector<std::string> parameter_config_keys;
  std::vector<std::string> parameter_units;
  std::string model;                   // StudyDesign::model of the run that wrote the file
  std::vector<std::string> feature_names;
  Eigen::MatrixXd points;              // the design, physical θ
  std::vector<int> swept_parameter;    // empty unless one-at-a-time
  enum class Status { pending = -1, failed = 0, ok = 1 };
  std::vector<Status> status;          // per point
  Eigen::MatrixXd features;            // n_points × n_features, NaN unless ok; NaN in an
                                       // ok row: a feature that run leaves undefined
  Eigen::VectorXd wall_time;           // [s], NaN unless run
  std::vector<std::string> failure_reasons;  // per point, empty unless failed
  std::vector<std::string> warnings;         // per point, empty unless an ok run warned
  std::vector<int> rank;               // per point, −1 unless run
  TaskPartition task;                  // the partition the file was written for

  std::size_t n_points() const { return status.size(); }
  std::size_t count(Status s) const;
};

// Reads the design and every committed record; throws FarmError for a file that is not
// a study results file (naming what is missing).
StudyResults read_study_results(const std::filesystem::path& file);

// Throws FarmError naming the first difference (parameter names, config keys and
// units, feature names, the model set-up, sizes, or point and parameter with both
// values) between the design in a results file and `design`.
// check_model = false skips the model set-up (for reading results, not adding to them).
void check_same_design(const StudyResults& stored, const StudyDesign& design,
                       const std::filesystem::path& file, bool check_model = true);

struct MergeSummary {
  std::size_t n_points = 0;
  std::size_t n_added = 0;       // records copied from the parts
  std::size_t n_duplicates = 0;  // identical records already present
  std::size_t n_ok = 0;          // over the merged file
  std::size_t n_failed = 0;
  std::size_t n_pending = 0;     // points no file holds a result for
};

// Copies the records of the partial files into study_file (created if missing), after
// checking that each part holds `design`. A point finished in two files with different
// results is an error naming both files.
MergeSummary merge_study_files(const StudyDesign& design, const std::filesystem::path& study_file,
                               const std::vector<std::filesystem::path>& parts);

// "1m12s", "45s", "2h03m".
std::string format_duration(double seconds);

// Whether this build of rsw supports MPI.
bool built_with_mpi();

}  // namespace rsw::calibration
