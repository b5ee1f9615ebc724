// Seating under displacement control, then a force ramp; see squeeze.hpp.
#include "physics/squeeze.hpp"

namespace rsw::physics {

SqueezeResult ramp_force(Mechanics& mechanics, double target_force, int n_steps,
                         const Eigen::VectorXd& nodal_temperature) {
  SqueezeResult result;
  const double start = mechanics.electrode_force();
  for (int k = 1; k <= n_steps; ++k) {
    const double F = start + (target_force - start) * k / n_steps;
    const auto report = mechanics.solve_force_step(F, nodal_temperature);
    if (!report.converged) {
      result.message = "force step to " + std::to_string(F) + " N: " + report.message;
      return result;
    }
    mechanics.commit();
    result.steps.push_back({"force", F, mechanics.end_face_displacement(), report.iterations});
  }
  result.converged = true;
  return result;
}

SqueezeResult squeeze(Mechanics& mechanics, double target_force, const Eigen::VectorXd& nodal_temperature,
                      const SqueezeSettings& settings) {
  SqueezeResult result;
  const double seat_force = settings.seat_fraction * target_force;
  int k = 0;
  while (mechanics.electrode_force() < seat_force) {
    if (++k > settings.max_seat_steps) {
      result.message = "seating did not reach " + std::to_string(seat_force) + " N in " +
                       std::to_string(settings.max_seat_steps) + " steps of " +
                       std::to_string(settings.seat_step * 1e6) + " um";
      return result;
    }
    const double w = mechanics.end_face_displacement() - settings.seat_step;
    const auto report = mechanics.solve_displacement_step(w, nodal_temperature);
    if (!report.converged) {
      result.message = "seating step to w = " + std::to_string(w * 1e6) + " um: " + report.message;
      return result;
    }
    mechanics.commit();
    result.steps.push_back({"displacement", mechanics.electrode_force(), w, report.iterations});
  }
  auto ramp = ramp_force(mechanics, target_force, settings.squeeze_force_steps, nodal_temperature);
  result.steps.insert(result.steps.end(), ramp.steps.begin(), ramp.steps.end());
  result.converged = ramp.converged;
  result.message = ramp.message;
  return result;
}

}  // namespace rsw::physics
