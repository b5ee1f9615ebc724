// Exact elimination of interior unknowns (static condensation); see
// interior_elimination.hpp.
#include "fem/interior_elimination.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace rsw::fem {

InteriorElimination::InteriorElimination(std::vector<char> interior) : interior_(std::move(interior)) {
  local_.assign(interior_.size(), -1);
  for (int k = 0; k < n_unknowns(); ++k) {
    std::vector<int>& list = interior_[k] ? interior_index_ : reduced_index_;
    local_[k] = static_cast<int>(list.size());
    list.push_back(k);
  }
}

void InteriorElimination::build(const SparseMatrix& K) {
  ready_ = false;
  changes_in_a_row_ = 0;
  pattern_outer_.assign(K.outerIndexPtr(), K.outerIndexPtr() + K.cols() + 1);
  pattern_inner_.assign(K.innerIndexPtr(), K.innerIndexPtr() + K.nonZeros());
  watched_.clear();
  watched_values_.clear();
  ia_.clear();
  ai_.clear();
  const int* outer = pattern_outer_.data();
  const int* inner = pattern_inner_.data();
  // Position of entry (i, j) in K, or −1.
  auto position = [&](int i, int j) {
    const int* first = inner + outer[j];
    const int* last = inner + outer[j + 1];
    const int* hit = std::lower_bound(first, last, i);
    return hit != last && *hit == i ? static_cast<int>(hit - inner) : -1;
  };
  std::vector<char> on_border(reduced_index_.size(), 0);
  for (int j = 0; j < n_unknowns(); ++j)
    for (int k = outer[j]; k < outer[j + 1]; ++k) {
      const int i = inner[k];
      if (!interior_[i] && !interior_[j]) continue;
      const int watch = static_cast<int>(watched_.size());
      watched_.push_back(k);
      if (interior_[i] && !interior_[j]) {
        ia_.push_back({k, local_[i], local_[j], watch});
        on_border[local_[j]] = 1;
      } else if (!interior_[i]) {
        ai_.push_back({k, local_[i], local_[j], watch});
        on_border[local_[i]] = 1;
      }
    }
  border_.clear();
  border_slot_.assign(reduced_index_.size(), -1);
  for (int a = 0; a < n_reduced(); ++a)
    if (on_border[a]) {
      border_slot_[a] = static_cast<int>(border_.size());
      border_.push_back(a);
    }
  const int nb = n_border(), ni = n_interior();

  // The lower triangle of K over I then B: interior column i holds the interior rows
  // from i on, then the border rows; border column b the border rows from b on.
  symmetric_pattern_ = true;
  bordered_position_.clear();
  bordered_mirror_.clear();
  std::vector<int> b_outer{0}, b_inner;
  auto take = [&](int k, int row, int j) {
    const int mirror = position(j, inner[k]);
    if (mirror < 0) symmetric_pattern_ = false;
    bordered_position_.push_back(k);
    bordered_mirror_.push_back(std::max(mirror, 0));
    b_inner.push_back(row);
  };
  for (int c = 0; c < ni; ++c) {
    const int j = interior_index_[c];
    for (int k = outer[j]; k < outer[j + 1]; ++k)
      if (interior_[inner[k]] && local_[inner[k]] >= c) take(k, local_[inner[k]], j);
    for (int k = outer[j]; k < outer[j + 1]; ++k)
      if (!interior_[inner[k]] && border_slot_[local_[inner[k]]] >= 0) take(k, ni + border_slot_[local_[inner[k]]], j);
    b_outer.push_back(static_cast<int>(b_inner.size()));
  }
  for (int c = 0; c < nb; ++c) {
    const int j = reduced_index_[border_[c]];
    for (int k = outer[j]; k < outer[j + 1]; ++k) {
      const int i = inner[k];
      if (!interior_[i] && border_slot_[local_[i]] >= c) take(k, ni + border_slot_[local_[i]], j);
    }
    b_outer.push_back(static_cast<int>(b_inner.size()));
  }
  bordered_.resize(ni + nb, ni + nb);
  bordered_.resizeNonZeros(static_cast<Eigen::Index>(b_inner.size()));
  std::copy(b_outer.begin(), b_outer.end(), bordered_.outerIndexPtr());
  std::copy(b_inner.begin(), b_inner.end(), bordered_.innerIndexPtr());

  // S: K_AA's entries of each column of A, and in a border column every border row.
  aa_map_.clear();
  bb_position_.assign(static_cast<std::size_t>(nb) * nb, -1);
  std::vector<int> s_outer{0}, s_inner;
  std::vector<std::pair<int, int>> column;  // (row in A, position in K, or −1 − border slot)
  for (int a = 0; a < n_reduced(); ++a) {
    const int j = reduced_index_[a];
    column.clear();
    for (int k = outer[j]; k < outer[j + 1]; ++k)
      if (!interior_[inner[k]]) column.push_back({local_[inner[k]], k});
    if (border_slot_[a] >= 0)
      for (int s = 0; s < nb; ++s) column.push_back({border_[s], -1 - s});
    std::sort(column.begin(), column.end());
    for (std::size_t c = 0; c < column.size();) {
      const int row = column[c].first;
      const int at = static_cast<int>(s_inner.size());
      s_inner.push_back(row);
      for (; c < column.size() && column[c].first == row; ++c) {
        if (column[c].second >= 0)
          aa_map_.push_back({column[c].second, at});
        else
          bb_position_[static_cast<std::size_t>(-1 - column[c].second) +
                       static_cast<std::size_t>(nb) * border_slot_[a]] = at;
      }
    }
    s_outer.push_back(static_cast<int>(s_inner.size()));
  }
  // Runs of consecutive positions in both K and S, copied as blocks.
  aa_runs_.clear();
  for (const auto& [from, to] : aa_map_)
    if (!aa_runs_.empty() && aa_runs_.back().from + aa_runs_.back().length == from &&
        aa_runs_.back().to + aa_runs_.back().length == to)
      ++aa_runs_.back().length;
    else
      aa_runs_.push_back({from, to, 1});
  // Border-block positions that no entry of K fills: zeroed before C is subtracted.
  std::vector<char> filled(s_inner.size(), 0);
  for (const auto& pair : aa_map_) filled[pair.second] = 1;
  bb_only_.clear();
  for (int at : bb_position_)
    if (!filled[at]) bb_only_.push_back(at);
  aa_map_.clear();
  for (SparseMatrix* S : {&S_, &S_other_}) {
    S->resize(n_reduced(), n_reduced());
    S->resizeNonZeros(static_cast<Eigen::Index>(s_inner.size()));
    std::copy(s_outer.begin(), s_outer.end(), S->outerIndexPtr());
    std::copy(s_inner.begin(), s_inner.end(), S->innerIndexPtr());
  }
}

