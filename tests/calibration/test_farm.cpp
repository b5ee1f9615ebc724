// The evaluation farm (calibration/farm.*): parallel worker processes give the same
// results as one; a study killed with SIGKILL and resumed equals an uninterrupted one
// without repeating finished runs; failures of every kind (returned, thrown, crashed,
// hung, an infinite feature) are recorded with their reason and the study finishes; a
// run with an undefined (NaN) feature is ok and keeps its NaN; array-job partitions
// merge into the full study; an MPI run with two ranks equals a local run; warnings of
// ok runs are recorded per run.
// The models are the analytic ones of analytic_models.hpp.
#include "calibration/designs.hpp"
#include "calibration/farm.hpp"
#include "tests/calibration/analytic_models.hpp"

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>

namespace rsw::calibration {
namespace {

namespace fs = std::filesystem;
using rsw::testing::AnalyticBehaviour;
using rsw::testing::AnalyticFunction;
using rsw::testing::AnalyticModel;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_farm_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// n_points LHS points of three parameters uniform on [0, 1] and two features.
StudyDesign unit_design(std::size_t n_points, std::uint64_t seed = 7) {
  StudyDesign design;
  design.name = "farm_test";
  design.kind = "lhs";
  for (const char* name : {"a", "b", "c"}) {
    design.parameters.add(Parameter{name, std::string("test.") + name, "1", Prior::uniform(0, 1)});
  }
  design.feature_names = {"y1", "y2"};
  design.points = design.parameters.points_to_physical(
      design.parameters.unit_points_to_standard(latin_hypercube(n_points, 3, seed)));
  design.description = "farm test design";
  return design;
}

constexpr double never = std::numeric_limits<double>::infinity();

// A model that sleeps `delay` seconds per run and misbehaves above the given values of
// the first parameter (see analytic_models.hpp).
AnalyticBehaviour behaviour(double delay, double fail_above = never, double throw_above = never,
                            double crash_above = never, double hang_above = never) {
  AnalyticBehaviour b;
  b.delay = delay;
  b.fail_above = fail_above;
  b.throw_above = throw_above;
  b.crash_above = crash_above;
  b.hang_above = hang_above;
  return b;
}

AnalyticModel smooth_model(const StudyDesign& design, AnalyticBehaviour behaviour = {}) {
  return AnalyticModel(AnalyticFunction::smooth, design.parameters.names(), design.feature_names, behaviour);
}

FarmOptions quiet_options(std::size_t n_workers) {
  FarmOptions options;
  options.n_workers = n_workers;
  options.distribution = FarmDistribution::local;
  return options;
}

// Same status, failure reasons and bit-identical features (NaN matching NaN).
void expect_same_results(const StudyResults& a, const StudyResults& b) {
  ASSERT_EQ(a.n_points(), b.n_points());
  for (std::size_t i = 0; i < a.n_points(); ++i) {
    EXPECT_EQ(a.status[i], b.status[i]) << "point " << i;
    EXPECT_EQ(a.failure_reasons[i], b.failure_reasons[i]) << "point " << i;
    for (Eigen::Index k = 0; k < a.features.cols(); ++k) {
      const double x = a.features(static_cast<Eigen::Index>(i), k), y = b.features(static_cast<Eigen::Index>(i), k);
      if (std::isnan(x) && std::isnan(y)) continue;
      EXPECT_EQ(x, y) << "point " << i << ", feature " << k;
    }
  }
}

TEST(Farm, ParallelWorkersGiveSameResultsAsSerial) {
  const fs::path dir = fresh_dir("parallel");
  const StudyDesign design = unit_design(40);
  const AnalyticModel model = smooth_model(design, behaviour(0, 0.9));
  const FarmSummary serial = EvaluationFarm(model, design, dir / "serial.h5", quiet_options(1)).run();
  const FarmSummary parallel = EvaluationFarm(model, design, dir / "parallel.h5", quiet_options(3)).run();
  EXPECT_TRUE(serial.complete);
  EXPECT_TRUE(parallel.complete);
  EXPECT_EQ(serial.n_workers, 1u);
  EXPECT_EQ(parallel.n_workers, 3u);
  EXPECT_EQ(parallel.n_evaluated, 40u);
  EXPECT_EQ(parallel.n_failed, 4u);  // one LHS stratum of width 1/40 in each tenth above 0.9
  expect_same_results(read_study_results(dir / "serial.h5"), read_study_results(dir / "parallel.h5"));
  fs::remove_all(dir);
}

TEST(Farm, KilledAndResumedStudyEqualsUninterruptedStudy) {
  const fs::path dir = fresh_dir("killed");
  const StudyDesign design = unit_design(30);
  const AnalyticModel model = smooth_model(design, behaviour(0.03));
  const std::size_t n_before_kill = 8;

  // The study runs in a child process that is killed with SIGKILL once n_before_kill
  // results are in the file. The child reports each flushed result through a pipe and,
  // after the last one, waits inside the result callback, so the kill lands between
  // two appends (an HDF5 file is not journaled: a kill inside the microseconds of a
  // flush could damage it) while both workers are in the middle of evaluations.
  int report[2];
  ASSERT_EQ(::pipe(report), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(report[0]);
    FarmOptions options = quiet_options(2);
    options.stop_on_interrupt = false;
    std::size_t n_reported = 0;
    options.on_result = [&](const RunRecord&) {
      const char byte = 1;
      if (::write(report[1], &byte, 1) != 1) _exit(3);
      if (++n_reported == n_before_kill) ::pause();
    };
    try {
      EvaluationFarm(model, design, dir / "killed.h5", options).run();
    } catch (...) {
      _exit(4);
    }
    _exit(5);  // never reached: the parent kills us first
  }
  ::close(report[1]);
  std::size_t n_seen = 0;
  char byte = 0;
  while (n_seen < n_before_kill && ::read(report[0], &byte, 1) == 1) ++n_seen;
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ::close(report[0]);
  ASSERT_EQ(n_seen, n_before_kill);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);

