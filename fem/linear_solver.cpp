// SuiteSparse solvers behind one interface; see linear_solver.hpp.
#include "fem/linear_solver.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/KLUSupport>
#include <Eigen/UmfPackSupport>

#include <stdexcept>

namespace rsw::fem {

SolverKind solver_kind_from_string(const std::string& name) {
  if (name == "cholmod") return SolverKind::cholmod;
  if (name == "umfpack") return SolverKind::umfpack;
  if (name == "klu") return SolverKind::klu;
  throw std::invalid_argument("unknown linear solver '" + name + "'; allowed: cholmod, umfpack, klu");
}

std::string to_string(SolverKind kind) {
  switch (kind) {
    case SolverKind::cholmod: return "cholmod";
    case SolverKind::umfpack: return "umfpack";
    case SolverKind::klu: return "klu";
  }
  return "?";
}

struct LinearSolver::Impl {
  Eigen::CholmodDecomposition<SparseMatrix, Eigen::Lower> cholmod;
  Eigen::UmfPackLU<SparseMatrix> umfpack;
  Eigen::KLU<SparseMatrix> klu;
};

LinearSolver::LinearSolver(SolverKind kind) : kind_(kind), impl_(std::make_unique<Impl>()) {}
LinearSolver::~LinearSolver() = default;
LinearSolver::LinearSolver(LinearSolver&&) noexcept = default;
LinearSolver& LinearSolver::operator=(LinearSolver&&) noexcept = default;

void LinearSolver::analyze(const SparseMatrix& A) {
  switch (kind_) {
    case SolverKind::cholmod: impl_->cholmod.analyzePattern(A); break;
    case SolverKind::umfpack: impl_->umfpack.analyzePattern(A); break;
    case SolverKind::klu: impl_->klu.analyzePattern(A); break;
  }
  analyzed_rows_ = A.rows();
  analyzed_nnz_ = A.nonZeros();
}

void LinearSolver::factorize(const SparseMatrix& A) {
  if (A.rows() != analyzed_rows_ || A.nonZeros() != analyzed_nnz_) analyze(A);
  Eigen::ComputationInfo info = Eigen::Success;
  switch (kind_) {
    case SolverKind::cholmod:
      impl_->cholmod.factorize(A);
      info = impl_->cholmod.info();
      break;
    case SolverKind::umfpack:
      impl_->umfpack.factorize(A);
      info = impl_->umfpack.info();
      break;
    case SolverKind::klu:
      impl_->klu.factorize(A);
      info = impl_->klu.info();
      break;
  }
  if (info != Eigen::Success)
    throw std::runtime_error(to_string(kind_) + ": factorisation of a " + std::to_string(A.rows()) +
                             "x" + std::to_string(A.cols()) + " system failed" +
                             (kind_ == SolverKind::cholmod ? " (matrix not positive definite?)" : " (singular matrix?)"));
}

Eigen::VectorXd LinearSolver::solve(const Eigen::VectorXd& b) const {
  switch (kind_) {
    case SolverKind::cholmod: return impl_->cholmod.solve(b);
    case SolverKind::umfpack: return impl_->umfpack.solve(b);
    case SolverKind::klu: return impl_->klu.solve(b);
  }
  return {};
}

Eigen::VectorXd LinearSolver::solve(const SparseMatrix& A, const Eigen::VectorXd& b) {
  factorize(A);
  return solve(b);
}

}  // namespace rsw::fem
