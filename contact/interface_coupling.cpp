// The interface layer of a scalar field; see interface_coupling.hpp.
#include "contact/interface_coupling.hpp"

#include <stdexcept>

namespace rsw::contact {

InterfaceCoupling::InterfaceCoupling(const fem::Mesh& mesh, InterfaceModel model, const fem::DofMap& dofs,
                                     int n_gauss, double search_margin, const std::string& field)
    : mesh_(mesh), model_(std::move(model)), field_(field) {
  if (model_.interfaces.size() != mesh.interfaces.size())
    throw std::invalid_argument(field_ + ": the interface model must list every mesh interface");
  std::size_t k = 0;
  for (const auto& [name, pair] : mesh.interfaces) {
    const auto& entry = model_.interfaces[k++];
    if (entry.name != name)
      throw std::invalid_argument(field_ + ": interface model out of order at '" + name + "'");
    if (!entry.law) throw std::invalid_argument(field_ + ": interface '" + name + "' has no law");
    pairings_.emplace_back(mesh, name, n_gauss, search_margin);
    const auto& pairing = pairings_.back();
    face_lengths_.push_back(slave_face_lengths(mesh, pairing));
    const int p = static_cast<int>(pairings_.size()) - 1;
    for (int f = 0; f < pairing.n_slave_faces(); ++f) {
      groups_.emplace_back(p, f);
      std::vector<int> g;
      for (int n : pairing.coupling_nodes(f)) g.push_back(dofs.dof(n, 0));
      dof_groups_.push_back(std::move(g));
    }
  }
}

void InterfaceCoupling::check(const ContactState& state) const {
  if (!state.pairings || state.pairings->size() != pairings_.size() || state.pressure.size() != pairings_.size())
    throw std::invalid_argument(field_ +
                                ": the contact state must hold one pairing and one pressure list per interface");
  for (std::size_t p = 0; p < pairings_.size(); ++p) {
    const auto& given = (*state.pairings)[p];
    const auto& own = pairings_[p];
    bool same = given.name() == own.name() && given.n_gauss() == own.n_gauss() &&
                given.n_slave_faces() == own.n_slave_faces() && state.pressure[p].size() == given.points().size();
    for (int f = 0; same && f < own.n_slave_faces(); ++f) same = given.coupling_nodes(f) == own.coupling_nodes(f);
    if (!same)
      throw std::invalid_argument(field_ + ": pairing '" + own.name() +
                                  "' of the contact state differs from the solver's (n_gauss, search margin?)");
  }
}

InterfacePoint InterfaceCoupling::point(const ContactState& state, const InterfaceHistory& history, std::size_t p,
                                        std::size_t i, const Eigen::VectorXd& temperature,
                                        const std::vector<const materials::Material*>& node_material) const {
  const ContactPoint& pt = (*state.pairings)[p].points()[i];
  InterfacePoint s;
  s.slave = node_material[pt.slave_nodes[0]];
  s.master = node_material[pt.master_nodes[0]];
  s.slave_temperature = slave_value(pt, temperature);
  s.master_temperature = master_value(pt, temperature);
  s.pressure = state.pressure[p][i];
  s.gap = pt.gap;
  s.face_length = face_lengths_[p][pt.slave_face];
  s.bonding_degree = law(p).bonds() ? history.degree(static_cast<int>(p), static_cast<int>(i)) : 0.0;
  s.film_breakdown = history.breakdown(static_cast<int>(p), static_cast<int>(i));
  return s;
}

void InterfaceCoupling::conductances(InterfaceField which, const ContactState& state, const InterfaceHistory& history,
                                     const Eigen::VectorXd& temperature,
                                     const std::vector<const materials::Material*>& node_material,
                                     std::vector<std::vector<double>>& out) const {
  out.resize(pairings_.size());
  for (std::size_t p = 0; p < pairings_.size(); ++p) {
    const auto& pairing = (*state.pairings)[p];
    const InterfaceLaw& l = law(p);
    out[p].assign(pairing.points().size(), 0.0);
    for (std::size_t i = 0; i < pairing.points().size(); ++i) {
      const auto& pt = pairing.points()[i];
      if (!pt.paired || pairing.local_index(pt.slave_face, pt.master_nodes[0]) < 0 ||
          pairing.local_index(pt.slave_face, pt.master_nodes[1]) < 0)
        continue;
      const InterfacePoint s = point(state, history, p, i, temperature, node_material);
      out[p][i] = which == InterfaceField::electrical ? l.electrical_conductance(s) : l.thermal_conductance(s);
    }
  }
}

}  // namespace rsw::contact
