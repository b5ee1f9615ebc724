// A study whose forward model is an external command (model.command,
// calibration/command_model.hpp), through the rsw program as a user runs it: no weld is
// run. The command is tests/tools/data/linear_model.py, which reads parameters.json and
// writes features.json with
//     y_sum = a + b,   y_diff = a − b,
// and misbehaves on purpose where asked (its options, on the parameter a).
//   - `rsw study run` gives exactly the closed form at every point;
//   - a command that exits with code 1, one that writes no features.json and one that
//     outlives the run time limit are failed runs with their reasons, the study goes
//     on, and a NaN feature is an undefined feature of an ok run; the command stopped at
//     the time limit does not outlive its worker;
//   - `rsw calibrate` on a two-parameter Gaussian problem gives the posterior mean and
//     standard deviation and the evidence of the closed form (derived below);
//   - bad model.command values are input errors (exit code 2) naming the key.
#include "tests/tools/cli_support.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
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

CommandResult run_rsw(const std::string& args) { return run_command(std::string(RSW_BINARY) + " " + args); }

fs::path fresh_dir(const std::string& name) { return rsw::testing::fresh_dir("rsw_command_cli", name); }



// The model script, copied next to the study file (so that the study names it
// relative to its own folder, as a user's would).
void copy_model(const fs::path& dir) {
  fs::copy_file(fs::path(RSW_SOURCE_DIR) / "tests/tools/data/linear_model.py", dir / "linear_model.py",
                fs::copy_options::overwrite_existing);
}

fs::path write_study(const fs::path& dir, const std::string& name, const std::string& command, int n_points,
                     const std::string& extra = "") {
  copy_model(dir);
  return write_file(dir / (name + ".yaml"), "study: {name: " + name + R"(, output: out}
parameters:
  - {name: a, prior: uniform, lower: 0, upper: 1}
  - {name: b, prior: uniform, lower: 0, upper: 1}
design: {kind: hammersley, n_points: )" + std::to_string(n_points) + R"(}
features: [{name: y_sum}, {name: y_diff}]
model: {command: ")" + command + R"("}
)" + extra);
}

// Whether process `pid` has ended: no such process, or a zombie nobody has reaped yet
// (an orphan's parent in a container need not reap).
bool process_ended(pid_t pid) {
  if (::kill(pid, 0) != 0 && errno == ESRCH) return true;
  const std::string stat = read_file("/proc/" + std::to_string(pid) + "/stat");
  const std::size_t close = stat.rfind(')');
  return close != std::string::npos && close + 2 < stat.size() && stat[close + 2] == 'Z';
}

nlohmann::json runs_of(const fs::path& dir, const std::string& name) {
  return nlohmann::json::parse(read_file(dir / "out" / (name + "_runs.json")))["runs"];
}

}  // namespace

