// HDF5 results files through the HDF5 C API; see hdf5_file.hpp for the layout.
//
// Every HDF5 identifier lives in a Handle that closes it; every call that can fail
// goes through check(), which turns a negative return into an Hdf5Error carrying the
// file name, the object path and the innermost message of HDF5's error stack.
#include "fem/hdf5_file.hpp"

#include <hdf5.h>

#include <algorithm>
#include <mutex>
#include <type_traits>
#include <utility>

namespace rsw::fem {

namespace {

static_assert(std::is_same_v<hid_t, std::int64_t>, "Hdf5File stores hid_t as std::int64_t");

// Owns one HDF5 identifier and closes it with the matching H5?close.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer close) : id_(id), close_(close) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, -1)), close_(o.close_) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, -1);
      close_ = o.close_;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t get() const { return id_; }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }

 private:
  hid_t id_ = -1;
  Closer close_ = nullptr;
};

#ifndef H5_HAVE_THREADSAFE
// A thread-safe HDF5 build serialises its API itself; otherwise this mutex does.
std::recursive_mutex& api_mutex() {
  static std::recursive_mutex m;
  return m;
}
#endif

// Held for the duration of every public operation: switches off HDF5's automatic
// error printing for the calling thread (the setting is per thread in thread-safe
// builds) and serialises the API when the library is not thread-safe.
class ApiScope {
 public:
  ApiScope() {
#ifndef H5_HAVE_THREADSAFE
    lock_ = std::unique_lock<std::recursive_mutex>(api_mutex());
#endif
    thread_local bool silenced = false;
    if (!silenced) {
      H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
      silenced = true;
    }
  }

 private:
  std::unique_lock<std::recursive_mutex> lock_;
};

herr_t innermost_error(unsigned n, const H5E_error2_t* err, void* data) {
  if (n == 0 && err && err->desc) *static_cast<std::string*>(data) = err->desc;
  return 0;
}

// The most specific message on the HDF5 error stack, which is then cleared.
std::string take_hdf5_message() {
  std::string msg;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost_error, &msg);
  H5Eclear2(H5E_DEFAULT);
  return msg;
}

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& object,
                       const std::string& what) {
  const std::string detail = take_hdf5_message();
  std::string msg = "HDF5 file '" + file.string() + "'";
  if (!object.empty()) msg += ", object '" + object + "'";
  msg += ": " + what;
  if (!detail.empty()) msg += " (HDF5: " + detail + ")";
  throw Hdf5Error(msg);
}

// Returns `status` unless it is negative (HDF5's failure convention), else throws.
template <typename T>
T check(T status, const std::filesystem::path& file, const std::string& object,
        const std::string& what) {
  if (status < 0) fail(file, object, what);
  return status;
}

std::string normalise(const std::string& path) {
  if (path.empty() || path.front() != '/') return "/" + path;
  return path;
}

herr_t collect_link_name(hid_t, const char* name, const H5L_info_t*, void* data) {
  static_cast<std::vector<std::string>*>(data)->emplace_back(name);
  return 0;
}

herr_t collect_attribute_name(hid_t, const char* name, const H5A_info_t*, void* data) {
  static_cast<std::vector<std::string>*>(data)->emplace_back(name);
  return 0;
}

herr_t reclaim_strings(hid_t type, hid_t space, void* buf) {
#if H5_VERSION_GE(1, 12, 0)
  return H5Treclaim(type, space, H5P_DEFAULT, buf);
#else
  return H5Dvlen_reclaim(type, space, H5P_DEFAULT, buf);
#endif
}

Handle variable_utf8_string_type() {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  return type;
}

