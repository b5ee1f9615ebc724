// VTK XML output of multi-body meshes (.vtm of .vtu/.vtp pieces, .pvd time series)
// and read-back; see vtk_output.hpp for the file layout.
//
// The pieces are written with VTK's XML writers (appended raw binary, LZ4
// compressed, 64-bit headers). The .vtm and .pvd index files are small XML documents
// written here directly, because VTK's own multiblock writer names pieces by index
// instead of by body. Each file goes to `<name>.tmp` first and is renamed into place.
#include "fem/vtk_output.hpp"

#include "fem/threads.hpp"

#include <omp.h>

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataSet.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkInformation.h>
#include <vtkIntArray.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSMPTools.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLMultiBlockDataReader.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <vtkXMLUtilities.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <set>
#include <stdexcept>

namespace rsw::fem {

namespace {

namespace fs = std::filesystem;

// Arrays the writer adds itself; user fields may not take these names.
const std::set<std::string> reserved_point_names = {"hanging", "node_id"};
const std::set<std::string> reserved_cell_names = {"body", "level", "scaled_jacobian", "cell_id"};
const std::set<std::string> reserved_face_names = {"boundary_id"};

// Collects the messages of VTK error events so that they become exceptions instead
// of text on the VTK output window.
class ErrorCollector : public vtkCommand {
 public:
  static ErrorCollector* New() { return new ErrorCollector; }
  void Execute(vtkObject*, unsigned long, void* call_data) override {
    if (call_data)
      messages += (messages.empty() ? "" : "; ") + std::string(static_cast<const char*>(call_data));
  }
  std::string messages;
};

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

template <typename Map>
std::string join_keys(const Map& map) {
  std::vector<std::string> names;
  for (const auto& [k, v] : map) names.push_back(k);
  return join(names);
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

// Text that reads back as the same double (17 significant digits, zeros trimmed).
std::string exact(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// A body name as a file name: characters other than letters, digits, '_', '-' and
// '.' become '_'.
std::string file_safe(const std::string& name) {
  std::string out = name.empty() ? std::string("body") : name;
  for (char& c : out)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) c = '_';
  return out;
}

fs::path temporary_name(const fs::path& target) { return fs::path(target.string() + ".tmp"); }

void move_into_place(const fs::path& temporary, const fs::path& target) {
  std::error_code ec;
  fs::rename(temporary, target, ec);
  if (ec) {
    fs::remove(temporary, ec);
    throw std::runtime_error("cannot move " + quoted(temporary) + " to " + quoted(target) + ": " +
                             ec.message());
  }
}

// Writes `text` to `target` through a temporary file.
void write_text_atomically(const fs::path& target, const std::string& text) {
  const fs::path tmp = temporary_name(target);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) throw std::runtime_error("cannot write " + quoted(tmp));
  }
  move_into_place(tmp, target);
}

// Writes one VTK dataset with a VTK XML writer through a temporary file. The writer
// fills a string first: writing the file directly, it makes a system call (write or
// lseek) per data block header and array, about 570 per file (150 000 per coarse
// weld), each several microseconds in a virtual machine.
// VTK's own loops (vtkSMPTools, in the writers) follow the process's thread count
// (fem/threads.hpp): one thread selects the sequential backend (Debian's default, TBB,
// asks the system for the processors on every loop and spins after it), n threads
// the build's default backend on n threads.
void follow_thread_count() {
  static int selected = 0;  // the thread count the backend was last set for
  const int n = parallel_regions_run_inline() ? 1 : omp_get_max_threads();
  if (n == selected) return;
  if (n == 1) {
    vtkSMPTools::SetBackend("Sequential");
  } else {
    vtkSMPTools::SetBackend(VTK_SMP_BACKEND);
    vtkSMPTools::Initialize(n);
  }
  selected = n;
}

template <typename Writer, typename Data>
void write_piece_atomically(const fs::path& target, Data* data) {
  follow_thread_count();
  vtkNew<Writer> writer;
  vtkNew<ErrorCollector> errors;
  writer->AddObserver(vtkCommand::ErrorEvent, errors);
  writer->SetInputData(data);
  writer->WriteToOutputStringOn();
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  // LZ4 (readable by ParaView 5.5 and later): the default weld's 33 field files take
  // 36 MB and 0.27 s to write, against 28 MB and 0.75 s with zlib at its fastest level
  // and 57 MB and 0.30 s uncompressed (one core, docs/PERFORMANCE.md).
  writer->SetCompressorTypeToLZ4();
  writer->SetCompressionLevel(1);
  writer->SetHeaderTypeToUInt64();
  if (writer->Write() != 1 || !errors->messages.empty())
    throw std::runtime_error("cannot write " + quoted(target) + ": " + errors->messages);
  write_text_atomically(target, writer->GetOutputString());
}

vtkSmartPointer<vtkIntArray> int_array(const char* name, vtkIdType n) {
  auto a = vtkSmartPointer<vtkIntArray>::New();
  a->SetName(name);
  a->SetNumberOfTuples(n);
  return a;
}

// A double array of n tuples: 1 component for scalars, 3 (r, z, 0) for vectors.
vtkSmartPointer<vtkDoubleArray> double_array(const std::string& name, int n_components,
                                             vtkIdType n) {
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(name.c_str());
  a->SetNumberOfComponents(n_components == 2 ? 3 : 1);
  a->SetNumberOfTuples(n);
  a->Fill(0.0);
  return a;
}

// Copies entity `from` of a field into tuple `to` of its VTK array.
void set_tuple(vtkDoubleArray* a, vtkIdType to, const Field& f, std::size_t from) {
  const double* v = f.values.data() + from * static_cast<std::size_t>(f.n_components);
  if (f.n_components == 2) {
    const double t[3] = {v[0], v[1], 0.0};
    a->SetTuple(to, t);
  } else {
    a->SetValue(to, v[0]);
  }
}

vtkSmartPointer<vtkStringArray> string_array(const char* name,
                                             const std::vector<std::string>& values) {
  auto a = vtkSmartPointer<vtkStringArray>::New();
  a->SetName(name);
  a->SetNumberOfValues(static_cast<vtkIdType>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i) a->SetValue(static_cast<vtkIdType>(i), values[i]);
  return a;
}

// "name [unit]" for each field of the lists that has a unit, each name once.
std::vector<std::string> unit_legend(std::initializer_list<const std::vector<Field>*> lists) {
  std::vector<std::string> legend;
  for (const auto* list : lists)
    for (const Field& f : *list) {
      if (f.unit.empty()) continue;
      const std::string entry = f.name + " [" + f.unit + "]";
      if (std::find(legend.begin(), legend.end(), entry) == legend.end()) legend.push_back(entry);
    }
  return legend;
}

// --- checks ------------------------------------------------------------------------

void check_mesh(const Mesh& mesh) {
  const auto n_cells = mesh.cells.size();
  if (mesh.cell_body.size() != n_cells || mesh.cell_level.size() != n_cells)
    throw std::invalid_argument("write_vtm: mesh has " + std::to_string(n_cells) + " cells but " +
                                std::to_string(mesh.cell_body.size()) + " cell_body and " +
                                std::to_string(mesh.cell_level.size()) + " cell_level entries");
  if (mesh.node_body.size() != mesh.nodes.size())
    throw std::invalid_argument("write_vtm: mesh has " + std::to_string(mesh.nodes.size()) +
                                " nodes but " + std::to_string(mesh.node_body.size()) +
                                " node_body entries");
  for (int b : mesh.node_body)
    if (b < 0 || b >= mesh.n_bodies())
      throw std::invalid_argument("write_vtm: node body index " + std::to_string(b) +
                                  " out of range (" + std::to_string(mesh.n_bodies()) + " bodies)");
  for (int c = 0; c < mesh.n_cells(); ++c) {
    const int b = mesh.cell_body[c];
    if (b < 0 || b >= mesh.n_bodies())
      throw std::invalid_argument("write_vtm: cell " + std::to_string(c) + " has body index " +
                                  std::to_string(b) + " out of range");
    for (int n : mesh.cells[c])
      if (n < 0 || n >= mesh.n_nodes() || mesh.node_body[n] != b)
        throw std::invalid_argument("write_vtm: cell " + std::to_string(c) + " of body '" +
                                    mesh.body_names[b] + "' uses node " + std::to_string(n) +
                                    " which is not a node of that body");
  }
  for (const auto& h : mesh.hanging_nodes)
    if (h.node < 0 || h.node >= mesh.n_nodes())
      throw std::invalid_argument("write_vtm: hanging node index " + std::to_string(h.node) +
                                  " out of range (" + std::to_string(mesh.n_nodes()) + " nodes)");
  for (const auto& [name, faces] : mesh.boundaries)
    for (const auto& f : faces)
      if (f.cell < 0 || f.cell >= mesh.n_cells() || f.face < 0 || f.face > 3)
        throw std::invalid_argument("write_vtm: boundary '" + name +
                                    "' has an invalid face (cell " + std::to_string(f.cell) +
                                    ", face " + std::to_string(f.face) + ")");
}

void check_field(const Field& f, const char* kind, std::size_t n_entities, const char* entity) {
  if (f.name.empty())
    throw std::invalid_argument(std::string("write_vtm: a ") + kind + " field has no name");
  if (f.n_components != 1 && f.n_components != 2)
    throw std::invalid_argument("write_vtm: field '" + f.name + "' has " +
                                std::to_string(f.n_components) + " components; 1 or 2 expected");
  const std::size_t expected = n_entities * static_cast<std::size_t>(f.n_components);
  if (f.values.size() != expected)
    throw std::invalid_argument("write_vtm: " + std::string(kind) + " field '" + f.name + "' has " +
                                std::to_string(f.values.size()) + " values, expected " +
                                std::to_string(expected) + " (" + std::to_string(f.n_components) +
                                " per " + entity + ")");
}

void check_names(const std::vector<Field>& fields, const std::set<std::string>& reserved,
                 const char* kind) {
  std::set<std::string> seen;
  for (const auto& f : fields) {
    if (reserved.count(f.name))
      throw std::invalid_argument("write_vtm: " + std::string(kind) + " field name '" + f.name +
                                  "' is reserved for an array the writer adds");
    if (!seen.insert(f.name).second)
      throw std::invalid_argument("write_vtm: " + std::string(kind) + " field '" + f.name +
                                  "' is given twice");
  }
}

void check_fields(const Mesh& mesh, const FieldSet& fields) {
  check_names(fields.point_fields, reserved_point_names, "point");
  check_names(fields.cell_fields, reserved_cell_names, "cell");
  for (const auto& f : fields.point_fields) check_field(f, "point", mesh.nodes.size(), "node");
  for (const auto& f : fields.cell_fields) check_field(f, "cell", mesh.cells.size(), "cell");
  std::map<std::string, int> face_components;
  std::set<std::pair<std::string, std::string>> seen;
  for (const auto& f : fields.face_fields) {
    if (reserved_face_names.count(f.name))
      throw std::invalid_argument("write_vtm: face field name '" + f.name +
                                  "' is reserved for an array the writer adds");
    if (!seen.insert({f.name, f.boundary}).second)
      throw std::invalid_argument("write_vtm: face field '" + f.name + "' is given twice on '" +
                                  f.boundary + "'");
    if (!mesh.boundaries.count(f.boundary))
      throw std::invalid_argument("write_vtm: face field '" + f.name +
                                  "' is on unknown boundary '" + f.boundary +
                                  "'; boundaries are: " + join_keys(mesh.boundaries));
    check_field(f, "face", mesh.boundaries.at(f.boundary).size(), "face");
    auto [it, inserted] = face_components.emplace(f.name, f.n_components);
    if (!inserted && it->second != f.n_components)
      throw std::invalid_argument("write_vtm: face field '" + f.name +
                                  "' is a scalar on one boundary and a vector on another");
  }
}

// --- building the pieces -----------------------------------------------------------

// Nodes and cells of one body.
struct BodyPart {
  std::vector<int> nodes;  // global indices, ascending
  std::vector<int> cells;  // global indices, ascending
};

std::vector<BodyPart> split_bodies(const Mesh& mesh) {
  std::vector<BodyPart> parts(mesh.body_names.size());
  for (int n = 0; n < mesh.n_nodes(); ++n) parts[mesh.node_body[n]].nodes.push_back(n);
  for (int c = 0; c < mesh.n_cells(); ++c) parts[mesh.cell_body[c]].cells.push_back(c);
  return parts;
}

vtkSmartPointer<vtkPoints> points_of(const Mesh& mesh, const std::vector<int>& nodes) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Point& x = mesh.nodes[nodes[i]];
    points->SetPoint(static_cast<vtkIdType>(i), x.x(), x.y(), 0.0);
  }
  return points;
}

