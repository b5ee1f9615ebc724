// Weld-case meshes: element sizes of the default case, validity of every cell,
// boundary nodes on the true contour, volumes of the electrode against closed forms,
// the mirror symmetry of symmetric stacks.
#include "fem/fe_values.hpp"
#include "fem/mirror.hpp"
#include "meshes/weld_mesh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace rsw;

namespace {
meshes::StackGeometry default_stack() {
  meshes::StackGeometry s;
  s.sheets = {{"sheet_1", "DP1200", 1e-3}, {"sheet_2", "DP1200", 1e-3}};
  return s;
}

double body_volume(const fem::Mesh& mesh, int body) {
  fem::CellValues cv(2);
  double v = 0;
  for (int e = 0; e < mesh.n_cells(); ++e) {
    if (mesh.cell_body[e] != body) continue;
    cv.reinit(mesh, e);
    for (int q = 0; q < cv.n_q(); ++q) v += cv.JxW(q);
  }
  return v;
}

bool inside(const meshes::RefinementBox& b, const fem::Point& p) {
  return p.x() > b.r_min && p.x() < b.r_max && p.y() > b.z_min && p.y() < b.z_max;
}
}  // namespace

TEST(WeldMesh, DefaultCaseHasRequestedElementSizes) {
  const auto stack = default_stack();
  const meshes::MeshSettings settings;
  const fem::Mesh mesh = meshes::weld_mesh(stack, settings);
  ASSERT_EQ(mesh.body_names, (std::vector<std::string>{"upper_electrode", "sheet_1", "sheet_2", "lower_electrode"}));
  const auto zone = meshes::refinement_boxes(stack, settings).front();
  EXPECT_DOUBLE_EQ(zone.z_max, 1.5e-3);  // half the 2 mm stack plus 0.5 mm into the electrode
  int n_zone = 0;
  for (int e = 0; e < mesh.n_cells(); ++e) {
    const auto& c = mesh.cells[e];
    const fem::Point centre = 0.25 * (mesh.nodes[c[0]] + mesh.nodes[c[1]] + mesh.nodes[c[2]] + mesh.nodes[c[3]]);
    const bool is_sheet = mesh.body_names[mesh.cell_body[e]].rfind("sheet", 0) == 0;
    const double expected = 0.25e-3 / (1 << mesh.cell_level[e]);
    if (inside(zone, centre)) {
      ++n_zone;
      EXPECT_EQ(mesh.cell_level[e], 2) << "cell " << e << " in the weld zone";
    }
    for (int k = 0; k < 4; ++k) {
      const double len = (mesh.nodes[c[(k + 1) % 4]] - mesh.nodes[c[k]]).norm();
      if (is_sheet) {
        EXPECT_NEAR(len, expected, 1e-12) << "sheet cell " << e;  // sheets: exact 0.25 mm grid
      } else {
        // Electrodes: segment rounding and the flank's blend layer stretch cells by
        // at most a factor 1/cos(30 deg) and compress them by at most 1 - 3.1/8.
        EXPECT_GT(len, 0.55 * expected) << "electrode cell " << e;
        EXPECT_LT(len, 1.2 * expected) << "electrode cell " << e;
      }
    }
  }
  std::printf("weld zone: %d cells of level 2 (0.0625 mm)\n", n_zone);
  EXPECT_GT(n_zone, 2 * 16 * 18 * 4);  // both sheets at least, 4 x 18 base cells each
}

TEST(WeldMesh, EveryCellHasPositiveJacobianAndBoundedAngles) {
  const fem::Mesh mesh = meshes::weld_mesh(default_stack(), {});
  const auto stats = fem::mesh_stats(mesh);
  std::printf("default mesh: %d cells, %d nodes, %d hanging, edges %.4f..%.4f mm, worst scaled Jacobian %.3f, "
              "angles %.1f..%.1f deg\n",
              stats.n_cells, stats.n_nodes, stats.n_hanging, stats.min_edge * 1e3, stats.max_edge * 1e3,
              stats.min_scaled_jacobian, stats.min_angle_deg, stats.max_angle_deg);
  EXPECT_GT(stats.min_scaled_jacobian, 0.8);
  fem::CellValues cv(2);
  for (int e = 0; e < mesh.n_cells(); ++e) EXPECT_NO_THROW(cv.reinit(mesh, e));
}

