// Nugget sizes on the interpolated peak-temperature field: an elliptic synthetic
// field gives diameter, height, penetration and unmolten thickness in closed form,
// and the sizes move continuously (not in element steps) when the field changes.
// Melt on the outer surface apart from the nugget counts only in the whole region's
// extent; a ring of melt has no height on the axis.
#include "meshes/weld_mesh.hpp"
#include "physics/nugget.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace rsw;

namespace {
struct EllipticField {
  fem::Mesh mesh;
  std::vector<int> sheets;
  std::vector<double> iso;
  EllipticField() {
    meshes::StackGeometry s;
    s.sheets = {{"sheet_1", "DP1200", 1e-3}, {"sheet_2", "DP1200", 1e-3}};
    mesh = meshes::weld_mesh(s, {});
    sheets = {mesh.body_index("sheet_1"), mesh.body_index("sheet_2")};
    iso.assign(mesh.n_bodies(), 1500.0);
  }
  // T = 1000 + 1000 (1 - r²/A² - z²/B²): the 1500 °C isotherm is the ellipse
  // r²/A² + z²/B² = 1/2.
  // With `spot`, a second peak of 1600 °C, 0.25 mm in radius, on the top sheet's
  // outer surface at r = 2.75 mm: melt at the edge of an electrode face, apart from
  // the nugget.
  physics::NuggetSize measure(double A, double B, bool spot = false) const {
    std::vector<double> peak(mesh.n_nodes());
    for (int n = 0; n < mesh.n_nodes(); ++n) {
      const auto& p = mesh.nodes[n];
      peak[n] = 1000 + 1000 * (1 - p.x() * p.x() / (A * A) - p.y() * p.y() / (B * B));
      const double dr = p.x() - 2.75e-3, dz = p.y() - 1e-3;
      if (spot && mesh.node_body[n] == sheets[0])
        peak[n] = std::max(peak[n], 1600 - 100 * (dr * dr + dz * dz) / (0.25e-3 * 0.25e-3));
    }
    return physics::measure_nugget(mesh, mesh.nodes, peak, sheets, iso);
  }
};
}  // namespace

TEST(Nugget, EllipticIsothermGivesClosedFormSizes) {
  EllipticField f;
  const double A = 4e-3, B = 1e-3;
  const auto n = f.measure(A, B);
  const double d = 2 * A * std::sqrt(0.5), h = 2 * B * std::sqrt(0.5);
  std::printf("nugget: d = %.4f mm (%.4f), h = %.4f mm (%.4f), penetration %.3f / %.3f (%.3f), t_unmolt %.4f mm\n",
              n.diameter * 1e3, d * 1e3, n.height * 1e3, h * 1e3, n.penetration[0], n.penetration[1],
              B * std::sqrt(0.5) / 1e-3, n.unmolten_thickness * 1e3);
  // Linear interpolation of the quadratic field along an edge of length h_c errs by at
  // most h_c² |T''| / 8 in T, i.e. h_c² |T''| / (8 |T'|) in the crossing position:
  // along z at the nugget's top, (62.5 µm)² · 2000 K/mm² / (8 · 1414 K/mm) = 0.7 µm per
  // side; along r at its rim, (62.5 µm)² · 125 K/mm² / (8 · 354 K/mm) = 0.17 µm.
  ASSERT_FALSE(n.empty);
  EXPECT_NEAR(n.diameter, d, 2 * 0.17e-6);
  EXPECT_NEAR(n.height, h, 2 * 0.7e-6);
  EXPECT_NEAR(n.extent, h, 2 * 0.7e-6);  // a lens is thickest on the axis
  EXPECT_NEAR(n.penetration[0], B * std::sqrt(0.5) / 1e-3, 0.7e-3);
  EXPECT_NEAR(n.unmolten_thickness, 1e-3 - B * std::sqrt(0.5), 0.7e-6);
}

TEST(Nugget, SizesMoveContinuouslyWithTheField) {
  // Steps far smaller than a cell (0.0625 mm): a counted size would not move at all
  // or jump by a cell; the interpolated one follows 2√½ dA.
  EllipticField f;
  const double A = 4e-3, dA = 1e-6;
  double previous = f.measure(A, 1e-3).diameter;
  for (int k = 1; k <= 5; ++k) {
    const double d = f.measure(A + k * dA, 1e-3).diameter;
    EXPECT_NEAR(d - previous, 2 * std::sqrt(0.5) * dA, 0.05 * dA);
    previous = d;
  }
}

TEST(Nugget, NoRegionAboveIsothermIsEmpty) {
  EllipticField f;
  std::vector<double> peak(f.mesh.n_nodes(), 20.0);
  const auto n = physics::measure_nugget(f.mesh, f.mesh.nodes, peak, f.sheets, f.iso);
  EXPECT_TRUE(n.empty);
  EXPECT_EQ(n.diameter, 0.0);
  EXPECT_NEAR(n.unmolten_thickness, 2e-3, 1e-15);
}

TEST(Nugget, SurfaceMeltBesideTheFaceCountsInExtentAndPenetrationNotInHeightDiameterOrUnmoltenThickness) {
  // The spot's 1500 °C isotherm is the half-circle of radius 0.25 mm around
  // (2.75 mm, 1 mm): it reaches down to 0.75 mm above the faying surface and out to
  // r = 3 mm, beyond the nugget's rim at A √½ = 2.83 mm. The nugget's height on the
  // axis stays 2 B √½ and its diameter in the faying plane 2 A √½; the whole
  // region's extent runs from the nugget's bottom, −B √½, to the top surface.
  EllipticField f;
  const double A = 4e-3, B = 1e-3;
  const auto lens = f.measure(A, B);
  const auto both = f.measure(A, B, true);
  EXPECT_DOUBLE_EQ(both.height, lens.height);
  EXPECT_DOUBLE_EQ(both.diameter, lens.diameter);
  EXPECT_NEAR(both.diameter, 2 * A * std::sqrt(0.5), 2 * 0.17e-6);
  EXPECT_NEAR(both.height, 2 * B * std::sqrt(0.5), 2 * 0.7e-6);
  EXPECT_NEAR(both.extent, 1e-3 + B * std::sqrt(0.5), 0.7e-6);
  EXPECT_DOUBLE_EQ(both.unmolten_thickness, lens.unmolten_thickness);  // measured on the axis
  EXPECT_GT(both.penetration[0], lens.penetration[0]);                 // penetration counts all melt
}

TEST(Nugget, RingShapedMeltHasNoHeightOnTheAxis) {
  EllipticField f;
  std::vector<double> peak(f.mesh.n_nodes());
  for (int n = 0; n < f.mesh.n_nodes(); ++n) {  // a torus of melt around r = 2 mm, z = 0
    const double dr = f.mesh.nodes[n].x() - 2e-3, z = f.mesh.nodes[n].y();
    peak[n] = 1600 - 100 * (dr * dr + z * z) / (0.5e-3 * 0.5e-3);
  }
  const auto n = physics::measure_nugget(f.mesh, f.mesh.nodes, peak, f.sheets, f.iso);
  ASSERT_FALSE(n.empty);
  EXPECT_NEAR(n.diameter, 2 * 2.5e-3, 1e-6);
  EXPECT_EQ(n.height, 0.0);
  EXPECT_NEAR(n.extent, 2 * 0.5e-3, 2e-6);
  EXPECT_NEAR(n.unmolten_thickness, 2e-3, 1e-15);  // the axis is solid through the stack
}
