// Mechanics against closed forms: free thermal expansion, the Lamé thick cylinder,
// Hertz contact of the R30 dome on a flat; and the plastic squeeze of the default
// weld case (force balance on every interface, contact radius beyond Hertz).
#include "mechanics_fixtures.hpp"
#include "fem/mirror.hpp"
#include "meshes/weld_mesh.hpp"
#include "physics/mechanics.hpp"
#include "physics/problem.hpp"
#include "physics/squeeze.hpp"

#include <Eigen/QR>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

using namespace rsw;

namespace {
// One force-free step of a block heated uniformly by dT from 20 °C: the bottom held in
// z, the top kept plane (the loaded end face, force 0), no radial clamping; committed.
std::unique_ptr<physics::Mechanics> heated_block(const fem::Mesh& mesh, const std::string& body,
                                                 const materials::Material& mat, double dT) {
  physics::MechanicsSettings s;
  s.fixed_boundary = body + ".bottom";
  s.loaded_boundary = body + ".top";
  s.clamp_radially = false;
  s.friction_coefficient = 0;
  auto mech = std::make_unique<physics::Mechanics>(mesh, std::vector<const materials::Material*>{&mat}, s, 20.0);
  const auto report = mech->solve_force_step(0.0, Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0 + dT));
  EXPECT_TRUE(report.converged) << report.message;
  mech->commit();
  return mech;
}

// The default case on the coarse mesh (0.5 mm base, one refinement level): its config,
// mesh and the electrode and sheet materials.
struct CoarseStack {
  physics::Problem problem;
  fem::Mesh mesh;
  materials::Material copper, steel;
};
CoarseStack coarse_default_stack() {
  physics::Problem problem = physics::load_problem(std::string(RSW_SOURCE_DIR) + "/validation/paper_case/weld.yaml");
  problem.mesh.base_size = 0.5e-3;
  problem.mesh.weld_zone_levels = 1;
  fem::Mesh mesh = meshes::weld_mesh(problem.geometry, problem.mesh);
  materials::MaterialLibrary library;
  return {std::move(problem), std::move(mesh), library.load("CuCrZr"), library.load("DP1200")};
}

// The squeeze of the coarse stack at the case's force, then three committed 1 ms steps
// heated by a Gaussian of 300 K per step about the centre (radius `width`); the Newton
// iterations of all of them.
int squeeze_and_heat(physics::Mechanics& mech, const CoarseStack& stack, double width) {
  const fem::Mesh& mesh = stack.mesh;
  const double F = stack.problem.schedule.force.at(0.0);
  int iterations = 0;
  const auto squeezed = physics::squeeze(mech, F, Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0));
  EXPECT_TRUE(squeezed.converged) << squeezed.message;
  for (const auto& st : squeezed.steps) iterations += st.iterations;
  mech.set_time_step(1e-3);
  for (int k = 1; k <= 3; ++k) {
    Eigen::VectorXd T(mesh.n_nodes());
    for (int n = 0; n < mesh.n_nodes(); ++n)
      T[n] = 20.0 + 300.0 * k * std::exp(-mesh.nodes[n].squaredNorm() / (width * width));
    const auto report = mech.solve_force_step(F, T);
    EXPECT_TRUE(report.converged) << report.message;
    iterations += report.iterations;
    mech.commit();
  }
  return iterations;
}
}  // namespace

