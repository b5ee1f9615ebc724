// The contact law of a film-covered interface (electrode/sheet and sheet/sheet of a
// weld), after paper §2.1.1 (eqs. 1, 2) with the closure and bonding of
// docs/MODEL.md, "Interfaces"; the pure functions are in contact/interface_laws.hpp.
//
//   h_e = Bay–Wanheim conductance h_e(σ_n, T_s, T_m)        where σ_n > 0, else 0  [S/m²]
//   h   = χ(g) · HTC(F_n, T_s, T_m)   (Simufact, paper eq. 2)                   [W/(m²K)]
// and, for an interface that bonds (sheet/sheet), at bonding degree β > 0 the film
// fades in series with a bonded layer of conductance F (k_s + k_m)/h_local:
//   h = 1/((1 − β)/h_contact + β/h_bonded),   β = S(x) χ(g; g_b)  (bonding_degree_at_gap).
// The coating term ρ_c of h_e fades with the film's committed breakdown degree φ
// (film_breakdown_degree of the hotter side's temperature; off: φ = 0).
// The film replaces bulk (film_replaces_bulk, default): the interface adds only the
// constriction resistance in excess of the bulk layer of thickness t_f that the mesh
// already holds, in series with the bonded conductance (bay_wanheim_excess_conductance).
// Each side's properties at its own temperature. Units: Pa, m, °C, Ω·m, W/(m·K).
#pragma once

#include "contact/interface_law.hpp"
#include "contact/interface_laws.hpp"

#include <memory>
#include <vector>

namespace rsw::contact {

// Constants shared by the film-contact interfaces of a model; the weld case's keys
// contact.htc_p2..p4, bonding_band and bonding_gap take their defaults from here.
struct FilmContactConstants {
  ThermalContactConstants thermal;  // P2..P4 of paper eq. 2
  double closure_gap = 1e-6;        // m, g_c of χ(g)
  double bonded_factor = 1e3;       // F of the bonded conductance
  double bonding_band = 50;         // K, Δ of bonding_degree (0: bond at the solidus)
  double bonding_gap = 1e-6;        // m, points farther apart do not bond
  bool film_breakdown = true;       // ρ_c fades with the film breakdown degree φ
  double film_breakdown_start = 20;  // °C, T_start of film_breakdown_degree
  double film_breakdown_end = 700;   // °C, T_end: the film is gone
  bool film_replaces_bulk = true;    // h_e adds only the resistance in excess of bulk (off: eq. 1 as written)
};

class FilmContactLaw : public InterfaceLaw {
 public:
  // `properties.bonding`: points bond as both sides approach their solidus.
  FilmContactLaw(const InterfaceProperties& properties, const FilmContactConstants& constants = {});

  double electrical_conductance(const InterfacePoint& point) const override;
  double thermal_conductance(const InterfacePoint& point) const override;
  bool bonds() const override { return properties_.bonding; }
  double bonding_degree(const InterfacePoint& point) const override;
  double film_breakdown_degree(const InterfacePoint& point) const override;

  const InterfaceProperties& properties() const { return properties_; }
  const FilmContactConstants& constants() const { return constants_; }

 private:
  InterfaceProperties properties_;
  FilmContactConstants constants_;
};

// A model of film-contact interfaces, one per entry of `interfaces` (named by its
// `name`), all with the same constants.
InterfaceModel film_contact_model(const std::vector<InterfaceProperties>& interfaces,
                                  const FilmContactConstants& constants = {});

}  // namespace rsw::contact
