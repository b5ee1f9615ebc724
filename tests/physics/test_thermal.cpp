// Heat conduction (physics/thermal), alone and driven by the electrical field,
// against the closed forms listed in docs/VERIFICATION.md: the Joule-heated rod with a cooled
// lateral face, adiabatic Joule heating with a linearly rising resistivity, the
// two-block electro-thermal contact with interface heat split half/half, the
// one-phase Stefan problem in enthalpy form, the first-order temporal convergence of
// backward Euler, and the energy balance ∫VI dt = stored + removed through melting,
// bonding and the λ_m switch. Each test derives its reference numbers from the
// closed form and prints them.
#include "contact/film_contact_law.hpp"
#include "fem/fe_values.hpp"
#include "mechanics_fixtures.hpp"
#include "meshes/weld_mesh.hpp"
#include "physics/electrical.hpp"
#include "physics/interface_model.hpp"
#include "physics/problem.hpp"
#include "physics/thermal.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>

using namespace rsw;

namespace {
using materials::PropertyTable;

struct MaterialSpec {
  std::string name = "metal";
  PropertyTable resistivity = PropertyTable::constant(2.5e-7);  // Ω·m
  PropertyTable conductivity = PropertyTable::constant(30.0);   // W/(m·K)
  PropertyTable specific_heat = PropertyTable::constant(500.0);  // J/(kg·K)
  double density = 7800;                                         // kg/m³
  double yield_stress = 500e6;                                   // Pa
  double solidus = 5000, liquidus = 5100, melting_temperature = 5100;  // °C (no melting by default)
  double latent_heat = 0;                                        // J/kg
};

materials::Material make_material(const MaterialSpec& s) {
  materials::MaterialData d;
  d.name = s.name;
  d.electrical_resistivity = s.resistivity;
  d.thermal_conductivity = s.conductivity;
  d.specific_heat = s.specific_heat;
  d.density = PropertyTable::constant(s.density);
  d.youngs_modulus = PropertyTable::constant(200e9);
  d.poisson_ratio = PropertyTable::constant(0.3);
  d.secant_expansion = PropertyTable::constant(1e-5);
  d.flow_curves = materials::FlowCurveTable({{20.0, {0.0, 1.0}, {s.yield_stress, s.yield_stress}}});
  d.solidus = s.solidus;
  d.liquidus = s.liquidus;
  d.melting_temperature = s.melting_temperature;
  d.latent_heat = s.latent_heat;
  d.strength_floor = 1e6;
  return materials::Material(d);
}

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

// Thermal settings with no convection anywhere (tests switch on what they need).
// k = 30 W/(m·K), melting between 1450 and 1490 °C, T_melting = 1500 °C.
MaterialSpec melting_spec() {
  MaterialSpec spec;
  spec.conductivity = PropertyTable::constant(30.0);
  spec.solidus = 1450;
  spec.liquidus = 1490;
  spec.melting_temperature = 1500;
  spec.latent_heat = 2.7e5;
  return spec;
}

physics::ThermalSettings insulated(double initial_temperature) {
  physics::ThermalSettings s;
  s.initial_temperature = initial_temperature;
  s.water_htc = 0;
  s.air_htc = 0;
  s.melt_conductivity = 0;  // the tables everywhere
  s.melt_conductivity_band = 0;
  return s;
}

// Two discs of radius R and thickness t, sheet_2 below sheet_1, cells t/n_cells high,
// joined by the sheet/sheet interface ss_1_2.
fem::Mesh two_discs(double R, double t, int n_cells) {
  fem::Mesh mesh = test::block_mesh("sheet_2", 0, R, -t, 0, t / n_cells);
  mesh.append(test::block_mesh("sheet_1", 0, R, 0, t, t / n_cells));
  mesh.interfaces["ss_1_2"] = {"sheet_1.bottom", "sheet_2.top", meshes::interface_kind::sheet_sheet};
  return mesh;
}

// Lumped volume of every node, ∫ N_a dV on the undeformed mesh (m³).
Eigen::VectorXd nodal_volume(const fem::Mesh& mesh) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(mesh.n_nodes());
  fem::CellValues cv(2);
  for (int e = 0; e < mesh.n_cells(); ++e) {
    cv.reinit(mesh, e);
    for (int q = 0; q < cv.n_q(); ++q)
      for (int a = 0; a < 4; ++a) v[mesh.cells[e][a]] += cv.N(q, a) * cv.JxW(q);
  }
  return v;
}
}  // namespace

