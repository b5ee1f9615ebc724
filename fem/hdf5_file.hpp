// The one wrapper around the HDF5 C API: results files readable by h5py and h5dump.
//
// An Hdf5File is an open HDF5 file. Objects are addressed by absolute paths
// ("/signals/t"); writing a dataset creates any missing parent groups. Datasets are
// stored as little-endian IEEE double (H5T_IEEE_F64LE) or 32-bit int (H5T_STD_I32LE),
// 1-D or 2-D (row-major, as h5py shows them); text is a scalar variable-length UTF-8
// string, the form h5py reads as `str`. Appendable datasets are chunked with an
// unlimited first dimension so that rows can be added as study runs finish.
//
// HDF5's automatic error printing is switched off; every failure throws Hdf5Error
// naming the file, the object path and the innermost HDF5 error message.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::fem {

class Hdf5Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Hdf5Mode {
  truncate,  // create the file, replacing an existing one; read-write
  read,      // open an existing file read-only
  append,    // open an existing file read-write, or create it if missing
};

// A 2-D table of doubles, row-major: value (i, j) is values[i * n_cols + j].
struct RowMajorMatrix {
  std::size_t n_rows = 0;
  std::size_t n_cols = 0;
  std::vector<double> values;

  double operator()(std::size_t i, std::size_t j) const { return values[i * n_cols + j]; }
};

class Hdf5File {
 public:
  Hdf5File(const std::filesystem::path& path, Hdf5Mode mode);
  ~Hdf5File();
  Hdf5File(Hdf5File&& other) noexcept;
  Hdf5File& operator=(Hdf5File&& other) noexcept;
  Hdf5File(const Hdf5File&) = delete;
  Hdf5File& operator=(const Hdf5File&) = delete;

  const std::filesystem::path& path() const { return path_; }

  // Writes buffered data to disk; the file stays open.
  void flush();
  // Closes the file, reporting errors the destructor would have to swallow.
  void close();

  // --- groups and look-up --------------------------------------------------------
  // Creates a group and any missing parents; does nothing if the group exists.
  void create_group(const std::string& path);
  // True if every link along `path` exists ("/" always exists).
  bool exists(const std::string& path) const;
  // Names of the members (groups and datasets) of a group, sorted by name.
  std::vector<std::string> list(const std::string& group = "/") const;
  // Dimensions of a dataset (empty for a scalar dataset).
  std::vector<std::size_t> shape(const std::string& path) const;

  // --- fixed-size datasets -------------------------------------------------------
  // Each write replaces an existing dataset of the same path.
  void write(const std::string& path, const std::vector<double>& values);
  void write(const std::string& path, const std::vector<int>& values);
  void write(const std::string& path, const RowMajorMatrix& matrix);
  void write_string(const std::string& path, const std::string& text);
  void write_scalar(const std::string& path, double value);  // a scalar dataspace (shape ())

  std::vector<double> read_doubles(const std::string& path) const;  // 1-D dataset
  double read_scalar(const std::string& path) const;                // scalar dataset
  std::vector<int> read_ints(const std::string& path) const;        // 1-D dataset
  RowMajorMatrix read_matrix(const std::string& path) const;        // 2-D dataset
  std::string read_string(const std::string& path) const;           // scalar string

  // --- appendable datasets -------------------------------------------------------
  // Creates an empty double dataset with an unlimited first dimension: 1-D when
  // n_cols == 0, else n_rows x n_cols with n_rows growing. Throws if `path` exists
  // (recreating it would drop the rows appended so far).
  void create_appendable(const std::string& path, std::size_t n_cols = 0,
                         std::size_t chunk_rows = 64);
  // Appends one row (n_cols values) to a 2-D appendable dataset, or any number of
  // values to a 1-D one, then flushes the file so a killed run keeps the row.
  void append(const std::string& path, const std::vector<double>& row);

  // --- attributes on a group or dataset ("/" is the root group) -----------------
  // Each set replaces an existing attribute of the same name.
  void set_attribute(const std::string& path, const std::string& name, const std::string& value);
  void set_attribute(const std::string& path, const std::string& name, double value);
  bool has_attribute(const std::string& path, const std::string& name) const;
  std::string string_attribute(const std::string& path, const std::string& name) const;
  double double_attribute(const std::string& path, const std::string& name) const;
  // Names of the attributes of an object, sorted by name.
  std::vector<std::string> attribute_names(const std::string& path) const;

 private:
  std::filesystem::path path_;
  std::int64_t file_id_ = -1;  // hid_t of the open file, -1 once closed
  bool writable_ = false;

  std::int64_t id() const;  // throws if the file was closed
  void require_writable(const std::string& what, const std::string& path) const;
  void remove_if_exists(const std::string& path);
};

}  // namespace rsw::fem
