// SuiteSparse solvers behind one interface; see linear_solver.hpp.
#include "fem/linear_solver.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/KLUSupport>
#include <Eigen/UmfPackSupport>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

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
  // Eigen's UMFPACK and KLU wrappers keep a reference to the factorised matrix
  // (UMFPACK's iterative refinement reads it in every solve): the solver owns a copy,
  // so the caller may change or drop its matrix after factorize().
  SparseMatrix factorized;
};

LinearSolver::LinearSolver(SolverKind kind) : kind_(kind), impl_(std::make_unique<Impl>()) {
  // A matrix that is not positive definite is reported by the exception of factorize();
  // CHOLMOD's own message on stderr would only repeat it.
  impl_->cholmod.cholmod().print = 0;
}
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
      impl_->factorized = A;
      impl_->umfpack.factorize(impl_->factorized);
      info = impl_->umfpack.info();
      break;
    case SolverKind::klu:
      impl_->factorized = A;
      impl_->klu.factorize(impl_->factorized);
      info = impl_->klu.info();
      break;
  }
  if (info != Eigen::Success)
    throw std::runtime_error(to_string(kind_) + ": factorisation of a " + std::to_string(A.rows()) +
                             "x" + std::to_string(A.cols()) + " system failed" +
                             (kind_ == SolverKind::cholmod ? " (matrix not positive definite?)" : " (singular matrix?)"));
}

void LinearSolver::set_refinement_steps(int steps) {
  impl_->umfpack.umfpackControl()(UMFPACK_IRSTEP) = steps;
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

double componentwise_backward_error(const SparseMatrix& A, const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  if (A.rows() != b.size() || A.cols() != x.size())
    throw std::invalid_argument("componentwise_backward_error: sizes of A, x and b do not match");
  Eigen::VectorXd residual = b, scale = b.cwiseAbs();
  for (Eigen::Index j = 0; j < A.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(A, j); it; ++it) {
      residual[it.row()] -= it.value() * x[j];
      scale[it.row()] += std::abs(it.value() * x[j]);
    }
  double omega = 0;  // |r_i| <= scale_i, so a row with scale_i = 0 has r_i = 0
  for (Eigen::Index i = 0; i < b.size(); ++i)
    if (residual[i] != 0) omega = std::max(omega, std::abs(residual[i]) / scale[i]);
  return omega;
}

struct PreconditionedGmres::Impl {
  LinearSolver cholmod{SolverKind::cholmod};
  LinearSolver umfpack{SolverKind::umfpack};
};

PreconditionedGmres::PreconditionedGmres() : impl_(std::make_unique<Impl>()) {
  impl_->umfpack.set_refinement_steps(0);  // GMRES corrects the preconditioner's error anyway
}
PreconditionedGmres::~PreconditionedGmres() = default;
PreconditionedGmres::PreconditionedGmres(PreconditionedGmres&&) noexcept = default;
PreconditionedGmres& PreconditionedGmres::operator=(PreconditionedGmres&&) noexcept = default;

void PreconditionedGmres::set_preconditioner(const SparseMatrix& M) {
  kind_ = Kind::none;
  ++n_factorizations_;
  const SparseMatrix S = 0.5 * (M + SparseMatrix(M.transpose()));
  try {
    impl_->cholmod.factorize(S);
    kind_ = Kind::symmetric_part;
    return;
  } catch (const std::runtime_error&) {
    // Not positive definite: the full matrix by LU (GMRES then converges at once).
  }
  impl_->umfpack.factorize(M);
  kind_ = Kind::full;
}

PreconditionedGmres::Report PreconditionedGmres::solve(const SparseMatrix& A, const Eigen::VectorXd& b,
                                                       Eigen::VectorXd& x, double tolerance,
                                                       int max_iterations) const {
  if (kind_ == Kind::none) throw std::logic_error("PreconditionedGmres: no preconditioner");
  const LinearSolver& M = kind_ == Kind::symmetric_part ? impl_->cholmod : impl_->umfpack;
  Report report;
  const Eigen::Index n = b.size();
  x = Eigen::VectorXd::Zero(n);
  const double beta = b.norm();
  if (beta == 0) {
    report.converged = true;
    return report;
  }
  // Arnoldi on A M⁻¹ with modified Gram-Schmidt; Givens rotations keep the small
  // least-squares problem triangular, so the residual norm is known every iteration.
  const int m = std::max(1, max_iterations);
  std::vector<Eigen::VectorXd> V, Z;  // Krylov basis and its preconditioned images
  V.reserve(m + 1);
  Z.reserve(m);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m + 1, m);
  Eigen::VectorXd cs = Eigen::VectorXd::Zero(m), sn = Eigen::VectorXd::Zero(m), g = Eigen::VectorXd::Zero(m + 1);
  g[0] = beta;
  V.push_back(b / beta);
  int k = 0;
  double residual = beta;
  while (k < m) {
    Z.push_back(M.solve(V[k]));
    Eigen::VectorXd w = A * Z[k];
    for (int i = 0; i <= k; ++i) {
      H(i, k) = w.dot(V[i]);
      w -= H(i, k) * V[i];
    }
    H(k + 1, k) = w.norm();
    for (int i = 0; i < k; ++i) {  // earlier rotations on the new column
      const double t = cs[i] * H(i, k) + sn[i] * H(i + 1, k);
      H(i + 1, k) = -sn[i] * H(i, k) + cs[i] * H(i + 1, k);
      H(i, k) = t;
    }
    const double r = std::hypot(H(k, k), H(k + 1, k));
    cs[k] = r > 0 ? H(k, k) / r : 1.0;
    sn[k] = r > 0 ? H(k + 1, k) / r : 0.0;
    const double h_next = H(k + 1, k);
    H(k, k) = r;
    H(k + 1, k) = 0;
    g[k + 1] = -sn[k] * g[k];
    g[k] *= cs[k];
    residual = std::abs(g[k + 1]);
    ++k;
    if (residual <= 0.5 * tolerance * beta || h_next <= 1e-300) break;
    V.push_back(w / h_next);
  }
  const Eigen::VectorXd y = H.topLeftCorner(k, k).triangularView<Eigen::Upper>().solve(g.head(k));
  for (int i = 0; i < k; ++i) x += y[i] * Z[i];
  report.iterations = k;
  report.relative_residual = (b - A * x).norm() / beta;
  report.converged = report.relative_residual <= tolerance;
  return report;
}

PreconditionedGmres::Report PreconditionedGmres::solve_refreshing(const SparseMatrix& A, const Eigen::VectorXd& b,
                                                                  Eigen::VectorXd& x, double tolerance,
                                                                  int refresh_after, int max_iterations) {
  if (!has_preconditioner() || last_iterations_ > refresh_after) set_preconditioner(A);
  Report report = solve(A, b, x, tolerance, max_iterations);
  n_iterations_ += report.iterations;
  if (!report.converged) {
    set_preconditioner(A);
    report = solve(A, b, x, tolerance, max_iterations);
    n_iterations_ += report.iterations;
    if (!report.converged)
      throw std::runtime_error("GMRES with a fresh preconditioner did not converge (relative residual " +
                               std::to_string(report.relative_residual) + ")");
  }
  last_iterations_ = report.iterations;
  return report;
}

}  // namespace rsw::fem