bool InteriorElimination::condense(const SparseMatrix& K) {
  if (!symmetric_pattern_) return false;
  const double* v = K.valuePtr();
  double* b = bordered_.valuePtr();
  double scale = 0;
  for (std::size_t u = 0; u < bordered_position_.size(); ++u) {
    b[u] = v[bordered_position_[u]];
    scale = std::max(scale, std::abs(b[u]));
  }
  // K_II and K_IB = K_BIᵀ to rounding: each entry within 10⁻¹² of the largest of its
  // mirror. K_BB needs no symmetry: C does not depend on it, and its lower triangle
  // only completes a positive definite matrix to factorise.
  const int interior_columns_end = bordered_.outerIndexPtr()[n_interior()];
  for (int u = 0; u < interior_columns_end; ++u)
    if (!(std::abs(b[u] - v[bordered_mirror_[u]]) <= 1e-12 * scale)) return false;
  const int nb = n_border(), ni = n_interior();
  try {
    if (!factor_.factorize(bordered_, nb)) return false;  // not positive definite
  } catch (const std::runtime_error&) {
    return false;  // no ordering or analysis: the caller solves with K itself
  }
  // C = K_BB − (K_BB − K_BI K_II⁻¹ K_IB), with K_BB as factorised (its lower triangle).
  C_ = -factor_.schur_complement();
  for (int c = 0; c < nb; ++c)
    for (int k = bordered_.outerIndexPtr()[ni + c]; k < bordered_.outerIndexPtr()[ni + c + 1]; ++k) {
      const int r = bordered_.innerIndexPtr()[k] - ni;
      C_(r, c) += b[k];
      if (r != c) C_(c, r) += b[k];
    }
  for (std::size_t u = 0; u < watched_.size(); ++u) watched_values_[u] = v[watched_[u]];
  return true;
}

