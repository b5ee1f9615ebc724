// The interface laws of a weld case: each mesh interface gets the law of its kind
// (fem::InterfacePair::kind, set by meshes/weld_mesh.hpp) with the parameters of the
// case's section of that kind,
//     electrode_sheet -> contact::FilmContactLaw, contact.electrode_sheet.*, no bonding
//     sheet_sheet     -> contact::FilmContactLaw, contact.sheet_sheet.*, bonds
// both with P2–P4 (contact.htc_p2..p4), the bonding band and gap of the case
// (paper eqs. 1, 2; docs/MODEL.md, "Interfaces"). A new law is its class in contact/,
// its keys in the schema (physics/problem.cpp) and one row in interface_law()
// (docs/ARCHITECTURE.md, "The interface laws").
#pragma once

#include "contact/interface_law.hpp"
#include "fem/mesh.hpp"
#include "physics/problem.hpp"

#include <memory>
#include <string>

namespace rsw::physics {

// The law of an interface kind with the case's parameters; throws
// std::invalid_argument for a kind without a law.
std::shared_ptr<const contact::InterfaceLaw> interface_law(const std::string& kind,
                                                           const ContactParameters& parameters);

// One law per mesh interface, in mesh.interfaces order, by kind; throws
// std::invalid_argument naming an interface whose kind has no law.
contact::InterfaceModel interface_model(const fem::Mesh& mesh, const ContactParameters& parameters);

}  // namespace rsw::physics
