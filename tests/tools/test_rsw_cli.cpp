// The rsw program as a user runs it: `rsw mesh` writes files that VTK reads back and
// reports the weld-zone element size; bad input exits non-zero with a message naming
// the key and what is allowed, and writes nothing.
#include "fem/hdf5_file.hpp"
#include "fem/output_folder.hpp"
#include "fem/vtk_output.hpp"
#include "tests/tools/cli_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {
struct CommandResult {
  int status = -1;
  std::string output;  // stdout and stderr
};

CommandResult run_rsw(const std::string& args) {
  CommandResult r;
  const std::string cmd = std::string(RSW_BINARY) + " " + args + " 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  std::array<char, 4096> buf;
  while (fgets(buf.data(), buf.size(), pipe.get())) r.output += buf.data();
  r.status = WEXITSTATUS(pclose(pipe.release()));
  return r;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("rsw_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

const std::string paper_case = std::string(RSW_SOURCE_DIR) + "/validation/paper_case/weld.yaml";
}  // namespace

// Exit codes (README.md): 0 done, 1 the run failed, 2 bad input, usage errors included.
TEST(RswCli, UnknownCommandIsNamedWithTheCommandsAndTheClosestAndExitsTwo) {
  const CommandResult r = run_rsw("simulat " + paper_case);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("rsw: error: unknown command 'simulat'; commands: mesh, simulate, study, calibrate, "
                          "features, config (did you mean 'simulate'?)"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("A subcommand is required"), std::string::npos) << r.output;
}

TEST(RswCli, UsageErrorsExitTwoAndHelpAndVersionExitZero) {
  for (const char* args : {"simulate", "simulate --no-such-option x.yaml", "", "mesh a.yaml b.yaml"}) {
    const CommandResult r = run_rsw(args);
    EXPECT_EQ(r.status, 2) << "rsw " << args << "\n" << r.output;
  }
  EXPECT_EQ(run_rsw("--help").status, 0);
  EXPECT_EQ(run_rsw("simulate --help").status, 0);
  EXPECT_EQ(run_rsw("--version").status, 0);
}

TEST(RswMesh, WritesMeshThatVtkReadsBackAndReportsWeldZoneSize) {
  const fs::path dir = fresh_dir("mesh");
  const CommandResult r = run_rsw("mesh " + paper_case + " -o " + dir.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("nominal edge 0.0625 mm"), std::string::npos) << r.output;
  // The weld zone of a sheet: 1 mm / 0.0625 mm = 16 rows of 3.5 mm / 0.0625 mm = 56 cells.
  EXPECT_NE(r.output.find("sheet_1               896 cells, edges 0.0625..0.0625 mm"), std::string::npos) << r.output;

  const auto data = rsw::fem::read_vtm(dir / "mesh.vtm");
  int n_cells = 0;
  for (const char* body : {"upper_electrode", "sheet_1", "sheet_2", "lower_electrode"}) {
    const auto& block = data.block(body);
    n_cells += block.n_cells;
    const auto& level = block.cell_array("level");
    for (int i = 0; i < level.n_tuples(); ++i) EXPECT_LE(level.at(i), 2);
    EXPECT_GT(data.block(std::string(body) + "_boundaries").n_cells, 0);
  }
  EXPECT_NE(r.output.find("all                   " + std::to_string(n_cells)), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(RswMesh, SetOverrideChangesTheMesh) {
  const fs::path dir = fresh_dir("set");
  const CommandResult r = run_rsw("mesh " + paper_case + " -o " + dir.string() + " --set mesh.weld_zone.levels=1");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("nominal edge 0.1250 mm"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(RswMesh, OutOfRangeOverrideExitsWithKeyAndRangeAndWritesNothing) {
  const fs::path dir = fresh_dir("bad");
  const CommandResult r = run_rsw("mesh " + paper_case + " -o " + dir.string() + " --set mesh.weld_zone.levels=9");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("mesh.weld_zone.levels"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("allowed"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir));
}

TEST(RswMesh, MissingCaseFileIsAnError) {
  const CommandResult r = run_rsw("mesh /nonexistent/weld.yaml");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("/nonexistent/weld.yaml"), std::string::npos) << r.output;
}

TEST(RswConfig, SchemaCommandDocumentsListItemKeys) {
  const CommandResult r = run_rsw("config schema --format markdown");
  ASSERT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("stack.sheets[].thickness"), std::string::npos);
}

namespace {
const std::string squeeze_case = std::string(RSW_SOURCE_DIR) + "/validation/squeeze_only/weld.yaml";
const std::string coarse = " --set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1";
}  // namespace

TEST(RswSimulate, SqueezeRunWritesReadableResultsAndFields) {
  const fs::path dir = fresh_dir("squeeze");
  const CommandResult r = run_rsw("simulate " + squeeze_case + " -q -o " + dir.string() + coarse);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("es_upper  contact radius"), std::string::npos) << r.output;
  rsw::fem::Hdf5File h5(dir / "results.h5", rsw::fem::Hdf5Mode::read);
  const auto time = h5.read_doubles("/signals/time");
  const auto force = h5.read_doubles("/signals/force");
  ASSERT_EQ(time.size(), 41u);  // signals at every step (output.interval 0): 0.25 ms steps, 0 to 10 ms
  EXPECT_DOUBLE_EQ(time.back(), 0.01);
  EXPECT_NEAR(force.back(), 3000.0, 1e-6);
  EXPECT_NE(h5.read_string("/run/config").find("squeeze_only"), std::string::npos);
  // Provenance: the source tree's commit (40 hex digits, "-modified" if tracked files
  // differed from it at build time) or "unknown" outside a git work tree.
  const std::string commit = h5.string_attribute("/run", "git_commit");
  EXPECT_TRUE(commit == "unknown" || std::regex_match(commit, std::regex("[0-9a-f]{40}(-modified)?"))) << commit;
  std::ifstream summary_file(dir / "summary.json");
  std::stringstream summary;
  summary << summary_file.rdbuf();
  EXPECT_NE(summary.str().find("\"git_commit\": \"" + commit + "\""), std::string::npos);
  EXPECT_NE(run_rsw("--version").output.find("(commit " + commit + ")"), std::string::npos);
  const auto steps = rsw::fem::read_pvd(dir / "fields.pvd");
  ASSERT_EQ(steps.size(), 3u);  // fields every 5 ms (output.field_interval): 0, 5 and 10 ms
  const auto last = rsw::fem::read_vtm(steps.back().file);
  EXPECT_GT(last.block("sheet_1").point_array("displacement").n_tuples(), 0);
  EXPECT_GT(last.block("sheet_1").cell_array("von_mises_stress").n_tuples(), 0);
  // Contact quantities on both sides of each interface: under 3 kN every contact face,
  // the electrodes' and both sheets' (top and bottom), carries pressure.
  for (const char* block : {"upper_electrode_boundaries", "sheet_1_boundaries", "sheet_2_boundaries",
                            "lower_electrode_boundaries"}) {
    const auto& boundary = last.block(block);
    const auto& names = boundary.strings("boundary_names");
    const auto& pressure = boundary.cell_array("contact_pressure");
    std::set<std::string> pressed;
    for (int k = 0; k < boundary.n_cells; ++k)
      if (pressure.at(k) > 1e6) pressed.insert(names[static_cast<std::size_t>(boundary.cell_array("boundary_id").at(k))]);
    EXPECT_EQ(pressed.size(), std::string(block).rfind("sheet", 0) == 0 ? 2u : 1u) << block;
  }
  const auto& units = last.block("sheet_1").strings("units");
  for (const char* entry : {"displacement [m]", "temperature [degC]", "von_mises_stress [Pa]", "joule_heat [W/m^3]"})
    EXPECT_NE(std::find(units.begin(), units.end(), entry), units.end()) << entry;
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  EXPECT_TRUE(fs::exists(dir / "signals.csv"));
  EXPECT_FALSE(fs::exists(dir / "partial"));
  EXPECT_FALSE(fs::exists(dir / "failure.txt"));
  fs::remove_all(dir);
}

// Signals every 2 ms, fields at least 5 ms apart: signal rows at 0, 2, ..., 10 ms;
// fields at 0 ms (the first output), 6 ms (the first output at least 5 ms after it)
// and 10 ms (the last step, only 4 ms after 6 ms).
TEST(RswSimulate, FieldsAreWrittenAtLeastTheFieldIntervalApartAndAtTheEnd) {
  const fs::path dir = fresh_dir("field_interval");
  const CommandResult r = run_rsw("simulate " + squeeze_case + " -q -o " + dir.string() + coarse +
                                  " --set output.interval=2ms --set output.field_interval=5ms");
  ASSERT_EQ(r.status, 0) << r.output;
  rsw::fem::Hdf5File h5(dir / "results.h5", rsw::fem::Hdf5Mode::read);
  EXPECT_EQ(h5.read_doubles("/signals/time").size(), 6u);
  const auto steps = rsw::fem::read_pvd(dir / "fields.pvd");
  ASSERT_EQ(steps.size(), 3u);
  EXPECT_NEAR(steps[0].time, 0.0, 1e-12);
  EXPECT_NEAR(steps[1].time, 0.006, 1e-12);
  EXPECT_NEAR(steps[2].time, 0.010, 1e-12);
  fs::remove_all(dir);
}

TEST(RswSimulate, FailedRunLeavesItsReasonAndNoResult) {
  const fs::path dir = fresh_dir("fail");
  // Seating steps of 1 nm cannot reach 5 % of the force within the step cap.
  const CommandResult r = run_rsw("simulate " + squeeze_case + " -q -o " + dir.string() + coarse +
                                  " --set solver.seat_step=0.001um");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("seating"), std::string::npos) << r.output;
  EXPECT_NE(rsw::testing::read_file(dir / "failure.txt").find("seating"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
  EXPECT_FALSE(fs::exists(dir / "results.h5"));
  EXPECT_FALSE(fs::exists(dir.string() + ".partial"));
  fs::remove_all(dir);
}

// Output folders (fem/output_folder.hpp) through rsw simulate: the squeeze-only case on
// the coarse mesh, about a second per run.
namespace {
// A folder <tmp>/rsw_cli_<name>_<pid> that exists and is empty.
fs::path empty_dir(const std::string& name) { return rsw::testing::fresh_dir("rsw_cli", name); }

CommandResult simulate_into(const fs::path& out, const std::string& extra = "") {
  return run_rsw("simulate " + squeeze_case + " -q -o " + out.string() + coarse + extra);
}
}  // namespace

TEST(RswSimulateOutput, RefusesTheWorkingDirectoryHoldingTheCaseFileUnlessOverwriteAndThenKeepsIt) {
  const fs::path dir = empty_dir("dot");
  const std::string case_text = rsw::testing::read_file(squeeze_case);
  rsw::testing::write_file(dir / "weld.yaml", case_text);
  const std::string in_dir = "cd " + dir.string() + " && " + std::string(RSW_BINARY) + " simulate weld.yaml -q -o ." + coarse;
  rsw::testing::CommandResult r = rsw::testing::run_command(in_dir);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("output folder '.' (" + dir.string() + ")"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("'weld.yaml'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--overwrite"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "results.h5"));
  EXPECT_FALSE(fs::exists(dir / ".rsw-output"));

  r = rsw::testing::run_command(in_dir + " --overwrite");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  EXPECT_EQ(rsw::testing::read_file(dir / "weld.yaml"), case_text);
  // The folder is now one rsw made its results in: a rerun needs no --overwrite, and
  // replaces only its own files.
  r = rsw::testing::run_command(in_dir);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(rsw::testing::read_file(dir / "weld.yaml"), case_text);
  fs::remove_all(dir);
}

TEST(RswSimulateOutput, RefusesAFileAsOutputFolderAndLeavesItAsItWas) {
  const fs::path dir = empty_dir("file");
  const fs::path file = rsw::testing::write_file(dir / "notes.txt", "mine\n");
  for (const std::string extra : {"", " --overwrite"}) {
    const CommandResult r = simulate_into(file, extra);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("'" + file.string() + "' is a file, not a folder"), std::string::npos) << r.output;
    EXPECT_TRUE(fs::is_regular_file(file));
    EXPECT_EQ(rsw::testing::read_file(file), "mine\n");
  }
  fs::remove_all(dir);
}

TEST(RswSimulateOutput, SecondRunIntoTheSameFolderReplacesItsOwnResultAndKeepsOtherFiles) {
  const fs::path dir = fresh_dir("again");
  ASSERT_EQ(simulate_into(dir).status, 0);
  ASSERT_EQ(rsw::fem::read_pvd(dir / "fields.pvd").size(), 3u);
  rsw::testing::write_file(dir / "notes.txt", "mine\n");
  // Fields every 5 ms from 2 ms signals: 0, 6 and 10 ms; signals 0, 2, ..., 10 ms.
  const CommandResult r = simulate_into(dir, " --set output.interval=2ms");
  ASSERT_EQ(r.status, 0) << r.output;
  rsw::fem::Hdf5File h5(dir / "results.h5", rsw::fem::Hdf5Mode::read);
  EXPECT_EQ(h5.read_doubles("/signals/time").size(), 6u);
  const auto steps = rsw::fem::read_pvd(dir / "fields.pvd");
  ASSERT_EQ(steps.size(), 3u);
  EXPECT_NEAR(steps[1].time, 0.006, 1e-12);
  EXPECT_EQ(rsw::testing::read_file(dir / "notes.txt"), "mine\n");
  EXPECT_FALSE(fs::exists(dir / "partial"));
  fs::remove_all(dir);
}

TEST(RswSimulateOutput, FailedRerunLeavesNoEarlierSuccessLookingCurrent) {
  const fs::path dir = fresh_dir("rerun");
  ASSERT_EQ(simulate_into(dir).status, 0);
  ASSERT_TRUE(fs::exists(dir / "summary.json"));
  // Seating steps of 1 nm cannot reach 5 % of the force within the step cap.
  CommandResult r = simulate_into(dir, " --set solver.seat_step=0.001um");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(rsw::testing::read_file(dir / "failure.txt").find("seating"), std::string::npos);
  for (const char* name : {"summary.json", "results.h5", "signals.csv", "fields.pvd", "fields_0000.vtm"})
    EXPECT_FALSE(fs::exists(dir / name)) << name;
  r = simulate_into(dir);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  EXPECT_FALSE(fs::exists(dir / "failure.txt"));
  fs::remove_all(dir);
}

TEST(RswSimulateOutput, RunIntoAFolderInUseIsRefusedAtTheStartAndChangesNothing) {
  const fs::path dir = fresh_dir("busy");
  ASSERT_EQ(simulate_into(dir).status, 0);
  const std::string summary = rsw::testing::read_file(dir / "summary.json");
  {
    // Another run holds the folder (the claim rsw simulate makes).
    rsw::fem::OutputFolderOptions other;
    other.kind = "simulate";
    const rsw::fem::OutputFolder held(dir, other);
    const CommandResult r = simulate_into(dir);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("is in use by another rsw run"), std::string::npos) << r.output;
    EXPECT_EQ(rsw::testing::read_file(dir / "summary.json"), summary);
  }
  EXPECT_EQ(simulate_into(dir).status, 0);  // free again
  fs::remove_all(dir);
}

TEST(RswSimulateOutput, OverwriteNeverReplacesAResultFileRswDidNotWrite) {
  const fs::path dir = empty_dir("foreign_summary");
  rsw::testing::write_file(dir / "summary.json", "the user's\n");
  const CommandResult r = simulate_into(dir, " --overwrite");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find((dir / "summary.json").string() + "' was not written by rsw"), std::string::npos)
      << r.output;
  EXPECT_EQ(rsw::testing::read_file(dir / "summary.json"), "the user's\n");
  EXPECT_FALSE(fs::exists(dir / "results.h5"));
  fs::remove_all(dir);
}

