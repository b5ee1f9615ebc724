// Mechanical contact laws at a paired contact point: the normal pressure against the
// gap and the regularised Coulomb friction traction, as pure functions returning the
// value and the derivatives the mechanics' Newton tangent needs.
//
// Normal pressure, a C¹ penalty law of the gap g (m; g < 0 is penetration):
//     p(g) = 0                   g ≥ 0
//          = ε_N g² / (2δ)       −δ < g < 0
//          = ε_N (−g − δ/2)      g ≤ −δ                                   [Pa]
// with the penalty ε_N (Pa/m) and the smoothing width δ (m). p and its slope
// k = −dp/dg are continuous at g = 0 and g = −δ, so Newton's residual is
// differentiable where a point enters contact (no cycling between active sets).
//
// Friction, Coulomb regularised by a hyperbolic tangent:
//     τ = μ p tanh(τ_trial / (μ p)),   τ_trial = τ_n + ε_T Δs                [Pa]
// τ_n the committed tangential traction, Δs the slip increment, ε_T the tangential
// penalty (Pa/m): stick with stiffness ε_T for |τ_trial| ≪ μp, sliding as |τ| → μp,
// with no switch between the two, so the tangent stays continuous. Derivatives, with
// u = τ_trial/(μp):
//     ∂τ/∂τ_trial = sech²u = 1 − tanh²u,     ∂τ/∂p = μ (tanh u − u sech²u).
//
// Sources: penalty regularisation of contact constraints, P. Wriggers, Computational
// Contact Mechanics, 2nd ed., Springer 2006, ch. 5 (penalty method) and §5.2 (smoothed
// laws); regularised Coulomb friction, ibid. §5.2.3 and J. C. Simo and T. A. Laursen,
// Computers & Structures 42 (1992) 97–116. The choice of δ and ε_T for the weld is in
// physics/mechanics.hpp.
#pragma once

#include <cmath>

namespace rsw::contact {

struct PenaltyPressure {
  double pressure;   // Pa
  double stiffness;  // Pa/m, −dp/dg ≥ 0
};

inline PenaltyPressure penalty_pressure(double gap, double eps_n, double delta) {
  if (gap >= 0) return {0.0, 0.0};
  if (gap > -delta) return {eps_n * gap * gap / (2 * delta), -eps_n * gap / delta};
  return {eps_n * (-gap - 0.5 * delta), eps_n};
}

struct FrictionTraction {
  double traction;     // τ, Pa (the sign of τ_trial)
  double d_trial;      // ∂τ/∂τ_trial
  double d_pressure;   // ∂τ/∂p
};

// Requires μ p > 0.
inline FrictionTraction regularised_coulomb(double trial, double mu, double pressure) {
  const double limit = mu * pressure;
  const double u = trial / limit;
  const double th = std::tanh(u), sech2 = 1 - th * th;
  return {limit * th, sech2, mu * (th - u * sech2)};
}

}  // namespace rsw::contact