TEST(WeldMesh, BoundaryNodesLieOnTheTrueElectrodeContour) {
  const auto stack = default_stack();
  const fem::Mesh mesh = meshes::weld_mesh(stack, {});
  const auto& g = stack.upper;
  const double apex = 1e-3;
  for (const char* name : {"upper_electrode.contact_face", "upper_electrode.flank"})
    for (int n : mesh.boundary_nodes(name)) {
      const fem::Point& p = mesh.nodes[n];
      EXPECT_NEAR(p.y(), apex + meshes::electrode_profile(g, p.x()), 1e-15) << name << " node " << n;
    }
  // Dome nodes exactly on the R30 sphere centred on the axis 30 mm above the apex. The
  // contact face also takes in the flank's first millimetre beyond the face edge (where
  // deep indentation wraps the sheet around the edge), and stops there.
  const double a = 0.5 * g.face_diameter;
  int on_flank = 0;
  double outermost = 0;
  for (int n : mesh.boundary_nodes("upper_electrode.contact_face")) {
    const fem::Point& p = mesh.nodes[n];
    outermost = std::max(outermost, p.x());
    if (p.x() > a + 1e-15) {
      ++on_flank;
      continue;
    }
    EXPECT_NEAR(std::hypot(p.x(), p.y() - (apex + g.face_radius)), g.face_radius, 1e-15);
  }
  EXPECT_GE(on_flank, 3);
  EXPECT_GT(outermost, a + 0.75e-3);
  EXPECT_LT(outermost, a + 1.25e-3);
  for (int n : mesh.boundary_nodes("upper_electrode.flank")) EXPECT_GE(mesh.nodes[n].x(), outermost - 1e-15);
  for (int n : mesh.boundary_nodes("upper_electrode.cooling_bore")) {
    const fem::Point& p = mesh.nodes[n];
    const bool on_wall = std::abs(p.x() - 0.5 * g.bore_diameter) < 1e-15;
    const bool on_bottom = std::abs(p.y() - (apex + g.bore_depth)) < 1e-15;
    EXPECT_TRUE(on_wall || on_bottom) << "bore node at " << p.transpose();
  }
  for (int n : mesh.boundary_nodes("upper_electrode.side")) EXPECT_NEAR(mesh.nodes[n].x(), 0.5 * g.cap_diameter, 1e-15);
  for (int n : mesh.boundary_nodes("lower_electrode.end_face"))
    EXPECT_NEAR(mesh.nodes[n].y(), -apex - stack.lower.length, 1e-15);
  for (int n : mesh.boundary_nodes("sheet_2.bottom")) EXPECT_NEAR(mesh.nodes[n].y(), -apex, 1e-15);
}

TEST(WeldMesh, InterfacesPairTheTouchingSurfaces) {
  const fem::Mesh mesh = meshes::weld_mesh(default_stack(), {});
  ASSERT_EQ(mesh.interfaces.size(), 3u);
  EXPECT_EQ(mesh.interfaces.at("es_upper").first, "upper_electrode.contact_face");
  EXPECT_EQ(mesh.interfaces.at("es_upper").second, "sheet_1.top");
  EXPECT_EQ(mesh.interfaces.at("ss_1_2").second, "sheet_2.top");
  EXPECT_EQ(mesh.interfaces.at("es_lower").first, "lower_electrode.contact_face");
  // At r = 0 each contact pair starts touching.
  for (const auto& [name, pair] : mesh.interfaces) {
    double z1 = 1e9, z2 = -1e9;
    for (int n : mesh.boundary_nodes(pair.first))
      if (mesh.nodes[n].x() == 0) z1 = mesh.nodes[n].y();
    for (int n : mesh.boundary_nodes(pair.second))
      if (mesh.nodes[n].x() == 0) z2 = mesh.nodes[n].y();
    EXPECT_NEAR(z1, z2, 1e-15) << name;
  }
}

