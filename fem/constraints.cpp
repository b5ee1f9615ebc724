// Affine constraints: chain resolution, reduced numbering, distribute/condense;
// see constraints.hpp.
#include "fem/constraints.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>

namespace rsw::fem {

Constraints::Constraints(int n_dofs) : n_dofs_(n_dofs), line_of_(n_dofs, -1) {}

void Constraints::add_line(int dof, const std::vector<Entry>& entries, double inhomogeneity) {
  if (dof < 0 || dof >= n_dofs_)
    throw std::out_of_range("Constraints: dof " + std::to_string(dof) + " outside 0.." + std::to_string(n_dofs_ - 1));
  for (const auto& e : entries)
    if (e.dof < 0 || e.dof >= n_dofs_ || e.dof == dof)
      throw std::out_of_range("Constraints: dof " + std::to_string(dof) + " refers to invalid master " +
                              std::to_string(e.dof));
  if (line_of_[dof] >= 0) {
    const Line& old = lines_[line_of_[dof]];
    if (old.entries.empty() && entries.empty() && old.inhomogeneity == inhomogeneity) return;
    throw std::logic_error("Constraints: dof " + std::to_string(dof) + " is constrained twice");
  }
  line_of_[dof] = static_cast<int>(lines_.size());
  lines_.push_back({dof, entries, inhomogeneity});
  closed_ = false;
}

void Constraints::set_value(int dof, double value) {
  if (dof < 0 || dof >= n_dofs_ || line_of_[dof] < 0 || !lines_[line_of_[dof]].entries.empty())
    throw std::logic_error("Constraints::set_value: dof " + std::to_string(dof) + " is not a fixed-value line");
  lines_[line_of_[dof]].inhomogeneity = value;
  closed_ = false;
}

void Constraints::add_hanging_nodes(const Mesh& mesh, const DofMap& dofs) {
  for (const auto& h : mesh.hanging_nodes)
    for (int c = 0; c < dofs.n_components(); ++c)
      add_line(dofs.dof(h.node, c), {{dofs.dof(h.parents[0], c), 0.5}, {dofs.dof(h.parents[1], c), 0.5}});
}

void Constraints::close() {
  // Free dofs in increasing full order.
  free_index_.assign(n_dofs_, -1);
  n_free_ = 0;
  for (int d = 0; d < n_dofs_; ++d)
    if (line_of_[d] < 0) free_index_[d] = n_free_++;

  // Resolve every line to free dofs only (depth-first, memoised, cycle-checked).
  const int n_lines = static_cast<int>(lines_.size());
  std::vector<std::map<int, double>> resolved(n_lines);  // free full dof -> weight
  std::vector<double> resolved_b(n_lines, 0.0);
  std::vector<int> state(n_lines, 0);  // 0 new, 1 in progress, 2 done
  std::function<void(int)> resolve = [&](int l) {
    if (state[l] == 2) return;
    if (state[l] == 1)
      throw std::logic_error("Constraints: cyclic constraint through dof " + std::to_string(lines_[l].dof));
    state[l] = 1;
    double b = lines_[l].inhomogeneity;
    std::map<int, double> acc;
    for (const auto& e : lines_[l].entries) {
      const int m = line_of_[e.dof];
      if (m < 0) {
        acc[e.dof] += e.weight;
      } else {
        resolve(m);
        for (const auto& [d, w] : resolved[m]) acc[d] += e.weight * w;
        b += e.weight * resolved_b[m];
      }
    }
    resolved[l] = std::move(acc);
    resolved_b[l] = b;
    state[l] = 2;
  };
  for (int l = 0; l < n_lines; ++l) resolve(l);

  expansion_start_.assign(n_dofs_ + 1, 0);
  expansion_entries_.clear();
  resolved_inhomogeneity_.assign(n_dofs_, 0.0);
  for (int d = 0; d < n_dofs_; ++d) {
    expansion_start_[d] = static_cast<int>(expansion_entries_.size());
    const int l = line_of_[d];
    if (l < 0) {
      expansion_entries_.push_back({free_index_[d], 1.0});
    } else {
      for (const auto& [m, w] : resolved[l])
        if (w != 0.0) expansion_entries_.push_back({free_index_[m], w});
      resolved_inhomogeneity_[d] = resolved_b[l];
    }
  }
  expansion_start_[n_dofs_] = static_cast<int>(expansion_entries_.size());
  closed_ = true;
}

Eigen::VectorXd Constraints::distribute(const Eigen::VectorXd& reduced, bool homogeneous) const {
  if (!closed_) throw std::logic_error("Constraints::distribute before close()");
  if (reduced.size() != n_free_) throw std::invalid_argument("Constraints::distribute: size mismatch");
  Eigen::VectorXd full(n_dofs_);
  for (int d = 0; d < n_dofs_; ++d) {
    double v = homogeneous ? 0.0 : resolved_inhomogeneity_[d];
    auto [b, e] = expansion(d);
    for (auto it = b; it != e; ++it) v += it->weight * reduced[it->dof];
    full[d] = v;
  }
  return full;
}

Eigen::VectorXd Constraints::restrict_to_free(const Eigen::VectorXd& full) const {
  Eigen::VectorXd y(n_free_);
  for (int d = 0; d < n_dofs_; ++d)
    if (free_index_[d] >= 0) y[free_index_[d]] = full[d];
  return y;
}

Eigen::VectorXd Constraints::condense(const Eigen::VectorXd& full) const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n_free_);
  for (int d = 0; d < n_dofs_; ++d) {
    auto [b, e] = expansion(d);
    for (auto it = b; it != e; ++it) y[it->dof] += it->weight * full[d];
  }
  return y;
}

std::string Constraints::table() const {
  if (!closed_) throw std::logic_error("Constraints::table before close()");
  std::vector<int> full_of_free(n_free_);
  for (int d = 0; d < n_dofs_; ++d)
    if (free_index_[d] >= 0) full_of_free[free_index_[d]] = d;
  std::ostringstream out;
  out.precision(12);
  for (int d = 0; d < n_dofs_; ++d) {
    if (free_index_[d] >= 0) continue;
    out << d << ": " << resolved_inhomogeneity_[d];
    std::vector<Entry> entries(expansion(d).first, expansion(d).second);
    for (auto& e : entries) e.dof = full_of_free[e.dof];
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.dof < b.dof; });
    for (const auto& e : entries) out << " + " << e.weight << "*x" << e.dof;
    out << "\n";
  }
  return out.str();
}

}  // namespace rsw::fem
