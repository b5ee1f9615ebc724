// Gauss-point-to-segment pairing; see interface_pairing.hpp.
#include "contact/interface_pairing.hpp"

#include "fem/fe_values.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rsw::contact {

namespace {
Eigen::Vector2d outward_normal(const fem::Point& a, const fem::Point& b) {
  const fem::Point t = b - a;  // counter-clockwise in the cell: outward is (t_z, -t_r)
  return Eigen::Vector2d(t.y(), -t.x()).normalized();
}
}  // namespace

InterfacePairing::InterfacePairing(const fem::Mesh& mesh, const std::string& name, int n_gauss,
                                   double search_margin, bool mirrored)
    : mesh_(mesh), name_(name), n_gauss_(n_gauss) {
  auto it = mesh.interfaces.find(name);
  if (it == mesh.interfaces.end()) throw std::out_of_range("unknown interface '" + name + "'");
  slave_ = mirrored ? it->second.second : it->second.first;
  master_ = mirrored ? it->second.first : it->second.second;
  for (const auto& f : mesh.boundary(slave_)) slave_faces_.push_back(mesh.face_nodes(f));
  for (const auto& f : mesh.boundary(master_)) master_faces_.push_back(mesh.face_nodes(f));

  for (const auto& mf : master_faces_) {
    master_nodes_.push_back(mf[0]);
    master_nodes_.push_back(mf[1]);
  }
  std::sort(master_nodes_.begin(), master_nodes_.end());
  master_nodes_.erase(std::unique(master_nodes_.begin(), master_nodes_.end()), master_nodes_.end());
  master_faces_of_node_.assign(master_nodes_.size(), {});
  for (std::size_t f = 0; f < master_faces_.size(); ++f)
    for (int n : master_faces_[f]) {
      auto pos = std::lower_bound(master_nodes_.begin(), master_nodes_.end(), n) - master_nodes_.begin();
      master_faces_of_node_[pos].push_back(static_cast<int>(f));
    }

  candidates_.resize(slave_faces_.size());
  coupling_nodes_.resize(slave_faces_.size());
  for (std::size_t s = 0; s < slave_faces_.size(); ++s) {
    const double r0 = std::min(mesh.nodes[slave_faces_[s][0]].x(), mesh.nodes[slave_faces_[s][1]].x()) - search_margin;
    const double r1 = std::max(mesh.nodes[slave_faces_[s][0]].x(), mesh.nodes[slave_faces_[s][1]].x()) + search_margin;
    std::vector<int> nodes;
    for (std::size_t m = 0; m < master_faces_.size(); ++m) {
      const double m0 = std::min(mesh.nodes[master_faces_[m][0]].x(), mesh.nodes[master_faces_[m][1]].x());
      const double m1 = std::max(mesh.nodes[master_faces_[m][0]].x(), mesh.nodes[master_faces_[m][1]].x());
      if (m1 < r0 || m0 > r1) continue;
      candidates_[s].push_back(static_cast<int>(m));
      nodes.push_back(master_faces_[m][0]);
      nodes.push_back(master_faces_[m][1]);
    }
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    coupling_nodes_[s] = {slave_faces_[s][0], slave_faces_[s][1]};
    coupling_nodes_[s].insert(coupling_nodes_[s].end(), nodes.begin(), nodes.end());
  }

  const auto rule = fem::gauss_legendre(n_gauss);
  points_.resize(slave_faces_.size() * n_gauss);
  for (std::size_t s = 0; s < slave_faces_.size(); ++s)
    for (int q = 0; q < n_gauss; ++q) {
      ContactPoint& p = points_[s * n_gauss + q];
      p.slave_face = static_cast<int>(s);
      p.slave_nodes = slave_faces_[s];
      p.slave_weights = {0.5 * (1 - rule.points[q]), 0.5 * (1 + rule.points[q])};
    }
  update(mesh.nodes);
  for (auto& p : points_) {
    p.reference_position = p.position;
    p.reference_area = p.area;
  }
}

