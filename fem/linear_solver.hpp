// The one wrapper around the sparse linear solvers: the SuiteSparse direct solvers
// (CHOLMOD and UMFPACK through Eigen's support modules, KLU through its C interface)
// and, inside PreconditionedGmres, SUNDIALS' flexible GMRES (SUNLinSol_SPFGMR on
// serial N_Vectors). CHOLMOD for symmetric positive definite systems (heat and
// electrical conduction, elasticity without friction), UMFPACK and KLU for general
// unsymmetric ones (friction, the thermal tangent with the λ_m blend). The symbolic
// analysis is done once per sparsity pattern and reused by every numerical
// factorisation.
//
// The factorised pattern is that of the entries that have been nonzero in some
// matrix factorised since the caller's pattern was set, not the caller's whole
// pattern: an assembled contact pattern holds every coupling a contact point might
// reach (each slave face with all master faces within the search margin), and most of
// those entries stay exactly zero. They add no value but much fill: on the default
// weld's thermal tangent 2.3·10⁷ against 0.8–1.1·10⁷ flops per factorisation, on the
// mechanics tangent's symmetric part 8.9·10⁷ against 3.5·10⁷ (docs/PERFORMANCE.md).
// Dropping exact zeros changes nothing in the factorised matrix; the
// pattern only grows (a new nonzero entry, such as a contact point reaching another
// master face, is taken in with a new analysis), so the analysis is redone rarely.
#pragma once

#include "fem/assembler.hpp"

#include <Eigen/Core>

#include <functional>
#include <memory>
#include <string>

namespace rsw::fem {

enum class SolverKind { cholmod, umfpack, klu };

// "cholmod", "umfpack" or "klu".
SolverKind solver_kind_from_string(const std::string& name);
std::string to_string(SolverKind kind);

class LinearSolver {
 public:
  explicit LinearSolver(SolverKind kind = SolverKind::cholmod);
  ~LinearSolver();
  LinearSolver(LinearSolver&&) noexcept;
  LinearSolver& operator=(LinearSolver&&) noexcept;

  SolverKind kind() const { return kind_; }
  // Symbolic analyses so far (the used pattern grew, or the caller's pattern changed).
  int n_analyses() const { return n_analyses_; }
  // Numerical factorisation; throws std::runtime_error if the matrix is singular or,
  // for CHOLMOD, not positive definite. KLU refactorises a matrix of the last
  // factorisation's pattern with that factorisation's pivot sequence while the pivots
  // stay sound (see kept_pivots), else it pivots afresh.
  void factorize(const SparseMatrix& A);
  // KLU: the last factorize() reused the pivot sequence of an earlier one.
  bool kept_pivots() const;
  // Solution of A x = b with the last factorisation.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  // Steps of iterative refinement in UMFPACK solves (UMFPACK's default: 2; each costs
  // a product with A and a solve). Other kinds ignore it.
  void set_refinement_steps(int steps);
  // analyze (if needed) + factorize + solve.
  Eigen::VectorXd solve(const SparseMatrix& A, const Eigen::VectorXd& b);