  const StudyResults killed = read_study_results(dir / "killed.h5");
  EXPECT_EQ(killed.count(StudyResults::Status::pending), 30 - n_before_kill);

  FarmOptions resume = quiet_options(2);
  resume.resume = true;
  const FarmSummary resumed = EvaluationFarm(model, design, dir / "killed.h5", resume).run();
  EXPECT_TRUE(resumed.complete);
  EXPECT_EQ(resumed.n_done_before, n_before_kill);
  EXPECT_EQ(resumed.n_evaluated, 30 - n_before_kill);  // finished runs are not repeated

  const FarmSummary whole = EvaluationFarm(model, design, dir / "whole.h5", quiet_options(2)).run();
  EXPECT_EQ(whole.n_evaluated, 30u);
  expect_same_results(read_study_results(dir / "killed.h5"), read_study_results(dir / "whole.h5"));
  fs::remove_all(dir);
}

TEST(Farm, InterruptStopsCleanlyAndResumeCompletesTheStudy) {
  const fs::path dir = fresh_dir("interrupt");
  const StudyDesign design = unit_design(20);
  const AnalyticModel model = smooth_model(design, behaviour(0.02));
  // SIGINT (Ctrl-C) in a child process after five results: the farm abandons the runs
  // in flight, writes the by-index arrays, closes the file and reports the interruption.
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    FarmOptions options = quiet_options(2);
    std::size_t n_results = 0;
    options.on_result = [&](const RunRecord&) {
      if (++n_results == 5) ::raise(SIGINT);
    };
    try {
      const FarmSummary summary = EvaluationFarm(model, design, dir / "s.h5", options).run();
      _exit(summary.interrupted && !summary.complete ? 0 : 1);
    } catch (...) {
      _exit(2);
    }
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << "status " << status;
  ASSERT_EQ(WEXITSTATUS(status), 0);
  const StudyResults stopped = read_study_results(dir / "s.h5");
  const std::size_t n_done = stopped.n_points() - stopped.count(StudyResults::Status::pending);
  EXPECT_GE(n_done, 5u);
  EXPECT_LT(n_done, 20u);

  FarmOptions resume = quiet_options(2);
  resume.resume = true;
  const FarmSummary resumed = EvaluationFarm(model, design, dir / "s.h5", resume).run();
  EXPECT_TRUE(resumed.complete);
  EXPECT_EQ(resumed.n_evaluated, 20 - n_done);
  EvaluationFarm(model, design, dir / "whole.h5", quiet_options(2)).run();
  expect_same_results(read_study_results(dir / "s.h5"), read_study_results(dir / "whole.h5"));
  fs::remove_all(dir);
}

TEST(Farm, FailingModelRecordsFailuresAndFinishes) {
  const fs::path dir = fresh_dir("failing");
  // LHS with 20 points puts exactly one point in each twentieth of [0, 1] for the first
  // parameter: 1 hangs (> 0.95), 2 crash (0.85..0.95), 2 throw (0.75..0.85), 3 fail
  // (0.6..0.75), 12 succeed.
  const StudyDesign design = unit_design(20);
  const AnalyticModel model =
      smooth_model(design, behaviour(0, 0.6, 0.75, 0.85, 0.95));
  FarmOptions options = quiet_options(2);
  options.run_timeout = 1.0;
  const FarmSummary summary = EvaluationFarm(model, design, dir / "failing.h5", options).run();
  EXPECT_TRUE(summary.complete);
  EXPECT_EQ(summary.n_ok, 12u);
  EXPECT_EQ(summary.n_failed, 8u);

  const StudyResults results = read_study_results(dir / "failing.h5");
  std::map<std::string, int> kinds;
  for (std::size_t i = 0; i < results.n_points(); ++i) {
    const double a = results.points(static_cast<Eigen::Index>(i), 0);
    const std::string& reason = results.failure_reasons[i];
    if (a <= 0.6) {
      EXPECT_EQ(results.status[i], StudyResults::Status::ok) << reason;
      EXPECT_TRUE(results.features.row(static_cast<Eigen::Index>(i)).allFinite());
      continue;
    }
    EXPECT_EQ(results.status[i], StudyResults::Status::failed);
    EXPECT_TRUE(results.features.row(static_cast<Eigen::Index>(i)).array().isNaN().all());
    if (a > 0.95) {
      EXPECT_NE(reason.find("exceeded the run time limit of 1s"), std::string::npos) << reason;
      ++kinds["hang"];
    } else if (a > 0.85) {
      EXPECT_NE(reason.find("worker process ended by signal 6 (Aborted) while evaluating"), std::string::npos) << reason;
      ++kinds["crash"];
    } else if (a > 0.75) {
      EXPECT_EQ(reason, "the model threw: analytic model: thrown on purpose");
      ++kinds["throw"];
    } else {
      EXPECT_NE(reason.find("analytic model: no convergence above 0.6"), std::string::npos) << reason;
      ++kinds["fail"];
    }
  }
  EXPECT_EQ(kinds["hang"], 1);
  EXPECT_EQ(kinds["crash"], 2);
  EXPECT_EQ(kinds["throw"], 2);
  EXPECT_EQ(kinds["fail"], 3);
  fs::remove_all(dir);
}

TEST(Farm, RunWithUndefinedFeatureIsOkAndStoresNaNButInfiniteValueFails) {
  const fs::path dir = fresh_dir("undefined");
  // LHS with 20 points: 8 with a > 0.6 leave y1 undefined (NaN), of which the 2 with
  // a > 0.9 are failures through y2 = +inf instead; 12 are ordinary.
  class ShapeModel : public ForwardModel {
   public:
    std::vector<std::string> parameter_names() const override { return {"a", "b", "c"}; }
    std::vector<std::string> feature_names() const override { return {"y1", "y2"}; }
    EvaluationResult evaluate(const Eigen::VectorXd& theta) const override {
      const double a = theta[0];
      const double y1 = a > 0.6 ? std::numeric_limits<double>::quiet_NaN() : a + theta[1];
      const double y2 = a > 0.9 ? std::numeric_limits<double>::infinity() : a * theta[2];
      return EvaluationResult::success(Eigen::Vector2d(y1, y2));
    }
  };
  const StudyDesign design = unit_design(20);
  const ShapeModel model;
  const FarmSummary summary = EvaluationFarm(model, design, dir / "undefined.h5", quiet_options(2)).run();
  EXPECT_EQ(summary.n_ok, 18u);
  EXPECT_EQ(summary.n_failed, 2u);

  // Read back from the HDF5 file: the NaN is stored as NaN in an ok row.
  const StudyResults results = read_study_results(dir / "undefined.h5");
  std::size_t n_undefined = 0;
  for (std::size_t i = 0; i < results.n_points(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const double a = results.points(ii, 0);
    if (a > 0.9) {
      EXPECT_EQ(results.status[i], StudyResults::Status::failed);
      EXPECT_EQ(results.failure_reasons[i], "feature 'y2' is not finite (inf)");
      continue;
    }
    EXPECT_EQ(results.status[i], StudyResults::Status::ok) << results.failure_reasons[i];
    EXPECT_EQ(results.failure_reasons[i], "");
    EXPECT_EQ(results.features(ii, 1), a * results.points(ii, 2));
    if (a > 0.6) {
      EXPECT_TRUE(std::isnan(results.features(ii, 0)));
      ++n_undefined;
    } else {
      EXPECT_EQ(results.features(ii, 0), a + results.points(ii, 1));
    }
  }
  EXPECT_EQ(n_undefined, 6u);
  fs::remove_all(dir);
}

// A successful run may carry warnings (the weld: an electrode past its solidus, a
// loosely accepted mechanics sub-step): they travel from the worker processes to the
// results file and back, only for the runs that have them; a failed run has none.
TEST(Farm, WarningsOfOkRunsAreRecordedPerRun) {
  const fs::path dir = fresh_dir("warnings");
  class WarningModel : public ForwardModel {
   public:
    std::vector<std::string> parameter_names() const override { return {"a", "b", "c"}; }
    std::vector<std::string> feature_names() const override { return {"y1", "y2"}; }
    EvaluationResult evaluate(const Eigen::VectorXd& theta) const override {
      const double a = theta[0];
      if (a > 0.9) return EvaluationResult::failure("a above 0.9");
      const Eigen::Vector2d y(a, theta[1]);
      if (a > 0.5) return EvaluationResult::success(y, "a = " + std::to_string(a) + " is above 0.5");
      return EvaluationResult::success(y);
    }
  };
  const StudyDesign design = unit_design(20);
  const WarningModel model;
  const FarmSummary summary = EvaluationFarm(model, design, dir / "warnings.h5", quiet_options(2)).run();
  EXPECT_EQ(summary.n_failed, 2u);
  const StudyResults results = read_study_results(dir / "warnings.h5");
  std::size_t n_warned = 0;
  for (std::size_t i = 0; i < results.n_points(); ++i) {
    const double a = results.points(static_cast<Eigen::Index>(i), 0);
    if (a > 0.5 && a <= 0.9) {
      EXPECT_EQ(results.warnings[i], "a = " + std::to_string(a) + " is above 0.5");
      ++n_warned;
    } else {
      EXPECT_EQ(results.warnings[i], "") << "run " << i << ", a = " << a;
    }
  }
  EXPECT_EQ(n_warned, 8u);
  fs::remove_all(dir);
}

TEST(Farm, TaskPartitionsMergeToFullStudy) {
  const fs::path dir = fresh_dir("tasks");
  const StudyDesign design = unit_design(25);
  const AnalyticModel model = smooth_model(design, behaviour(0, 0.8));
  const fs::path study_file = dir / "study.h5";
  std::vector<fs::path> parts;
  for (std::size_t i = 0; i < 3; ++i) {
    FarmOptions options = quiet_options(1);
    options.task = TaskPartition{i, 3};
    const fs::path part = task_results_file(study_file, options.task);
    EXPECT_EQ(part.filename().string(), "study.task-" + std::to_string(i) + "-of-3.h5");
    const FarmSummary summary = EvaluationFarm(model, design, part, options).run();
    EXPECT_TRUE(summary.complete);
    EXPECT_EQ(summary.n_assigned, i == 0 ? 9u : 8u);
    const StudyResults partial = read_study_results(part);
    for (std::size_t p = 0; p < partial.n_points(); ++p) {
      EXPECT_EQ(partial.status[p] == StudyResults::Status::pending, p % 3 != i) << "point " << p;
    }
    parts.push_back(part);
  }
  const MergeSummary merged = merge_study_files(design, study_file, parts);
  EXPECT_EQ(merged.n_added, 25u);
  EXPECT_EQ(merged.n_pending, 0u);
  EXPECT_EQ(merged.n_failed, 5u);
  // Merging a part again adds nothing: its records are already there, identical.
  const MergeSummary again = merge_study_files(design, study_file, {parts[1]});
  EXPECT_EQ(again.n_added, 0u);
  EXPECT_EQ(again.n_duplicates, 8u);

  EvaluationFarm(model, design, dir / "whole.h5", quiet_options(2)).run();
  expect_same_results(read_study_results(study_file), read_study_results(dir / "whole.h5"));

  // A part of another design is refused before anything is written.
  const StudyDesign other = unit_design(25, 8);
  FarmOptions options = quiet_options(1);
  options.task = TaskPartition{0, 2};
  const fs::path foreign = dir / "other.task-0-of-2.h5";
  EvaluationFarm(smooth_model(other), other, foreign, options).run();
  try {
    merge_study_files(design, study_file, {foreign});
    FAIL() << "merging a part of another design must fail";
  } catch (const FarmError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(foreign.string()), std::string::npos) << message;
    EXPECT_NE(message.find("different design"), std::string::npos) << message;
    EXPECT_NE(message.find("point 0, parameter 'a'"), std::string::npos) << message;
  }
  fs::remove_all(dir);
}

TEST(Farm, ResumeRefusesAFileOfAnotherDesignAndExistingFileNeedsResume) {
  const fs::path dir = fresh_dir("mismatch");
  const StudyDesign design = unit_design(6);
  EvaluationFarm(smooth_model(design), design, dir / "s.h5", quiet_options(1)).run();
  try {
    EvaluationFarm(smooth_model(design), design, dir / "s.h5", quiet_options(1)).run();
    FAIL() << "an existing results file needs --resume";
  } catch (const FarmError& e) {
    EXPECT_NE(std::string(e.what()).find("exists already; continue it with --resume"), std::string::npos) << e.what();
  }
  FarmOptions resume = quiet_options(1);
  resume.resume = true;
  const FarmSummary nothing_to_do = EvaluationFarm(smooth_model(design), design, dir / "s.h5", resume).run();
  EXPECT_EQ(nothing_to_do.n_evaluated, 0u);
  EXPECT_EQ(nothing_to_do.n_done_before, 6u);
  const StudyDesign other = unit_design(6, 99);
  try {
    EvaluationFarm(smooth_model(other), other, dir / "s.h5", resume).run();
    FAIL() << "resuming with another design must fail";
  } catch (const FarmError& e) {
    EXPECT_NE(std::string(e.what()).find("holds a different design"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("point 0, parameter 'a'"), std::string::npos) << e.what();
  }
  // The same points with another forward model set-up (an edited weld case) are refused too.
  StudyDesign edited = design;
  edited.model = "case fnv1a64:0123456789abcdef; set nothing";
  try {
    EvaluationFarm(smooth_model(edited), edited, dir / "s.h5", resume).run();
    FAIL() << "resuming with another model set-up must fail";
  } catch (const FarmError& e) {
    EXPECT_NE(std::string(e.what()).find("another forward model set-up"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(Farm, ProgressLineReportsRunsFailuresElapsedAndEta) {
  const fs::path dir = fresh_dir("progress");
  const StudyDesign design = unit_design(10);
  std::ostringstream progress;
  FarmOptions options = quiet_options(2);
  options.progress = &progress;
  options.progress_interval = 0;
  EvaluationFarm(smooth_model(design, behaviour(0, 0.8)), design, dir / "p.h5", options).run();
  const std::string text = progress.str();
  EXPECT_NE(text.find("study farm_test: 10 runs, 0 done before, 10 to evaluate on 2 worker processes"),
            std::string::npos) << text;
  EXPECT_NE(text.find(", elapsed "), std::string::npos) << text;
  EXPECT_NE(text.find(", ETA "), std::string::npos) << text;
  EXPECT_NE(text.find("runs 10/10, 2 failed, elapsed "), std::string::npos) << text;
  EXPECT_EQ(format_duration(72), "1m12s");
  EXPECT_EQ(format_duration(110), "1m50s");
  EXPECT_EQ(format_duration(7380), "2h03m");
  EXPECT_EQ(format_duration(9.4), "9s");
  fs::remove_all(dir);
}

TEST(Farm, TaskTextIsCheckedAndExplained) {
  const TaskPartition task = TaskPartition::parse("2/5");
  EXPECT_EQ(task.index, 2u);
  EXPECT_EQ(task.count, 5u);
  EXPECT_TRUE(task.owns(7));
  EXPECT_FALSE(task.owns(8));
  for (const char* bad : {"5/5", "1", "a/3", "1/0", "-1/3"}) {
    try {
      TaskPartition::parse(bad);
      FAIL() << bad;
    } catch (const FarmError& e) {
      EXPECT_NE(std::string(e.what()).find("expected i/n with 0 <= i < n"), std::string::npos) << e.what();
    }
  }
}

// --- MPI ------------------------------------------------------------------------------

struct CommandResult {
  int status = -1;
  std::string output;
};

CommandResult run_command(const std::string& command) {
  CommandResult result;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen((command + " 2>&1").c_str(), "r"), pclose);
  std::array<char, 4096> buffer;
  while (fgets(buffer.data(), buffer.size(), pipe.get())) result.output += buffer.data();
  result.status = WEXITSTATUS(pclose(pipe.release()));
  return result;
}

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

TEST(Farm, MpiTwoRanksEqualLocalRun) {
  const std::string mpirun = RSW_MPIRUN;
  if (!built_with_mpi()) GTEST_SKIP() << "rsw was built without MPI (install libopenmpi-dev via tools/setup.sh)";
  if (mpirun.empty() || !fs::exists(mpirun)) GTEST_SKIP() << "no mpirun (install openmpi-bin via tools/setup.sh)";
  const fs::path dir = fresh_dir("mpi");
  write_file(dir / "case.yaml", "analytic: {function: smooth, delay: 20 ms, fail_above: 0.875}\n");
  write_file(dir / "study.yaml", R"(study: {name: mpi_test}
parameters:
  - {name: a, config_key: test.a, prior: uniform, lower: 0, upper: 1}
  - {name: b, config_key: test.b, prior: log10_uniform, lower: 1e-3, upper: 1e-1}
design: {kind: lhs, n_points: 24, seed: 3}
features: [{name: y1}, {name: y2}, {name: y3}]
model: {case: case.yaml}
)");
  const std::string study = (dir / "study.yaml").string();
  const std::string binary = RSW_ANALYTIC_BINARY;
  const CommandResult local = run_command(binary + " study run " + study + " -q --workers 1 -o " + (dir / "local").string());
  ASSERT_EQ(local.status, 0) << local.output;
  const CommandResult mpi = run_command(mpirun + " -n 2 --oversubscribe --allow-run-as-root " + binary + " study run " +
                                        study + " -q --workers 1 -o " + (dir / "mpi").string());
  ASSERT_EQ(mpi.status, 0) << mpi.output;
  EXPECT_NE(mpi.output.find("over 2 MPI ranks"), std::string::npos) << mpi.output;

  const StudyResults a = read_study_results(dir / "local" / "mpi_test.h5");
  const StudyResults b = read_study_results(dir / "mpi" / "mpi_test.h5");
  EXPECT_EQ(b.count(StudyResults::Status::pending), 0u);
  EXPECT_EQ(b.count(StudyResults::Status::failed), 3u);
  expect_same_results(a, b);
  // Both ranks evaluated points (rank 0 runs its own worker besides dispatching).
  const std::set<int> ranks(b.rank.begin(), b.rank.end());
  EXPECT_EQ(ranks, (std::set<int>{0, 1})) << mpi.output;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rsw::calibration
