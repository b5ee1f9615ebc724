// Transient heat conduction in the electrode/sheet stack (docs/MODEL.md, "Fields"), backward
// Euler in enthalpy form, solved by Newton's method:
//
//   Σ_a M_a (H(T_a) − H(T_a^n))/Δt v_a + ∫ k(T) ∇T·∇v dV
//       = ∫ q_v v dV + Σ_points ½ q_s (v_s + v_m) A − Σ_points h (T_s − T_m)(v_s − v_m) A
//         − ∫_water h_w (T − T_w) v dA − ∫_air h_air (T − T_amb) v dA
//
// - H(T): specific enthalpy with latent heat (materials::Material::enthalpy, J/kg),
//   H' = dH/dT the apparent heat capacity. The capacity term is lumped at the nodes
//   (row-sum mass M_a = ∫ ρ_0 N_a dV_0 on the undeformed mesh, ρ_0 = density at
//   20 °C): the body's mass does not change when it deforms, and nodal enthalpy keeps
//   a narrow melting range monotone (no consistent-mass overshoot ahead of a front).
//   The Newton tangent carries M_a H'(T_a)/Δt exactly, and the residual uses H
//   itself, so the latent heat is conserved whatever the step: the energy stored in a
//   step is Σ_a M_a (H(T_a) − H(T_a^n)).
// - k(T): the table conductivity; for the sheet bodies (name prefix "sheet_") k = λ_m
//   at and above T_melting (paper eq. 3, λ_m = thermal.melt_conductivity), switched
//   per Gauss point. An optional band of width δ below T_melting blends the two C¹
//   (k = (1 − w) k_table + w λ_m, w = smoothstep(T; T_m − δ, T_m); in nodal
//   Kirchhoff form, below); δ = 0 (the settings' default) is the paper's switch. The sharp switch states are set once per step, at the
//   step's predicted field (our choice): a state that flipped between the iterations
//   of one step could keep a Gauss point near T_melting cycling between λ_m and the
//   table, and no iteration would settle.
// - Coefficients (our choice): each solve evaluates the table k(T) at the cell
//   Gauss points and the interface conductances h at the field it starts from. Like
//   σ(T) of the electrical field, they are brought up to date by the staggered
//   coupling iterations of a step (a fixed point of those iterations is the fully
//   implicit solution). Implicit table k(T) and h(T_s, T_m) made Newton stall on the
//   weld: h falls steeply near the solidus, where σ_d drops to the strength floor,
//   and the kinks of the piecewise-linear k and σ_d tables trap the iterates; the
//   flux stays conservative either way.
// - The λ_m blend (band δ > 0) is implicit, in nodal Kirchhoff form: in a sheet cell
//   the flux is −k_t ∇T − (λ_m − k_t) ∇(Σ_b N_b W(T_b)), W(T) = ∫ w dT the integral
//   of the blend weight, k_t the table value at the solve's start. Its tangent
//   [k_t + (λ_m − k_t) w(T_b)] ∇N_b·∇N_a is unsymmetric (KLU) but bounded. A
//   lagged blend made the coupling map steeply decreasing where a thin layer melts
//   (k rising sixfold within 20 K: a layer computed with the table k overheats, with
//   λ_m it falls below the band), and the coupling cycled by hundreds of kelvin
//   (design point 44 of the Table I study, 4 ms: 60 iterations at six retries without
//   convergence; now 5). A Gauss-point blend k(T_q) with its tangent term
//   k'(T_q) N_b ∇T·∇N_a was tried first: that term dwarfs the conduction where the
//   band meets a steep gradient, and Newton took steps of 10⁴ K and stalled on the
//   default weld at 16 ms. For a cell whose nodes lie on one side of the band the
//   two forms agree; across it the Kirchhoff form conducts with the mean of k over
//   the nodal temperature range (exact for steady 1-D conduction).
// - Newton: the tangent is exact for the solve's problem and symmetric (capacity
//   M_a H'(T_a)/Δt, conduction k ∇N·∇N, convection, interface conductances;
//   CHOLMOD, symbolic analysis reused). A backtracking line search on |R| guards the
//   large corrections (the S-shaped enthalpy of a melting range can make full steps
//   cycle). Corrections reuse the step's last factorisation (chord steps) while
//   they shrink fourfold per iteration and are taken whole. The iteration ends when a full
//   correction is below `temperature_tolerance` (∞-norm). Each step starts from the
//   linear extrapolation of the last two committed fields.
// - Conduction, sources and boundary terms live on the current configuration (node
//   positions passed in), like the electrical field, so the Joule heat integrates to
//   exactly the electrical power.
// - Sources: bulk Joule heat q_v (W/m³) at the cell Gauss points and interface Joule
//   heat q_s (W/m²) at the pairing points, both from physics::Electrical; q_s is
//   released half on each side, distributed with the side's interpolation weights.
// - Interfaces (the interface layer contact/interface_coupling.hpp, shared with the
//   electrical field): at every paired point the flux h (T_s − T_m) with h from the
//   interface's law (contact/interface_law.hpp; for the weld HTC(F_n, T_s, T_m) χ(g),
//   paper eq. 2 times the C¹ closure factor, or the bonded conductance at bonded S/S
//   points, perfect thermal contact).
// - Boundaries: water cooling q = h_w (T − T_w) on every "*.cooling_bore"; air
//   q = h_air (T − T_amb) on every other named outer boundary except the axis
//   ("*.axis", symmetry) and the electrode end faces ("*.end_face", adiabatic: the
//   cap continues into its holder there). Sheet and electrode surfaces that are in
//   contact keep their air term too: with h_air = 20 W/(m²K) it removes about 1 W from
//   a closed contact of 30 mm² at 1500 °C, against ~10 kW of Joule heat, and it
//   spares a switch on the contact state. Fixed temperatures on named boundaries are
//   offered for verification problems.
// - Initial temperature uniform (settings), or a given field.
//
// Outputs: nodal T (last solve), committed T, peak temperature (nodal maximum over
// the committed steps), liquid fraction, HTC at the pairing points, the bonded state
// (committed with the step: a S/S point whose two sides are both at or above their
// solidus after a converged step bonds for good) and the energy of the last step:
// stored ∫ρ_0 ΔH dV, generated (bulk, interface) and removed (water, air, fixed
// temperatures, the last as the consistent reaction), so that a driver can check
// ∫ V I dt = stored + removed.
//
// Sources: paper §2.1.2 (eq. 3) and §2.1.1 (eq. 2); docs/MODEL.md; enthalpy method after
// V.R. Voller, C.R. Swaminathan, B.G. Thomas, Int. J. Numer. Meth. Eng. 30 (1990)
// 875–898 (fixed-grid enthalpy with nodal lumping).
#pragma once

