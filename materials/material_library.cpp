// Material file schema, loading with cross-key checks, and lookup by name over a
// directory search path (see material_library.hpp).
#include "materials/material_library.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <utility>

#ifndef RSW_MATERIALS_DIR
#error "RSW_MATERIALS_DIR must name the shipped data directory (materials/CMakeLists.txt)"
#endif

namespace rsw::materials {
namespace {

namespace fs = std::filesystem;

// A temperature table of one property: section key, value column and where it goes.
struct TableProperty {
  const char* key;
  const char* column;
  const char* unit;
  const char* display_unit;
  fem::Range range;
  const char* doc;
  PropertyTable MaterialData::*member;
};

const std::vector<TableProperty>& table_properties() {
  static const std::vector<TableProperty> properties = {
      {"electrical_resistivity", "resistivity", "ohm*m", "uohm*m",
       fem::Range::open_closed(0, 100), "Electrical resistivity rho_e(T).",
       &MaterialData::electrical_resistivity},
      {"thermal_conductivity", "conductivity", "W/(m*K)", "W/(m*K)",
       fem::Range::open_closed(0, 2000),
       "Thermal conductivity k(T) of the solid (the melt value lambda_m is a model parameter).",
       &MaterialData::thermal_conductivity},
      {"specific_heat", "specific_heat", "J/(kg*K)", "J/(kg*K)",
       fem::Range::open_closed(0, 1e5),
       "Specific heat c_p(T), sensible heat only (latent heat of fusion is melting.latent_heat).",
       &MaterialData::specific_heat},
      {"density", "density", "kg/m^3", "kg/m^3", fem::Range::open_closed(0, 3e4),
       "Mass density rho(T); one row means a constant.", &MaterialData::density},
      {"youngs_modulus", "youngs_modulus", "Pa", "GPa", fem::Range::open_closed(0, 1000),
       "Young's modulus E(T).", &MaterialData::youngs_modulus},
      {"poisson_ratio", "poisson_ratio", "1", "1", fem::Range::closed_open(0, 0.5),
       "Poisson ratio nu(T).", &MaterialData::poisson_ratio},
      {"thermal_expansion", "secant_coefficient", "K^-1", "K^-1",
       fem::Range::closed(-1e-4, 1e-4),
       "Secant (mean) linear expansion coefficient alpha(T) from 20 degC: "
       "eps_th = alpha(T) (T - 20 degC).",
       &MaterialData::secant_expansion},
      {"flow_viscosity", "viscosity", "Pa*s", "MPa*s", fem::Range::closed(0, 1e4),
       "Viscosity eta(T) of plastic flow: above yield the equivalent stress is "
       "sigma_y + eta d(eps_bar_p)/dt (Perzyna overstress, exponent 1); 0 = rate-independent.",
       &MaterialData::flow_viscosity},
  };
  return properties;
}

const fem::Range temperature_range = fem::Range::closed(-273.15, 4000);

void declare_provenance(fem::ConfigSchema& schema, const std::string& section) {
  schema.string(section + ".source")
      .default_value("")
      .doc("Required: where the data come from (author, year, title or standard).");
  schema.string(section + ".note")
      .default_value("")
      .doc("How the data were derived, and whether they are generic rather than grade data.");
}

[[noreturn]] void missing(const std::string& file, const std::string& key,
                          const fem::ConfigSchema& schema) {
  const fem::KeySpec* spec = schema.find(key);
  std::string doc;
  if (spec == nullptr) {
    // A list item key: look the declaration up without the index.
    std::string schema_path;
    for (std::size_t i = 0; i < key.size(); ++i) {
      schema_path += key[i];
      if (key[i] == '[') {
        while (i + 1 < key.size() && key[i + 1] != ']') ++i;
      }
    }
    spec = schema.find(schema_path);
  }
  if (spec != nullptr) doc = " (" + spec->doc + ")";
  throw fem::ConfigError(file + ": " + key + ": missing; every material file must give it" +
                         doc);
}

void require_given(const fem::Config& config, const std::string& file, const std::string& key) {
  if (config.is_default(key)) missing(file, key, config.schema());
}

void require_source(const fem::Config& config, const std::string& file,
                    const std::string& section) {
  const std::string key = section + ".source";
  if (config.text(key).find_first_not_of(" \t\r\n") == std::string::npos) {
    if (config.is_default(key)) missing(file, key, config.schema());
    config.fail(key, "must name the source of the data (author, year, title or standard)");
  }
}

const fem::ConfigTable& required_table(const fem::Config& config, const std::string& file,
                                       const std::string& key) {
  const fem::ConfigTable& table = config.table(key);
  if (table.n_rows() == 0) {
    if (config.is_default(key)) missing(file, key, config.schema());
    config.fail(key, "needs at least one row");
  }
  return table;
}

std::string join(const std::vector<std::string>& parts) {
  std::string text;
  for (std::size_t i = 0; i < parts.size(); ++i) text += (i > 0 ? ", " : "") + parts[i];
  return text.empty() ? "(none)" : text;
}


}  // namespace

std::vector<std::string> split_path_list(const std::string& text) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t colon = text.find(':', start);
    const std::string part =
        text.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
    if (!part.empty()) parts.push_back(part);
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  return parts;
}

