// Node-major dof numbering; see dof_map.hpp.
#include "fem/dof_map.hpp"

#include <stdexcept>

namespace rsw::fem {

DofMap::DofMap(const Mesh& mesh, int n_components, int n_extra)
    : n_components_(n_components), n_extra_(n_extra), n_dofs_(n_components * mesh.n_nodes() + n_extra) {
  if (n_components < 1 || n_components > 2)
    throw std::invalid_argument("DofMap: n_components must be 1 or 2");
}

void DofMap::cell_dofs(const Mesh& mesh, int cell, std::vector<int>& dofs) const {
  dofs.resize(dofs_per_cell());
  const auto& c = mesh.cells[cell];
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < n_components_; ++k) dofs[a * n_components_ + k] = dof(c[a], k);
}

}  // namespace rsw::fem
