// J2 return mapping on single points along prescribed strain paths
// (docs/VERIFICATION.md, "Physics"): Hooke's law
// below yield from hand-computed Lame constants, the yield condition and normality
// along a load-unload-reverse path, the consistent tangent and the temperature
// derivative of the stress against central differences, uniaxial stress against the
// closed form for linear hardening and against the flow curve, no stress from free
// thermal expansion, and the viscous overstress (Perzyna, exponent 1): the closed-form
// return of one step, the relaxation of a held strain at the rate 3G/eta, and the
// tangent and temperature derivative with the overstress on; coefficients evaluated once
// per temperature and committed state give the same update to the bit.
#include "materials/j2_plasticity.hpp"
#include "materials/material_library.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace rsw::materials {
namespace {

// Properties every material needs but these tests do not look at.
MaterialData base_data(const std::string& name) {
  MaterialData data;
  data.name = name;
  data.electrical_resistivity = PropertyTable::constant(2e-7);
  data.thermal_conductivity = PropertyTable::constant(30);
  data.specific_heat = PropertyTable::constant(500);
  data.density = PropertyTable::constant(7800);
  data.secant_expansion = PropertyTable::constant(1.2e-5);
  data.solidus = 1450;
  data.liquidus = 1500;
  data.melting_temperature = 1480;
  data.latent_heat = 2.7e5;
  data.strength_floor = 1e6;
  return data;
}

// E = 200 GPa, nu = 0.25 (Lame lambda = mu = 80 GPa), sigma_y = 300 MPa + 2000 MPa eps_p.
Material linear_hardening_material() {
  MaterialData data = base_data("linear_hardening");
  data.youngs_modulus = PropertyTable::constant(200e9);
  data.poisson_ratio = PropertyTable::constant(0.25);
  data.flow_curves = FlowCurveTable({{20.0, {0.0, 10.0}, {300e6, 300e6 + 2000e6 * 10.0}}});
  return Material(data);
}

// Everything varies with T between 20 and 1000 degC.
Material temperature_dependent_material() {
  MaterialData data = base_data("temperature_dependent");
  data.youngs_modulus = PropertyTable({20.0, 1000.0}, {200e9, 100e9});
  data.poisson_ratio = PropertyTable({20.0, 1000.0}, {0.28, 0.36});
  data.secant_expansion = PropertyTable({20.0, 1000.0}, {1.2e-5, 1.5e-5});
  data.flow_curves = FlowCurveTable({{20.0, {0.0, 1.0}, {400e6, 2400e6}},
                                     {1000.0, {0.0, 1.0}, {100e6, 600e6}}});
  return Material(data);
}

Material dp1200() { return MaterialLibrary({RSW_MATERIALS_DIR}).load("DP1200"); }

// Strain measured from a stress-free state at 20 degC.
J2Input input_at(const Material& material, const MandelVector& strain, double temperature) {
  return j2_input(material, strain, temperature, 20.0);
}

double relative_error(const MandelMatrix& approximate, const MandelMatrix& exact) {
  return (approximate - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff();
}

double relative_error(const MandelVector& approximate, const MandelVector& exact) {
  return (approximate - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff();
}

MandelMatrix tangent_by_central_differences(const Material& material, const J2State& state,
                                            const J2Input& input, double step) {
  MandelMatrix tangent;
  for (int j = 0; j < 4; ++j) {
    J2Input plus = input;
    J2Input minus = input;
    plus.strain[j] += step;
    minus.strain[j] -= step;
    tangent.col(j) = (j2_update(material, state, plus).stress -
                      j2_update(material, state, minus).stress) / (2 * step);
  }
  return tangent;
}

MandelVector temperature_slope_by_central_differences(const Material& material,
                                                      const J2State& state,
                                                      const MandelVector& strain,
                                                      double temperature, double step,
                                                      double time_step = 0) {
  J2Input plus = input_at(material, strain, temperature + step);
  J2Input minus = input_at(material, strain, temperature - step);
  plus.time_step = minus.time_step = time_step;
  return (j2_update(material, state, plus).stress - j2_update(material, state, minus).stress) /
         (2 * step);
}

// E = 200 GPa, nu = 0.25 (G = 80 GPa), sigma_y = 300 MPa + H eps_p, viscosity eta.
Material viscous_material(double hardening, double viscosity) {
  MaterialData data = base_data("viscous");
  data.youngs_modulus = PropertyTable::constant(200e9);
  data.poisson_ratio = PropertyTable::constant(0.25);
  data.flow_viscosity = PropertyTable::constant(viscosity);
  data.flow_curves = FlowCurveTable({{20.0, {0.0, 10.0}, {300e6, 300e6 + hardening * 10.0}}});
  return Material(data);
}

// Distance of eps_bar_p from the nearest strain point of the curves bracketing T, so
// that a finite-difference test can make sure it does not straddle a kink.
double distance_to_strain_point(const Material& material, double strain) {
  double distance = 1e300;
  for (const FlowCurve& curve : material.data().flow_curves.curves()) {
    for (double point : curve.plastic_strain) {
      distance = std::min(distance, std::abs(strain - point));
    }
  }
  return distance;
}

TEST(J2, ElasticStepBelowYieldIsHookean) {
  const Material material = linear_hardening_material();
  // eps_rr = 1e-4, eps_zz = -2e-4, eps_tt = 0.5e-4, eps_rz = 0.3e-4; tr = -0.5e-4.
  const MandelVector strain = to_mandel(1e-4, -2e-4, 0.5e-4, 0.3e-4);
  const J2Result result = j2_update(material, J2State{}, input_at(material, strain, 20));
  EXPECT_FALSE(result.yielded);
  // sigma = lambda tr 1 + 2 mu eps with lambda = mu = 80 GPa:
  //   rr: -4 + 16 = 12 MPa; zz: -4 - 32 = -36 MPa; tt: -4 + 8 = 4 MPa; rz: 4.8 MPa.
  EXPECT_NEAR(result.stress[0], 12e6, 1e-3);
  EXPECT_NEAR(result.stress[1], -36e6, 1e-3);
  EXPECT_NEAR(result.stress[2], 4e6, 1e-3);
  EXPECT_NEAR(shear_component(result.stress), 4.8e6, 1e-3);
  // Tangent = elasticity matrix: lambda + 2 mu on the diagonal, lambda off it, 2 mu
  // for the Mandel shear entry.
  MandelMatrix elasticity = MandelMatrix::Zero();
  elasticity.topLeftCorner<3, 3>().setConstant(80e9);
  elasticity.topLeftCorner<3, 3>().diagonal().setConstant(240e9);
  elasticity(3, 3) = 160e9;
  EXPECT_LT(relative_error(result.tangent, elasticity), 1e-14);
  EXPECT_DOUBLE_EQ(result.state.equivalent_plastic_strain, 0.0);
  EXPECT_TRUE(result.state.plastic_strain.isZero(0));
  // Constant moduli and expansion coefficient: the stress still changes with T through
  // the thermal strain only, by -3 K alpha per kelvin (K = 400/3 GPa).
  EXPECT_NEAR(result.stress_temperature_derivative[0], -3 * (400e9 / 3) * 1.2e-5, 1e-6);
  EXPECT_NEAR(result.stress_temperature_derivative[3], 0.0, 1e-9);
}

void check_path(const Material& material, double temperature) {
  SCOPED_TRACE(material.name() + " at " + std::to_string(temperature) + " degC");
  const double yield_0 = material.yield_stress(0, temperature).yield_stress;
  const ElasticModuli moduli = elastic_moduli(material, temperature);
  // A mixed direction (normal, hoop, shear, some volume change) scaled so that 60 steps
  // reach about six times the yield strain, then unload to zero and reverse.
  const MandelVector direction = to_mandel(1.0, -0.6, -0.2, 0.5) + 0.1 * mandel_identity();
  const double yield_strain = yield_0 / (2 * moduli.shear_modulus);
  const MandelVector step = direction / direction.norm() * (6 * yield_strain / 60);
  std::vector<double> multipliers;
  for (int k = 0; k <= 60; ++k) multipliers.push_back(k);
  for (int k = 59; k >= -40; --k) multipliers.push_back(k);

  J2State committed;
  int n_plastic_loading = 0;
  int n_plastic_reverse = 0;
  for (std::size_t i = 0; i < multipliers.size(); ++i) {
    const MandelVector strain = multipliers[i] * step;
    const J2Result r = j2_update(material, committed, input_at(material, strain, temperature));
    const double yield = material.yield_stress(r.state.equivalent_plastic_strain, temperature)
                             .yield_stress;
    EXPECT_LE(r.equivalent_stress, yield * (1 + 1e-10)) << "step " << i;
    EXPECT_NEAR(von_mises_stress(r.stress), r.equivalent_stress, 1e-9 * yield);
    const MandelVector plastic_increment = r.state.plastic_strain - committed.plastic_strain;
    if (r.yielded) {
      EXPECT_NEAR(r.equivalent_stress, yield, 1e-10 * yield) << "step " << i;
      EXPECT_GT(r.plastic_increment, 0.0);
      EXPECT_DOUBLE_EQ(r.state.equivalent_plastic_strain,
                       committed.equivalent_plastic_strain + r.plastic_increment);
      // Plastic flow is isochoric, of length sqrt(3/2) d eps_bar_p, along dev(sigma).
      EXPECT_NEAR(trace(plastic_increment), 0.0, 1e-15);
      EXPECT_NEAR(plastic_increment.norm(), std::sqrt(1.5) * r.plastic_increment,
                  1e-12 * r.plastic_increment);
      const MandelVector deviatoric = deviator(r.stress);
      EXPECT_NEAR(plastic_increment.dot(deviatoric) /
                      (plastic_increment.norm() * deviatoric.norm()),
                  1.0, 1e-12);
      if (i <= 60) ++n_plastic_loading;
      if (multipliers[i] < 0) ++n_plastic_reverse;
    } else {
      EXPECT_EQ(r.state.equivalent_plastic_strain, committed.equivalent_plastic_strain);
      EXPECT_TRUE(plastic_increment.isZero(0));
    }
    if (i == 61) {
      EXPECT_FALSE(r.yielded) << "the first unloading step must be elastic";
    }
    committed = r.state;
  }
  EXPECT_GT(n_plastic_loading, 40);
  EXPECT_GT(n_plastic_reverse, 5);
}

TEST(J2, YieldConditionHoldsAfterReturn) {
  check_path(linear_hardening_material(), 20);
  const Material steel = dp1200();
  check_path(steel, 20);    // nonlinear hardening (piecewise-linear flow curve)
  check_path(steel, 650);   // between flow curves
  check_path(steel, 1445);  // inside the blend to the strength floor
  check_path(steel, 1490);  // at the floor: perfectly plastic, sigma_y = 5 MPa
}

TEST(J2, ConsistentTangentMatchesFiniteDifferences) {
  const double h = 1e-8;
  const Material linear = linear_hardening_material();
  const Material steel = dp1200();

  // Elastic regime.
  {
    const J2Input input = input_at(steel, to_mandel(2e-4, -1e-4, 0.5e-4, 1e-4), 300);
    const J2Result r = j2_update(steel, J2State{}, input);
    ASSERT_FALSE(r.yielded);
    EXPECT_LT(relative_error(tangent_by_central_differences(steel, J2State{}, input, h),
                             r.tangent), 1e-6);
  }
  // Plastic regimes, each from a committed state that already carries plastic strain.
  struct Case {
    const Material* material;
    double temperature;
    MandelVector first;   // strain of the step that creates the committed state
    MandelVector second;  // strain of the step whose tangent is checked
  };
  const MandelVector uniaxial_like = to_mandel(-0.5, 1.0, -0.5, 0.0);
  const std::vector<Case> cases = {
      {&linear, 20, 0.004 * uniaxial_like, 0.006 * uniaxial_like + to_mandel(1e-3, 0, -5e-4, 2e-3)},
      {&steel, 20, 0.012 * uniaxial_like,
       0.035 * uniaxial_like + to_mandel(2e-3, 1e-3, -1e-3, 4e-3)},
      {&steel, 650, 0.01 * uniaxial_like, 0.02 * uniaxial_like + to_mandel(0, 2e-3, 0, 3e-3)},
      {&steel, 1445, 0.01 * uniaxial_like, 0.015 * uniaxial_like + to_mandel(1e-3, 0, 0, 1e-3)},
      {&steel, 1490, 0.01 * uniaxial_like, 0.015 * uniaxial_like + to_mandel(1e-3, 0, 0, 1e-3)},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.material->name() + " at " + std::to_string(c.temperature) + " degC");
    const J2State committed =
        j2_update(*c.material, J2State{}, input_at(*c.material, c.first, c.temperature)).state;
    ASSERT_GT(committed.equivalent_plastic_strain, 0.0);
    const J2Input input = input_at(*c.material, c.second, c.temperature);
    const J2Result r = j2_update(*c.material, committed, input);
    ASSERT_TRUE(r.yielded);
    // The finite differences must not straddle a kink of the flow curve.
    ASSERT_GT(distance_to_strain_point(*c.material, r.state.equivalent_plastic_strain), 1e-5);
    EXPECT_LT(relative_error(tangent_by_central_differences(*c.material, committed, input, h),
                             r.tangent), 1e-6);
    // The consistent tangent is symmetric (associative flow).
    EXPECT_LT(relative_error(r.tangent.transpose(), r.tangent), 1e-14);
  }
}

// Strain with sigma_rr = sigma_tt = sigma_rz = 0 for a given eps_zz: Newton on the two
// lateral strains with the consistent tangent.
J2Result uniaxial_step(const Material& material, const J2State& committed, double axial_strain,
                       double temperature, double& lateral_rr, double& lateral_tt) {
  J2Result r;
  for (int iteration = 0; iteration < 50; ++iteration) {
    // Isothermal test: stress free at the test temperature, no thermal strain.
    r = j2_update(material, committed,
                  j2_input(material, to_mandel(lateral_rr, axial_strain, lateral_tt, 0.0),
                           temperature, temperature));
    const Eigen::Vector2d residual(r.stress[0], r.stress[2]);
    if (residual.norm() <= 1e-12 * std::abs(r.stress[1]) + 1e-6) return r;
    Eigen::Matrix2d jacobian;
    jacobian << r.tangent(0, 0), r.tangent(0, 2), r.tangent(2, 0), r.tangent(2, 2);
    const Eigen::Vector2d correction = jacobian.lu().solve(residual);
    lateral_rr -= correction[0];
    lateral_tt -= correction[1];
  }
  ADD_FAILURE() << "lateral strains did not converge at eps_zz = " << axial_strain;
  return r;
}

TEST(J2, UniaxialStressMatchesFlowCurve) {
  // Linear hardening, closed form: sigma = E (eps - eps_p) = sigma_0 + H eps_p gives
  // eps_p = (E eps - sigma_0) / (E + H) once eps > sigma_0 / E = 1.5e-3.
  {
    const Material material = linear_hardening_material();
    const double e = 200e9, sigma_0 = 300e6, hardening = 2000e6, nu = 0.25;
    J2State committed;
    double rr = 0, tt = 0;
    for (int k = 1; k <= 50; ++k) {
      const double axial = 2e-4 * k;
      const J2Result r = uniaxial_step(material, committed, axial, 20, rr, tt);
      committed = r.state;
      const double plastic = std::max(0.0, (e * axial - sigma_0) / (e + hardening));
      const double stress = plastic > 0 ? sigma_0 + hardening * plastic : e * axial;
      EXPECT_NEAR(r.state.equivalent_plastic_strain, plastic, 1e-12) << "eps_zz " << axial;
      EXPECT_NEAR(r.stress[1], stress, 1e-6 * stress) << "eps_zz " << axial;
      // Lateral contraction: elastic -nu sigma/E plus plastic -eps_p/2.
      EXPECT_NEAR(rr, -nu * stress / e - 0.5 * plastic, 1e-11);
      EXPECT_NEAR(tt, rr, 1e-14);
    }
  }
  // DP1200 at 20 and 800 degC: the axial stress is the flow curve at the reached
  // eps_bar_p, and eps_bar_p is the axial plastic strain.
  const Material steel = dp1200();
  for (double temperature : {20.0, 800.0}) {
    J2State committed;
    double rr = 0, tt = 0;
    int n_plastic = 0;
    for (int k = 1; k <= 100; ++k) {
      const double axial = 1e-3 * k;
      const J2Result r = uniaxial_step(steel, committed, axial, temperature, rr, tt);
      committed = r.state;
      const double eps_bar = r.state.equivalent_plastic_strain;
      const double flow = steel.yield_stress(eps_bar, temperature).yield_stress;
      if (eps_bar > 0) {
        ++n_plastic;
        EXPECT_NEAR(r.stress[1], flow, 1e-9 * flow) << "eps_zz " << axial;
        EXPECT_NEAR(r.state.plastic_strain[1], eps_bar, 1e-12);
        EXPECT_NEAR(r.state.plastic_strain[0], -0.5 * eps_bar, 1e-12);
      } else {
        EXPECT_LE(r.stress[1], flow);
      }
    }
    EXPECT_GT(n_plastic, 90) << temperature;
  }
}

TEST(J2, ThermalStrainAloneGivesNoStressWhenFree) {
  const Material steel = dp1200();
  for (double temperature : {20.0, 350.0, 950.0, 1480.0}) {
    SCOPED_TRACE(temperature);
    const double thermal = steel.thermal_strain(temperature, 20).value;
    // Virgin point, free expansion.
    J2Result r = j2_update(steel, J2State{},
                           input_at(steel, thermal * mandel_identity(), temperature));
    EXPECT_FALSE(r.yielded);
    EXPECT_LT(r.stress.cwiseAbs().maxCoeff(), 1e-3);
    // After plastic deformation, free expansion on top of the plastic strain.
    const J2State deformed =
        j2_update(steel, J2State{}, input_at(steel, 0.02 * to_mandel(-0.5, 1, -0.5, 0), 20)).state;
    ASSERT_GT(deformed.equivalent_plastic_strain, 0.0);
    r = j2_update(steel, deformed,
                  input_at(steel, deformed.plastic_strain + thermal * mandel_identity(),
                           temperature));
    EXPECT_FALSE(r.yielded);
    EXPECT_LT(r.stress.cwiseAbs().maxCoeff(), 1e-3);
    // With no elastic strain, heating at fixed strain builds pressure at -3 K eps_th'.
    const double bulk = elastic_moduli(steel, temperature).bulk_modulus;
    const double expected = -3 * bulk * steel.thermal_strain(temperature, 20).slope;
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(r.stress_temperature_derivative[i], expected, 1e-12 * std::abs(expected));
    }
    EXPECT_NEAR(r.stress_temperature_derivative[3], 0.0, 1e-9);
  }
}

TEST(J2, StressTemperatureDerivativeMatchesFiniteDifference) {
  const double h = 1e-3;
  const Material smooth = temperature_dependent_material();
  const Material steel = dp1200();
  struct Case {
    const Material* material;
    double temperature;
    MandelVector strain;
    bool plastic;
  };
  const MandelVector uniaxial_like = to_mandel(-0.5, 1.0, -0.5, 0.0);
  const std::vector<Case> cases = {
      {&smooth, 500, to_mandel(4e-4, -3e-4, 1e-4, 2e-4), false},
      {&smooth, 500, 0.02 * uniaxial_like + to_mandel(1e-3, 0, 0, 2e-3), true},
      {&steel, 550, to_mandel(5e-4, -2e-4, 1e-4, 1e-4), false},
      {&steel, 550, 0.03 * uniaxial_like + to_mandel(0, 1e-3, 0, 2e-3), true},
      {&steel, 1445, 0.01 * uniaxial_like, true},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.material->name() + " at " + std::to_string(c.temperature) + " degC");
    const J2State committed;
    const J2Result r = j2_update(*c.material, committed,
                                 input_at(*c.material, c.strain, c.temperature));
    ASSERT_EQ(r.yielded, c.plastic);
    const MandelVector difference = temperature_slope_by_central_differences(
        *c.material, committed, c.strain, c.temperature, h);
    EXPECT_LT(relative_error(difference, r.stress_temperature_derivative), 1e-6)
        << "analytic " << r.stress_temperature_derivative.transpose() << "\nfinite difference "
        << difference.transpose();
  }
}

