// Mirror symmetry about z = 0 (fem/mirror.hpp): the images of a symmetric stack found
// (and refused for an unequal one), and the half-stack solve against the closed-form
// fields of whole stacks: a potential odd in z across a contact conductance, a
// temperature even in z from a uniform source, a body the plane cuts.
#include "fem/assembler.hpp"
#include "fem/fe_values.hpp"
#include "fem/linear_solver.hpp"
#include "fem/mirror.hpp"
#include "fem/quadtree.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

using namespace rsw;

namespace {

constexpr double R = 2e-3;  // m, radius of every slab

// Body `name` on [0, R] x [z0, z1] on an n_r x n_z base grid, refined to `level(box)`
// (index coordinates); boundaries "<name>.bottom", ".right", ".top", ".left".
fem::Mesh slab(const std::string& name, double z0, double z1, int n_r, int n_z,
               const std::function<int(const fem::IndexBox&)>& level = {}) {
  fem::Quadtree tree(n_r, n_z);
  if (level) tree.refine(level);
  tree.balance();
  return tree.build(
      name, [=](double x, double y) { return fem::Point(R * x / n_r, z0 + (z1 - z0) * y / n_z); },
      [](double, double, fem::Side s) -> std::string {
        static const char* names[] = {"bottom", "right", "top", "left"};
        return names[static_cast<int>(s)];
      });
}

// Two slabs of thickness H on either side of z = 0: "upper" on [0, H], "lower" on
// [−H, 0]; `refine_near_plane` refines the cells within H/4 of the plane once.
fem::Mesh two_slabs(double H_upper, double H_lower, int n, bool refine_near_plane = false) {
  using Level = std::function<int(const fem::IndexBox&)>;
  auto near = [n, refine_near_plane](bool upper) -> Level {
    if (!refine_near_plane) return {};
    return [=](const fem::IndexBox& b) {
      const double y = upper ? b.y0 : n - b.y1;  // index distance from the plane
      return y < 0.25 * n ? 1 : 0;
    };
  };
  fem::Mesh mesh = slab("upper", 0.0, H_upper, n, n, near(true));
  mesh.append(slab("lower", -H_lower, 0.0, n, n, near(false)));
  return mesh;
}

// The coupling groups of the contact between upper.bottom and lower.top: per face of
// upper.bottom its two nodes and the two lower nodes at the same places.
std::vector<std::vector<int>> contact_groups(const fem::Mesh& mesh) {
  std::vector<std::vector<int>> groups;
  const auto lower = mesh.boundary_nodes("lower.top");
  auto at = [&](int n) {
    for (int m : lower)
      if ((mesh.nodes[m] - mesh.nodes[n]).norm() < 1e-12) return m;
    return -1;
  };
  for (const auto& f : mesh.boundary("upper.bottom")) {
    const auto ab = mesh.face_nodes(f);
    groups.push_back({ab[0], ab[1], at(ab[0]), at(ab[1])});
  }
  return groups;
}

struct Field {
  Eigen::VectorXd x;  // nodal values
  int n_free = 0;
};

// −∇·(k∇u) = q on the mesh (axisymmetric), u = value on the named boundaries, and a
// contact conductance h between upper.bottom and lower.top (if both exist):
// h ∫ (u_s − u_m)(v_s − v_m) dA on the groups of contact_groups(). With a mirror of
// sign s the lower half is the image of the upper one.
Field solve(const fem::Mesh& mesh, double k, double q, double h,
            const std::vector<std::pair<std::string, double>>& fixed, const fem::MirrorSymmetry& mirror,
            double sign) {
  fem::DofMap dofs(mesh, 1);
  fem::Constraints constraints(dofs.n_dofs());
  fem::add_mirror_constraints(constraints, mesh, dofs, mirror, {sign});
  constraints.add_hanging_nodes(mesh, dofs);
  for (const auto& [name, value] : fixed)
    constraints.constrain_boundary(mesh, dofs, name, 0, [v = value](const fem::Point&) { return v; });
  constraints.close();
  const bool contact = mesh.boundaries.count("upper.bottom") && mesh.boundaries.count("lower.top");
  const auto groups = contact ? contact_groups(mesh) : std::vector<std::vector<int>>{};
  fem::Assembler assembler(mesh, dofs, constraints, groups);
  assembler.set_mirror(mirror);

  fem::Assembler::Terms terms;
  terms.cells = [&](int cell, fem::LocalSystem& local) {
    fem::CellValues cv(2);
    cv.reinit(mesh, cell);
    for (int g = 0; g < cv.n_q(); ++g)
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) local.matrix(a, b) += k * cv.grad_N(g, a).dot(cv.grad_N(g, b)) * cv.JxW(g);
        local.vector(a) += q * cv.N(g, a) * cv.JxW(g);
      }
  };
  terms.groups = [&](int g, fem::LocalSystem& local) {
    const auto& n = groups[g];
    const double r0 = mesh.nodes[n[0]].x(), r1 = mesh.nodes[n[1]].x();
    for (const double xi : {-1 / std::sqrt(3.0), 1 / std::sqrt(3.0)}) {  // 2-point Gauss on the face
      const double N0 = 0.5 * (1 - xi), N1 = 0.5 * (1 + xi);
      const double dA = 2 * M_PI * (N0 * r0 + N1 * r1) * 0.5 * std::abs(r1 - r0);
      const double jump[4] = {N0, N1, -N0, -N1};
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) local.matrix(a, b) += h * jump[a] * jump[b] * dA;
    }
  };
  fem::SparseMatrix K;
  Eigen::VectorXd F;
  assembler.assemble(terms, K, F);
  fem::LinearSolver solver(fem::SolverKind::cholmod);
  return {constraints.distribute(solver.solve(K, F)), constraints.n_free()};
}

