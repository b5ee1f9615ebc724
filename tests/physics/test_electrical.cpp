// Electrical conduction (physics/electrical) against closed forms: the uniform rod
// R = ρL/(πr²) (exact on any mesh), the two-block contact column (docs/VERIFICATION.md)
// (exact for bilinear elements, also on non-matching meshes), and current and energy
// conservation on the default weld stack with contact, bonding and a hot spot.
#include "contact/film_contact_law.hpp"
#include "mechanics_fixtures.hpp"
#include "meshes/weld_mesh.hpp"
#include "physics/electrical.hpp"
#include "physics/interface_model.hpp"
#include "physics/problem.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>

using namespace rsw;

namespace {
// A conductor with constant properties (SI); only resistivity and yield stress matter
// to the electrical field and the contact law.
materials::Material conductor(const std::string& name, double resistivity, double yield_stress) {
  materials::MaterialData d;
  d.name = name;
  d.electrical_resistivity = materials::PropertyTable::constant(resistivity);
  d.thermal_conductivity = materials::PropertyTable::constant(50.0);
  d.specific_heat = materials::PropertyTable::constant(500.0);
  d.density = materials::PropertyTable::constant(7800.0);
  d.youngs_modulus = materials::PropertyTable::constant(200e9);
  d.poisson_ratio = materials::PropertyTable::constant(0.3);
  d.secant_expansion = materials::PropertyTable::constant(1e-5);
  d.flow_curves = materials::FlowCurveTable({{20.0, {0.0, 1.0}, {yield_stress, yield_stress}}});
  d.solidus = 5000;
  d.liquidus = 5100;
  d.melting_temperature = 5100;
  d.latent_heat = 0;
  d.strength_floor = 1e6;
  return materials::Material(d);
}

// A contact state with a pressure given as a function of the pairing point.
contact::ContactState fixed_contact(const std::vector<contact::InterfacePairing>& pairings,
                                    const std::function<double(const std::string&, const fem::Point&)>& pressure) {
  contact::ContactState state;
  state.pairings = &pairings;
  for (const auto& p : pairings) {
    std::vector<double> values;
    for (const auto& pt : p.points()) values.push_back(pressure(p.name(), pt.position));
    state.pressure.push_back(values);
  }
  return state;
}

// Two blocks 0 ≤ r ≤ radius stacked along z: "lower" on [0, L] (cells lower_size),
// "upper" on [L, 2L] (cells upper_size), touching at the interface "contact".
fem::Mesh two_block_column(double L, double radius, double lower_size, double upper_size) {
  fem::Mesh mesh = test::block_mesh("lower", 0, radius, 0, L, lower_size);
  mesh.append(test::block_mesh("upper", 0, radius, L, 2 * L, upper_size));
  mesh.interfaces["contact"] = {"upper.bottom", "lower.top", "film_contact"};
  return mesh;
}

// The column's current enters the upper block's top face; the lower block's bottom
// face is grounded.
physics::ElectricalSettings column_settings() {
  physics::ElectricalSettings s;
  s.current_boundary = "upper.top";
  s.ground_boundary = "lower.bottom";
  return s;
}
}  // namespace

// Rod r ≤ 1 mm, 2 mm long, with a refined corner (hanging nodes): φ is linear in z,
// so the bilinear solution is exact and R = ρL/(πr²) to round-off.
TEST(ElectricalVerification, UniformRodResistanceIsExactOnHangingNodeMesh) {
  const double rho = 2.5e-7, radius = 1e-3, length = 2e-3, current = 5e3;
  const auto steel = conductor("steel", rho, 500e6);
  const fem::Mesh mesh = test::block_mesh("rod", 0, radius, 0, length, 0.25e-3, 2,
                                          [](const fem::IndexBox& b) { return b.x0 < 2 && b.y0 < 3; });
  ASSERT_GT(mesh.hanging_nodes.size(), 0u);
  physics::ElectricalSettings s;
  s.current_boundary = "rod.top";
  s.ground_boundary = "rod.bottom";
  s.probes = {{"half", {0.3e-3, 1.5e-3}, {0.7e-3, 0.5e-3}}};
  physics::Electrical electrical(mesh, {&steel}, {}, s);
  const std::vector<contact::InterfacePairing> none;
  const contact::ContactState contact{&none, {}};
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);
  const auto& sol = electrical.solve(mesh.nodes, T, current, contact);
  const double exact = rho * length / (M_PI * radius * radius);
  std::printf("uniform rod: R = %.12e ohm (closed form %.12e), probe over half the rod %.12e (%.12e), "
              "ground current %.12f A, V*I - P = %.2e W\n",
              sol.resistance, exact, sol.probe_resistance[0], exact / 2, sol.ground_current,
              sol.voltage * current - sol.bulk_power);
  EXPECT_NEAR(sol.resistance, exact, 1e-12 * exact);
  EXPECT_NEAR(sol.probe_resistance[0], exact / 2, 1e-12 * exact);
  EXPECT_NEAR(sol.ground_current, current, 1e-10 * current);
  EXPECT_NEAR(sol.bulk_power, sol.voltage * current, 1e-10 * sol.bulk_power);
  for (int n = 0; n < mesh.n_nodes(); ++n)
    EXPECT_NEAR(sol.potential[n], sol.voltage * mesh.nodes[n].y() / length, 1e-12 * sol.voltage);
  // Uniform heat σ|∇φ|² = J²ρ at every Gauss point.
  const double J = current / (M_PI * radius * radius);
  for (double q : sol.joule_heat) EXPECT_NEAR(q, J * J * rho, 1e-9 * J * J * rho);
}