// A disc with a hanging-node corner heated uniformly by 100 K expands freely:
// u = ε_th x with ε_th = α ΔT, and the stress vanishes.
TEST(MechanicsVerification, FreeThermalExpansionIsStressFreeOnHangingNodeMesh) {
  const double alpha = 12e-6, dT = 100.0;
  const auto mat = test::elastic_material("steel", 210e9, 0.3, alpha);
  const fem::Mesh mesh = test::block_mesh("disc", 0, 2e-3, 0, 1e-3, 0.25e-3, 2,
                                          [](const fem::IndexBox& b) { return b.x0 < 2 && b.y0 < 2; });
  ASSERT_GT(mesh.hanging_nodes.size(), 0u);
  const auto mech = heated_block(mesh, "disc", mat, dT);
  const double eps = alpha * dT;
  const Eigen::VectorXd u = mech->displacement();
  double worst_u = 0, worst_s = 0;
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    worst_u = std::max(worst_u, std::abs(u[2 * n] - eps * mesh.nodes[n].x()));
    worst_u = std::max(worst_u, std::abs(u[2 * n + 1] - eps * mesh.nodes[n].y()));
  }
  for (const auto& p : mech->point_stresses()) worst_s = std::max(worst_s, p.stress.lpNorm<Eigen::Infinity>());
  std::printf("free expansion: eps_th = %.3e, max |u - eps x| = %.2e m, max |sigma| = %.2e Pa (E eps = %.2e Pa)\n", eps,
              worst_u, worst_s, 210e9 * eps);
  EXPECT_LT(worst_u, 1e-9 * eps * 2e-3 + 1e-15);
  EXPECT_LT(worst_s, 1e-6 * 210e9 * eps);
}

// Ring r in [1, 2] mm under 100 MPa internal pressure, free ends (generalised plane
// strain): σ_r = A - B/r², σ_θ = A + B/r², A = p r_i²/(r_o² - r_i²) = 33.33 MPa,
// B = A r_o² = 133.33 MPa mm². Compared per cell: the mean of the cell's Gauss-point
// stresses against the closed form at the mean Gauss-point radius (B̄ averages the
// volumetric strain over the cell, so single Gauss points carry an O(h) error where
// σ_r is steep).
TEST(MechanicsVerification, LameThickCylinderStressesWithinOnePercent) {
  const double ri = 1e-3, ro = 2e-3, p = 100e6;
  const auto mat = test::elastic_material("steel", 210e9, 0.3, 12e-6);
  const fem::Mesh mesh = test::block_mesh("ring", ri, ro, 0, 0.125e-3, 1.0e-3 / 32);
  physics::MechanicsSettings s;
  s.fixed_boundary = "ring.bottom";
  s.loaded_boundary = "ring.top";
  s.clamp_radially = false;
  s.friction_coefficient = 0;
  s.pressure_loads = {{"ring.left", p}};
  physics::Mechanics mech(mesh, {&mat}, s, 20.0);
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);
  const auto report = mech.solve_force_step(0.0, T);
  ASSERT_TRUE(report.converged) << report.message;
  mech.commit();
  const double A = p * ri * ri / (ro * ro - ri * ri), B = A * ro * ro;
  const auto points = mech.point_stresses();
  double worst = 0;
  for (std::size_t c = 0; c < points.size(); c += 4) {
    double r = 0, s_r = 0, s_t = 0;
    for (std::size_t q = c; q < c + 4; ++q) {
      r += points[q].position.x() / 4;
      s_r += points[q].stress[0] / 4;
      s_t += points[q].stress[2] / 4;
    }
    worst = std::max({worst, std::abs(s_r - (A - B / (r * r))) / (B / (r * r)),
                      std::abs(s_t - (A + B / (r * r))) / (A + B / (r * r))});
  }
  std::printf("Lame cylinder: A = %.3f MPa, B = %.3f MPa mm^2, %d cells across the wall, worst relative error "
              "%.3f %%\n", A / 1e6, B / 1e6 * 1e6, 32, 100 * worst);
  EXPECT_LT(worst, 0.01);
}

