// Quasi-static axisymmetric thermo-elasto-plastic mechanics of the electrode/sheet
// stack with contact on the named interfaces.
//
// Equilibrium ∇·σ = 0, solved per load step for the displacement increment Δu:
//   R(Δu) = f_ext + f_contact(x_n + Δu) - Σ_cells ∫ B̄ᵀ σ(ε_n + B̄ Δu, T) dV  = 0,
// by Newton's method with a backtracking line search on |R|.
//
// Kinematics (updated Lagrangian, small increments): B̄ and dV are evaluated on the
// configuration x_n at the start of the step; after convergence x_{n+1} = x_n + Δu
// and the strain accumulates, ε_{n+1} = ε_n + B̄ Δu. Stresses are not rotated, so
// the formulation is valid while rigid rotations stay small (in a spot weld the
// material near the electrode rotates by well under a degree; indentation is a few
// per cent of the sheet thickness). The force imbalance created by moving the
// geometry is carried into the next step's residual and removed there.
// Strains use Mandel notation [ε_rr, ε_zz, ε_θθ, √2 ε_rz] with the hoop strain
// ε_θθ = u_r / r; B̄ replaces the volumetric part of B by its cell average (Hughes
// 1980) so that isochoric plastic flow does not lock the bilinear elements.
// Material: J2 plasticity with temperature-dependent E, ν, α and flow curves and a
// viscous overstress η(T) ε̄̇_p over the step length set by set_time_step()
// (materials/j2_plasticity), driven by the nodal temperature field.
//
// Loads: the lower electrode's end face is fixed (u = 0); the upper end face moves
// rigidly in z (one extra unknown w: u_z = w on all its nodes, u_r = 0) and carries
// the electrode force F, or w is prescribed (displacement control, used to seat the
// bodies before force control takes over); u_r = 0 on the axis.
//
// Contact (per interface, Gauss-point-to-segment, contact/interface_pairing): normal
// pressure from a C¹ penalty law
//   p = 0 (g >= 0),  ε_N g²/(2δ) (-δ < g < 0),  ε_N (-g - δ/2) (g <= -δ),
// with ε_N = contact_penalty_factor · E/h (E the stiffer side's room-temperature modulus, h
// the finest interface cell) and δ = contact_smoothing. The quadratic start keeps
// the residual differentiable when a point enters contact, so Newton converges
// quadratically instead of cycling between active sets, and contact outputs vary
// smoothly. δ = 30 µm by default: at 0.2–1 GPa and ε_N ≈ 3·10¹⁶ Pa/m the
// penetration is √(2δ p/ε_N) ≈ 0.6–1.4 µm, and a ring of contact that closes takes
// its load gradually instead of in one step, which keeps the features smooth in the
// parameters (docs/VERIFICATION.md, "Smoothness over the prior"); the contact is
// wider and softer than between smooth surfaces, as roughness makes it (Johnson,
// Contact Mechanics, 1985, ch. 13). With δ = 10 nm Newton cycled on the paper's mesh
// where contact points open and close around the first melt (measured: failure at
// 14 ms; 200 nm passes in 3529 iterations, 1 µm in 1956). Bodies touching
// at a single point are not held by that, so seating (displacement control, see
// physics/squeeze) puts the unsupported bodies on a weak elastic foundation until
// contact carries them.
// Coulomb friction, regularised: τ = μ p tanh(τ_trial / (μ p)) with the elastic
// trial traction τ_trial = τ_n + ε_T Δs (Δs the tangential slip increment of the
// slave point relative to the master, τ_n the committed history): stick with
// stiffness ε_T at small traction, sliding as |τ| → μ p, and no switch between the
// two, so the tangent stays continuous. ε_T = 0.1 ε_N by default
// (solver.friction_penalty_ratio): the elastic slip before sliding, μp/ε_T, is about
// 40 nm at μp = 150 MPa on the paper's mesh (Abaqus/Standard's default penalty
// friction allows 0.5 % of a contact face's length, 0.3 µm there). ε_T = ε_N (4 nm)
// gave the same weld to 0.2 % with 35 % more Newton iterations, spent on points
// switching between stick and slip. Points where the
// sheets have fused (set_bonded) are tied instead.
#pragma once

#include "contact/interface_pairing.hpp"
#include "fem/assembler.hpp"
#include "fem/constraints.hpp"
#include "fem/dof_map.hpp"
#include "fem/linear_solver.hpp"
#include "fem/mesh.hpp"
#include "materials/j2_plasticity.hpp"
#include "materials/material.hpp"
#include "physics/problem.hpp"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace rsw::physics {