#include "contact/interface_law.hpp"
#include "contact/interface_laws.hpp"
#include "fem/mesh.hpp"
#include "fem/mirror.hpp"
#include "materials/material.hpp"
#include "physics/problem.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace rsw::physics {

struct ThermalSettings {
  int n_gauss = 2;                    // per direction; must match the electrical solver's
  double search_margin = 0.5e-3;      // m, of the pairings (must equal the mechanics')
  // The weld case's initial and boundary values (thermal.*), defaults from its schema.
  double initial_temperature = case_default("thermal.initial_temperature");  // °C
  double water_htc = case_default("thermal.water_htc");                      // W/(m²K), on "*<water_suffix>"
  double water_temperature = case_default("thermal.water_temperature");      // °C
  double air_htc = case_default("thermal.air_htc");                          // W/(m²K), other named outer boundaries
  double ambient_temperature = case_default("thermal.ambient_temperature");  // °C
  std::string water_suffix = ".cooling_bore";
  std::vector<std::string> adiabatic_suffixes = {".axis", ".end_face"};
  // Fixed temperatures (°C) on named boundaries (verification problems); these
  // boundaries get no convection.
  std::vector<std::pair<std::string, double>> fixed_temperatures;
  // W/(m·K), λ_m (thermal.melt_conductivity); <= 0 keeps the tables everywhere
  double melt_conductivity = case_default("thermal.melt_conductivity");
  std::string melt_conductivity_prefix = "sheet_";  // bodies whose k switches to λ_m
  // K, blend band below T_melting (thermal.melt_conductivity_band; 0: sharp switch)
  double melt_conductivity_band = case_default("thermal.melt_conductivity_band");
  // With a blend band: the blend is implicit in nodal Kirchhoff form (above; the
  // table part of k stays at the solve's starting field) and the tangent unsymmetric
  // (KLU instead of CHOLMOD). false: the blend at the solve's starting field too.
  bool implicit_melt_blend = true;
  int max_iterations = 40;
  // K, ∞-norm of a full Newton correction that ends the iteration: the field is then
  // within ~10⁻⁵ K of the solve's discrete solution (chord steps contract fourfold at
  // least), and the energy balance of a weld step closes to ~10⁻⁹ of its Joule heat.
  double temperature_tolerance = 1e-4;
  // Each step starts from the linear extrapolation of the last two committed fields
  // (from the committed field if false or at the first step).
  bool extrapolate = true;
  bool verbose = false;  // print Newton iterations to stderr
  // A mirror symmetry about z = 0 (fem/mirror.hpp), or empty: solve for the upper half,
  // T even in z. Mesh, materials and boundary values must then be symmetric.
  fem::MirrorSymmetry mirror;
};