// Reads a scalar string from a dataset or an attribute: `read` is H5Dread or H5Aread
// bound to the object, taking a memory type and a buffer. Handles both variable- and
// fixed-length strings (h5py and other tools write either).
template <typename Read>
std::string read_string_value(hid_t file_type, hid_t space, Read read,
                              const std::filesystem::path& file, const std::string& object) {
  if (H5Tget_class(file_type) != H5T_STRING) fail(file, object, "is not a string");
  if (H5Sget_simple_extent_npoints(space) != 1) fail(file, object, "holds more than one string");
  if (check(H5Tis_variable_str(file_type), file, object, "cannot inspect string type") > 0) {
    Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem.get(), H5T_VARIABLE);
    H5Tset_cset(mem.get(), H5Tget_cset(file_type));
    char* buf = nullptr;
    check(read(mem.get(), &buf), file, object, "cannot read string");
    std::string value = buf ? buf : "";
    reclaim_strings(mem.get(), space, &buf);
    return value;
  }
  const std::size_t size = H5Tget_size(file_type);
  std::string value(size, '\0');
  check(read(file_type, value.data()), file, object, "cannot read string");
  value.resize(std::min(value.find('\0'), size));
  if (H5Tget_strpad(file_type) == H5T_STR_SPACEPAD) {
    const auto last = value.find_last_not_of(' ');
    value.resize(last == std::string::npos ? 0 : last + 1);
  }
  return value;
}

}  // namespace

// --- file ------------------------------------------------------------------------

Hdf5File::Hdf5File(const std::filesystem::path& path, Hdf5Mode mode) : path_(path) {
  ApiScope scope;
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  // Closing the file closes every object still open in it, so the file is really
  // released (and can be reopened or renamed) once close() returns.
  H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_STRONG);
  const std::string name = path.string();
  const bool present = std::filesystem::exists(path);
  switch (mode) {
    case Hdf5Mode::truncate:
      file_id_ = H5Fcreate(name.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get());
      writable_ = true;
      break;
    case Hdf5Mode::read:
      if (!present) fail(path_, "", "cannot open for reading: no such file");
      file_id_ = H5Fopen(name.c_str(), H5F_ACC_RDONLY, fapl.get());
      break;
    case Hdf5Mode::append:
      file_id_ = present ? H5Fopen(name.c_str(), H5F_ACC_RDWR, fapl.get())
                         : H5Fcreate(name.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, fapl.get());
      writable_ = true;
      break;
  }
  check(file_id_, path_, "", writable_ ? "cannot open for writing" : "cannot open for reading");
}

Hdf5File::~Hdf5File() {
  if (file_id_ < 0) return;
  ApiScope scope;
  H5Fclose(file_id_);
  H5Eclear2(H5E_DEFAULT);
}

Hdf5File::Hdf5File(Hdf5File&& other) noexcept
    : path_(std::move(other.path_)),
      file_id_(std::exchange(other.file_id_, -1)),
      writable_(other.writable_) {}

Hdf5File& Hdf5File::operator=(Hdf5File&& other) noexcept {
  if (this != &other) {
    if (file_id_ >= 0) {
      ApiScope scope;
      H5Fclose(file_id_);
      H5Eclear2(H5E_DEFAULT);
    }
    path_ = std::move(other.path_);
    file_id_ = std::exchange(other.file_id_, -1);
    writable_ = other.writable_;
  }
  return *this;
}

std::int64_t Hdf5File::id() const {
  if (file_id_ < 0) throw Hdf5Error("HDF5 file '" + path_.string() + "': used after close()");
  return file_id_;
}

void Hdf5File::require_writable(const std::string& what, const std::string& path) const {
  if (!writable_)
    throw Hdf5Error("HDF5 file '" + path_.string() + "', object '" + path + "': cannot " + what +
                    ": file is open read-only");
}

void Hdf5File::flush() {
  ApiScope scope;
  check(H5Fflush(id(), H5F_SCOPE_LOCAL), path_, "", "cannot flush");
}

void Hdf5File::close() {
  if (file_id_ < 0) return;
  ApiScope scope;
  const hid_t file = std::exchange(file_id_, -1);
  check(H5Fclose(file), path_, "", "cannot close");
}

// --- groups and look-up ----------------------------------------------------------

