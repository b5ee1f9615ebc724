// VTK output: a hand-built two-body mesh with a hanging node and named boundaries is
// written as .vtm/.vtu/.vtp (and as a .pvd time series), read back through VTK's own
// XML readers, and every count, coordinate and array value is compared with the input.
#include "fem/vtk_output.hpp"

#include "fem/threads.hpp"

#include <gtest/gtest.h>
#include <vtkSMPTools.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace {

namespace fs = std::filesystem;
using rsw::fem::FieldSet;
using rsw::fem::Mesh;
using rsw::fem::VtkTimeSeries;

// Body "sheet_1": two 1 mm quads side by side, z in [0, 1] mm.
// Body "electrode": one coarse 2 mm quad at r in [0, 2] mm and two fine 1 mm quads to
// its right, z in [1, 3] mm; node (2, 2) mm hangs on the coarse cell's right edge.
Mesh two_body_mesh() {
  const double mm = 1e-3;
  Mesh m;
  m.body_names = {"sheet_1", "electrode"};
  auto node = [&](double r, double z, int body) {
    m.nodes.emplace_back(r * mm, z * mm);
    m.node_body.push_back(body);
    return m.n_nodes() - 1;
  };
  auto cell = [&](std::array<int, 4> nodes, int body, int level) {
    m.cells.push_back(nodes);
    m.cell_body.push_back(body);
    m.cell_level.push_back(level);
    return m.n_cells() - 1;
  };
  // sheet_1
  const int s0 = node(0, 0, 0), s1 = node(1, 0, 0), s2 = node(2, 0, 0);
  const int s3 = node(0, 1, 0), s4 = node(1, 1, 0), s5 = node(2, 1, 0);
  const int c0 = cell({s0, s1, s4, s3}, 0, 0);
  const int c1 = cell({s1, s2, s5, s4}, 0, 0);
  // electrode
  const int e0 = node(0, 1, 1), e1 = node(2, 1, 1), e2 = node(3, 1, 1);
  const int e3 = node(2, 2, 1), e4 = node(3, 2, 1);
  const int e5 = node(0, 3, 1), e6 = node(2, 3, 1), e7 = node(3, 3, 1);
  const int c2 = cell({e0, e1, e6, e5}, 1, 0);
  const int c3 = cell({e1, e2, e4, e3}, 1, 1);
  cell({e3, e4, e7, e6}, 1, 1);
  m.hanging_nodes.push_back({e3, {e1, e6}});
  m.boundaries["sheet_1.top"] = {{c0, 2}, {c1, 2}};
  m.boundaries["sheet_1.axis"] = {{c0, 3}};
  m.boundaries["electrode.bottom"] = {{c2, 0}, {c3, 0}};
  m.interfaces["es_upper"] = {"electrode.bottom", "sheet_1.top", "electrode_sheet"};
  return m;
}

class VtkOutput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rsw_vtk_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

// T = 300 + 1e5 r + 2e5 z, u = (r, -z) / 100, current density (c, -c) per cell.
FieldSet sample_fields(const Mesh& mesh) {
  std::vector<double> temperature, displacement, joule, current;
  for (const auto& x : mesh.nodes) {
    temperature.push_back(300 + 1e5 * x.x() + 2e5 * x.y());
    displacement.push_back(x.x() / 100);
    displacement.push_back(-x.y() / 100);
  }
  for (int c = 0; c < mesh.n_cells(); ++c) {
    joule.push_back(1e9 * (c + 1));
    current.push_back(c);
    current.push_back(-c);
  }
  FieldSet f;
  f.add_point_scalar("T", temperature)
      .add_point_vector("u", displacement)
      .add_cell_scalar("joule_heat", joule)
      .add_cell_vector("current_density", current);
  return f;
}

