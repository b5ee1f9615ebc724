// Meshes of a spot-weld stack-up: one quadtree mesh per body (upper electrode, each
// sheet top to bottom, lower electrode), merged into one fem::Mesh whose bodies share
// no nodes, with named boundaries and named contact interfaces.
//
// Each body is a quadtree on a grid of base cells mapped onto the body:
// - A sheet is a rectangle [0, sheet_radius] x [z_bottom, z_top]; its radial grid
//   has lines at the electrode face radii so that the initial contact zone of the
//   sheet and of the electrode face share their radial node positions.
// - An electrode is the region between its face profile z_low(ρ) (dome, then flank)
//   and its end face, minus the cooling bore. The grid lives in (ρ, ζ), ζ the axial
//   distance from the face apex, and is mapped by
//       ζ' = z_low(ρ) + ζ (1 - z_low(ρ)/ζ_b)   for ζ <= ζ_b,   ζ' = ζ above,
//   with ζ_b the bore bottom (or the electrode length without a bore). Nodes on
//   ζ = 0 land exactly on the dome and the cone; ρ = cap radius is the cylindrical
//   side; the bore walls are grid lines. The map is smooth in the geometry, so the
//   mesh moves continuously when a dimension changes (no staircase snapping).
// Grid spacing: every segment between breakpoints (axis, face radius, bore radius,
// cap radius; face, bore bottom, end) is divided into round(length / base_size)
// equal cells, so the spacing is the base size up to the rounding of each segment.
// Refinement: a cell is split while its physical bounding box overlaps a refinement
// box of higher level; each body is then 2:1 balanced.
//
// Names: bodies "upper_electrode", "sheet_1".."sheet_n", "lower_electrode";
// electrode boundaries "axis", "contact_face" (the dome and the flank's first
// millimetre, radially, beyond the face edge), "flank" (the rest of it), "side",
// "end_face", "cooling_bore"; sheet boundaries "axis", "top", "bottom", "edge";
// interfaces "es_upper" (upper_electrode.contact_face, sheet_1.top),
// "ss_1_2", "ss_2_3" (sheet_k.bottom, sheet_k+1.top), "es_lower"
// (lower_electrode.contact_face, sheet_n.bottom). The first surface of a pair is the
// slave side of contact (its quadrature points are projected onto the second), so
// both electrode interfaces are discretised alike and a symmetric stack stays
// symmetric. Each interface carries its kind (fem::InterfacePair::kind, below), which
// selects its interface law; the names are for outputs only. The mesh depends on
// geometry and mesh settings only, never on model parameters.
#pragma once

#include "fem/mesh.hpp"
#include "meshes/weld_geometry.hpp"

#include <vector>

namespace rsw::meshes {

// The kinds of interface of a weld mesh (fem::InterfacePair::kind): es_upper and
// es_lower are electrode/sheet, ss_k_k+1 sheet/sheet. Each is also the name of the
// weld case's section of that interface's parameters (contact.electrode_sheet,
// contact.sheet_sheet; physics/interface_model.hpp).
namespace interface_kind {
inline constexpr char electrode_sheet[] = "electrode_sheet";
inline constexpr char sheet_sheet[] = "sheet_sheet";
}  // namespace interface_kind

// Axial distance of the electrode surface from the face apex at radius r
// (0 <= r <= cap radius): dome sagitta, then the cone flank.
double electrode_profile(const ElectrodeGeometry& g, double r);

// Exact volume of the electrode (dome, flank, cylinder, minus the bore), m^3.
double electrode_volume(const ElectrodeGeometry& g);

// Throws std::invalid_argument naming the offending dimension if the electrode
// cannot be meshed (face wider than the cap, flank reaching the bore bottom, ...).
void check_electrode(const ElectrodeGeometry& g, const char* which);

// The weld-zone refinement box and the extra boxes, in stack coordinates.
std::vector<RefinementBox> refinement_boxes(const StackGeometry& stack, const MeshSettings& settings);

// One electrode: apex at (0, z_apex), body extending towards +z (direction = +1,
// upper) or -z (direction = -1, lower).
fem::Mesh electrode_mesh(const ElectrodeGeometry& g, const std::string& body, double z_apex, int direction,
                         const MeshSettings& settings, const std::vector<RefinementBox>& boxes);

// One sheet occupying z in [z_bottom, z_top]; `radial_breaks` are extra radii at
// which the radial grid must have lines.
fem::Mesh sheet_mesh(const Sheet& sheet, double sheet_radius, double z_bottom, double z_top,
                     const std::vector<double>& radial_breaks, const MeshSettings& settings,
                     const std::vector<RefinementBox>& boxes);

// The whole stack-up: bodies, boundaries and interfaces as described above.
fem::Mesh weld_mesh(const StackGeometry& stack, const MeshSettings& settings);

// Where the stack is symmetric about its mid-plane z = 0 (two sheets of equal
// thickness and material, the two electrodes of equal geometry and material), the
// body that mirrors each body of its weld mesh: the electrodes each other, the sheets
// each other; else empty. Three sheets never qualify: the interface laws take the
// upper sheet of a sheet/sheet pair as the slave side, so the mirror of one of their
// two interfaces is not the other (slave and master swap), and on the coarse mesh the
// penetrations of a 1 + 1.5 + 1 mm stack's outer sheets differ by 1.4 %. Whether the
// mesh follows (refinement boxes) is fem::find_mirror_symmetry's to check.
std::vector<int> mirror_bodies(const StackGeometry& stack, const fem::Mesh& mesh);

}  // namespace rsw::meshes