void InteriorElimination::fill_reduced(const SparseMatrix& M, SparseMatrix& out) const {
  if (M.rows() != n_unknowns() || M.nonZeros() != static_cast<Eigen::Index>(pattern_inner_.size()))
    throw std::logic_error("InteriorElimination: a matrix of another pattern than the one prepared");
  const double* m = M.valuePtr();
  double* s = out.valuePtr();
  for (int at : bb_only_) s[at] = 0.0;
  for (const Run& run : aa_runs_) std::copy(m + run.from, m + run.from + run.length, s + run.to);
  const int nb = n_border();
  for (int b = 0; b < nb; ++b)
    for (int a = 0; a < nb; ++a)
      s[bb_position_[static_cast<std::size_t>(a) + static_cast<std::size_t>(nb) * b]] -= C_(a, b);
}

bool InteriorElimination::prepare(const SparseMatrix& K) {
  if (n_interior() == 0 || K.rows() != n_unknowns() || K.cols() != n_unknowns() || !K.isCompressed()) return false;
  // The pattern is taken as the last one where the column starts match (matrices of
  // one assembler).
  const bool same_pattern = static_cast<Eigen::Index>(pattern_outer_.size()) == K.cols() + 1 &&
                            static_cast<Eigen::Index>(pattern_inner_.size()) == K.nonZeros() &&
                            std::equal(pattern_outer_.begin(), pattern_outer_.end(), K.outerIndexPtr());
  if (!same_pattern) build(K);
  const double* v = K.valuePtr();
  bool same = watched_values_.size() == watched_.size();
  for (std::size_t u = 0; same && u < watched_.size(); ++u) same = watched_values_[u] == v[watched_[u]];
  if (same && ready_) {
    ++n_reuses_;
    changes_in_a_row_ = 0;
    fill_reduced(K, S_);
    return true;
  }
  watched_values_.resize(watched_.size());
  // An interior that changes from one matrix to the next is not worth condensing: the
  // third matrix in a row whose interior differs from the one before is not
  // condensed, and the caller solves with K itself until two matrices in a row agree
  // on the interior again.
  changes_in_a_row_ = same ? 0 : changes_in_a_row_ + 1;
  ready_ = changes_in_a_row_ <= 2 && condense(K);
  if (!ready_) {
    for (std::size_t u = 0; u < watched_.size(); ++u) watched_values_[u] = v[watched_[u]];
    return false;
  }
  ++n_condensations_;
  fill_reduced(K, S_);
  return true;
}

const SparseMatrix& InteriorElimination::reduce_matrix(const SparseMatrix& M) {
  if (!ready_) throw std::logic_error("InteriorElimination::reduce_matrix before a successful prepare()");
  fill_reduced(M, S_other_);
  return S_other_;
}

Eigen::VectorXd InteriorElimination::reduce(const Eigen::VectorXd& r, double negligible) const {
  if (!ready_) throw std::logic_error("InteriorElimination::reduce before a successful prepare()");
  Eigen::VectorXd z(n_interior()), out(n_reduced());
  for (int i = 0; i < n_interior(); ++i) z[i] = r[interior_index_[i]];
  for (int a = 0; a < n_reduced(); ++a) out[a] = r[reduced_index_[a]];
  if (z.norm() <= negligible) return out;
  factor_.solve_leading(z.data(), z.data());
  for (const Entry& e : ai_) out[e.row] -= watched_values_[e.watch] * z[e.column];
  return out;
}

Eigen::VectorXd InteriorElimination::expand(const Eigen::VectorXd& r, const Eigen::VectorXd& y_A) const {
  if (!ready_) throw std::logic_error("InteriorElimination::expand before a successful prepare()");
  Eigen::VectorXd t(n_interior());
  for (int i = 0; i < n_interior(); ++i) t[i] = r[interior_index_[i]];
  for (const Entry& e : ia_) t[e.row] -= watched_values_[e.watch] * y_A[e.column];
  factor_.solve_leading(t.data(), t.data());
  Eigen::VectorXd y(n_unknowns());
  for (int i = 0; i < n_interior(); ++i) y[interior_index_[i]] = t[i];
  for (int a = 0; a < n_reduced(); ++a) y[reduced_index_[a]] = y_A[a];
  return y;
}

}  // namespace rsw::fem
