// Small-strain J2 (von Mises) plasticity with isotropic hardening and an optional
// viscous overstress for axisymmetric stress states, integrated by the radial-return
// mapping (backward Euler), with the consistent tangent and the temperature
// derivative of the stress.
//
// Components in Mandel notation, ordered [rr, zz, theta-theta, sqrt(2) rz]:
//     strain  e = [eps_rr, eps_zz, eps_tt, sqrt(2) eps_rz],  eps_rz = gamma_rz / 2,
//     stress  s = [sig_rr, sig_zz, sig_tt, sqrt(2) sig_rz],
// so that sigma : eps = s . e and tensor norms are vector norms; tangents are
// symmetric 4x4 matrices. (An element builds the fourth strain entry as
// (du_r/dz + du_z/dr) / sqrt(2).)
//
// Model (total-strain form, elastic constants at the current temperature T):
//     sigma = K(T) tr(eps_e) 1 + 2 G(T) dev(eps_e),  eps_e = eps - eps_p - eps_th 1,
//     K = E / (3 (1 - 2 nu)),  G = E / (2 (1 + nu)),
//     f = q - sigma_y(eps_bar_p, T) <= 0,  q = sqrt(3/2) |dev(sigma)|,
//     eps_p' = dgamma sqrt(3/2) n,  eps_bar_p' = dgamma,  n = dev(sigma) / |dev(sigma)|.
// Rate dependence (Perzyna 1966 with exponent 1, a linear overstress): while f > 0 the
// plastic strain grows at eps_bar_p' = f / eta(T), i.e. q = sigma_y + eta eps_bar_p',
// eta the material's flow_viscosity (Pa*s). Over a step of length dt (backward Euler)
// the overstress is (eta/dt) dgamma, so eta/dt = H_v acts as an extra hardening modulus
// that is not remembered: the next step starts from sigma_y again, and a held strain
// relaxes, q - sigma_y falling by the factor 1/(1 + 3 G dt/eta) per step (exactly
// exp(-3 G t/eta) as dt -> 0 for perfect plasticity). dt = 0 (or eta = 0) is the
// rate-independent limit. (Simo & Hughes 1998, 2.7; de Souza Neto, Peric & Owen 2008,
// 11.3: the return mapping of Perzyna viscoplasticity with linear rate dependence.)
// Because sigma depends on eps - eps_p - eps_th at the current K, G, a change of E(T)
// at fixed strain changes the stress only in proportion to the existing elastic
// strain: heating an unstressed point creates no stress.
//
// Return mapping (de Souza Neto, Peric & Owen 2008, "Computational Methods for
// Plasticity", Box 7.3/7.4; Simo & Hughes 1998, "Computational Inelasticity", 3.3):
// trial state with eps_p frozen; if f_trial > 0, solve the scalar equation
//     r(dgamma) = q_trial - 3 G dgamma - sigma_y(eps_bar_p_n + dgamma, T) - H_v dgamma = 0
// by Newton's method safeguarded by bisection on the bracket [0, q_trial / (3G)]
// (r(0) > 0, r decreasing since H >= 0, r(q_trial / 3G) < 0), so it converges for
// piecewise-linear hardening and near the strength floor. Then
//     dev(sigma) = (1 - 3 G dgamma / q_trial) dev(sigma_trial),
//     D = K 1(x)1 + 2G (1 - 3G dgamma/q_trial) I_dev
//         + 6 G^2 (dgamma/q_trial - 1/(3G + H + H_v)) N(x)N,   N = n_trial,
// with H = d sigma_y / d eps_bar_p at the converged state and H_v = eta/dt. Near the
// strength floor H vanishes and the rate-independent tangent is almost singular in the
// flow direction; H_v keeps it regular, which is what lets the mechanics' Newton
// iteration converge where the sheets soften and melt.
//
// Temperature derivative at fixed total strain and committed state (for a coupled
// Jacobian): with K' = dK/dT, G' = dG/dT, eps_th' = d eps_th / dT,
//     elastic: d sigma/dT = (K' tr(eps_e) - 3 K eps_th') 1 + 2 G' dev(eps_e);
//     plastic: the flow direction N does not depend on T, dev(sigma) = sqrt(2/3) q N,
//        d dgamma/dT = (q_trial G'/G - 3 G' dgamma - d sigma_y/dT - H_v' dgamma)
//                      / (3G + H + H_v),
//        dq/dT = d sigma_y/dT + H_v' dgamma + (H + H_v) d dgamma/dT,  H_v' = eta'(T)/dt,
//        d sigma/dT = (K' tr(eps_e) - 3 K eps_th') 1 + sqrt(2/3) (dq/dT) N.
//
// Units: stresses and moduli Pa, strains dimensionless, temperatures degC.
// History lives in J2State: the caller keeps the committed state per quadrature
// point and replaces it with J2Result::state only after the global step converged.
#pragma once

