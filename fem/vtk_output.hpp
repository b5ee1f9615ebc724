// The one wrapper around VTK: multi-body meshes and fields written for ParaView,
// and read back for tests.
//
// write_vtm() writes a VTK XML multiblock file `<stem>.vtm` whose pieces live in the
// sibling folder `<stem>/`. For every body, in mesh order, there are two blocks:
//   `<body>`             `<stem>/<body>.vtu`, unstructured grid of the body's quads;
//                        point data: `hanging` (0/1), `node_id` (global node index),
//                        the user point fields; cell data: `body` (index into
//                        body_names), `level` (quadtree level), `scaled_jacobian`,
//                        `cell_id` (global cell index), the user cell fields; field
//                        data: the string array `body_names`.
//   `<body>_boundaries`  `<stem>/<body>_boundaries.vtp`, poly data with one line cell
//                        per face of every named boundary on the body (a face on two
//                        boundaries appears twice); cell data: `boundary_id` and the
//                        user face fields (NaN on faces the field does not cover);
//                        point data: `node_id` and the user point fields; field data:
//                        the string array `boundary_names`, boundary_id -> "body.name",
//                        the same for every body.
// Points are (r, z, 0) in metres. Vector fields are given as (r, z) pairs and written
// as 3-component vectors (r, z, 0) so that ParaView can glyph and warp by them.
//
// VtkTimeSeries writes one such multiblock file per output time, `<stem>_NNNN.vtm`,
// and rewrites the collection file `<stem>.pvd` (time value -> step file) after each
// step. Every file is written under a temporary name and renamed into place, so a
// killed run leaves only complete files and a .pvd listing the steps written so far.
#pragma once

#include "fem/mesh.hpp"

#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace rsw::fem {

// One named field: n_components values per entity, interleaved (vector fields are
// (r, z) pairs). The entities are the mesh nodes (point fields), the mesh cells (cell
// fields) or the faces of one named boundary in the order of Mesh::boundary()
// (face fields, e.g. contact pressure on "sheet_1.top").
struct Field {
  std::string name;
  int n_components = 1;        // 1 (scalar) or 2 (vector (r, z))
  std::vector<double> values;  // n_components per entity
  std::string boundary;        // face fields only: the boundary the faces belong to
  std::string unit;            // e.g. "degC", "Pa"; "" if none is given
};

// The fields written with a mesh. Each block's field data holds a string array
// "units" with "name [unit]" for every field of the block given a unit. Names are unique within point fields and within
// cell fields and may not shadow the arrays the writer adds itself; face fields of
// one name may be given on several boundaries (one array per name in the output).
// Sizes are checked against the mesh when written.
struct FieldSet {
  std::vector<Field> point_fields;
  std::vector<Field> cell_fields;
  std::vector<Field> face_fields;

  FieldSet& add_point_scalar(const std::string& name, std::vector<double> values, const std::string& unit = "");
  FieldSet& add_point_vector(const std::string& name, std::vector<double> values, const std::string& unit = "");
  FieldSet& add_cell_scalar(const std::string& name, std::vector<double> values, const std::string& unit = "");
  FieldSet& add_cell_vector(const std::string& name, std::vector<double> values, const std::string& unit = "");
  FieldSet& add_face_scalar(const std::string& name, const std::string& boundary,
                            std::vector<double> values, const std::string& unit = "");
  FieldSet& add_face_vector(const std::string& name, const std::string& boundary,
                            std::vector<double> values, const std::string& unit = "");
};

// Writes `mesh` and `fields` as the multiblock file `vtm_path` (extension .vtm) with
// its pieces in the folder next to it named after its stem. Creates missing parent
// folders. Throws std::invalid_argument for an inconsistent mesh or field and
// std::runtime_error (naming the file) when a file cannot be written.
void write_vtm(const std::filesystem::path& vtm_path, const Mesh& mesh,
               const FieldSet& fields = {});

// A time series of multiblock files listed in a .pvd collection.
class VtkTimeSeries {
 public:
  struct Step {
    double time = 0;             // s
    std::filesystem::path file;  // the step's .vtm file (the .pvd folder joined with its name)
  };

  // Steps go next to `pvd_path` as `<stem>_NNNN.vtm`. Writes an empty collection at
  // once, replacing a .pvd left by an earlier run.
  explicit VtkTimeSeries(std::filesystem::path pvd_path);

  // Writes the next step at `time` (strictly greater than the previous one), then
  // rewrites the .pvd. Returns the path of the step's .vtm file.
  std::filesystem::path write_step(double time, const Mesh& mesh, const FieldSet& fields = {});

  const std::filesystem::path& pvd_path() const { return pvd_path_; }
  const std::vector<Step>& steps() const { return steps_; }
  int n_steps() const { return static_cast<int>(steps_.size()); }

 private:
  std::filesystem::path pvd_path_;
  std::vector<Step> steps_;

  void write_pvd() const;
};

// --- reading back (tests, post-processing checks) ----------------------------------

// A numeric VTK array: value (tuple i, component c) is values[i * n_components + c].
struct VtkArray {
  int n_components = 1;
  std::vector<double> values;

  int n_tuples() const {
    return n_components > 0 ? static_cast<int>(values.size()) / n_components : 0;
  }
  double at(int i, int c = 0) const {
    return values[static_cast<std::size_t>(i) * n_components + c];
  }
};

// One leaf block of a multiblock file.
struct VtkBlock {
  std::string name;
  int n_points = 0;
  int n_cells = 0;
  std::vector<std::array<double, 3>> points;
  std::vector<std::vector<int>> cells;  // point indices of each cell
  std::map<std::string, VtkArray> point_data;
  std::map<std::string, VtkArray> cell_data;
  std::map<std::string, std::vector<std::string>> field_strings;  // string field-data arrays

  // Named arrays; throw std::out_of_range naming the block and the known arrays.
  const VtkArray& point_array(const std::string& array_name) const;
  const VtkArray& cell_array(const std::string& array_name) const;
  const std::vector<std::string>& strings(const std::string& array_name) const;
};

struct VtmData {
  std::vector<VtkBlock> blocks;  // in file order

  // Block by name; throws std::out_of_range naming the known blocks.
  const VtkBlock& block(const std::string& name) const;
};

// Reads a multiblock file through vtkXMLMultiBlockDataReader. Throws
// std::runtime_error naming the file (and block) if it or a piece cannot be read.
VtmData read_vtm(const std::filesystem::path& vtm_path);

// The steps listed in a .pvd collection, in file order; `file` is resolved against the
// .pvd folder. Throws std::runtime_error naming the file if it is not a collection.
std::vector<VtkTimeSeries::Step> read_pvd(const std::filesystem::path& pvd_path);

}  // namespace rsw::fem
