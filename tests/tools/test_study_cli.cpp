// `rsw features` and `rsw study` as a user runs them (including signals and runs whose
// shape leaves features undefined), and tools/plot_study.py on their output. The binary is rsw_analytic (tests/calibration/analytic_rsw_main.cpp): the
// same commands (tools/study_commands.cpp) with analytic forward models in place of
// the weld simulator, so a study takes well under a second.
#include "calibration/farm.hpp"

#include "tests/tools/cli_support.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

using rsw::testing::CommandResult;
using rsw::testing::read_file;
using rsw::testing::run_command;
using rsw::testing::write_file;

CommandResult run_rsw(const std::string& args) { return run_command(std::string(RSW_ANALYTIC_BINARY) + " " + args); }

fs::path fresh_dir(const std::string& name) { return rsw::testing::fresh_dir("rsw_study_cli", name); }



const std::string shipped_signal = std::string(RSW_SOURCE_DIR) + "/validation/signals/measured_example.csv";

// A small LHS study of the smooth analytic model with the weld's feature names.
fs::path write_lhs_study(const fs::path& dir, const std::string& name, int n_points) {
  write_file(dir / "case.yaml", "analytic: {function: smooth, fail_above: 0.95}\n");
  return write_file(dir / (name + ".yaml"), "study: {name: " + name + R"(}
parameters:
  - {name: a, config_key: test.a, prior: uniform, lower: 0, upper: 1}
  - {name: p1, config_key: test.p1, prior: log10_uniform, lower: 1e-3, upper: 1e-1}
  - {name: c, config_key: test.c, prior: truncated_normal, mean: 2, standard_deviation: 1, lower: 0, upper: 5}
design: {kind: lhs, n_points: )" + std::to_string(n_points) + R"(, seed: 4}
features: [{name: R_beta}, {name: dS_P}, {name: T_max}, {name: d_n_liq}]
model: {case: case.yaml}
)");
}

}  // namespace

