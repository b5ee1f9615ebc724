// The mechanical tangent (B̄ elements with the consistent J2 tangent, penalty contact
// with friction) against central finite differences of the residual, on a coarse
// weld case with plastic points, contact, stick and slip.
#include "fem/quadtree.hpp"
#include "meshes/weld_mesh.hpp"
#include "physics/mechanics.hpp"
#include "physics/problem.hpp"
#include "physics/squeeze.hpp"
#include "materials/material_library.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

using namespace rsw;

namespace {
struct CoarseCase {
  physics::Problem problem = physics::load_problem(std::string(RSW_SOURCE_DIR) + "/validation/paper_case/weld.yaml",
                                                   {"mesh.base_size=0.5 mm", "mesh.weld_zone.levels=1"});
  fem::Mesh mesh = meshes::weld_mesh(problem.geometry, problem.mesh);
  materials::MaterialLibrary library;
  materials::Material copper = library.load("CuCrZr"), steel = library.load("DP1200");
};

double jacobian_error(physics::Mechanics& mech, const Eigen::VectorXd& T, double force, const Eigen::VectorXd& base) {
  Eigen::VectorXd R;
  fem::SparseMatrix K;
  mech.residual_and_tangent(base, force, T, R, K);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  Eigen::VectorXd v(mech.n_free_force_control());
  for (int i = 0; i < v.size(); ++i) v[i] = normal(rng);
  v *= 1e-6 / v.lpNorm<Eigen::Infinity>();  // a 1 µm direction
  const double h = 1e-4;                     // step: 0.1 nm
  const Eigen::VectorXd Kv = K * v;
  Eigen::VectorXd Rp, Rm;
  fem::SparseMatrix dummy;
  mech.residual_and_tangent(base + mech.full_increment(h * v), force, T, Rp, dummy);
  mech.residual_and_tangent(base - mech.full_increment(h * v), force, T, Rm, dummy);
  const Eigen::VectorXd fd = -(Rp - Rm) / (2 * h);
  return (fd - Kv).norm() / Kv.norm();
}

// Two steel blocks touching along z = 0 (radius 2 mm, 0.5 mm high each): "upper" (4
// columns of cells) on "lower" (5 columns), their faces paired as the interface "tie";
// lower.bottom fixed, upper.top loaded, friction 0.3.
fem::Mesh two_blocks() {
  auto block = [](const std::string& name, double z0, double z1, int n_r) {
    fem::Quadtree tree(n_r, 2);
    return tree.build(name, [=](double x, double y) { return fem::Point(1e-3 * x / n_r * 2, z0 + (z1 - z0) * y / 2); },
                      [](double, double, fem::Side s) -> std::string {
                        static const char* n[] = {"bottom", "right", "top", "axis"};
                        return n[static_cast<int>(s)];
                      });
  };
  fem::Mesh mesh = block("upper", 0.0, 0.5e-3, 4);
  mesh.append(block("lower", -0.5e-3, 0.0, 5));
  mesh.interfaces["tie"] = {"upper.bottom", "lower.top", "tie"};
  return mesh;
}

physics::MechanicsSettings two_block_settings() {
  physics::MechanicsSettings s;
  s.fixed_boundary = "lower.bottom";
  s.loaded_boundary = "upper.top";
  s.friction_coefficient = 0.3;
  s.contact_smoothing = 1e-6;  // the lifts below are set against a 1 µm quadratic start
  return s;
}

// The two blocks of steel at 20 °C, and the residual with the upper block (body 0)
// moved up rigidly by `lift` (down if negative) from the committed state.
struct TwoBlockCase {
  fem::Mesh mesh = two_blocks();
  materials::MaterialLibrary library;
  materials::Material steel = library.load("DP1200");
  physics::MechanicsSettings settings = two_block_settings();
  Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);

  physics::Mechanics mechanics() const { return physics::Mechanics(mesh, {&steel, &steel}, settings, 20.0); }
  Eigen::VectorXd lifted(physics::Mechanics& mech, double lift) const {
    Eigen::VectorXd u = mech.full_increment(Eigen::VectorXd::Zero(mech.n_free_force_control()));
    for (int n = 0; n < mesh.n_nodes(); ++n)
      if (mesh.node_body[n] == 0) u[2 * n + 1] = lift;
    u[u.size() - 1] = lift;  // the rigid motion w of the loaded boundary, the one extra dof
    Eigen::VectorXd R;
    fem::SparseMatrix K;
    mech.residual_and_tangent(u, 0.0, T, R, K);
    return R;
  }
};