// Two blocks of length L with conductivities σ_1 (current side) and σ_2 (grounded
// side) and interface conductance C_E. With x the distance from the current face and
// V the potential there, the closed form (derived for blocks of unit length, scaled
// to length L):
//   φ_1(x) = V (1 − C_E σ_2 x / D),  φ_2(x) = −V C_E σ_1 (x − 2L) / D,
//   D = σ_1σ_2 + C_E L (σ_1 + σ_2),   V = I/(πr²) (L/σ_1 + 1/C_E + L/σ_2).
// C_E is Bay–Wanheim at a fixed 80 MPa contact pressure (the default film that
// replaces bulk, in series with the bonded layer). The blocks have different
// (non-matching) meshes; the fields are linear in z, so the solution is exact.
TEST(ElectricalContact, TwoBlockPotentialMatchesClosedForm) {
  const double upper_size = 0.25e-3;
  const double L = 1e-3, radius = 1e-3, current = 2e3, pressure = 80e6;
  const double rho_1 = 2e-8, rho_2 = 3e-7;
  const auto upper_mat = conductor("upper_metal", rho_1, 350e6);
  const auto lower_mat = conductor("lower_metal", rho_2, 900e6);
  const fem::Mesh mesh = two_block_column(L, radius, 0.25e-3, upper_size);
  const contact::InterfaceProperties props{"contact", 1e-6, 2e-6, 1e-3, false};
  const contact::InterfaceModel model = contact::film_contact_model({props});
  physics::Electrical electrical(mesh, {&lower_mat, &upper_mat}, model, column_settings());
  std::vector<contact::InterfacePairing> pairings;
  pairings.emplace_back(mesh, "contact", 2);
  const auto contact = fixed_contact(pairings, [&](const std::string&, const fem::Point&) { return pressure; });
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);
  const auto& sol = electrical.solve(mesh.nodes, T, current, contact);

  // The default film replaces bulk: eq. 1's excess over ρ̄ t_f in series with the bonded
  // layer F (σ_1 + σ_2)/h_local of the 0.25 mm interface faces.
  const auto bulk = contact::bonded_electrical_conductance(upper_mat, lower_mat, 20.0, 20.0, upper_size, 1e3);
  const double C =
      contact::electrical_contact_conductance(upper_mat, lower_mat, pressure, 20.0, 20.0, props, 0.0, &bulk).value;
  const double s1 = 1 / rho_1, s2 = 1 / rho_2;
  const double D = s1 * s2 + C * L * (s1 + s2);
  const double V = current / (M_PI * radius * radius) * (L / s1 + 1 / C + L / s2);
  double worst = 0;
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const double x = 2 * L - mesh.nodes[n].y();
    const bool upper = mesh.body_names[mesh.node_body[n]] == "upper";
    const double exact = upper ? V * (1 - C * s2 * x / D) : -V * C * s1 * (x - 2 * L) / D;
    worst = std::max(worst, std::abs(sol.potential[n] - exact));
  }
  std::printf("two-block contact: C_E = %.4e S/m^2, V = %.9e V (closed form %.9e), max |phi - exact| = %.2e V, "
              "interface current %.9f A, interface heat %.6e W (j^2/C_E A = %.6e W)\n",
              C, sol.voltage, V, worst, sol.interface_current[0], sol.interface_power[0],
              std::pow(current / (M_PI * radius * radius), 2) / C * M_PI * radius * radius);
  EXPECT_NEAR(sol.voltage, V, 1e-10 * V);
  EXPECT_LT(worst, 1e-10 * V);
  for (double h : sol.interface_conductance[0]) EXPECT_NEAR(h, C, 1e-12 * C);
  EXPECT_NEAR(sol.interface_current[0], current, 1e-10 * current);
  const double j = current / (M_PI * radius * radius);
  EXPECT_NEAR(sol.interface_power[0], j * j / C * M_PI * radius * radius, 1e-9 * sol.interface_power[0]);
}

