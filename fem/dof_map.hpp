// Degrees of freedom of a nodal field with n_components values per mesh node
// (1: a scalar such as T or φ; 2: a vector such as u = (u_r, u_z)), over every body
// of the mesh. Numbering is node-major: dof(node, c) = n_components * node + c, so
// a cell's local dof k is (local node k / n_components, component k % n_components).
// Optional extra dofs that belong to no node (e.g. the rigid axial motion of an
// electrode end face) are numbered after the nodal ones.
#pragma once

#include "fem/mesh.hpp"

#include <vector>

namespace rsw::fem {

class DofMap {
 public:
  DofMap(const Mesh& mesh, int n_components, int n_extra = 0);

  int n_components() const { return n_components_; }
  int n_dofs() const { return n_dofs_; }
  int dofs_per_cell() const { return 4 * n_components_; }
  int dof(int node, int component) const { return n_components_ * node + component; }
  int n_extra() const { return n_extra_; }
  int extra_dof(int k) const { return n_dofs_ - n_extra_ + k; }
  // Local dof k of the cell is node cells[cell][k / n_components], component k % n_components.
  void cell_dofs(const Mesh& mesh, int cell, std::vector<int>& dofs) const;

 private:
  int n_components_;
  int n_extra_;
  int n_dofs_;
};

}  // namespace rsw::fem
