// An interface law as an object: what crosses one paired point of an interface per
// unit area, given the state of the point's two sides,
//     h_e  (S/m²)      electrical conductance, j = h_e (φ_slave − φ_master),
//     h    (W/(m²K))   thermal conductance,    q = h (T_slave − T_master),
//     β    (-)         the bonding degree the point may reach (laws that bond),
//     φ    (-)         the breakdown degree its coating film may reach (laws with a film).
// The laws themselves are the pure functions of contact/interface_laws.hpp; an
// InterfaceLaw picks them and their parameters for one kind of interface
// (contact/film_contact_law.hpp). The mesh builder sets each interface's kind
// (fem::InterfacePair::kind) and physics/interface_model.hpp turns kinds into laws;
// contact/interface_coupling.hpp evaluates them at the pairing points for the
// electrical and thermal fields.
#pragma once

#include "materials/material.hpp"

#include <memory>
#include <string>
#include <vector>

namespace rsw::contact {

// The state of one paired point, each side's value interpolated on its face.
struct InterfacePoint {
  const materials::Material* slave = nullptr;
  const materials::Material* master = nullptr;
  double slave_temperature = 0;   // °C
  double master_temperature = 0;  // °C
  double pressure = 0;            // Pa, contact normal stress (> 0 pressing)
  double gap = 0;                 // m, > 0 open
  double face_length = 0;         // m, the slave face in the undeformed mesh
  double bonding_degree = 0;      // β ∈ [0, 1], committed (0 for laws that never bond)
  double film_breakdown = 0;      // φ ∈ [0, 1], committed (0: film intact)
};

class InterfaceLaw {
 public:
  virtual ~InterfaceLaw() = default;
  // h_e at the point, S/m² (0: no current crosses).
  virtual double electrical_conductance(const InterfacePoint& point) const = 0;
  // h at the point, W/(m²K).
  virtual double thermal_conductance(const InterfacePoint& point) const = 0;
  // Whether points of this interface bond (and carry a bonding degree).
  virtual bool bonds() const { return false; }
  // The bonding degree the point may reach in its present state (never decreasing:
  // the caller keeps the maximum); 0 for laws that never bond.
  virtual double bonding_degree(const InterfacePoint& /*point*/) const { return 0.0; }
  // The breakdown degree the point's film may reach in its present state (never
  // decreasing: the caller keeps the maximum); 0 for laws without a film that breaks.
  virtual double film_breakdown_degree(const InterfacePoint& /*point*/) const { return 0.0; }
};

// The interfaces of a mesh with their laws, in mesh.interfaces order.
struct InterfaceModel {
  struct Entry {
    std::string name;                          // mesh interface
    std::shared_ptr<const InterfaceLaw> law;
  };
  std::vector<Entry> interfaces;
};

}  // namespace rsw::contact