// Rod of radius R carrying I along z, lateral face held at T_s, ends insulated:
// q = I²ρ_e/(π²R⁴) and, at steady state, T(r) = T_s + q (R² − r²)/(4k). Steady state
// by backward Euler with Δt = 10⁴ s (the capacity term is then ~10⁻⁹ of conduction).
TEST(ThermalVerification, JouleHeatedRodMatchesParabolicProfile) {
  const double R = 1e-3, length = 0.5e-3, current = 1e3, rho_e = 2.5e-7, k = 30, T_s = 20;
  MaterialSpec spec;
  spec.resistivity = PropertyTable::constant(rho_e);
  spec.conductivity = PropertyTable::constant(k);
  const auto metal = make_material(spec);
  const fem::Mesh mesh = test::block_mesh("rod", 0, R, 0, length, R / 40);
  physics::ElectricalSettings es;
  es.current_boundary = "rod.top";
  es.ground_boundary = "rod.bottom";
  physics::Electrical electrical(mesh, {&metal}, {}, es);
  physics::ThermalSettings ts = insulated(T_s);
  ts.fixed_temperatures = {{"rod.right", T_s}};
  physics::Thermal thermal(mesh, {&metal}, {}, ts);
  const std::vector<contact::InterfacePairing> none;
  const contact::ContactState contact{&none, {}};

  const auto& sol = electrical.solve(mesh.nodes, thermal.temperature(), current, contact);
  for (int step = 0; step < 3; ++step) {
    const auto report = thermal.solve(1e4, mesh.nodes, contact, sol.joule_heat, {});
    ASSERT_TRUE(report.converged) << report.message;
    thermal.commit();
  }
  const double q = current * current * rho_e / (M_PI * M_PI * std::pow(R, 4));
  const double rise = q * R * R / (4 * k);
  double worst = 0;
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const double r = mesh.nodes[n].x();
    worst = std::max(worst, std::abs(thermal.temperature()[n] - (T_s + q * (R * R - r * r) / (4 * k))));
  }
  std::printf("Joule-heated rod: q = %.4e W/m^3, centre rise %.4f K (closed form), max nodal error %.2e K "
              "(%.1e of the rise), 40 cells across\n",
              q, rise, worst, worst / rise);
  EXPECT_LT(worst, 1e-3 * rise);
  // Steady state: all the Joule heat leaves through the cooled face.
  const auto& E = thermal.energy();
  EXPECT_NEAR(E.removed_fixed, E.generated(), 1e-6 * E.generated());
}

// Uniform current density J through an insulated rod with ρ_e(T) = ρ_0 (1 + β ΔT) and no
// conduction (uniform field): ρc dΔT/dt = J² ρ_0 (1 + β ΔT), so
//   ΔT(t) = [exp(J² ρ_0 β t/(ρc)) − 1]/β  ≈ 443 K at 50 ms (the values below).
// Staggered coupling iterated to convergence in every step (Joule heat at T_{n+1}).
TEST(ThermalVerification, AdiabaticJouleHeatingFollowsExponentialLaw) {
  const double J = 2.83e8, rho_0 = 2.5e-7, beta = 4e-3, rho_c = 3.93e6, density = 7860;
  const double R = 0.5e-3, current = J * M_PI * R * R, t_end = 0.05, dt = 1e-4;
  MaterialSpec spec;
  spec.resistivity = PropertyTable({20.0, 1020.0}, {rho_0, rho_0 * (1 + beta * 1000)});
  spec.density = density;
  spec.specific_heat = PropertyTable::constant(rho_c / density);
  const auto metal = make_material(spec);
  const fem::Mesh mesh = test::block_mesh("rod", 0, R, 0, 0.5e-3, 0.125e-3);
  physics::ElectricalSettings es;
  es.current_boundary = "rod.top";
  es.ground_boundary = "rod.bottom";
  physics::Electrical electrical(mesh, {&metal}, {}, es);
  physics::Thermal thermal(mesh, {&metal}, {}, insulated(20.0));
  const std::vector<contact::InterfacePairing> none;
  const contact::ContactState contact{&none, {}};

  double electrical_energy = 0, stored = 0;
  int n_coupling = 0;
  const int n_steps = static_cast<int>(std::lround(t_end / dt));
  for (int step = 0; step < n_steps; ++step) {
    double change = 1e300;
    for (int it = 0; it < 30 && change > 1e-9; ++it, ++n_coupling) {
      const Eigen::VectorXd before = thermal.temperature();
      const auto& sol = electrical.solve(mesh.nodes, before, current, contact);
      const auto report = thermal.solve(dt, mesh.nodes, contact, sol.joule_heat, {});
      ASSERT_TRUE(report.converged) << report.message;
      change = (thermal.temperature() - before).lpNorm<Eigen::Infinity>();
    }
    electrical_energy += electrical.solution().voltage * current * dt;
    stored += thermal.energy().stored;
    thermal.commit();
  }
  const double exact = (std::exp(J * J * rho_0 * beta * t_end / rho_c) - 1) / beta;
  const double rise = thermal.temperature().mean() - 20;
  const double spread = thermal.temperature().maxCoeff() - thermal.temperature().minCoeff();
  std::printf("adiabatic Joule heating: dT(50 ms) = %.3f K, closed form %.3f K (%.3f %%), spread %.1e K, "
              "%d steps, %.2f coupling iterations per step; int V I dt = %.6f J, stored %.6f J\n",
              rise, exact, 100 * (rise / exact - 1), spread, n_steps, double(n_coupling) / n_steps, electrical_energy,
              stored);
  EXPECT_NEAR(rise, exact, 0.005 * exact);
  EXPECT_LT(spread, 1e-6 * exact);
  EXPECT_NEAR(stored, electrical_energy, 1e-9 * electrical_energy);
}