// One step from the virgin state with a pure shear strain gamma (eps_rz = gamma/2):
// q_trial = sqrt(3) G gamma, and the return equation is linear,
//     dgamma = (q_trial - sigma_y0) / (3G + H + eta/dt),  q = q_trial - 3 G dgamma.
TEST(J2, ViscousOverstressMatchesClosedFormStep) {
  const double G = 80e9, H = 2000e6, eta = 2e6, dt = 1e-3, sigma_y0 = 300e6;
  const Material material = viscous_material(H, eta);
  const double gamma = 0.01;
  J2Input input = input_at(material, to_mandel(0, 0, 0, 0.5 * gamma), 20.0);
  input.time_step = dt;
  const J2Result r = j2_update(material, J2State{}, input);
  ASSERT_TRUE(r.yielded);
  const double q_trial = std::sqrt(3.0) * G * gamma;
  const double dgamma = (q_trial - sigma_y0) / (3 * G + H + eta / dt);
  EXPECT_NEAR(r.plastic_increment, dgamma, 1e-12 * dgamma);
  EXPECT_NEAR(r.equivalent_stress, q_trial - 3 * G * dgamma, 1e-9 * q_trial);
  // The overstress above the (static) flow stress is eta times the plastic rate.
  EXPECT_NEAR(r.equivalent_stress - r.yield_stress, eta * dgamma / dt, 1e-9 * q_trial);
  // dt = 0 is the rate-independent limit.
  input.time_step = 0;
  const J2Result rate_independent = j2_update(material, J2State{}, input);
  EXPECT_NEAR(rate_independent.plastic_increment, (q_trial - sigma_y0) / (3 * G + H), 1e-12 * dgamma);
}