// Point data shared by the .vtu and the .vtp of a body: node_id and user point fields.
void add_point_fields(vtkPointData* data, const std::vector<int>& nodes, const FieldSet& fields) {
  const auto n = static_cast<vtkIdType>(nodes.size());
  auto node_id = int_array("node_id", n);
  for (vtkIdType i = 0; i < n; ++i) node_id->SetValue(i, nodes[i]);
  data->AddArray(node_id);
  for (const auto& f : fields.point_fields) {
    auto a = double_array(f.name, f.n_components, n);
    for (vtkIdType i = 0; i < n; ++i) set_tuple(a, i, f, static_cast<std::size_t>(nodes[i]));
    data->AddArray(a);
  }
}

vtkSmartPointer<vtkUnstructuredGrid> body_grid(const Mesh& mesh, const BodyPart& part,
                                               const std::vector<int>& local,
                                               const std::vector<char>& is_hanging,
                                               const FieldSet& fields) {
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points_of(mesh, part.nodes));

  auto quads = vtkSmartPointer<vtkCellArray>::New();
  for (int c : part.cells) {
    vtkIdType ids[4];
    for (int k = 0; k < 4; ++k) ids[k] = local[mesh.cells[c][k]];
    quads->InsertNextCell(4, ids);
  }
  grid->SetCells(VTK_QUAD, quads);

  const auto n_points = static_cast<vtkIdType>(part.nodes.size());
  auto hanging = vtkSmartPointer<vtkUnsignedCharArray>::New();
  hanging->SetName("hanging");
  hanging->SetNumberOfTuples(n_points);
  for (vtkIdType i = 0; i < n_points; ++i) hanging->SetValue(i, is_hanging[part.nodes[i]] ? 1 : 0);
  grid->GetPointData()->AddArray(hanging);
  add_point_fields(grid->GetPointData(), part.nodes, fields);

  const auto n_cells = static_cast<vtkIdType>(part.cells.size());
  auto body = int_array("body", n_cells);
  auto level = int_array("level", n_cells);
  auto cell_id = int_array("cell_id", n_cells);
  auto jacobian = double_array("scaled_jacobian", 1, n_cells);
  for (vtkIdType i = 0; i < n_cells; ++i) {
    const int c = part.cells[i];
    body->SetValue(i, mesh.cell_body[c]);
    level->SetValue(i, mesh.cell_level[c]);
    cell_id->SetValue(i, c);
    jacobian->SetValue(i, scaled_jacobian(mesh, c));
  }
  vtkCellData* cell_data = grid->GetCellData();
  cell_data->AddArray(body);
  cell_data->AddArray(level);
  cell_data->AddArray(jacobian);
  cell_data->AddArray(cell_id);
  for (const auto& f : fields.cell_fields) {
    auto a = double_array(f.name, f.n_components, n_cells);
    for (vtkIdType i = 0; i < n_cells; ++i)
      set_tuple(a, i, f, static_cast<std::size_t>(part.cells[i]));
    cell_data->AddArray(a);
  }
  grid->GetFieldData()->AddArray(string_array("body_names", mesh.body_names));
  grid->GetFieldData()->AddArray(string_array("units", unit_legend({&fields.point_fields, &fields.cell_fields})));
  return grid;
}