TEST_F(VtkOutput, MultiBodyMeshRoundTripsThroughVtkReader) {
  const Mesh mesh = two_body_mesh();
  const FieldSet fields = sample_fields(mesh);
  const fs::path vtm = dir_ / "weld.vtm";
  rsw::fem::write_vtm(vtm, mesh, fields);

  const auto data = rsw::fem::read_vtm(vtm);
  ASSERT_EQ(data.blocks.size(), 4u);
  EXPECT_EQ(data.blocks[0].name, "sheet_1");
  EXPECT_EQ(data.blocks[1].name, "sheet_1_boundaries");
  EXPECT_EQ(data.blocks[2].name, "electrode");
  EXPECT_EQ(data.blocks[3].name, "electrode_boundaries");

  const int expected_points[2] = {6, 8};
  const int expected_cells[2] = {2, 3};
  for (int b = 0; b < 2; ++b) {
    const auto& block = data.block(mesh.body_names[b]);
    EXPECT_EQ(block.n_points, expected_points[b]) << block.name;
    EXPECT_EQ(block.n_cells, expected_cells[b]) << block.name;
    EXPECT_EQ(block.strings("body_names"), mesh.body_names);

    const auto& node_id = block.point_array("node_id");
    const auto& hanging = block.point_array("hanging");
    const auto& temperature = block.point_array("T");
    const auto& u = block.point_array("u");
    ASSERT_EQ(u.n_components, 3);
    for (int p = 0; p < block.n_points; ++p) {
      const int n = static_cast<int>(node_id.at(p));
      EXPECT_EQ(mesh.node_body[n], b);
      EXPECT_DOUBLE_EQ(block.points[p][0], mesh.nodes[n].x());
      EXPECT_DOUBLE_EQ(block.points[p][1], mesh.nodes[n].y());
      EXPECT_EQ(block.points[p][2], 0.0);
      EXPECT_DOUBLE_EQ(temperature.at(p), fields.point_fields[0].values[n]);
      EXPECT_DOUBLE_EQ(u.at(p, 0), mesh.nodes[n].x() / 100);
      EXPECT_DOUBLE_EQ(u.at(p, 1), -mesh.nodes[n].y() / 100);
      EXPECT_EQ(u.at(p, 2), 0.0);
      const bool is_hanging = n == mesh.hanging_nodes[0].node;
      EXPECT_EQ(hanging.at(p), is_hanging ? 1.0 : 0.0) << "node " << n;
    }

    const auto& cell_id = block.cell_array("cell_id");
    const auto& current = block.cell_array("current_density");
    ASSERT_EQ(current.n_components, 3);
    for (int k = 0; k < block.n_cells; ++k) {
      const int c = static_cast<int>(cell_id.at(k));
      EXPECT_EQ(block.cell_array("body").at(k), b);
      EXPECT_EQ(block.cell_array("level").at(k), mesh.cell_level[c]);
      EXPECT_DOUBLE_EQ(block.cell_array("scaled_jacobian").at(k),
                       rsw::fem::scaled_jacobian(mesh, c));
      EXPECT_DOUBLE_EQ(block.cell_array("joule_heat").at(k), 1e9 * (c + 1));
      EXPECT_DOUBLE_EQ(current.at(k, 0), c);
      EXPECT_DOUBLE_EQ(current.at(k, 1), -c);
      // The quad keeps its counter-clockwise node order.
      ASSERT_EQ(block.cells[k].size(), 4u);
      for (int j = 0; j < 4; ++j)
        EXPECT_EQ(node_id.at(block.cells[k][j]), mesh.cells[c][j]) << "cell " << c;
    }
  }
}

TEST_F(VtkOutput, PiecesLiveInSiblingFolderNamedAfterBodies) {
  rsw::fem::write_vtm(dir_ / "weld.vtm", two_body_mesh());
  EXPECT_TRUE(fs::is_regular_file(dir_ / "weld" / "sheet_1.vtu"));
  EXPECT_TRUE(fs::is_regular_file(dir_ / "weld" / "sheet_1_boundaries.vtp"));
  EXPECT_TRUE(fs::is_regular_file(dir_ / "weld" / "electrode.vtu"));
  EXPECT_TRUE(fs::is_regular_file(dir_ / "weld" / "electrode_boundaries.vtp"));
  // Nothing is left under a temporary name.
  for (const auto& entry : fs::recursive_directory_iterator(dir_))
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();
}