// A heated core held radially grows axially by its whole volumetric expansion once it
// yields: the mechanism behind most of a weld's electrode displacement S (a molten
// core inside cold, strong sheet metal). Ring r in [1, 2] mm, z in [0, 1] mm, u_r = 0
// on both radial faces (both named "<body>.axis"), bottom fixed in z, top free
// (force 0), heated uniformly by ΔT, perfectly plastic (σ_y) with constant E, ν, α.
// The state is uniform: ε_rr = ε_θθ = 0, σ_zz = 0, σ_rr = σ_θθ = s, and
//   elastic:           s = −E α ΔT / (1 − ν),          ε_zz = α ΔT (1 + ν)/(1 − ν);
//   yielded (|s| ≥ σ_y): s = −σ_y, plastic flow is isochoric, so tr ε = tr σ/(3K) + 3αΔT:
//                      ε_zz = 3 α ΔT − 2 σ_y / (3K),   K = E / (3 (1 − 2ν)).
// E = 210 GPa, ν = 0.3, α = 12e-6 /K, ΔT = 500 K, σ_y = 50 MPa: free expansion
// α ΔT = 6.0e-3, elastic confinement 1.114e-2, yielded 1.781e-2 (three times the free
// value, less 1.9e-4 of elastic compression).
TEST(MechanicsVerification, ConfinedHeatedCoreGrowsAxiallyByItsVolumetricExpansion) {
  const double E = 210e9, nu = 0.3, alpha = 12e-6, dT = 500.0, sigma_y = 50e6, H = 1e-3;
  materials::MaterialData d = test::elastic_material("soft_core", E, nu, alpha).data();
  d.flow_curves = materials::FlowCurveTable({{20.0, {0.0, 1.0}, {sigma_y, sigma_y}}});
  const materials::Material mat(d);
  fem::Quadtree tree(8, 8);
  const fem::Mesh mesh = tree.build(
      "core", [](double x, double y) { return fem::Point(1e-3 + 1e-3 * x / 8, 1e-3 * y / 8); },
      [](double, double, fem::Side s) -> std::string {
        return s == fem::Side::bottom ? "bottom" : s == fem::Side::top ? "top" : "axis";
      });
  const auto mech = heated_block(mesh, "core", mat, dT);

  const double K = E / (3 * (1 - 2 * nu));
  const double eps_free = alpha * dT, eps_elastic = alpha * dT * (1 + nu) / (1 - nu);
  const double eps_yielded = 3 * alpha * dT - 2 * sigma_y / (3 * K);
  const double eps_fe = mech->end_face_displacement() / H;
  double worst_s = 0;
  for (const auto& p : mech->point_stresses())
    worst_s = std::max({worst_s, std::abs(p.stress[0] + sigma_y), std::abs(p.stress[2] + sigma_y),
                        std::abs(p.stress[1])});
  std::printf("confined heated core: axial strain %.6e (closed form %.6e; free %.3e, elastic confinement %.3e), "
              "worst stress error %.2e Pa\n",
              eps_fe, eps_yielded, eps_free, eps_elastic, worst_s);
  EXPECT_NEAR(eps_fe, eps_yielded, 1e-9 * eps_yielded);
  EXPECT_LT(worst_s, 1e-6 * sigma_y);
}