vtkSmartPointer<vtkPolyData> body_boundaries(const Mesh& mesh, int body,
                                             const std::vector<std::string>& boundary_names,
                                             const FieldSet& fields) {
  // One line per (boundary, face) whose cell lies in this body.
  struct Line {
    int boundary_id;
    int face_index;  // position in mesh.boundary(name)
    std::array<int, 2> nodes;
  };
  std::vector<Line> lines;
  std::vector<int> nodes;
  for (int b = 0; b < static_cast<int>(boundary_names.size()); ++b) {
    const auto& faces = mesh.boundaries.at(boundary_names[b]);
    for (int j = 0; j < static_cast<int>(faces.size()); ++j) {
      if (mesh.cell_body[faces[j].cell] != body) continue;
      const auto ends = mesh.face_nodes(faces[j]);
      lines.push_back({b, j, ends});
      nodes.push_back(ends[0]);
      nodes.push_back(ends[1]);
    }
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  auto local = [&nodes](int n) {
    return static_cast<vtkIdType>(std::lower_bound(nodes.begin(), nodes.end(), n) - nodes.begin());
  };

  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points_of(mesh, nodes));
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  for (const auto& l : lines) {
    const vtkIdType ids[2] = {local(l.nodes[0]), local(l.nodes[1])};
    cells->InsertNextCell(2, ids);
  }
  poly->SetLines(cells);
  add_point_fields(poly->GetPointData(), nodes, fields);

  const auto n_lines = static_cast<vtkIdType>(lines.size());
  auto boundary_id = int_array("boundary_id", n_lines);
  for (vtkIdType i = 0; i < n_lines; ++i) boundary_id->SetValue(i, lines[i].boundary_id);
  poly->GetCellData()->AddArray(boundary_id);

  // Face fields: one array per name; faces the field does not cover stay NaN.
  std::map<std::string, vtkSmartPointer<vtkDoubleArray>> face_arrays;
  for (const auto& f : fields.face_fields) {
    auto& a = face_arrays[f.name];
    if (!a) {
      a = double_array(f.name, f.n_components, n_lines);
      a->Fill(std::numeric_limits<double>::quiet_NaN());
      poly->GetCellData()->AddArray(a);
    }
    const int b =
        static_cast<int>(std::find(boundary_names.begin(), boundary_names.end(), f.boundary) -
                         boundary_names.begin());
    for (vtkIdType i = 0; i < n_lines; ++i)
      if (lines[i].boundary_id == b)
        set_tuple(a, i, f, static_cast<std::size_t>(lines[i].face_index));
  }
  poly->GetFieldData()->AddArray(string_array("boundary_names", boundary_names));
  poly->GetFieldData()->AddArray(string_array("units", unit_legend({&fields.point_fields, &fields.face_fields})));
  return poly;
}

}  // namespace

