// Exact elimination of interior unknowns from a sparse linear system K y = r (static
// condensation, block Gaussian elimination). With the unknowns split into an interior
// set I and the rest A,
//
//     S y_A = r_A − K_AI K_II⁻¹ r_I,        S = K_AA − K_AI K_II⁻¹ K_IA,
//     y_I = K_II⁻¹ (r_I − K_IA y_A),
//
// which is K y = r rearranged (Y. Saad, Iterative Methods for Sparse Linear Systems,
// 2nd ed., SIAM 2003, §14.2: the Schur complement). K_II must be symmetric positive
// definite, and K_IA = K_AIᵀ. K_IA has nonzero columns only on the border B ⊂ A (the
// unknowns of A coupled to I), so the correction C = K_AI K_II⁻¹ K_IA is a dense
// |B| × |B| block and S has K_AA's pattern plus B × B. One Cholesky factorisation of
// the matrix over I and B with B ordered last (fem::BorderedCholesky) gives C and the
// solves with K_II. An iterative solver then works on |A| unknowns instead of
// |I| + |A|.
//
// It pays where K_II, K_IA and K_AI stay the same over many solves, as the stiffness
// of a region that stays elastic does between the Newton iterations of one load step.
// prepare(K) compares K's interior rows and columns with those it condensed last and
// condenses afresh only where an entry differs, so each solve is that of the K given,
// whatever changed. Units are the caller's.
#pragma once

#include "fem/assembler.hpp"
#include "fem/linear_solver.hpp"

#include <Eigen/Core>

#include <vector>

namespace rsw::fem {

class InteriorElimination {
 public:
  // interior[k] != 0: unknown k of the systems to come is eliminated.
  explicit InteriorElimination(std::vector<char> interior = {});

  int n_unknowns() const { return static_cast<int>(interior_.size()); }
  int n_interior() const { return static_cast<int>(interior_index_.size()); }
  int n_reduced() const { return static_cast<int>(reduced_index_.size()); }
  // Unknowns of A coupled to I (known after the first prepare()).
  int n_border() const { return static_cast<int>(border_.size()); }
  // Condensations done (factorisations of K_II) and prepare() calls that reused one.
  int n_condensations() const { return n_condensations_; }
  int n_reuses() const { return n_reuses_; }

  // Makes the elimination ready for K (square, compressed, n_unknowns() rows):
  // condenses unless K's interior rows and columns equal those condensed last. The
  // matrices must share one sparsity pattern while their column starts do (those of
  // one assembler). Also false for the third matrix in a row whose interior differs
  // from the one before (see prepare()), until two in a row agree again. False
  // if K does not fit, the interior is empty, or K_II is not symmetric positive
  // definite (the caller then solves with K itself).
  bool prepare(const SparseMatrix& K);
  // S of the K prepared, over the unknowns of A in their order.
  const SparseMatrix& reduced() const { return S_; }
  // M_AA − C for a matrix M of the prepared K's pattern (a preconditioner's
  // surrogate): S exactly where M's interior rows and columns are K's.
  const SparseMatrix& reduce_matrix(const SparseMatrix& M);
  // r_A − K_AI K_II⁻¹ r_I for the prepared K (r over all unknowns); r_A alone where
  // |r_I|₂ ≤ negligible. Where the interior's equations are linear (an elastic
  // region), a Newton step solved by expand() leaves the next residual's interior part
  // zero but for rounding ((1 − α) r_I after a step shortened to α): a caller that
  // solves the reduced system to a residual ε may neglect |r_I| ≤ ε/100, as the term
  // it drops is about that size (K_AI K_II⁻¹ transfers the interior loads to the
  // border), and save a solve with K_II.
  Eigen::VectorXd reduce(const Eigen::VectorXd& r, double negligible = 0) const;
  // The whole solution y of K y = r from the solution y_A of the reduced system.
  Eigen::VectorXd expand(const Eigen::VectorXd& r, const Eigen::VectorXd& y_A) const;

 private:
  void build(const SparseMatrix& K);  // maps for K's pattern
  bool condense(const SparseMatrix& K);
  void fill_reduced(const SparseMatrix& M, SparseMatrix& out) const;

  std::vector<char> interior_;
  std::vector<int> interior_index_, reduced_index_;  // unknown of I / A in order
  std::vector<int> local_;                           // unknown → its index within I or A
  std::vector<int> border_;                          // A-indices of B, ascending
  std::vector<int> border_slot_;                     // A-index → its place in B, or −1
  bool symmetric_pattern_ = true;                    // K's pattern (false: never usable)
  // K's pattern, and the positions of its entries in interior rows or columns, whose
  // values (`watched_values_`) were condensed last.
  std::vector<int> pattern_outer_, pattern_inner_;
  std::vector<int> watched_;
  std::vector<double> watched_values_;
  // Entries of K_IA (column in A, row in I) and K_AI (column in I, row in A).
  struct Entry {
    int position, row, column;  // row and column within I or A
    int watch;                  // its index in watched_
  };
  std::vector<Entry> ia_, ai_;
  // The lower triangle of K over I and B (B last) for the factorisation: the position
  // in K of each entry and of its mirror (the entry across the diagonal).
  SparseMatrix bordered_;
  std::vector<int> bordered_position_, bordered_mirror_;
  BorderedCholesky factor_;
  // S's pattern: K_AA's entries (position in K → position in S) and the B × B block.
  std::vector<std::pair<int, int>> aa_map_;  // while building
  struct Run {
    int from, to, length;
  };
  std::vector<Run> aa_runs_;   // cover every position of S but bb_only_
  std::vector<int> bb_only_;
  std::vector<int> bb_position_;  // S position of (B row a, B column b) at a + |B| b
  SparseMatrix S_, S_other_;
  Eigen::MatrixXd C_;  // K_AI K_II⁻¹ K_IA on B × B
  bool ready_ = false;
  int changes_in_a_row_ = 0;  // prepare() calls whose interior differed from the last
  int n_condensations_ = 0, n_reuses_ = 0;
};

}  // namespace rsw::fem