// Hertz: the R30 CuCrZr dome (E = 128 GPa) pressed on steel (E = 210 GPa), ν = 0.3,
// both elastic, frictionless: E* = 87.4 GPa, and at 3 kN
//   a = (3FR/(4E*))^(1/3) = 0.918 mm, p0 = 3F/(2πa²) = 1.70 GPa, δ = a²/R = 28.1 µm.
// Thick sheets (2 x 4 mm) approximate the half-space. The approach of the distant
// points is δ_total(F) = c F + 2 K F^(2/3) (bulk compliance plus the two Hertz
// contacts, upper and lower); c and K are fitted to four loads and δ = K F^(2/3).
// Hertz's surfaces are smooth: the penalty law's quadratic start is 1 µm here. The
// default 30 µm adds the compliance of rough surfaces (solver.contact_smoothing):
// measured a = 1.001 mm, p0 = 1.625 GPa, δ = 32.5 µm, a contact wider and flatter, as
// roughness makes a Hertz contact (Johnson, Contact Mechanics, 1985, ch. 13).
TEST(MechanicsVerification, HertzDomeOnFlatMatchesClosedForm) {
  const double E1 = 128e9, E2 = 210e9, nu = 0.3, R = 30e-3, F = 3000.0;
  const double E_star = 1.0 / ((1 - nu * nu) / E1 + (1 - nu * nu) / E2);
  const double a = std::cbrt(3 * F * R / (4 * E_star)), p0 = 3 * F / (2 * M_PI * a * a), delta = a * a / R;
  const auto copper = test::elastic_material("copper", E1, nu, 17e-6);
  const auto steel = test::elastic_material("steel", E2, nu, 12e-6);

  meshes::StackGeometry stack;
  stack.sheets = {{"sheet_1", "steel", 4e-3}, {"sheet_2", "steel", 4e-3}};
  meshes::MeshSettings ms;
  ms.weld_zone_levels = 0;
  ms.extra_boxes = {{0, 2e-3, 3e-3, 5e-3, 2}, {0, 2e-3, -5e-3, -3e-3, 2}};
  const fem::Mesh mesh = meshes::weld_mesh(stack, ms);
  physics::MechanicsSettings s;
  s.friction_coefficient = 0;
  s.contact_smoothing = 1e-6;
  physics::Mechanics mech(mesh, {&copper, &steel, &steel, &copper}, s, 20.0);
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);

  const auto seated = physics::squeeze(mech, 750.0, T, {1e-6, 0.2, 400, 2});
  ASSERT_TRUE(seated.converged) << seated.message;
  std::vector<double> loads{mech.electrode_force()}, approach{-mech.end_face_displacement()};
  for (double f : {1500.0, 2250.0, 3000.0}) {
    const auto ramp = physics::ramp_force(mech, f, 1, T);
    ASSERT_TRUE(ramp.converged) << ramp.message;
    loads.push_back(f);
    approach.push_back(-mech.end_face_displacement());
  }
  // Least squares for δ_total = c F + 2 K F^(2/3).
  Eigen::MatrixXd M(loads.size(), 2);
  Eigen::VectorXd y(loads.size());
  for (std::size_t i = 0; i < loads.size(); ++i) {
    M(i, 0) = loads[i];
    M(i, 1) = 2 * std::pow(loads[i], 2.0 / 3.0);
    y[i] = approach[i];
  }
  const Eigen::Vector2d fit = M.colPivHouseholderQr().solve(y);
  const double delta_fe = fit[1] * std::pow(F, 2.0 / 3.0);

  double a_fe = 0, p_fe = 0;
  for (const auto& st : mech.interface_states())
    if (st.name == "es_upper") {
      a_fe = st.contact_radius;
      for (double p : st.pressure) p_fe = std::max(p_fe, p);
    }
  std::printf("Hertz at 3 kN: a = %.4f mm (closed form %.4f), p0 = %.3f GPa (%.3f), delta = %.2f um (%.2f); "
              "fit residual %.2e m\n",
              a_fe * 1e3, a * 1e3, p_fe / 1e9, p0 / 1e9, delta_fe * 1e6, delta * 1e6, (M * fit - y).norm());
  EXPECT_NEAR(a_fe, a, 0.05 * a);
  EXPECT_NEAR(p_fe, p0, 0.05 * p0);
  EXPECT_NEAR(delta_fe, delta, 0.05 * delta);
}

// The plastic squeeze of the default case (paper: 2 x 1 mm DP1200, CuCrZr R30, 3 kN,
// friction 0.3): every contact surface transmits the electrode force, and plastic
// indentation makes the E/S contact wider than the elastic Hertz radius 0.918 mm.
TEST(MechanicsVerification, PlasticSqueezeOfDefaultCaseBalancesForceOnEveryInterface) {
  const physics::Problem problem = physics::load_problem(std::string(RSW_SOURCE_DIR) + "/validation/paper_case/weld.yaml");
  const fem::Mesh mesh = meshes::weld_mesh(problem.geometry, problem.mesh);
  materials::MaterialLibrary library;
  const auto copper = library.load("CuCrZr");
  const auto steel = library.load("DP1200");
  physics::MechanicsSettings s;
  s.friction_coefficient = problem.contact.friction_coefficient;
  physics::Mechanics mech(mesh, {&copper, &steel, &steel, &copper}, s, 20.0);
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);
  const double F = problem.schedule.force.at(0.0);
  const auto result = physics::squeeze(mech, F, T);
  ASSERT_TRUE(result.converged) << result.message;
  int n_iter = 0;
  for (const auto& st : result.steps) n_iter += st.iterations;
  std::printf("squeeze: %zu steps, %d Newton iterations, electrode displacement %.2f um\n", result.steps.size(), n_iter,
              mech.end_face_displacement() * 1e6);
  for (const auto& st : mech.interface_states()) {
    double p_max = 0;
    for (double p : st.pressure) p_max = std::max(p_max, p);
    std::printf("  %-9s contact radius %.4f mm, peak pressure %.3f GPa, integral of sigma_n %.2f N (%.3f %% off)\n",
                st.name.c_str(), st.contact_radius * 1e3, p_max / 1e9, st.normal_force,
                100 * (st.normal_force - F) / F);
    EXPECT_NEAR(st.normal_force, F, 0.005 * F) << st.name;
    if (st.name != "ss_1_2") {
      EXPECT_GT(st.contact_radius, 0.918e-3) << st.name;
    }
  }
  // Indentation: the sheet surface on the axis moved down relative to the sheet's
  // free surface at r = 6 mm.
  const Eigen::VectorXd u = mech.displacement();
  double u_axis = 0, u_out = 0;
  for (int n : mesh.boundary_nodes("sheet_1.top")) {
    if (mesh.nodes[n].x() == 0) u_axis = u[2 * n + 1];
    if (std::abs(mesh.nodes[n].x() - 6e-3) < 1e-9) u_out = u[2 * n + 1];
  }
  std::printf("  indentation of sheet_1 (axis vs r = 6 mm): %.2f um\n", (u_out - u_axis) * 1e6);
  EXPECT_GT(u_out - u_axis, 0.0);
}

