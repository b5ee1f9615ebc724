// `rsw calibrate` as a user runs it, and tools/plot_calibration.py on its output. The
// binary is rsw_analytic (tests/calibration/analytic_rsw_main.cpp): the same command
// (tools/calibrate_command.cpp) with the smooth analytic model of analytic_models.hpp,
// which also writes synthetic predictive signals, so a calibration takes about a second.
//   - every result file is written with its documented columns and keys;
//   - an existing calibration needs --resume; --resume reruns nothing and reproduces
//     the files exactly; a calibration stopped by SIGTERM mid-batch resumes without
//     repeating finished runs and ends like an uninterrupted one;
//   - the warnings of a calibration (why it did not converge) come before the line that
//     says whether it converged, and into the summary;
//   - a bad observation file exits with code 2 naming the study key, file and line;
//   - a calibration can start from the runs of an earlier `rsw study run`
//     (calibration.initial_runs): they are its first GP's data, none is run again, θ is
//     mapped into the unit cube through the calibration's priors, runs outside a
//     narrower prior are skipped with a note, runs of another set-up are refused, and
//     --resume replays such a calibration exactly;
//   - the twin-experiment studies load (`study show`);
//   - the plot script draws the corner plot, the convergence history and the
//     predictive overlay.
#include "calibration/farm.hpp"
#include "fem/hdf5_file.hpp"
#include "fem/output_folder.hpp"

#include "tests/tools/cli_support.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

namespace {

using rsw::testing::CommandResult;
using rsw::testing::read_file;
using rsw::testing::run_command;
using rsw::testing::write_file;

CommandResult run_rsw(const std::string& args) { return run_command(std::string(RSW_ANALYTIC_BINARY) + " " + args); }

fs::path fresh_dir(const std::string& name) { return rsw::testing::fresh_dir("rsw_calibrate_cli", name); }



// The smooth analytic model y_k = (k + 1) a + Σ_i cos((k + 1)(i + 1) θ_i / 7) of two
// parameters on [0, 1], observed three times near θ = (0.3, 0.6) (y = 2.28442,
// 2.53813), with σ = 0.05 per feature.
fs::path write_calibration_study(const fs::path& dir, const std::string& name, const std::string& case_text,
                                 int batch_size = 3, int max_evaluations = 60) {
  write_file(dir / "case.yaml", case_text);
  write_file(dir / "observed.csv", "# y at (0.3, 0.6) plus noise\nR_beta, dS_P\n2.29, 2.53\n2.28, 2.55\n2.30, 2.52\n");
  return write_file(dir / (name + ".yaml"), "study: {name: " + name + R"(}
parameters:
  - {name: a, config_key: test.a, prior: uniform, lower: 0, upper: 1}
  - {name: b, config_key: test.b, prior: uniform, lower: 0, upper: 1}
features: [{name: R_beta}, {name: dS_P}]
model: {case: case.yaml}
calibration:
  observations: {features_file: observed.csv}
  noise:
    kind: standard_deviations
    standard_deviations: [{feature: R_beta, value: 0.05}, {feature: dS_P, value: 0.05}]
  sbalc: {batch_size: )" + std::to_string(batch_size) + R"(, max_evaluations: )" +
                                                         std::to_string(max_evaluations) + R"(}
  posterior: {n_samples: 1000, n_predictive: 2}
)");
}

// A study of the same smooth analytic model with a 12-point LHS design and a
// calibration section whose initial design is `initial_runs`; `parameters` and
// `features` replace the defaults (a, b on [0, 1]; R_beta, dS_P).
fs::path write_initial_runs_study(const fs::path& dir, const std::string& name, const std::string& initial_runs,
                                  const std::string& parameters = "", const std::string& features = "",
                                  const std::string& sbalc = "{batch_size: 3, max_evaluations: 60}",
                                  const std::string& case_file = "case.yaml") {
  if (!fs::exists(dir / "case.yaml")) write_file(dir / "case.yaml", "analytic: {function: smooth}\n");
  if (!fs::exists(dir / "observed.csv"))
    write_file(dir / "observed.csv", "R_beta, dS_P, T_max\n2.29, 2.53, 1\n2.28, 2.55, 1\n2.30, 2.52, 1\n");
  const std::string default_parameters = R"(
  - {name: a, config_key: test.a, prior: uniform, lower: 0, upper: 1}
  - {name: b, config_key: test.b, prior: uniform, lower: 0, upper: 1})";
  return write_file(dir / (name + ".yaml"), "study: {name: " + name + "}\nparameters:" +
                                                (parameters.empty() ? default_parameters : parameters) + R"(
design: {kind: lhs, n_points: 12, seed: 7}
features: )" + (features.empty() ? "[{name: R_beta}, {name: dS_P}]" : features) + R"(
model: {case: )" + case_file + R"(}
calibration:
  observations: {features_file: observed.csv}
  noise: {kind: relative, fraction: 0.02}
  sbalc: )" + sbalc + R"(
  posterior: {n_samples: 1000, n_predictive: 1}
  initial_runs: )" + initial_runs + "\n");
}