// The settings that mirror a key of the weld case (named in their comment) take its
// default from the schema (physics/problem.hpp); the weld driver sets them from the case.
struct MechanicsSettings {
  double friction_coefficient = case_default("contact.friction_coefficient");  // μ; 0 = frictionless
  double contact_penalty_factor = case_default("solver.contact_penalty_factor");  // ε_N = factor · E / h
  // ε_T = ratio · ε_N (elastic slip before sliding μp/ε_T)
  double friction_penalty_ratio = case_default("solver.friction_penalty_ratio");
  double contact_smoothing = case_default("solver.contact_smoothing");  // m, δ of the C¹ penalty law (see below)
  // Interfaces treated in two passes (docs/MECHANICS.md, "Contact"): besides the
  // named slave/master pass, a mirrored pass with the roles swapped, each pass with
  // half the area weight, so that two sides of the same kind are loaded alike. Under
  // a mirror (below), an interface whose one side is the other's image keeps its
  // first pass alone with the whole area weight: the second is its mirror image.
  // pairings(), interface_states() and contact_pressure() show the first pass.
  std::vector<std::string> two_pass_interfaces;
  // Seating aid: under displacement control, bodies with no support of their own
  // (the sheets) rest on an elastic foundation of this total stiffness (N/m) towards
  // their initial axial position, so that they are held before contact closes.
  // Force-controlled steps never use it.
  double seating_stiffness = 1e3;
  int max_iterations = 40;               // per Newton solve (one target of the continuation)
  int max_continuation_iterations = 200;  // over all targets of a step's continuation
  double mechanics_tolerance = case_default("solver.mechanics_tolerance");  // relative to the load scale
  double displacement_tolerance = 1e-13;  // m, on the Newton correction
  // m: a step is also accepted when the estimated remaining error |Δu_k|²/|Δu_k−1| of
  // a superlinearly converging iteration is below this and |R| within 10² of the
  // residual tolerance (0 turns the estimate off).
  double mechanics_error_estimate = case_default("solver.mechanics_error_estimate");
  // Cells whose Gauss points are elastic and provably stay so (a bound on the stress
  // change from the displacement change since the cell's last full evaluation) take
  // their force and tangent from the linear update f(Δu*) − K_e (Δu − Δu*) instead of
  // their Gauss points; equal to round-off (false: every cell at its Gauss points).
  bool linear_elastic_updates = true;
  // m: the unknowns of the nodes farther than this from every contact face of their
  // body (the electrodes' interiors) are eliminated from the force-controlled Newton
  // systems before GMRES (fem/interior_elimination.hpp): the same solution within
  // Newton's tolerance (the paper's case: signals within 7·10⁻¹⁰). Such a region
  // stays elastic, so its stiffness changes once per step (with the temperature), not
  // between Newton iterations; nearer to the contact the electrode yields under the
  // squeeze on the default weld (within 1.5 mm). 0 or less: none.
  double interior_elimination_distance = 2e-3;
  int n_gauss = 2;
  bool verbose = false;                   // print Newton iterations to stderr
  // Supports: u_z = 0 on `fixed_boundary`; the nodes of `loaded_boundary` share one
  // axial displacement w (force or displacement controlled); with clamp_radially,
  // u_r = 0 on both. u_r = 0 on every boundary named "<body>.axis".
  std::string fixed_boundary = "lower_electrode.end_face";
  std::string loaded_boundary = "upper_electrode.end_face";
  bool clamp_radially = true;
  // Normal pressure on named boundaries (Pa, pressing into the body), applied on the
  // configuration at the start of each step.
  std::vector<std::pair<std::string, double>> pressure_loads;
  // A mirror symmetry about z = 0 (fem/mirror.hpp), or empty: solve for the upper half,
  // the lower half its image (u_r even, u_z odd in z). The stack, its loads and supports
  // must then be symmetric: `fixed_boundary` is the image of `loaded_boundary`, so that
  // the plane z = 0 stays put and the end faces move by ±w (see end_face_displacement).
  fem::MirrorSymmetry mirror;
};

// Stress at one quadrature point (current configuration).
struct PointStress {
  fem::Point position;                // m
  Eigen::Matrix<double, 4, 1> stress;  // Mandel [rr, zz, θθ, √2 rz], Pa
};

struct MechanicsStepReport {
  bool converged = false;
  int iterations = 0;
  double residual = 0;  // N, final ∞-norm of the reduced residual
  std::string message;
};

// Contact state of one interface after a step.
struct InterfaceState {
  std::string name;
  std::vector<double> radius;    // current r of each slave point, m
  std::vector<double> pressure;  // Pa
  std::vector<double> gap;       // m
  std::vector<double> shear;     // tangential traction, Pa
  double normal_force = 0;       // N, ∫ p dA
  double contact_radius = 0;     // m, outermost zero of the interpolated gap (bonded points closed)
};

// Work of the linear algebra so far (fem::PreconditionedGmres, fem::Assembler), over
// force and displacement control.
struct MechanicsSolverCounts {
  long gmres_iterations = 0;
  long factorisations = 0;          // preconditioners factorised
  long surrogates = 0;              // of which needed the surrogate (an indefinite symmetric part)
  long lu_factorisations = 0;       // of which fell back to the LU of the tangent
  long cell_matrices_scattered = 0;  // cell matrices assembled (new or changed)
  long cell_matrices_reused = 0;     // unchanged cell matrices taken from the previous assembly
  long condensations = 0;           // factorisations of the eliminated interior (InteriorElimination)
  long condensations_reused = 0;    // Newton systems solved with an earlier one
  int interior_unknowns = 0, border_unknowns = 0;  // eliminated, and coupled to them
};