// A strain held after a fast step: with perfect plasticity the plastic rate is
// (q - sigma_y)/eta and dq/dt = -3G (q - sigma_y)/eta, so the overstress relaxes as
// exp(-3 G t / eta); backward Euler gives the factor 1/(1 + 3 G dt/eta) per step
// exactly, and the exponential as dt -> 0 (first order).
TEST(J2, HeldStrainRelaxesAtTheViscousRate) {
  const double G = 80e9, eta = 4e6, sigma_y = 300e6;
  const Material material = viscous_material(0.0, eta);
  const MandelVector strain = to_mandel(0, 0, 0, 0.5 * 0.02);
  const double tau = eta / (3 * G);  // s, relaxation time
  const double total_time = 2 * tau;
  double previous_error = 0;
  for (int n : {20, 40, 80}) {
    const double dt = total_time / n;
    J2Input input = input_at(material, strain, 20.0);
    input.time_step = 1e-6;  // the fast step that loads the point
    J2Result r = j2_update(material, J2State{}, input);
    const double overstress0 = r.equivalent_stress - sigma_y;
    ASSERT_GT(overstress0, 10e6);
    input.time_step = dt;
    double overstress = overstress0;
    for (int k = 0; k < n; ++k) {
      r = j2_update(material, r.state, input);
      const double next = r.equivalent_stress - sigma_y;
      EXPECT_NEAR(next / overstress, 1 / (1 + 3 * G * dt / eta), 1e-9);
      overstress = next;
    }
    const double error = std::abs(overstress / overstress0 - std::exp(-total_time / tau));
    EXPECT_LT(error, 0.1);
    if (previous_error > 0) {
      EXPECT_NEAR(previous_error / error, 2.0, 0.2);  // first order
    }
    previous_error = error;
  }
}