void Hdf5File::create_group(const std::string& path) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("create group", p);
  if (exists(p)) {
    Handle obj(check(H5Oopen(id(), p.c_str(), H5P_DEFAULT), path_, p, "cannot open"), H5Oclose);
    if (H5Iget_type(obj.get()) != H5I_GROUP) fail(path_, p, "exists and is not a group");
    return;
  }
  Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  H5Pset_create_intermediate_group(lcpl.get(), 1);
  Handle group(H5Gcreate2(id(), p.c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  check(group.get(), path_, p, "cannot create group");
}

bool Hdf5File::exists(const std::string& path) const {
  ApiScope scope;
  const std::string p = normalise(path);
  std::string prefix;
  std::size_t start = 1;
  while (start <= p.size()) {
    std::size_t end = p.find('/', start);
    if (end == std::string::npos) end = p.size();
    if (end > start) {
      prefix += "/" + p.substr(start, end - start);
      // A negative answer means a parent is not a group: the path does not exist.
      if (H5Lexists(id(), prefix.c_str(), H5P_DEFAULT) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return false;
      }
    }
    start = end + 1;
  }
  if (prefix.empty()) return true;  // the root group
  const htri_t target = H5Oexists_by_name(id(), prefix.c_str(), H5P_DEFAULT);
  H5Eclear2(H5E_DEFAULT);
  return target > 0;
}

std::vector<std::string> Hdf5File::list(const std::string& group) const {
  ApiScope scope;
  const std::string p = normalise(group);
  Handle g(check(H5Gopen2(id(), p.c_str(), H5P_DEFAULT), path_, p, "cannot open group"), H5Gclose);
  std::vector<std::string> names;
  hsize_t index = 0;
  check(H5Literate(g.get(), H5_INDEX_NAME, H5_ITER_INC, &index, collect_link_name, &names), path_,
        p, "cannot list group members");
  return names;
}

std::vector<std::size_t> Hdf5File::shape(const std::string& path) const {
  ApiScope scope;
  const std::string p = normalise(path);
  Handle dset(check(H5Dopen2(id(), p.c_str(), H5P_DEFAULT), path_, p, "cannot open dataset"),
              H5Dclose);
  Handle space(H5Dget_space(dset.get()), H5Sclose);
  const int rank = check(H5Sget_simple_extent_ndims(space.get()), path_, p, "cannot read shape");
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return {dims.begin(), dims.end()};
}

// --- fixed-size datasets ---------------------------------------------------------

void Hdf5File::remove_if_exists(const std::string& path) {
  if (!exists(path)) return;
  Handle obj(check(H5Oopen(id(), path.c_str(), H5P_DEFAULT), path_, path, "cannot open"), H5Oclose);
  if (H5Iget_type(obj.get()) != H5I_DATASET) fail(path_, path, "exists and is not a dataset");
  obj.reset();
  check(H5Ldelete(id(), path.c_str(), H5P_DEFAULT), path_, path, "cannot replace dataset");
}

namespace {

// Creates (replacing) a dataset of the given shape and writes `data` into it.
void write_dataset(hid_t file, const std::filesystem::path& file_path, const std::string& path,
                   hid_t file_type, hid_t mem_type, const std::vector<hsize_t>& dims,
                   const void* data) {
  Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  H5Pset_create_intermediate_group(lcpl.get(), 1);
  Handle space(dims.empty() ? H5Screate(H5S_SCALAR)
                            : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
               H5Sclose);
  check(space.get(), file_path, path, "cannot create dataspace");
  Handle dset(
      H5Dcreate2(file, path.c_str(), file_type, space.get(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
      H5Dclose);
  check(dset.get(), file_path, path, "cannot create dataset");
  hsize_t n = 1;
  for (hsize_t d : dims) n *= d;
  if (n > 0)
    check(H5Dwrite(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), file_path, path,
          "cannot write dataset");
}

// Opens a dataset, checks its rank and returns (handle, dims).
std::pair<Handle, std::vector<hsize_t>> open_with_rank(hid_t file,
                                                       const std::filesystem::path& file_path,
                                                       const std::string& path, int rank) {
  Handle dset(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  check(dset.get(), file_path, path, "cannot open dataset");
  Handle space(H5Dget_space(dset.get()), H5Sclose);
  const int actual = H5Sget_simple_extent_ndims(space.get());
  if (actual != rank)
    fail(file_path, path,
         "expected a " + std::to_string(rank) + "-D dataset, found rank " + std::to_string(actual));
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return {std::move(dset), dims};
}

template <typename T>
std::vector<T> read_1d(hid_t file, const std::filesystem::path& file_path, const std::string& path,
                       hid_t mem_type) {
  auto [dset, dims] = open_with_rank(file, file_path, path, 1);
  std::vector<T> values(dims[0]);
  if (!values.empty())
    check(H5Dread(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), file_path,
          path, "cannot read dataset");
  return values;
}

}  // namespace

void Hdf5File::write(const std::string& path, const std::vector<double>& values) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("write dataset", p);
  remove_if_exists(p);
  write_dataset(id(), path_, p, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {values.size()}, values.data());
}

void Hdf5File::write(const std::string& path, const std::vector<int>& values) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("write dataset", p);
  remove_if_exists(p);
  write_dataset(id(), path_, p, H5T_STD_I32LE, H5T_NATIVE_INT, {values.size()}, values.data());
}

void Hdf5File::write(const std::string& path, const RowMajorMatrix& matrix) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("write dataset", p);
  if (matrix.values.size() != matrix.n_rows * matrix.n_cols)
    fail(path_, p,
         "matrix of " + std::to_string(matrix.n_rows) + " x " + std::to_string(matrix.n_cols) +
             " holds " + std::to_string(matrix.values.size()) + " values");
  remove_if_exists(p);
  write_dataset(id(), path_, p, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {matrix.n_rows, matrix.n_cols},
                matrix.values.data());
}

void Hdf5File::write_string(const std::string& path, const std::string& text) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("write dataset", p);
  remove_if_exists(p);
  Handle type = variable_utf8_string_type();
  const char* data = text.c_str();
  write_dataset(id(), path_, p, type.get(), type.get(), {}, &data);
}