class Mechanics {
 public:
  // `body_materials[b]` is the material of mesh body b; `initial_temperature` is the
  // stress-free temperature (°C).
  Mechanics(const fem::Mesh& mesh, std::vector<const materials::Material*> body_materials,
            const MechanicsSettings& settings, double initial_temperature);
  ~Mechanics();

  // Force control: the upper end face carries `force` (N, > 0 presses the stack).
  MechanicsStepReport solve_force_step(double force, const Eigen::VectorXd& nodal_temperature);
  // Displacement control: the upper end face's total z displacement is `w` (m).
  MechanicsStepReport solve_displacement_step(double w, const Eigen::VectorXd& nodal_temperature);
  // For the next force step only: the last committed increment times `scale` (e.g.
  // the ratio of the time steps) is tried as the initial guess besides the load-change
  // rule, and the one with the smaller residual starts Newton; the converged step does
  // not depend on it (up to the tolerance). 0 (the default) tries the rule only.
  void set_predictor(double scale);
  // Length (s) of the steps that follow, for rate-dependent plastic flow (the
  // materials' flow_viscosity η: overstress η ε̄̇_p, materials/j2_plasticity). 0 (the
  // default) is rate-independent, as in the squeeze, whose loading time the model
  // does not resolve.
  void set_time_step(double seconds);
  // Accepts the last converged step: history, geometry and totals move forward.
  void commit();
  // Points of sheet/sheet interfaces bonded by melting (flags per pairing point, in
  // pairing order). A bonded point is tied: its traction follows the change of the
  // relative position since bonding linearly in tension and compression, t = ε_N
  // (d_b − d), starting from the contact traction of that moment, with no friction
  // limit, so the two sheets move as one body there. Takes effect from the next step.
  void set_bonded(const std::vector<std::vector<char>>& bonded);
  // The same with a bonding degree β ∈ [0, 1] per point (never decreasing; values
  // above 1 read as 1): the tie carries the share β of the traction, contact and
  // friction the share 1 − β. The tie is formed where β first exceeds 0, keeping the
  // contact traction of that moment, so the traction is continuous in β and in time.
  void set_bonding_degree(const std::vector<std::vector<double>>& degree);

  // Totals after the last commit, with the fixed end face at rest (under a mirror the
  // solution moves both end faces; the rigid shift that puts the fixed one back is
  // added, so the outputs are the full mesh's).
  const std::vector<fem::Point>& positions() const { return positions_; }
  Eigen::VectorXd displacement() const;  // nodal (u_r, u_z), node-major
  // Axial displacement of the loaded end face relative to the fixed one (m, < 0
  // closing): w, or 2w under a mirror. solve_displacement_step() prescribes it.
  double end_face_displacement() const { return approach_per_w_ * w_; }
  // Axial force transmitted through the upper end face (N, > 0 pressing), from the
  // last solved step (the reaction in displacement control).
  double electrode_force() const { return force_; }
  std::vector<InterfaceState> interface_states() const;
  // Cell averages over the Gauss points: von Mises stress (Pa), equivalent plastic strain.
  std::vector<double> von_mises() const;
  std::vector<double> equivalent_plastic_strain() const;
  std::vector<PointStress> point_stresses() const;
  // Cell evaluations so far that took the linear update of an elastic cell
  // (MechanicsSettings::linear_elastic_updates) instead of their Gauss points.
  long linear_cell_updates() const;
  MechanicsSolverCounts solver_counts() const;
  double normal_penalty(const std::string& interface) const;
  // The contact pairings (one per mesh interface, in mesh.interfaces order), at the
  // last solved configuration, and the normal pressure at each of their points (Pa).
  // Under a mirror their points stay in the solve's frame, without the rigid shift of
  // positions(): gaps, weights and areas are the same.
  // The electrical and thermal interface laws use the same points.
  const std::vector<contact::InterfacePairing>& pairings() const;
  std::vector<double> contact_pressure(int pairing) const;

  // Residual and tangent of the reduced system for a given increment (force
  // control), for finite-difference checks of the Jacobian.
  void residual_and_tangent(const Eigen::VectorXd& increment, double force, const Eigen::VectorXd& nodal_temperature,
                            Eigen::VectorXd& residual, fem::SparseMatrix& tangent);
  int n_free_force_control() const;
  Eigen::VectorXd full_increment(const Eigen::VectorXd& reduced) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<fem::Point> positions_;
  double w_ = 0, force_ = 0;
  double approach_per_w_ = 1;  // 2 under a mirror: the fixed end face moves by −w
};

}  // namespace rsw::physics