// Two rsw processes into one folder: the second is refused at its start while the first
// runs (the paper's case on the coarse mesh, a few seconds), and the first's result is
// whole.
TEST(RswSimulateOutput, SecondProcessIntoAFolderARunIsWritingIsRefusedAtItsStart) {
  const fs::path dir = fresh_dir("two");
  const fs::path log = fs::path(dir.string() + ".log"), rc = fs::path(dir.string() + ".rc");
  fs::remove(rc);
  const std::string paper = std::string(RSW_SOURCE_DIR) + "/validation/paper_case/weld.yaml";
  const std::string first = std::string(RSW_BINARY) + " simulate " + paper + " -q -o " + dir.string() + coarse +
                            " --set output.fields=false";
  rsw::testing::run_command("(" + first + " > " + log.string() + " 2>&1; echo $? > " + rc.string() +
                            ") < /dev/null > /dev/null 2>&1 &");  // popen returns at once
  // The first run has claimed the folder once partial/ exists (it is made after the claim).
  for (int i = 0; i < 600 && !fs::exists(dir / "partial") && !fs::exists(rc); ++i) ::usleep(50000);
  ASSERT_TRUE(fs::exists(dir / "partial")) << rsw::testing::read_file(log);
  const CommandResult second = simulate_into(dir);
  const bool first_still_running = !fs::exists(rc);
  EXPECT_EQ(second.status, 2) << second.output;
  EXPECT_NE(second.output.find("is in use by another rsw run"), std::string::npos) << second.output;
  for (int i = 0; i < 1200 && !fs::exists(rc); ++i) ::usleep(50000);
  ASSERT_TRUE(fs::exists(rc));
  EXPECT_TRUE(first_still_running);  // else the refusal above proves nothing
  EXPECT_EQ(rsw::testing::read_file(rc), "0\n") << rsw::testing::read_file(log);
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  EXPECT_NE(rsw::testing::read_file(dir / "summary.json").find("\"case\": \"paper_case\""), std::string::npos);
  fs::remove_all(dir);
  fs::remove(log);
  fs::remove(rc);
}