 private:
  friend class PreconditionedGmres;  // copies a supernodal CHOLMOD factor in single precision
  struct Impl;
  SolverKind kind_;
  std::unique_ptr<Impl> impl_;
  int n_analyses_ = 0;
  void analyze(const SparseMatrix& A);  // of the used pattern
};

// Cholesky factor P A Pᵀ = L Lᵀ of a symmetric positive definite matrix
//     A = [A_II  A_IB]
//         [A_BI  A_BB]
// whose last n_border unknowns (the border B) are eliminated after all others (CHOLMOD
// with a constrained minimum-degree ordering, CAMD, that keeps B last). Its trailing
// block then holds the Schur complement of the leading block I,
//     L_BB L_BBᵀ = A_BB − A_BI A_II⁻¹ A_IB,
// and its leading columns are the factor of A_II alone, so one factorisation gives
// both the condensed border matrix and solves with A_II (InteriorElimination). The
// ordering is found once per pattern. Only A's lower triangle is read.
class BorderedCholesky {
 public:
  BorderedCholesky();
  ~BorderedCholesky();
  BorderedCholesky(BorderedCholesky&&) noexcept;
  BorderedCholesky& operator=(BorderedCholesky&&) noexcept;
  // False (nothing kept) if A is not positive definite.
  bool factorize(const SparseMatrix& A, int n_border);
  // A_BB − A_BI A_II⁻¹ A_IB, n_border × n_border, in A's order of B.
  const Eigen::MatrixXd& schur_complement() const { return schur_; }
  // x = A_II⁻¹ b over the leading n − n_border unknowns; x and b may be the same.
  void solve_leading(const double* b, double* x) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Eigen::MatrixXd schur_;
};

// Componentwise relative backward error of an approximate solution x of A x = b
// (Oettli and Prager, Numer. Math. 6 (1964) 405–409; LAPACK's BERR):
//     ω = max_i |b − A x|_i / (|A| |x| + |b|)_i,
// the smallest ε for which x solves some (A + δA) x = b + δb with |δA| ≤ ε|A| and
// |δb| ≤ ε|b| entry by entry. A backward-stable direct solve reaches ω of a small
// multiple of the unit round-off (1.1·10⁻¹⁶) however ill-conditioned A is, where the
// plain relative residual |b − A x|/|b| of the same solution can be 10⁻⁶ (a
// conductance matrix whose entries span 10¹⁰). Dimensionless, between 0 and 1 (x = 0
// gives 1). It bounds what the solve did, not the accuracy of x: that is about the
// condition number of A times ω.
double componentwise_backward_error(const SparseMatrix& A, const Eigen::VectorXd& x, const Eigen::VectorXd& b);

// Iterative solution of a general system A x = b by GMRES (SUNDIALS' SPFGMR, no
// restart, modified Gram-Schmidt), right-preconditioned with a direct factorisation
// of a nearby matrix: the symmetric part (M + Mᵀ)/2 of some earlier matrix M of the
// same pattern (CHOLMOD), or M itself (UMFPACK) when that symmetric part is not
// positive definite. Made for Newton's method on a slowly
// changing, nearly symmetric tangent (the unsymmetric part of a contact tangent is
// the friction coupling): one factorisation serves many iterations and steps, and
// the GMRES iterations show when it has gone stale. The tolerance is on the true
// residual of the system, so the solution does not depend on how old the
// preconditioner is.
//
// A supernodal Cholesky factor (CHOLMOD's choice for the mechanics tangent; the
// scalar conduction matrices factorise column by column) is applied in single
// precision: a float copy of L halves the memory the two triangular solves stream,
// which bounds their speed (0.62 against 0.86 ms per application on the default
// weld's 16 155-unknown tangent, docs/PERFORMANCE.md). The Krylov basis, the products
// with A and the residual stay in double, and the preconditioned vectors are kept
// (flexible GMRES), so the rounding of the preconditioner changes how many
// iterations reach the tolerance, not the accuracy of the solution. Where a fresh
// single-precision factor does not converge, the solve is repeated with the double
// one.
//
// Where the symmetric part of M is not positive definite, a caller may offer a
// surrogate matrix S of the same pattern, nearby and with a positive definite
// symmetric part (for a frictional contact tangent: without the coupling of the
// friction traction to the contact pressure, μ ∂p/∂u, whose symmetric part is
// indefinite where points slide); the factor of (S + Sᵀ)/2 is then tried before the
// LU of M. GMRES still solves with M, so only the iteration count depends on the
// choice.
class PreconditionedGmres {
 public:
  struct Report {
    bool converged = false;
    int iterations = 0;              // GMRES iterations (preconditioner applications)
    double relative_residual = 0;    // |b - A x| / |b|
  };
  PreconditionedGmres();
  ~PreconditionedGmres();
  PreconditionedGmres(PreconditionedGmres&&) noexcept;
  PreconditionedGmres& operator=(PreconditionedGmres&&) noexcept;

  // The surrogate S (see above), formed only when needed; empty: none.
  using Surrogate = std::function<const SparseMatrix&()>;
  // Factorises the preconditioner from M (see above). Throws std::runtime_error if
  // neither factorisation succeeds.
  void set_preconditioner(const SparseMatrix& M, const Surrogate& surrogate = {});
  bool has_preconditioner() const { return kind_ != Kind::none; }
  // Drops the preconditioner (the next solve must set one).
  void reset() { kind_ = Kind::none; }
  // Apply supernodal Cholesky factors in single precision (the default), or never.
  void set_single_precision(bool on) { single_precision_ = on; }
  // Factorise the symmetric part supernodally always (on), or where CHOLMOD's flop
  // count per factor entry says so (the default; LinearSolver). Only a supernodal
  // factor is applied in single precision: for a large factor, whose solves stream
  // it from memory, that pays even where the flop count would choose the simplicial
  // factorisation (the default weld's mechanics tangent, 56 flops per entry once its
  // never-used contact entries are left out: docs/PERFORMANCE.md).
  void set_supernodal(bool on);
  // The current preconditioner is applied in single precision.
  bool single_precision_active() const;
  int n_factorizations() const { return n_factorizations_; }
  int n_surrogates() const { return n_surrogates_; }                   // surrogates formed
  int n_full_factorizations() const { return n_full_factorizations_; }  // LU of M itself

  // x with |b - A x| <= tolerance |b| after at most max_iterations GMRES iterations
  // (no restart), starting from x = 0, or with `from_x` from the x given (if sized as
  // b): GMRES then solves for the correction A d = b − A x to the same absolute
  // residual, and none is needed if x meets the tolerance already. Without convergence
  // x is the last iterate.
  Report solve(const SparseMatrix& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
               int max_iterations, bool from_x = false) const;
  // The same with the refresh policy: the preconditioner is refactorised from A
  // before the solve when there is none or the previous solve of this object needed
  // more than `refresh_after` iterations, and after a solve that did not converge
  // within `max_iterations` (which is then repeated). Throws std::runtime_error if
  // even a fresh preconditioner does not converge.
  Report solve_refreshing(const SparseMatrix& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                          int refresh_after, int max_iterations, const Surrogate& surrogate = {},
                          bool from_x = false);
  int n_iterations() const { return n_iterations_; }  // summed over solve_refreshing

 private:
  enum class Kind { none, symmetric_part, full };
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Kind kind_ = Kind::none;
  bool single_precision_ = true;
  int n_factorizations_ = 0;
  int n_surrogates_ = 0;
  int n_full_factorizations_ = 0;
  int n_iterations_ = 0;
  int last_iterations_ = 0;
  Eigen::Index size_ = -1;  // rows of the matrix the preconditioner was factorised from
};

}  // namespace rsw::fem