// The two-block column with its interface bonded at a conductance C_b 10⁹ times a
// bonded layer's (bonded_factor, against 10³ in the weld): the interface rows of K
// then hold entries about 10¹² times the bulk's, and the relative residual of the
// unit-current solve stalls near 5·10⁻⁶ (measured), above the GMRES tolerance (10⁻¹⁰)
// and above what the solve once accepted (10⁻⁶). It is accepted on its componentwise
// backward error (round-off), and the potential is the closed form of the column,
// V = I/(πr²) (L/σ_1 + 1/C_b + L/σ_2), to 10⁻⁴ of V: the bulk entries of the interface
// rows keep only ε·10¹² ≈ 2·10⁻⁴ of their value, so the error depends on the order in
// which the assembly sums them (measured 3·10⁻⁸ of V with the cells summed colour by
// colour, 2.5·10⁻⁶ in the cells' own order). The interface current
// C_b Δφ A, from a potential jump of 10⁻¹² of φ, carries that rounding: to 10⁻³.
TEST(ElectricalContact, NearlyRigidBondedInterfaceSolvesToRoundOffOfItsBackwardError) {
  const double L = 1e-3, radius = 1e-3, current = 2e3, factor = 1e9;
  const double rho_1 = 2e-8, rho_2 = 3e-7;
  const auto upper_mat = conductor("upper_metal", rho_1, 350e6);
  const auto lower_mat = conductor("lower_metal", rho_2, 900e6);
  const fem::Mesh mesh = two_block_column(L, radius, 0.25e-3, 0.25e-3);
  const contact::InterfaceProperties props{"contact", 1e-6, 2e-6, 1e-3, true};
  contact::FilmContactConstants constants;
  constants.bonded_factor = factor;
  const contact::InterfaceModel model = contact::film_contact_model({props}, constants);
  physics::Electrical electrical(mesh, {&lower_mat, &upper_mat}, model, column_settings());
  std::vector<contact::InterfacePairing> pairings;
  pairings.emplace_back(mesh, "contact", 2);
  const auto contact = fixed_contact(pairings, [](const std::string&, const fem::Point&) { return 80e6; });
  contact::InterfaceHistory bonding(pairings);
  for (std::size_t i = 0; i < pairings[0].points().size(); ++i) bonding.bond(0, static_cast<int>(i));
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);
  const auto& sol = electrical.solve(mesh.nodes, T, current, contact, bonding);

  const double C = sol.interface_conductance[0].front();
  for (double h : sol.interface_conductance[0]) EXPECT_EQ(h, C);
  EXPECT_GT(C, 1e20);  // S/m²: 10⁹ × σ over a half cell
  const double V = current / (M_PI * radius * radius) * (L / (1 / rho_1) + 1 / C + L / (1 / rho_2));
  std::printf("bonded column: C_b = %.3e S/m^2, V = %.12e V (closed form %.12e)\n", C, sol.voltage, V);
  EXPECT_NEAR(sol.voltage, V, 1e-4 * V);
  EXPECT_NEAR(sol.interface_current[0], current, 1e-3 * current);
}