TEST(CommandModelCli, StudyRunGivesTheClosedFormAtEveryPoint) {
  const fs::path dir = fresh_dir("closed_form");
  // The script itself as the program (found in the study's folder, run through its
  // #! line).
  const fs::path study = write_study(dir, "linear", "linear_model.py", 12);
  CommandResult r = run_rsw("study show " + study.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("# command: " + (dir / "linear_model.py").string()), std::string::npos) << r.output;

  r = run_rsw("study run " + study.string() + " --workers 2 -q");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("12/12 runs done (12 now, 0 before), 0 failed"), std::string::npos) << r.output;
  const auto runs = runs_of(dir, "linear");
  ASSERT_EQ(runs.size(), 12u);
  for (const auto& run : runs) {
    ASSERT_EQ(run["status"], "ok") << run.dump();
    const double a = run["theta"]["a"].get<double>(), b = run["theta"]["b"].get<double>();
    // θ reaches the script as shortest round-trip decimal text and the features come
    // back the same way, so the double sums agree exactly.
    EXPECT_EQ(run["features"]["y_sum"].get<double>(), a + b) << run.dump();
    EXPECT_EQ(run["features"]["y_diff"].get<double>(), a - b) << run.dump();
  }
  // The model set-up names the command and the hash of its script: an edited script
  // is another model, which --resume refuses.
  write_file(dir / "linear_model.py", read_file(dir / "linear_model.py") + "# edited\n");
  r = run_rsw("study run " + study.string() + " -q --resume");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("another forward model set-up"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("command linear_model.py; linear_model.py fnv1a64:"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(CommandModelCli, FailedCommandsAreRecordedWithTheirReasonsAndTheStudyGoesOn) {
  const fs::path dir = fresh_dir("failures");
  const fs::path pids = dir / "pids.txt";
  // Through the interpreter named first, with arguments; a above 0.8 exits with code 1,
  // below 0.2 writes nothing, in (0.6, 0.7] leaves y_diff undefined, in (0.7, 0.8]
  // sleeps past the 2 s limit.
  const fs::path study = write_study(dir, "misbehaving",
                                     "/usr/bin/python3 linear_model.py --fail-above 0.8 --silent-below 0.2 "
                                     "--undefined-above 0.6 --sleep-above 0.7 --pid-file " + pids.string(),
                                     20);
  // A temporary directory of its own: what the runs leave there is checked at the end.
  const fs::path tmp = dir / "tmp";
  fs::create_directories(tmp);
  const CommandResult r = run_command("TMPDIR=" + tmp.string() + " " + std::string(RSW_BINARY) + " study run " +
                                      study.string() + " --workers 2 --timeout 2 -q");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto runs = runs_of(dir, "misbehaving");
  ASSERT_EQ(runs.size(), 20u);
  int n_exit = 0, n_silent = 0, n_undefined = 0, n_slow = 0, n_ok = 0;
  for (const auto& run : runs) {
    const double a = run["theta"]["a"].get<double>(), b = run["theta"]["b"].get<double>();
    if (a > 0.8) {
      ++n_exit;
      ASSERT_EQ(run["status"], "failed") << run.dump();
      std::ostringstream message;
      message << "the command exited with code 1; its stderr ends: linear_model.py: starting | linear_model.py: a = ";
      EXPECT_EQ(run["failure_reason"].get<std::string>().rfind(message.str(), 0), 0u) << run.dump();
      EXPECT_NE(run["failure_reason"].get<std::string>().find(" is above 0.8"), std::string::npos) << run.dump();
    } else if (a > 0.7) {
      ++n_slow;
      ASSERT_EQ(run["status"], "failed") << run.dump();
      EXPECT_EQ(run["failure_reason"], "exceeded the run time limit of 2s and was stopped") << run.dump();
    } else if (a < 0.2) {
      ++n_silent;
      ASSERT_EQ(run["status"], "failed") << run.dump();
      EXPECT_EQ(run["failure_reason"], "the command exited with code 0 but wrote no features.json; it wrote nothing "
                                       "to stderr")
          << run.dump();
    } else if (a > 0.6) {
      ++n_undefined;
      ASSERT_EQ(run["status"], "ok") << run.dump();
      EXPECT_EQ(run["features"]["y_sum"].get<double>(), a + b);
      EXPECT_TRUE(run["features"]["y_diff"].is_null()) << run.dump();
      EXPECT_EQ(run["undefined_features"]["y_diff"], "the model returned NaN") << run.dump();
    } else {
      ++n_ok;
      ASSERT_EQ(run["status"], "ok") << run.dump();
      EXPECT_EQ(run["features"]["y_diff"].get<double>(), a - b);
    }
  }
  // Hammersley's first coordinate is evenly spread, so every band has runs.
  EXPECT_GT(n_exit, 0);
  EXPECT_GT(n_silent, 0);
  EXPECT_GT(n_undefined, 0);
  EXPECT_GT(n_slow, 0);
  EXPECT_GT(n_ok, 0);
  EXPECT_NE(r.output.find("y_diff undefined in " + std::to_string(n_undefined) + " ok run"), std::string::npos)
      << r.output;
  // Every command has ended, those stopped at the time limit included (they die with
  // their worker).
  std::istringstream pid_lines(read_file(pids));
  int n_commands = 0;
  for (std::string line; std::getline(pid_lines, line);) {
    ++n_commands;
    const pid_t pid = static_cast<pid_t>(std::stol(line));
    bool gone = false;
    for (int k = 0; k < 200 && !gone; ++k) {
      gone = process_ended(pid);
      if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_TRUE(gone) << "command process " << pid << " outlived the study";
  }
  EXPECT_EQ(n_commands, 20);
  // No run folder is left behind, not even those of the workers killed at the time limit
  // (the farm's workers keep them in its own folder and it removes that at the end).
  for (const auto& entry : fs::directory_iterator(tmp)) ADD_FAILURE() << "left behind: " << entry.path();
  fs::remove_all(dir);
}

// Two parameters with uniform priors on [0, 1], the model y_sum = a + b, y_diff = a − b,
// N = 2 replicates y_k = (y_sum,k, y_diff,k) with σ = 0.1 on each feature:
//   y_1 = (1.03, −0.19), y_2 = (0.99, −0.23).
// With p_k = (y_sum,k + y_diff,k)/2 and q_k = (y_sum,k − y_diff,k)/2, the residuals
// satisfy (y_sum − a − b)² + (y_diff − a + b)² = 2(p − a)² + 2(q − b)², so
//   ln L(a, b) = −N ln(2πσ²) − (S_p + S_q)/σ² − (N/σ²)[(p̄ − a)² + (q̄ − b)²],
// S_p = Σ(p_k − p̄)², S_q likewise. Here p = (0.42, 0.38), p̄ = 0.40, S_p = 8·10⁻⁴;
// q = (0.61, 0.61), q̄ = 0.61, S_q = 0. The posterior is a product of normals:
//   a ~ N(p̄, σ²/(2N)) = N(0.40, 0.05²),   b ~ N(q̄, σ²/(2N)) = N(0.61, 0.05²),
// truncated to [0, 1], whose edges lie 7.8 standard deviations or more away (mass
// outside below 4·10⁻¹⁵, neglected). The evidence, with prior density 1:
//   c = ∫∫ L da db = (2πσ²)^(−N) e^(−(S_p + S_q)/σ²) · π σ²/N,
//   ln c = −2 ln(0.02π) − 0.08 + ln(0.005π) = 1.300999.
// Accuracy asked of SBALC: converged means a ratio (c_upper − c_lower)/ĉ below its
// tolerance 0.1, so ln ĉ within 0.1; the posterior moments come from the importance-
// weighted pool, whose effective sample size for this posterior is about
// N_M · 4π (0.05)² ≈ 600 of N_M = 20000, so means within 0.01 (a fifth of a standard
// deviation, three Monte Carlo standard errors) and standard deviations within 15 %.
TEST(CommandModelCli, CalibrationOfATwoParameterGaussianProblemMatchesTheClosedForm) {
  const fs::path dir = fresh_dir("gaussian");
  write_file(dir / "observed.csv", "y_sum, y_diff\n1.03, -0.19\n0.99, -0.23\n");
  const fs::path study = write_study(dir, "gaussian", "/usr/bin/python3 linear_model.py", 12, R"(calibration:
  observations: {features_file: observed.csv}
  noise:
    kind: standard_deviations
    standard_deviations: [{feature: y_sum, value: 0.1}, {feature: y_diff, value: 0.1}]
  sbalc: {max_evaluations: 80, nugget: "off"}
  posterior: {n_samples: 1000, n_predictive: 1}
)");
  const CommandResult r = run_rsw("calibrate " + study.string() + " --workers 2 -q --no-plots");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto json = nlohmann::json::parse(read_file(dir / "out" / "gaussian_calibration.json"));
  ASSERT_TRUE(json["converged"].get<bool>()) << r.output;
  EXPECT_EQ(json["n_failed"], 0);
  EXPECT_NEAR(json["evidence"]["log_evidence"].get<double>(), 1.300999, 0.1) << r.output;
  const auto& a = json["parameters"][0];
  const auto& b = json["parameters"][1];
  EXPECT_NEAR(a["mean"].get<double>(), 0.40, 0.01) << r.output;
  EXPECT_NEAR(b["mean"].get<double>(), 0.61, 0.01) << r.output;
  EXPECT_NEAR(a["standard_deviation"].get<double>(), 0.05, 0.0075) << r.output;
  EXPECT_NEAR(b["standard_deviation"].get<double>(), 0.05, 0.0075) << r.output;
  // A command has no signals: the predictive runs are recorded as such.
  ASSERT_EQ(json["predictive"].size(), 2u);
  EXPECT_EQ(json["predictive"][0]["status"], "no_signals");
  fs::remove_all(dir);
}

// The same problem by the emulator route (calibration.method: emulator): its evidence
// comes from importance sampling of a posterior that the emulators (a quadratic trend
// holds this linear model exactly) reproduce, so it must match the closed form to 5 %
// (ln 1.05 = 0.049); the moments come from a pool with an effective sample size of
// thousands, so means within 0.005 (a tenth of a standard deviation) and standard
// deviations within 5 %. The summary records the method and calls both parameters
// identified (posterior sd 0.05 against the prior's 0.289).
TEST(CommandModelCli, EmulatorCalibrationOfATwoParameterGaussianProblemMatchesTheClosedForm) {
  const fs::path dir = fresh_dir("gaussian_emulator");
  write_file(dir / "observed.csv", "y_sum, y_diff\n1.03, -0.19\n0.99, -0.23\n");
  const fs::path study = write_study(dir, "gaussian", "/usr/bin/python3 linear_model.py", 12, R"(calibration:
  method: emulator
  observations: {features_file: observed.csv}
  noise:
    kind: standard_deviations
    standard_deviations: [{feature: y_sum, value: 0.1}, {feature: y_diff, value: 0.1}]
  emulator: {max_evaluations: 40}
  posterior: {n_samples: 1000, n_predictive: 1}
)");
  const CommandResult r = run_rsw("calibrate " + study.string() + " --workers 2 -q --no-plots");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto json = nlohmann::json::parse(read_file(dir / "out" / "gaussian_calibration.json"));
  EXPECT_EQ(json["method"], "emulator");
  ASSERT_TRUE(json["converged"].get<bool>()) << r.output;
  EXPECT_LE(json["n_evaluations"].get<int>(), 40);
  EXPECT_NEAR(json["evidence"]["log_evidence"].get<double>(), 1.300999, 0.049) << r.output;
  const auto& a = json["parameters"][0];
  const auto& b = json["parameters"][1];
  EXPECT_NEAR(a["mean"].get<double>(), 0.40, 0.005) << r.output;
  EXPECT_NEAR(b["mean"].get<double>(), 0.61, 0.005) << r.output;
  EXPECT_NEAR(a["standard_deviation"].get<double>(), 0.05, 0.0025) << r.output;
  EXPECT_NEAR(b["standard_deviation"].get<double>(), 0.05, 0.0025) << r.output;
  EXPECT_EQ(a["identification"], "identified");
  EXPECT_EQ(b["identification"], "identified");
  fs::remove_all(dir);
}

TEST(CommandModelCli, BadCommandsAreInputErrorsNamingTheKey) {
  const fs::path dir = fresh_dir("errors");
  struct Case {
    std::string command, subcommand, message;
  };
  const std::vector<Case> cases = {
      {"/usr/bin/python3 linear_model.py > out.txt", "show",
       "model.command = /usr/bin/python3 linear_model.py > out.txt: '>' at character 34 would mean something to a "
       "shell, but the command runs without one"},
      {"python3 'linear_model.py", "show", "the quote ' at character 9 is not closed"},
      {"no_such_program_of_rsw --x", "run", "no program 'no_such_program_of_rsw' in the study file's folder or on PATH"},
      {"./missing.py", "show", "no program " + (dir / "missing.py").string() + "; allowed: an executable file"},
      {"observed.txt", "show", "the program " + (dir / "observed.txt").string() + " is not an executable file"},
  };
  write_file(dir / "observed.txt", "not a program\n");
  for (const Case& c : cases) {
    const fs::path study = write_study(dir, "bad", c.command, 4);
    const CommandResult r = run_rsw("study " + c.subcommand + " " + study.string() + (c.subcommand == "run" ? " -q" : ""));
    EXPECT_EQ(r.status, 2) << c.command << "\n" << r.output;
    EXPECT_NE(r.output.find("bad.yaml:"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.command << "\n" << r.output;
  }
  // A command and a weld case, or a command and weld-case overrides, are refused.
  write_file(dir / "both.yaml", R"(parameters: [{name: a, lower: 0, upper: 1}]
features: [{name: y_sum}]
model: {command: linear_model.py, case: weld.yaml}
)");
  CommandResult r = run_rsw("study show " + (dir / "both.yaml").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("model.command = linear_model.py: given together with model.case"), std::string::npos)
      << r.output;
  fs::remove_all(dir);
}