// /evaluations/table of a calibration file, by column name.
struct EvaluationTable {
  std::vector<std::string> columns;
  rsw::fem::RowMajorMatrix values;
  double operator()(std::size_t row, const std::string& column) const {
    const auto k = static_cast<std::size_t>(std::find(columns.begin(), columns.end(), column) - columns.begin());
    return values(row, k);
  }
};

EvaluationTable evaluation_table(const fs::path& file) {
  const rsw::fem::Hdf5File h5(file, rsw::fem::Hdf5Mode::read);
  EvaluationTable table;
  table.columns = nlohmann::json::parse(h5.string_attribute("/evaluations/table", "columns")).get<std::vector<std::string>>();
  table.values = h5.read_matrix("/evaluations/table");
  return table;
}

bool has_line_starting(const std::string& text, const std::string& start) {
  return text.rfind(start, 0) == 0 || text.find("\n" + start) != std::string::npos;
}

}  // namespace

TEST(CalibrateCli, WritesEveryFileAndResumesIdentically) {
  const fs::path dir = fresh_dir("files");
  const fs::path study = write_calibration_study(dir, "smooth", "analytic: {function: smooth}\n");
  const fs::path out = dir / "out";
  CommandResult r = run_rsw("calibrate " + study.string() + " --workers 2 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("calibration smooth: converged after "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("calibration smooth: batch 0, 5 runs (5 new on 2 workers, 0 reused, 0 failed)"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("90 % interval ["), std::string::npos) << r.output;

  // The summary.
  const auto json = nlohmann::json::parse(read_file(out / "smooth_calibration.json"));
  EXPECT_EQ(json["study"], "smooth");
  EXPECT_TRUE(json["converged"].get<bool>()) << json.dump(2);
  const int n_runs = json["n_evaluations"].get<int>();
  EXPECT_GE(n_runs, 8);
  EXPECT_LE(n_runs, 60);
  EXPECT_EQ(json["n_reused"], 0);
  for (const char* key : {"log_evidence", "log_evidence_lower", "log_evidence_upper", "ratio"}) {
    EXPECT_TRUE(json["evidence"][key].is_number()) << key;
  }
  ASSERT_EQ(json["parameters"].size(), 2u);
  const auto& a = json["parameters"][0];
  EXPECT_EQ(a["name"], "a");
  EXPECT_NEAR(a["mean"].get<double>(), 0.3, 0.05);  // a is well determined by the observations
  EXPECT_LT(a["credible_lower"].get<double>(), 0.3);
  EXPECT_GT(a["credible_upper"].get<double>(), 0.3);
  EXPECT_TRUE(a["map"].is_number());
  EXPECT_DOUBLE_EQ(json["credible_level"].get<double>(), 0.9);
  EXPECT_GT(json["effective_sample_size"].get<double>(), 0.0);
  EXPECT_TRUE(json["warning"].is_string());
  ASSERT_TRUE(json["warnings"].is_array());
  EXPECT_EQ(json["warnings"].empty(), json["warning"].get<std::string>().empty()) << json["warnings"].dump(1);
  EXPECT_GT(json["evidence"]["pool_effective_sample_size"].get<double>(), 0.0);
  EXPECT_TRUE(json["evidence"]["pool_relative_error"].is_number());
  EXPECT_EQ(json["noise"]["kind"], "standard_deviations");
  EXPECT_DOUBLE_EQ(json["noise"]["features"][0]["measurement_standard_deviation"].get<double>(), 0.05);
  ASSERT_EQ(json["predictive"].size(), 3u);  // the posterior mean and two samples
  EXPECT_EQ(json["predictive"][0]["name"], "posterior_mean");
  for (const auto& run : json["predictive"]) {
    EXPECT_EQ(run["status"], "ok") << run.dump();
    EXPECT_TRUE(fs::exists(run["signal_file"].get<std::string>())) << run.dump();
  }

  // The tables.
  const std::string posterior = read_file(out / "smooth_posterior.csv");
  EXPECT_EQ(posterior.rfind("sample,a [1],b [1]\n0,", 0), 0u) << posterior.substr(0, 200);
  EXPECT_EQ(std::count(posterior.begin(), posterior.end(), '\n'), 1001);
  const std::string diagnostics = read_file(out / "smooth_diagnostics.csv");
  EXPECT_EQ(diagnostics.rfind("iteration,n_points,n_evaluations,log_evidence,log_evidence_lower,log_evidence_upper,"
                              "ratio,noise_ratio,tolerance_used,noise_standard_deviation,signal_variance,jitter,"
                              "log_learning_function,n_chosen,n_imputed,pool_ess,gp_ratio,pool_relative_error,"
                              "peak_spread,counted,length_scale:a,length_scale:b\n0,5,5,",
                              0),
            0u)
      << diagnostics.substr(0, 300);
  EXPECT_TRUE(fs::exists(out / "smooth_calibration.h5"));
  EXPECT_TRUE(fs::exists(out / "smooth_calibration/evaluations/runs_0000.h5"));
  EXPECT_TRUE(fs::exists(out / "smooth_calibration/predictive.h5"));

  // No silent overwrite; --resume reruns nothing and writes the same files.
  r = run_rsw("calibrate " + study.string() + " -q -o " + out.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("exists already; continue the calibration with --resume"), std::string::npos) << r.output;
  r = run_rsw("calibrate " + study.string() + " -q --resume -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("after " + std::to_string(n_runs) + " runs (" + std::to_string(n_runs) + " reused, 0 failed)"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(read_file(out / "smooth_posterior.csv"), posterior);
  EXPECT_EQ(read_file(out / "smooth_diagnostics.csv"), diagnostics);
  const auto again = nlohmann::json::parse(read_file(out / "smooth_calibration.json"));
  EXPECT_EQ(again["evidence"], json["evidence"]);
  EXPECT_EQ(again["parameters"], json["parameters"]);
  fs::remove_all(dir);
}

TEST(CalibrateCli, TerminatedCalibrationResumesWithoutRepeatingRuns) {
  const fs::path dir = fresh_dir("terminated");
  const fs::path study = write_calibration_study(dir, "slow", "analytic: {function: smooth, delay: 40 ms}\n", 2);
  const fs::path stopped = dir / "stopped", whole = dir / "whole";

  // Start the calibration, stop it with SIGTERM (a batch system's time limit) once its
  // third batch is under way.
  const fs::path log = dir / "stopped.log";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    ::execl(RSW_ANALYTIC_BINARY, "rsw_analytic", "calibrate", study.c_str(), "-q", "--workers", "2", "-o",
            stopped.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  const fs::path third = stopped / "slow_calibration/evaluations/runs_0002.h5";
  for (int k = 0; k < 600 && !fs::exists(third); ++k) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(child, SIGTERM);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(fs::exists(third)) << read_file(log);
  const std::string stopped_output = read_file(log);
  // Stopped inside a batch: a clean interrupt naming the resume command; between
  // batches (in the GP fit) the default action of SIGTERM ends the process. (On a
  // heavily loaded machine the calibration may even have finished first.)
  const bool finished = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (WIFEXITED(status) && !finished) {
    EXPECT_EQ(WEXITSTATUS(status), 1) << stopped_output;
    EXPECT_NE(stopped_output.find("interrupted"), std::string::npos) << stopped_output;
    EXPECT_NE(stopped_output.find("--resume"), std::string::npos) << stopped_output;
  } else if (!finished) {
    EXPECT_EQ(WTERMSIG(status), SIGTERM);
  }
  if (!finished) {
    EXPECT_FALSE(fs::exists(stopped / "slow_posterior.csv"));
  }

  CommandResult r = run_rsw("calibrate " + study.string() + " -q --workers 2 --resume -o " + stopped.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const std::size_t reused_at = r.output.find(" reused");
  ASSERT_NE(reused_at, std::string::npos) << r.output;
  const std::size_t open = r.output.rfind('(', reused_at);
  const int n_reused = std::stoi(r.output.substr(open + 1, reused_at - open - 1));
  EXPECT_GE(n_reused, 7) << r.output;  // the initial design and the second batch at least

  r = run_rsw("calibrate " + study.string() + " -q --workers 2 -o " + whole.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(read_file(stopped / "slow_posterior.csv"), read_file(whole / "slow_posterior.csv"));
  EXPECT_EQ(read_file(stopped / "slow_diagnostics.csv"), read_file(whole / "slow_diagnostics.csv"));
  fs::remove_all(dir);
}

// A calibration that does not converge says why before it says "NOT converged", and
// the summary lists the same warnings.
TEST(CalibrateCli, WarningsArePrintedBeforeTheConvergenceLineAndWritten) {
  const fs::path dir = fresh_dir("warnings");
  const fs::path study = write_calibration_study(dir, "capped", "analytic: {function: smooth}\n", 3, 8);
  const fs::path out = dir / "out";
  const CommandResult r = run_rsw("calibrate " + study.string() + " --no-plots -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const std::size_t warning = r.output.find("calibration capped: warning: not converged: evaluation cap of 8 reached");
  const std::size_t verdict = r.output.find("calibration capped: NOT converged after 8 runs");
  ASSERT_NE(warning, std::string::npos) << r.output;
  ASSERT_NE(verdict, std::string::npos) << r.output;
  EXPECT_LT(warning, verdict) << r.output;
  EXPECT_EQ(r.output.find("calibration capped: converged"), std::string::npos) << r.output;
  const auto json = nlohmann::json::parse(read_file(out / "capped_calibration.json"));
  EXPECT_FALSE(json["converged"].get<bool>());
  ASSERT_TRUE(json["warnings"].is_array());
  bool listed = false;
  for (const auto& w : json["warnings"])
    listed = listed || w.get<std::string>().rfind("not converged: evaluation cap of 8 reached", 0) == 0;
  EXPECT_TRUE(listed) << json["warnings"].dump(1);
  fs::remove_all(dir);
}

TEST(CalibrateCli, BadObservationFileExitsWithCodeTwoNamingKeyFileAndLine) {
  const fs::path dir = fresh_dir("bad");
  const fs::path study = write_calibration_study(dir, "bad", "analytic: {function: smooth}\n");
  write_file(dir / "observed.csv", "R_beta, dS_P\n2.29, 2.53\n2.28, x\n");
  const CommandResult r = run_rsw("calibrate " + study.string() + " -o " + (dir / "out").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("bad.yaml:8:33: calibration.observations.features_file = observed.csv: " +
                          (dir / "observed.csv").string() + ":3: column 2 ('dS_P'): 'x' is not a finite number"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "bad_calibration"));
  fs::remove_all(dir);
}

// `rsw study run` of a 12-point LHS, then `rsw calibrate` of the same study file with
// calibration.initial_runs naming it: the 12 runs are SBALC's initial design (batch 0;
// the first GP holds the successful ones and, imputed, the failed ones) and no θ of
// the study is run again.
TEST(CalibrateCli, StartsFromTheRunsOfAnEarlierStudy) {
  const fs::path dir = fresh_dir("initial_runs");
  write_file(dir / "case.yaml", "analytic: {function: smooth, fail_above: 0.85}\n");
  const fs::path study = write_initial_runs_study(dir, "sens", "sens.yaml");
  const fs::path out = dir / "out";
  CommandResult r = run_rsw("study run " + study.string() + " -q -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const rsw::calibration::StudyResults earlier = rsw::calibration::read_study_results(out / "sens.h5");
  ASSERT_EQ(earlier.n_points(), 12u);
  // The runs with a > 0.85 failed (LHS: one or two of the 12 strata of a lie above it).
  int n_failed = 0;
  for (Eigen::Index i = 0; i < 12; ++i) {
    const bool fails = earlier.points(i, 0) > 0.85;
    n_failed += fails ? 1 : 0;
    ASSERT_EQ(earlier.status[static_cast<std::size_t>(i)], fails ? rsw::calibration::StudyResults::Status::failed
                                                                 : rsw::calibration::StudyResults::Status::ok);
  }
  ASSERT_GT(n_failed, 0);
  const std::string failed = std::to_string(n_failed), ok = std::to_string(12 - n_failed);

  r = run_rsw("calibrate " + study.string() + " --workers 2 --no-plots -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("calibration sens: initial design from " + (out / "sens.h5").string() + ": 12 runs (" + ok +
                          " ok, " + failed + " failed)\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("calibration sens: batch 0, 12 runs (0 new, 12 from the study, 0 reused, " + failed +
                          " failed)"),
            std::string::npos)
      << r.output;
  const auto json = nlohmann::json::parse(read_file(out / "sens_calibration.json"));
  EXPECT_TRUE(json["converged"].get<bool>()) << r.output;
  EXPECT_EQ(json["n_from_study"], 12);
  EXPECT_EQ(json["n_reused"], 0);
  EXPECT_EQ(json["initial_runs"]["n_runs"], 12);
  EXPECT_NEAR(json["parameters"][0]["mean"].get<double>(), 0.3, 0.05);  // as without the study's runs
  // The first GP: the ok runs as data points, the failed ones imputed (impute_minimum).
  const std::string diagnostics = read_file(out / "sens_diagnostics.csv");
  std::istringstream lines(diagnostics);
  std::string header, first;
  std::getline(lines, header);
  std::getline(lines, first);
  const auto field = [](const std::string& line, const std::string& header_line, const std::string& name) {
    std::vector<std::string> names, values;
    std::istringstream h(header_line), v(line);
    for (std::string x; std::getline(h, x, ',');) names.push_back(x);
    for (std::string x; std::getline(v, x, ',');) values.push_back(x);
    return values.at(static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin()));
  };
  EXPECT_EQ(field(first, header, "iteration"), "0");
  EXPECT_EQ(field(first, header, "n_points"), ok) << first;
  EXPECT_EQ(field(first, header, "n_imputed"), failed) << first;
  EXPECT_EQ(field(first, header, "n_evaluations"), "12") << first;

  // The first 12 evaluations are the study's runs in order, θ as stored, u = θ (uniform
  // priors on [0, 1]); the rest are SBALC's own.
  const int n_evaluations = json["n_evaluations"].get<int>();
  const EvaluationTable table = evaluation_table(out / "sens_calibration.h5");
  ASSERT_EQ(table.values.n_rows, static_cast<std::size_t>(n_evaluations));
  for (std::size_t i = 0; i < table.values.n_rows; ++i) {
    EXPECT_EQ(table(i, "from_study"), i < 12 ? 1.0 : 0.0) << i;
    if (i >= 12) continue;
    const auto ii = static_cast<Eigen::Index>(i);
    EXPECT_EQ(table(i, "batch"), 0.0);
    EXPECT_EQ(table(i, "theta:a"), earlier.points(ii, 0)) << i;
    EXPECT_EQ(table(i, "theta:b"), earlier.points(ii, 1)) << i;
    EXPECT_EQ(table(i, "u:a"), earlier.points(ii, 0)) << i;
    EXPECT_EQ(table(i, "ok"), earlier.points(ii, 0) > 0.85 ? 0.0 : 1.0) << i;
    if (earlier.points(ii, 0) <= 0.85) {
      EXPECT_EQ(table(i, "y:R_beta"), earlier.features(ii, 0)) << i;
    }
  }
  // What the calibration ran: each of its other runs once, none of the study's points.
  std::size_t n_run = 0;
  for (const auto& entry : fs::directory_iterator(out / "sens_calibration/evaluations")) {
    const rsw::calibration::StudyResults runs = rsw::calibration::read_study_results(entry.path());
    n_run += runs.n_points();
    for (Eigen::Index i = 0; i < runs.points.rows(); ++i)
      for (Eigen::Index k = 0; k < earlier.points.rows(); ++k)
        EXPECT_FALSE(runs.points.row(i) == earlier.points.row(k)) << entry.path() << " runs study point " << k;
  }
  EXPECT_EQ(n_run, static_cast<std::size_t>(n_evaluations - 12));
  EXPECT_EQ(rsw::calibration::read_study_results(out / "sens_calibration/evaluations/runs_0000.h5").n_points(), 3u)
      << "the first file holds SBALC's first batch";

  // --resume replays it: the study's runs again from the study, the rest from the cache.
  const std::string posterior = read_file(out / "sens_posterior.csv");
  r = run_rsw("calibrate " + study.string() + " -q --no-plots --resume -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("after " + std::to_string(n_evaluations) + " runs (12 from the study, " +
                          std::to_string(n_evaluations - 12) + " reused, "),
            std::string::npos)
      << r.output;
  EXPECT_EQ(read_file(out / "sens_posterior.csv"), posterior);
  fs::remove_all(dir);
}

// A prior narrower than the study's: the runs outside it are skipped with a note, the
// rest mapped into the unit cube through the calibration's priors, and Hammersley
// points fill the initial design up to initial_points.
TEST(CalibrateCli, InitialRunsOutsideANarrowerPriorAreSkipped) {
  const fs::path dir = fresh_dir("narrower");
  const fs::path study = write_initial_runs_study(dir, "sens", "sens.yaml");
  CommandResult r = run_rsw("study run " + study.string() + " -q -o " + (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.output;
  const rsw::calibration::StudyResults earlier = rsw::calibration::read_study_results(dir / "out/sens.h5");
  int n_outside = 0;
  for (Eigen::Index i = 0; i < earlier.points.rows(); ++i) n_outside += earlier.points(i, 0) > 0.5 ? 1 : 0;
  ASSERT_GT(n_outside, 0);
  const int n_inside = 12 - n_outside;
  ASSERT_LT(n_inside, 9);
  const fs::path narrow = write_initial_runs_study(dir, "narrow", "out/sens.h5", R"(
  - {name: a, config_key: test.a, prior: uniform, lower: 0, upper: 0.5}
  - {name: b, config_key: test.b, prior: uniform, lower: 0, upper: 1})", "", "{batch_size: 3, max_evaluations: 60, initial_points: 9}");
  r = run_rsw("calibrate " + narrow.string() + " --no-plots -o " + (dir / "narrow_out").string());
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string n = std::to_string(n_outside);
  EXPECT_NE(r.output.find(": " + std::to_string(n_inside) + " runs (" + std::to_string(n_inside) +
                          " ok, 0 failed) and " + std::to_string(9 - n_inside) + " Hammersley points\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("  note: the prior of a is uniform [0, 0.5] here, uniform [0, 1] in the study\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("  note: " + n + " runs outside the calibration's prior box skipped (" + n +
                          " with a outside uniform [0, 0.5])\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("batch 0, 9 runs (" + std::to_string(9 - n_inside) + " new on "), std::string::npos)
      << r.output;
  const EvaluationTable table = evaluation_table(dir / "narrow_out/narrow_calibration.h5");
  std::size_t row = 0;
  for (Eigen::Index i = 0; i < earlier.points.rows(); ++i) {
    if (earlier.points(i, 0) > 0.5) continue;
    EXPECT_EQ(table(row, "from_study"), 1.0);
    EXPECT_EQ(table(row, "theta:a"), earlier.points(i, 0));
    EXPECT_NEAR(table(row, "u:a"), earlier.points(i, 0) / 0.5, 1e-15);  // u = F(θ) of uniform [0, 0.5]
    ++row;
  }
  EXPECT_EQ(table(row, "from_study"), 0.0);
  fs::remove_all(dir);
}

TEST(CalibrateCli, InitialRunsOfAnotherSetUpAreRefused) {
  const fs::path dir = fresh_dir("refused");
  const fs::path study = write_initial_runs_study(dir, "sens", "sens.yaml");
  CommandResult r = run_rsw("study run " + study.string() + " -q -o " + (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string file = (dir / "out/sens.h5").string();
  write_file(dir / "other_case.yaml", "analytic: {function: smooth, delay: 0 ms}\n");
  struct Case {
    fs::path study;
    std::string message;
  };
  const std::vector<Case> cases = {
      {write_initial_runs_study(dir, "model", "out/sens.h5", "", "", "{batch_size: 3, max_evaluations: 60}",
                                "other_case.yaml"),
       "calibration.initial_runs = out/sens.h5: study results file '" + file +
           "' holds runs of another forward model set-up: 'case fnv1a64:"},
      {write_initial_runs_study(dir, "names", "out/sens.h5", R"(
  - {name: a, config_key: test.a, prior: uniform, lower: 0, upper: 1}
  - {name: c, config_key: test.c, prior: uniform, lower: 0, upper: 1})"),
       "study results file '" + file + "' has the parameters (a, b), the calibration (a, c)"},
      {write_initial_runs_study(dir, "units", "out/sens.h5", R"(
  - {name: a, config_key: test.a, prior: uniform, lower: 0, upper: 1}
  - {name: b, config_key: test.b, unit: m, prior: uniform, lower: 0, upper: 1})"),
       "sets parameter 'b' as test.b [1], the calibration as test.b [m]"},
      {write_initial_runs_study(dir, "features", "out/sens.h5", "", "[{name: R_beta}, {name: T_max}]"),
       "has no feature T_max (it has R_beta, dS_P)"},
      {write_initial_runs_study(dir, "cap", "out/sens.h5", "", "", "{max_evaluations: 12}"),
       "calibration.sbalc.max_evaluations = 12: the initial design holds 12 runs of " + file +
           " (calibration.initial_runs), and the cap counts them; allowed: more than 12"},
      {write_initial_runs_study(dir, "missing", "out/none.h5"),
       "calibration.initial_runs = out/none.h5: no such file (looked for " + (dir / "out/none.h5").string()},
  };
  for (const Case& c : cases) {
    r = run_rsw("calibrate " + c.study.string() + " -q --no-plots -o " + (dir / "refused_out").string());
    EXPECT_EQ(r.status, 2) << c.study << "\n" << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.study << "\n" << r.output;
    EXPECT_NE(r.output.find(c.study.filename().string() + ":"), std::string::npos) << r.output;  // where it was set
  }
  EXPECT_FALSE(fs::exists(dir / "refused_out"));
  fs::remove_all(dir);
}

TEST(CalibrateCli, TwinStudiesShowTheirCalibrationSection) {
  for (const char* name : {"twin_p1", "twin_multi"}) {
    const CommandResult r =
        run_rsw("study show " + std::string(RSW_SOURCE_DIR) + "/validation/twin/" + name + ".yaml");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(has_line_starting(r.output, "calibration:")) << r.output;
    EXPECT_NE(r.output.find("paper_case/weld.yaml"), std::string::npos) << r.output;
  }
}

TEST(CalibrateCli, PlotScriptDrawsCornerConvergenceAndPredictive) {
  const CommandResult has_libraries = run_command("/usr/bin/python3 -c 'import matplotlib, h5py, numpy'");
  if (has_libraries.status != 0) {
    GTEST_SKIP() << "/usr/bin/python3 lacks matplotlib, h5py or numpy (run tools/setup.sh): " << has_libraries.output;
  }
  const fs::path dir = fresh_dir("plot");
  const fs::path study = write_calibration_study(dir, "plotted", "analytic: {function: smooth}\n");
  const fs::path out = dir / "out";
  CommandResult r = run_rsw("calibrate " + study.string() + " -q -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string script = "/usr/bin/python3 " + std::string(RSW_SOURCE_DIR) + "/tools/plot_calibration.py ";
  r = run_command(script + (out / "plotted_calibration.json").string() + " --truth a=0.3 b=0.6 --measured " +
                  std::string(RSW_SOURCE_DIR) + "/validation/signals/measured_example.csv -o " +
                  (dir / "plots").string());
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* file : {"plotted_corner.png", "plotted_convergence.png", "plotted_predictive.png"}) {
    EXPECT_TRUE(fs::exists(dir / "plots" / file)) << file << "\n" << r.output;
    EXPECT_GT(fs::file_size(dir / "plots" / file), 10000u) << file;
  }
  // From the .h5 too, into the result's folder; a wrong --truth name is an error.
  r = run_command(script + (out / "plotted_calibration.h5").string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "plotted_corner.png"));
  r = run_command(script + (out / "plotted_calibration.json").string() + " --truth c=1");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("no parameter 'c' (the calibration has: a, b)"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

// One command gives the tables and the pictures: rsw calibrate runs
// tools/plot_calibration.py itself; --no-plots skips it, and a missing interpreter
// is a note with the command to run later, not a failure.
TEST(CalibrateCli, WritesPlotsUnlessToldNotTo) {
  const CommandResult has_libraries = run_command("/usr/bin/python3 -c 'import matplotlib, h5py, numpy'");
  if (has_libraries.status != 0) {
    GTEST_SKIP() << "/usr/bin/python3 lacks matplotlib, h5py or numpy (run tools/setup.sh): " << has_libraries.output;
  }
  const fs::path dir = fresh_dir("autoplot");
  const fs::path study = write_calibration_study(dir, "auto", "analytic: {function: smooth}\n");
  CommandResult r = run_rsw("calibrate " + study.string() + " -q -o " + (dir / "with").string());
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* file : {"auto_corner.png", "auto_convergence.png"}) {
    EXPECT_TRUE(fs::exists(dir / "with" / file)) << file << "\n" << r.output;
  }
  r = run_rsw("calibrate " + study.string() + " -q --no-plots -o " + (dir / "without").string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "without" / "auto_calibration.json"));
  EXPECT_FALSE(fs::exists(dir / "without" / "auto_corner.png"));
  r = run_command("RSW_PYTHON=/nonexistent/python3 " + std::string(RSW_ANALYTIC_BINARY) + " calibrate " + study.string() +
                  " -q -o " + (dir / "nopython").string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("note: plots not made (/nonexistent/python3 not found"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir / "nopython" / "auto_calibration.json"));
  fs::remove_all(dir);
}

// The output folder (fem/output_folder.hpp): a folder rsw did not make is refused
// (here the study file's own), and so is a calibration whose folder another run holds;
// a resume refused at its start removes nothing.
TEST(CalibrateCli, RefusesAFolderItDidNotMakeAndACalibrationFolderInUse) {
  const fs::path dir = fresh_dir("folders");
  const fs::path study = write_calibration_study(dir, "busy", "analytic: {function: smooth}\n", 3, 9);
  CommandResult r = run_rsw("calibrate " + study.string() + " -q --no-plots -o " + dir.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("output folder '" + dir.string() + "' holds entries rsw did not write"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("--overwrite"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "busy_calibration"));

  const fs::path out = dir / "out";
  {
    rsw::fem::OutputFolderOptions other;
    other.kind = "calibrate";
    const rsw::fem::OutputFolder held(out / "busy_calibration", other);
    r = run_rsw("calibrate " + study.string() + " -q --no-plots --resume -o " + out.string());
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("busy_calibration' is in use by another rsw run"), std::string::npos) << r.output;
  }
  // Free again, and the marker alone is no earlier calibration.
  r = run_rsw("calibrate " + study.string() + " -q --no-plots -o " + out.string());
  EXPECT_EQ(r.status, 0) << r.output;
  const std::string summary = read_file(out / "busy_calibration.json");
  // A resume refused at its start (the model changed) leaves the result as it was.
  write_file(dir / "case.yaml", "analytic: {function: smooth, fail_above: 0.99}\n");
  r = run_rsw("calibrate " + study.string() + " -q --no-plots --resume -o " + out.string());
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("another forward model set-up"), std::string::npos) << r.output;
  EXPECT_EQ(read_file(out / "busy_calibration.json"), summary);
  fs::remove_all(dir);
}