// Two blocks (lengths L, conductivities k_1 below, k_2 above, resistivities ρ_1, ρ_2)
// stacked along z, both outer faces at T_0, current I through them, interface with
// electrical conductance C_E and thermal conductance h (Bay–Wanheim and Simufact at a
// fixed pressure). Steady 1-D fields with uniform bulk heat q_i = j² ρ_i and interface
// heat q_s = j²/C_E released half on each side (MOOSE/MALAMUTE two-block problem):
//   T_1(z) = T_0 + a_1 z − q_1 z²/(2k_1)              (lower block, z ∈ [0, L])
//   T_2(z) = T_0 + a_2 (2L − z) − q_2 (2L − z)²/(2k_2)  (upper block, z ∈ [L, 2L])
// with, at the interface z = L (flux continuity with the half source on each side),
//   −k_1 T_1'(L) + q_s/2 = h (T_1(L) − T_2(L)) = k_2 T_2'(L) − q_s/2 ... written out:
//   k_1 a_1 − q_1 L − q_s/2 + h (T_1(L) − T_2(L)) = 0,
//   k_2 a_2 − q_2 L − q_s/2 − h (T_1(L) − T_2(L)) = 0,
// a 2×2 linear system for a_1, a_2. Bilinear elements reproduce 1-D solutions of this
// kind at the nodes, so the comparison is to round-off.
TEST(ThermalVerification, TwoBlockElectroThermalContactMatchesClosedForm) {
  const double L = 1e-3, R = 1e-3, current = 314.0, pressure = 80e6, T_0 = 20;
  MaterialSpec lower_spec, upper_spec;
  lower_spec.name = "lower_metal";
  lower_spec.resistivity = PropertyTable::constant(1e-7);
  lower_spec.conductivity = PropertyTable::constant(50);
  upper_spec.name = "upper_metal";
  upper_spec.resistivity = PropertyTable::constant(3e-7);
  upper_spec.conductivity = PropertyTable::constant(25);
  upper_spec.yield_stress = 300e6;
  const auto lower_mat = make_material(lower_spec);
  const auto upper_mat = make_material(upper_spec);
  fem::Mesh mesh = test::block_mesh("lower", 0, R, 0, L, L / 8);
  mesh.append(test::block_mesh("upper", 0, R, L, 2 * L, L / 8));
  mesh.interfaces["contact"] = {"upper.bottom", "lower.top", "film_contact"};
  const contact::InterfaceProperties props{"contact", 1e-4, 1e-5, 1e-3, false};
  const contact::InterfaceModel model = contact::film_contact_model({props});
  const std::vector<const materials::Material*> mats{&lower_mat, &upper_mat};
  physics::ElectricalSettings es;
  es.current_boundary = "upper.top";
  es.ground_boundary = "lower.bottom";
  physics::Electrical electrical(mesh, mats, model, es);
  physics::ThermalSettings ts = insulated(T_0);
  ts.fixed_temperatures = {{"lower.bottom", T_0}, {"upper.top", T_0}};
  physics::Thermal thermal(mesh, mats, model, ts);
  std::vector<contact::InterfacePairing> pairings;
  pairings.emplace_back(mesh, "contact", 2);
  const auto contact = fixed_contact(pairings, [&](const std::string&, const fem::Point&) { return pressure; });

  const auto& sol = electrical.solve(mesh.nodes, thermal.temperature(), current, contact);
  for (int step = 0; step < 3; ++step) {
    const auto report = thermal.solve(1e6, mesh.nodes, contact, sol.joule_heat, sol.interface_heat);
    ASSERT_TRUE(report.converged) << report.message;
    thermal.commit();
  }

  const double j = current / (M_PI * R * R);
  // The default film replaces bulk: in series with the bonded layer of the L/8 faces.
  const auto bulk = contact::bonded_electrical_conductance(upper_mat, lower_mat, T_0, T_0, L / 8, 1e3);
  const double C =
      contact::electrical_contact_conductance(upper_mat, lower_mat, pressure, T_0, T_0, props, 0.0, &bulk).value;
  const double h = contact::thermal_contact_conductance(upper_mat, lower_mat, pressure, T_0, T_0, props,
                                                        contact::ThermalContactConstants{})
                       .value;
  const double q1 = j * j * 1e-7, q2 = j * j * 3e-7, qs = j * j / C, k1 = 50, k2 = 25;
  // T_1(L) − T_2(L) = (a_1 − a_2) L − q_1L²/(2k_1) + q_2L²/(2k_2)
  Eigen::Matrix2d A;
  Eigen::Vector2d b;
  const double c0 = -q1 * L * L / (2 * k1) + q2 * L * L / (2 * k2);
  A << k1 + h * L, -h * L, -h * L, k2 + h * L;
  b << q1 * L + qs / 2 - h * c0, q2 * L + qs / 2 + h * c0;
  const Eigen::Vector2d a = A.partialPivLu().solve(b);
  const auto exact = [&](const fem::Point& x, bool upper) {
    const double z = x.y();
    return upper ? T_0 + a[1] * (2 * L - z) - q2 * std::pow(2 * L - z, 2) / (2 * k2)
                 : T_0 + a[0] * z - q1 * z * z / (2 * k1);
  };
  double worst = 0, peak = 0;
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const bool upper = mesh.body_names[mesh.node_body[n]] == "upper";
    worst = std::max(worst, std::abs(thermal.temperature()[n] - exact(mesh.nodes[n], upper)));
    peak = std::max(peak, exact(mesh.nodes[n], upper) - T_0);
  }
  const double jump = exact({0, L}, false) - exact({0, L}, true);
  std::printf("two-block electro-thermal: C_E = %.4e S/m^2, HTC = %.4e W/m^2K, q_s = %.4e W/m^2, interface "
              "T jump %.4f K, peak rise %.4f K, max nodal error %.2e K\n",
              C, h, qs, jump, peak, worst);
  EXPECT_LT(worst, 1e-8 * peak);
  for (double v : thermal.interface_conductance()[0]) EXPECT_NEAR(v, h, 1e-12 * h);
  const auto& E = thermal.energy();
  EXPECT_NEAR(E.generated_interface / 1e6, qs * M_PI * R * R, 1e-9 * qs * M_PI * R * R);
  EXPECT_NEAR(E.removed_fixed, E.generated(), 1e-6 * E.generated());
}

