// Bilinear (Q1) isoparametric quadrilateral: shape functions, Gauss quadrature and
// the integration weights of cells and faces in the axisymmetric (r, z) half-plane.
//
// Shape functions on the reference square [-1, 1]^2, nodes counter-clockwise from
// (-1, -1): N_a(ξ, η) = (1 + ξ_a ξ)(1 + η_a η) / 4. Physical gradients use the
// inverse Jacobian of x(ξ, η) = Σ N_a x_a.
//
// The axisymmetric measure lives here and nowhere else: a cell integral
// ∫_Ω f dV = ∫∫ f 2π r dr dz is evaluated as Σ_q f(x_q) JxW(q) with
// JxW(q) = w_q det J(q) · 2π r_q, and a face integral ∫_Γ g dA = ∫ g 2π r ds as
// Σ_q g(x_q) JxW(q) with JxW(q) = w_q |dx/ds| · 2π r_q. A planar (per unit depth)
// coordinate system drops the 2π r factor; it exists for verification problems
// posed in Cartesian coordinates.
#pragma once

#include "fem/mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace rsw::fem {

enum class CoordinateSystem { axisymmetric, planar };

// Gauss–Legendre points and weights on [-1, 1]; n = 1..5.
struct GaussRule1d {
  std::vector<double> points, weights;
};
GaussRule1d gauss_legendre(int n);

// Q1 shape functions and their reference derivatives at (ξ, η).
std::array<double, 4> shape_values(double xi, double eta);
std::array<Eigen::Vector2d, 4> shape_gradients_ref(double xi, double eta);

// Values at the quadrature points of one cell (n_gauss x n_gauss Gauss rule).
class CellValues {
 public:
  explicit CellValues(int n_gauss = 2, CoordinateSystem coords = CoordinateSystem::axisymmetric);
  // Throws std::runtime_error naming the cell if det J <= 0 at a quadrature point.
  void reinit(const Mesh& mesh, int cell);

  int n_q() const { return static_cast<int>(ref_points_.size()); }
  double JxW(int q) const { return JxW_[q]; }                       // m^3 (axisym) or m^2
  const Point& point(int q) const { return x_[q]; }                  // (r, z) in m
  double N(int q, int a) const { return N_[q][a]; }
  const Eigen::Vector2d& grad_N(int q, int a) const { return grad_[q][a]; }  // 1/m
  CoordinateSystem coordinates() const { return coords_; }

 private:
  CoordinateSystem coords_;
  std::vector<Eigen::Vector2d> ref_points_;
  std::vector<double> ref_weights_;
  std::vector<std::array<double, 4>> N_;
  std::vector<std::array<Eigen::Vector2d, 4>> grad_ref_, grad_;
  std::vector<Point> x_;
  std::vector<double> JxW_;
};

// The Gauss-point geometry of every cell of a mesh for given node positions (a
// deformed configuration): JxW and ∇N_a at each cell Gauss point, stored cell-major
// (index k = cell · n_q + q; gradients at 4k + a), and N_a at the reference points.
// update() recomputes them only when the positions differ from the last call's, so
// solves on one configuration (the coupling iterations of a time step) share them.
class CellGeometry {
 public:
  CellGeometry(const Mesh& mesh, int n_gauss, CoordinateSystem coords = CoordinateSystem::axisymmetric);
  void update(const std::vector<Point>& positions);

  int n_q() const { return n_q_; }
  const Mesh& current() const { return current_; }  // the mesh at the last positions
  const std::vector<double>& JxW() const { return JxW_; }
  const std::vector<Eigen::Vector2d>& grad() const { return grad_; }
  const std::vector<std::array<double, 4>>& shape() const { return shape_; }

 private:
  Mesh current_;
  int n_gauss_, n_q_;
  CoordinateSystem coords_;
  bool valid_ = false;
  std::vector<double> JxW_;
  std::vector<Eigen::Vector2d> grad_;
  std::vector<std::array<double, 4>> shape_;
};

// Values at the quadrature points of one face of a cell. Shape functions are those of
// the whole cell (the two nodes off the face have N = 0 there).
class FaceValues {
 public:
  explicit FaceValues(int n_gauss = 2, CoordinateSystem coords = CoordinateSystem::axisymmetric);
  void reinit(const Mesh& mesh, int cell, int face);

  int n_q() const { return static_cast<int>(JxW_.size()); }
  double JxW(int q) const { return JxW_[q]; }                 // m^2 (axisym) or m
  const Point& point(int q) const { return x_[q]; }
  const Eigen::Vector2d& normal(int q) const { return normal_[q]; }  // outward unit normal
  double N(int q, int a) const { return N_[q][a]; }

 private:
  CoordinateSystem coords_;
  GaussRule1d rule_;
  std::vector<std::array<double, 4>> N_;
  std::vector<Point> x_;
  std::vector<Eigen::Vector2d> normal_;
  std::vector<double> JxW_;
};

// Position in the cell at reference coordinates (ξ, η).
Point map_to_physical(const Mesh& mesh, int cell, double xi, double eta);

}  // namespace rsw::fem