TEST(WeldMesh, ThreeSheetStackOfUnequalThicknessMeshes) {
  meshes::StackGeometry s;
  s.sheets = {{"", "DP1200", 0.8e-3}, {"", "DP600", 1.5e-3}, {"", "DC04", 0.7e-3}};
  const fem::Mesh mesh = meshes::weld_mesh(s, {});
  EXPECT_EQ(mesh.n_bodies(), 5);
  EXPECT_EQ(mesh.interfaces.count("ss_2_3"), 1u);
  EXPECT_GT(fem::mesh_stats(mesh).min_scaled_jacobian, 0.8);
  // Sheet volumes are exact cylinders.
  const double R = s.sheet_radius;
  EXPECT_NEAR(body_volume(mesh, mesh.body_index("sheet_2")), M_PI * R * R * 1.5e-3, 1e-18);
}

// The mesh builder says which interface law applies where: the electrode contacts
// are electrode/sheet, every contact between two sheets sheet/sheet, whatever the
// interfaces are called.
TEST(WeldMesh, EachInterfaceCarriesTheKindThatSelectsItsLaw) {
  meshes::StackGeometry s;
  s.sheets = {{"", "DP1200", 0.8e-3}, {"", "DP600", 1.5e-3}, {"", "DC04", 0.7e-3}};
  const fem::Mesh mesh = meshes::weld_mesh(s, {});
  ASSERT_EQ(mesh.interfaces.size(), 4u);
  EXPECT_EQ(mesh.interfaces.at("es_upper").kind, meshes::interface_kind::electrode_sheet);
  EXPECT_EQ(mesh.interfaces.at("es_lower").kind, meshes::interface_kind::electrode_sheet);
  EXPECT_EQ(mesh.interfaces.at("ss_1_2").kind, meshes::interface_kind::sheet_sheet);
  EXPECT_EQ(mesh.interfaces.at("ss_2_3").kind, meshes::interface_kind::sheet_sheet);
}

TEST(ElectrodeVolume, ConeElectrodeWithFlatFaceIsExact) {
  meshes::ElectrodeGeometry g;
  g.face_radius = 0;  // flat face: the profile is a polygon, meshed exactly
  g.bore_diameter = 0;
  meshes::MeshSettings settings;
  const fem::Mesh mesh = meshes::electrode_mesh(g, "e", 0.0, 1, settings, {});
  // Closed form: cylinder minus the cone frustum ring below the flank.
  const double a = 0.5 * g.face_diameter, b = 0.5 * g.cap_diameter, m = 1 / std::tan(0.5 * g.cone_angle);
  const double ring = 2 * M_PI * m * ((b * b * b - a * a * a) / 3 - a * (b * b - a * a) / 2);
  const double exact = M_PI * b * b * g.length - ring;
  EXPECT_NEAR(meshes::electrode_volume(g), exact, 1e-15);
  EXPECT_NEAR(body_volume(mesh, 0), exact, 1e-12 * exact);
}

