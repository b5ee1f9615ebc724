// Mirror symmetry of a mesh about the plane z = 0, and the reduced problem that solves
// for the upper half only.
//
// A problem whose mesh, coefficients, loads and boundary conditions are unchanged by the
// reflection z → −z has a solution with that symmetry: a scalar field with
// f(r, −z) = s f(r, z), s = +1 for a symmetric one (temperature) and s = −1 for an
// antisymmetric one (the potential of a current that crosses the plane, taken as 0
// there), and a displacement with u_r(r, −z) = u_r(r, z), u_z(r, −z) = −u_z(r, z)
// (signs {+1, −1}). Unknowns on the lower half are then images of those on the upper
// half, x_image = s x_source, and the reduced system has half the unknowns.
//
// Nodes: each body is mirrored by a body (body_mirror[b]). All nodes of the lower body
// of a pair are images of the node of the upper body at the reflected position; a body
// that is its own mirror (the middle sheet of three) is split by the plane: its nodes
// below are images, its nodes on the plane their own images (where s = −1 the field is
// zero there), its nodes above sources.
//
// Terms: the reduced system is the Galerkin projection P^T R(P y) onto symmetric fields
// (x = P y by fem::Constraints). Every term of the full residual (a cell, a boundary
// face, a coupling group such as a contact face) has a mirror term, and P^T adds a
// term and its mirror onto the same source rows with equal values at a symmetric
// state. So each pair is assembled once (fem::Assembler::set_mirror): a term on source
// nodes (and plane nodes) only with weight 1, on image nodes (and plane nodes) only
// with weight 0 (not assembled), and a term that couples both (an interface across the
// plane, a cell the plane cuts) or lies in the plane with weight 1/2, since its mirror
// is another such term or itself. The reduced residual is then the full residual's
// rows of the source nodes (half of them for plane nodes), its zero the full problem's
// symmetric solution, its Jacobian consistent: Newton's method converges as on the
// full mesh. What a term keeps as state (plasticity at the Gauss points of an image
// cell) is not updated: report it from the source (cell_source below).
//
// The symmetry of the mesh is checked node by node and cell by cell; that of the
// coefficients, loads and boundary conditions is the caller's to ensure.
#pragma once

#include "fem/constraints.hpp"
#include "fem/dof_map.hpp"
#include "fem/mesh.hpp"

#include <vector>

namespace rsw::fem {

struct MirrorSymmetry {
  // Per node: the source node it is the image of (itself on the plane); -1 for a source.
  std::vector<int> image_of;
  // Per cell: the source cell whose mirror it is, for a cell on image nodes; -1 otherwise.
  std::vector<int> cell_source;

  bool empty() const { return image_of.empty(); }
  bool is_image(int node) const { return !empty() && image_of[node] >= 0 && image_of[node] != node; }
  bool on_plane(int node) const { return !empty() && image_of[node] == node; }
  int n_images() const;
  // Weight of a term over these nodes (see above): 1, 1/2 or 0; 1 without a symmetry.
  // A face's weight is its cell's (fem::Assembler).
  double weight(const std::vector<int>& nodes) const;
};

// The mirror symmetry of `mesh` about z = 0 with body b mirrored by body_mirror[b]
// (an involution: body_mirror[body_mirror[b]] == b), positions compared to within
// `tolerance` (m). Empty where any node, hanging node or cell has no mirror image.
MirrorSymmetry find_mirror_symmetry(const Mesh& mesh, const std::vector<int>& body_mirror, double tolerance);

// True where the nodes `images` are exactly the images of the nodes `sources` (both
// sorted, as Mesh::boundary_nodes gives them): a boundary condition on the lower half
// that the mirror replaces must be the image of one on the upper half.
bool are_images(const MirrorSymmetry& mirror, const std::vector<int>& images, const std::vector<int>& sources);

// x_image = sign[k] x_source for every component k of every image node that is not a
// hanging node (hanging nodes follow their parents), and x = 0 for a component with
// sign −1 on a plane node. Call before any other constraint of those dofs: a boundary
// condition on image nodes (a grounded lower end face) must give way to the symmetry.
void add_mirror_constraints(Constraints& constraints, const Mesh& mesh, const DofMap& dofs,
                            const MirrorSymmetry& mirror, const std::vector<double>& sign);

}  // namespace rsw::fem
