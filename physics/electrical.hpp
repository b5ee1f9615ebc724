// Quasi-static electrical conduction in the electrode/sheet stack (docs/MODEL.md, "Fields").
//
//     ∇·(σ(T) ∇φ) = 0 in every body,   σ = 1/ρ_e(T)   (S/m; φ in V)
// on the current configuration (node positions passed in), σ evaluated at each Gauss
// point from the interpolated nodal temperature. Boundary conditions:
// - the upper electrode's end face is an equipotential at the unknown potential V
//   (one extra dof, φ = V on all its nodes) carrying the total current I: the load I
//   on that dof, i.e. ∫_face j·(−n) dA = I;
// - the lower electrode's end face is at φ = 0;
// - every other outer surface is insulated (natural condition);
// - hanging nodes are constrained to their coarse edges.
// Interfaces (the interface layer contact/interface_coupling.hpp): at every paired
// point the normal current density
//     j = h_e (φ_slave − φ_master)   (A/m²)
// with h_e from the interface's law (contact/interface_law.hpp; for the weld
// Bay–Wanheim, paper eq. 1, where the contact pressure p > 0, or the bonded
// conductance). Each slave face is one coupling group over the same coupling nodes as
// the mechanics pairing. Weak form:
//     Σ_cells ∫ σ ∇φ·∇v dV + Σ_points h_e (φ_s − φ_m)(v_s − v_m) A = I v(V)
// The system is linear and symmetric positive definite for a given T and contact
// state: one CHOLMOD factorisation per solve, the symbolic analysis reused; the
// Gauss-point geometry is kept while the node positions do not change (the coupling
// iterations of a step). It is solved for a unit current and scaled by I, so
// R = V/I is defined even at I = 0 (the resistance of a linear conductor does not
// depend on the current).
//
// Outputs: nodal φ, V, dynamic resistance R = V/I and, for configurable probe pairs,
// the potential difference between two material points (located in the undeformed
// mesh, so they move with the material) over I; bulk Joule heat q_v = σ|∇φ|² (W/m³) at
// every cell Gauss point and per cell (volume average); interface Joule heat
// q_s = h_e Δφ² (W/m²) and h_e at every pairing point; total bulk and interface
// powers; the current through every interface (slave to master) and out through the
// ground face (the consistent reaction ∫ σ∇φ·∇w dV, w = 1 on the face nodes) for
// current conservation. Discrete energy identity: V I = bulk + interface power
// (φᵀKφ = φᵀF, to the linear tolerance 10⁻¹⁰), so the thermal solver receives the
// electrical power.
//
// Sources: paper §2.1.1; docs/MODEL.md; verification problems in docs/VERIFICATION.md
// (uniform rod, two-block contact).
#pragma once

#include "contact/interface_law.hpp"
#include "contact/interface_laws.hpp"
#include "contact/interface_pairing.hpp"
#include "fem/mesh.hpp"
#include "fem/mirror.hpp"
#include "materials/material.hpp"
#include "physics/mechanics.hpp"
#include "physics/problem.hpp"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace rsw::physics {

// A voltage probe pair: the potential at `upper` minus the potential at `lower`, both
// (r, z) material points of the undeformed mesh (m).
struct VoltageProbe {
  std::string name;
  fem::Point upper;
  fem::Point lower;
};

struct ElectricalSettings {
  std::string current_boundary = "upper_electrode.end_face";  // equipotential, carries I
  std::string ground_boundary = "lower_electrode.end_face";   // φ = 0
  int n_gauss = 2;                // per direction in cells and along the interfaces
  double search_margin = 0.5e-3;  // m, of the pairings (must equal the mechanics')
  std::vector<VoltageProbe> probes;
  // A mirror symmetry about z = 0 (fem/mirror.hpp), or empty: solve for the upper half,
  // φ odd in z (the ground face is then the current face's image, at −V; potentials and
  // the resistance are reported relative to it, as without the mirror).
  fem::MirrorSymmetry mirror;
};

// A point of the mesh: its cell and reference coordinates (ξ, η) ∈ [-1, 1]².
struct PointLocation {
  int cell = -1;
  double xi = 0, eta = 0;
};
// The cell holding `point` (in the mesh's node positions): the lowest-numbered cell
// whose closure contains it (within 1e-9 in reference coordinates), found by
// inverting the bilinear map with Newton's method. Throws std::out_of_range if no
// cell holds the point.
PointLocation locate_point(const fem::Mesh& mesh, const fem::Point& point);
// Σ N_a(ξ, η) u_a over the cell's nodes.
double interpolate(const fem::Mesh& mesh, const PointLocation& where, const Eigen::VectorXd& nodal);

struct ElectricalSolution {
  double current = 0;     // A, I
  double voltage = 0;     // V, potential of the current face
  double resistance = 0;  // Ω, V/I
  std::vector<double> probe_voltage;     // V, per probe
  std::vector<double> probe_resistance;  // Ω, per probe
  Eigen::VectorXd potential;             // V, nodal φ (hanging nodes included)
  std::vector<double> joule_heat;        // W/m³, σ|∇φ|² per cell Gauss point (cell-major)
  std::vector<std::vector<double>> interface_conductance;  // S/m², h_e per pairing point
  std::vector<std::vector<double>> interface_heat;         // W/m², q_s per pairing point
  std::vector<double> interface_current;  // A, slave to master, per interface
  std::vector<double> interface_power;    // W, ∫ q_s dA per interface
  double bulk_power = 0;                  // W, ∫ q_v dV
  double ground_current = 0;              // A, leaving through the ground face
  double total_interface_power() const;
};

class Electrical {
 public:
  // `body_materials[b]` is the material of mesh body b; `model` holds one entry per
  // mesh interface, in mesh.interfaces order.
  Electrical(const fem::Mesh& mesh, std::vector<const materials::Material*> body_materials,
             contact::InterfaceModel model, const ElectricalSettings& settings = {});
  ~Electrical();

  // Solves for the node positions, nodal temperatures (°C), current I (A), contact
  // state and interface history (bonding, film breakdown; an empty one: none). Throws
  // std::runtime_error if a body has no conducting path (no closed contact).
  const ElectricalSolution& solve(const std::vector<fem::Point>& positions, const Eigen::VectorXd& nodal_temperature,
                                  double current, const contact::ContactState& contact,
                                  const contact::InterfaceHistory& history = {});
  const ElectricalSolution& solution() const { return solution_; }

  // Per cell, from the last solve: Joule heat (volume average, W/m³) and current
  // density j = −σ∇φ (volume average, A/m²).
  std::vector<double> cell_joule_heat() const;
  std::vector<Eigen::Vector2d> cell_current_density() const;
  int n_gauss() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  ElectricalSolution solution_;
};

// The contact state of the mechanics solver after its last step: its pairings and
// the normal stress at their points.
contact::ContactState contact_state(const Mechanics& mechanics);

}  // namespace rsw::physics
