// The interface layer of a scalar field (electrical potential, temperature): every
// interface of the mesh paired (contact/interface_pairing.hpp), its law
// (contact/interface_law.hpp), the coupling groups of the assembly (one per slave
// face, over the face's coupling nodes) and the interface conductance at every
// pairing point,
//     h(p, i) = law_p(state of point i)   (S/m² or W/(m²K)),
// 0 where the point is unpaired or its master nodes lie outside the coupling pattern.
// A point's state holds each side's value interpolated on its face,
//     u_slave = w_s0 u(s0) + w_s1 u(s1),   u_master = w_m0 u(m0) + w_m1 u(m1).
// The electrical and thermal solvers each own one, built alike, so their pairings
// match the mechanics' point for point (the contact state they are given is checked
// against them).
#pragma once

#include "contact/interface_law.hpp"
#include "contact/interface_laws.hpp"
#include "contact/interface_pairing.hpp"
#include "fem/dof_map.hpp"
#include "fem/mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace rsw::contact {

// Each side's value at a pairing point, interpolated on its face from nodal values.
inline double slave_value(const ContactPoint& pt, const Eigen::VectorXd& nodal) {
  return pt.slave_weights[0] * nodal[pt.slave_nodes[0]] + pt.slave_weights[1] * nodal[pt.slave_nodes[1]];
}
inline double master_value(const ContactPoint& pt, const Eigen::VectorXd& nodal) {
  return pt.master_weights[0] * nodal[pt.master_nodes[0]] + pt.master_weights[1] * nodal[pt.master_nodes[1]];
}

// u_slave − u_master at a pairing point, summed term by term,
// w_s0 u(s0) + w_s1 u(s1) − w_m0 u(m0) − w_m1 u(m1).
inline double jump(const ContactPoint& pt, const Eigen::VectorXd& nodal) {
  return pt.slave_weights[0] * nodal[pt.slave_nodes[0]] + pt.slave_weights[1] * nodal[pt.slave_nodes[1]] -
         pt.master_weights[0] * nodal[pt.master_nodes[0]] - pt.master_weights[1] * nodal[pt.master_nodes[1]];
}

// A pairing point in the coupling group of its slave face: its four nodes (slave 0,
// slave 1, master 0, master 1) as local indices into coupling_nodes(face) (-1 for a
// master node outside the pattern) and their weights in u_slave − u_master.
struct PointStencil {
  std::array<int, 4> node;
  std::array<double, 4> jump;
  bool in_pattern() const { return node[2] >= 0 && node[3] >= 0; }
};
inline PointStencil point_stencil(const InterfacePairing& pairing, int face, const ContactPoint& pt) {
  return {{pairing.local_index(face, pt.slave_nodes[0]), pairing.local_index(face, pt.slave_nodes[1]),
           pairing.local_index(face, pt.master_nodes[0]), pairing.local_index(face, pt.master_nodes[1])},
          {pt.slave_weights[0], pt.slave_weights[1], -pt.master_weights[0], -pt.master_weights[1]}};
}

// Which conductance of the law a field couples with.
enum class InterfaceField { electrical, thermal };

class InterfaceCoupling {
 public:
  // Pairs every mesh interface (in mesh.interfaces order, which `model` must follow)
  // with `n_gauss` points per slave face; the coupling groups hold the dofs of
  // component 0 of `dofs`. `field` names the solver in error messages. Throws
  // std::invalid_argument if the model does not list the mesh's interfaces in order.
  InterfaceCoupling(const fem::Mesh& mesh, InterfaceModel model, const fem::DofMap& dofs, int n_gauss,
                    double search_margin, const std::string& field);

  std::size_t size() const { return pairings_.size(); }
  const std::vector<InterfacePairing>& pairings() const { return pairings_; }
  const InterfaceLaw& law(std::size_t interface) const { return *model_.interfaces[interface].law; }
  // (interface, slave face) of every coupling group, and the group's dofs.
  const std::vector<std::pair<int, int>>& groups() const { return groups_; }
  const std::vector<std::vector<int>>& dof_groups() const { return dof_groups_; }
  // Length of every slave face in the undeformed mesh, per interface, m.
  const std::vector<std::vector<double>>& face_lengths() const { return face_lengths_; }

  // Throws std::invalid_argument unless the contact state holds one pairing and one
  // pressure list per interface, each pairing like this layer's (n_gauss, search margin).
  void check(const ContactState& state) const;

  // The state of point i of interface p: the sides' materials (`node_material` per
  // mesh node) and temperatures, the pressure and gap of the contact state, β and φ.
  InterfacePoint point(const ContactState& state, const InterfaceHistory& history, std::size_t p, std::size_t i,
                       const Eigen::VectorXd& temperature,
                       const std::vector<const materials::Material*>& node_material) const;

  // The law's conductance at every pairing point into out[p][i] (resized).
  void conductances(InterfaceField which, const ContactState& state, const InterfaceHistory& history,
                    const Eigen::VectorXd& temperature, const std::vector<const materials::Material*>& node_material,
                    std::vector<std::vector<double>>& out) const;

 private:
  const fem::Mesh& mesh_;
  InterfaceModel model_;
  std::string field_;
  std::vector<InterfacePairing> pairings_;
  std::vector<std::vector<double>> face_lengths_;
  std::vector<std::pair<int, int>> groups_;
  std::vector<std::vector<int>> dof_groups_;
};

}  // namespace rsw::contact