// The squeeze of the default case on a coarse mesh solved on its upper half
// (fem/mirror.hpp) is the whole stack's: the electrode travel, and on every interface,
// the lower electrode's included, the pressure and the friction shear at each point
// (Newton ends within 10⁻⁶ of the force: 10⁻⁴ of the peak pressure covers both solves).
// The lower electrode's friction history is kept by its contact kernel, evaluated but
// not assembled.
TEST(MechanicsVerification, SqueezeOnTheUpperHalfGivesTheWholeStacksContactsBelowThePlaneToo) {
  physics::Problem problem = physics::load_problem(std::string(RSW_SOURCE_DIR) + "/validation/paper_case/weld.yaml");
  problem.mesh.base_size = 0.5e-3;
  problem.mesh.weld_zone_levels = 1;
  const fem::Mesh mesh = meshes::weld_mesh(problem.geometry, problem.mesh);
  materials::MaterialLibrary library;
  const auto copper = library.load("CuCrZr");
  const auto steel = library.load("DP1200");
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);
  const double F = problem.schedule.force.at(0.0);
  auto squeezed = [&](const fem::MirrorSymmetry& mirror) {
    physics::MechanicsSettings s;
    s.friction_coefficient = problem.contact.friction_coefficient;
    s.two_pass_interfaces = {"ss_1_2"};
    s.mirror = mirror;
    auto mech = std::make_unique<physics::Mechanics>(mesh, std::vector<const materials::Material*>{&copper, &steel, &steel, &copper}, s, 20.0);
    const auto result = physics::squeeze(*mech, F, T);
    EXPECT_TRUE(result.converged) << result.message;
    return mech;
  };
  const fem::MirrorSymmetry mirror =
      fem::find_mirror_symmetry(mesh, meshes::mirror_bodies(problem.geometry, mesh), 1e-9);
  ASSERT_FALSE(mirror.empty());
  const auto whole = squeezed({});
  const auto half = squeezed(mirror);
  EXPECT_NEAR(half->end_face_displacement(), whole->end_face_displacement(), 1e-5 * std::abs(whole->end_face_displacement()));
  const auto a = whole->interface_states(), b = half->interface_states();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    double p_max = 0, shear_max = 0;
    for (double p : a[i].pressure) p_max = std::max(p_max, p);
    for (double t : a[i].shear) shear_max = std::max(shear_max, std::abs(t));
    ASSERT_EQ(a[i].pressure.size(), b[i].pressure.size()) << a[i].name;
    if (a[i].name != "ss_1_2") {  // between equal sheets friction has next to nothing to carry
      EXPECT_GT(shear_max, 1e-2 * p_max) << a[i].name << ": friction carries shear";
    }
    for (std::size_t k = 0; k < a[i].pressure.size(); ++k) {
      EXPECT_NEAR(b[i].pressure[k], a[i].pressure[k], 1e-4 * p_max) << a[i].name << " point " << k;
      EXPECT_NEAR(b[i].shear[k], a[i].shear[k], 1e-4 * p_max) << a[i].name << " point " << k;
    }
  }
}

