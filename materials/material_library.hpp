// Material data files and the library that finds them by name.
//
// A material is one YAML file, <name>.yaml, read through the project's config loader
// (fem/config.hpp) against material_file_schema(): every key is declared with its
// unit, range and doc, numbers carry units ("0.25 uohm*m", "210 GPa", "1470 degC")
// and are converted to SI (temperatures in degC), and every error names the file,
// line and column, the key, the offending value and what is allowed. Beyond the
// per-key checks, load_material_file() requires every property to be given (tables
// at least one row, each with a non-empty source) and checks the relations between
// keys: liquidus above solidus, flow-curve temperatures increasing, yield stress
// non-decreasing along each curve. The format is described in
// materials/data/README.md; material_file_schema().to_markdown() is its key
// reference.
//
// MaterialLibrary searches a list of directories in order for <name>.yaml. The
// default list is the user directories set by the program (the `rsw` program takes
// them from the environment variable RSW_MATERIALS_PATH, separated by ':'; the
// library reads no environment), followed by the shipped data directory: the source
// tree's materials/data (compile definition RSW_MATERIALS_DIR) unless the program names
// another (set_shipped_directory: an installed rsw's <prefix>/share/rsw/materials, the
// CMake package's rsw_MATERIALS_DIR), so a user directory can add grades or shadow the
// shipped ones.
#pragma once

#include "fem/config.hpp"
#include "materials/material.hpp"

#include <string>
#include <vector>

namespace rsw::materials {

// A material name that no directory of the search path holds.
class MaterialNotFound : public fem::ConfigError {
 public:
  using fem::ConfigError::ConfigError;
};

// The declared keys of a material data file.
fem::ConfigSchema material_file_schema();

// "a:b::c" → {"a", "b", "c"}: a ':'-separated directory list, empty entries dropped.
std::vector<std::string> split_path_list(const std::string& text);

// Reads and checks one material file. Throws fem::ConfigError.
Material load_material_file(const std::string& path);

class MaterialLibrary {
 public:
  // Searches default_directories().
  MaterialLibrary();
  explicit MaterialLibrary(std::vector<std::string> directories);

  // The user directories (set_user_directories), then the shipped materials/data.
  static std::vector<std::string> default_directories();
  // Directories searched before the shipped data by every default-constructed
  // library of this process.
  static void set_user_directories(std::vector<std::string> directories);
  // The shipped data directory of every default-constructed library of this process.
  static void set_shipped_directory(std::string directory);

  const std::vector<std::string>& directories() const { return directories_; }
  // Names of the materials found (file stems of *.yaml), sorted, each once.
  std::vector<std::string> available() const;
  // Path of <name>.yaml in the first directory holding it; throws MaterialNotFound
  // naming the material, the directories searched and the available names.
  std::string find(const std::string& name) const;
  // find() and load_material_file(); the file's `name` key must equal `name`.
  Material load(const std::string& name) const;

 private:
  std::vector<std::string> directories_;
};

}  // namespace rsw::materials