int InterfacePairing::local_index(int slave_face, int node) const {
  const auto& nodes = coupling_nodes_[slave_face];
  auto it = std::find(nodes.begin(), nodes.end(), node);
  return it == nodes.end() ? -1 : static_cast<int>(it - nodes.begin());
}

InterfacePairing::Projection InterfacePairing::projection(const std::vector<fem::Point>& x, int face,
                                                          const fem::Point& point) const {
  const fem::Point& m1 = x[master_faces_[face][0]];
  const fem::Point& m2 = x[master_faces_[face][1]];
  const fem::Point t = m2 - m1;
  Projection pr;
  pr.eta_raw = (point - m1).dot(t) / t.squaredNorm();
  pr.eta = std::clamp(pr.eta_raw, 0.0, 1.0);
  pr.distance2 = (point - (m1 + pr.eta * t)).squaredNorm();
  return pr;
}

bool InterfacePairing::update(const std::vector<fem::Point>& x) {
  const auto rule = fem::gauss_legendre(n_gauss_);
  bool within = true;
  std::vector<Eigen::Vector2d> nodal_normals(master_nodes_.size(), Eigen::Vector2d::Zero());
  for (std::size_t k = 0; k < master_nodes_.size(); ++k) {
    for (int f : master_faces_of_node_[k])
      nodal_normals[k] += outward_normal(x[master_faces_[f][0]], x[master_faces_[f][1]]);
    nodal_normals[k].normalize();
  }
  std::vector<Box> boxes(master_faces_.size());
  for (std::size_t m = 0; m < master_faces_.size(); ++m) {
    const fem::Point& m1 = x[master_faces_[m][0]];
    const fem::Point& m2 = x[master_faces_[m][1]];
    boxes[m] = {std::min(m1.x(), m2.x()), std::max(m1.x(), m2.x()), std::min(m1.y(), m2.y()), std::max(m1.y(), m2.y())};
  }
  last_closest_.resize(points_.size(), -1);
  // A face with a coordinate that is not finite is never the closest (its distance is
  // NaN), so it is left out of the search.
  std::vector<int> by_r, nearby;
  double widest = 0;
  for (std::size_t m = 0; m < boxes.size(); ++m) {
    const Box& box = boxes[m];
    if (!std::isfinite(box.r0 + box.r1 + box.z0 + box.z1)) continue;
    by_r.push_back(static_cast<int>(m));
    widest = std::max(widest, box.r1 - box.r0);
  }
  std::sort(by_r.begin(), by_r.end(), [&](int a, int b) { return boxes[a].r0 < boxes[b].r0; });
  for (auto& p : points_) {
    const fem::Point& a = x[p.slave_nodes[0]];
    const fem::Point& b = x[p.slave_nodes[1]];
    p.position = p.slave_weights[0] * a + p.slave_weights[1] * b;
    const int q = static_cast<int>(&p - points_.data()) % n_gauss_;
    p.area = rule.weights[q] * 0.5 * (b - a).norm() * 2.0 * M_PI * p.position.x();

    // Closest point over all master faces, the first in face order where several are
    // equally close (a point facing a master node); the winner need not be a
    // candidate. A face whose bounding box lies farther than the last update's closest
    // face is now (`bound`) cannot win and is not projected on: the result is that of
    // projecting on every face.
    const std::size_t point = static_cast<std::size_t>(&p - points_.data());
    double bound = std::numeric_limits<double>::infinity();
    if (last_closest_[point] >= 0) bound = projection(x, last_closest_[point], p.position).distance2;
    if (!(bound <= std::numeric_limits<double>::max()))  // NaN: that face has collapsed or is not finite
      bound = std::numeric_limits<double>::infinity();
    bound = bound * (1 + 1e-6) + 1e-24;  // margin for rounding: 1 pm, or 10⁻⁶ of the distance²
    // Faces that may lie within the bound: by r (faces sorted by their smaller r,
    // none longer in r than `widest`), then by their boxes, in face order.
    nearby.clear();
    const double reach = std::sqrt(bound) * (1 + 1e-12);
    auto first = std::lower_bound(by_r.begin(), by_r.end(), p.position.x() - reach - widest,
                                  [&](int m, double r) { return boxes[m].r0 < r; });
    for (auto it = first; it != by_r.end() && boxes[*it].r0 <= p.position.x() + reach; ++it) {
      const Box& box = boxes[*it];
      const double dr = std::max({0.0, box.r0 - p.position.x(), p.position.x() - box.r1});
      const double dz = std::max({0.0, box.z0 - p.position.y(), p.position.y() - box.z1});
      if (dr * dr + dz * dz <= bound) nearby.push_back(*it);
    }
    std::sort(nearby.begin(), nearby.end());
    // Equally close: within 10⁻⁹ of the distance², the rounding of two projections on
    // the same master node through its two faces (which differ in the last bits, and
    // by more with fused multiply-adds), so that face order and not rounding decides.
    double best = 1e300;
    int best_face = -1;
    double best_eta = 0, best_eta_raw = 0;
    for (const int m : nearby) {
      const Projection pr = projection(x, m, p.position);
      if (pr.distance2 < best * (1 - 1e-9) - 1e-30) {
        best = pr.distance2;
        best_face = static_cast<int>(m);
        best_eta = pr.eta;
        best_eta_raw = pr.eta_raw;
      }
    }
    last_closest_[point] = best_face;
    p.paired = false;
    p.master_face = -1;
    if (best_face < 0) continue;
    const auto& mf = master_faces_[best_face];
    auto node_normal = [&](int node) {
      const auto pos = std::lower_bound(master_nodes_.begin(), master_nodes_.end(), node) - master_nodes_.begin();
      return nodal_normals[pos];
    };
    double eta = best_eta;
    if (best_eta_raw < 0 || best_eta_raw > 1) {
      // Beyond a free end of the master surface: follow the end face's line for half
      // a face length (so that a point sliding off the end loses contact gradually,
      // not at a jump), unpaired further out.
      const int node = mf[best_eta_raw < 0 ? 0 : 1];
      const auto pos = std::lower_bound(master_nodes_.begin(), master_nodes_.end(), node) - master_nodes_.begin();
      if (master_faces_of_node_[pos].size() < 2) {
        if (best_eta_raw < -0.5 || best_eta_raw > 1.5) continue;
        eta = best_eta_raw;
      }
    }
    // Smoothed normal: the nodal normals (mean of the adjacent face normals)
    // interpolated along the face, so that the gap does not jump when a point
    // crosses a master node.
    // Face normal inside the face (perpendicular to it, so the gap does not change
    // when the point slides along the face); the nodal normal when the closest
    // point is a node between two faces (convex corner).
    Eigen::Vector2d normal = outward_normal(x[mf[0]], x[mf[1]]);
    p.node_normal = false;
    if (best_eta <= 0.0 || best_eta >= 1.0) {
      const int node = mf[best_eta <= 0.0 ? 0 : 1];
      normal = node_normal(node);
      // At a free end the nodal normal is the end face's own normal.
      const auto pos = std::lower_bound(master_nodes_.begin(), master_nodes_.end(), node) - master_nodes_.begin();
      p.node_normal = master_faces_of_node_[pos].size() > 1;
    }
    p.paired = true;
    p.master_face = best_face;
    p.master_nodes = mf;
    p.master_weights = {1 - eta, eta};
    p.normal = normal;
    p.tangent = Eigen::Vector2d(normal.y(), -normal.x());
    const fem::Point xm = (1 - eta) * x[mf[0]] + eta * x[mf[1]];
    p.gap = (p.position - xm).dot(normal);
    const auto& cand = candidates_[p.slave_face];
    if (std::find(cand.begin(), cand.end(), best_face) == cand.end()) within = false;
  }
  return within;
}

}  // namespace rsw::contact