TEST(ElectrodeVolume, DomedElectrodeConvergesToSphericalCapClosedForm) {
  // The dome region below the face plane z = s(a) is the cylinder π a^2 s(a) minus the
  // spherical cap π s^2 (3R - s)/3; chords converge to it at second order.
  meshes::ElectrodeGeometry g;
  g.face_radius = 8e-3;  // a strongly curved dome makes the chord error visible
  g.bore_diameter = 0;
  const double a = 0.5 * g.face_diameter, R = g.face_radius, s = R - std::sqrt(R * R - a * a);
  const double cap = M_PI * s * s * (3 * R - s) / 3;
  meshes::ElectrodeGeometry flat = g;
  flat.face_radius = 0;
  // Volume removed by the dome relative to the flat face, at the face: π a^2 s - cap,
  // plus the flank raised by s over the ring a..b: π (b^2 - a^2) s.
  const double b = 0.5 * g.cap_diameter;
  EXPECT_NEAR(meshes::electrode_volume(flat) - meshes::electrode_volume(g),
              (M_PI * a * a * s - cap) + M_PI * (b * b - a * a) * s, 1e-15);
  std::vector<double> errors;
  for (double h : {0.5e-3, 0.25e-3, 0.125e-3}) {
    meshes::MeshSettings settings;
    settings.base_size = h;
    const fem::Mesh mesh = meshes::electrode_mesh(g, "e", 0.0, 1, settings, {});
    errors.push_back(std::abs(body_volume(mesh, 0) - meshes::electrode_volume(g)) / cap);
    std::printf("dome volume, h = %.3f mm: error %.3e of the cap volume\n", h * 1e3, errors.back());
  }
  EXPECT_NEAR(std::log2(errors[1] / errors[2]), 2.0, 0.15);
  EXPECT_LT(errors.back(), 1e-3);
}

TEST(WeldMesh, ImpossibleElectrodeIsRejectedWithItsDimension) {
  auto s = default_stack();
  s.upper.bore_depth = 2e-3;  // the flank rises 3.1 mm: it would cut into the bore
  try {
    meshes::weld_mesh(s, {});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("upper_electrode"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bore"), std::string::npos) << e.what();
  }
}

// A stack of two equal sheets between equal electrodes meshes symmetrically about its
// mid-plane: every node below has its image above (fem/mirror.hpp). Unequal sheets,
// electrodes or refinement do not, nor three sheets.
TEST(WeldMesh, SymmetricStacksMeshAsTheirMirrorImageAndOthersDoNot) {
  const meshes::MeshSettings settings;
  const fem::Mesh two = meshes::weld_mesh(default_stack(), settings);
  const auto bodies = meshes::mirror_bodies(default_stack(), two);
  ASSERT_EQ(bodies, (std::vector<int>{3, 2, 1, 0}));
  const fem::MirrorSymmetry m = fem::find_mirror_symmetry(two, bodies, 1e-9);
  ASSERT_FALSE(m.empty());
  int lower = 0;
  for (int n = 0; n < two.n_nodes(); ++n) lower += two.node_body[n] >= 2;
  EXPECT_EQ(m.n_images(), lower);

  // Three sheets, however symmetric, are solved whole (meshes/weld_mesh.hpp).
  meshes::StackGeometry three;
  three.sheets = {{"sheet_1", "DP1200", 1e-3}, {"sheet_2", "DX54", 1.5e-3}, {"sheet_3", "DP1200", 1e-3}};
  EXPECT_TRUE(meshes::mirror_bodies(three, meshes::weld_mesh(three, settings)).empty());
  meshes::StackGeometry unequal = default_stack();
  unequal.sheets[1].thickness = 1.5e-3;
  EXPECT_TRUE(meshes::mirror_bodies(unequal, meshes::weld_mesh(unequal, settings)).empty());
  meshes::StackGeometry other_material = default_stack();
  other_material.sheets[1].material = "DX54";
  EXPECT_TRUE(meshes::mirror_bodies(other_material, two).empty());
  meshes::StackGeometry other_electrode = default_stack();
  other_electrode.lower.face_radius = 40e-3;
  EXPECT_TRUE(meshes::mirror_bodies(other_electrode, two).empty());
  // Equal bodies, but a refinement box above the plane only: the mesh is not symmetric.
  meshes::MeshSettings one_sided = settings;
  one_sided.extra_boxes.push_back({0.0, 2e-3, 0.2e-3, 0.6e-3, 3});
  const fem::Mesh boxed = meshes::weld_mesh(default_stack(), one_sided);
  EXPECT_TRUE(fem::find_mirror_symmetry(boxed, meshes::mirror_bodies(default_stack(), boxed), 1e-9).empty());
}
