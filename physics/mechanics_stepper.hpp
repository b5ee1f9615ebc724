// The mechanics of one weld step, with sub-stepping where Newton fails.
//
// The mechanics follows the force and temperature changes of the step: it solves at
// the step's end force F_end and end temperature T_end. Where Newton fails (the first
// melting makes the material collapse within a step) the failed part of the step is
// halved, down to 1/32 of the step, with the force and the nodal temperatures
// interpolated linearly between the step's start and end. Steps that converge are
// never subdivided. A 1/32 sub-step whose Newton iteration stalls with an
// out-of-balance force below 10⁻⁵ of the load (the load at least 1 kN; 100 times the
// tolerance: measured 0.004–0.012 N at 3 kN, at contact points of the E/S face whose
// projection switches between master segments) is accepted and reported instead of
// failing the run. Each solve starts from the last committed increment scaled to the
// new (sub-)step length (Mechanics::set_predictor).
#pragma once

#include "physics/mechanics.hpp"

#include <Eigen/Dense>

#include <string>

namespace rsw::physics {

struct MechanicsStepOutcome {
  bool converged = false;
  std::string failure;          // Newton's message for the last failed solve
  double loose_residual = 0;    // N, the largest residual accepted at the smallest sub-step (0: none)
  std::string loose_message;    // Newton's message for that sub-step
};

class MechanicsStepper {
 public:
  explicit MechanicsStepper(Mechanics& mechanics) : mech_(mechanics) {}

  // Advances the committed state over a step of dt (s) from (F_start, T_start) to
  // (F_end, T_end); commits every (sub-)step that is accepted.
  MechanicsStepOutcome advance(double dt, double F_start, double F_end, const Eigen::VectorXd& T_start,
                               const Eigen::VectorXd& T_end);

  int newton_iterations() const { return newton_iterations_; }  // summed over the run
  int splits() const { return splits_; }                        // sub-steps made (halvings)
  int loose_substeps() const { return loose_; }                 // sub-steps accepted at a stalled residual

  static constexpr int max_depth = 5;  // halvings: the smallest sub-step is 1/32 of the step

 private:
  // Advances over the fraction [s0, s1] of the current step.
  bool advance_part(double s0, double s1, int depth);
  void accept(double length);

  Mechanics& mech_;
  double last_step_ = 0;  // s, the last committed (sub-)step
  int newton_iterations_ = 0, splits_ = 0, loose_ = 0;
  // The step being advanced.
  double dt_ = 0, F_start_ = 0, F_end_ = 0;
  const Eigen::VectorXd* T_start_ = nullptr;
  const Eigen::VectorXd* T_end_ = nullptr;
  MechanicsStepReport report_;
  MechanicsStepOutcome outcome_;
};

}  // namespace rsw::physics