void Hdf5File::write_scalar(const std::string& path, double value) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("write dataset", p);
  remove_if_exists(p);
  write_dataset(id(), path_, p, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {}, &value);
}

double Hdf5File::read_scalar(const std::string& path) const {
  ApiScope scope;
  const std::string p = normalise(path);
  auto [dset, dims] = open_with_rank(id(), path_, p, 0);
  double value = 0.0;
  check(H5Dread(dset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &value), path_, p,
        "cannot read dataset");
  return value;
}

std::vector<double> Hdf5File::read_doubles(const std::string& path) const {
  ApiScope scope;
  return read_1d<double>(id(), path_, normalise(path), H5T_NATIVE_DOUBLE);
}

std::vector<int> Hdf5File::read_ints(const std::string& path) const {
  ApiScope scope;
  return read_1d<int>(id(), path_, normalise(path), H5T_NATIVE_INT);
}

RowMajorMatrix Hdf5File::read_matrix(const std::string& path) const {
  ApiScope scope;
  const std::string p = normalise(path);
  auto [dset, dims] = open_with_rank(id(), path_, p, 2);
  RowMajorMatrix m;
  m.n_rows = dims[0];
  m.n_cols = dims[1];
  m.values.resize(m.n_rows * m.n_cols);
  if (!m.values.empty())
    check(H5Dread(dset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, m.values.data()),
          path_, p, "cannot read dataset");
  return m;
}

