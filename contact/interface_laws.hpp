// Interface laws of the electrode/sheet (E/S) and sheet/sheet (S/S) contacts: what
// crosses a paired contact point per unit area, as pure functions of the local state
// returning the value and the derivatives the field solvers need.
//
// Electrical contact conductance, Bay–Wanheim (paper eq. 1, as in Simufact):
//     ρ_contact = 3 (σ_soft/σ_n) (ρ_1 + ρ_2)/2 + ρ_c,   h_e = 1/(ρ_contact t_f)   [S/m²]
// written as h_e = σ_n / (t_f (3 σ_soft ρ̄ + ρ_c σ_n)), ρ̄ = (ρ_1 + ρ_2)/2, so that
// σ_n → 0 gives h_e → 0 smoothly (no division by zero; σ_n < 0 is read as 0).
// σ_soft: the smaller of the two sides' yield stresses σ_y(ε_p = 0, T) (flow stress of
// the softer material, strength floor included above the solidus); ρ_1, ρ_2: bulk
// resistivities; ρ_c: coating resistivity (Ω·m); t_f: film thickness (m).
//
// The film replaces bulk (default; contact.film_replaces_bulk): eq. 1 is the
// resistivity of a layer of thickness t_f in which only the real-area fraction
// α = σ_n/(3 σ_soft) conducts (Tabor: hardness ≈ 3 × flow stress; Bay–Wanheim: the
// real area grows with σ_n), so at α = 1 its constriction part equals bulk ρ̄. Here
// the interface has zero thickness and the mesh already holds the bulk metal on both
// sides, so the interface adds only what the layer has in excess of that bulk, and
// none once the contact is complete — as constriction resistance is defined: the
// resistance in addition to that of the same conductor in full contact (R. Holm,
// Electric Contacts, 4th ed., Springer 1967; M.G. Cooper, B.B. Mikic and M.M.
// Yovanovich, Int. J. Heat Mass Transfer 12 (1969) 279–300):
//     r = t_f (ρ̄ (3 σ_soft/σ_n − 1)⁺ + ρ_c) + 1/h_b,   h_e = 1/r,
// α capped at 1 (an area fraction), and h_b the bonded layer's conductance (below) in
// series, which keeps h_e finite where r's first part vanishes (at most 1/2000 of a
// cell's resistance). The layer form is our reading; its 1/α growth at small α is
// eq. 1's, where the flux-tube theory of Cooper et al. grows as 1/√α, so the sources
// carry the principle (zero at complete contact), not the shape. Without it
// (film_replaces_bulk: false) the interface counts ρ̄ t_f twice at complete contact:
// with t_f,E/S = 0.48 mm, 14–17 µΩ on each electrode face for the whole weld, which
// melts the electrode (docs/MODEL.md, "Interfaces").
//
// Thermal contact conductance, Simufact form (paper eq. 2):
//     HTC = P1 (c_1 + c_2)/2 (1/P2) (1 − exp(−P3 (F_n/σ_d + P3)))^P4   [W/(m²K)]
// c_i: table thermal conductivities of the two sides (the λ_m modification of paper
// eq. 3 models convection in the bulk melt and is not applied here); F_n: contact
// normal stress (Pa); σ_d: yield stress of the softer side; P2 = 1 µm, P3 = P4 = 1 by
// default (docs/MODEL.md, "Interfaces"). The formula is finite at F_n = 0 (≈ 0.63 P1 c̄/P2), so it is
// applied on closed contact only; to keep the outputs smooth in the parameters the
// flux is multiplied by a C¹ closure factor of the gap g (our choice):
//     χ(g) = 1 − (3 s² − 2 s³),  s = clamp(g/g_c, 0, 1),
// χ = 1 for g ≤ 0 (closed), 0 for g ≥ g_c (open), default g_c = 1 µm: a point that
// opens loses its thermal contact over the first micrometre instead of at once.
//
// Interface Joule heat: q_s = h_e (φ⁺ − φ⁻)² per unit area (W/m²), released half on
// each side of the interface (the convention of MOOSE/MALAMUTE interface heating).
//
// Temperatures (our choice, the paper is silent): each side's properties (ρ_i, c_i,
// its yield stress) at that side's own temperature at the point, T_slave or
// T_master, interpolated on its face. Where the thermal contact is good the two are
// close and any rule agrees; where they differ, their mean would give one body's
// material the other's temperature — a copper face at 1000 °C against steel at
// 1160 °C would read as molten copper (its resistivity doubles across the
// 1070–1080 °C melting range), and the lagged E/S conductances then make the
// electro-thermal coupling cycle (docs/MODEL.md, "Interfaces").
//
// Bonding (our choice; docs/MODEL.md, "Interfaces"): a S/S point bonds as both sides approach their
// solidus, with a degree β that rises smoothly from 0 at Δ (`contact.bonding_band`,
// 50 K) below the colder side's solidus to 1 at it, and never falls (history per
// pairing point, committed after a converged step). Where β < 1 the film's resistance
// fades in series with the bonded layer (partly_bonded_conductance); bonding all at
// once (Δ = 0) made the dynamic resistance drop by up to 10 % in one step where a
// region of the interface reached the solidus together, a step earlier or later for
// neighbouring parameter values. A bonded point conducts like bulk material: electrical and
// thermal conductance h = F · k̄ · 2/h_local, k̄ the mean of the two sides' bulk
// conductivities (σ = 1/ρ_e, or the table k), each at its side's temperature, and h_local the length of the
// slave face in the undeformed mesh. 2 k̄/h_local is the conductance of a layer of
// half a cell; the factor F (default 10³) makes the bonded interface's resistance
// 1/(2000) of one cell's and about 10⁻⁵ of the sheet stack's, negligible, while
// keeping the assembled systems well conditioned for the direct solvers.
//
// Film breakdown (our choice; docs/MODEL.md, "Interfaces"): ρ_c stands for the surface
// films (oxide, contaminants, coating), and measured contact resistances of steel
// fall steeply as the interface heats under load (M. Vogler and S. Sheppard, Weld. J.
// 72 (1993) 231s–238s; S.S. Babu et al., Sci. Technol. Weld. Join. 6 (2001) 126–132;
// P. Rogeon et al., J. Mater. Process. Technol. 195 (2008) 117–124). So ρ_c is
// multiplied by 1 − φ, the breakdown degree
//     φ = S(x),  x = clamp((T_hot − T_start)/(T_end − T_start), 0, 1),  S(x) = 3x² − 2x³,
// T_hot the hotter side's temperature. The band, T_start = 20 °C to T_end = 700 °C by
// default (`contact.film_breakdown_start`, `_end`), the use of the hotter side and the
// irreversibility are modelling choices, not measured values: a broken film does not
// re-form within a weld, so φ is a history per pairing point (the largest value
// reached, committed after a converged step, as β is). Coated sheets (zinc melts at
// about 420 °C) may need another band. The constriction term 3 σ_soft ρ̄ keeps its own
// temperature dependence.
//
// Sources: paper §2.1.1 (eqs. 1, 2); N. Bay and T. Wanheim, Wear 38 (1976) 201–209
// (real contact area against normal stress); MOOSE electrical contact and MALAMUTE
// interface heating verification problems (closed-form two-block solutions).
#pragma once

