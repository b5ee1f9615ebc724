// The one assembly loop: cell (and boundary-face) kernels return a local matrix K_e
// and vector F_e over the full dofs of a cell; the assembler condenses them through
// the constraints into the reduced system over the free dofs,
//     K_red[p, q] += w_ap w_bq K_e[a, b]
//     F_red[p]    += w_ap (F_e[a] - Σ_b K_e[a, b] g_b)
// where dof a expands as x_a = Σ_p w_ap y_p + g_a (fem/constraints.hpp). This is
// P^T K P and P^T (F - K g) without forming P. The sparsity pattern and the
// position of every contribution in it are computed once, so re-assembly (every
// Newton iteration and time step) only zeroes and accumulates values. Cells are
// coloured so that no two cells of one colour share a free dof; each colour is
// assembled in parallel with OpenMP (kernels must then be thread-safe: keep scratch
// such as CellValues in thread_local storage or build it inside the kernel). Cells
// on a dof shared by more than 16 cells (a "hub", e.g. a rigid end face's motion)
// are assembled serially at the end.
#pragma once

#include "fem/constraints.hpp"
#include "fem/dof_map.hpp"
#include "fem/mesh.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <functional>
#include <vector>

namespace rsw::fem {

using SparseMatrix = Eigen::SparseMatrix<double>;  // column-major, as SuiteSparse wants

struct LocalSystem {
  Eigen::MatrixXd matrix;  // K_e, dofs_per_cell x dofs_per_cell
  Eigen::VectorXd vector;  // F_e
};

class Assembler {
 public:
  using CellKernel = std::function<void(int cell, LocalSystem& local)>;
  using FaceKernel = std::function<void(const BoundaryFace& face, LocalSystem& local)>;
  // Couplings beyond cells, e.g. contact across two bodies: group g couples the dofs
  // groups[g] (in that order: the local system has groups[g].size() rows).
  using GroupKernel = std::function<void(int group, LocalSystem& local)>;
  struct FaceTerm {
    const std::vector<BoundaryFace>* faces;
    FaceKernel kernel;
  };
  struct Terms {
    CellKernel cells;
    std::vector<FaceTerm> faces;
    GroupKernel groups;
  };

  // The constraints must be closed; they may later change their inhomogeneities
  // (and be closed again) but not their structure. `dof_groups` lists the dofs of
  // every coupling group; the pattern covers them too.
  Assembler(const Mesh& mesh, const DofMap& dofs, const Constraints& constraints,
            const std::vector<std::vector<int>>& dof_groups = {});
  int n_groups() const { return static_cast<int>(element_dofs_.size()) - mesh_.n_cells(); }

  int n_free() const { return constraints_.n_free(); }
  int n_colours() const { return static_cast<int>(colours_.size()); }

  // Assembles K_red and F_red. `cell_kernel` may be empty (face terms only) and the
  // matrix may be skipped (assemble_matrix = false, e.g. for a residual check).
  // homogeneous = true ignores the constraint values g (Newton increments).
  void assemble(const Terms& terms, SparseMatrix& K, Eigen::VectorXd& F, bool homogeneous = false,
                bool assemble_matrix = true) const;
  void assemble(const CellKernel& cell_kernel, const std::vector<FaceTerm>& face_terms,
                SparseMatrix& K, Eigen::VectorXd& F, bool homogeneous = false,
                bool assemble_matrix = true) const {
    assemble(Terms{cell_kernel, face_terms, {}}, K, F, homogeneous, assemble_matrix);
  }
  void assemble(const CellKernel& cell_kernel, SparseMatrix& K, Eigen::VectorXd& F) const {
    assemble(Terms{cell_kernel, {}, {}}, K, F);
  }

 private:
  // Element e: cells first (e < n_cells), then coupling groups.
  void scatter(int element, const LocalSystem& local, SparseMatrix& K, Eigen::VectorXd& F,
               bool homogeneous, bool assemble_matrix) const;

  const Mesh& mesh_;
  const DofMap& dofs_;
  const Constraints& constraints_;
  SparseMatrix pattern_;
  std::vector<std::vector<int>> element_dofs_;
  std::vector<int> position_start_;  // per element, into positions_
  std::vector<int> positions_;       // value index of every (a, p, b, q) contribution
  // The constraint expansion of every element dof, copied out of the constraints so
  // that the scatter loop reads one contiguous array: element e's dof a expands to
  // expansion_[expansion_start_[offset_[e] + a] ... expansion_start_[offset_[e] + a + 1]).
  struct Term {
    int dof;
    double weight;
  };
  std::vector<int> offset_;           // per element, into expansion_start_
  std::vector<int> expansion_start_;
  std::vector<Term> expansion_;
  std::vector<int> expanded_size_;    // per element, Σ_a |expansion(a)|
  std::vector<std::vector<int>> colours_;  // cells assembled in parallel, colour by colour
  std::vector<int> serial_cells_;          // cells on hub dofs, assembled serially
};

}  // namespace rsw::fem