std::string Hdf5File::read_string(const std::string& path) const {
  ApiScope scope;
  const std::string p = normalise(path);
  Handle dset(check(H5Dopen2(id(), p.c_str(), H5P_DEFAULT), path_, p, "cannot open dataset"),
              H5Dclose);
  Handle type(H5Dget_type(dset.get()), H5Tclose);
  Handle space(H5Dget_space(dset.get()), H5Sclose);
  const hid_t d = dset.get();
  return read_string_value(
      type.get(), space.get(),
      [d](hid_t mem, void* buf) { return H5Dread(d, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf); },
      path_, p);
}

// --- appendable datasets ---------------------------------------------------------

void Hdf5File::create_appendable(const std::string& path, std::size_t n_cols,
                                 std::size_t chunk_rows) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("create dataset", p);
  if (exists(p)) fail(path_, p, "cannot create appendable dataset: the path exists already");
  if (chunk_rows == 0) fail(path_, p, "cannot create appendable dataset: chunk_rows is 0");
  const int rank = n_cols == 0 ? 1 : 2;
  const hsize_t dims[2] = {0, n_cols};
  const hsize_t max_dims[2] = {H5S_UNLIMITED, n_cols};
  const hsize_t chunk[2] = {chunk_rows, n_cols};
  Handle space(H5Screate_simple(rank, dims, max_dims), H5Sclose);
  check(space.get(), path_, p, "cannot create dataspace");
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  check(H5Pset_chunk(dcpl.get(), rank, chunk), path_, p, "cannot set chunk size");
  Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  H5Pset_create_intermediate_group(lcpl.get(), 1);
  Handle dset(
      H5Dcreate2(id(), p.c_str(), H5T_IEEE_F64LE, space.get(), lcpl.get(), dcpl.get(), H5P_DEFAULT),
      H5Dclose);
  check(dset.get(), path_, p, "cannot create appendable dataset");
}

void Hdf5File::append(const std::string& path, const std::vector<double>& row) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("append to dataset", p);
  Handle dset(check(H5Dopen2(id(), p.c_str(), H5P_DEFAULT), path_, p, "cannot open dataset"),
              H5Dclose);
  Handle space(H5Dget_space(dset.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank != 1 && rank != 2) fail(path_, p, "cannot append: dataset is neither 1-D nor 2-D");
  hsize_t dims[2] = {0, 1};
  hsize_t max_dims[2] = {0, 1};
  H5Sget_simple_extent_dims(space.get(), dims, max_dims);
  if (max_dims[0] != H5S_UNLIMITED)
    fail(path_, p, "cannot append: dataset was not created by create_appendable");
  const hsize_t n_cols = rank == 2 ? dims[1] : 1;
  if (rank == 2 && row.size() != n_cols)
    fail(path_, p,
         "cannot append a row of " + std::to_string(row.size()) + " values to a table of " +
             std::to_string(n_cols) + " columns");
  if (row.empty()) return;

  const hsize_t n_new = row.size() / n_cols;
  const hsize_t new_dims[2] = {dims[0] + n_new, n_cols};
  check(H5Dset_extent(dset.get(), new_dims), path_, p, "cannot extend dataset");
  Handle file_space(H5Dget_space(dset.get()), H5Sclose);
  const hsize_t start[2] = {dims[0], 0};
  const hsize_t count[2] = {n_new, n_cols};
  check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr),
        path_, p, "cannot select appended rows");
  Handle mem_space(H5Screate_simple(rank, count, nullptr), H5Sclose);
  check(H5Dwrite(dset.get(), H5T_NATIVE_DOUBLE, mem_space.get(), file_space.get(), H5P_DEFAULT,
                 row.data()),
        path_, p, "cannot write appended rows");
  check(H5Fflush(id(), H5F_SCOPE_LOCAL), path_, p, "cannot flush after append");
}

// --- attributes ------------------------------------------------------------------