TEST(J2, ViscousTangentAndTemperatureSlopeMatchFiniteDifferences) {
  const Material steel = dp1200();
  const MandelVector uniaxial_like = to_mandel(-0.5, 1.0, -0.5, 0.0);
  struct Case {
    double temperature;
    MandelVector first, second;
  };
  const std::vector<Case> cases = {
      {650, 0.01 * uniaxial_like, 0.02 * uniaxial_like + to_mandel(0, 2e-3, 0, 3e-3)},
      {1150, 0.01 * uniaxial_like, 0.015 * uniaxial_like + to_mandel(1e-3, 0, 0, 1e-3)},
      {1445, 0.01 * uniaxial_like, 0.015 * uniaxial_like + to_mandel(1e-3, 0, 0, 1e-3)},
      {1490, 0.01 * uniaxial_like, 0.015 * uniaxial_like + to_mandel(1e-3, 0, 0, 1e-3)},
  };
  const double dt = 1e-3;
  for (const Case& c : cases) {
    SCOPED_TRACE("DP1200 at " + std::to_string(c.temperature) + " degC");
    ASSERT_GT(steel.flow_viscosity(c.temperature).value, 0.0);
    J2Input first = input_at(steel, c.first, c.temperature);
    first.time_step = dt;
    const J2State committed = j2_update(steel, J2State{}, first).state;
    J2Input input = input_at(steel, c.second, c.temperature);
    input.time_step = dt;
    const J2Result r = j2_update(steel, committed, input);
    ASSERT_TRUE(r.yielded);
    // The overstress is there: more than the rate-independent return leaves.
    EXPECT_GT(r.equivalent_stress - r.yield_stress, 1e-3 * r.yield_stress);
    ASSERT_GT(distance_to_strain_point(steel, r.state.equivalent_plastic_strain), 1e-5);
    EXPECT_LT(relative_error(tangent_by_central_differences(steel, committed, input, 1e-8), r.tangent), 1e-6);
    const MandelVector slope =
        temperature_slope_by_central_differences(steel, committed, c.second, c.temperature, 1e-3, dt);
    EXPECT_LT(relative_error(slope, r.stress_temperature_derivative), 1e-6)
        << "analytic " << r.stress_temperature_derivative.transpose() << "\nfinite difference "
        << slope.transpose();
  }
}