#include "contact/interface_pairing.hpp"
#include "materials/material.hpp"

#include <string>
#include <vector>

namespace rsw::contact {

// ---------------------------------------------------------------------------------
// Pure laws (numbers in, value and partial derivatives out).

// h_e of paper eq. 1 and its partial derivatives.
struct ElectricalConductanceLaw {
  double conductance = 0;      // S/m², h_e
  double d_normal_stress = 0;  // ∂h_e/∂σ_n, S/(m²·Pa)
  double d_flow_stress = 0;    // ∂h_e/∂σ_soft
  double d_resistivity = 0;    // ∂h_e/∂ρ̄, S/(m²·Ω·m)
};
// h_e = σ_n / (t_f (3 σ_soft ρ̄ + ρ_c σ_n)); σ_n in Pa (< 0 read as 0), σ_soft in Pa,
// ρ̄ and ρ_c in Ω·m, t_f in m.
ElectricalConductanceLaw bay_wanheim_conductance(double normal_stress, double flow_stress,
                                                 double mean_resistivity, double coating_resistivity,
                                                 double film_thickness);
// The same film as a zero-thickness interface on a mesh that already holds the bulk
// metal the film stands for: only the constriction resistance in excess of that bulk
// layer, with the real-area fraction α = σ_n/(3 σ_soft) capped at 1 (complete
// contact), in series with the bulk-like conductance h_b that keeps h_e finite:
//     r = t_f (ρ̄ (3 σ_soft/σ_n − 1)⁺ + ρ_c) + 1/h_b,   h_e = 1/r
//       = σ_n / (t_f D + σ_n/h_b),   D = ρ̄ (3 σ_soft − σ_n)⁺ + ρ_c σ_n.
// d_resistivity is ∂h_e/∂ρ̄; ∂h_e/∂h_b is returned in d_series.
ElectricalConductanceLaw bay_wanheim_excess_conductance(double normal_stress, double flow_stress,
                                                        double mean_resistivity, double coating_resistivity,
                                                        double film_thickness, double series_conductance,
                                                        double* d_series = nullptr);

// HTC of paper eq. 2 and its partial derivatives.
struct ThermalConductanceLaw {
  double conductance = 0;       // W/(m²K), HTC
  double d_normal_stress = 0;   // ∂HTC/∂F_n
  double d_yield_stress = 0;    // ∂HTC/∂σ_d
  double d_conductivity = 0;    // ∂HTC/∂c̄, c̄ = (c_1 + c_2)/2
};
// Constants of eq. 2 (P1 is per interface type, see InterfaceProperties).
struct ThermalContactConstants {
  double p2 = 1e-6;  // m
  double p3 = 1.0;   // -
  double p4 = 1.0;   // -
};
// HTC = P1 c̄ /P2 (1 − exp(−P3 (F_n/σ_d + P3)))^P4; F_n in Pa (< 0 read as 0).
ThermalConductanceLaw simufact_conductance(double normal_stress, double yield_stress, double mean_conductivity,
                                           double p1, const ThermalContactConstants& constants);

// A value and its derivative with respect to its one argument.
struct Slope {
  double value = 0;
  double slope = 0;
};
// χ(g) and dχ/dg (1/m): 1 for g ≤ 0, 0 for g ≥ g_c, C¹ in between.
Slope closure_factor(double gap, double closure_gap);
// q_s = h_e Δφ² (W/m²) and dq_s/dΔφ, Δφ = φ_slave − φ_master.
Slope interface_joule_heat(double conductance, double potential_jump);
// h = F (k_1 + k_2)/2 · 2/h_local = F (k_1 + k_2)/h_local, per unit area; k in S/m or
// W/(m·K), h_local in m.
double bonded_conductance(double conductivity_1, double conductivity_2, double local_size, double factor);
// A S/S point bonds when both sides are at or above their solidus (°C).
bool bonds(double temperature_slave, double solidus_slave, double temperature_master, double solidus_master);
// Bonding degree β ∈ [0, 1] at the temperatures of the two sides (°C):
//   β = S(x), x = clamp((min(T_s − T_sol,s, T_m − T_sol,m) + Δ)/Δ, 0, 1), S(x) = 3x² − 2x³,
// 0 up to Δ below the solidus of the colder side, 1 from the solidus (both sides) on,
// C¹ in between; Δ = 0 is bonds() as 0 or 1. Our choice (docs/MODEL.md, "Interfaces").
double bonding_degree(double temperature_slave, double solidus_slave, double temperature_master,
                      double solidus_master, double band);
// Sheets fuse only where they touch: the bonding degree a point may reach at its gap g
// (m, positive open) is the thermal degree above times the closure factor's shape
// taken over the bonding gap g_b (`contact.bonding_gap`, 1 µm by default), β = S(x)
// χ(g; g_b): full where the surfaces are closed (g ≤ 0), none from g_b on, C¹ in
// between. Without the factor the
// sheets of the default weld bonded across gaps of 10–55 µm that had opened beside
// the contact as the centre expanded, and the ties then held them apart as struts
// carrying about 1.3 GPa (MODEL.md, "Interfaces"). Our choice.
double bonding_degree_at_gap(double temperature_slave, double solidus_slave, double temperature_master,
                             double solidus_master, double band, double gap, double bonding_gap);
// Film breakdown degree φ ∈ [0, 1] at the temperatures of the two sides (°C): S(x) of
// the hotter side between T_start and T_end (T_end > T_start), C¹ in T_hot.
double film_breakdown_degree(double temperature_slave, double temperature_master, double start, double end);
// Conductance of a point with bonding degree β: the contact's film resistance fades
// with 1 − β in series with the bonded layer, h = 1/((1 − β)/h_contact + β/h_bonded);
// β = 0 gives h_contact, β = 1 h_bonded, h_contact = 0 (open) gives 0 below β = 1.
double partly_bonded_conductance(double contact, double bonded, double degree);

// ---------------------------------------------------------------------------------
// The laws with material properties evaluated at the interface temperature.

// Parameters of one interface (of a FilmContactLaw, contact/film_contact_law.hpp).
struct InterfaceProperties {
  std::string name;                // mesh interface
  double film_thickness = 0;       // m, t_f
  double coating_resistivity = 0;  // Ω·m, ρ_c
  double htc_p1 = 0;               // -, P1
  bool bonding = false;            // sheet/sheet: bonds when both sides pass the solidus
};

// A conductance with its derivatives with respect to the normal stress and to the
// two sides' temperatures (through the temperature-dependent properties).
struct Conductance {
  double value = 0;            // S/m² or W/(m²K)
  double d_pressure = 0;       // per Pa
  double d_temperature_a = 0;  // per K, side a (the first material)
  double d_temperature_b = 0;  // per K, side b
};

// Bay–Wanheim h_e between material a at T_a and material b at T_b (°C), normal stress
// σ_n, with the film broken down to degree φ (ρ_c (1 − φ) in place of ρ_c; φ is a
// history, so the temperature derivatives do not include it). The min() choosing the
// softer side is only C⁰ where the two yield curves cross.
// With `bulk` (a conductance > 0, e.g. bonded_electrical_conductance), the excess
// form bay_wanheim_excess_conductance in series with it; without, eq. 1 as written.
Conductance electrical_contact_conductance(const materials::Material& a, const materials::Material& b,
                                           double normal_stress, double temperature_a, double temperature_b,
                                           const InterfaceProperties& properties, double film_breakdown = 0.0,
                                           const Conductance* bulk = nullptr);
// Simufact HTC between material a at T_a and b at T_b, normal stress F_n (no closure factor).
Conductance thermal_contact_conductance(const materials::Material& a, const materials::Material& b,
                                        double normal_stress, double temperature_a, double temperature_b,
                                        const InterfaceProperties& properties, const ThermalContactConstants& constants);
// Bonded conductances (σ = 1/ρ_e of both sides, or their table k), each side at its
// own temperature.
Conductance bonded_electrical_conductance(const materials::Material& a, const materials::Material& b,
                                          double temperature_a, double temperature_b, double local_size, double factor);
Conductance bonded_thermal_conductance(const materials::Material& a, const materials::Material& b,
                                       double temperature_a, double temperature_b, double local_size, double factor);

// ---------------------------------------------------------------------------------
// State shared by the electrical and thermal solvers.

// The mechanical contact state: the pairings (one per mesh interface, in
// mesh.interfaces order, projected at the current configuration) and the contact
// normal stress at each of their points (Pa). physics::contact_state(Mechanics)
// builds it from the mechanics solver.
struct ContactState {
  const std::vector<InterfacePairing>* pairings = nullptr;
  std::vector<std::vector<double>> pressure;  // per interface, per pairing point
};

// The history of every pairing point of every interface, committed after a converged
// step and never decreasing: the bonding degree β (interfaces that bond) and the film
// breakdown degree φ (film_breakdown_degree).
class InterfaceHistory {
 public:
  InterfaceHistory() = default;
  explicit InterfaceHistory(const std::vector<InterfacePairing>& pairings);

  bool empty() const { return degree_.empty(); }
  int n_interfaces() const { return static_cast<int>(degree_.size()); }
  double degree(int interface, int point) const { return degree_.empty() ? 0.0 : degree_[interface][point]; }
  bool bonded(int interface, int point) const { return degree(interface, point) >= 1.0; }
  // β ← max(β, value), at most 1.
  void raise(int interface, int point, double value);
  void bond(int interface, int point) { raise(interface, point, 1.0); }
  int n_bonded(int interface) const;  // points with β = 1
  // φ of the point's coating film (0 intact, 1 gone).
  double breakdown(int interface, int point) const {
    return breakdown_.empty() ? 0.0 : breakdown_[interface][point];
  }
  // φ ← max(φ, value), at most 1.
  void raise_breakdown(int interface, int point, double value);

 private:
  std::vector<std::vector<double>> degree_;
  std::vector<std::vector<double>> breakdown_;
};

// Length of every slave face of a pairing in the undeformed mesh (h_local of the
// bonded conductance), m.
std::vector<double> slave_face_lengths(const fem::Mesh& mesh, const InterfacePairing& pairing);

}  // namespace rsw::contact
