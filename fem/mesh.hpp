// Unstructured mesh of bilinear quadrilaterals in the axisymmetric (r, z) half-plane,
// possibly made of several bodies that share no nodes.
//
// Coordinates are metres, r >= 0 (r is the radial coordinate, z the axial one).
// Cells list their four nodes counter-clockwise in the (r, z) plane; local face f
// joins local nodes f and (f + 1) % 4. A hanging node lies on the midpoint of a
// coarser neighbour's edge; its value is the mean of the two edge end nodes (the
// constraint is applied by fem::Constraints, never by the mesh itself).
// Boundaries and interfaces are named ("sheet_1.top", "es_upper"), never numbered.
#pragma once

#include <Eigen/Core>

#include <array>
#include <map>
#include <string>
#include <vector>

namespace rsw::fem {

using Point = Eigen::Vector2d;  // (r, z) in m

// Local face f of a quadrilateral joins local nodes f and (f + 1) % 4.
struct BoundaryFace {
  int cell = -1;
  int face = -1;
};

// Node `node` lies on the midpoint of the edge (parents[0], parents[1]) of a coarser
// cell: u(node) = (u(parents[0]) + u(parents[1])) / 2 for every field.
struct HangingNode {
  int node = -1;
  std::array<int, 2> parents{-1, -1};
};

// Two named boundaries that may touch: `first` and `second` are boundary names.
// `kind` is a label the mesh builder sets to say which interface law applies there
// (meshes/weld_mesh.hpp); fem gives it no meaning.
struct InterfacePair {
  std::string first;
  std::string second;
  std::string kind;
};

struct Mesh {
  std::vector<Point> nodes;
  std::vector<std::array<int, 4>> cells;
  std::vector<int> cell_body;   // index into body_names
  std::vector<int> cell_level;  // quadtree refinement level (0 = base cell)
  std::vector<int> node_body;   // bodies share no nodes
  std::vector<std::string> body_names;
  std::vector<HangingNode> hanging_nodes;
  std::map<std::string, std::vector<BoundaryFace>> boundaries;  // "body.name" -> faces
  std::map<std::string, InterfacePair> interfaces;

  int n_nodes() const { return static_cast<int>(nodes.size()); }
  int n_cells() const { return static_cast<int>(cells.size()); }
  int n_bodies() const { return static_cast<int>(body_names.size()); }

  // Index of a body by name; throws std::out_of_range naming the known bodies.
  int body_index(const std::string& name) const;
  // Faces of a named boundary; throws std::out_of_range naming the known boundaries.
  const std::vector<BoundaryFace>& boundary(const std::string& name) const;
  // The two end nodes of a boundary face, in the cell's counter-clockwise order.
  std::array<int, 2> face_nodes(const BoundaryFace& f) const;
  // Sorted unique nodes of a named boundary.
  std::vector<int> boundary_nodes(const std::string& name) const;

  // Appends another mesh as further bodies (node, cell and body indices shifted).
  // Body names must not clash.
  void append(const Mesh& other);
};

// Quality and size figures of a mesh (or of one body of it).
struct MeshStats {
  int n_cells = 0;
  int n_nodes = 0;
  int n_hanging = 0;
  double min_edge = 0;         // m
  double max_edge = 0;         // m
  double min_scaled_jacobian = 0;  // 1 for a rectangle, <= 0 for an inverted corner
  double min_angle_deg = 0;    // smallest interior angle over all cells
  double max_angle_deg = 0;    // largest interior angle over all cells
};

// Scaled Jacobian of a cell: the minimum over its corners of
// cross(e_next, e_prev) / (|e_next| |e_prev|), i.e. the sine of the corner angle.
double scaled_jacobian(const Mesh& mesh, int cell);
// The same for a cell whose nodes sit at `positions` (e.g. a deformed configuration;
// one entry per mesh node). A value ≤ 0 means a folded corner: the bilinear map is no
// longer one-to-one, even where its quadrature-point Jacobians stay positive.
double scaled_jacobian(const std::vector<Point>& positions, const std::array<int, 4>& cell);

// Statistics over the cells of one body (body >= 0) or of the whole mesh (body < 0).
MeshStats mesh_stats(const Mesh& mesh, int body = -1);

}  // namespace rsw::fem
