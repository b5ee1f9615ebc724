// The rsw program as a user runs it: `rsw mesh` writes files that VTK reads back and
// reports the weld-zone element size; bad input exits non-zero with a message naming
// the key and what is allowed, and writes nothing.
#include "fem/hdf5_file.hpp"
#include "fem/vtk_output.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <memory>
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

TEST(RswMesh, WritesMeshThatVtkReadsBackAndReportsWeldZoneSize) {
  const fs::path dir = fresh_dir("mesh");
  const CommandResult r = run_rsw("mesh " + paper_case + " -o " + dir.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("nominal edge 0.0625 mm"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("sheet_1              1152 cells, edges 0.0625..0.0625 mm"), std::string::npos) << r.output;

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
  ASSERT_EQ(time.size(), 11u);  // signals every 1 ms (output.interval), 0 to 10 ms
  EXPECT_DOUBLE_EQ(time.back(), 0.01);
  EXPECT_NEAR(force.back(), 3000.0, 1e-6);
  EXPECT_NE(h5.read_string("/run/config").find("squeeze_only"), std::string::npos);
  const auto steps = rsw::fem::read_pvd(dir / "fields.pvd");
  ASSERT_EQ(steps.size(), 3u);  // fields every 5 ms (output.field_interval): 0, 5 and 10 ms
  const auto last = rsw::fem::read_vtm(steps.back().file);
  EXPECT_GT(last.block("sheet_1").point_array("displacement").n_tuples(), 0);
  EXPECT_GT(last.block("sheet_1").cell_array("von_mises_stress").n_tuples(), 0);
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  EXPECT_TRUE(fs::exists(dir / "signals.csv"));
  EXPECT_FALSE(fs::exists(dir.string() + ".partial"));
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

TEST(RswSimulate, FailedRunLeavesOnlyPartialFolderWithReason) {
  const fs::path dir = fresh_dir("fail");
  // Seating steps of 1 nm cannot reach 5 % of the force within the step cap.
  const CommandResult r = run_rsw("simulate " + squeeze_case + " -q -o " + dir.string() + coarse +
                                  " --set solver.seat_step=0.001um");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("seating"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir));
  EXPECT_TRUE(fs::exists(dir.string() + ".partial/failure.txt"));
  fs::remove_all(dir.string() + ".partial");
}
