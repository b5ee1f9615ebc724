// The squeeze phase: brings the stack from touching to the electrode force.
//
// At the start the bodies touch at one point on the axis, so force control alone
// has nothing to push against. The squeeze therefore first seats the stack under
// displacement control (the upper end face moves down in steps of `seat_step`)
// until the transmitted force reaches `seat_fraction` of the target, then raises
// the force linearly to the target in `squeeze_force_steps` force-controlled steps. Each
// converged step is committed. The steps depend only on the geometry and the
// target force, never on model parameters.
#pragma once

#include "physics/mechanics.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace rsw::physics {

struct SqueezeSettings {
  double seat_step = case_default("solver.seat_step");  // m
  double seat_fraction = 0.05;   // of the target force
  int max_seat_steps = 400;
  int squeeze_force_steps = static_cast<int>(case_default("solver.squeeze_force_steps"));
};

struct SqueezeStep {
  std::string control;  // "displacement" or "force"
  double force = 0;     // N
  double displacement = 0;  // m, upper end face (negative: down)
  int iterations = 0;
};

struct SqueezeResult {
  bool converged = false;
  std::string message;
  std::vector<SqueezeStep> steps;
};

SqueezeResult squeeze(Mechanics& mechanics, double target_force, const Eigen::VectorXd& nodal_temperature,
                      const SqueezeSettings& settings = {});

// Continues under force control from the current force to `target_force` in n steps.
SqueezeResult ramp_force(Mechanics& mechanics, double target_force, int n_steps,
                         const Eigen::VectorXd& nodal_temperature);

}  // namespace rsw::physics