// One-phase Stefan problem in enthalpy form (docs/VERIFICATION.md): solid at the melting
// temperature, wall raised by ΔT = 100 K; c = 700, L = 2.7e5, k = 30, ρ = 7000 give
// St = cΔT/L, λ e^{λ²} erf(λ) = St/√π, λ = 0.3459, s(t) = 2λ√(αt) = 0.541 mm at 0.1 s.
// A 1-D column of 5 µm cells, melting range 1 K (solidus 1500 °C = initial T), steps of
// 0.1 ms; the front is the molten depth ∫ f_l dV / A.
TEST(ThermalVerification, StefanFrontPositionMatchesNeumannSolution) {
  const double c = 700, latent = 2.7e5, k = 30, density = 7000, dT = 100, T_m = 1500;
  const double h = 5e-6, length = 2e-3, t_end = 0.1, dt = 1e-4;
  MaterialSpec spec;
  spec.conductivity = PropertyTable::constant(k);
  spec.specific_heat = PropertyTable::constant(c);
  spec.density = density;
  spec.solidus = T_m;
  spec.liquidus = T_m + 1;
  spec.melting_temperature = T_m + 1;
  spec.latent_heat = latent;
  const auto metal = make_material(spec);
  const fem::Mesh mesh = test::block_mesh("column", 0, h, 0, length, h);
  physics::ThermalSettings ts = insulated(T_m);
  ts.fixed_temperatures = {{"column.bottom", T_m + dT}};
  physics::Thermal thermal(mesh, {&metal}, {}, ts);
  const std::vector<contact::InterfacePairing> none;
  const contact::ContactState contact{&none, {}};
  const Eigen::VectorXd volume = nodal_volume(mesh);

  int iterations = 0, worst_iterations = 0;
  const int n_steps = static_cast<int>(std::lround(t_end / dt));
  double energy_error = 0, stored = 0;  // J; the column holds ~5e-7 J/K, so 1e-11 J is ~2e-5 K
  for (int step = 0; step < n_steps; ++step) {
    const auto report = thermal.solve(dt, mesh.nodes, contact, {}, {});
    ASSERT_TRUE(report.converged) << "step " << step << ": " << report.message;
    iterations += report.iterations;
    worst_iterations = std::max(worst_iterations, report.iterations);
    energy_error = std::max(energy_error, std::abs(thermal.energy().imbalance()));
    stored += thermal.energy().stored;
    thermal.commit();
  }
  const Eigen::VectorXd f = thermal.liquid_fraction();
  const double front = volume.dot(f) / (M_PI * h * h);

  const double St = c * dT / latent;
  double lo = 0, hi = 2;  // λ e^{λ²} erf(λ) − St/√π is increasing in λ
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (mid * std::exp(mid * mid) * std::erf(mid) < St / std::sqrt(M_PI) ? lo : hi) = mid;
  }
  const double lambda = 0.5 * (lo + hi);
  const double exact = 2 * lambda * std::sqrt(k / (density * c) * t_end);
  std::printf("Stefan: St = %.5f, lambda = %.4f, s(0.1 s) = %.4f mm (closed form %.4f mm, %.2f %%); Newton "
              "iterations %.2f per step (max %d); largest step energy imbalance %.1e J of %.3e J stored\n",
              St, lambda, front * 1e3, exact * 1e3, 100 * (front / exact - 1), double(iterations) / n_steps,
              worst_iterations, energy_error, stored);
  EXPECT_NEAR(lambda, 0.3459, 5e-4);
  EXPECT_NEAR(front, exact, 0.03 * exact);
}

