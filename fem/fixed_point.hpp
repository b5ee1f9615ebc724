// Fixed points u = G(u) by Anderson-accelerated iteration or by Newton–Krylov, the one
// wrapper around SUNDIALS KINSOL (strategies KIN_FP and KIN_LINESEARCH) in rsw.
//
// Plain (Picard) iteration u_{k+1} = G(u_k) converges only where G contracts; it
// diverges, slowly and monotonically, along any mode whose gain exceeds 1. Anderson
// acceleration of depth m (Walker & Ni 2011, SIAM J. Numer. Anal. 49:1715; KINSOL's
// implementation: Lott, Walker, Woodward & Yang 2012) takes the combination of the last
// m+1 evaluations G(u_j) whose residuals f_j = G(u_j) − u_j best cancel in the least-
// squares sense:
//     u_{k+1} = G(u_k) − Σ_i γ_i ΔG_i,   γ = argmin |f_k − Σ_i γ_i Δf_i|₂,
// a multisecant quasi-Newton step that also finds fixed points that plain iteration
// runs away from. Depth 0 is plain iteration. Damping β ∈ (0, 1] relaxes each update,
// u_{k+1} = (1 − β) ũ_k + β G̃_k (ũ, G̃ the accelerated iterate and map value; KINSOL's
// KINSetDamping/KINSetDampingAA): β < 1 trades speed for robustness where G is only
// piecewise smooth (kinks of tabulated properties) and the undamped iteration cycles.
//
// Stopping (KINSOL's test for KIN_FP): the ∞-norm of the change of the iterate,
// |u_{k+1} − u_k|_∞ ≤ tolerance, in the units of u. On success `u` holds the last
// point G was evaluated at (u_k), so the caller's state from that evaluation (G(u_k)
// and whatever produced it) belongs to the returned point.
//
// With `estimate_error`, the iteration also stops once the change is estimated to be
// converged (Deuflhard, Newton Methods for Nonlinear Problems, Springer 2004, §2.1.2,
// for a linearly contracting sequence): after two successive contractions
// θ_k = c_k / c_{k−1} ≤ 1/2 of the changes c_k = |G(u_k) − u_k|_∞, the distance of G(u_k)
// from the fixed point is about θ_k c_k / (1 − θ_k), and when that is at most
// `tolerance` the evaluation that would only confirm it is saved.
#pragma once

#include <Eigen/Dense>

#include <functional>
#include <string>

namespace rsw::fem {

struct FixedPointSettings {
  int depth = 5;             // Anderson depth m (0: plain fixed-point iteration)
  double tolerance = 1e-8;   // on |u_{k+1} − u_k|_∞, units of u
  int max_iterations = 50;   // evaluations of G
  double damping = 1.0;      // β in (0, 1]; 1 = undamped
  bool estimate_error = false;  // also stop on the contraction estimate (above)
};

struct FixedPointReport {
  bool converged = false;
  int iterations = 0;        // evaluations of G
  double change = 0;         // |u_{k+1} − u_k|_∞ of the last iteration
  bool estimated = false;    // converged on the contraction estimate (estimate_error)
  std::string message;       // why it stopped, if not converged
};

// G(u, g) writes g = G(u) and returns true, or false if G cannot be evaluated at u
// (the iteration then stops, not converged). `u` is the start on entry and the last
// evaluated point on return.
using FixedPointMap = std::function<bool(const Eigen::VectorXd& u, Eigen::VectorXd& g)>;
FixedPointReport solve_fixed_point(const FixedPointMap& G, Eigen::VectorXd& u, const FixedPointSettings& settings);

// The same fixed point by Newton's method on F(u) = G(u) − u = 0 (KINSOL, strategy
// KIN_LINESEARCH; Brown & Saad, SIAM J. Sci. Stat. Comput. 11 (1990) 450–481): each
// step solves (∂G/∂u − I) δ = −F(u) by GMRES (SUNDIALS' SPFGMR, no preconditioner) to
// |residual| ≤ linear_tolerance |F|, with the products (∂G/∂u − I) v as difference
// quotients of G (KINSOL's: an increment of √relative_error relative to u, where
// relative_error is the relative accuracy of an evaluation of G), then a backtracking
// line search on |F|₂ (Dennis & Schnabel, Numerical Methods for Unconstrained
// Optimization and Nonlinear Equations, SIAM 1996, §6.3). It converges where G has a
// few strongly expanding modes that Anderson's combination of past iterates does not
// cancel; each GMRES iteration costs one evaluation of G, so GMRES needs about as many
// iterations as G has modes that do not contract. Stopping: |G(u) − u|_∞ ≤ tolerance
// at the returned u, the last point G was evaluated at (as above), within
// `max_evaluations` evaluations of G.
struct NewtonKrylovSettings {
  double tolerance = 1e-8;         // on |G(u) − u|_∞, units of u
  int max_evaluations = 100;       // of G, difference quotients and the final check included
  int max_krylov = 50;             // GMRES iterations per Newton step
  double linear_tolerance = 1e-6;  // relative residual of each GMRES solve
  double relative_error = 1e-12;   // of an evaluation of G
};
FixedPointReport solve_fixed_point_newton(const FixedPointMap& G, Eigen::VectorXd& u,
                                          const NewtonKrylovSettings& settings);

}  // namespace rsw::fem