// The settings of a weld case (initial temperature, cooling, air, λ_m).
ThermalSettings thermal_settings(const ThermalParameters& parameters);

// Energy of the last solved step, J.
struct ThermalEnergy {
  double stored = 0;               // Σ M_a (H(T_a) − H(T_a^n))
  double generated_bulk = 0;       // Δt ∫ q_v dV
  double generated_interface = 0;  // Δt Σ q_s A
  double removed_water = 0;        // Δt ∫ h_w (T − T_w) dA
  double removed_air = 0;          // Δt ∫ h_air (T − T_amb) dA
  double removed_fixed = 0;        // Δt · heat leaving through fixed-temperature boundaries
  double generated() const { return generated_bulk + generated_interface; }
  double removed() const { return removed_water + removed_air + removed_fixed; }
  double imbalance() const { return generated() - stored - removed(); }
};

// Linear algebra of the thermal solves so far: corrections solved (Newton and chord
// steps) and factorisations of the tangent.
struct ThermalSolverCounts {
  long solves = 0;
  long factorisations = 0;
};

struct ThermalStepReport {
  bool converged = false;
  int iterations = 0;
  int factorizations = 0;
  double correction = 0;  // K, ∞-norm of the last Newton correction
  std::string message;
};

class Thermal {
 public:
  // `body_materials[b]` is the material of mesh body b; `model` holds one entry per
  // mesh interface, in mesh.interfaces order.
  Thermal(const fem::Mesh& mesh, std::vector<const materials::Material*> body_materials,
          contact::InterfaceModel model, const ThermalSettings& settings = {});
  ~Thermal();

  // Replaces the committed (and trial, and peak) temperature field, °C.
  void set_temperature(const Eigen::VectorXd& nodal_temperature);

  // One backward Euler step of length dt (s) from the committed field, with the
  // bulk Joule heat per cell Gauss point (W/m³, cell-major, may be empty) and the
  // interface Joule heat per pairing point (W/m², may be empty). The first call of a
  // step starts from predicted_temperature(dt); repeated calls before commit()
  // (staggered coupling) start from the previous call's result, or from the field
  // given to set_start().
  // `tolerance` (K, > 0) replaces settings.temperature_tolerance for this solve: a
  // coupling iteration far from its fixed point needs the field only roughly.
  ThermalStepReport solve(double dt, const std::vector<fem::Point>& positions, const contact::ContactState& contact,
                          const std::vector<double>& joule_heat,
                          const std::vector<std::vector<double>>& interface_heat, double tolerance = 0);
  // The field a new step of length dt starts from: the linear extrapolation of the
  // last two committed fields (the committed field at the first step or without
  // `extrapolate`).
  Eigen::VectorXd predicted_temperature(double dt) const;
  // The next solve of this step starts from `nodal_temperature` and evaluates its
  // coefficients (k, h; at the step's first solve also the λ_m switch) there: a
  // coupling iteration that relaxes or accelerates the temperature hands its iterate
  // over this way.
  void set_start(const Eigen::VectorXd& nodal_temperature);
  // Accepts the last solve: committed T, peak T and bonded points move forward.
  void commit();

  const Eigen::VectorXd& temperature() const;            // °C, last solve
  const Eigen::VectorXd& committed_temperature() const;  // °C
  const Eigen::VectorXd& peak_temperature() const;       // °C, committed nodal maximum
  Eigen::VectorXd liquid_fraction() const;               // of temperature()
  const ThermalEnergy& energy() const;                   // of the last solve
  ThermalSolverCounts solver_counts() const;             // summed over the run
  const contact::InterfaceHistory& interface_history() const;  // committed β and φ
  // h at every pairing point of the last solve (HTC·χ, or bonded), W/(m²K).
  const std::vector<std::vector<double>>& interface_conductance() const;

  // For finite-difference checks of the Newton tangent: the reduced residual R and
  // ∂R/∂T of a step of length dt from the committed field, at the free values
  // `reduced` (the field is expanded through the constraints). The coefficients (k,
  // h, λ_m switch states) are taken at `reference` (a full nodal field), as a solve
  // starting there would.
  void residual_and_tangent(double dt, const std::vector<fem::Point>& positions, const contact::ContactState& contact,
                            const std::vector<double>& joule_heat,
                            const std::vector<std::vector<double>>& interface_heat, const Eigen::VectorXd& reference,
                            const Eigen::VectorXd& reduced, Eigen::VectorXd& residual, Eigen::SparseMatrix<double>& tangent);
  // The free values of a full nodal field, and the full field of free values.
  Eigen::VectorXd free_values(const Eigen::VectorXd& nodal_temperature) const;
  Eigen::VectorXd nodal_values(const Eigen::VectorXd& free) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rsw::physics