fem::MirrorSymmetry upper_lower_mirror(const fem::Mesh& mesh) {
  return fem::find_mirror_symmetry(mesh, {mesh.body_index("lower"), mesh.body_index("upper")}, 1e-12);
}

}  // namespace

TEST(Mirror, FindsEveryImageOfASymmetricStackAndNoneOfAnUnequalOne) {
  const fem::Mesh mesh = two_slabs(1e-3, 1e-3, 4, /*refine_near_plane=*/true);
  const fem::MirrorSymmetry m = upper_lower_mirror(mesh);
  ASSERT_FALSE(m.empty());
  const int lower = mesh.body_index("lower");
  int lower_nodes = 0;
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    if (mesh.node_body[n] != lower) {
      EXPECT_EQ(m.image_of[n], -1) << "node " << n;
      continue;
    }
    ++lower_nodes;
    ASSERT_TRUE(m.is_image(n));
    const fem::Point& x = mesh.nodes[n];
    const fem::Point& s = mesh.nodes[m.image_of[n]];
    EXPECT_EQ(x.x(), s.x());
    EXPECT_EQ(x.y(), -s.y());
  }
  EXPECT_EQ(m.n_images(), lower_nodes);
  EXPECT_FALSE(mesh.hanging_nodes.empty());
  for (int c = 0; c < mesh.n_cells(); ++c) {
    const std::vector<int> nodes(mesh.cells[c].begin(), mesh.cells[c].end());
    EXPECT_EQ(m.weight(nodes), mesh.cell_body[c] == lower ? 0.0 : 1.0);
    EXPECT_EQ(m.cell_source[c] >= 0, mesh.cell_body[c] == lower);
  }
  // A contact face couples both halves: half its weight.
  EXPECT_EQ(m.weight(contact_groups(mesh).front()), 0.5);
  // The lower slab's bottom is the image of the upper one's top, not of its sides.
  EXPECT_TRUE(fem::are_images(m, mesh.boundary_nodes("lower.bottom"), mesh.boundary_nodes("upper.top")));
  EXPECT_FALSE(fem::are_images(m, mesh.boundary_nodes("lower.bottom"), mesh.boundary_nodes("upper.right")));
  EXPECT_FALSE(fem::are_images(m, mesh.boundary_nodes("upper.top"), mesh.boundary_nodes("upper.top")));

  EXPECT_TRUE(upper_lower_mirror(two_slabs(1e-3, 1.2e-3, 4)).empty()) << "unequal thickness";
  fem::Mesh one_sided = slab("upper", 0.0, 1e-3, 4, 4, [](const fem::IndexBox& b) { return b.y0 < 1 ? 1 : 0; });
  one_sided.append(slab("lower", -1e-3, 0.0, 4, 4));
  EXPECT_TRUE(upper_lower_mirror(one_sided).empty()) << "refined on one side only";
}