#include "materials/material.hpp"

#include <Eigen/Core>

namespace rsw::materials {

using MandelVector = Eigen::Matrix<double, 4, 1>;
using MandelMatrix = Eigen::Matrix<double, 4, 4>;

// [1, 1, 1, 0]: the second-order identity.
MandelVector mandel_identity();
// I - (1/3) 1 (x) 1: maps a Mandel vector to its deviator.
MandelMatrix deviatoric_projector();
// Mandel vector of a symmetric tensor given by its components (rz is the tensor
// component, e.g. eps_rz = gamma_rz / 2).
MandelVector to_mandel(double rr, double zz, double theta_theta, double rz);
// The tensor rz component of a Mandel vector: v[3] / sqrt(2).
double shear_component(const MandelVector& v);
double trace(const MandelVector& v);
MandelVector deviator(const MandelVector& v);
// q = sqrt(3/2) |dev(sigma)|, Pa.
double von_mises_stress(const MandelVector& stress);

// Bulk and shear moduli from E(T), nu(T), with their temperature derivatives.
struct ElasticModuli {
  double bulk_modulus = 0;   // Pa, K
  double shear_modulus = 0;  // Pa, G
  double bulk_slope = 0;     // Pa/K, dK/dT
  double shear_slope = 0;    // Pa/K, dG/dT
};
ElasticModuli elastic_moduli(const Material& material, double temperature);

// History of one quadrature point.
struct J2State {
  MandelVector plastic_strain = MandelVector::Zero();  // eps_p, deviatoric
  double equivalent_plastic_strain = 0;                // eps_bar_p
};

struct J2Input {
  MandelVector strain = MandelVector::Zero();  // total strain eps
  double thermal_strain = 0;                   // eps_th (isotropic), from Material
  double thermal_strain_slope = 0;             // d eps_th / dT, 1/K
  double temperature = 20;                     // degC
  double time_step = 0;                        // s, dt of the step; 0 = rate-independent
};

struct J2Result {
  MandelVector stress = MandelVector::Zero();         // Pa
  MandelMatrix tangent = MandelMatrix::Zero();        // d stress / d strain, Pa
  MandelVector stress_temperature_derivative = MandelVector::Zero();  // Pa/K, at fixed strain
  J2State state;                  // the updated history, to commit after convergence
  bool yielded = false;           // the step was plastic
  double plastic_increment = 0;   // d eps_bar_p of this step
  double equivalent_stress = 0;   // q of the returned stress, Pa
  double yield_stress = 0;        // sigma_y at the returned state, Pa
  int n_iterations = 0;           // Newton/bisection iterations of the return
};

// The coefficients of an update that depend only on the temperature and the
// committed state: E, ν as K, G; σ_y(ε̄_p,n, T); η(T). A caller that updates one
// point many times at one temperature from one committed state (the Newton
// iterations of a step) evaluates them once; the update is then the same to the bit.
// η is evaluated only for a rate-dependent update (time_step > 0).
struct J2Coefficients {
  ElasticModuli moduli;
  FlowStress initial;       // yield stress and hardening at the committed ε̄_p
  PropertyValue viscosity;  // η(T), Pa·s
};
J2Coefficients j2_coefficients(const Material& material, const J2State& committed, double temperature,
                               double time_step);

// One stress update from the committed state. Throws std::invalid_argument for
// non-finite input.
J2Result j2_update(const Material& material, const J2State& committed, const J2Input& input);
// The same with coefficients from j2_coefficients(material, committed, input.temperature,
// input.time_step).
J2Result j2_update(const Material& material, const J2State& committed, const J2Input& input,
                   const J2Coefficients& coefficients);

// J2Input with the thermal strain of `material` between the stress-free temperature
// and `temperature`.
J2Input j2_input(const Material& material, const MandelVector& strain, double temperature,
                 double stress_free_temperature);

}  // namespace rsw::materials