// Newton stops on its error estimate (|Δu_k|²/|Δu_k−1| below 10⁻¹⁰ m once two full
// steps contract superlinearly) instead of iterating to the residual tolerance: the
// plastic squeeze of the default case on a coarse mesh ends where the fully converged
// one does, to within that tolerance, in fewer iterations.
TEST(MechanicsVerification, ErrorEstimateStopsNewtonWithinItsToleranceOfTheConvergedState) {
  const CoarseStack stack = coarse_default_stack();
  const physics::Problem& problem = stack.problem;
  const fem::Mesh& mesh = stack.mesh;
  const materials::Material &copper = stack.copper, &steel = stack.steel;
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);
  auto squeezed = [&](double estimate_tolerance, int& iterations) {
    physics::MechanicsSettings s;
    s.friction_coefficient = problem.contact.friction_coefficient;
    s.mechanics_error_estimate = estimate_tolerance;
    // With the default 30 µm quadratic start the squeeze's Newton converges quadratically
    // to the tolerance in 65 iterations either way; 1 µm leaves the slow final
    // iterations that the estimate cuts short.
    s.contact_smoothing = 1e-6;
    physics::Mechanics mech(mesh, {&copper, &steel, &steel, &copper}, s, 20.0);
    const auto result = physics::squeeze(mech, problem.schedule.force.at(0.0), T);
    EXPECT_TRUE(result.converged) << result.message;
    iterations = 0;
    for (const auto& st : result.steps) iterations += st.iterations;
    return mech.displacement();
  };
  int n_tight = 0, n_estimate = 0;
  const Eigen::VectorXd tight = squeezed(0.0, n_tight);
  const Eigen::VectorXd estimated = squeezed(1e-10, n_estimate);
  const double difference = (estimated - tight).lpNorm<Eigen::Infinity>();
  std::printf("squeeze, coarse mesh: %d Newton iterations to the residual tolerance, %d with the error estimate; "
              "largest displacement difference %.2e m\n",
              n_tight, n_estimate, difference);
  EXPECT_LT(n_estimate, n_tight);
  EXPECT_LT(difference, 1e-9);
}

// Elastic cells that provably stay elastic take their force and tangent from the
// linear update f(Δu*) − K_e (Δu − Δu*) instead of their Gauss points
// (MechanicsSettings::linear_elastic_updates). The squeeze of the default case on a
// coarse mesh and three heated steps at constant force (a hot spot at the sheet/sheet
// interface, 300 K more per step: the sheets yield around it, the electrodes stay
// elastic) end in the same displacements and Gauss-point stresses with and without
// it, to round-off, in the same Newton iterations.
TEST(MechanicsVerification, LinearUpdatesOfElasticCellsGiveTheGaussPointSolution) {
  const CoarseStack stack = coarse_default_stack();
  const physics::Problem& problem = stack.problem;
  const fem::Mesh& mesh = stack.mesh;
  const materials::Material &copper = stack.copper, &steel = stack.steel;
  struct Outcome {
    Eigen::VectorXd u;
    std::vector<physics::PointStress> stresses;
    int iterations = 0;
    long linear = 0;
    double plastic_strain = 0;  // largest cell average
  };
  auto run = [&](bool linear) {
    physics::MechanicsSettings s;
    s.friction_coefficient = problem.contact.friction_coefficient;
    s.linear_elastic_updates = linear;
    physics::Mechanics mech(mesh, {&copper, &steel, &steel, &copper}, s, 20.0);
    Outcome out;
    out.iterations = squeeze_and_heat(mech, stack, 1.5e-3);
    out.u = mech.displacement();
    out.stresses = mech.point_stresses();
    out.linear = mech.linear_cell_updates();
    for (double p : mech.equivalent_plastic_strain()) out.plastic_strain = std::max(out.plastic_strain, p);
    return out;
  };
  const Outcome gauss = run(false), linear = run(true);
  double du = (linear.u - gauss.u).lpNorm<Eigen::Infinity>(), ds = 0, smax = 0;
  for (std::size_t i = 0; i < gauss.stresses.size(); ++i) {
    ds = std::max(ds, (linear.stresses[i].stress - gauss.stresses[i].stress).lpNorm<Eigen::Infinity>());
    smax = std::max(smax, gauss.stresses[i].stress.lpNorm<Eigen::Infinity>());
  }
  std::printf("linear updates of elastic cells: %ld cell evaluations (of %d cells), Newton iterations %d / %d, "
              "largest plastic strain %.3f; largest difference %.2e m of %.2e m, %.2e Pa of %.2e Pa\n",
              linear.linear, mesh.n_cells(), linear.iterations, gauss.iterations, gauss.plastic_strain, du,
              gauss.u.lpNorm<Eigen::Infinity>(), ds, smax);
  EXPECT_GT(gauss.plastic_strain, 1e-3);
  EXPECT_EQ(gauss.linear, 0);
  EXPECT_GT(linear.linear, 10L * mesh.n_cells());
  EXPECT_EQ(linear.iterations, gauss.iterations);
  EXPECT_LT(du, 1e-9 * gauss.u.lpNorm<Eigen::Infinity>());
  EXPECT_LT(ds, 1e-6 * smax);
}