// --- FieldSet ----------------------------------------------------------------------

namespace {
Field make_field(const std::string& name, int n_components, std::vector<double> values,
                 const std::string& boundary = {}, const std::string& unit = {}) {
  Field f;
  f.name = name;
  f.n_components = n_components;
  f.values = std::move(values);
  f.boundary = boundary;
  f.unit = unit;
  return f;
}

void add_unique(std::vector<Field>& fields, Field f, const std::set<std::string>& reserved,
                const char* kind) {
  if (reserved.count(f.name))
    throw std::invalid_argument("FieldSet: " + std::string(kind) + " field name '" + f.name +
                                "' is reserved for an array the writer adds");
  for (const auto& g : fields)
    if (g.name == f.name && g.boundary == f.boundary)
      throw std::invalid_argument("FieldSet: " + std::string(kind) + " field '" + f.name + "'" +
                                  (f.boundary.empty() ? "" : " on '" + f.boundary + "'") +
                                  " is given twice");
  fields.push_back(std::move(f));
}
}  // namespace

FieldSet& FieldSet::add_point_scalar(const std::string& name, std::vector<double> values, const std::string& unit) {
  add_unique(point_fields, make_field(name, 1, std::move(values), "", unit), reserved_point_names, "point");
  return *this;
}

FieldSet& FieldSet::add_point_vector(const std::string& name, std::vector<double> values, const std::string& unit) {
  add_unique(point_fields, make_field(name, 2, std::move(values), "", unit), reserved_point_names, "point");
  return *this;
}

