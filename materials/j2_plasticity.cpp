// Radial return for axisymmetric J2 plasticity in Mandel notation (equations and
// sources in j2_plasticity.hpp).
#include "materials/j2_plasticity.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rsw::materials {
namespace {

const double sqrt_two = std::sqrt(2.0);
const double sqrt_three_halves = std::sqrt(1.5);
const double sqrt_two_thirds = std::sqrt(2.0 / 3.0);

// Trial yield function below this fraction of sigma_y counts as elastic, so that a
// converged plastic state re-evaluated at the same strain stays elastic.
constexpr double yield_tolerance = 1e-10;
// The scalar return equation is solved to |r| <= this fraction of q_trial.
constexpr double return_tolerance = 1e-13;
constexpr int max_return_iterations = 200;

}  // namespace

MandelVector mandel_identity() { return MandelVector(1.0, 1.0, 1.0, 0.0); }

MandelMatrix deviatoric_projector() {
  const MandelVector one = mandel_identity();
  return MandelMatrix::Identity() - one * one.transpose() / 3.0;
}

MandelVector to_mandel(double rr, double zz, double theta_theta, double rz) {
  return MandelVector(rr, zz, theta_theta, sqrt_two * rz);
}

double shear_component(const MandelVector& v) { return v[3] / sqrt_two; }

double trace(const MandelVector& v) { return v[0] + v[1] + v[2]; }

MandelVector deviator(const MandelVector& v) {
  MandelVector d = v;
  const double mean = trace(v) / 3.0;
  d[0] -= mean;
  d[1] -= mean;
  d[2] -= mean;
  return d;
}

double von_mises_stress(const MandelVector& stress) {
  return sqrt_three_halves * deviator(stress).norm();
}

ElasticModuli elastic_moduli(const Material& material, double temperature) {
  const PropertyValue e = material.youngs_modulus(temperature);
  const PropertyValue nu = material.poisson_ratio(temperature);
  const double a = 1 - 2 * nu.value;
  const double b = 1 + nu.value;
  ElasticModuli m;
  m.bulk_modulus = e.value / (3 * a);
  m.shear_modulus = e.value / (2 * b);
  m.bulk_slope = e.slope / (3 * a) + 2 * e.value * nu.slope / (3 * a * a);
  m.shear_slope = e.slope / (2 * b) - e.value * nu.slope / (2 * b * b);
  return m;
}

J2Input j2_input(const Material& material, const MandelVector& strain, double temperature,
                 double stress_free_temperature) {
  const PropertyValue thermal = material.thermal_strain(temperature, stress_free_temperature);
  J2Input input;
  input.strain = strain;
  input.thermal_strain = thermal.value;
  input.thermal_strain_slope = thermal.slope;
  input.temperature = temperature;
  return input;
}

J2Coefficients j2_coefficients(const Material& material, const J2State& committed, double temperature,
                               double time_step) {
  J2Coefficients c;
  c.moduli = elastic_moduli(material, temperature);
  c.initial = material.yield_stress(committed.equivalent_plastic_strain, temperature);
  if (time_step > 0) c.viscosity = material.flow_viscosity(temperature);
  return c;
}

J2Result j2_update(const Material& material, const J2State& committed, const J2Input& input) {
  if (!std::isfinite(input.temperature) || !std::isfinite(committed.equivalent_plastic_strain))
    throw std::invalid_argument("J2 update (" + material.name() + "): non-finite input");
  return j2_update(material, committed, input,
                   j2_coefficients(material, committed, input.temperature, input.time_step));
}

