// SuiteSparse direct solvers (CHOLMOD, UMFPACK, KLU) and SUNDIALS' flexible GMRES
// (SUNLinSol_SPFGMR) behind one interface; see linear_solver.hpp.
#include "fem/linear_solver.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/UmfPackSupport>
#include <klu.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_spfgmr.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <exception>
#include <functional>
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

// A copy of a compressed matrix's sparsity pattern, to recognise the pattern of a
// later matrix (what a kept analysis, pivot order or entry map belongs to).
struct PatternCopy {
  std::vector<int> outer, inner;
  bool matches(const SparseMatrix& A) const {
    return static_cast<Eigen::Index>(outer.size()) == A.cols() + 1 &&
           static_cast<Eigen::Index>(inner.size()) == A.nonZeros() &&
           std::equal(outer.begin(), outer.end(), A.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), A.innerIndexPtr());
  }
  void assign(const SparseMatrix& A) {
    outer.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.cols() + 1);
    inner.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  }
};

// KLU through its C interface (Eigen's wrapper always factorises afresh): a matrix of
// the pattern of the last factorisation is refactorised with that factorisation's
// pivot sequence (klu_refactor, no pivot search: 6.4 against 13.4 ms on the
// default weld's 8166-unknown thermal tangent with its whole contact pattern; 2.7–3.6
// ms on the entries ever nonzero, docs/PERFORMANCE.md). The old pivots
// can be poor for the new values; the refactorisation is kept only while the
// reciprocal pivot ratio min|u_ii|/max|u_ii| (klu_rcond) stays above 10⁻³ of that of
// the last pivoted factorisation, else the matrix is factorised afresh.
struct KluFactor {
  klu_common common;
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  PatternCopy pattern;             // of the analysis
  double pivoted_rcond = 0;        // klu_rcond of the last factorisation with pivoting
  bool refactorized = false;       // the last factorize() kept the pivot sequence
  KluFactor() { klu_defaults(&common); }
  ~KluFactor() { clear(); }
  KluFactor(const KluFactor&) = delete;
  KluFactor& operator=(const KluFactor&) = delete;
  void clear() {
    if (numeric) klu_free_numeric(&numeric, &common);
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
  void analyze(const SparseMatrix& A) {
    clear();
    pattern.assign(A);
    symbolic = klu_analyze(static_cast<int>(A.rows()), pattern.outer.data(), pattern.inner.data(), &common);
    if (!symbolic) throw std::runtime_error("klu: symbolic analysis failed (status " + std::to_string(common.status) + ")");
  }
  // False if the matrix is singular.
  bool factorize(const SparseMatrix& A) {
    if (!symbolic || !pattern.matches(A)) analyze(A);
    const double* values = A.valuePtr();
    if (numeric) {
      refactorized = klu_refactor(pattern.outer.data(), pattern.inner.data(), const_cast<double*>(values), symbolic, numeric, &common) &&
                     klu_rcond(symbolic, numeric, &common) && common.rcond >= 1e-3 * pivoted_rcond;
      if (refactorized) return true;
      klu_free_numeric(&numeric, &common);
    }
    refactorized = false;
    numeric = klu_factor(pattern.outer.data(), pattern.inner.data(), const_cast<double*>(values), symbolic, &common);
    if (!numeric || !klu_rcond(symbolic, numeric, &common) || !(common.rcond > 0)) {
      if (numeric) klu_free_numeric(&numeric, &common);
      return false;
    }
    pivoted_rcond = common.rcond;
    return true;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) {
    Eigen::VectorXd x = b;
    klu_solve(symbolic, numeric, static_cast<int>(x.size()), 1, x.data(), &common);
    return x;
  }
};

// Eigen's CHOLMOD wrapper with read access to the factor (PreconditionedGmres copies
// a supernodal one in single precision). UpLo: the triangle handed to CHOLMOD.
template <int UpLo>
struct CholmodCholesky : Eigen::CholmodDecomposition<SparseMatrix, UpLo> {
  const cholmod_factor* factor() const { return this->m_cholmodFactor; }  // null before the first factorisation
};

// The entries of a caller's matrix that have been nonzero in some matrix of its
// pattern so far (see linear_solver.hpp), as a matrix of their own: `used` marks
// them in the caller's pattern, `kept` lists their positions column by column (the
// diagonal always), and `matrix` holds them, refreshed by take().
struct UsedPattern {
  PatternCopy caller;
  std::vector<char> used;
  std::vector<int> kept;
  SparseMatrix matrix;
  // Copies A's values into `matrix`; true if its pattern changed (a new analysis).
  bool take(const SparseMatrix& A) {
    const double* v = A.valuePtr();
    const int n_entries = static_cast<int>(A.nonZeros());
    bool grew = false;
    if (!caller.matches(A)) {
      caller.assign(A);
      used.assign(n_entries, 0);
      for (Eigen::Index j = 0; j < A.outerSize(); ++j)
        for (int k = caller.outer[j]; k < caller.outer[j + 1]; ++k)
          if (caller.inner[k] == j) used[k] = 1;
      grew = true;
    }
    for (int k = 0; k < n_entries; ++k)
      if (v[k] != 0.0 && !used[k]) {
        used[k] = 1;
        grew = true;
      }
    if (grew) {
      kept.clear();
      std::vector<int> outer(A.outerSize() + 1, 0);
      for (Eigen::Index j = 0; j < A.outerSize(); ++j) {
        for (int k = caller.outer[j]; k < caller.outer[j + 1]; ++k)
          if (used[k]) kept.push_back(k);
        outer[j + 1] = static_cast<int>(kept.size());
      }
      matrix.resize(A.rows(), A.cols());
      matrix.resizeNonZeros(static_cast<Eigen::Index>(kept.size()));
      std::copy(outer.begin(), outer.end(), matrix.outerIndexPtr());
      for (std::size_t i = 0; i < kept.size(); ++i) matrix.innerIndexPtr()[i] = caller.inner[kept[i]];
    }
    double* m = matrix.valuePtr();
    for (std::size_t i = 0; i < kept.size(); ++i) m[i] = v[kept[i]];
    return grew;
  }
};

struct LinearSolver::Impl {
  UsedPattern used;
  // CHOLMOD factorises P A Pᵀ: the supernodal code from its lower triangle, the
  // simplicial one from its upper triangle, and each permuted transpose of the input
  // costs a pass over it (cholmod_factorize.c). From the lower triangle of A that is
  // one transpose for the simplicial and two for the supernodal factorisation; from the
  // upper triangle, one for the supernodal. So the factor that is forced supernodal
  // (set_supernodal) is handed the upper triangle, every other the lower. The values
  // factorised are the same: A is symmetric.
  CholmodCholesky<Eigen::Lower> cholmod;
  CholmodCholesky<Eigen::Upper> cholmod_upper;
  bool upper = false;
  const cholmod_factor* factor() const { return upper ? cholmod_upper.factor() : cholmod.factor(); }
  Eigen::UmfPackLU<SparseMatrix> umfpack;
  // Mutable: klu_solve takes its workspace from the (non-const) common object.
  mutable KluFactor klu;
  // Eigen's UMFPACK wrapper keeps a reference to the factorised matrix (its iterative
  // refinement reads it in every solve): the solver owns a copy, so the caller may
  // change or drop its matrix after factorize().
  SparseMatrix factorized;
};

LinearSolver::LinearSolver(SolverKind kind) : kind_(kind), impl_(std::make_unique<Impl>()) {
  // A matrix that is not positive definite is reported by the exception of factorize();
  // CHOLMOD's own message on stderr would only repeat it.
  impl_->cholmod.cholmod().print = 0;
  impl_->cholmod_upper.cholmod().print = 0;
  // CHOLMOD factorises supernodally (dense BLAS blocks) when the factorisation's flops
  // per nonzero of L reach supernodal_switch, else column by column. Measured on the
  // default weld's matrices (docs/PERFORMANCE.md): the 8166-unknown scalar conduction
  // matrices (43 flops per nonzero) factorise in 4.9 ms and solve in 0.21 ms
  // column by column against 6.0 and 0.35 ms supernodally; the 16 155-unknown
  // mechanics tangent (87) takes 15 ms and 0.82 ms supernodally against 31 and 0.68
  // ms. CHOLMOD's default switch, 40, would send both the supernodal way. (Figures of
  // the whole contact patterns; on the entries ever nonzero the mechanics tangent has
  // 56 flops per nonzero, and its preconditioner asks for a supernodal factor:
  // PreconditionedGmres::set_supernodal.)
  impl_->cholmod.cholmod().supernodal_switch = 80;
  impl_->cholmod_upper.cholmod().supernodal = CHOLMOD_SUPERNODAL;
}
LinearSolver::~LinearSolver() = default;
LinearSolver::LinearSolver(LinearSolver&&) noexcept = default;
LinearSolver& LinearSolver::operator=(LinearSolver&&) noexcept = default;

void LinearSolver::analyze(const SparseMatrix& A) {
  switch (kind_) {
    case SolverKind::cholmod:
      if (impl_->upper)
        impl_->cholmod_upper.analyzePattern(A);
      else
        impl_->cholmod.analyzePattern(A);
      break;
    case SolverKind::umfpack: impl_->umfpack.analyzePattern(A); break;
    case SolverKind::klu: impl_->klu.analyze(A); break;
  }
  ++n_analyses_;
}

void LinearSolver::factorize(const SparseMatrix& caller_matrix) {
  SparseMatrix compressed;
  if (!caller_matrix.isCompressed()) {
    compressed = caller_matrix;
    compressed.makeCompressed();
  }
  if (impl_->used.take(caller_matrix.isCompressed() ? caller_matrix : compressed)) analyze(impl_->used.matrix);
  const SparseMatrix& A = impl_->used.matrix;
  Eigen::ComputationInfo info = Eigen::Success;
  switch (kind_) {
    case SolverKind::cholmod:
      if (impl_->upper) {
        impl_->cholmod_upper.factorize(A);
        info = impl_->cholmod_upper.info();
      } else {
        impl_->cholmod.factorize(A);
        info = impl_->cholmod.info();
      }
      break;
    case SolverKind::umfpack:
      impl_->factorized = A;
      impl_->umfpack.factorize(impl_->factorized);
      info = impl_->umfpack.info();
      break;
    case SolverKind::klu:
      if (!impl_->klu.factorize(A)) info = Eigen::NumericalIssue;
      break;
  }
  if (info != Eigen::Success)
    throw std::runtime_error(to_string(kind_) + ": factorisation of a " + std::to_string(A.rows()) +
                             "x" + std::to_string(A.cols()) + " system failed" +
                             (kind_ == SolverKind::cholmod ? " (matrix not positive definite?)" : " (singular matrix?)"));
}

bool LinearSolver::kept_pivots() const { return kind_ == SolverKind::klu && impl_->klu.refactorized; }

void LinearSolver::set_refinement_steps(int steps) {
  impl_->umfpack.umfpackControl()(UMFPACK_IRSTEP) = steps;
}

Eigen::VectorXd LinearSolver::solve(const Eigen::VectorXd& b) const {
  switch (kind_) {
    case SolverKind::cholmod:
      if (impl_->upper) return impl_->cholmod_upper.solve(b);
      return impl_->cholmod.solve(b);
    case SolverKind::umfpack: return impl_->umfpack.solve(b);
    case SolverKind::klu: return impl_->klu.solve(b);
  }
  return {};
}

Eigen::VectorXd LinearSolver::solve(const SparseMatrix& A, const Eigen::VectorXd& b) {
  factorize(A);
  return solve(b);
}

// The two sweeps of a supernodal triangular solve with L (CHOLMOD's layout: supernode s
// holds columns super[s]..super[s+1]−1 and the rows rows[pi[s]..pi[s+1]−1], the first
// of them the columns themselves, as a dense column-major block at values + px[s]),
// on the first n_solved columns only, in place on z; w is a work vector as long as the
// tallest supernode. Each supernode is one sweep over its block, column by column:
// forward, the column's unknown and then an axpy down the rest of the column (into the
// block's own unknowns and the work vector for the rows below, scattered afterwards);
// backward, the column's dot product with the known values of the rows below the
// block's triangle (gathered once per supernode, `dot`), then the triangle's own terms.
// The same flops as a dense triangular solve plus a matrix-vector product per
// supernode, without their per-call set-up, which dominated on supernodes of ~12
// columns (docs/PERFORMANCE.md). Where n_solved ends inside a supernode, the forward
// sweep leaves what the solved columns add to the later rows in z, and the backward
// sweep reads the later rows of z as they are.
template <typename T>
void supernodal_forward(const int* super, const int* pi, const int* px, const int* rows, const T* values, int n_super,
                        int n_solved, T* z, T* w) {
  using Vector = Eigen::Map<Eigen::Matrix<T, Eigen::Dynamic, 1>>;
  using ConstVector = Eigen::Map<const Eigen::Matrix<T, Eigen::Dynamic, 1>>;
  for (int s = 0; s < n_super && super[s] < n_solved; ++s) {
    const int k1 = super[s], n_own = super[s + 1] - k1, n_col = std::min(super[s + 1], n_solved) - k1;
    const int n_row = pi[s + 1] - pi[s];
    const T* L = values + px[s];
    std::copy(z + k1, z + k1 + n_own, w);
    std::fill(w + n_own, w + n_row, T(0));
    for (int j = 0; j < n_col; ++j) {
      const T* column = L + static_cast<std::ptrdiff_t>(j) * n_row;
      const T x = w[j] / column[j];
      w[j] = x;
      const int rest = n_row - j - 1;
      if (rest > 0) Vector(w + j + 1, rest).noalias() -= x * ConstVector(column + j + 1, rest);
    }
    std::copy(w, w + n_own, z + k1);
    const int* r = rows + pi[s];
    for (int i = n_own; i < n_row; ++i) z[r[i]] += w[i];
  }
}
template <typename T, typename Dot>
void supernodal_backward(const int* super, const int* pi, const int* px, const int* rows, const T* values,
                         int n_super, int n_solved, T* z, T* w, Dot dot) {
  for (int s = n_super - 1; s >= 0; --s) {
    const int k1 = super[s];
    if (k1 >= n_solved) continue;
    const int n_own = super[s + 1] - k1, n_col = std::min(super[s + 1], n_solved) - k1, n_row = pi[s + 1] - pi[s];
    const T* L = values + px[s];
    const int* r = rows + pi[s];
    const int below = n_row - n_own;
    for (int i = 0; i < below; ++i) w[i] = z[r[n_own + i]];
    T* own = z + k1;  // the supernode's own unknowns
    for (int j = n_col - 1; j >= 0; --j) {
      const T* column = L + static_cast<std::ptrdiff_t>(j) * n_row;
      T known = dot(column + n_own, w, below);
      for (int k = n_own - 1; k > j; --k) known += column[k] * own[k];
      own[j] = (own[j] - known) / column[j];
    }
  }
}

// A CHOLMOD view of a compressed matrix's lower triangle (no copy).
static cholmod_sparse lower_triangle_view(const SparseMatrix& A) {
  cholmod_sparse view{};
  view.nrow = static_cast<size_t>(A.rows());
  view.ncol = static_cast<size_t>(A.cols());
  view.nzmax = static_cast<size_t>(A.nonZeros());
  view.p = const_cast<int*>(A.outerIndexPtr());
  view.i = const_cast<int*>(A.innerIndexPtr());
  view.x = const_cast<double*>(A.valuePtr());
  view.stype = -1;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;
  view.packed = 1;
  return view;
}

// The arrays of a supernodal CHOLMOD factor (int indices, real values).
struct SupernodalArrays {
  const int *super, *pi, *px, *rows, *perm;
  const double* x;
  int n_super;
  explicit SupernodalArrays(const cholmod_factor* L)
      : super(static_cast<const int*>(L->super)), pi(static_cast<const int*>(L->pi)),
        px(static_cast<const int*>(L->px)), rows(static_cast<const int*>(L->s)),
        perm(static_cast<const int*>(L->Perm)), x(static_cast<const double*>(L->x)),
        n_super(static_cast<int>(L->nsuper)) {}
};

struct BorderedCholesky::Impl {
  cholmod_common common;
  cholmod_factor* L = nullptr;
  PatternCopy pattern;  // of the analysis
  int n_border = -1;
  mutable std::vector<double> z, work;  // workspace of solve_leading()
  Impl() {
    cholmod_start(&common);
    common.print = 0;
    common.supernodal = CHOLMOD_SUPERNODAL;  // the trailing block is dense: one supernode
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_GIVEN;
    common.postorder = 0;  // a postordering could move leading columns behind the border
    // Fundamental supernodes only (no explicit zeros merged in): the solves, which
    // stream the factor twice per Newton iteration, outnumber the factorisations
    // (on the default weld 23 % less factor to stream).
    for (int k = 0; k < 3; ++k) {
      common.nrelax[k] = 0;
      common.zrelax[k] = 0;
    }
  }
  ~Impl() {
    if (L) cholmod_free_factor(&L, &common);
    cholmod_finish(&common);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
};

BorderedCholesky::BorderedCholesky() : impl_(std::make_unique<Impl>()) {}
BorderedCholesky::~BorderedCholesky() = default;
BorderedCholesky::BorderedCholesky(BorderedCholesky&&) noexcept = default;
BorderedCholesky& BorderedCholesky::operator=(BorderedCholesky&&) noexcept = default;

bool BorderedCholesky::factorize(const SparseMatrix& A, int n_border) {
  Impl& m = *impl_;
  const int n = static_cast<int>(A.rows());
  if (A.cols() != n || !A.isCompressed() || n_border < 0 || n_border > n)
    throw std::invalid_argument("BorderedCholesky: a square compressed matrix and 0 <= n_border <= n expected");
  cholmod_sparse view = lower_triangle_view(A);
  if (!m.L || n_border != m.n_border || !m.pattern.matches(A)) {
    if (m.L) cholmod_free_factor(&m.L, &m.common);
    m.pattern.assign(A);
    m.n_border = n_border;
    std::vector<int> constraint(n, 0), perm(n);
    std::fill(constraint.begin() + (n - n_border), constraint.end(), 1);  // CAMD orders set 1 after set 0
    if (!cholmod_camd(&view, nullptr, 0, constraint.data(), perm.data(), &m.common))
      throw std::runtime_error("BorderedCholesky: CAMD ordering failed (CHOLMOD status " +
                               std::to_string(m.common.status) + ")");
    m.L = cholmod_analyze_p(&view, perm.data(), nullptr, 0, &m.common);
    if (!m.L) throw std::runtime_error("BorderedCholesky: analysis failed");
    const int* P = static_cast<const int*>(m.L->Perm);
    for (int k = 0; k < n - n_border; ++k)
      if (P[k] >= n - n_border) throw std::logic_error("BorderedCholesky: the ordering put a border unknown first");
  }
  cholmod_factorize(&view, m.L, &m.common);
  if (m.common.status != CHOLMOD_OK || m.L->minor < m.L->n || !m.L->is_super) return false;
  // L_BB from the supernodes holding the last n_border columns, then L_BB L_BBᵀ.
  const int n_lead = n - n_border;
  const SupernodalArrays f(m.L);
  Eigen::MatrixXd L_BB = Eigen::MatrixXd::Zero(n_border, n_border);
  for (int s = 0; s < f.n_super; ++s) {
    const int k1 = f.super[s], k2 = f.super[s + 1], n_row = f.pi[s + 1] - f.pi[s];
    for (int j = std::max(k1, n_lead); j < k2; ++j)
      for (int t = j - k1; t < n_row; ++t)
        L_BB(f.rows[f.pi[s] + t] - n_lead, j - n_lead) = f.x[f.px[s] + static_cast<std::ptrdiff_t>(j - k1) * n_row + t];
  }
  const Eigen::MatrixXd T = L_BB.triangularView<Eigen::Lower>() * L_BB.transpose();
  schur_.resize(n_border, n_border);
  for (int b = 0; b < n_border; ++b)
    for (int a = 0; a < n_border; ++a) schur_(f.perm[n_lead + a] - n_lead, f.perm[n_lead + b] - n_lead) = T(a, b);
  return true;
}

void BorderedCholesky::solve_leading(const double* b, double* out) const {
  const Impl& m = *impl_;
  if (!m.L) throw std::logic_error("BorderedCholesky::solve_leading before factorize()");
  const int n = static_cast<int>(m.L->n), n_lead = n - m.n_border;
  const SupernodalArrays f(m.L);
  std::vector<double>& z = m.z;
  z.assign(n, 0.0);
  m.work.resize(n);
  double* w = m.work.data();
  for (int k = 0; k < n_lead; ++k) z[k] = b[f.perm[k]];
  // L_II y = P b on the leading columns (what they add to the border rows is
  // dropped), then L_IIᵀ v = y with the border rows zero (they add nothing).
  supernodal_forward(f.super, f.pi, f.px, f.rows, f.x, f.n_super, n_lead, z.data(), w);
  std::fill(z.begin() + n_lead, z.end(), 0.0);
  supernodal_backward(f.super, f.pi, f.px, f.rows, f.x, f.n_super, n_lead, z.data(), w,
                      [](const double* l, const double* v, int count) {
                        return Eigen::Map<const Eigen::VectorXd>(l, count).dot(Eigen::Map<const Eigen::VectorXd>(v, count));
                      });
  for (int k = 0; k < n_lead; ++k) out[f.perm[k]] = z[k];
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

// Single-precision copy of a supernodal CHOLMOD factor P A Pᵀ = L Lᵀ, and the two
// triangular solves with it: x = Pᵀ L⁻ᵀ L⁻¹ P b. CHOLMOD stores supernode s (columns
// k1..k2−1, sharing one row structure of n_row rows, the first k2−k1 of them the
// columns themselves) as a dense column-major n_row × (k2−k1) block; each solve
// treats the block's triangle and its remaining rows together (the supernodal solve of
// Davis, Direct Methods for Sparse Linear Systems, SIAM 2006, ch. 9). Arithmetic in
// float, like the stored factor.
class SinglePrecisionCholesky {
 public:
  // False (and nothing kept) unless L is a real supernodal LLᵀ factor.
  bool assign(const cholmod_factor* L) {
    if (!L || !L->is_super || !L->is_ll || L->xtype != CHOLMOD_REAL || L->itype != CHOLMOD_INT) return false;
    n_ = static_cast<int>(L->n);
    const int n_super = static_cast<int>(L->nsuper);
    const int* super = static_cast<const int*>(L->super);
    const int* pi = static_cast<const int*>(L->pi);
    const int* px = static_cast<const int*>(L->px);
    super_.assign(super, super + n_super + 1);
    pi_.assign(pi, pi + n_super + 1);
    px_.assign(px, px + n_super + 1);
    rows_.assign(static_cast<const int*>(L->s), static_cast<const int*>(L->s) + pi[n_super]);
    perm_.assign(static_cast<const int*>(L->Perm), static_cast<const int*>(L->Perm) + n_);
    const double* x = static_cast<const double*>(L->x);
    values_.assign(x, x + px[n_super]);  // double → float
    int widest = 0;  // rows of the tallest supernode: the work vector holds a whole column
    for (int k = 0; k < n_super; ++k) widest = std::max(widest, pi[k + 1] - pi[k]);
    z_.resize(n_);
    work_.resize(widest);
    return true;
  }

  // The two sweeps are supernodal_forward and supernodal_backward, the backward's dot
  // products below the supernodes' triangles by dot_below:
  // Σ_i l_i w_i over n terms as `lanes` partial sums (term i into sum i mod lanes),
  // added up in order: a fixed order that the compiler vectorises on any x86-64.
  static constexpr int lanes = 8;
  static float dot_below(const float* l, const float* w, int n) {
    float sum[lanes] = {};
    int i = 0;
    for (; i + lanes <= n; i += lanes)
      for (int b = 0; b < lanes; ++b) sum[b] += l[i + b] * w[i + b];
    for (int b = 0; i + b < n; ++b) sum[b] += l[i + b] * w[i + b];
    float total = 0.0f;
    for (int b = 0; b < lanes; ++b) total += sum[b];
    return total;
  }

  // x = Pᵀ L⁻ᵀ L⁻¹ P b; x and b may be the same vector.
  void solve(const double* b, double* x) const {
    for (int k = 0; k < n_; ++k) z_[k] = static_cast<float>(b[perm_[k]]);
    const int n_super = static_cast<int>(super_.size()) - 1;
    supernodal_forward(super_.data(), pi_.data(), px_.data(), rows_.data(), values_.data(), n_super, n_, z_.data(),
                       work_.data());
    supernodal_backward(super_.data(), pi_.data(), px_.data(), rows_.data(), values_.data(), n_super, n_, z_.data(),
                        work_.data(), dot_below);
    for (int k = 0; k < n_; ++k) x[perm_[k]] = z_[k];
  }

 private:
  int n_ = 0;
  std::vector<int> super_, pi_, px_, rows_, perm_;
  std::vector<float> values_;
  mutable std::vector<float> z_, work_;  // workspace of solve()
};

// SUNDIALS' flexible GMRES (SUNLinSol_SPFGMR, Saad, SIAM J. Sci. Comput. 14 (1993)
// 461–469) on A x = b from x = 0: right-preconditioned, modified Gram-Schmidt, no
// restart, at most maxl iterations, stopped where its estimate of |b − A x|₂ (the
// Givens rotations' product times |b|; no scaling vectors) is at most delta. The
// Krylov vectors are SUNDIALS serial N_Vectors with Eigen's dot product, scaling and
// linear sum (see dot below); x and b are wrapped, not copied. One solver is kept
// for the next solve of the same size and maxl; it holds 2 maxl + 4 vectors from the
// start (11 MB for the default weld's mechanics, maxl 40). Exceptions of the product
// or the preconditioner are carried past SUNDIALS' C code and rethrown.
class FlexibleGmres {
 public:
  using Preconditioner = std::function<void(const double* r, double* z)>;  // z = M⁻¹ r, n values each
  FlexibleGmres() = default;
  FlexibleGmres(const FlexibleGmres&) = delete;
  FlexibleGmres& operator=(const FlexibleGmres&) = delete;
  ~FlexibleGmres() { release(); }

  // Iterations done; x (sized as b) is the last iterate, or zero where SUNDIALS
  // reports no reduction of the residual (or a failed QR factorisation).
  int solve(const SparseMatrix& A, const Preconditioner& precondition, const Eigen::VectorXd& b,
            Eigen::VectorXd& x, double delta, int maxl) {
    const auto n = static_cast<sunindextype>(b.size());
    if (!solver_ || n != n_ || maxl != maxl_) create(n, maxl);
    call_ = Call{&A, &precondition, nullptr};
    x = Eigen::VectorXd::Zero(b.size());
    N_VSetArrayPointer_Serial(x.data(), x_);
    N_VSetArrayPointer_Serial(const_cast<double*>(b.data()), b_);  // read only
    SUNLinSolSetZeroGuess(solver_, SUNTRUE);  // skips the product A x₀; reset by every solve
    const int flag = SUNLinSolSolve(solver_, nullptr, x_, b_, delta);
    const int iterations = SUNLinSolNumIters(solver_);
    const std::exception_ptr error = call_.error;
    call_ = Call{};
    if (error) std::rethrow_exception(error);
    if (flag != SUNLS_SUCCESS && flag != SUNLS_RES_REDUCED) x.setZero();  // SUNDIALS left x alone
    return iterations;
  }

 private:
  struct Call {
    const SparseMatrix* A = nullptr;
    const Preconditioner* precondition = nullptr;
    std::exception_ptr error;
  };
  static Eigen::Map<Eigen::VectorXd> view(N_Vector v) {
    return {N_VGetArrayPointer_Serial(v), static_cast<Eigen::Index>(N_VGetLength_Serial(v))};
  }
  // The serial N_Vector's own kernels, as Debian builds them, are plain scalar loops:
  // the dot product, one chain of dependent additions, alone took 10 % of a coarse
  // run's time. Eigen's vectorised ones replace them in the operations table (the
  // N_Vector interface's customisation point), which the solver's clones copy.
  static double dot(N_Vector x, N_Vector y) { return view(x).dot(view(y)); }
  static void linear_sum(double a, N_Vector x, double b, N_Vector y, N_Vector z) {
    view(z) = a * view(x) + b * view(y);  // coefficientwise: z may be x or y
  }
  static void scale(double c, N_Vector x, N_Vector z) { view(z) = c * view(x); }
  static int product(void* data, N_Vector v, N_Vector z) {  // z = A v
    auto& call = *static_cast<Call*>(data);
    view(z).noalias() = *call.A * view(v);
    return 0;
  }
  static int preconditioner(void* data, N_Vector r, N_Vector z, double /*tolerance*/, int /*side*/) {
    auto& call = *static_cast<Call*>(data);
    try {
      (*call.precondition)(N_VGetArrayPointer_Serial(r), N_VGetArrayPointer_Serial(z));
      return 0;
    } catch (...) {
      call.error = std::current_exception();
      return -1;  // unrecoverable: SUNDIALS returns at once
    }
  }
  void create(sunindextype n, int maxl) {
    release();
    if (SUNContext_Create(nullptr, &context_) != 0) throw std::runtime_error("SUNDIALS: no context");
    x_ = N_VNewEmpty_Serial(n, context_);
    b_ = N_VNewEmpty_Serial(n, context_);
    if (!x_ || !b_) {
      release();
      throw std::runtime_error("SUNDIALS: no vectors");
    }
    for (N_Vector v : {x_, b_}) {
      v->ops->nvdotprod = dot;
      v->ops->nvlinearsum = linear_sum;
      v->ops->nvscale = scale;
    }
    solver_ = SUNLinSol_SPFGMR(x_, SUN_PREC_RIGHT, maxl, context_);  // clones x_
    if (!solver_) {
      release();
      throw std::runtime_error("SUNDIALS: SPFGMR could not be created");
    }
    SUNLinSol_SPFGMRSetGSType(solver_, SUN_MODIFIED_GS);
    SUNLinSol_SPFGMRSetMaxRestarts(solver_, 0);
    SUNLinSolSetATimes(solver_, &call_, product);
    SUNLinSolSetPreconditioner(solver_, &call_, nullptr, preconditioner);
    if (SUNLinSolInitialize(solver_) != SUNLS_SUCCESS) {
      release();
      throw std::runtime_error("SUNDIALS: SPFGMR could not be initialised");
    }
    n_ = n;
    maxl_ = maxl;
  }
  void release() {
    if (solver_) SUNLinSolFree(solver_);
    if (x_) N_VDestroy(x_);
    if (b_) N_VDestroy(b_);
    if (context_) SUNContext_Free(&context_);
    solver_ = nullptr;
    x_ = b_ = nullptr;
    context_ = nullptr;
    n_ = -1;
    maxl_ = -1;
  }
  SUNContext context_ = nullptr;
  N_Vector x_ = nullptr, b_ = nullptr;  // wrap the caller's x and b
  SUNLinearSolver solver_ = nullptr;
  sunindextype n_ = -1;
  int maxl_ = -1;
  Call call_;
};

struct PreconditionedGmres::Impl {
  LinearSolver cholmod{SolverKind::cholmod};
  SinglePrecisionCholesky single;
  FlexibleGmres gmres;  // SUNDIALS' SPFGMR, kept between solves
  bool single_active = false;  // the symmetric-part factor is applied through `single`
  LinearSolver umfpack{SolverKind::umfpack};
  // The symmetric part (M + Mᵀ)/2 of a structurally symmetric M (every assembled FE
  // matrix), in the one triangle that the Cholesky factorisation reads (the upper one
  // for a supernodal factor, else the lower: LinearSolver): its values are
  // 0.5 (m_k + m_transpose[k]) over the positions k of M in that triangle (`source`),
  // with transpose[k] the position of the mirrored entry, found once per pattern (0.2
  // against 2.8 ms for Eigen's transpose and sum on the 16 155-unknown mechanics
  // tangent). Half of M's entries, so half the copying here and in the factorisation's
  // own copy of the entries it uses. Empty transpose: the pattern is not symmetric.
  PatternCopy pattern;
  bool pattern_upper = false;
  std::vector<int> transpose, source;
  SparseMatrix symmetric;
  const SparseMatrix& symmetric_part(const SparseMatrix& M, bool upper) {
    if (!pattern.matches(M) || upper != pattern_upper) {
      pattern.assign(M);
      pattern_upper = upper;
      const std::vector<int>& outer = pattern.outer;
      const std::vector<int>& inner = pattern.inner;
      transpose.assign(inner.size(), 0);
      bool symmetric_pattern = M.rows() == M.cols() && M.isCompressed();
      for (Eigen::Index j = 0; symmetric_pattern && j < M.cols(); ++j)
        for (int k = outer[j]; k < outer[j + 1]; ++k) {
          const int i = inner[k];
          const auto first = inner.begin() + outer[i], last = inner.begin() + outer[i + 1];
          const auto hit = std::lower_bound(first, last, static_cast<int>(j));
          if (hit == last || *hit != j) {
            symmetric_pattern = false;
            break;
          }
          transpose[k] = static_cast<int>(hit - inner.begin());
        }
      source.clear();
      if (!symmetric_pattern) {
        transpose.clear();
      } else {
        std::vector<int> triangle_outer(M.cols() + 1, 0);
        for (Eigen::Index j = 0; j < M.cols(); ++j) {
          for (int k = outer[j]; k < outer[j + 1]; ++k)
            if (upper ? inner[k] <= j : inner[k] >= j) source.push_back(k);
          triangle_outer[j + 1] = static_cast<int>(source.size());
        }
        symmetric.resize(M.rows(), M.cols());
        symmetric.resizeNonZeros(static_cast<Eigen::Index>(source.size()));
        std::copy(triangle_outer.begin(), triangle_outer.end(), symmetric.outerIndexPtr());
        for (std::size_t u = 0; u < source.size(); ++u) symmetric.innerIndexPtr()[u] = inner[source[u]];
      }
    }
    if (transpose.empty()) {
      const SparseMatrix whole = 0.5 * (M + SparseMatrix(M.transpose()));
      if (upper)
        symmetric = whole.triangularView<Eigen::Upper>();
      else
        symmetric = whole.triangularView<Eigen::Lower>();
    } else {
      const double* m = M.valuePtr();
      double* v = symmetric.valuePtr();
      for (std::size_t u = 0; u < source.size(); ++u) v[u] = 0.5 * (m[source[u]] + m[transpose[source[u]]]);
    }
    return symmetric;
  }
};

PreconditionedGmres::PreconditionedGmres() : impl_(std::make_unique<Impl>()) {
  impl_->umfpack.set_refinement_steps(0);  // GMRES corrects the preconditioner's error anyway
}

void PreconditionedGmres::set_supernodal(bool on) {
  impl_->cholmod.impl_->upper = on;  // the upper-triangle factor is always supernodal
  impl_->cholmod.impl_->used = UsedPattern{};  // the next factorisation analyses afresh
}
PreconditionedGmres::~PreconditionedGmres() = default;
PreconditionedGmres::PreconditionedGmres(PreconditionedGmres&&) noexcept = default;
PreconditionedGmres& PreconditionedGmres::operator=(PreconditionedGmres&&) noexcept = default;

bool PreconditionedGmres::single_precision_active() const {
  return kind_ == Kind::symmetric_part && impl_->single_active;
}

void PreconditionedGmres::set_preconditioner(const SparseMatrix& M, const Surrogate& surrogate) {
  kind_ = Kind::none;
  impl_->single_active = false;
  ++n_factorizations_;
  size_ = M.rows();
  auto try_symmetric_part = [&](const SparseMatrix& S) {
    try {
      impl_->cholmod.factorize(impl_->symmetric_part(S, impl_->cholmod.impl_->upper));
    } catch (const std::runtime_error&) {
      return false;  // not positive definite
    }
    kind_ = Kind::symmetric_part;
    impl_->single_active = single_precision_ && impl_->single.assign(impl_->cholmod.impl_->factor());
    return true;
  };
  if (try_symmetric_part(M)) return;
  if (surrogate) {
    ++n_surrogates_;
    if (try_symmetric_part(surrogate())) return;
  }
  // The full matrix by LU (GMRES then converges at once).
  impl_->umfpack.factorize(M);
  kind_ = Kind::full;
  ++n_full_factorizations_;
}

PreconditionedGmres::Report PreconditionedGmres::solve(const SparseMatrix& A, const Eigen::VectorXd& b,
                                                       Eigen::VectorXd& x, double tolerance, int max_iterations,
                                                       bool from_x) const {
  if (kind_ == Kind::none) throw std::logic_error("PreconditionedGmres: no preconditioner");
  const LinearSolver& M = kind_ == Kind::symmetric_part ? impl_->cholmod : impl_->umfpack;
  const bool single = single_precision_active();
  const auto n = static_cast<Eigen::Index>(b.size());
  const FlexibleGmres::Preconditioner precondition = [&](const double* r, double* z) {
    if (single) {
      impl_->single.solve(r, z);
    } else {
      Eigen::Map<Eigen::VectorXd>(z, n) = M.solve(Eigen::Map<const Eigen::VectorXd>(r, n));
    }
  };
  Report report;
  const double beta = b.norm();
  if (beta == 0) {
    x = Eigen::VectorXd::Zero(b.size());
    report.converged = true;
    return report;
  }
  // Stopped at half the tolerance on SPFGMR's residual estimate, so that the true
  // residual, which rounding moves away from the estimate, meets the tolerance.
  const double delta = 0.5 * tolerance * beta;
  if (from_x && x.size() == b.size() && x.allFinite()) {
    // GMRES on the correction: A d = b − A x₀, to the same absolute residual.
    const Eigen::VectorXd start = x;
    const Eigen::VectorXd r0 = b - A * start;
    if (!(r0.norm() <= delta)) {
      Eigen::VectorXd d;
      report.iterations = impl_->gmres.solve(A, precondition, r0, d, delta, std::max(1, max_iterations));
      x = start + d;
    }
  } else {
    report.iterations = impl_->gmres.solve(A, precondition, b, x, delta, std::max(1, max_iterations));
  }
  report.relative_residual = (b - A * x).norm() / beta;
  report.converged = report.relative_residual <= tolerance;
  return report;
}

PreconditionedGmres::Report PreconditionedGmres::solve_refreshing(const SparseMatrix& A, const Eigen::VectorXd& b,
                                                                  Eigen::VectorXd& x, double tolerance,
                                                                  int refresh_after, int max_iterations,
                                                                  const Surrogate& surrogate, bool from_x) {
  if (!has_preconditioner() || size_ != A.rows() || last_iterations_ > refresh_after) set_preconditioner(A, surrogate);
  const Eigen::VectorXd start = from_x ? x : Eigen::VectorXd();
  Report report = solve(A, b, x, tolerance, max_iterations, from_x);
  n_iterations_ += report.iterations;
  if (!report.converged) {
    set_preconditioner(A, surrogate);
    x = start;
    report = solve(A, b, x, tolerance, max_iterations, from_x);
    n_iterations_ += report.iterations;
    if (!report.converged && impl_->single_active) {  // the rounding of the float copy hurt
      impl_->single_active = false;
      x = start;
      report = solve(A, b, x, tolerance, max_iterations, from_x);
      n_iterations_ += report.iterations;
    }
    if (!report.converged) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "GMRES with a fresh preconditioner did not converge in %d iterations (relative residual %.3g, "
                    "tolerance %.3g)",
                    max_iterations, report.relative_residual, tolerance);
      throw std::runtime_error(text);
    }
  }
  last_iterations_ = report.iterations;
  return report;
}

}  // namespace rsw::fem