// Potential odd in z: two slabs of conductivity k and thickness H, a contact
// conductance h between them, φ = ±V on the outer faces. The current density is
// j = 2V / (2H/k + 1/h); φ is linear in each slab with φ(0±) = ±j/(2h). Bilinear
// cells hold that field exactly, so both solves must reproduce it to round-off.
TEST(Mirror, HalfStackGivesTheWholeStacksOddPotentialAcrossAContactConductance) {
  const double H = 1e-3, k = 2e6, h = 5e9, V = 0.1;  // m, S/m, S/m², V
  const fem::Mesh mesh = two_slabs(H, H, 6);
  const std::vector<std::pair<std::string, double>> fixed{{"upper.top", V}, {"lower.bottom", -V}};
  const double j = 2 * V / (2 * H / k + 1 / h);
  const Field full = solve(mesh, k, 0, h, fixed, {}, -1);
  const Field half = solve(mesh, k, 0, h, fixed, upper_lower_mirror(mesh), -1);
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const double z = mesh.nodes[n].y();
    const bool upper = mesh.node_body[n] == mesh.body_index("upper");
    const double exact = (upper ? j / (2 * h) : -j / (2 * h)) + j * z / k;
    EXPECT_NEAR(full.x[n], exact, 1e-12 * V) << "node " << n;
    EXPECT_NEAR(half.x[n], exact, 1e-12 * V) << "node " << n;
  }
  // The upper slab less its fixed face: 6 x 6 nodes against twice that.
  EXPECT_EQ(half.n_free, 6 * 7);
  EXPECT_EQ(full.n_free, 2 * 6 * 7);
}

// Temperature even in z: a uniform source q in both slabs, T = 0 on the outer faces.
// By symmetry no heat crosses the plane, whatever h: T = q (H² − z²) / (2k). The
// axisymmetric Galerkin solution of a field of z alone on a tensor grid is the 1D
// linear-element solution, exact at the nodes for a uniform source.
TEST(Mirror, HalfStackGivesTheWholeStacksEvenTemperatureUnderAUniformSource) {
  const double H = 1e-3, k = 40, q = 3e11, h = 1e5;  // m, W/(m K), W/m³, W/(m² K)
  const fem::Mesh mesh = two_slabs(H, H, 6);
  const std::vector<std::pair<std::string, double>> fixed{{"upper.top", 0.0}, {"lower.bottom", 0.0}};
  const Field half = solve(mesh, k, q, h, fixed, upper_lower_mirror(mesh), +1);
  const double T_peak = q * H * H / (2 * k);
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const double z = mesh.nodes[n].y();
    EXPECT_NEAR(half.x[n], q * (H * H - z * z) / (2 * k), 1e-10 * T_peak) << "node " << n;
  }
}