FieldSet& FieldSet::add_cell_scalar(const std::string& name, std::vector<double> values, const std::string& unit) {
  add_unique(cell_fields, make_field(name, 1, std::move(values), "", unit), reserved_cell_names, "cell");
  return *this;
}

FieldSet& FieldSet::add_cell_vector(const std::string& name, std::vector<double> values, const std::string& unit) {
  add_unique(cell_fields, make_field(name, 2, std::move(values), "", unit), reserved_cell_names, "cell");
  return *this;
}

FieldSet& FieldSet::add_face_scalar(const std::string& name, const std::string& boundary,
                                    std::vector<double> values, const std::string& unit) {
  add_unique(face_fields, make_field(name, 1, std::move(values), boundary, unit), reserved_face_names,
             "face");
  return *this;
}

FieldSet& FieldSet::add_face_vector(const std::string& name, const std::string& boundary,
                                    std::vector<double> values, const std::string& unit) {
  add_unique(face_fields, make_field(name, 2, std::move(values), boundary, unit), reserved_face_names,
             "face");
  return *this;
}

// --- writing -----------------------------------------------------------------------

void write_vtm(const std::filesystem::path& vtm_path, const Mesh& mesh, const FieldSet& fields) {
  if (vtm_path.extension() != ".vtm")
    throw std::invalid_argument("write_vtm: " + quoted(vtm_path) + " does not end in .vtm");
  check_mesh(mesh);
  check_fields(mesh, fields);

  std::vector<std::string> file_names;
  for (const auto& name : mesh.body_names) {
    const std::string safe = file_safe(name);
    if (std::find(file_names.begin(), file_names.end(), safe) != file_names.end())
      throw std::invalid_argument("write_vtm: bodies '" + join(mesh.body_names) +
                                  "' clash as file names ('" + safe + "')");
    file_names.push_back(safe);
  }

  const fs::path folder_name = vtm_path.stem();
  const fs::path folder = vtm_path.parent_path() / folder_name;
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw std::runtime_error("cannot create folder " + quoted(folder) + ": " + ec.message());
  // An index that still lists pieces being replaced would look valid while they change.
  fs::remove(vtm_path, ec);

  std::vector<char> is_hanging(mesh.nodes.size(), 0);
  for (const auto& h : mesh.hanging_nodes) is_hanging[h.node] = 1;
  std::vector<std::string> boundary_names;
  for (const auto& [name, faces] : mesh.boundaries) boundary_names.push_back(name);

  const auto parts = split_bodies(mesh);
  std::vector<int> local(mesh.nodes.size(), -1);
  std::string index;
  int block = 0;
  for (int b = 0; b < mesh.n_bodies(); ++b) {
    for (std::size_t i = 0; i < parts[b].nodes.size(); ++i)
      local[parts[b].nodes[i]] = static_cast<int>(i);

    const fs::path vtu = folder_name / (file_names[b] + ".vtu");
    auto grid = body_grid(mesh, parts[b], local, is_hanging, fields);
    write_piece_atomically<vtkXMLUnstructuredGridWriter>(vtm_path.parent_path() / vtu, grid.Get());

    const fs::path vtp = folder_name / (file_names[b] + "_boundaries.vtp");
    auto poly = body_boundaries(mesh, b, boundary_names, fields);
    write_piece_atomically<vtkXMLPolyDataWriter>(vtm_path.parent_path() / vtp, poly.Get());

    index += "    <DataSet index=\"" + std::to_string(block++) + "\" name=\"" +
             xml_escape(mesh.body_names[b]) + "\" file=\"" + xml_escape(vtu.generic_string()) +
             "\"/>\n";
    index += "    <DataSet index=\"" + std::to_string(block++) + "\" name=\"" +
             xml_escape(mesh.body_names[b] + "_boundaries") + "\" file=\"" +
             xml_escape(vtp.generic_string()) + "\"/>\n";
  }

  write_text_atomically(vtm_path,
                        "<?xml version=\"1.0\"?>\n"
                        "<VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\" "
                        "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                        "  <vtkMultiBlockDataSet>\n" +
                            index +
                            "  </vtkMultiBlockDataSet>\n"
                            "</VTKFile>\n");
}