// The same column with non-matching interface meshes (upper cells L/6, lower L/4):
// Gauss-point-to-segment coupling integrates the master shape functions at the slave
// points only, which is not exact when master nodes fall inside slave faces, so the
// 1-D field is reproduced to O(h) near the interface, not to round-off. Current is
// still conserved exactly (the master weights of every point sum to one).
TEST(ElectricalContact, TwoBlockOnNonMatchingMeshesConservesCurrent) {
  const double L = 1e-3, radius = 1e-3, current = 2e3, pressure = 80e6;
  const auto upper_mat = conductor("upper_metal", 2e-8, 350e6);
  const auto lower_mat = conductor("lower_metal", 3e-7, 900e6);
  const fem::Mesh mesh = two_block_column(L, radius, L / 4, L / 6);
  const contact::InterfaceProperties props{"contact", 1e-6, 2e-6, 1e-3, false};
  contact::FilmContactConstants as_written;  // eq. 1 as written: C is the same on both meshes' faces
  as_written.film_replaces_bulk = false;
  const contact::InterfaceModel model = contact::film_contact_model({props}, as_written);
  physics::Electrical electrical(mesh, {&lower_mat, &upper_mat}, model, column_settings());
  std::vector<contact::InterfacePairing> pairings;
  pairings.emplace_back(mesh, "contact", 2);
  const auto contact = fixed_contact(pairings, [&](const std::string&, const fem::Point&) { return pressure; });
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);
  const auto& sol = electrical.solve(mesh.nodes, T, current, contact);
  const double C = contact::electrical_contact_conductance(upper_mat, lower_mat, pressure, 20.0, 20.0, props).value;
  const double V = current / (M_PI * radius * radius) * (L * 2e-8 + 1 / C + L * 3e-7);
  std::printf("two-block contact, non-matching meshes: V = %.9e V (closed form %.9e, %.1e relative), interface "
              "current %.9f A, ground current %.9f A\n",
              sol.voltage, V, sol.voltage / V - 1, sol.interface_current[0], sol.ground_current);
  EXPECT_NEAR(sol.interface_current[0], current, 1e-10 * current);
  EXPECT_NEAR(sol.ground_current, current, 1e-10 * current);
  EXPECT_NEAR(sol.voltage, V, 1e-4 * V);
}

// The default weld stack (paper case mesh) with a smooth contact pressure on every
// interface, bonded S/S points near the axis and a hot spot: the current I enters
// the upper end face, crosses every interface and leaves through the lower end face;
// V I equals the bulk plus interface Joule power. Also times the solve.
TEST(ElectricalVerification, CurrentIsConservedThroughEveryInterfaceOfTheWeldStack) {
  const physics::Problem problem =
      physics::load_problem(std::string(RSW_SOURCE_DIR) + "/validation/paper_case/weld.yaml");
  const fem::Mesh mesh = meshes::weld_mesh(problem.geometry, problem.mesh);
  materials::MaterialLibrary library;
  const auto copper = library.load("CuCrZr");
  const auto steel = library.load("DP1200");
  const std::vector<const materials::Material*> mats{&copper, &steel, &steel, &copper};
  double z_top = -1e300, z_bottom = 1e300;
  for (int n : mesh.boundary_nodes("upper_electrode.end_face")) z_top = std::max(z_top, mesh.nodes[n].y());
  for (int n : mesh.boundary_nodes("lower_electrode.end_face")) z_bottom = std::min(z_bottom, mesh.nodes[n].y());
  physics::ElectricalSettings s;
  // The end faces are annuli around the cooling bores: probe them at r = 6.5 mm.
  s.probes = {{"end_faces", {6.5e-3, z_top}, {6.5e-3, z_bottom}}, {"tips", {1e-3, 3e-3}, {1e-3, -3e-3}}};
  physics::Electrical electrical(mesh, mats, physics::interface_model(mesh, problem.contact), s);

  std::vector<contact::InterfacePairing> pairings;
  for (const auto& [name, pair] : mesh.interfaces) pairings.emplace_back(mesh, name, 2);
  const auto contact = fixed_contact(pairings, [&mesh](const std::string& name, const fem::Point& x) {
    const double a = mesh.interfaces.at(name).kind == meshes::interface_kind::electrode_sheet ? 2.5e-3 : 3e-3;
    return 300e6 * std::max(0.0, 1 - std::pow(x.x() / a, 2));
  });
  contact::InterfaceHistory bonding(pairings);
  int p_ss = 0;
  for (const auto& [name, pair] : mesh.interfaces) {
    if (pair.kind == meshes::interface_kind::sheet_sheet) break;
    ++p_ss;
  }
  for (std::size_t i = 0; i < pairings[p_ss].points().size(); ++i)
    if (pairings[p_ss].points()[i].position.x() < 1e-3) bonding.bond(p_ss, static_cast<int>(i));
  Eigen::VectorXd T(mesh.n_nodes());
  for (int n = 0; n < mesh.n_nodes(); ++n)
    T[n] = 20 + 1300 * std::exp(-mesh.nodes[n].squaredNorm() / (2e-3 * 2e-3));

  const double current = 8e3;
  electrical.solve(mesh.nodes, T, current, contact, bonding);
  const auto start = std::chrono::steady_clock::now();
  const auto& sol = electrical.solve(mesh.nodes, T, current, contact, bonding);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  std::printf("weld stack (%d cells, %d nodes): R = %.2f uohm, probes: end faces %.2f uohm, tips %.2f uohm; "
              "solve %.1f ms\n",
              mesh.n_cells(), mesh.n_nodes(), sol.resistance * 1e6, sol.probe_resistance[0] * 1e6,
              sol.probe_resistance[1] * 1e6, ms);
  std::printf("  ground current %.10f A; bulk %.2f W + interfaces %.2f W = %.6f W, V I = %.6f W\n",
              sol.ground_current, sol.bulk_power, sol.total_interface_power(),
              sol.bulk_power + sol.total_interface_power(), sol.voltage * current);
  EXPECT_NEAR(sol.ground_current, current, 1e-10 * current);
  EXPECT_NEAR(sol.probe_resistance[0], sol.resistance, 1e-12 * sol.resistance);
  std::size_t p = 0;
  for (const auto& [name, pair] : mesh.interfaces) {
    std::printf("  %-9s current %.10f A, power %.2f W\n", name.c_str(), sol.interface_current[p],
                sol.interface_power[p]);
    // Slave to master: down through es_upper and ss_1_2, up (master to slave) through es_lower.
    EXPECT_NEAR(std::abs(sol.interface_current[p]), current, 1e-10 * current) << name;
    ++p;
  }
  EXPECT_NEAR(sol.bulk_power + sol.total_interface_power(), sol.voltage * current, 1e-10 * sol.voltage * current);
  EXPECT_GT(bonding.n_bonded(p_ss), 0);
}