// Backward Euler is first order in time: on a smooth nonlinear problem (k(T), c(T)
// linear in T, convection on one end, a source q(t) = q_0 t/t_end switched on from an
// equilibrium start, so no initial layer) the error at t_end = 20 ms against a
// reference with Δt/16 of the finest step halves with Δt.
TEST(ThermalVerification, BackwardEulerTemporalSlopeIsOne) {
  MaterialSpec spec;
  spec.conductivity = PropertyTable({20.0, 1020.0}, {30.0, 50.0});
  spec.specific_heat = PropertyTable({20.0, 1020.0}, {500.0, 800.0});
  const auto metal = make_material(spec);
  const fem::Mesh mesh = test::block_mesh("column", 0, 0.25e-3, 0, 1e-3, 0.05e-3);
  physics::ThermalSettings ts = insulated(20.0);
  ts.air_htc = 5e4;
  ts.adiabatic_suffixes = {".axis", ".right", ".bottom"};  // convection on column.top only
  const std::vector<contact::InterfacePairing> none;
  const contact::ContactState contact{&none, {}};
  const double t_end = 0.02, q_0 = 4e10;  // W/m³ at t_end
  const auto run = [&](int n_steps) {
    physics::Thermal thermal(mesh, {&metal}, {}, ts);
    const double dt = t_end / n_steps;
    for (int i = 1; i <= n_steps; ++i) {
      const std::vector<double> source(4 * mesh.n_cells(), q_0 * i * dt / t_end);  // q(t_{n+1})
      const auto report = thermal.solve(dt, mesh.nodes, contact, source, {});
      EXPECT_TRUE(report.converged) << report.message;
      thermal.commit();
    }
    return Eigen::VectorXd(thermal.temperature());
  };
  const Eigen::VectorXd reference = run(160 * 16);
  std::vector<double> errors;
  for (int n_steps : {20, 40, 80, 160}) errors.push_back((run(n_steps) - reference).lpNorm<Eigen::Infinity>());
  std::printf("backward Euler: T(20 ms) - 20 degC = %.2f .. %.2f K; max errors for dt = 1, 0.5, 0.25, 0.125 ms: "
              "%.3e %.3e %.3e %.3e K; slopes",
              reference.minCoeff() - 20, reference.maxCoeff() - 20, errors[0], errors[1], errors[2], errors[3]);
  for (std::size_t i = 1; i < errors.size(); ++i) {
    const double slope = std::log2(errors[i - 1] / errors[i]);
    std::printf(" %.3f", slope);
    EXPECT_NEAR(slope, 1.0, 0.1);
  }
  std::printf("\n");
}

// Energy balance with latent heat, the λ_m switch and bonding: two DP1200 discs pressed
// together, heated by a current through them until the interface region melts, cooled
// by convection. In every step the electrical energy V I Δt equals the stored enthalpy
// change plus the heat removed (to the Newton tolerance: solved here to 10⁻⁶ K, so
// that the check sees the discretisation's conservation, not the default 10⁻⁴ K
// tolerance, which leaves up to ~M H' 10⁻⁴ K, a few 10⁻⁷ of a step's input), and the S/S
// points bond once both sides pass the solidus. Run with the paper's sharp λ_m switch
// and with a 20 K smoothing band: Newton converges in both.
TEST(ThermalVerification, EnergyIsConservedThroughMeltingAndBonding) {
  materials::MaterialLibrary library;
  const auto steel = library.load("DP1200");
  const double R = 0.5e-3, t = 0.5e-3, current = 800.0, dt = 0.5e-3;
  const fem::Mesh mesh = two_discs(R, t, 8);
  const contact::InterfaceProperties props{"ss_1_2", 1e-5, 2e-5, 1e-3, true};
  const contact::InterfaceModel model = contact::film_contact_model({props});
  const std::vector<const materials::Material*> mats{&steel, &steel};
  physics::ElectricalSettings es;
  es.current_boundary = "sheet_1.top";
  es.ground_boundary = "sheet_2.bottom";
  std::vector<contact::InterfacePairing> pairings;
  pairings.emplace_back(mesh, "ss_1_2", 2);
  const auto contact = fixed_contact(pairings, [](const std::string&, const fem::Point&) { return 50e6; });
  const Eigen::VectorXd volume = nodal_volume(mesh);

  for (const double band : {0.0, 20.0}) {
    physics::Electrical electrical(mesh, mats, model, es);
    physics::ThermalSettings ts;
    ts.air_htc = 2e3;  // on the rims and the end faces: a visible heat loss
    ts.adiabatic_suffixes = {".axis"};
    ts.melt_conductivity = 117.5;
    ts.melt_conductivity_band = band;
    ts.temperature_tolerance = 1e-6;
    physics::Thermal thermal(mesh, mats, model, ts);
    double electrical_energy = 0, stored = 0, removed = 0, worst = 0;
    int newton = 0, steps = 0;
    while (steps < 40) {
      for (int it = 0; it < 3; ++it) {
        const auto& sol = electrical.solve(mesh.nodes, thermal.temperature(), current, contact, thermal.interface_history());
        const auto report = thermal.solve(dt, mesh.nodes, contact, sol.joule_heat, sol.interface_heat);
        ASSERT_TRUE(report.converged) << "band " << band << " K, step " << steps << ": " << report.message;
        newton += report.iterations;
      }
      const double input = electrical.solution().voltage * current * dt;
      const auto& E = thermal.energy();
      worst = std::max(worst, std::abs(E.stored + E.removed() - input) / input);
      electrical_energy += input;
      stored += E.stored;
      removed += E.removed();
      thermal.commit();
      ++steps;
      if (thermal.liquid_fraction().maxCoeff() > 0.99 && thermal.interface_history().n_bonded(0) > 4) break;
    }
    const Eigen::VectorXd f = thermal.liquid_fraction();
    const double latent = steel.density(20).value * steel.latent_heat() * volume.dot(f);
    std::printf("melting discs (lambda_m band %.0f K): %d steps of 0.5 ms, %.2f Newton iterations per thermal solve; "
                "int V I dt = %.4f J, stored %.4f J (latent %.4f J), removed %.4f J, worst step imbalance %.1e; "
                "%d of %zu S/S points bonded, peak T %.1f degC\n",
                band, steps, double(newton) / (3 * steps), electrical_energy, stored, latent, removed, worst,
                thermal.interface_history().n_bonded(0), pairings[0].points().size(), thermal.peak_temperature().maxCoeff());
    EXPECT_LT(worst, 1e-7);
    EXPECT_NEAR(stored + removed, electrical_energy, 1e-8 * electrical_energy);
    EXPECT_GT(f.maxCoeff(), 0.99);
    EXPECT_GT(thermal.interface_history().n_bonded(0), 0);
    EXPECT_GT(latent, 0.05 * stored);
  }
}