// --- time series -------------------------------------------------------------------

VtkTimeSeries::VtkTimeSeries(std::filesystem::path pvd_path) : pvd_path_(std::move(pvd_path)) {
  if (pvd_path_.extension() != ".pvd")
    throw std::invalid_argument("VtkTimeSeries: " + quoted(pvd_path_) + " does not end in .pvd");
  if (pvd_path_.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(pvd_path_.parent_path(), ec);
    if (ec)
      throw std::runtime_error("cannot create folder " + quoted(pvd_path_.parent_path()) + ": " +
                               ec.message());
  }
  write_pvd();
}

std::filesystem::path VtkTimeSeries::write_step(double time, const Mesh& mesh,
                                                const FieldSet& fields) {
  if (!std::isfinite(time))
    throw std::invalid_argument("VtkTimeSeries: step time " + exact(time) + " is not finite");
  if (!steps_.empty() && !(time > steps_.back().time))
    throw std::invalid_argument("VtkTimeSeries: step time " + exact(time) +
                                " does not follow the previous step time " +
                                exact(steps_.back().time));
  char number[16];
  std::snprintf(number, sizeof number, "_%04d.vtm", n_steps());
  const fs::path vtm = pvd_path_.parent_path() / (pvd_path_.stem().string() + number);
  write_vtm(vtm, mesh, fields);
  steps_.push_back({time, vtm});
  write_pvd();
  return vtm;
}