// Studies and calibrations check the weld model before they spend runs: every
// parameter at both ends of its prior and every design point must give a valid case.
namespace {
fs::path write_weld_study(const fs::path& dir, const std::string& parameter, const std::string& set,
                          const std::string& calibration = "") {
  fs::create_directories(dir);
  const fs::path file = dir / "study.yaml";
  std::ofstream(file) << "study: {name: dry, output: out}\nparameters:\n  - " << parameter
                      << "\ndesign: {kind: lhs, n_points: 3, seed: 1}\nfeatures: [{name: R_beta}]\nmodel:\n  case: "
                      << RSW_SOURCE_DIR << "/validation/paper_case/weld.yaml\n  set: " << set << "\n"
                      << calibration;
  return file;
}
const std::string p1_parameter =
    "{name: p1, config_key: contact.electrode_sheet.htc_p1, unit: \"1\", prior: log10_uniform, lower: 1e-3, upper: 1e-1}";
}  // namespace

TEST(RswStudy, BadModelOverrideIsRefusedBeforeAnyRunWithExitTwo) {
  const fs::path dir = fresh_dir("dry_set");
  const fs::path study = write_weld_study(dir, p1_parameter, "[{key: mesh.weld_zone.levels, value: \"9\"}]");
  const CommandResult r = run_rsw("study run " + study.string() + " -q --workers 1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("mesh.weld_zone.levels"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("allowed: [0, 4]"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("nothing was run"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out")) << r.output;
  fs::remove_all(dir);
}