// The electrodes' interiors eliminated before GMRES (fem::InteriorElimination): the
// squeeze and three heated steps of the coarse default case give the whole system's
// solution within Newton's own tolerance (a step stops once its estimated remaining
// error is below solver.mechanics_error_estimate, 1 nm), with the interior condensed
// once per step and reused in between. The two Newton paths differ by the linear
// solves' rounding and tolerance: on the coarse mesh every step takes the same
// iterations but the last heated one (900 K, wide plastic flow), where the line search
// crosses kinks and rounding picks the step length (17 against 26 iterations there,
// 95 against 104 in all); the bound only asks that Newton not fail on the reduced
// system: at most half as many more or fewer iterations.
TEST(MechanicsVerification, EliminatedElectrodeInteriorsGiveTheWholeSystemsSolution) {
  const CoarseStack stack = coarse_default_stack();
  const physics::Problem& problem = stack.problem;
  const fem::Mesh& mesh = stack.mesh;
  struct Outcome {
    Eigen::VectorXd u;
    std::vector<physics::PointStress> stresses;
    int iterations = 0;
    physics::MechanicsSolverCounts counts;
  };
  auto run = [&](double distance) {
    physics::MechanicsSettings s;
    s.friction_coefficient = problem.contact.friction_coefficient;
    s.interior_elimination_distance = distance;
    physics::Mechanics mech(mesh, {&stack.copper, &stack.steel, &stack.steel, &stack.copper}, s, 20.0);
    Outcome out;
    out.iterations = squeeze_and_heat(mech, stack, 3e-3);
    out.u = mech.displacement();
    out.stresses = mech.point_stresses();
    out.counts = mech.solver_counts();
    return out;
  };
  const Outcome whole = run(0.0), eliminated = run(2e-3);
  double du = (eliminated.u - whole.u).lpNorm<Eigen::Infinity>(), ds = 0, smax = 0;
  for (std::size_t i = 0; i < whole.stresses.size(); ++i) {
    ds = std::max(ds, (eliminated.stresses[i].stress - whole.stresses[i].stress).lpNorm<Eigen::Infinity>());
    smax = std::max(smax, whole.stresses[i].stress.lpNorm<Eigen::Infinity>());
  }
  const auto& c = eliminated.counts;
  std::printf("interior elimination: %d interior and %d border unknowns, %ld condensations, %ld reused; Newton "
              "iterations %d / %d; largest difference %.2e m of %.2e m, %.2e Pa of %.2e Pa\n",
              c.interior_unknowns, c.border_unknowns, c.condensations, c.condensations_reused, eliminated.iterations,
              whole.iterations, du, whole.u.lpNorm<Eigen::Infinity>(), ds, smax);
  EXPECT_EQ(whole.counts.interior_unknowns, 0);
  EXPECT_GT(c.interior_unknowns, 1000);
  EXPECT_GT(c.condensations, 3);
  EXPECT_GT(c.condensations_reused, c.condensations);
  EXPECT_LE(2 * std::abs(eliminated.iterations - whole.iterations), whole.iterations);
  EXPECT_LT(du, physics::MechanicsSettings{}.mechanics_error_estimate);
  EXPECT_LT(ds, 1e-5 * smax);
}