J2Result j2_update(const Material& material, const J2State& committed, const J2Input& input,
                   const J2Coefficients& coefficients) {
  if (!input.strain.allFinite() || !std::isfinite(input.thermal_strain) ||
      !std::isfinite(input.thermal_strain_slope) || !std::isfinite(input.temperature) ||
      !committed.plastic_strain.allFinite() ||
      !std::isfinite(committed.equivalent_plastic_strain)) {
    throw std::invalid_argument("J2 update (" + material.name() + "): non-finite input");
  }
  const double temperature = input.temperature;
  const ElasticModuli& moduli = coefficients.moduli;
  const double bulk = moduli.bulk_modulus;
  const double shear = moduli.shear_modulus;
  const MandelVector one = mandel_identity();

  // Trial state: plastic strain frozen.
  const MandelVector elastic_strain =
      input.strain - committed.plastic_strain - input.thermal_strain * one;
  const double volumetric_strain = trace(elastic_strain);
  const MandelVector deviatoric_strain = deviator(elastic_strain);
  const double pressure = bulk * volumetric_strain;  // mean stress, tension positive
  const MandelVector trial_deviator = 2 * shear * deviatoric_strain;
  const double trial_norm = trial_deviator.norm();
  const double trial_q = sqrt_three_halves * trial_norm;
  const double eps_bar_n = committed.equivalent_plastic_strain;
  const FlowStress& initial = coefficients.initial;
  // Viscous overstress modulus H_v = eta/dt and its temperature slope.
  double viscous = 0, viscous_slope = 0;
  if (input.time_step > 0) {
    const PropertyValue& eta = coefficients.viscosity;
    viscous = eta.value / input.time_step;
    viscous_slope = eta.slope / input.time_step;
  }

  // Mean-stress part of the temperature derivative, shared by both branches.
  const double pressure_slope =
      moduli.bulk_slope * volumetric_strain - 3 * bulk * input.thermal_strain_slope;

  J2Result result;
  result.state = committed;
  if (trial_q - initial.yield_stress <= yield_tolerance * initial.yield_stress) {
    result.stress = pressure * one + trial_deviator;
    result.tangent = bulk * one * one.transpose() + 2 * shear * deviatoric_projector();
    result.stress_temperature_derivative =
        pressure_slope * one + 2 * moduli.shear_slope * deviatoric_strain;
    result.equivalent_stress = trial_q;
    result.yield_stress = initial.yield_stress;
    return result;
  }

  // Plastic: solve r(dgamma) = q_trial - 3 G dgamma - sigma_y(eps_bar_n + dgamma) - H_v dgamma = 0.
  double lower = 0;
  double upper = trial_q / (3 * shear);
  double dgamma = std::clamp((trial_q - initial.yield_stress) / (3 * shear + initial.hardening + viscous),
                             lower, upper);
  FlowStress flow;
  bool converged = false;
  int iteration = 0;
  while (iteration < max_return_iterations) {
    ++iteration;
    flow = material.yield_stress(eps_bar_n + dgamma, temperature);
    const double residual = trial_q - 3 * shear * dgamma - flow.yield_stress - viscous * dgamma;
    if (std::abs(residual) <= return_tolerance * trial_q) {
      converged = true;
      break;
    }
    if (residual > 0) {
      lower = dgamma;
    } else {
      upper = dgamma;
    }
    double next = dgamma + residual / (3 * shear + flow.hardening + viscous);
    if (!(next > lower && next < upper)) next = 0.5 * (lower + upper);
    if (upper - lower <= 1e-15 * upper) {
      // Bracket collapsed (a kink of the flow curve): the root is pinned.
      dgamma = next;
      flow = material.yield_stress(eps_bar_n + dgamma, temperature);
      converged = true;
      break;
    }
    dgamma = next;
  }
  if (!converged) {
    throw std::runtime_error("J2 update (" + material.name() +
                             "): return mapping did not converge at T = " +
                             std::to_string(temperature) + " degC");
  }

  const MandelVector normal = trial_deviator / trial_norm;
  const double q = trial_q - 3 * shear * dgamma;
  const double hardening = flow.hardening + viscous;  // H + H_v

  result.yielded = true;
  result.plastic_increment = dgamma;
  result.n_iterations = iteration;
  result.equivalent_stress = q;
  result.yield_stress = flow.yield_stress;
  result.state.plastic_strain = committed.plastic_strain + dgamma * sqrt_three_halves * normal;
  result.state.equivalent_plastic_strain = eps_bar_n + dgamma;
  result.stress = pressure * one + sqrt_two_thirds * q * normal;

  const double ratio = dgamma / trial_q;
  result.tangent = bulk * one * one.transpose() +
                   2 * shear * (1 - 3 * shear * ratio) * deviatoric_projector() +
                   6 * shear * shear * (ratio - 1 / (3 * shear + hardening)) * normal *
                       normal.transpose();

  const double trial_q_slope = trial_q * moduli.shear_slope / shear;
  const double dgamma_slope =
      (trial_q_slope - 3 * moduli.shear_slope * dgamma - flow.temperature_slope -
       viscous_slope * dgamma) /
      (3 * shear + hardening);
  const double q_slope = flow.temperature_slope + viscous_slope * dgamma + hardening * dgamma_slope;
  result.stress_temperature_derivative =
      pressure_slope * one + sqrt_two_thirds * q_slope * normal;
  return result;
}

}  // namespace rsw::materials