// A caller that updates one point many times at one temperature and committed state
// (the Newton iterations of a mechanics step) evaluates the coefficients once; the
// update must not change by a bit, elastic or plastic, rate-independent or viscous.
TEST(J2, PrecomputedCoefficientsGiveTheSameUpdateToTheBit) {
  const Material steel = dp1200();
  const MandelVector uniaxial_like = to_mandel(-0.5, 1.0, -0.5, 0.0);
  for (double dt : {0.0, 1e-3}) {
    for (double temperature : {20.0, 650.0, 1150.0, 1490.0}) {
      SCOPED_TRACE("dt " + std::to_string(dt) + " s, " + std::to_string(temperature) + " degC");
      J2Input first = input_at(steel, 0.01 * uniaxial_like, temperature);
      first.time_step = dt;
      const J2State committed = j2_update(steel, J2State{}, first).state;
      const J2Coefficients coefficients = j2_coefficients(steel, committed, temperature, dt);
      for (double scale : {1e-5, 0.012, 0.02}) {
        J2Input input = input_at(steel, scale * uniaxial_like + to_mandel(1e-3, 0, 0, 1e-3), temperature);
        input.time_step = dt;
        const J2Result plain = j2_update(steel, committed, input);
        const J2Result cached = j2_update(steel, committed, input, coefficients);
        EXPECT_EQ(plain.yielded, cached.yielded);
        EXPECT_TRUE(plain.stress == cached.stress);
        EXPECT_TRUE(plain.tangent == cached.tangent);
        EXPECT_TRUE(plain.stress_temperature_derivative == cached.stress_temperature_derivative);
        EXPECT_EQ(plain.state.equivalent_plastic_strain, cached.state.equivalent_plastic_strain);
      }
    }
  }
}

}  // namespace
}  // namespace rsw::materials
