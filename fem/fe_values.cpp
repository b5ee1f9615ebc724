// Q1 shape functions, Gauss rules, and cell/face quadrature values; see fe_values.hpp.
#include "fem/fe_values.hpp"

#include <Eigen/LU>

#include <cmath>
#include <stdexcept>
#include <string>

namespace rsw::fem {

namespace {
constexpr double xi_node[4] = {-1, 1, 1, -1};
constexpr double eta_node[4] = {-1, -1, 1, 1};
constexpr double two_pi = 2.0 * M_PI;
}  // namespace

GaussRule1d gauss_legendre(int n) {
  // Abscissae and weights from the roots of the Legendre polynomials
  // (Abramowitz & Stegun, Table 25.4).
  switch (n) {
    case 1: return {{0.0}, {2.0}};
    case 2: {
      const double a = 1.0 / std::sqrt(3.0);
      return {{-a, a}, {1.0, 1.0}};
    }
    case 3: {
      const double a = std::sqrt(0.6);
      return {{-a, 0.0, a}, {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0}};
    }
    case 4: {
      const double a = std::sqrt(3.0 / 7.0 - 2.0 / 7.0 * std::sqrt(1.2));
      const double b = std::sqrt(3.0 / 7.0 + 2.0 / 7.0 * std::sqrt(1.2));
      const double wa = (18.0 + std::sqrt(30.0)) / 36.0, wb = (18.0 - std::sqrt(30.0)) / 36.0;
      return {{-b, -a, a, b}, {wb, wa, wa, wb}};
    }
    case 5: {
      const double a = std::sqrt(5.0 - 2.0 * std::sqrt(10.0 / 7.0)) / 3.0;
      const double b = std::sqrt(5.0 + 2.0 * std::sqrt(10.0 / 7.0)) / 3.0;
      const double wa = (322.0 + 13.0 * std::sqrt(70.0)) / 900.0;
      const double wb = (322.0 - 13.0 * std::sqrt(70.0)) / 900.0;
      return {{-b, -a, 0.0, a, b}, {wb, wa, 128.0 / 225.0, wa, wb}};
    }
    default: throw std::invalid_argument("gauss_legendre: n = " + std::to_string(n) + ", allowed 1..5");
  }
}

std::array<double, 4> shape_values(double xi, double eta) {
  std::array<double, 4> N;
  for (int a = 0; a < 4; ++a) N[a] = 0.25 * (1 + xi_node[a] * xi) * (1 + eta_node[a] * eta);
  return N;
}

std::array<Eigen::Vector2d, 4> shape_gradients_ref(double xi, double eta) {
  std::array<Eigen::Vector2d, 4> g;
  for (int a = 0; a < 4; ++a)
    g[a] = {0.25 * xi_node[a] * (1 + eta_node[a] * eta), 0.25 * eta_node[a] * (1 + xi_node[a] * xi)};
  return g;
}

Point map_to_physical(const Mesh& mesh, int cell, double xi, double eta) {
  const auto N = shape_values(xi, eta);
  Point x = Point::Zero();
  for (int a = 0; a < 4; ++a) x += N[a] * mesh.nodes[mesh.cells[cell][a]];
  return x;
}

CellValues::CellValues(int n_gauss, CoordinateSystem coords) : coords_(coords) {
  const auto rule = gauss_legendre(n_gauss);
  for (int i = 0; i < n_gauss; ++i)
    for (int j = 0; j < n_gauss; ++j) {
      ref_points_.emplace_back(rule.points[i], rule.points[j]);
      ref_weights_.push_back(rule.weights[i] * rule.weights[j]);
    }
  for (const auto& p : ref_points_) {
    N_.push_back(shape_values(p.x(), p.y()));
    grad_ref_.push_back(shape_gradients_ref(p.x(), p.y()));
  }
  grad_.resize(n_q());
  x_.resize(n_q());
  JxW_.resize(n_q());
}

void CellValues::reinit(const Mesh& mesh, int cell) {
  const auto& c = mesh.cells[cell];
  for (int q = 0; q < n_q(); ++q) {
    Eigen::Matrix2d J = Eigen::Matrix2d::Zero();  // J_ij = ∂x_i/∂ξ_j
    Point x = Point::Zero();
    for (int a = 0; a < 4; ++a) {
      const Point& xa = mesh.nodes[c[a]];
      J += xa * grad_ref_[q][a].transpose();
      x += N_[q][a] * xa;
    }
    const double det = J.determinant();
    if (!(det > 0)) {
      Point centre = Point::Zero();
      for (int a = 0; a < 4; ++a) centre += 0.25 * mesh.nodes[c[a]];
      const std::string body =
          mesh.cell_body.empty() ? std::string("?") : mesh.body_names.at(mesh.cell_body[cell]);
      throw std::runtime_error("cell " + std::to_string(cell) + " of body " + body + " at (r, z) = (" +
                               std::to_string(centre.x() * 1e3) + ", " + std::to_string(centre.y() * 1e3) +
                               ") mm is inverted (Jacobian " + std::to_string(det) + " at a quadrature point)");
    }
    const Eigen::Matrix2d J_inv_T = J.inverse().transpose();
    for (int a = 0; a < 4; ++a) grad_[q][a] = J_inv_T * grad_ref_[q][a];
    x_[q] = x;
    const double measure = coords_ == CoordinateSystem::axisymmetric ? two_pi * x.x() : 1.0;
    JxW_[q] = ref_weights_[q] * det * measure;
  }
}

FaceValues::FaceValues(int n_gauss, CoordinateSystem coords) : coords_(coords), rule_(gauss_legendre(n_gauss)) {
  N_.resize(rule_.points.size());
  x_.resize(rule_.points.size());
  normal_.resize(rule_.points.size());
  JxW_.resize(rule_.points.size());
}

void FaceValues::reinit(const Mesh& mesh, int cell, int face) {
  const auto& c = mesh.cells[cell];
  const Point& xa = mesh.nodes[c[face]];
  const Point& xb = mesh.nodes[c[(face + 1) % 4]];
  const Point t = xb - xa;  // counter-clockwise tangent: the outward normal is (t_z, -t_r)
  const double length = t.norm();
  const Eigen::Vector2d n(t.y() / length, -t.x() / length);
  for (std::size_t q = 0; q < rule_.points.size(); ++q) {
    const double s = rule_.points[q];  // from node `face` (s = -1) to node `face + 1`
    const double xi_a = xi_node[face], eta_a = eta_node[face];
    const double xi_b = xi_node[(face + 1) % 4], eta_b = eta_node[(face + 1) % 4];
    const double xi = 0.5 * ((1 - s) * xi_a + (1 + s) * xi_b);
    const double eta = 0.5 * ((1 - s) * eta_a + (1 + s) * eta_b);
    N_[q] = shape_values(xi, eta);
    x_[q] = 0.5 * ((1 - s) * xa + (1 + s) * xb);
    normal_[q] = n;
    const double measure = coords_ == CoordinateSystem::axisymmetric ? two_pi * x_[q].x() : 1.0;
    JxW_[q] = rule_.weights[q] * 0.5 * length * measure;
  }
}

CellGeometry::CellGeometry(const Mesh& mesh, int n_gauss, CoordinateSystem coords)
    : current_(mesh), n_gauss_(n_gauss), n_q_(n_gauss * n_gauss), coords_(coords) {
  const std::size_t n_points = static_cast<std::size_t>(mesh.n_cells()) * n_q_;
  JxW_.assign(n_points, 0.0);
  grad_.assign(4 * n_points, Eigen::Vector2d::Zero());
  CellValues cv(n_gauss, coords);
  if (mesh.n_cells() > 0) cv.reinit(mesh, 0);
  for (int q = 0; q < n_q_; ++q) shape_.push_back({cv.N(q, 0), cv.N(q, 1), cv.N(q, 2), cv.N(q, 3)});
}

void CellGeometry::update(const std::vector<Point>& positions) {
  if (valid_ && positions == current_.nodes) return;
  current_.nodes = positions;
  CellValues cv(n_gauss_, coords_);
  for (int e = 0; e < current_.n_cells(); ++e) {
    cv.reinit(current_, e);
    for (int q = 0; q < n_q_; ++q) {
      const std::size_t k = static_cast<std::size_t>(e) * n_q_ + q;
      JxW_[k] = cv.JxW(q);
      for (int a = 0; a < 4; ++a) grad_[4 * k + a] = cv.grad_N(q, a);
    }
  }
  valid_ = true;
}

}  // namespace rsw::fem
