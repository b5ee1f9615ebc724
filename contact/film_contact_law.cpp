// The film-contact interface law; see film_contact_law.hpp.
#include "contact/film_contact_law.hpp"

namespace rsw::contact {

namespace {
using BondedConductance = Conductance (*)(const materials::Material&, const materials::Material&, double, double,
                                          double, double);

// h_contact at an unbonded point; at β > 0 the film fading in series with the bonded
// layer of conductance `bonded`.
double with_bonding(double h_contact, const InterfacePoint& pt, BondedConductance bonded, double factor) {
  if (!(pt.bonding_degree > 0)) return h_contact;
  const double h_bonded =
      bonded(*pt.slave, *pt.master, pt.slave_temperature, pt.master_temperature, pt.face_length, factor).value;
  return partly_bonded_conductance(h_contact, h_bonded, pt.bonding_degree);
}
}  // namespace

FilmContactLaw::FilmContactLaw(const InterfaceProperties& properties, const FilmContactConstants& constants)
    : properties_(properties), constants_(constants) {}

double FilmContactLaw::electrical_conductance(const InterfacePoint& pt) const {
  double h_contact = 0;
  if (pt.bonding_degree < 1 && pt.pressure > 0) {
    Conductance bulk;
    if (constants_.film_replaces_bulk)
      bulk = bonded_electrical_conductance(*pt.slave, *pt.master, pt.slave_temperature, pt.master_temperature,
                                           pt.face_length, constants_.bonded_factor);
    h_contact = electrical_contact_conductance(*pt.slave, *pt.master, pt.pressure, pt.slave_temperature,
                                               pt.master_temperature, properties_, pt.film_breakdown,
                                               constants_.film_replaces_bulk ? &bulk : nullptr)
                    .value;
  }
  return with_bonding(h_contact, pt, bonded_electrical_conductance, constants_.bonded_factor);
}

double FilmContactLaw::thermal_conductance(const InterfacePoint& pt) const {
  double h_contact = 0;
  if (pt.bonding_degree < 1) {
    const double chi = closure_factor(pt.gap, constants_.closure_gap).value;
    if (chi > 0)
      h_contact = chi * thermal_contact_conductance(*pt.slave, *pt.master, pt.pressure, pt.slave_temperature,
                                                    pt.master_temperature, properties_, constants_.thermal)
                            .value;
  }
  return with_bonding(h_contact, pt, bonded_thermal_conductance, constants_.bonded_factor);
}

double FilmContactLaw::bonding_degree(const InterfacePoint& pt) const {
  if (!properties_.bonding) return 0.0;
  return bonding_degree_at_gap(pt.slave_temperature, pt.slave->solidus(), pt.master_temperature,
                               pt.master->solidus(), constants_.bonding_band, pt.gap, constants_.bonding_gap);
}

double FilmContactLaw::film_breakdown_degree(const InterfacePoint& pt) const {
  if (!constants_.film_breakdown) return 0.0;
  return contact::film_breakdown_degree(pt.slave_temperature, pt.master_temperature, constants_.film_breakdown_start,
                                        constants_.film_breakdown_end);
}

InterfaceModel film_contact_model(const std::vector<InterfaceProperties>& interfaces,
                                  const FilmContactConstants& constants) {
  InterfaceModel model;
  for (const auto& props : interfaces)
    model.interfaces.push_back({props.name, std::make_shared<FilmContactLaw>(props, constants)});
  return model;
}

}  // namespace rsw::contact
