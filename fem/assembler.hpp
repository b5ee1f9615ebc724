// The one assembly loop: cell (and boundary-face) kernels return a local matrix K_e
// and vector F_e over the full dofs of a cell; the assembler condenses them through
// the constraints into the reduced system over the free dofs,
//     K_red[p, q] += w_ap w_bq K_e[a, b]
//     F_red[p]    += w_ap (F_e[a] - Σ_b K_e[a, b] g_b)
// where dof a expands as x_a = Σ_p w_ap y_p + g_a (fem/constraints.hpp). This is
// P^T K P and P^T (F - K g) without forming P. The sparsity pattern and the
// position of every contribution in it are computed once, so re-assembly (every
// Newton iteration and time step) only zeroes and accumulates values. Cells are
// visited in their own order, which keeps neighbouring cells' data and matrix entries
// together in the caches (visiting them colour by colour, across the whole mesh each
// time, makes the default weld 13 % slower on one core: docs/PERFORMANCE.md). With
// one thread no OpenMP region is entered (each of its barriers costs a
// system call, even in a team of one). With T threads the cells are split into T
// blocks of consecutive numbers; each thread assembles, in order, the cells of its
// block whose free dofs no other block touches, and the cells on the block borders
// follow serially (kernels must be thread-safe: keep scratch such as CellValues in
// thread_local storage or build it inside the kernel). Cells on a dof shared by more
// than 16 cells (a "hub", e.g. a rigid end face's motion) are assembled serially at
// the end. Sums over cells are then formed in another order than with one thread, and
// differ in the last bits.
//
// Incremental cell matrices (optional, enable_cell_matrix_cache()): in a Newton
// iteration most cells often return the same matrix as before (an elastic cell
// within a load step). The assembler then keeps each cell's last matrix K_e^old and
// the sum S of all cells' condensed contributions; a matrix assembly scatters, for
// each cell whose matrix changed (bit for bit), only the difference K_e − K_e^old
// into S, and the matrix starts as a copy of S before the face and group terms are
// added. The result equals a fresh assembly to round-off (the sum is formed in
// another order); S is rebuilt from scratch every 64th matrix assembly so that the
// rounding of the differences cannot accumulate. A kernel that knows its matrix is
// unchanged says so (LocalSystem::matrix_kept) and skips forming it: the elastic
// cells of a mechanics Newton iteration, most of the mesh.
#pragma once

#include "fem/constraints.hpp"
#include "fem/dof_map.hpp"
#include "fem/mesh.hpp"
#include "fem/mirror.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <atomic>

#include <functional>
#include <vector>

namespace rsw::fem {

using SparseMatrix = Eigen::SparseMatrix<double>;  // column-major, as SuiteSparse wants

struct LocalSystem {
  Eigen::MatrixXd matrix;  // K_e, dofs_per_cell x dofs_per_cell
  Eigen::VectorXd vector;  // F_e
  // Set by a cell kernel, instead of filling `matrix`, when the cell's matrix is bit for
  // bit the one it returned in its last matrix assembly by this assembler (only with
  // the cell-matrix cache, which then reuses its copy: enable_cell_matrix_cache()).
  bool matrix_kept = false;
  // A group kernel (coupling groups, below) sets lists_touched and lists in `touched`
  // every local dof whose row or column of `matrix` it writes (repeats allowed). Its
  // system is mostly zero (each contact point touches four of the group's nodes), and
  // the assembler then zeroes and scatters only the touched rows and columns. Without
  // lists_touched the whole matrix is scanned.
  bool lists_touched = false;
  std::vector<int> touched;
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
  // Turns on the incremental cell matrices (see above). Worth it where most cell
  // matrices repeat between assemblies; costs 8 n_local² bytes per cell.
  void enable_cell_matrix_cache();
  // Cells whose matrix was scattered (as a difference or afresh) by the matrix
  // assemblies so far, and cells whose unchanged matrix was skipped (cache only).
  long cell_matrices_scattered() const { return cache_scattered_; }
  long cell_matrices_reused() const { return cache_reused_; }

