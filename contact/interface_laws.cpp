// Interface laws: Bay–Wanheim electrical conductance, Simufact thermal conductance,
// closure factor, interface Joule heat, bonding and film breakdown; equations in interface_laws.hpp.
#include "contact/interface_laws.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rsw::contact {

ElectricalConductanceLaw bay_wanheim_conductance(double normal_stress, double flow_stress, double mean_resistivity,
                                                 double coating_resistivity, double film_thickness) {
  // h_e = σ_n / (t_f D),  D = 3 σ_soft ρ̄ + ρ_c σ_n  (paper eq. 1 multiplied through by σ_n)
  const double sn = std::max(normal_stress, 0.0);
  const double D = 3 * flow_stress * mean_resistivity + coating_resistivity * sn;
  const double tD2 = film_thickness * D * D;
  ElectricalConductanceLaw out;
  out.conductance = sn / (film_thickness * D);
  out.d_normal_stress = normal_stress > 0 ? 3 * flow_stress * mean_resistivity / tD2 : 0.0;
  out.d_flow_stress = -3 * sn * mean_resistivity / tD2;
  out.d_resistivity = -3 * sn * flow_stress / tD2;
  return out;
}

ElectricalConductanceLaw bay_wanheim_excess_conductance(double normal_stress, double flow_stress,
                                                        double mean_resistivity, double coating_resistivity,
                                                        double film_thickness, double series_conductance,
                                                        double* d_series) {
  // h_e = σ_n / N,  N = t_f D + σ_n/h_b,  D = ρ̄ (3 σ_soft − σ_n)⁺ + ρ_c σ_n
  const double sn = std::max(normal_stress, 0.0);
  const double excess = 3 * flow_stress - sn;
  const bool partial = excess > 0;  // α < 1: part of the apparent area conducts
  const double D = (partial ? mean_resistivity * excess : 0.0) + coating_resistivity * sn;
  const double N = film_thickness * D + sn / series_conductance;
  ElectricalConductanceLaw out;
  if (!(sn > 0)) {
    if (d_series) *d_series = 0;
    return out;  // open or just touching: no conductance
  }
  const double tN2 = film_thickness / (N * N);
  const double dD_dsn = (partial ? -mean_resistivity : 0.0) + coating_resistivity;
  out.conductance = sn / N;
  out.d_normal_stress = tN2 * (D - sn * dD_dsn);  // ∂(σ_n/N)/∂σ_n; the σ_n/h_b part cancels
  out.d_flow_stress = partial ? -sn * tN2 * 3 * mean_resistivity : 0.0;
  out.d_resistivity = partial ? -sn * tN2 * excess : 0.0;
  if (d_series) *d_series = sn * sn / (N * N * series_conductance * series_conductance);
  return out;
}

ThermalConductanceLaw simufact_conductance(double normal_stress, double yield_stress, double mean_conductivity,
                                           double p1, const ThermalContactConstants& c) {
  // HTC = P1 c̄/P2 E^P4,  E = 1 − exp(−u),  u = P3 (F_n/σ_d + P3)  (paper eq. 2)
  const double fn = std::max(normal_stress, 0.0);
  const double u = c.p3 * (fn / yield_stress + c.p3);
  const double decay = std::exp(-u);
  const double E = 1 - decay;
  const double scale = p1 * mean_conductivity / c.p2;
  const double Ep = std::pow(E, c.p4);
  const double dHdu = scale * c.p4 * std::pow(E, c.p4 - 1) * decay;  // ∂HTC/∂u
  ThermalConductanceLaw out;
  out.conductance = scale * Ep;
  out.d_normal_stress = normal_stress > 0 ? dHdu * c.p3 / yield_stress : 0.0;
  out.d_yield_stress = -dHdu * c.p3 * fn / (yield_stress * yield_stress);
  out.d_conductivity = p1 / c.p2 * Ep;
  return out;
}