// The same at the first Newton iterate from the committed state towards `force`.
double jacobian_error_at_first_iterate(physics::Mechanics& mech, const Eigen::VectorXd& T, double force) {
  Eigen::VectorXd R;
  fem::SparseMatrix K;
  const Eigen::VectorXd zero =
      Eigen::VectorXd::Zero(mech.full_increment(Eigen::VectorXd::Zero(mech.n_free_force_control())).size());
  mech.residual_and_tangent(zero, force, T, R, K);
  fem::LinearSolver solver(fem::SolverKind::umfpack);
  return jacobian_error(mech, T, force, mech.full_increment(solver.solve(K, R)));
}
}  // namespace

// With the sheet/sheet contact in one pass and in two (MechanicsSettings::two_pass_interfaces).
TEST(MechanicsJacobian, TangentMatchesFiniteDifferencesWithPlasticityContactAndFriction) {
  CoarseCase c;
  for (bool two_pass : {false, true}) {
    physics::MechanicsSettings s;
    s.friction_coefficient = 0.3;
    if (two_pass) s.two_pass_interfaces = {"ss_1_2"};
    physics::Mechanics mech(c.mesh, {&c.copper, &c.steel, &c.steel, &c.copper}, s, 20.0);
    const Eigen::VectorXd T = Eigen::VectorXd::Constant(c.mesh.n_nodes(), 20.0);
    const auto sq = physics::squeeze(mech, 3000.0, T);
    ASSERT_TRUE(sq.converged) << sq.message;
    // One Newton iterate towards 3.6 kN: plastic loading, contact growth, slip.
    const double err = jacobian_error_at_first_iterate(mech, T, 3600.0);
    std::printf("%s: relative difference between K v and the central difference of R: %.2e\n",
                two_pass ? "two-pass" : "one-pass", err);
    EXPECT_LT(err, 1e-3);
  }
}

TEST(MechanicsJacobian, FrictionlessTangentIsSymmetric) {
  CoarseCase c;
  physics::MechanicsSettings s;
  s.friction_coefficient = 0.0;
  physics::Mechanics mech(c.mesh, {&c.copper, &c.steel, &c.steel, &c.copper}, s, 20.0);
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(c.mesh.n_nodes(), 20.0);
  const auto sq = physics::squeeze(mech, 3000.0, T);
  ASSERT_TRUE(sq.converged) << sq.message;
  Eigen::VectorXd R;
  fem::SparseMatrix K;
  const Eigen::VectorXd zero = mech.full_increment(Eigen::VectorXd::Zero(mech.n_free_force_control()));
  mech.residual_and_tangent(zero, 3000.0, T, R, K);
  const fem::SparseMatrix Kt = K.transpose();
  EXPECT_LT((K - Kt).norm(), 1e-10 * K.norm());
}

// Two stacked blocks whose interface is tied (fused sheets): the tie is linear in the
// displacements, so the tangent must match finite differences to round-off.
TEST(MechanicsJacobian, TiedInterfaceTangentMatchesFiniteDifferences) {
  const fem::Mesh mesh = two_blocks();
  materials::MaterialLibrary library;
  const auto steel = library.load("DP1200");
  const physics::MechanicsSettings s = two_block_settings();
  physics::Mechanics mech(mesh, {&steel, &steel}, s, 20.0);
  std::vector<std::vector<char>> all(1, std::vector<char>(mech.pairings()[0].points().size(), 1));
  mech.set_bonded(all);
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 1600.0);  // molten
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  Eigen::VectorXd y(mech.n_free_force_control()), v(mech.n_free_force_control());
  for (int i = 0; i < y.size(); ++i) {
    y[i] = 1e-6 * normal(rng);
    v[i] = 1e-6 * normal(rng);
  }
  const Eigen::VectorXd base = mech.full_increment(y);
  Eigen::VectorXd R, Rp, Rm;
  fem::SparseMatrix K, dummy;
  mech.residual_and_tangent(base, 100.0, T, R, K);
  const double h = 1e-4;
  mech.residual_and_tangent(base + mech.full_increment(h * v), 100.0, T, Rp, dummy);
  mech.residual_and_tangent(base - mech.full_increment(h * v), 100.0, T, Rm, dummy);
  const Eigen::VectorXd fd = -(Rp - Rm) / (2 * h), Kv = K * v;
  const double err = (fd - Kv).norm() / Kv.norm();
  std::printf("tied interface: relative difference %.2e\n", err);
  EXPECT_LT(err, 1e-6);
}

