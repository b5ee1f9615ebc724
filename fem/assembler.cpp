// Pattern, colouring and condensed scatter of the assembly loop; see assembler.hpp.
#include "fem/assembler.hpp"

#include "fem/threads.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <exception>
#include <stdexcept>

namespace rsw::fem {

Assembler::Assembler(const Mesh& mesh, const DofMap& dofs, const Constraints& constraints,
                     const std::vector<std::vector<int>>& dof_groups)
    : mesh_(mesh), dofs_(dofs), constraints_(constraints) {
  if (!constraints.closed()) throw std::logic_error("Assembler: constraints must be closed");
  if (constraints.n_dofs() != dofs.n_dofs()) throw std::logic_error("Assembler: constraints and dof map differ in size");
  const int n_cells = mesh.n_cells();
  const int n = constraints.n_free();

  const int n_elements = n_cells + static_cast<int>(dof_groups.size());
  element_dofs_.resize(n_elements);
  for (int e = 0; e < n_cells; ++e) dofs.cell_dofs(mesh, e, element_dofs_[e]);
  for (std::size_t g = 0; g < dof_groups.size(); ++g) {
    for (int d : dof_groups[g])
      if (d < 0 || d >= dofs.n_dofs()) throw std::out_of_range("Assembler: coupling group dof out of range");
    element_dofs_[n_cells + g] = dof_groups[g];
  }
  // The pattern: every pair of free dofs that an element couples, built column by
  // column (each element's reduced dofs, counted, listed, then sorted and made
  // unique per column) without a triplet list, which took a quarter of the run's
  // set-up on the paper's mesh.
  std::vector<std::vector<int>> reduced_of(n_elements);
  std::vector<int> column_count(n + 1, 0);
  for (int e = 0; e < n_elements; ++e) {
    std::vector<int>& reduced = reduced_of[e];
    for (int d : element_dofs_[e]) {
      auto [b, end] = constraints.expansion(d);
      for (auto it = b; it != end; ++it) reduced.push_back(it->dof);
    }
    std::sort(reduced.begin(), reduced.end());
    reduced.erase(std::unique(reduced.begin(), reduced.end()), reduced.end());
    for (int q : reduced) column_count[q + 1] += static_cast<int>(reduced.size());
  }
  for (int q = 0; q < n; ++q) column_count[q + 1] += column_count[q];
  std::vector<int> rows(static_cast<std::size_t>(column_count[n]));
  {
    std::vector<int> fill(column_count.begin(), column_count.end() - 1);
    for (const auto& reduced : reduced_of)
      for (int q : reduced)
        for (int p : reduced) rows[fill[q]++] = p;
  }
  pattern_.resize(n, n);
  std::vector<int> pattern_outer(n + 1, 0);
  int n_entries = 0;
  for (int q = 0; q < n; ++q) {
    const auto first = rows.begin() + column_count[q], last = rows.begin() + column_count[q + 1];
    std::sort(first, last);
    const auto unique_end = std::unique(first, last);
    for (auto it = first; it != unique_end; ++it) rows[n_entries++] = *it;  // n_entries ≤ the column's start
    pattern_outer[q + 1] = n_entries;
  }
  pattern_.resizeNonZeros(n_entries);
  std::copy(pattern_outer.begin(), pattern_outer.end(), pattern_.outerIndexPtr());
  std::copy(rows.begin(), rows.begin() + n_entries, pattern_.innerIndexPtr());
  std::fill(pattern_.valuePtr(), pattern_.valuePtr() + n_entries, 0.0);

  // Position of every contribution, in the exact order scatter() visits them.
  const int* outer = pattern_.outerIndexPtr();
  const int* inner = pattern_.innerIndexPtr();
  position_start_.resize(n_elements + 1);
  for (int e = 0; e < n_elements; ++e) {
    position_start_[e] = static_cast<int>(positions_.size());
    const auto& cd = element_dofs_[e];
    for (std::size_t b = 0; b < cd.size(); ++b) {
      auto [qb, qe] = constraints.expansion(cd[b]);
      for (auto q = qb; q != qe; ++q)
        for (std::size_t a = 0; a < cd.size(); ++a) {
          auto [pb, pe] = constraints.expansion(cd[a]);
          for (auto p = pb; p != pe; ++p) {
            const int* first = inner + outer[q->dof];
            const int* last = inner + outer[q->dof + 1];
            const int* hit = std::lower_bound(first, last, p->dof);
            positions_.push_back(static_cast<int>(hit - inner));
          }
        }
    }
  }
  position_start_[n_elements] = static_cast<int>(positions_.size());

  offset_.resize(n_elements + 1);
  expanded_size_.resize(n_elements);
  direct_vector_.assign(n_elements, 1);
  direct_matrix_.assign(n_elements, 1);
  for (int e = 0; e < n_elements; ++e) {
    offset_[e] = static_cast<int>(expansion_start_.size());
    int size = 0;
    for (int d : element_dofs_[e]) {
      expansion_start_.push_back(static_cast<int>(expansion_.size()));
      auto [b, end] = constraints.expansion(d);
      for (auto it = b; it != end; ++it) expansion_.push_back({it->dof, it->weight});
      size += static_cast<int>(end - b);
      if (end - b > 1 || (end - b == 1 && b->weight != 1.0)) direct_vector_[e] = 0;
      if (end - b != 1 || b->weight != 1.0) direct_matrix_[e] = 0;
      direct_dof_.push_back(end - b == 1 ? b->dof : -1);
    }
    expanded_size_[e] = size;
  }
  offset_[n_elements] = static_cast<int>(expansion_start_.size());
  expansion_start_.push_back(static_cast<int>(expansion_.size()));

  // Cells touching a hub dof (one shared by more than 16 cells, such as the rigid
  // motion of an electrode end face) are assembled serially after the others.
  std::vector<int> n_cells_of(n, 0);
  reduced_dofs_.resize(n_cells);
  for (int e = 0; e < n_cells; ++e) {
    reduced_dofs_[e] = std::move(reduced_of[e]);
    for (int p : reduced_dofs_[e]) ++n_cells_of[p];
  }
  constexpr int hub = 16;
  for (int e = 0; e < n_cells; ++e)
    if (std::any_of(reduced_dofs_[e].begin(), reduced_dofs_[e].end(), [&](int p) { return n_cells_of[p] > hub; }))
      serial_cells_.push_back(e);
}

void Assembler::partition(int n_threads) const {
  // Block t holds the cells t n/T ≤ e < (t + 1) n/T (the mesh numbers neighbouring
  // cells close together); a cell all of whose free dofs are touched only by cells of
  // its own block is assembled by that block's thread, the others (along the block
  // borders) serially afterwards. No two threads then write the same entry.
  // Under a mirror only the evaluated cells count (set_mirror), so that each thread
  // gets a share of the upper half.
  const int n_cells = mesh_.n_cells();
  blocks_.assign(n_threads, {});
  border_cells_.clear();
  std::vector<char> serial(n_cells, 0);
  for (int e : serial_cells_) serial[e] = 1;
  std::vector<int> rank(n_cells);
  int n_evaluated = 0;
  for (int e = 0; e < n_cells; ++e) {
    rank[e] = n_evaluated;
    if (element_weight(e) != 0.0) ++n_evaluated;
    else serial[e] = 1;  // in no block: never evaluated
  }
  auto block_of = [&](int e) { return static_cast<int>(static_cast<long>(rank[e]) * n_threads / n_evaluated); };
  std::vector<int> owner(constraints_.n_free(), -1);  // block of the cells touching a dof; -2: several
  for (int e = 0; e < n_cells; ++e) {
    if (serial[e]) continue;
    for (int p : reduced_dofs_[e]) owner[p] = owner[p] == -1 || owner[p] == block_of(e) ? block_of(e) : -2;
  }
  for (int e = 0; e < n_cells; ++e) {
    if (serial[e]) continue;
    const bool inside = std::all_of(reduced_dofs_[e].begin(), reduced_dofs_[e].end(),
                                    [&](int p) { return owner[p] == block_of(e); });
    (inside ? blocks_[block_of(e)] : border_cells_).push_back(e);
  }
  partitioned_threads_ = n_threads;
}

void Assembler::scatter_vector(int element, const Eigen::VectorXd& vector, const double* matrix, Eigen::VectorXd& F,
                               bool homogeneous) const {
  const auto& cd = element_dofs_[element];
  const int n_local = static_cast<int>(cd.size());
  const int* start = expansion_start_.data() + offset_[element];
  const Term* terms = expansion_.data();
  auto add = [&](const Eigen::VectorXd& rhs) {
    if (direct_vector_[element]) {
      const int* dof = direct_dof_.data() + offset_[element];
      for (int a = 0; a < n_local; ++a)
        if (dof[a] >= 0) F[dof[a]] += rhs[a];
      return;
    }
    for (int a = 0; a < n_local; ++a)
      for (int i = start[a]; i < start[a + 1]; ++i) F[terms[i].dof] += terms[i].weight * rhs[a];
  };
  // F_e - K_e g where the element touches a dof with an inhomogeneous constraint.
  const bool inhomogeneous = !homogeneous && std::any_of(cd.begin(), cd.end(), [&](int d) {
    return constraints_.inhomogeneity(d) != 0.0;
  });
  if (!inhomogeneous) {
    add(vector);
  } else {
    const Eigen::Map<const Eigen::MatrixXd> K_e(matrix, n_local, n_local);
    Eigen::VectorXd rhs = vector;
    for (int b = 0; b < n_local; ++b) {
      const double g = constraints_.inhomogeneity(cd[b]);
      if (g != 0.0) rhs -= K_e.col(b) * g;
    }
    add(rhs);
  }
}

void Assembler::scatter_matrix(int element, const double* matrix, int n_local, double* values) const {
  const int* start = expansion_start_.data() + offset_[element];
  const Term* terms = expansion_.data();
  // Zero entries are skipped (a coupling group's system is mostly zero: each contact
  // point touches four of its nodes); the positions are then advanced past them.
  const int* pos = positions_.data() + position_start_[element];
  if (direct_matrix_[element]) {  // one position per entry, column by column
    for (int b = 0; b < n_local; ++b, pos += n_local) {
      const double* column = matrix + static_cast<std::ptrdiff_t>(b) * n_local;
      for (int a = 0; a < n_local; ++a)
        if (column[a] != 0.0) values[pos[a]] += column[a];
    }
    return;
  }
  const int column_size = expanded_size_[element];
  for (int b = 0; b < n_local; ++b) {
    const double* column = matrix + static_cast<std::ptrdiff_t>(b) * n_local;
    const int n_q = start[b + 1] - start[b];
    if (std::all_of(column, column + n_local, [](double v) { return v == 0.0; })) {
      pos += n_q * column_size;
      continue;
    }
    for (int j = start[b]; j < start[b + 1]; ++j) {
      const double wq = terms[j].weight;
      for (int a = 0; a < n_local; ++a) {
        const double kab = column[a] * wq;
        if (kab == 0.0) {
          pos += start[a + 1] - start[a];
          continue;
        }
        for (int i = start[a]; i < start[a + 1]; ++i) values[*pos++] += terms[i].weight * kab;
      }
    }
  }
}

void Assembler::scatter_touched(int element, const double* matrix, int n_local, const std::vector<int>& touched,
                                double* values) const {
  // The entries scatter_matrix would add, in its order (column by column, rows
  // ascending; zero entries skipped), so the sums are the same to the bit. The
  // positions of element entry (row term i, column term j) lie at
  // (j − s0) · column_size + (i − s0), s0 the element's first expansion term
  // (scatter_matrix's order); with one term per dof that is b · n_local + a.
  const int* start = expansion_start_.data() + offset_[element];
  const Term* terms = expansion_.data();
  const int* pos = positions_.data() + position_start_[element];
  if (direct_matrix_[element]) {
    for (int b : touched) {
      const double* column = matrix + static_cast<std::ptrdiff_t>(b) * n_local;
      const int* column_pos = pos + static_cast<std::ptrdiff_t>(b) * n_local;
      for (int a : touched)
        if (column[a] != 0.0) values[column_pos[a]] += column[a];
    }
    return;
  }
  const int column_size = expanded_size_[element];
  const int s0 = start[0];
  for (int b : touched) {
    const double* column = matrix + static_cast<std::ptrdiff_t>(b) * n_local;
    for (int j = start[b]; j < start[b + 1]; ++j) {
      const double wq = terms[j].weight;
      const int* column_pos = pos + static_cast<std::ptrdiff_t>(j - s0) * column_size;
      for (int a : touched) {
        const double kab = column[a] * wq;
        if (kab == 0.0) continue;
        for (int i = start[a]; i < start[a + 1]; ++i) values[column_pos[i - s0]] += terms[i].weight * kab;
      }
    }
  }
}

void Assembler::scatter(int element, const LocalSystem& local, SparseMatrix& K, Eigen::VectorXd& F,
                        bool homogeneous, bool assemble_matrix) const {
  if (local.matrix_kept)
    throw std::logic_error("Assembler: a kernel kept its matrix, but no cell matrices are cached");
  scatter_vector(element, local.vector, local.matrix.data(), F, homogeneous);
  if (assemble_matrix)
    scatter_matrix(element, local.matrix.data(), static_cast<int>(local.matrix.rows()), K.valuePtr());
}

void Assembler::enable_cell_matrix_cache() {
  const std::size_t n_local = static_cast<std::size_t>(dofs_.dofs_per_cell());
  cache_matrices_.assign(static_cast<std::size_t>(mesh_.n_cells()) * n_local * n_local, 0.0);
  cache_sum_.assign(static_cast<std::size_t>(pattern_.nonZeros()), 0.0);
  cache_assemblies_ = 0;
  cache_enabled_ = true;
}

void Assembler::scatter_cached(int cell, const LocalSystem& local, Eigen::VectorXd& F, bool homogeneous,
                               bool rebuild) const {
  const int n_local = dofs_.dofs_per_cell();
  const std::size_t size = static_cast<std::size_t>(n_local) * n_local;
  double* kept = cache_matrices_.data() + static_cast<std::size_t>(cell) * size;
  scatter_vector(cell, local.vector, local.matrix_kept ? kept : local.matrix.data(), F, homogeneous);
  if (local.matrix_kept) {
    if (rebuild)
      scatter_matrix(cell, kept, n_local, cache_sum_.data());
    else
      cache_reused_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  const double* now = local.matrix.data();
  if (rebuild) {
    std::copy(now, now + size, kept);
    scatter_matrix(cell, now, n_local, cache_sum_.data());
    cache_scattered_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (std::equal(now, now + size, kept)) {
    cache_reused_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  double difference[64 * 64];
  if (size > sizeof difference / sizeof difference[0])
    throw std::logic_error("Assembler: cell matrices above 64 x 64 are not cached");
  for (std::size_t i = 0; i < size; ++i) difference[i] = now[i] - kept[i];
  std::copy(now, now + size, kept);
  scatter_matrix(cell, difference, n_local, cache_sum_.data());
  cache_scattered_.fetch_add(1, std::memory_order_relaxed);
}

void Assembler::set_mirror(const MirrorSymmetry& mirror) {
  weight_.clear();
  partitioned_threads_ = 0;  // the threads' blocks follow the evaluated cells
  cache_assemblies_ = 0;     // the cached sum holds the cells of the old weights
  cache_complete_ = false;
  if (mirror.empty()) return;
  if (static_cast<int>(mirror.image_of.size()) != mesh_.n_nodes())
    throw std::invalid_argument("Assembler::set_mirror: the mirror is of another mesh");
  const int nc = dofs_.n_components();
  const int node_dofs = nc * mesh_.n_nodes();
  weight_.resize(element_dofs_.size());
  std::vector<int> nodes;
  for (std::size_t e = 0; e < element_dofs_.size(); ++e) {
    nodes.clear();
    for (int d : element_dofs_[e])
      if (d < node_dofs) nodes.push_back(d / nc);  // extra dofs (a rigid face) belong to no half
    weight_[e] = mirror.weight(nodes);
  }
}

void Assembler::assemble(const Terms& terms, SparseMatrix& K, Eigen::VectorXd& F, bool homogeneous,
                         bool assemble_matrix) const {
  const CellKernel& cell_kernel = terms.cells;
  // Cell matrices go through the cache (into cache_sum_, copied into K below).
  const bool cached = cache_enabled_ && assemble_matrix && cell_kernel;
  if (assemble_matrix) {
    if (K.rows() != pattern_.rows() || K.nonZeros() != pattern_.nonZeros()) K = pattern_;
    if (!cached) std::fill(K.valuePtr(), K.valuePtr() + K.nonZeros(), 0.0);
  }
  // A rebuild scatters every cell afresh into a zeroed sum; until it completes (a
  // kernel may throw) the sum is incomplete and the next assembly rebuilds again.
  const bool rebuild = cached && (cache_assemblies_ == 0 || !cache_complete_);
  if (rebuild) {
    std::fill(cache_sum_.begin(), cache_sum_.end(), 0.0);
    cache_complete_ = false;
  }
  auto scatter_cell = [&](int e, LocalSystem& local) {
    // A cell the mirror plane cuts counts half (fem/mirror.hpp); a kept matrix is the
    // cache's copy, already weighted.
    if (const double w = element_weight(e); w != 1.0) {
      if (!local.matrix_kept) local.matrix *= w;
      local.vector *= w;
    }
    if (cached)
      scatter_cached(e, local, F, homogeneous, rebuild);
    else
      scatter(e, local, K, F, homogeneous, assemble_matrix);
  };
  F.setZero(constraints_.n_free());
  const int n_local = dofs_.dofs_per_cell();

  if (cell_kernel && omp_get_max_threads() == 1) {
    // One thread: no OpenMP region at all. Even a one-thread team ends each worksharing
    // loop at a barrier whose last arrival wakes its waiters by a futex system call,
    // waiters or not (with the kernel's futex path about 5 % of a default weld's
    // profile on a virtual machine, when the threaded loop went colour by colour,
    // docs/PERFORMANCE.md). The cells in their own order, hub cells included (visiting
    // them colour by colour, all over the mesh, cost the default weld 13 % in cache
    // misses: docs/PERFORMANCE.md).
    LocalSystem local;
    for (int e = 0; e < mesh_.n_cells(); ++e) {
      if (element_weight(e) == 0.0) continue;
      local.matrix.setZero(n_local, n_local);
      local.vector.setZero(n_local);
      local.matrix_kept = false;
      cell_kernel(e, local);
      scatter_cell(e, local);
    }
  } else if (cell_kernel) {
    // An exception may not leave an OpenMP region (the process would terminate): the
    // first one thrown by a cell kernel is kept, the remaining cells are skipped, and
    // it is rethrown after the region.
    const int n_threads = omp_get_max_threads();
    if (partitioned_threads_ != n_threads) partition(n_threads);
    std::exception_ptr failure;
    std::atomic<bool> failed{false};
    {
      const TeamRegion team;  // this loop on the process's threads (fem/threads.hpp)
#pragma omp parallel
      {
        LocalSystem local;
        for (int b = omp_get_thread_num(); b < n_threads; b += omp_get_num_threads())
          for (const int e : blocks_[b]) {
            if (failed.load(std::memory_order_relaxed)) break;
            if (element_weight(e) == 0.0) continue;
            try {
              local.matrix.setZero(n_local, n_local);
              local.vector.setZero(n_local);
              local.matrix_kept = false;
              cell_kernel(e, local);
              scatter_cell(e, local);
            } catch (...) {
#pragma omp critical(rsw_assembler_failure)
              if (!failed.exchange(true)) failure = std::current_exception();
            }
          }
      }
    }
    if (failure) std::rethrow_exception(failure);
  }
  // Cells on block borders and hub dofs (threaded runs; one thread visited them
  // above), face terms and coupling groups: serial.
  LocalSystem local;
  if (cell_kernel && omp_get_max_threads() > 1)
    for (const std::vector<int>* cells : std::array<const std::vector<int>*, 2>{&border_cells_, &serial_cells_})
      for (int e : *cells) {
        if (element_weight(e) == 0.0) continue;
        local.matrix.setZero(n_local, n_local);
        local.vector.setZero(n_local);
        local.matrix_kept = false;
        cell_kernel(e, local);
        scatter_cell(e, local);
      }
  if (cached) {
    cache_complete_ = true;
    cache_assemblies_ = (cache_assemblies_ + 1) % 64;
    std::copy(cache_sum_.begin(), cache_sum_.end(), K.valuePtr());
  }
  for (const auto& term : terms.faces)
    for (const auto& face : *term.faces) {
      const double w = element_weight(face.cell);
      if (w == 0.0) continue;
      local.matrix.setZero(n_local, n_local);
      local.vector.setZero(n_local);
      local.matrix_kept = false;
      term.kernel(face, local);
      if (w != 1.0) {
        local.matrix *= w;
        local.vector *= w;
      }
      scatter(face.cell, local, K, F, homogeneous, assemble_matrix);
    }
  if (terms.groups) {
    const int n_cells = mesh_.n_cells();
    for (int g = 0; g < n_groups(); ++g) {
      // A group of weight 0 is evaluated, not assembled: a contact kernel keeps its
      // points' friction history, which the image interface reports.
      const double w = element_weight(n_cells + g);
      const int n = static_cast<int>(element_dofs_[n_cells + g].size());
      if (static_cast<int>(zero_group_matrices_.size()) <= n) {
        zero_group_matrices_.resize(n + 1);
        zero_group_valid_.resize(n + 1, 0);
      }
      Eigen::MatrixXd& zero = zero_group_matrices_[n];
      if (!zero_group_valid_[n]) zero.setZero(n, n);
      zero_group_valid_[n] = 0;  // until it is returned zeroed below (a kernel may throw)
      local.matrix.swap(zero);   // local.matrix: n x n zeros
      local.vector.setZero(n);
      local.matrix_kept = false;
      local.lists_touched = false;
      local.touched.clear();
      terms.groups(g, local);
      std::vector<int>& touched = local.touched;
      if (local.lists_touched) {
        std::sort(touched.begin(), touched.end());
        touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
      }
      if (w != 0.0) {
        if (!local.lists_touched) {
          if (w != 1.0) {
            local.matrix *= w;
            local.vector *= w;
          }
          scatter(n_cells + g, local, K, F, homogeneous, assemble_matrix);
        } else {
          if (w != 1.0) {
            for (int b : touched)
              for (int a : touched) local.matrix(a, b) *= w;
            local.vector *= w;
          }
          scatter_vector(n_cells + g, local.vector, local.matrix.data(), F, homogeneous);
          if (assemble_matrix) scatter_touched(n_cells + g, local.matrix.data(), n, touched, K.valuePtr());
        }
      }
      if (local.lists_touched) {
        for (int b : touched)
          for (int a : touched) local.matrix(a, b) = 0.0;
      } else {
        local.matrix.setZero();
      }
      local.matrix.swap(zero);  // returned zeroed
      zero_group_valid_[n] = 1;
    }
  }
}

}  // namespace rsw::fem