// A broken film stays broken: two DP1200 discs with a resistive S/S film held at
// uniform temperatures step by step. The committed breakdown degree of every paired
// point follows φ of the hottest state so far (S(1/2) = 1/2 at 360 °C over the
// default 20–700 °C band) and keeps it when the discs are colder again; with φ = 1 the
// interface conducts current like a law without the coating term at the same state.
TEST(ThermalVerification, FilmBreakdownFollowsTheHottestStateAndStaysOnCooling) {
  materials::MaterialLibrary library;
  const auto steel = library.load("DP1200");
  const double R = 0.5e-3, t = 0.5e-3;
  const fem::Mesh mesh = two_discs(R, t, 4);
  const contact::InterfaceProperties film{"ss_1_2", 1e-5, 2e-5, 1e-3, false};
  contact::InterfaceProperties bare = film;
  bare.coating_resistivity = 0;
  const std::vector<const materials::Material*> mats{&steel, &steel};
  std::vector<contact::InterfacePairing> pairings;
  pairings.emplace_back(mesh, "ss_1_2", 2);
  const auto contact = fixed_contact(pairings, [](const std::string&, const fem::Point&) { return 50e6; });
  physics::Thermal thermal(mesh, mats, contact::film_contact_model({film}), insulated(20.0));
  const std::vector<double> no_heat(4 * mesh.n_cells(), 0.0);
  const int n = static_cast<int>(pairings[0].points().size());
  const auto hold = [&](double T) {
    thermal.set_temperature(Eigen::VectorXd::Constant(mesh.n_nodes(), T));
    const auto report = thermal.solve(0.5e-3, mesh.nodes, contact, no_heat, {});
    ASSERT_TRUE(report.converged) << report.message;
    thermal.commit();
  };
  const auto expect_degree = [&](double phi, const char* when) {
    for (int i = 0; i < n; ++i) {
      if (!pairings[0].points()[i].paired) continue;
      EXPECT_NEAR(thermal.interface_history().breakdown(0, i), phi, 1e-12) << when;
    }
  };
  hold(20.0);
  expect_degree(0.0, "cold");
  hold(360.0);
  expect_degree(0.5, "at 360 degC");
  hold(200.0);
  expect_degree(0.5, "cooled to 200 degC");
  hold(900.0);
  expect_degree(1.0, "at 900 degC");
  hold(20.0);
  expect_degree(1.0, "cooled to 20 degC");

  physics::ElectricalSettings es;
  es.current_boundary = "sheet_1.top";
  es.ground_boundary = "sheet_2.bottom";
  physics::Electrical with_film(mesh, mats, contact::film_contact_model({film}), es);
  physics::Electrical without_film(mesh, mats, contact::film_contact_model({bare}), es);
  const auto broken = with_film.solve(mesh.nodes, thermal.temperature(), 800.0, contact, thermal.interface_history())
                          .interface_conductance;
  const auto expected = without_film.solve(mesh.nodes, thermal.temperature(), 800.0, contact).interface_conductance;
  const auto intact = with_film.solve(mesh.nodes, thermal.temperature(), 800.0, contact).interface_conductance;
  for (int i = 0; i < n; ++i) {
    if (!pairings[0].points()[i].paired) continue;
    EXPECT_NEAR(broken[0][i], expected[0][i], 1e-12 * expected[0][i]) << i;
    EXPECT_LT(intact[0][i], 0.5 * expected[0][i]) << i;  // the intact film dominates at 20 degC
  }
}

// The Newton tangent equals central differences of the residual, column by column,
// on two DP1200 discs part molten (nodes inside the melting range, where H' is steep),
// with interface conduction, Joule sources and convection.
TEST(ThermalNewton, TangentMatchesFiniteDifferences) {
  materials::MaterialLibrary library;
  const auto steel = library.load("DP1200");
  const double R = 0.5e-3, t = 0.5e-3;
  const fem::Mesh mesh = two_discs(R, t, 4);
  const contact::InterfaceProperties props{"ss_1_2", 1e-5, 2e-5, 1e-3, true};
  const contact::InterfaceModel model = contact::film_contact_model({props});
  physics::ThermalSettings ts;
  ts.air_htc = 2e3;
  ts.melt_conductivity = 117.5;
  ts.melt_conductivity_band = 20;
  physics::Thermal thermal(mesh, {&steel, &steel}, model, ts);
  std::vector<contact::InterfacePairing> pairings;
  pairings.emplace_back(mesh, "ss_1_2", 2);
  const auto contact = fixed_contact(pairings, [](const std::string&, const fem::Point&) { return 50e6; });
  const std::vector<double> joule(4 * mesh.n_cells(), 1e12);
  const std::vector<std::vector<double>> interface_heat{std::vector<double>(pairings[0].points().size(), 1e8)};
  // A field across the melting range, 1437 to 1549 °C, no node at a kink of H' (the ends
  // of the melting range).
  Eigen::VectorXd T(mesh.n_nodes());
  for (int n = 0; n < mesh.n_nodes(); ++n) T[n] = 1541.3 - 97.1 * mesh.nodes[n].x() / R + 7.3 * mesh.nodes[n].y() / t;
  const Eigen::VectorXd y = thermal.free_values(T);
  Eigen::VectorXd residual, plus, minus;
  Eigen::SparseMatrix<double> tangent, unused;
  thermal.residual_and_tangent(1e-3, mesh.nodes, contact, joule, interface_heat, T, y, residual, tangent);
  const Eigen::MatrixXd K(tangent);
  double worst = 0;
  const double d = 1e-3;  // K
  for (Eigen::Index j = 0; j < y.size(); ++j) {
    Eigen::VectorXd yp = y, ym = y;
    yp[j] += d;
    ym[j] -= d;
    thermal.residual_and_tangent(1e-3, mesh.nodes, contact, joule, interface_heat, T, yp, plus, unused);
    thermal.residual_and_tangent(1e-3, mesh.nodes, contact, joule, interface_heat, T, ym, minus, unused);
    const Eigen::VectorXd fd = (plus - minus) / (2 * d);
    worst = std::max(worst, (fd - K.col(j)).lpNorm<Eigen::Infinity>() / K.col(j).lpNorm<Eigen::Infinity>());
  }
  std::printf("thermal tangent: %ld columns, largest relative difference to central differences %.2e\n",
              static_cast<long>(y.size()), worst);
  EXPECT_LT(worst, 1e-6);
}

