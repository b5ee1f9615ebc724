// The mechanics of one weld step with sub-stepping; see mechanics_stepper.hpp.
#include "physics/mechanics_stepper.hpp"

#include <algorithm>
#include <cmath>

namespace rsw::physics {

void MechanicsStepper::accept(double length) {
  mech_.commit();
  last_step_ = length;
}

bool MechanicsStepper::advance_part(double s0, double s1, int depth) {
  const double length = (s1 - s0) * dt_;
  if (last_step_ > 0) mech_.set_predictor(length / last_step_);
  mech_.set_time_step(length);
  const Eigen::VectorXd& T_start = *T_start_;
  report_ = mech_.solve_force_step(F_start_ + s1 * (F_end_ - F_start_), T_start + s1 * (*T_end_ - T_start));
  newton_iterations_ += report_.iterations;
  if (report_.converged) {
    accept(length);
    return true;
  }
  if (depth == max_depth) {
    const double load = std::max(std::abs(F_start_ + s1 * (F_end_ - F_start_)), 1e3);
    if (report_.residual > 1e-5 * load) return false;
    accept(length);
    ++loose_;
    if (report_.residual > outcome_.loose_residual) {
      outcome_.loose_residual = report_.residual;
      outcome_.loose_message = report_.message;
    }
    return true;
  }
  ++splits_;
  const double mid = 0.5 * (s0 + s1);
  return advance_part(s0, mid, depth + 1) && advance_part(mid, s1, depth + 1);
}

MechanicsStepOutcome MechanicsStepper::advance(double dt, double F_start, double F_end, const Eigen::VectorXd& T_start,
                                               const Eigen::VectorXd& T_end) {
  dt_ = dt;
  F_start_ = F_start;
  F_end_ = F_end;
  T_start_ = &T_start;
  T_end_ = &T_end;
  outcome_ = {};
  outcome_.converged = advance_part(0.0, 1.0, 0);
  if (!outcome_.converged) outcome_.failure = report_.message;
  return outcome_;
}

}  // namespace rsw::physics
