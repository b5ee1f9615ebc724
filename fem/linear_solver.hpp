// The one wrapper around the SuiteSparse direct solvers (through Eigen's support
// modules): CHOLMOD for symmetric positive definite systems (heat conduction,
// electrical conduction, elasticity without friction), UMFPACK and KLU for general
// unsymmetric ones (friction, monolithic coupling). The symbolic analysis is done
// once per sparsity pattern and reused by every numerical factorisation.
#pragma once

#include "fem/assembler.hpp"

#include <Eigen/Core>

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
  // Symbolic analysis (fill-reducing ordering); repeated automatically when the
  // pattern size changes.
  void analyze(const SparseMatrix& A);
  // Numerical factorisation; throws std::runtime_error if the matrix is singular or,
  // for CHOLMOD, not positive definite.
  void factorize(const SparseMatrix& A);
  // Solution of A x = b with the last factorisation.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  // analyze (if needed) + factorize + solve.
  Eigen::VectorXd solve(const SparseMatrix& A, const Eigen::VectorXd& b);

 private:
  struct Impl;
  SolverKind kind_;
  std::unique_ptr<Impl> impl_;
  Eigen::Index analyzed_rows_ = -1, analyzed_nnz_ = -1;
};

}  // namespace rsw::fem
