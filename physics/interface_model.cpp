// The interface laws of a weld case by interface kind; see interface_model.hpp.
#include "physics/interface_model.hpp"

#include "contact/film_contact_law.hpp"
#include "meshes/weld_mesh.hpp"

#include <stdexcept>

namespace rsw::physics {

namespace {
contact::FilmContactConstants film_constants(const ContactParameters& p) {
  contact::FilmContactConstants c;
  c.thermal = {p.htc_p2, p.htc_p3, p.htc_p4};
  c.bonding_band = p.bonding_band;
  c.bonding_gap = p.bonding_gap;
  c.film_breakdown = p.film_breakdown;
  c.film_breakdown_start = p.film_breakdown_start;
  c.film_breakdown_end = p.film_breakdown_end;
  c.film_replaces_bulk = p.film_replaces_bulk;
  return c;
}

std::shared_ptr<const contact::InterfaceLaw> film_contact(const std::string& kind, const InterfaceContact& c,
                                                          bool bonding, const ContactParameters& p) {
  contact::InterfaceProperties props;
  props.name = kind;
  props.film_thickness = c.film_thickness;
  props.coating_resistivity = c.coating_resistivity;
  props.htc_p1 = c.htc_p1;
  props.bonding = bonding;
  return std::make_shared<contact::FilmContactLaw>(props, film_constants(p));
}
}  // namespace

std::shared_ptr<const contact::InterfaceLaw> interface_law(const std::string& kind, const ContactParameters& p) {
  namespace kinds = meshes::interface_kind;
  if (kind == kinds::electrode_sheet) return film_contact(kind, p.electrode_sheet, /*bonding=*/false, p);
  if (kind == kinds::sheet_sheet) return film_contact(kind, p.sheet_sheet, /*bonding=*/true, p);
  throw std::invalid_argument("no interface law for the interface kind '" + kind + "' (known: " +
                              kinds::electrode_sheet + ", " + kinds::sheet_sheet + ")");
}

contact::InterfaceModel interface_model(const fem::Mesh& mesh, const ContactParameters& parameters) {
  contact::InterfaceModel model;
  for (const auto& [name, pair] : mesh.interfaces) {
    try {
      model.interfaces.push_back({name, interface_law(pair.kind, parameters)});
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("interface '" + name + "': " + e.what());
    }
  }
  return model;
}

}  // namespace rsw::physics