TEST_F(VtkOutput, BoundaryLinesCarryIdsNamesAndFaceNodes) {
  const Mesh mesh = two_body_mesh();
  const fs::path vtm = dir_ / "weld.vtm";
  rsw::fem::write_vtm(vtm, mesh);
  const auto data = rsw::fem::read_vtm(vtm);

  for (int b = 0; b < 2; ++b) {
    const auto& block = data.block(mesh.body_names[b] + "_boundaries");
    const auto& names = block.strings("boundary_names");
    ASSERT_EQ(names.size(), mesh.boundaries.size());
    // Every boundary face of this body appears once, as a line between its two nodes.
    int n_faces = 0;
    for (const auto& [name, faces] : mesh.boundaries)
      for (const auto& f : faces) n_faces += mesh.cell_body[f.cell] == b;
    ASSERT_EQ(block.n_cells, n_faces) << block.name;

    const auto& ids = block.cell_array("boundary_id");
    const auto& node_id = block.point_array("node_id");
    for (int k = 0; k < block.n_cells; ++k) {
      const std::string& name = names.at(static_cast<std::size_t>(ids.at(k)));
      EXPECT_EQ(name.substr(0, name.find('.')), mesh.body_names[b]);
      ASSERT_EQ(block.cells[k].size(), 2u);
      const int a = static_cast<int>(node_id.at(block.cells[k][0]));
      const int z = static_cast<int>(node_id.at(block.cells[k][1]));
      bool found = false;
      for (const auto& f : mesh.boundary(name))
        found |= mesh.face_nodes(f) == std::array<int, 2>{a, z};
      EXPECT_TRUE(found) << "line " << a << "-" << z << " is not a face of " << name;
    }
  }
}

TEST_F(VtkOutput, FaceFieldCoversItsBoundaryAndIsNanElsewhere) {
  const Mesh mesh = two_body_mesh();
  FieldSet fields;
  fields.add_face_scalar("contact_pressure", "sheet_1.top", {1e8, 2e8})
      .add_face_scalar("contact_pressure", "electrode.bottom", {3e8, 4e8});
  const fs::path vtm = dir_ / "weld.vtm";
  rsw::fem::write_vtm(vtm, mesh, fields);
  const auto data = rsw::fem::read_vtm(vtm);

  const auto& sheet = data.block("sheet_1_boundaries");
  const auto& names = sheet.strings("boundary_names");
  std::vector<double> top, axis;
  for (int k = 0; k < sheet.n_cells; ++k) {
    const auto& name = names[static_cast<std::size_t>(sheet.cell_array("boundary_id").at(k))];
    (name == "sheet_1.top" ? top : axis).push_back(sheet.cell_array("contact_pressure").at(k));
  }
  EXPECT_EQ(top, (std::vector<double>{1e8, 2e8}));
  ASSERT_EQ(axis.size(), 1u);
  EXPECT_TRUE(std::isnan(axis[0]));

  const auto& electrode = data.block("electrode_boundaries");
  EXPECT_EQ(electrode.cell_array("contact_pressure").values, (std::vector<double>{3e8, 4e8}));
}

TEST_F(VtkOutput, EachBlockListsTheUnitsOfItsFieldsInItsFieldData) {
  const Mesh mesh = two_body_mesh();
  FieldSet fields;
  fields.add_point_scalar("temperature", std::vector<double>(static_cast<std::size_t>(mesh.n_nodes()), 20.0), "degC")
      .add_cell_scalar("stress", std::vector<double>(static_cast<std::size_t>(mesh.n_cells()), 1e6), "Pa")
      .add_cell_scalar("marker", std::vector<double>(static_cast<std::size_t>(mesh.n_cells()), 1.0))
      .add_face_scalar("contact_pressure", "sheet_1.top", {1e8, 2e8}, "Pa")
      .add_face_scalar("contact_pressure", "electrode.bottom", {3e8, 4e8}, "Pa");
  const fs::path vtm = dir_ / "weld.vtm";
  rsw::fem::write_vtm(vtm, mesh, fields);
  const auto data = rsw::fem::read_vtm(vtm);
  // A field without a unit is not listed; a face field given on two boundaries once.
  EXPECT_EQ(data.block("sheet_1").strings("units"), (std::vector<std::string>{"temperature [degC]", "stress [Pa]"}));
  EXPECT_EQ(data.block("sheet_1_boundaries").strings("units"),
            (std::vector<std::string>{"temperature [degC]", "contact_pressure [Pa]"}));
}