void VtkTimeSeries::write_pvd() const {
  std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const auto& s : steps_)
    text += "    <DataSet timestep=\"" + exact(s.time) + "\" group=\"\" part=\"0\" file=\"" +
            xml_escape(s.file.filename().generic_string()) + "\"/>\n";
  text += "  </Collection>\n</VTKFile>\n";
  write_text_atomically(pvd_path_, text);
}

// --- reading -----------------------------------------------------------------------

namespace {

std::map<std::string, VtkArray> numeric_arrays(vtkFieldData* data) {
  std::map<std::string, VtkArray> out;
  for (int k = 0; k < data->GetNumberOfArrays(); ++k) {
    vtkDataArray* a = data->GetArray(k);
    if (!a || !a->GetName()) continue;
    VtkArray v;
    v.n_components = a->GetNumberOfComponents();
    v.values.reserve(static_cast<std::size_t>(a->GetNumberOfTuples() * v.n_components));
    for (vtkIdType i = 0; i < a->GetNumberOfTuples(); ++i)
      for (int c = 0; c < v.n_components; ++c) v.values.push_back(a->GetComponent(i, c));
    out[a->GetName()] = std::move(v);
  }
  return out;
}

template <typename Map>
const typename Map::mapped_type& find_named(const Map& map, const std::string& name,
                                            const std::string& what) {
  auto it = map.find(name);
  if (it == map.end())
    throw std::out_of_range("no " + what + " '" + name + "'; known: " + join_keys(map));
  return it->second;
}

}  // namespace

const VtkArray& VtkBlock::point_array(const std::string& array_name) const {
  return find_named(point_data, array_name, "point array in block '" + name + "' named");
}

const VtkArray& VtkBlock::cell_array(const std::string& array_name) const {
  return find_named(cell_data, array_name, "cell array in block '" + name + "' named");
}

const std::vector<std::string>& VtkBlock::strings(const std::string& array_name) const {
  return find_named(field_strings, array_name, "string array in block '" + name + "' named");
}

const VtkBlock& VtmData::block(const std::string& name) const {
  for (const auto& b : blocks)
    if (b.name == name) return b;
  std::vector<std::string> names;
  for (const auto& b : blocks) names.push_back(b.name);
  throw std::out_of_range("no block '" + name + "'; blocks are: " + join(names));
}