// One body from −H to H mirrored by itself: nodes on the plane are their own images,
// an odd field is zero there (φ = V z/H, exact on any mesh) and an even one free
// (T = q (H² − z²)/(2k), exact at the nodes of a tensor grid).
TEST(Mirror, ABodyCutByThePlaneIsZeroThereWhereOddAndFreeWhereEven) {
  const double H = 1e-3, k = 40, q = 3e11, V = 0.1;
  const fem::Mesh refined = slab("middle", -H, H, 4, 8, [](const fem::IndexBox& b) {
    return std::abs(0.5 * (b.y0 + b.y1) - 4) < 2 && b.x0 < 2 ? 1 : 0;  // hanging nodes on the plane
  });
  const fem::MirrorSymmetry m = fem::find_mirror_symmetry(refined, {0}, 1e-12);
  ASSERT_FALSE(m.empty());
  std::vector<int> plane;
  for (int n = 0; n < refined.n_nodes(); ++n)
    if (m.on_plane(n)) plane.push_back(n);
  EXPECT_GT(plane.size(), 5u);
  EXPECT_EQ(m.weight(plane), 0.5);  // a term in the plane is its own mirror
  const Field odd = solve(refined, k, 0, 0, {{"middle.top", V}, {"middle.bottom", -V}}, m, -1);
  for (int n = 0; n < refined.n_nodes(); ++n)
    EXPECT_NEAR(odd.x[n], V * refined.nodes[n].y() / H, 1e-12 * V) << "node " << n;

  const fem::Mesh uniform = slab("middle", -H, H, 4, 8);
  const Field even =
      solve(uniform, k, q, 0, {{"middle.top", 0.0}, {"middle.bottom", 0.0}}, fem::find_mirror_symmetry(uniform, {0}, 1e-12), +1);
  const double T_peak = q * H * H / (2 * k);
  for (int n = 0; n < uniform.n_nodes(); ++n) {
    const double z = uniform.nodes[n].y();
    EXPECT_NEAR(even.x[n], q * (H * H - z * z) / (2 * k), 1e-10 * T_peak) << "node " << n;
  }
  EXPECT_EQ(even.n_free, 5 * 4);  // rows z = 0 .. H less the fixed top: 4 of 5 nodes each
}

// On a mesh with hanging nodes no closed form is exact; the half solve must still be
// the whole stack's symmetric solution, to round-off.
TEST(Mirror, RefinedHalfStackSolvesAsTheWholeStack) {
  const double H = 1e-3, k = 40, q = 3e11, h = 2e4, V = 0.1;
  const fem::Mesh mesh = two_slabs(H, H, 6, /*refine_near_plane=*/true);
  const fem::MirrorSymmetry m = upper_lower_mirror(mesh);
  for (const double sign : {-1.0, 1.0}) {
    const std::vector<std::pair<std::string, double>> fixed{{"upper.top", V}, {"lower.bottom", sign * V}};
    const Field full = solve(mesh, k, sign > 0 ? q : 0.0, h, fixed, {}, sign);
    const Field half = solve(mesh, k, sign > 0 ? q : 0.0, h, fixed, m, sign);
    EXPECT_LT((half.x - full.x).lpNorm<Eigen::Infinity>(), 1e-12 * full.x.lpNorm<Eigen::Infinity>())
        << "sign " << sign;
    EXPECT_LT(2 * half.n_free, full.n_free + 1);
  }
}

// The same body on three cells across its thickness: the plane cuts the middle row of
// cells, each its own mirror, assembled at half weight. The odd field is still exact
// (linear), and the even one at the nodes (1D linear elements on a tensor grid).
TEST(Mirror, CellsThePlaneCutsCountHalfAndKeepBothClosedForms) {
  const double H = 1e-3, k = 40, q = 3e11, V = 0.1;
  const fem::Mesh mesh = slab("middle", -H, H, 4, 3);
  const fem::MirrorSymmetry m = fem::find_mirror_symmetry(mesh, {0}, 1e-12);
  ASSERT_FALSE(m.empty());
  int cut = 0;
  for (int c = 0; c < mesh.n_cells(); ++c)
    cut += m.weight(std::vector<int>(mesh.cells[c].begin(), mesh.cells[c].end())) == 0.5;
  EXPECT_EQ(cut, 4);
  const Field odd = solve(mesh, k, 0, 0, {{"middle.top", V}, {"middle.bottom", -V}}, m, -1);
  const Field even = solve(mesh, k, q, 0, {{"middle.top", 0.0}, {"middle.bottom", 0.0}}, m, +1);
  const double T_peak = q * H * H / (2 * k);
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const double z = mesh.nodes[n].y();
    EXPECT_NEAR(odd.x[n], V * z / H, 1e-12 * V) << "node " << n;
    EXPECT_NEAR(even.x[n], q * (H * H - z * z) / (2 * k), 1e-10 * T_peak) << "node " << n;
  }
  EXPECT_EQ(even.n_free, 5);  // the row at z = H/3; the one at z = H is fixed
}