// A bonded point resists opening with the contact's own law mirrored, and leaves
// compression to the contact (physics/mechanics.cpp, Tie): two stress-free blocks that
// touch along z = 0, the upper one moved rigidly by ±0.4 µm (within the 1 µm smoothing of
// the penalty law). Pressed in, the bonded interface pushes back exactly as the unbonded
// contact does; pulled apart by the same distance, it pulls back with the same forces,
// opposite in sign, where the unbonded interface carries nothing. A tie that also
// resisted compression from the state it formed in would hold sheets bonded while a
// few micrometres apart apart like a strut.
TEST(MechanicsContact, BondedPointsResistOpeningAsTheContactResistsPenetration) {
  const TwoBlockCase c;
  ASSERT_EQ(c.mesh.body_names[0], "upper");
  auto residual = [&](bool bonded, double lift) {
    physics::Mechanics mech = c.mechanics();
    if (bonded) mech.set_bonded({std::vector<char>(mech.pairings()[0].points().size(), 1)});
    return c.lifted(mech, lift);
  };
  const double d = 0.4e-6;
  const Eigen::VectorXd pressed = residual(false, -d);
  ASSERT_GT(pressed.norm(), 0.0);
  EXPECT_LT((residual(true, -d) - pressed).norm(), 1e-12 * pressed.norm());
  EXPECT_LT(residual(false, d).norm(), 1e-12 * pressed.norm());
  EXPECT_LT((residual(true, d) + pressed).norm(), 1e-9 * pressed.norm());
}

// The bonding degree β is the bonded share of a point's area, and each share bonds at
// rest where it is: a bond formed with β = 0.01 while the blocks part by d1, and then
// completed (β = 1) before they part by d2 more, pulls like a whole bond parted by
// 0.01 d1 + d2, not by d1 + d2. (The earlier law let the grown share act on the whole
// offset since the bond first formed; in the paper-mesh weld a degree rising from
// 10⁻⁵ to 1 in one step turned micrometres of slip into a 19 kN nodal force.)
TEST(MechanicsContact, AGrowingBondCarriesOnlyTheMotionSinceEachShareBonded) {
  const TwoBlockCase c;
  ASSERT_EQ(c.mesh.body_names[0], "upper");
  auto degree = [](const physics::Mechanics& mech, double beta) {
    return std::vector<std::vector<double>>{std::vector<double>(mech.pairings()[0].points().size(), beta)};
  };
  const double d1 = 0.4e-6, d2 = 0.3e-6, beta0 = 0.01;
  physics::Mechanics growing = c.mechanics();
  growing.set_bonding_degree(degree(growing, beta0));
  c.lifted(growing, d1);
  growing.commit();
  growing.set_bonding_degree(degree(growing, 1.0));
  const Eigen::VectorXd R_growing = c.lifted(growing, d2);
  auto whole_bond = [&](double lift) {
    physics::Mechanics mech = c.mechanics();
    mech.set_bonding_degree(degree(mech, 1.0));
    return c.lifted(mech, lift);
  };
  const Eigen::VectorXd expected = whole_bond(beta0 * d1 + d2), earlier_law = whole_bond(d1 + d2);
  ASSERT_GT(expected.norm(), 0.0);
  EXPECT_LT((R_growing - expected).norm(), 1e-9 * expected.norm());
  EXPECT_GT((R_growing - earlier_law).norm(), 0.5 * earlier_law.norm());
}

// Sheets that start to bond (bonding degree β on the sheet/sheet points) after the
// squeeze: the tie is formed at rest in the normal direction and with the friction
// traction of that moment, so the residual of the squeezed state does not depend on β
// (the traction is continuous as a point bonds), while the tangent of a partly bonded
// interface (the contact whole, the share β tied, 1 − β friction) matches finite
// differences like the contact's.
TEST(MechanicsJacobian, PartlyBondedPointsKeepTheirTractionAndAConsistentTangent) {
  CoarseCase c;
  for (bool two_pass : {false, true}) {
  physics::MechanicsSettings s;
  s.friction_coefficient = 0.3;
  s.contact_smoothing = 1e-6;  // a squeeze converged as tightly as the bound below needs
  if (two_pass) s.two_pass_interfaces = {"ss_1_2"};  // the mirrored pass bonds with the first
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(c.mesh.n_nodes(), 20.0);
  std::vector<Eigen::VectorXd> residuals;
  for (double beta : {0.0, 0.3, 1.0}) {
    physics::Mechanics mech(c.mesh, {&c.copper, &c.steel, &c.steel, &c.copper}, s, 20.0);
    const auto sq = physics::squeeze(mech, 3000.0, T);
    ASSERT_TRUE(sq.converged) << sq.message;
    std::vector<std::vector<double>> degree;
    int n_pressed = 0;
    for (std::size_t p = 0; p < mech.pairings().size(); ++p) {
      const bool sheet_sheet = mech.pairings()[p].name().rfind("ss_", 0) == 0;
      degree.emplace_back(mech.pairings()[p].points().size(), sheet_sheet ? beta : 0.0);
      if (sheet_sheet)
        for (double pressure : mech.contact_pressure(static_cast<int>(p))) n_pressed += pressure > 1e6;
    }
    ASSERT_GT(n_pressed, 3);
    mech.set_bonding_degree(degree);
    Eigen::VectorXd R;
    fem::SparseMatrix K;
    const Eigen::VectorXd zero =
        Eigen::VectorXd::Zero(mech.full_increment(Eigen::VectorXd::Zero(mech.n_free_force_control())).size());
    mech.residual_and_tangent(zero, 3000.0, T, R, K);
    residuals.push_back(R);
    if (beta == 0.3) {
      const double err = jacobian_error_at_first_iterate(mech, T, 3600.0);
      std::printf("%s, partly bonded (beta 0.3): relative difference %.2e\n", two_pass ? "two-pass" : "one-pass",
                  err);
      EXPECT_LT(err, 1e-3);
    }
  }
  // The squeeze converged to 1e-7 of the load (3e-4 N); bonding must not add to that.
  for (std::size_t k = 1; k < residuals.size(); ++k)
    EXPECT_LT((residuals[k] - residuals[0]).lpNorm<Eigen::Infinity>(), 1e-6) << k;
  }
}