fem::ConfigSchema material_file_schema() {
  fem::ConfigSchema schema(
      "Material data file reference",
      "One material per file, `materials/data/<name>.yaml`. Every table gives a property "
      "against temperature, piecewise linear between rows and constant outside them, "
      "with its source. See `materials/data/README.md`.");
  schema.identifier("name")
      .default_value("unnamed")
      .doc("Required: the material's name; must equal the file name without .yaml.");
  schema.string("description").default_value("").doc("One line on what the material is.");

  for (const TableProperty& property : table_properties()) {
    schema.section(property.key, property.doc);
    schema.table(std::string(property.key) + ".points")
        .column("temperature", "degC", "degC", temperature_range)
        .column(property.column, property.unit, property.display_unit, property.range)
        .increasing()
        .items(0, 1000)
        .default_value("[]")
        .doc(std::string("Required: ") + property.doc + " Rows [temperature, value].");
    declare_provenance(schema, property.key);
  }

  schema.section("flow_curves",
                 "Yield stress against equivalent plastic strain at several temperatures.");
  schema.list("flow_curves.curves")
      .items(0, 100)
      .doc("Required: one item per temperature, temperatures increasing.");
  schema.number("flow_curves.curves[].temperature", "degC", "degC")
      .default_value("20 degC")
      .range(temperature_range)
      .doc("Required: temperature of this curve.");
  schema.table("flow_curves.curves[].points")
      .column("plastic_strain", "1", "1", fem::Range::closed(0, 100))
      .column("yield_stress", "Pa", "MPa", fem::Range::open_closed(0, 1e5))
      .increasing()
      .items(0, 1000)
      .default_value("[]")
      .doc("Required: rows [equivalent plastic strain, yield stress]; stress non-decreasing, "
           "held constant beyond the last strain.");
  declare_provenance(schema, "flow_curves");

  schema.section("melting", "Solidification range and latent heat.");
  schema.number("melting.solidus", "degC", "degC")
      .default_value("0 degC")
      .range(temperature_range)
      .doc("Required: solidus temperature (liquid fraction 0 below it).");
  schema.number("melting.liquidus", "degC", "degC")
      .default_value("0 degC")
      .range(temperature_range)
      .doc("Required: liquidus temperature (liquid fraction 1 above it); above the solidus.");
  schema.number("melting.melting_temperature", "degC", "degC")
      .default_value("0 degC")
      .range(temperature_range)
      .doc("Required: T_melting of paper eq. 3, where the conductivity switches to lambda_m.");
  schema.number("melting.latent_heat", "J/kg", "kJ/kg")
      .default_value("0 kJ/kg")
      .range(fem::Range::closed(0, 5000))
      .doc("Required: latent heat of fusion, released between solidus and liquidus.");
  schema.number("melting.boiling_point", "degC", "degC")
      .default_value("4000 degC")
      .range(temperature_range)
      .doc("Optional: boiling point at 1 atm. Not used by the physics; a weld whose sheet "
           "passes it gets a plausibility warning (none where the file does not give it).");
  declare_provenance(schema, "melting");

  schema.section("strength_floor", "Yield stress of the melt and the blend into it.");
  schema.number("strength_floor.yield_stress", "Pa", "MPa")
      .default_value("1 MPa")
      .range(fem::Range::open_closed(0, 1000))
      .doc("Required: yield stress at and above the solidus (a small floor keeps the "
           "mechanics solvable).");
  schema.number("strength_floor.transition", "K", "K")
      .default_value("50 K")
      .range(fem::Range::open_closed(0, 200))
      .doc("Width of the C1 blend from the flow curves to the floor, ending at the solidus "
           "(a temperature difference: write K, not degC).");
  declare_provenance(schema, "strength_floor");
  return schema;
}