  // Assembles the upper half of a mirror-symmetric problem only (fem/mirror.hpp): each
  // cell and each coupling group weighted by its nodes (1, 1/2, or 0), a boundary face
  // by its cell. Cells and faces of weight 0 are not evaluated; groups of weight 0 are
  // evaluated (a contact kernel keeps history) but not assembled. The constraints must
  // hold the images (add_mirror_constraints). An empty mirror assembles every term again.
  void set_mirror(const MirrorSymmetry& mirror);
  // Weight of cell e in the assembly: 1 without a mirror.
  double cell_weight(int e) const { return element_weight(e); }

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
  // F_e − K_e g into F; `matrix` (column-major, n_local²) is K_e, read only for
  // inhomogeneous constraints.
  void scatter_vector(int element, const Eigen::VectorXd& vector, const double* matrix, Eigen::VectorXd& F,
                      bool homogeneous) const;
  // values[position] += the condensed entries of the local matrix `matrix` (column-major,
  // n_local x n_local) of `element`; zero entries are skipped.
  void scatter_matrix(int element, const double* matrix, int n_local, double* values) const;
  // The same over the entries in rows and columns `touched` (sorted, unique) only: every
  // other entry of `matrix` is zero.
  void scatter_touched(int element, const double* matrix, int n_local, const std::vector<int>& touched,
                       double* values) const;
  // Cell part with the incremental cache: local matrices compared with the kept ones,
  // differences scattered into cache_sum_.
  void scatter_cached(int cell, const LocalSystem& local, Eigen::VectorXd& F, bool homogeneous,
                      bool rebuild) const;

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
  // Per element: 1 if each of its dofs is its own reduced dof (one term of weight 1)
  // or fixed (no term), as for most cells; the scatter then adds the entries as they
  // are, the same sums to the bit (the general loop multiplies them by 1). The matrix
  // path also needs every dof free (a position for every entry).
  std::vector<char> direct_vector_, direct_matrix_;
  std::vector<int> direct_dof_;  // parallel to expansion_start_: the reduced dof of a one-term dof, else -1
  std::vector<std::vector<int>> reduced_dofs_;  // per cell, its free dofs (sorted)
  std::vector<int> serial_cells_;               // cells on hub dofs, assembled serially
  // Threaded assembly (partition()): per thread count, the cells of each block that
  // its thread assembles, and the cells on block borders, assembled serially.
  void partition(int n_threads) const;
  // Zero n x n matrices for the group kernels, by n (assemble(): a group's system is
  // taken from here and returned zeroed; not valid if a kernel threw meanwhile).
  mutable std::vector<Eigen::MatrixXd> zero_group_matrices_;
  mutable std::vector<char> zero_group_valid_;
  mutable int partitioned_threads_ = 0;
  mutable std::vector<std::vector<int>> blocks_;
  mutable std::vector<int> border_cells_;
  // Incremental cell matrices (mutable: a cache of what the kernels returned).
  bool cache_enabled_ = false;
  mutable std::vector<double> cache_matrices_;  // per cell, its last local matrix (n_local², column-major)
  mutable std::vector<double> cache_sum_;       // Σ over cells of their scattered matrices, in K's value order
  mutable int cache_assemblies_ = 0;            // matrix assemblies since the last rebuild (mod 64)
  mutable bool cache_complete_ = false;         // cache_sum_ holds every kept matrix
  mutable std::atomic<long> cache_scattered_{0}, cache_reused_{0};
  // Per element (cells, then groups), with a mirror: 1, 1/2 or 0 (set_mirror); else empty.
  std::vector<double> weight_;
  double element_weight(int element) const { return weight_.empty() ? 1.0 : weight_[element]; }
};

}  // namespace rsw::fem