// The stack of the coarse default case is symmetric about its mid-plane (equal sheets,
// equal electrodes): mirrored there, the squeezed state must map onto itself, with the
// mid-plane moved by half the electrode travel w: u_r(r, z) = u_r(r, −z) and
// u_z(r, z) + u_z(r, −z) = w for every sheet node. The one-pass S/S contact breaks the
// symmetry (its slave and master sides are treated differently); the two-pass one keeps
// it to what the Newton tolerance and the seating path leave.
TEST(MechanicsContact, TwoPassSheetContactSqueezesASymmetricStackSymmetrically) {
  CoarseCase c;
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(c.mesh.n_nodes(), 20.0);
  const int sheet_1 = c.mesh.body_index("sheet_1"), sheet_2 = c.mesh.body_index("sheet_2");
  // Mid-plane of the stack and the mirror partner of every sheet_1 node.
  double z_top = -1e300, z_bottom = 1e300;
  for (int n = 0; n < c.mesh.n_nodes(); ++n)
    if (c.mesh.node_body[n] == sheet_1) z_top = std::max(z_top, c.mesh.nodes[n].y());
    else if (c.mesh.node_body[n] == sheet_2) z_bottom = std::min(z_bottom, c.mesh.nodes[n].y());
  const double z_mid = 0.5 * (z_top + z_bottom);
  std::vector<std::pair<int, int>> mirror;
  for (int a = 0; a < c.mesh.n_nodes(); ++a) {
    if (c.mesh.node_body[a] != sheet_1) continue;
    for (int b = 0; b < c.mesh.n_nodes(); ++b)
      if (c.mesh.node_body[b] == sheet_2 && std::abs(c.mesh.nodes[b].x() - c.mesh.nodes[a].x()) < 1e-12 &&
          std::abs((c.mesh.nodes[b].y() - z_mid) + (c.mesh.nodes[a].y() - z_mid)) < 1e-12)
        mirror.emplace_back(a, b);
  }
  ASSERT_GT(mirror.size(), 100u);
  double asymmetry[2];
  for (int two_pass = 0; two_pass < 2; ++two_pass) {
    physics::MechanicsSettings s;
    s.friction_coefficient = 0.3;
    s.contact_smoothing = 1e-6;  // the figures below were measured with a 1 µm quadratic start
    if (two_pass) s.two_pass_interfaces = {"ss_1_2"};
    physics::Mechanics mech(c.mesh, {&c.copper, &c.steel, &c.steel, &c.copper}, s, 20.0);
    const auto sq = physics::squeeze(mech, 3000.0, T);
    ASSERT_TRUE(sq.converged) << sq.message;
    const Eigen::VectorXd u = mech.displacement();
    const double w = mech.end_face_displacement();
    double worst = 0, scale = 0;
    for (const auto& [a, b] : mirror) {
      worst = std::max({worst, std::abs(u[2 * a] - u[2 * b]), std::abs(u[2 * a + 1] + u[2 * b + 1] - w)});
      scale = std::max({scale, std::abs(u[2 * a]), std::abs(u[2 * a + 1] - 0.5 * w)});
    }
    asymmetry[two_pass] = worst;
    std::printf("%s: largest departure from mirror symmetry %.3e m (displacements relative to the mid-plane up "
                "to %.3e m, electrode travel %.3e m)\n",
                two_pass ? "two-pass" : "one-pass", worst, scale, w);
  }
  EXPECT_LT(asymmetry[1], 1e-11);  // measured 4·10⁻¹³ m
  EXPECT_LT(asymmetry[1], 0.1 * asymmetry[0]);  // one pass: 1.2·10⁻¹⁰ m
}