Slope closure_factor(double gap, double closure_gap) {
  // χ = 1 − (3 s² − 2 s³), s = g/g_c clamped to [0, 1]
  const double s = gap / closure_gap;
  if (s <= 0) return {1.0, 0.0};
  if (s >= 1) return {0.0, 0.0};
  return {1 - s * s * (3 - 2 * s), -6 * s * (1 - s) / closure_gap};
}

Slope interface_joule_heat(double conductance, double potential_jump) {
  return {conductance * potential_jump * potential_jump, 2 * conductance * potential_jump};
}

double bonded_conductance(double conductivity_1, double conductivity_2, double local_size, double factor) {
  // F · (k_1 + k_2)/2 · 2/h_local
  return factor * (conductivity_1 + conductivity_2) / local_size;
}

bool bonds(double temperature_slave, double solidus_slave, double temperature_master, double solidus_master) {
  return temperature_slave >= solidus_slave && temperature_master >= solidus_master;
}

double bonding_degree(double temperature_slave, double solidus_slave, double temperature_master,
                      double solidus_master, double band) {
  const double above = std::min(temperature_slave - solidus_slave, temperature_master - solidus_master);
  if (above >= 0) return 1.0;
  if (!(band > 0)) return 0.0;
  const double x = std::clamp((above + band) / band, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

double bonding_degree_at_gap(double temperature_slave, double solidus_slave, double temperature_master,
                             double solidus_master, double band, double gap, double bonding_gap) {
  const double chi = closure_factor(gap, bonding_gap).value;
  if (chi <= 0) return 0.0;
  return chi * bonding_degree(temperature_slave, solidus_slave, temperature_master, solidus_master, band);
}

double film_breakdown_degree(double temperature_slave, double temperature_master, double start, double end) {
  const double x = std::clamp((std::max(temperature_slave, temperature_master) - start) / (end - start), 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

double partly_bonded_conductance(double contact, double bonded, double degree) {
  if (degree >= 1) return bonded;
  if (degree <= 0) return contact;
  if (!(contact > 0)) return 0.0;
  return 1.0 / ((1 - degree) / contact + degree / bonded);
}

namespace {
// The softer side's yield stress σ_y(0, T) at each side's own temperature, and its
// slopes with respect to T_a and T_b (one of them is zero).
struct Softer {
  double value = 0, d_a = 0, d_b = 0;
};
Softer softer_yield_stress(const materials::Material& a, double T_a, const materials::Material& b, double T_b) {
  const materials::FlowStress ya = a.yield_stress(0.0, T_a);
  const materials::FlowStress yb = b.yield_stress(0.0, T_b);
  if (ya.yield_stress <= yb.yield_stress) return {ya.yield_stress, ya.temperature_slope, 0.0};
  return {yb.yield_stress, 0.0, yb.temperature_slope};
}
}  // namespace

Conductance electrical_contact_conductance(const materials::Material& a, const materials::Material& b,
                                           double normal_stress, double temperature_a, double temperature_b,
                                           const InterfaceProperties& properties, double film_breakdown,
                                           const Conductance* bulk) {
  const Softer soft = softer_yield_stress(a, temperature_a, b, temperature_b);
  const materials::PropertyValue ra = a.electrical_resistivity(temperature_a);
  const materials::PropertyValue rb = b.electrical_resistivity(temperature_b);
  const double mean_rho = 0.5 * (ra.value + rb.value);
  if (bulk) {
    double d_series = 0;
    const auto law = bay_wanheim_excess_conductance(normal_stress, soft.value, mean_rho,
                                                    properties.coating_resistivity * (1 - film_breakdown),
                                                    properties.film_thickness, bulk->value, &d_series);
    return {law.conductance, law.d_normal_stress,
            law.d_flow_stress * soft.d_a + law.d_resistivity * 0.5 * ra.slope + d_series * bulk->d_temperature_a,
            law.d_flow_stress * soft.d_b + law.d_resistivity * 0.5 * rb.slope + d_series * bulk->d_temperature_b};
  }
  const auto law = bay_wanheim_conductance(normal_stress, soft.value, mean_rho,
                                           properties.coating_resistivity * (1 - film_breakdown),
                                           properties.film_thickness);
  return {law.conductance, law.d_normal_stress, law.d_flow_stress * soft.d_a + law.d_resistivity * 0.5 * ra.slope,
          law.d_flow_stress * soft.d_b + law.d_resistivity * 0.5 * rb.slope};
}

Conductance thermal_contact_conductance(const materials::Material& a, const materials::Material& b,
                                        double normal_stress, double temperature_a, double temperature_b,
                                        const InterfaceProperties& properties,
                                        const ThermalContactConstants& constants) {
  const Softer soft = softer_yield_stress(a, temperature_a, b, temperature_b);
  const materials::PropertyValue ka = a.thermal_conductivity(temperature_a);
  const materials::PropertyValue kb = b.thermal_conductivity(temperature_b);
  const auto law =
      simufact_conductance(normal_stress, soft.value, 0.5 * (ka.value + kb.value), properties.htc_p1, constants);
  return {law.conductance, law.d_normal_stress, law.d_yield_stress * soft.d_a + law.d_conductivity * 0.5 * ka.slope,
          law.d_yield_stress * soft.d_b + law.d_conductivity * 0.5 * kb.slope};
}

Conductance bonded_electrical_conductance(const materials::Material& a, const materials::Material& b,
                                          double temperature_a, double temperature_b, double local_size,
                                          double factor) {
  const materials::PropertyValue ra = a.electrical_resistivity(temperature_a);
  const materials::PropertyValue rb = b.electrical_resistivity(temperature_b);
  // σ = 1/ρ_e, dσ/dT = −ρ_e'/ρ_e²
  const double sa = 1 / ra.value, sb = 1 / rb.value;
  const double dsa = -ra.slope * sa * sa, dsb = -rb.slope * sb * sb;
  return {bonded_conductance(sa, sb, local_size, factor), 0.0, bonded_conductance(dsa, 0.0, local_size, factor),
          bonded_conductance(0.0, dsb, local_size, factor)};
}

Conductance bonded_thermal_conductance(const materials::Material& a, const materials::Material& b,
                                       double temperature_a, double temperature_b, double local_size, double factor) {
  const materials::PropertyValue ka = a.thermal_conductivity(temperature_a);
  const materials::PropertyValue kb = b.thermal_conductivity(temperature_b);
  return {bonded_conductance(ka.value, kb.value, local_size, factor), 0.0,
          bonded_conductance(ka.slope, 0.0, local_size, factor), bonded_conductance(0.0, kb.slope, local_size, factor)};
}

InterfaceHistory::InterfaceHistory(const std::vector<InterfacePairing>& pairings) {
  for (const auto& p : pairings) degree_.emplace_back(p.points().size(), 0.0);
  breakdown_ = degree_;
}

void InterfaceHistory::raise_breakdown(int interface, int point, double value) {
  double& f = breakdown_[interface][point];
  f = std::max(f, std::min(1.0, value));
}

void InterfaceHistory::raise(int interface, int point, double value) {
  double& b = degree_[interface][point];
  b = std::max(b, std::min(1.0, value));
}

int InterfaceHistory::n_bonded(int interface) const {
  if (degree_.empty()) return 0;
  return static_cast<int>(
      std::count_if(degree_[interface].begin(), degree_[interface].end(), [](double b) { return b >= 1.0; }));
}

std::vector<double> slave_face_lengths(const fem::Mesh& mesh, const InterfacePairing& pairing) {
  std::vector<double> out(pairing.n_slave_faces());
  for (int f = 0; f < pairing.n_slave_faces(); ++f) {
    const auto& n = pairing.points()[f * pairing.n_gauss()].slave_nodes;
    out[f] = (mesh.nodes[n[1]] - mesh.nodes[n[0]]).norm();
  }
  return out;
}

}  // namespace rsw::contact