TEST(Features, CliPrintsFeaturesOfShippedSignal) {
  const fs::path dir = fresh_dir("features");
  const fs::path json_path = dir / "features.json";
  const CommandResult r = run_rsw("features " + shipped_signal + " -o " + json_path.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("weld stage 1.00 .. 148.98 ms"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("feature grid 1 ms (signal sampled every 0.2 ms)\n"), std::string::npos) << r.output;
  for (const char* name : {"R_alpha", "R_beta", "R_gamma", "t_beta", "m_1", "R_m", "dS_P", "S_end", "dS_net", "S_dot_exp"}) {
    EXPECT_NE(r.output.find(std::string("  ") + name + " "), std::string::npos) << name << "\n" << r.output;
  }
  // The synthetic weld: resistance peak near 180 µΩ, expansion near 30 µm.
  const auto json = nlohmann::json::parse(read_file(json_path));
  const double r_beta = json["features"]["R_beta"]["value"].get<double>();
  const double ds_p = json["features"]["dS_P"]["value"].get<double>();
  EXPECT_NEAR(r_beta, 180e-6, 5e-6);
  EXPECT_NEAR(ds_p, 32e-6, 4e-6);
  EXPECT_EQ(json["features"]["R_beta"]["unit"], "ohm");
  EXPECT_NEAR(json["weld_stage"]["peak_current"].get<double>(), 8000, 150);
  EXPECT_NE(r.output.find("R_beta       resistance  "), std::string::npos) << r.output;  // the layout
  fs::remove_all(dir);
}

TEST(Features, CliPrintsUndefinedFeaturesWithTheReasonAndExitsZero) {
  // A valid weld signal of unusual shape, generated here: 8 kA for 120 ms, resistance
  // falling over the whole weld (no peak), electrode displacement falling (no
  // expansion), temperature still rising at the record end.
  const fs::path dir = fresh_dir("undefined");
  std::string text = "time [ms], current [kA], voltage [V], displacement [mm], temperature [degC]\n";
  for (int k = 0; k <= 700; ++k) {
    const double t = -10.0 + 0.2 * k, tw = std::max(t, 0.0);
    const double current = k < 50 || k > 650 ? 0.0 : 8.0;  // 8 kA from 0 to 120 ms, decided on k: exact
    char row[160];
    std::snprintf(row, sizeof row, "%.1f, %.3f, %.8f, %.8f, %.4f\n", t, current,
                  current * (200.0 - 0.5 * tw) * 1e-3, 0.01 - 1e-4 * tw, 20.0 + 10.0 * tw);
    text += row;
  }
  const fs::path signal = write_file(dir / "unusual.csv", text);
  const fs::path json_path = dir / "unusual.json";
  const CommandResult r = run_rsw("features " + signal.string() + " -o " + json_path.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("R_beta       resistance    undefined (the dynamic resistance has no peak inside the "
                          "trimmed weld stage"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("S_dot_exp    displacement  undefined (the electrode displacement does not rise after the "
                          "weld start"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("T_dot_cool   temperature   undefined (the sheet temperature peaks at the end of the "
                          "record"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  R_gamma      resistance    "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("R_gamma      resistance    undefined"), std::string::npos) << r.output;

  const auto json = nlohmann::json::parse(read_file(json_path));
  EXPECT_TRUE(json["features"]["R_beta"]["value"].is_null());
  EXPECT_EQ(json["features"]["R_beta"]["unit"], "ohm");
  EXPECT_NE(json["features"]["R_beta"]["reason"].get<std::string>().find("no peak"), std::string::npos);
  EXPECT_TRUE(json["features"]["S_dot_exp"]["value"].is_null());
  EXPECT_TRUE(json["features"]["T_dot_cool"]["value"].is_null());
  EXPECT_NEAR(json["features"]["R_gamma"]["value"].get<double>(), 140.91e-6, 0.05e-6);  // 200 − 0.5 · 118.18 µΩ
  EXPECT_EQ(json["features"]["dS_P"]["value"].get<double>(), 0.0);
  EXPECT_FALSE(json["features"]["R_gamma"].contains("reason"));
  fs::remove_all(dir);
}

TEST(Features, CliWarnsOfAnImplausibleUnitAndStillPrintsTheFeatures) {
  // The shipped signal with its current header rewritten to [A] over the kA numbers.
  const fs::path dir = fresh_dir("ampere");
  std::string text = read_file(shipped_signal);
  const auto header = text.find("current [kA]");
  ASSERT_NE(header, std::string::npos);
  text.replace(header, 12, "current [A]");
  const fs::path signal = write_file(dir / "ampere.csv", text);
  const CommandResult r = run_rsw("features " + signal.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("rsw: warning: " + signal.string() + ": column 'current [A]' has a peak |I| of "),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" A, outside 100 A .. 100 kA of a spot weld: kA?"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  R_beta       resistance "), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(Features, SignalWithoutCurrentPulseIsAClearError) {
  const fs::path dir = fresh_dir("no_pulse");
  std::string text = "time [ms], current [kA], voltage [V]\n";
  for (int k = 0; k < 50; ++k) text += std::to_string(k) + ", 0, 0\n";
  const fs::path no_current = write_file(dir / "no_current.csv", text);
  CommandResult r = run_rsw("features " + no_current.string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find(no_current.string() + ": no current pulse: the current is zero over the whole record"),
            std::string::npos) << r.output;

  text = "time [ms], current [kA], voltage [V]\n";
  for (int k = 0; k < 50; ++k) text += std::to_string(k) + ", 8, 1.4\n";
  const fs::path flat = write_file(dir / "flat.csv", text);
  r = run_rsw("features " + flat.string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find(flat.string() + ": no current pulse"), std::string::npos) << r.output;

  const fs::path short_file = write_file(dir / "short.csv", "time [ms], current [kA], voltage [V]\n0, 8, 1.4\n");
  r = run_rsw("features " + short_file.string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("short.csv: a signal needs at least two data rows, found 1"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(StudyCli, UnknownStudyCommandNamesTheStudyCommandsAndExitsTwo) {
  const CommandResult r = run_rsw("study rnu x.yaml");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("rsw: error: unknown command 'study rnu'; commands of 'study': run, "), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("(did you mean 'run'?)"), std::string::npos) << r.output;
}

TEST(Features, UnreadableOrWeldlessSignalFileIsBadInputExitTwo) {
  const fs::path dir = fresh_dir("bad_input");
  CommandResult r = run_rsw("features " + (dir / "missing.csv").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("cannot open signal file"), std::string::npos) << r.output;
  std::string text = "time [ms], current [kA], voltage [V]\n";
  for (int k = 0; k < 50; ++k) text += std::to_string(k) + ", 0, 0\n";
  r = run_rsw("features " + write_file(dir / "no_current.csv", text).string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("no current pulse"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(StudyCli, RunResumeAndSensitivityWriteTables) {
  const fs::path dir = fresh_dir("run");
  const fs::path study = write_lhs_study(dir, "small", 40);
  const fs::path out = dir / "out";
  CommandResult r = run_rsw("study run " + study.string() + " --workers 2 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("study small: 40/40 runs done (40 now, 0 before), 2 failed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("failed run "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("runs 40/40, 2 failed, elapsed "), std::string::npos) << r.output;
  const std::string runs = read_file(out / "small_runs.csv");
  EXPECT_EQ(runs.rfind("index,status,wall_time_s,rank,a [1],p1 [1],c [1],R_beta [ohm],dS_P [m],T_max [degC],d_n_liq [m],"
                       "failure_reason,undefined_features,warnings\n", 0), 0u) << runs;
  EXPECT_TRUE(fs::exists(out / "small_runs.json"));

  // Without --resume an existing study is not overwritten; with it nothing is repeated.
  r = run_rsw("study run " + study.string() + " -q -o " + out.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("exists already; continue it with --resume"), std::string::npos) << r.output;
  r = run_rsw("study run " + study.string() + " -q --resume -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("40/40 runs done (0 now, 40 before)"), std::string::npos) << r.output;

  r = run_rsw("study sensitivity " + study.string() + " -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("study small: 40 runs, 38 used, 2 failed (excluded)"), std::string::npos) << r.output;
  const std::string sobol = read_file(out / "small_sobol.csv");
  EXPECT_EQ(sobol.rfind("feature,group,unit,parameter,first_order,total_order,loo_error,corrected_loo_error,n_runs,"
                        "degree,n_terms\nR_beta,resistance,ohm,a,", 0), 0u) << sobol;
  EXPECT_TRUE(fs::exists(out / "small_sobol_second_order.csv"));
  const auto json = nlohmann::json::parse(read_file(out / "small_sensitivity.json"));
  EXPECT_EQ(json["runs"]["failed"], 2);
  EXPECT_EQ(json["features"].size(), 4u);
  EXPECT_EQ(json["features"][0]["first_order"].size(), 3u);
  fs::remove_all(dir);
}

// A study whose every run failed is not a success: the run table is written, with the
// reasons, and the command exits 1 saying so.
TEST(StudyCli, EveryRunFailedExitsOneAfterWritingTheTable) {
  const fs::path dir = fresh_dir("all_failed");
  const fs::path study = write_lhs_study(dir, "all_failed", 4);
  write_file(dir / "case.yaml", "analytic: {function: smooth, fail_above: -1}\n");
  const CommandResult r = run_rsw("study run " + study.string() + " -q --workers 1 -o " + (dir / "out").string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("every one of its 4 runs failed"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir / "out" / "all_failed_runs.csv")) << r.output;
  fs::remove_all(dir);
}

TEST(StudyCli, RunWithUndefinedFeaturesIsOkAndTablesShowNanAndWhy) {
  // The analytic model leaves its first feature (R_beta) undefined (NaN) for a > 0.5.
  const fs::path dir = fresh_dir("undefined_runs");
  const fs::path study = write_lhs_study(dir, "shape", 20);
  write_file(dir / "case.yaml", "analytic: {function: smooth, undefined_above: 0.5}\n");
  const fs::path out = dir / "out";
  CommandResult r = run_rsw("study run " + study.string() + " -q --workers 2 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("study shape: 20/20 runs done (20 now, 0 before), 0 failed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("R_beta undefined in 10 ok runs (the dynamic resistance has no peak inside the trimmed "
                          "weld stage)"), std::string::npos) << r.output;

  const rsw::calibration::StudyResults results = rsw::calibration::read_study_results(out / "shape.h5");
  EXPECT_EQ(results.count(rsw::calibration::StudyResults::Status::ok), 20u);
  const auto json = nlohmann::json::parse(read_file(out / "shape_runs.json"));
  const std::string csv = read_file(out / "shape_runs.csv");
  EXPECT_NE(csv.find(",failure_reason,undefined_features,warnings\n"), std::string::npos) << csv;
  std::size_t n_undefined = 0;
  for (std::size_t i = 0; i < results.n_points(); ++i) {
    const auto& run = json["runs"][i];
    EXPECT_EQ(run["status"], "ok");
    const bool undefined = results.points(static_cast<Eigen::Index>(i), 0) > 0.5;
    EXPECT_EQ(std::isnan(results.features(static_cast<Eigen::Index>(i), 0)), undefined) << "run " << i;
    EXPECT_EQ(run["features"]["R_beta"].is_null(), undefined) << "run " << i;
    EXPECT_EQ(run.contains("undefined_features"), undefined) << "run " << i;
    if (!undefined) continue;
    ++n_undefined;
    EXPECT_EQ(run["undefined_features"]["R_beta"], "the dynamic resistance has no peak inside the trimmed weld stage");
    EXPECT_TRUE(run["features"]["dS_P"].is_number());
    // The CSV row: status ok, nan for R_beta, the name in the undefined_features
    // column, no warnings in the last.
    std::istringstream lines(csv);
    std::string line;
    for (std::size_t k = 0; k <= i + 1; ++k) std::getline(lines, line);
    EXPECT_EQ(line.rfind(std::to_string(i) + ",ok,", 0), 0u) << line;
    EXPECT_NE(line.find(",nan,"), std::string::npos) << line;
    EXPECT_EQ(line.substr(line.size() - 8), ",R_beta,") << line;
  }
  EXPECT_EQ(n_undefined, 10u);

  // The sensitivity analysis fits R_beta on the runs where it is defined.
  r = run_rsw("study sensitivity " + study.string() + " -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const auto sensitivity = nlohmann::json::parse(read_file(out / "shape_sensitivity.json"));
  EXPECT_EQ(sensitivity["features"][0]["n_runs"], 10);
  EXPECT_EQ(sensitivity["features"][1]["n_runs"], 20);
  fs::remove_all(dir);
}

TEST(StudyCli, ArrayTasksMergeIntoTheStudy) {
  const fs::path dir = fresh_dir("tasks");
  const fs::path study = write_lhs_study(dir, "tasks", 20);
  const fs::path out = dir / "out";
  std::string parts;
  for (int i = 0; i < 2; ++i) {
    const CommandResult r = run_rsw("study run " + study.string() + " -q --workers 1 --task " + std::to_string(i) +
                                    "/2 -o " + out.string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("study tasks task " + std::to_string(i) + "/2: 10/10 runs done"), std::string::npos) << r.output;
    const fs::path part = out / ("tasks.task-" + std::to_string(i) + "-of-2.h5");
    EXPECT_TRUE(fs::exists(part)) << r.output;
    parts += " " + part.string();
  }
  EXPECT_FALSE(fs::exists(out / "tasks.h5"));
  const CommandResult r = run_rsw("study merge " + study.string() + parts + " -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("20 runs added, 0 already present; 19 ok, 1 failed, 0 not run"), std::string::npos) << r.output;
  const rsw::calibration::StudyResults merged = rsw::calibration::read_study_results(out / "tasks.h5");
  EXPECT_EQ(merged.count(rsw::calibration::StudyResults::Status::pending), 0u);
  EXPECT_TRUE(fs::exists(out / "tasks_runs.csv"));
  fs::remove_all(dir);
}

TEST(StudyCli, BadStudyFileExitsWithFileLineKeyAndAllowed) {
  const fs::path dir = fresh_dir("bad");
  const fs::path study = write_file(dir / "bad.yaml", R"(parameters:
  - {name: a, config_key: test.a, prior: uniform, lower: 0, upper: 1}
design: {kind: lhs, n_points: 1}
features: [{name: R_beta}]
)");
  const CommandResult r = run_rsw("study run " + study.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("bad.yaml:3:31: design.n_points: '1' is out of range; allowed: [2, 1e6]"),
            std::string::npos) << r.output;
  const fs::path good = write_lhs_study(dir, "good", 4);
  const CommandResult task = run_rsw("study run " + good.string() + " --task 2/2");
  EXPECT_NE(task.status, 0);
  EXPECT_NE(task.output.find("--task '2/2': i must be less than n"), std::string::npos) << task.output;
  fs::remove_all(dir);
}

TEST(PlotStudy, DrawsOneAtATimeCurvesAndSobolHeatmaps) {
  const CommandResult has_libraries = run_command("/usr/bin/python3 -c 'import matplotlib, h5py, numpy'");
  if (has_libraries.status != 0) {
    GTEST_SKIP() << "/usr/bin/python3 lacks matplotlib, h5py or numpy (run tools/setup.sh): " << has_libraries.output;
  }
  const fs::path dir = fresh_dir("plot");
  write_file(dir / "case.yaml", "analytic: {function: smooth, fail_above: 0.95}\n");
  const fs::path oat = write_file(dir / "sweep.yaml", R"(study: {name: sweep}
parameters:
  - {name: a, config_key: test.a, prior: uniform, lower: 0, upper: 1}
  - {name: p1, config_key: test.p1, prior: log10_uniform, lower: 1e-3, upper: 1e-1}
design: {kind: oat, n_levels: 5, oat_levels: endpoints}
features: [{name: R_beta}, {name: R_m}, {name: dS_P}, {name: T_max}, {name: d_n_liq}]
model: {case: case.yaml}
)");
  const fs::path lhs = write_lhs_study(dir, "lhs", 40);
  const fs::path out = dir / "out";
  ASSERT_EQ(run_rsw("study run " + oat.string() + " -q -o " + out.string()).status, 0);
  ASSERT_EQ(run_rsw("study run " + lhs.string() + " -q -o " + out.string()).status, 0);
  ASSERT_EQ(run_rsw("study sensitivity " + lhs.string() + " -o " + out.string()).status, 0);

  const std::string script = "/usr/bin/python3 " + std::string(RSW_SOURCE_DIR) + "/tools/plot_study.py ";
  CommandResult r = run_command(script + "oat " + (out / "sweep.h5").string() + " -o " + (dir / "plots").string());
  ASSERT_EQ(r.status, 0) << r.output;
  r = run_command(script + "oat " + (out / "sweep.h5").string() + " --absolute --features R_beta,T_max -o " +
                  (dir / "absolute").string());
  ASSERT_EQ(r.status, 0) << r.output;
  r = run_command(script + "sobol " + (out / "lhs_sensitivity.json").string() + " -o " + (dir / "plots").string());
  ASSERT_EQ(r.status, 0) << r.output;
  for (const fs::path& png : {dir / "plots" / "sweep_oat_a.png", dir / "plots" / "sweep_oat_p1.png",
                             dir / "absolute" / "sweep_oat_a.png", dir / "plots" / "lhs_sobol_first_order.png",
                             dir / "plots" / "lhs_sobol_total_order.png"}) {
    ASSERT_TRUE(fs::exists(png)) << png;
    EXPECT_GT(fs::file_size(png), 10000u) << png;
    EXPECT_EQ(read_file(png).substr(1, 3), "PNG") << png;
  }
  // A study that is not one-at-a-time is refused with the reason.
  r = run_command(script + "oat " + (out / "lhs.h5").string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("is not a one-at-a-time study"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

// rsw study sensitivity draws the Sobol heatmaps itself (tools/plot_study.py) unless
// --no-plots.
TEST(StudyCli, SensitivityDrawsHeatmapsUnlessToldNotTo) {
  const CommandResult has_libraries = run_command("/usr/bin/python3 -c 'import matplotlib, h5py, numpy'");
  if (has_libraries.status != 0) {
    GTEST_SKIP() << "/usr/bin/python3 lacks matplotlib, h5py or numpy (run tools/setup.sh): " << has_libraries.output;
  }
  const fs::path dir = fresh_dir("heatmaps");
  const fs::path study = write_lhs_study(dir, "maps", 30);
  const fs::path out = dir / "out";
  ASSERT_EQ(run_rsw("study run " + study.string() + " -q -o " + out.string()).status, 0);
  CommandResult r = run_rsw("study sensitivity " + study.string() + " --no-plots -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_FALSE(fs::exists(out / "maps_sobol_first_order.png"));
  r = run_rsw("study sensitivity " + study.string() + " -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "maps_sobol_first_order.png")) << r.output;
  EXPECT_TRUE(fs::exists(out / "maps_sobol_total_order.png")) << r.output;
  fs::remove_all(dir);
}

// The output folder (fem/output_folder.hpp): a non-empty folder rsw did not make is
// refused unless --overwrite, which keeps what was there; the folder is then rsw's, so
// --resume and sensitivity need no --overwrite.
TEST(StudyCli, RunRefusesAFolderItDidNotMakeAndThenResumesInTheFolderItMade) {
  const fs::path dir = fresh_dir("folder");
  const fs::path study = write_lhs_study(dir, "small", 40);
  const fs::path out = dir / "out";
  fs::create_directories(out);
  write_file(out / "notes.txt", "mine\n");
  CommandResult r = run_rsw("study run " + study.string() + " -q -o " + out.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("output folder '" + out.string() + "' holds entries rsw did not write (e.g. 'notes.txt')"),
            std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "small.h5"));
  r = run_rsw("study run " + study.string() + " -q --overwrite -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  r = run_rsw("study run " + study.string() + " -q --resume -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("40/40 runs done (0 now, 40 before)"), std::string::npos) << r.output;
  r = run_rsw("study sensitivity " + study.string() + " --no-plots -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(read_file(out / "notes.txt"), "mine\n");
  fs::remove_all(dir);
}

// A folder a version before the marker wrote (the study's results file, no marker) is
// the study's own: resumed and analysed without --overwrite.
TEST(StudyCli, FolderOfAStudyFromBeforeTheMarkerIsAdopted) {
  const fs::path dir = fresh_dir("adopt");
  const fs::path study = write_lhs_study(dir, "small", 40);
  const fs::path out = dir / "out";
  ASSERT_EQ(run_rsw("study run " + study.string() + " -q -o " + out.string()).status, 0);
  fs::remove(out / ".rsw-output");
  write_file(out / "notes.txt", "mine\n");
  CommandResult r = run_rsw("study run " + study.string() + " -q --resume -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  r = run_rsw("study sensitivity " + study.string() + " --no-plots -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "small_sobol.csv"));
  EXPECT_EQ(read_file(out / "notes.txt"), "mine\n");
  fs::remove_all(dir);
}