TEST_F(VtkOutput, PvdListsEveryWrittenStep) {
  const Mesh mesh = two_body_mesh();
  const std::vector<double> times = {0.0, 1e-3 / 3, 2e-3 / 3, 0.02};
  VtkTimeSeries series(dir_ / "out" / "weld.pvd");
  EXPECT_TRUE(rsw::fem::read_pvd(series.pvd_path()).empty());

  for (std::size_t i = 0; i < times.size(); ++i) {
    FieldSet fields;
    fields.add_point_scalar("T", std::vector<double>(mesh.nodes.size(), 300.0 + i));
    const fs::path vtm = series.write_step(times[i], mesh, fields);
    EXPECT_EQ(vtm.filename(), "weld_000" + std::to_string(i) + ".vtm");

    // After each step the collection on disk lists exactly the steps written so far,
    // as a run killed at this point would leave it.
    const auto steps = rsw::fem::read_pvd(series.pvd_path());
    ASSERT_EQ(steps.size(), i + 1);
    for (std::size_t k = 0; k <= i; ++k) {
      EXPECT_EQ(steps[k].time, times[k]);  // exact: times are written with 17 digits
      EXPECT_TRUE(fs::equivalent(steps[k].file, series.steps()[k].file));
    }
  }
  const auto last = rsw::fem::read_vtm(series.steps().back().file);
  EXPECT_EQ(last.block("electrode").point_array("T").at(0), 303.0);
}

TEST_F(VtkOutput, StepTimesMustIncrease) {
  const Mesh mesh = two_body_mesh();
  VtkTimeSeries series(dir_ / "weld.pvd");
  series.write_step(1e-3, mesh);
  EXPECT_THROW(series.write_step(1e-3, mesh), std::invalid_argument);
  EXPECT_THROW(series.write_step(0.5e-3, mesh), std::invalid_argument);
  EXPECT_EQ(rsw::fem::read_pvd(series.pvd_path()).size(), 1u);
}

TEST_F(VtkOutput, FieldOfWrongSizeIsRejectedNamingIt) {
  const Mesh mesh = two_body_mesh();
  FieldSet fields;
  fields.add_point_scalar("T", std::vector<double>(5, 300.0));
  try {
    rsw::fem::write_vtm(dir_ / "weld.vtm", mesh, fields);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'T'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("14"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "weld.vtm"));
}

TEST_F(VtkOutput, FaceFieldOnUnknownBoundaryIsRejectedNamingIt) {
  FieldSet fields;
  fields.add_face_scalar("gap", "sheet_2.top", {0.0});
  try {
    rsw::fem::write_vtm(dir_ / "weld.vtm", two_body_mesh(), fields);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sheet_2.top"), std::string::npos) << e.what();
  }
}

TEST_F(VtkOutput, ReservedOrRepeatedFieldNamesAreRejected) {
  FieldSet fields;
  EXPECT_THROW(fields.add_cell_scalar("level", {}), std::invalid_argument);
  EXPECT_THROW(fields.add_point_scalar("hanging", {}), std::invalid_argument);
  fields.add_point_scalar("T", {});
  EXPECT_THROW(fields.add_point_scalar("T", {}), std::invalid_argument);
  fields.add_face_scalar("gap", "sheet_1.top", {});
  EXPECT_THROW(fields.add_face_scalar("gap", "sheet_1.top", {}), std::invalid_argument);
  EXPECT_NO_THROW(fields.add_face_scalar("gap", "electrode.bottom", {}));
}

TEST_F(VtkOutput, ReadingMissingFileNamesIt) {
  const fs::path missing = dir_ / "nothing.vtm";
  try {
    rsw::fem::read_vtm(missing);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(rsw::fem::read_pvd(dir_ / "nothing.pvd"), std::runtime_error);
}

// VTK's loops in the writers follow the process's thread count (fem/threads.hpp): one
// thread selects the sequential backend (no TBB worker that spins after each loop),
// several threads VTK's default backend again.
TEST_F(VtkOutput, WritersFollowTheProcessThreadCount) {
  rsw::fem::use_threads(1);
  rsw::fem::write_vtm(dir_ / "one.vtm", two_body_mesh());
  EXPECT_EQ(std::string(vtkSMPTools::GetBackend()), "Sequential");
  EXPECT_EQ(vtkSMPTools::GetEstimatedNumberOfThreads(), 1);
  rsw::fem::use_threads(2);
  rsw::fem::write_vtm(dir_ / "two.vtm", two_body_mesh());
  EXPECT_EQ(std::string(vtkSMPTools::GetBackend()), VTK_SMP_BACKEND);
  rsw::fem::use_threads(1);
}

}  // namespace