VtmData read_vtm(const std::filesystem::path& vtm_path) {
  if (!fs::is_regular_file(vtm_path))
    throw std::runtime_error("cannot read " + quoted(vtm_path) + ": no such file");
  vtkNew<vtkXMLMultiBlockDataReader> reader;
  vtkNew<ErrorCollector> errors;
  reader->AddObserver(vtkCommand::ErrorEvent, errors);
  reader->SetFileName(vtm_path.string().c_str());
  reader->Update();
  auto* multiblock = vtkMultiBlockDataSet::SafeDownCast(reader->GetOutputDataObject(0));
  if (!errors->messages.empty() || !multiblock)
    throw std::runtime_error("cannot read " + quoted(vtm_path) + ": " + errors->messages);

  VtmData data;
  for (unsigned i = 0; i < multiblock->GetNumberOfBlocks(); ++i) {
    VtkBlock block;
    if (multiblock->HasMetaData(i) && multiblock->GetMetaData(i)->Has(vtkCompositeDataSet::NAME()))
      block.name = multiblock->GetMetaData(i)->Get(vtkCompositeDataSet::NAME());
    auto* dataset = vtkDataSet::SafeDownCast(multiblock->GetBlock(i));
    if (!dataset)
      throw std::runtime_error("cannot read " + quoted(vtm_path) + ": block " + std::to_string(i) +
                               " ('" + block.name + "') is missing or not a dataset");
    block.n_points = static_cast<int>(dataset->GetNumberOfPoints());
    block.n_cells = static_cast<int>(dataset->GetNumberOfCells());
    for (vtkIdType p = 0; p < dataset->GetNumberOfPoints(); ++p) {
      std::array<double, 3> x{};
      dataset->GetPoint(p, x.data());
      block.points.push_back(x);
    }
    vtkNew<vtkIdList> ids;
    for (vtkIdType c = 0; c < dataset->GetNumberOfCells(); ++c) {
      dataset->GetCellPoints(c, ids);
      std::vector<int> cell;
      for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
        cell.push_back(static_cast<int>(ids->GetId(k)));
      block.cells.push_back(std::move(cell));
    }
    block.point_data = numeric_arrays(dataset->GetPointData());
    block.cell_data = numeric_arrays(dataset->GetCellData());
    vtkFieldData* field = dataset->GetFieldData();
    for (int k = 0; k < field->GetNumberOfArrays(); ++k) {
      auto* s = vtkStringArray::SafeDownCast(field->GetAbstractArray(k));
      if (!s || !s->GetName()) continue;
      auto& values = block.field_strings[s->GetName()];
      for (vtkIdType j = 0; j < s->GetNumberOfValues(); ++j) values.push_back(s->GetValue(j));
    }
    data.blocks.push_back(std::move(block));
  }
  return data;
}

std::vector<VtkTimeSeries::Step> read_pvd(const std::filesystem::path& pvd_path) {
  if (!fs::is_regular_file(pvd_path))
    throw std::runtime_error("cannot read " + quoted(pvd_path) + ": no such file");
  vtkSmartPointer<vtkXMLDataElement> root;
  root.TakeReference(vtkXMLUtilities::ReadElementFromFile(pvd_path.string().c_str()));
  const char* type = root ? root->GetAttribute("type") : nullptr;
  if (!root || std::string(root->GetName()) != "VTKFile" || !type ||
      std::string(type) != "Collection")
    throw std::runtime_error("cannot read " + quoted(pvd_path) +
                             ": not a VTK collection (.pvd) file");
  vtkXMLDataElement* collection = root->FindNestedElementWithName("Collection");
  if (!collection)
    throw std::runtime_error("cannot read " + quoted(pvd_path) + ": no <Collection> element");

  std::vector<VtkTimeSeries::Step> steps;
  for (int k = 0; k < collection->GetNumberOfNestedElements(); ++k) {
    vtkXMLDataElement* e = collection->GetNestedElement(k);
    if (std::string(e->GetName()) != "DataSet") continue;
    const char* time = e->GetAttribute("timestep");
    const char* file = e->GetAttribute("file");
    if (!time || !file)
      throw std::runtime_error("cannot read " + quoted(pvd_path) + ": DataSet " +
                               std::to_string(k) + " lacks a timestep or file attribute");
    steps.push_back({std::strtod(time, nullptr), pvd_path.parent_path() / file});
  }
  return steps;
}

}  // namespace rsw::fem