// Paper eq. 3: in a body named "sheet_*" k = λ_m at and above T_melting; other bodies
// keep their table. A column held at 1600 °C at its foot, insulated elsewhere, with a
// uniform source q: at steady state T(z) = T_b + q (2Lz − z²)/(2k), nodally exact for
// this 1-D problem, everywhere above T_melting = 1500 °C.
TEST(ThermalVerification, MeltConductivityReplacesTableAboveMeltingTemperature) {
  const MaterialSpec spec = melting_spec();
  const auto metal = make_material(spec);
  const double L = 1e-3, q = 1e10, T_b = 1600, lambda_m = 100;
  const std::vector<contact::InterfacePairing> none;
  const contact::ContactState contact{&none, {}};
  for (const std::string body : {"sheet_1", "electrode"}) {
    const fem::Mesh mesh = test::block_mesh(body, 0, 0.2e-3, 0, L, 0.05e-3);
    physics::ThermalSettings ts = insulated(T_b);
    ts.fixed_temperatures = {{body + ".bottom", T_b}};
    ts.melt_conductivity = lambda_m;
    physics::Thermal thermal(mesh, {&metal}, {}, ts);
    const std::vector<double> source(4 * mesh.n_cells(), q);
    for (int step = 0; step < 3; ++step) {
      const auto report = thermal.solve(1e4, mesh.nodes, contact, source, {});
      ASSERT_TRUE(report.converged) << report.message;
      thermal.commit();
    }
    const double k = body == "sheet_1" ? lambda_m : 30.0;
    double worst = 0;
    for (int n = 0; n < mesh.n_nodes(); ++n) {
      const double z = mesh.nodes[n].y();
      worst = std::max(worst, std::abs(thermal.temperature()[n] - (T_b + q * (2 * L * z - z * z) / (2 * k))));
    }
    std::printf("melt conductivity, body %-9s: top %.4f degC, closed form with k = %.1f: %.4f degC, max error %.1e K\n",
                body.c_str(), thermal.temperature().maxCoeff(), k, T_b + q * L * L / (2 * k), worst);
    EXPECT_LT(worst, 1e-6);
  }
}

// The λ_m blend is solved implicitly, in nodal Kirchhoff form: a column of a "sheet_"
// body held at 1460 °C at its foot and 1540 °C at its top, k = 30 W/(m·K) below the
// band [1480, 1500] °C and λ_m = 100 above it. At steady state the Kirchhoff variable
// U(T) = ∫ k dT is linear in z, and a conduction-only 1-D problem is nodally exact in
// U, so T(z) = U⁻¹(U(T_b) + (U(T_t) − U(T_b)) z/L). U is integrated here numerically
// (Simpson) from the smoothstep blend. One solve (dt = 10⁸ s, steady) must reach it from a start
// below the band and from one above it: the blend follows the iterate, so the solve
// does not depend on the field it starts from (a blend lagged at the start field gives
// the linear profile of k = 30 from below).
TEST(ThermalVerification, MeltBlendIsImplicitAndNodallyExactInKirchhoffForm) {
  const MaterialSpec spec = melting_spec();
  const auto metal = make_material(spec);
  const double L = 1e-3, T_b = 1460, T_t = 1540, lambda_m = 100, band = 20;
  auto k = [&](double tau) {
    const double x = std::clamp((tau - (spec.melting_temperature - band)) / band, 0.0, 1.0);
    return 30.0 + x * x * (3 - 2 * x) * (lambda_m - 30.0);
  };
  auto U = [&](double T) {  // ∫_{T_b}^{T} k dτ, composite Simpson on 2000 intervals
    const int n = 2000;
    const double h = (T - T_b) / n;
    double sum = k(T_b) + k(T);
    for (int i = 1; i < n; ++i) sum += (i % 2 ? 4 : 2) * k(T_b + i * h);
    return sum * h / 3;
  };
  const double U_t = U(T_t);
  const std::vector<contact::InterfacePairing> none;
  const contact::ContactState contact{&none, {}};
  const fem::Mesh mesh = test::block_mesh("sheet_1", 0, 0.2e-3, 0, L, 0.05e-3);
  for (const double start : {1400.0, 1600.0}) {
    physics::ThermalSettings ts = insulated(start);
    ts.fixed_temperatures = {{"sheet_1.bottom", T_b}, {"sheet_1.top", T_t}};
    ts.melt_conductivity = lambda_m;
    ts.melt_conductivity_band = band;
    ts.temperature_tolerance = 1e-9;
    physics::Thermal thermal(mesh, {&metal}, {}, ts);
    const auto report = thermal.solve(1e8, mesh.nodes, contact, {}, {});
    ASSERT_TRUE(report.converged) << report.message;
    double worst = 0;
    for (int n = 0; n < mesh.n_nodes(); ++n) {
      const double target = U_t * mesh.nodes[n].y() / L;
      double lo = T_b, hi = T_t;  // bisection on the increasing U
      for (int it = 0; it < 60; ++it) (U(0.5 * (lo + hi)) < target ? lo : hi) = 0.5 * (lo + hi);
      worst = std::max(worst, std::abs(thermal.temperature()[n] - 0.5 * (lo + hi)));
    }
    std::printf("implicit lambda_m blend, start %.0f degC: %d Newton iterations, max nodal error %.1e K\n", start,
                report.iterations, worst);
    EXPECT_LT(worst, 1e-6);
  }
}