Material load_material_file(const std::string& path) {
  const fem::Config config = fem::load_config(material_file_schema(), path);

  MaterialData data;
  require_given(config, path, "name");
  data.name = config.text("name");
  data.description = config.text("description");
  data.source_file = path;

  for (const TableProperty& property : table_properties()) {
    const std::string key = std::string(property.key) + ".points";
    const fem::ConfigTable& table = required_table(config, path, key);
    require_source(config, path, property.key);
    data.*(property.member) = PropertyTable(table.column(0), table.column(1));
  }

  const int n_curves = config.n_items("flow_curves.curves");
  if (n_curves == 0) {
    if (config.is_default("flow_curves.curves")) {
      missing(path, "flow_curves.curves", config.schema());
    }
    config.fail("flow_curves.curves", "needs at least one curve");
  }
  require_source(config, path, "flow_curves");
  std::vector<FlowCurve> curves;
  for (int j = 0; j < n_curves; ++j) {
    const std::string temperature_key = fem::item_path("flow_curves.curves", j, "temperature");
    const std::string points_key = fem::item_path("flow_curves.curves", j, "points");
    require_given(config, path, temperature_key);
    FlowCurve curve;
    curve.temperature = config.number(temperature_key);
    if (j > 0 && !(curve.temperature > curves.back().temperature)) {
      config.fail(temperature_key, "flow curve temperatures must increase from item to item "
                                   "(previous curve at " +
                                       config.display(fem::item_path("flow_curves.curves",
                                                                     j - 1, "temperature")) +
                                       ")");
    }
    const fem::ConfigTable& points = required_table(config, path, points_key);
    curve.plastic_strain = points.column(0);
    curve.yield_stress = points.column(1);
    for (int k = 1; k < points.n_rows(); ++k) {
      if (curve.yield_stress[k] < curve.yield_stress[k - 1]) {
        config.fail(points_key + "[" + std::to_string(k) + "]",
                    "yield stress must not decrease with plastic strain (previous row " +
                        config.display(points_key + "[" + std::to_string(k - 1) + "]") + ")");
      }
    }
    curves.push_back(std::move(curve));
  }
  data.flow_curves = FlowCurveTable(std::move(curves));

  for (const char* key : {"melting.solidus", "melting.liquidus", "melting.melting_temperature",
                          "melting.latent_heat", "strength_floor.yield_stress"}) {
    require_given(config, path, key);
  }
  require_source(config, path, "melting");
  require_source(config, path, "strength_floor");
  data.solidus = config.number("melting.solidus");
  data.liquidus = config.number("melting.liquidus");
  data.melting_temperature = config.number("melting.melting_temperature");
  data.latent_heat = config.number("melting.latent_heat");
  if (!config.is_default("melting.boiling_point")) {
    data.boiling_point = config.number("melting.boiling_point");
    if (!(data.boiling_point > data.liquidus))
      config.fail("melting.boiling_point", "must lie above the liquidus (" + config.display("melting.liquidus") + ")");
  }
  if (!(data.liquidus > data.solidus)) {
    config.fail("melting.liquidus",
                "must lie above the solidus (" + config.display("melting.solidus") + ")");
  }
  data.strength_floor = config.number("strength_floor.yield_stress");
  data.strength_floor_transition = config.number("strength_floor.transition");

  try {
    return Material(std::move(data));
  } catch (const std::invalid_argument& e) {
    throw fem::ConfigError(path + ": " + e.what());
  }
}

MaterialLibrary::MaterialLibrary() : MaterialLibrary(default_directories()) {}

MaterialLibrary::MaterialLibrary(std::vector<std::string> directories)
    : directories_(std::move(directories)) {}

namespace {
std::vector<std::string>& user_directories() {
  static std::vector<std::string> directories;
  return directories;
}

std::string& shipped_directory() {
  static std::string directory = RSW_MATERIALS_DIR;
  return directory;
}
}  // namespace

void MaterialLibrary::set_user_directories(std::vector<std::string> directories) {
  user_directories() = std::move(directories);
}

void MaterialLibrary::set_shipped_directory(std::string directory) { shipped_directory() = std::move(directory); }

std::vector<std::string> MaterialLibrary::default_directories() {
  std::vector<std::string> directories = user_directories();
  directories.push_back(shipped_directory());
  return directories;
}

std::vector<std::string> MaterialLibrary::available() const {
  std::set<std::string> names;
  for (const auto& directory : directories_) {
    std::error_code error;
    for (fs::directory_iterator it(directory, error), end; !error && it != end;
         it.increment(error)) {
      const fs::path& file = it->path();
      if (file.extension() == ".yaml" && it->is_regular_file(error)) {
        names.insert(file.stem().string());
      }
    }
  }
  return {names.begin(), names.end()};
}

std::string MaterialLibrary::find(const std::string& name) const {
  const bool plain_name =
      !name.empty() && name.find('/') == std::string::npos && name != "." && name != "..";
  if (plain_name) {
    for (const auto& directory : directories_) {
      const fs::path file = fs::path(directory) / (name + ".yaml");
      std::error_code error;
      if (fs::is_regular_file(file, error)) return file.string();
    }
  }
  std::vector<std::string> searched;
  for (const auto& directory : directories_) searched.push_back("'" + directory + "'");
  throw MaterialNotFound("material '" + name + "' not found: no file '" + name +
                         ".yaml' in the material directories searched (" + join(searched) +
                         "; set RSW_MATERIALS_PATH to add directories); available materials: " +
                         join(available()));
}

Material MaterialLibrary::load(const std::string& name) const {
  const std::string path = find(name);
  Material material = load_material_file(path);
  if (material.name() != name) {
    throw fem::ConfigError(path + ": name: '" + material.name() +
                           "' does not match the file name; the file for material '" + name +
                           "' must say name: " + name);
  }
  return material;
}

}  // namespace rsw::materials
