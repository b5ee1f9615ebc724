// Pairing of the two surfaces of a named interface: every Gauss point of the slave
// surface (the pair's first boundary) is projected onto the master surface (the
// second), giving the gap, the master normal and the interpolation weights on both
// sides. All interface laws use these points: mechanical contact pressure and
// friction, electrical contact conductance, thermal contact conductance, interface
// Joule heat — one pairing, one set of points ("Gauss-point-to-segment").
//
// Geometry, current configuration x = X + u:
//   x_s = Σ_a N_a(ξ_q) x_a over the two slave face nodes (ξ_q a Gauss point),
//   x_m = (1 - η) x_1 + η x_2 the closest point on a master face (η ∈ [0, 1]),
//   n   = the outward normal of the master face (perpendicular to it, so the gap's
//         derivative along the face vanishes and the contact tangent is exact);
//         where the closest point is a node between two faces, the nodal normal (the
//         normalised mean of the two face normals),
//   g   = (x_s - x_m) · n   (> 0 open, < 0 penetrating), t = n rotated by -90°.
// Beyond a free end of the master surface the end face's line is followed for half
// a face length (x_m extrapolated), so a point sliding off the end loses contact
// gradually; further out the point is unpaired.
// Area weight: w_q |x_2 - x_1|/2 · 2π r_q of the slave face in the current
// configuration (the axisymmetric measure, as in fem::FaceValues).
//
// The master faces a slave face may meet are fixed when the pairing is built (all
// master faces whose radial extent comes within `search_margin` of the slave face),
// so the coupling pattern of the assembled systems never changes; a projection that
// leaves its candidates is reported by `update`.
#pragma once

#include "fem/mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace rsw::contact {

struct ContactPoint {
  int slave_face = -1;                 // index into the slave boundary's face list
  std::array<int, 2> slave_nodes{};    // mesh nodes
  std::array<double, 2> slave_weights{};
  double area = 0;                     // m^2, the point's share of the slave surface
  double reference_area = 0;           // m^2, the same in the undeformed mesh
  fem::Point position;                 // current slave point, m
  fem::Point reference_position;       // the same point in the undeformed mesh, m
  bool paired = false;
  int master_face = -1;                // index into the master boundary's face list
  std::array<int, 2> master_nodes{};
  std::array<double, 2> master_weights{};
  Eigen::Vector2d normal = Eigen::Vector2d::Zero();   // master outward normal
  Eigen::Vector2d tangent = Eigen::Vector2d::Zero();  // (n_z, -n_r)
  double gap = 0;                      // m
  bool node_normal = false;            // n is the nodal normal of a master node between two faces
};

class InterfacePairing {
 public:
  // `mirrored`: the interface's second boundary is the slave and its first the master
  // (the second pass of a two-pass contact treatment; physics/mechanics).
  InterfacePairing(const fem::Mesh& mesh, const std::string& name, int n_gauss = 2,
                   double search_margin = 0.5e-3, bool mirrored = false);

  const std::string& name() const { return name_; }
  const std::string& slave_boundary() const { return slave_; }
  const std::string& master_boundary() const { return master_; }

  // Re-projects every slave point for the current node positions. Returns false if
  // some point's closest master face is not among its candidates (the pattern built
  // from coupling_nodes() would then miss that coupling).
  bool update(const std::vector<fem::Point>& positions);

  const std::vector<ContactPoint>& points() const { return points_; }
  // Points of slave face f: points_[f * n_gauss + k].
  int n_gauss() const { return n_gauss_; }
  int n_slave_faces() const { return static_cast<int>(candidates_.size()); }
  // Mesh nodes that slave face f can couple: its two nodes, then the nodes of its
  // candidate master faces (sorted, unique, slave nodes first).
  const std::vector<int>& coupling_nodes(int slave_face) const { return coupling_nodes_[slave_face]; }
  // Local index of a mesh node within coupling_nodes(slave_face); -1 if absent.
  int local_index(int slave_face, int node) const;

 private:
  // The closest point of master face `face` to `point`: the parameter along the face
  // (raw, and clamped to the face) and the squared distance.
  struct Projection {
    double eta_raw = 0, eta = 0, distance2 = 0;
  };
  struct Box {
    double r0, r1, z0, z1;
  };
  Projection projection(const std::vector<fem::Point>& x, int face, const fem::Point& point) const;

  const fem::Mesh& mesh_;
  std::string name_, slave_, master_;
  int n_gauss_;
  std::vector<std::array<int, 2>> slave_faces_, master_faces_;  // node pairs, CCW in their cells
  std::vector<std::vector<int>> candidates_;                    // master faces per slave face
  std::vector<std::vector<int>> coupling_nodes_;
  std::vector<std::vector<int>> master_faces_of_node_;          // indexed by position in master_nodes_
  std::vector<int> master_nodes_;                               // sorted mesh nodes of the master side
  std::vector<ContactPoint> points_;
  std::vector<int> last_closest_;  // per point, the closest master face of the last update (-1: none)
};

}  // namespace rsw::contact