TEST(RswStudy, PriorReachingOutsideAKeysRangeIsRefusedNamingTheParameterAndEnd) {
  const fs::path dir = fresh_dir("dry_prior");
  const fs::path study = write_weld_study(
      dir, "{name: lambda_m, config_key: thermal.melt_conductivity, unit: W/(m*K), prior: uniform, lower: -5, upper: 100}",
      "[]");
  const CommandResult r = run_rsw("study run " + study.string() + " -q --workers 1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("lambda_m at its prior's lower end"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("thermal.melt_conductivity"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out")) << r.output;
  fs::remove_all(dir);
}

TEST(RswCalibrate, PriorReachingOutsideAKeysRangeIsRefusedBeforeAnyRun) {
  const fs::path dir = fresh_dir("dry_calibrate");
  fs::create_directories(dir);
  std::ofstream(dir / "features.csv") << "R_beta [uohm]\n300\n";
  const fs::path study = write_weld_study(
      dir, "{name: lambda_m, config_key: thermal.melt_conductivity, unit: W/(m*K), prior: uniform, lower: -5, upper: 100}",
      "[]",
      "calibration:\n  observations: {features_file: features.csv}\n  noise:\n    kind: standard_deviations\n"
      "    standard_deviations: [{feature: R_beta, value: 6 uohm}]\n  method: emulator\n");
  const CommandResult r = run_rsw("calibrate " + study.string() + " --workers 1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("lambda_m at its prior's lower end"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("nothing was run"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "dry_calibration")) << r.output;
  fs::remove_all(dir);
}
