// The one constraints object: every constrained dof i satisfies
//     x_i = Σ_j a_ij x_j + b_i
// (hanging nodes: x_h = x_a/2 + x_b/2; Dirichlet values and the axis u_r = 0:
// x_i = b_i). After close(), every constrained dof is expressed through free
// (unconstrained) dofs only: chains such as a hanging node whose parent carries a
// Dirichlet value are resolved, cycles are an error. The free dofs are numbered
// 0..n_free-1; the assembled system lives in that reduced numbering (see
// fem/assembler.hpp), which is exactly P^T K P y = P^T (F - K g) for x = P y + g,
// so Dirichlet conditions are imposed exactly, never by penalty.
// Design after deal.II's AffineConstraints (close, then distribute).
#pragma once

#include "fem/dof_map.hpp"
#include "fem/mesh.hpp"

#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace rsw::fem {

class Constraints {
 public:
  struct Entry {
    int dof;
    double weight;
  };

  explicit Constraints(int n_dofs);

  int n_dofs() const { return n_dofs_; }

  // x_dof = Σ entries + inhomogeneity. A dof can be constrained once; constraining it
  // again throws, unless both are the same fixed value.
  void add_line(int dof, const std::vector<Entry>& entries, double inhomogeneity = 0.0);
  // x_dof = value (Dirichlet, axis).
  void constrain(int dof, double value = 0.0) { add_line(dof, {}, value); }
  // Every hanging node of the mesh, for every component of the field.
  void add_hanging_nodes(const Mesh& mesh, const DofMap& dofs);
  // x = value(node position) for every component `component` of the nodes of a named
  // boundary (hanging nodes never lie on a boundary).
  template <class Function>
  void constrain_boundary(const Mesh& mesh, const DofMap& dofs, const std::string& boundary,
                          int component, Function&& value) {
    for (int n : mesh.boundary_nodes(boundary)) {
      const int d = dofs.dof(n, component);
      if (!is_constrained(d)) constrain(d, value(mesh.nodes[n]));
    }
  }

  // Changes the value b of a fixed-value line (x_dof = value); close() again afterwards.
  void set_value(int dof, double value);

  // Resolves chains and numbers the free dofs. Must be called before the queries below.
  void close();
  bool closed() const { return closed_; }

  bool is_constrained(int dof) const { return line_of_[dof] >= 0; }
  int n_free() const { return n_free_; }
  int n_constrained() const { return n_dofs_ - n_free_; }
  // Reduced index of a free dof, -1 for a constrained one.
  int free_index(int dof) const { return free_index_[dof]; }
  // x_dof = Σ_k weight_k · y[free_k] + inhomogeneity(dof), in the reduced numbering.
  // A free dof expands to itself with weight 1.
  // (Both inline: the assembly's scatter asks for every dof of every element.)
  std::pair<const Entry*, const Entry*> expansion(int dof) const {
    const Entry* base = expansion_entries_.data();
    return {base + expansion_start_[dof], base + expansion_start_[dof + 1]};
  }
  double inhomogeneity(int dof) const { return resolved_inhomogeneity_[dof]; }

  // Full vector from reduced unknowns: x = P y + g (g omitted when homogeneous).
  Eigen::VectorXd distribute(const Eigen::VectorXd& reduced, bool homogeneous = false) const;
  // Reduced vector of the free entries of a full vector.
  Eigen::VectorXd restrict_to_free(const Eigen::VectorXd& full) const;
  // P^T r: a full residual or load vector summed onto the free dofs it depends on.
  Eigen::VectorXd condense(const Eigen::VectorXd& full) const;

  // The resolved table, one line per constrained dof: "dof: inhomogeneity + w*free_dof ...",
  // in full dof numbers; for tests and debugging.
  std::string table() const;

 private:
  struct Line {
    int dof;
    std::vector<Entry> entries;
    double inhomogeneity;
  };
  int n_dofs_;
  bool closed_ = false;
  std::vector<Line> lines_;
  std::vector<int> line_of_;
  int n_free_ = 0;
  std::vector<int> free_index_;
  // Resolved expansions in reduced numbering, CSR-like.
  std::vector<int> expansion_start_;
  std::vector<Entry> expansion_entries_;
  std::vector<double> resolved_inhomogeneity_;
};

}  // namespace rsw::fem