// A body without closed contact has no current path: reported, not a singular solve.
TEST(Electrical, FloatingBodyIsReported) {
  const auto metal = conductor("metal", 1e-7, 300e6);
  fem::Mesh mesh = test::block_mesh("lower", 0, 1e-3, 0, 1e-3, 0.25e-3);
  mesh.append(test::block_mesh("upper", 0, 1e-3, 1e-3, 2e-3, 0.25e-3));
  mesh.interfaces["contact"] = {"upper.bottom", "lower.top", "film_contact"};
  const contact::InterfaceProperties props{"contact", 1e-6, 2e-6, 1e-3, false};
  const contact::InterfaceModel model = contact::film_contact_model({props});
  physics::ElectricalSettings s;
  s.current_boundary = "upper.top";
  s.ground_boundary = "lower.bottom";
  physics::Electrical electrical(mesh, {&metal, &metal}, model, s);
  std::vector<contact::InterfacePairing> pairings;
  pairings.emplace_back(mesh, "contact", 2);
  const auto open = fixed_contact(pairings, [](const std::string&, const fem::Point&) { return 0.0; });
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), 20.0);
  EXPECT_THROW(electrical.solve(mesh.nodes, T, 1e3, open), std::runtime_error);
}

// locate_point + interpolate reproduce a bilinear field at arbitrary points of a
// hanging-node mesh (hanging values set by their constraint).
TEST(PointLocation, InterpolatesBilinearFieldExactly) {
  const fem::Mesh mesh = test::block_mesh("block", 0, 2e-3, 0, 1e-3, 0.25e-3, 2,
                                          [](const fem::IndexBox& b) { return b.x0 < 3 && b.y0 < 2; });
  const auto field = [](const fem::Point& x) { return 3 + 2e3 * x.x() - 5e3 * x.y() + 7e6 * x.x() * x.y(); };
  Eigen::VectorXd u(mesh.n_nodes());
  for (int n = 0; n < mesh.n_nodes(); ++n) u[n] = field(mesh.nodes[n]);
  double worst = 0;
  for (int i = 0; i < 50; ++i) {
    const fem::Point x(2e-3 * std::fmod(0.37 * i + 0.05, 1.0), 1e-3 * std::fmod(0.61 * i + 0.02, 1.0));
    const auto where = physics::locate_point(mesh, x);
    ASSERT_GE(where.cell, 0);
    worst = std::max(worst, std::abs(physics::interpolate(mesh, where, u) - field(x)));
  }
  EXPECT_LT(worst, 1e-12);
  EXPECT_THROW(physics::locate_point(mesh, fem::Point(3e-3, 0.5e-3)), std::out_of_range);
}