// The default weld stack with a fixed contact state and a hot, partly molten core:
// five 1 ms steps of staggered electrical/thermal coupling with the λ_m switch. Prints
// the solve times (the budget of a whole weld is ~20 s for ~160 steps including
// mechanics) and checks convergence and the energy balance of every step.
TEST(ThermalPerformance, WeldStackStepsConvergeAndBalanceEnergy) {
  const physics::Problem problem =
      physics::load_problem(std::string(RSW_SOURCE_DIR) + "/validation/paper_case/weld.yaml");
  const fem::Mesh mesh = meshes::weld_mesh(problem.geometry, problem.mesh);
  materials::MaterialLibrary library;
  const auto copper = library.load("CuCrZr");
  const auto steel = library.load("DP1200");
  const std::vector<const materials::Material*> mats{&copper, &steel, &steel, &copper};
  const auto model = physics::interface_model(mesh, problem.contact);
  physics::Electrical electrical(mesh, mats, model);
  physics::Thermal thermal(mesh, mats, model, physics::thermal_settings(problem.thermal));
  std::vector<contact::InterfacePairing> pairings;
  for (const auto& [name, pair] : mesh.interfaces) pairings.emplace_back(mesh, name, 2);
  const auto contact = fixed_contact(pairings, [&mesh](const std::string& name, const fem::Point& x) {
    const double a = mesh.interfaces.at(name).kind == meshes::interface_kind::electrode_sheet ? 2.5e-3 : 3e-3;
    return 300e6 * std::max(0.0, 1 - std::pow(x.x() / a, 2));
  });
  Eigen::VectorXd T(mesh.n_nodes());
  for (int n = 0; n < mesh.n_nodes(); ++n) {
    const double hot = mesh.node_body[n] == 1 || mesh.node_body[n] == 2 ? 1580.0 : 300.0;
    T[n] = 20 + hot * std::exp(-mesh.nodes[n].squaredNorm() / (1.5e-3 * 1.5e-3));
  }
  thermal.set_temperature(T);

  double t_electrical = 0, t_thermal = 0;
  int n_electrical = 0, n_thermal = 0, newton = 0, factorizations = 0;
  double worst = 0;
  for (int step = 0; step < 5; ++step) {
    for (int it = 0; it < 3; ++it) {
      auto t0 = std::chrono::steady_clock::now();
      const auto& sol = electrical.solve(mesh.nodes, thermal.temperature(), 8e3, contact, thermal.interface_history());
      auto t1 = std::chrono::steady_clock::now();
      const auto report = thermal.solve(1e-3, mesh.nodes, contact, sol.joule_heat, sol.interface_heat);
      auto t2 = std::chrono::steady_clock::now();
      ASSERT_TRUE(report.converged) << "step " << step << ": " << report.message;
      t_electrical += std::chrono::duration<double, std::milli>(t1 - t0).count();
      t_thermal += std::chrono::duration<double, std::milli>(t2 - t1).count();
      ++n_electrical;
      ++n_thermal;
      newton += report.iterations;
      factorizations += report.factorizations;
    }
    const double input = electrical.solution().voltage * 8e3 * 1e-3;
    const auto& E = thermal.energy();
    worst = std::max(worst, std::abs(E.stored + E.removed() - input) / input);
    thermal.commit();
  }
  std::printf("weld stack: electrical solve %.1f ms, thermal solve %.1f ms (%.2f Newton iterations, %.2f "
              "factorisations); R = %.1f uohm, peak T %.0f degC, %d S/S points bonded, worst step energy imbalance "
              "%.1e\n",
              t_electrical / n_electrical, t_thermal / n_thermal, double(newton) / n_thermal,
              double(factorizations) / n_thermal,
              electrical.solution().resistance * 1e6, thermal.peak_temperature().maxCoeff(),
              thermal.interface_history().n_bonded(2), worst);
  EXPECT_LT(worst, 1e-7);
}