namespace {

Handle open_object(hid_t file, const std::filesystem::path& file_path, const std::string& path) {
  Handle obj(H5Oopen(file, path.c_str(), H5P_DEFAULT), H5Oclose);
  check(obj.get(), file_path, path, "cannot open object");
  return obj;
}

// Writes a scalar attribute, replacing one of the same name.
void write_attribute(hid_t obj, const std::filesystem::path& file_path, const std::string& path,
                     const std::string& name, hid_t file_type, hid_t mem_type, const void* data) {
  const std::string where = path + "@" + name;
  if (check(H5Aexists(obj, name.c_str()), file_path, where, "cannot look up attribute") > 0)
    check(H5Adelete(obj, name.c_str()), file_path, where, "cannot replace attribute");
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(H5Acreate2(obj, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
              H5Aclose);
  check(attr.get(), file_path, where, "cannot create attribute");
  check(H5Awrite(attr.get(), mem_type, data), file_path, where, "cannot write attribute");
}

Handle open_attribute(hid_t obj, const std::filesystem::path& file_path, const std::string& path,
                      const std::string& name) {
  const std::string where = path + "@" + name;
  if (check(H5Aexists(obj, name.c_str()), file_path, where, "cannot look up attribute") == 0)
    fail(file_path, where, "no such attribute");
  Handle attr(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose);
  check(attr.get(), file_path, where, "cannot open attribute");
  return attr;
}

}  // namespace

void Hdf5File::set_attribute(const std::string& path, const std::string& name,
                             const std::string& value) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("set attribute", p + "@" + name);
  Handle obj = open_object(id(), path_, p);
  Handle type = variable_utf8_string_type();
  const char* data = value.c_str();
  write_attribute(obj.get(), path_, p, name, type.get(), type.get(), &data);
}

void Hdf5File::set_attribute(const std::string& path, const std::string& name, double value) {
  ApiScope scope;
  const std::string p = normalise(path);
  require_writable("set attribute", p + "@" + name);
  Handle obj = open_object(id(), path_, p);
  write_attribute(obj.get(), path_, p, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
}

bool Hdf5File::has_attribute(const std::string& path, const std::string& name) const {
  ApiScope scope;
  const std::string p = normalise(path);
  Handle obj = open_object(id(), path_, p);
  return check(H5Aexists(obj.get(), name.c_str()), path_, p + "@" + name,
               "cannot look up attribute") > 0;
}

std::string Hdf5File::string_attribute(const std::string& path, const std::string& name) const {
  ApiScope scope;
  const std::string p = normalise(path);
  Handle obj = open_object(id(), path_, p);
  Handle attr = open_attribute(obj.get(), path_, p, name);
  Handle type(H5Aget_type(attr.get()), H5Tclose);
  Handle space(H5Aget_space(attr.get()), H5Sclose);
  const hid_t a = attr.get();
  return read_string_value(
      type.get(), space.get(), [a](hid_t mem, void* buf) { return H5Aread(a, mem, buf); }, path_,
      p + "@" + name);
}

double Hdf5File::double_attribute(const std::string& path, const std::string& name) const {
  ApiScope scope;
  const std::string p = normalise(path);
  const std::string where = p + "@" + name;
  Handle obj = open_object(id(), path_, p);
  Handle attr = open_attribute(obj.get(), path_, p, name);
  Handle space(H5Aget_space(attr.get()), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != 1)
    fail(path_, where, "holds more than one value");
  Handle type(H5Aget_type(attr.get()), H5Tclose);
  const H5T_class_t type_class = H5Tget_class(type.get());
  if (type_class != H5T_FLOAT && type_class != H5T_INTEGER) fail(path_, where, "is not a number");
  double value = 0;
  check(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &value), path_, where, "cannot read attribute");
  return value;
}

std::vector<std::string> Hdf5File::attribute_names(const std::string& path) const {
  ApiScope scope;
  const std::string p = normalise(path);
  Handle obj = open_object(id(), path_, p);
  std::vector<std::string> names;
  hsize_t index = 0;
  check(H5Aiterate2(obj.get(), H5_INDEX_NAME, H5_ITER_INC, &index, collect_attribute_name, &names),
        path_, p, "cannot list attributes");
  return names;
}

}  // namespace rsw::fem
