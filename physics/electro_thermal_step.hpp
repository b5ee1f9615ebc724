// One weld step of the electro-thermal coupling, with its retry policy.
//
// The step solves the fixed point T = G(T): the electrical field with σ(T) and the
// interface conductances at T, then the backward Euler thermal step of length dt with
// that Joule heat and its coefficients (k, HTC) also at T. The contact state and the
// node positions are those of the last mechanics solve (staggered coupling). The
// iteration is Anderson-accelerated (SUNDIALS KINSOL, fem/fixed_point.hpp): plain
// iteration runs away where the current crowds into a contact edge that heats,
// softens and conducts better. It has converged when an iterate changes by at most
// solver.coupling_tolerance (K); the thermal and electrical states then belong to the
// last evaluated T. Without current there is no coupling: one thermal step.
//
// Inexact inner solves: an iterate that moved by Δ (K) is solved to 10⁻³ Δ, never
// looser than 0.1 K and never tighter than the thermal tolerance; far from the fixed
// point the field is needed only roughly, and the converged iterate is solved as
// tightly as a lone thermal step.
//
// Retry policy: where the iteration cycles (kinks of tabulated properties at a
// contact edge that heats), the step is solved again from its start by Newton's
// method on T − G(T) (Newton–Krylov, fem/fixed_point.hpp; its inner thermal solves to
// the thermal tolerance, so that the difference quotients of G are accurate), then
// with the other Anderson depth (2, or 5 where 2 is configured), then with damping 0.7
// and 0.4 at both depths. Each finds the step's fixed point to the tolerance; a step
// that one of them rescues keeps the step schedule, which a step solved in parts (the
// weld driver's last resort) does not. (Where later steps sit near such failures too,
// a weld can still follow the small difference: 26 of the 90 Table I welds moved when
// Newton came first, by up to 0.24 %, R_β of run 30.) On the paper-mesh
// Table I study Newton leaves 2 of 90 welds with a step solved in parts (6 with the
// Anderson retries alone, 4 with Newton after them); on its four slowest welds it
// converged in 9 of the 14 steps where Anderson failed, in 36–100 evaluations of G
// against up to 300 for the five Anderson retries (docs/PERFORMANCE.md, "Studies").
#pragma once

#include "contact/interface_laws.hpp"
#include "fem/mesh.hpp"
#include "physics/electrical.hpp"
#include "physics/stopwatch.hpp"
#include "physics/thermal.hpp"

#include <Eigen/Dense>

#include <string>
#include <vector>

namespace rsw::physics {

// The first three mirror solver.coupling_acceleration_depth, solver.coupling_tolerance
// and solver.max_coupling_iterations and take their defaults from the schema.
struct CouplingSettings {
  // Anderson depth (0: plain iteration, no depth retries)
  int acceleration_depth = static_cast<int>(case_default("solver.coupling_acceleration_depth"));
  double tolerance = case_default("solver.coupling_tolerance");  // K, on the change of an iterate
  int max_iterations = static_cast<int>(case_default("solver.max_coupling_iterations"));  // per attempt
  double thermal_tolerance = 1e-6;  // K, of the converged thermal solve
};

struct CoupledStepReport {
  bool converged = false;
  int iterations = 0;              // evaluations of G, over all attempts (1 without current)
  std::string failure;             // what failed, if not converged
};

class ElectroThermalStep {
 public:
  // `clock` receives the parts "electrical" and "thermal"; `verbose` prints each
  // iterate's largest change to stderr.
  ElectroThermalStep(const fem::Mesh& mesh, Electrical& electrical, Thermal& thermal, const CouplingSettings& settings,
                     Stopwatch& clock, bool verbose = false);

  // Solves the step of length dt (s) at current I (A) from the thermal solver's
  // committed field; on success thermal.temperature() is the step's field.
  CoupledStepReport solve(double dt, double current, const std::vector<fem::Point>& positions,
                          const contact::ContactState& contact);

  bool has_electrical_solution() const { return have_electrical_; }  // a step with current has run
  int retries() const { return retries_; }                         // attempts after the first, summed
  int newton_solves() const { return newton_solves_; }              // of which by Newton
  int newton_rescues() const { return newton_rescues_; }            // of which converged

 private:
  // G(T_in) → T_out; false (with failure_ set) if a field solve failed.
  bool evaluate(const Eigen::VectorXd& T_in, Eigen::VectorXd& T_out);
  // Evaluations of G allowed to the Newton retry: twice an Anderson attempt's (120 by
  // default; the rescues measured took 36–100).
  int newton_budget() const { return 2 * settings_.max_iterations; }

  const fem::Mesh& mesh_;
  Electrical& electrical_;
  Thermal& thermal_;
  CouplingSettings settings_;
  Stopwatch& clock_;
  bool verbose_;
  bool have_electrical_ = false;
  int retries_ = 0, newton_solves_ = 0, newton_rescues_ = 0;
  bool exact_inner_ = false;  // inner thermal solves to the thermal tolerance (Newton's evaluations)
  // The step being solved.
  double dt_ = 0, current_ = 0;
  const std::vector<fem::Point>* positions_ = nullptr;
  const contact::ContactState* contact_ = nullptr;
  double last_change_ = 0;
  std::string failure_;
};

}  // namespace rsw::physics
