// Materials: the shipped data files load with their reference values and physically
// consistent flow curves; lookup errors name what was searched; a bad data file is
// reported with file, line and key like a bad case file; latent heat is released
// exactly between solidus and liquidus; the yield stress reaches the strength floor
// smoothly; thermal strain vanishes at the stress-free temperature.
#include "materials/material.hpp"
#include "materials/material_library.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

namespace rsw::materials {
namespace {

namespace fs = std::filesystem;

const std::string shipped_directory = RSW_MATERIALS_DIR;

Material shipped(const std::string& name) {
  return MaterialLibrary({shipped_directory}).load(name);
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A fresh directory under the system temporary directory, removed at the end.
class ScratchDirectory {
 public:
  explicit ScratchDirectory(const std::string& tag)
      : path_(fs::temp_directory_path() /
              ("rsw_materials_" + tag + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDirectory() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  std::string path() const { return path_.string(); }
  std::string write(const std::string& file_name, const std::string& text) const {
    const fs::path file = path_ / file_name;
    std::ofstream(file) << text;
    return file.string();
  }

 private:
  fs::path path_;
};

// 1-based line of the first occurrence of `needle` in `text`.
int line_of(const std::string& text, const std::string& needle) {
  const auto at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

// Message of the ConfigError thrown by loading `path`, or "" if none was thrown.
std::string load_error(const std::string& path) {
  try {
    load_material_file(path);
  } catch (const fem::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(MaterialLibrary, ShippedMaterialsLoad) {
  const MaterialLibrary library({shipped_directory});
  const std::vector<std::string> names = library.available();
  EXPECT_NE(std::find(names.begin(), names.end(), "DP1200"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "CuCrZr"), names.end());

  const Material steel = library.load("DP1200");
  EXPECT_EQ(steel.name(), "DP1200");
  EXPECT_DOUBLE_EQ(steel.melting_temperature(), 1507.0);  // the paper's T_melting
  EXPECT_LT(steel.solidus(), steel.melting_temperature());
  EXPECT_GT(steel.liquidus(), steel.melting_temperature());
  EXPECT_DOUBLE_EQ(steel.electrical_resistivity(20).value, 2.5e-7);
  // Eurocode 3 conductivity at 20 degC: 54 - 0.0333 * 20 = 53.33 W/(m K).
  EXPECT_NEAR(steel.thermal_conductivity(20).value, 53.33, 1e-9);
  EXPECT_DOUBLE_EQ(steel.density(900).value, 7850.0);
  EXPECT_DOUBLE_EQ(steel.youngs_modulus(20).value, 210e9);
  // Room-temperature yield of the DP1200 fit, and a few tens of MPa near 1200 degC.
  EXPECT_DOUBLE_EQ(steel.yield_stress(0, 20).yield_stress, 950e6);
  EXPECT_GT(steel.yield_stress(0, 1200).yield_stress, 10e6);
  EXPECT_LT(steel.yield_stress(0, 1200).yield_stress, 100e6);

  // The electrode alloy's values at 20 degC (materials/data/CuCrZr.yaml).
  const Material copper = library.load("CuCrZr");
  EXPECT_DOUBLE_EQ(copper.density(20).value, 8900.0);
  EXPECT_DOUBLE_EQ(copper.specific_heat(20).value, 380.0);
  EXPECT_DOUBLE_EQ(copper.thermal_conductivity(20).value, 320.0);
  EXPECT_DOUBLE_EQ(copper.electrical_resistivity(20).value, 2.1e-8);
  EXPECT_DOUBLE_EQ(copper.youngs_modulus(20).value, 128e9);
  EXPECT_DOUBLE_EQ(copper.poisson_ratio(20).value, 0.3);
  EXPECT_DOUBLE_EQ(copper.secant_expansion(20).value, 17e-6);

  // Physical consistency: yield stress non-decreasing in eps_p and non-increasing in
  // T (floor included) over a grid through every table point.
  for (const Material* material : {&steel, &copper}) {
    for (double t = 0; t <= 1700; t += 10) {
      double previous = 0;
      for (double strain = 0; strain <= 1.2; strain += 0.0025) {
        const double s = material->yield_stress(strain, t).yield_stress;
        EXPECT_GE(s, previous - 1e-6) << material->name() << " T " << t << " eps " << strain;
        EXPECT_LE(material->yield_stress(strain, t + 10).yield_stress, s + 1e-6)
            << material->name() << " T " << t << " eps " << strain;
        EXPECT_GE(s, material->strength_floor() - 1e-6);
        previous = s;
      }
    }
    // Tables reach above the liquidus.
    EXPECT_GT(material->data().electrical_resistivity.temperatures().back(),
              material->liquidus());
  }
}

TEST(MaterialLibrary, UnknownMaterialNamesSearchedDirectories) {
  const ScratchDirectory user("user");
  const MaterialLibrary library({user.path(), shipped_directory});
  try {
    library.load("DP1300");
    FAIL() << "no error for an unknown material";
  } catch (const MaterialNotFound& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("'DP1300'"), std::string::npos) << message;
    EXPECT_NE(message.find(user.path()), std::string::npos) << message;
    EXPECT_NE(message.find(shipped_directory), std::string::npos) << message;
    EXPECT_NE(message.find("DP1200"), std::string::npos) << message;
    EXPECT_NE(message.find("CuCrZr"), std::string::npos) << message;
  }
}

TEST(MaterialLibrary, UserDirectoriesComeFirstAndShadowShippedFiles) {
  const ScratchDirectory user("env");
  const std::string shipped_text = read_text(shipped_directory + "/DP1200.yaml");
  user.write("DP1200.yaml", replaced(shipped_text, "yield_stress: 5 MPa", "yield_stress: 7 MPa"));
  // As the rsw program sets them from RSW_MATERIALS_PATH.
  MaterialLibrary::set_user_directories(split_path_list(user.path() + ":/nonexistent_rsw_dir"));
  const std::vector<std::string> directories = MaterialLibrary::default_directories();
  const MaterialLibrary library;
  MaterialLibrary::set_user_directories({});
  ASSERT_EQ(directories.size(), 3u);
  EXPECT_EQ(directories[0], user.path());
  EXPECT_EQ(directories[1], "/nonexistent_rsw_dir");
  EXPECT_EQ(directories[2], shipped_directory);
  EXPECT_DOUBLE_EQ(library.load("DP1200").strength_floor(), 7e6);
  EXPECT_DOUBLE_EQ(library.load("CuCrZr").strength_floor(), 34.2e6);
}

// melting.boiling_point is optional (only the plausibility warning reads it): the
// shipped files give iron's and copper's (CRC Handbook: 3134 K and 2835 K), a file
// without it loads with none, and one at or below the liquidus is refused at its line.
TEST(MaterialFile, BoilingPointIsOptionalAndMustLieAboveTheLiquidus) {
  const MaterialLibrary library({shipped_directory});
  EXPECT_DOUBLE_EQ(library.load("DP1200").boiling_point(), 2861.0);  // 3134 K to the degree
  EXPECT_DOUBLE_EQ(library.load("CuCrZr").boiling_point(), 2562.0);  // 2835 K to the degree

  const ScratchDirectory scratch("boiling");
  const std::string text = read_text(shipped_directory + "/DP1200.yaml");
  const std::string path = scratch.write("DP1200.yaml", replaced(text, "  boiling_point: 2861 degC\n", ""));
  EXPECT_TRUE(std::isnan(load_material_file(path).boiling_point()));

  const std::string low = replaced(text, "boiling_point: 2861 degC", "boiling_point: 1500 degC");
  scratch.write("DP1200.yaml", low);
  const std::string message = load_error(path);
  EXPECT_NE(message.find(path + ":" + std::to_string(line_of(low, "boiling_point: 1500")) + ":"), std::string::npos)
      << message;
  EXPECT_NE(message.find("melting.boiling_point"), std::string::npos) << message;
  EXPECT_NE(message.find("above the liquidus"), std::string::npos) << message;
}

TEST(MaterialFile, BadTableNamesFileLineAndKey) {
  const ScratchDirectory scratch("bad");
  const std::string text = read_text(shipped_directory + "/DP1200.yaml");

  // A value of the wrong kind of quantity in a table row.
  const std::string wrong_unit = replaced(text, "[300 degC, 0.44 uohm*m]", "[300 degC, 0.44 GPa]");
  const std::string path = scratch.write("DP1200.yaml", wrong_unit);
  std::string message = load_error(path);
  const std::string line = ":" + std::to_string(line_of(wrong_unit, "0.44 GPa")) + ":";
  EXPECT_NE(message.find(path + line), std::string::npos) << message;
  EXPECT_NE(message.find("electrical_resistivity.points[3]"), std::string::npos) << message;
  EXPECT_NE(message.find("0.44 GPa"), std::string::npos) << message;
  EXPECT_NE(message.find("electrical resistivity"), std::string::npos) << message;

  // Temperatures out of order.
  const std::string unsorted =
      replaced(text, "[1000 degC, 1.18 uohm*m]", "[850 degC, 1.18 uohm*m]");
  scratch.write("DP1200.yaml", unsorted);
  message = load_error(path);
  EXPECT_NE(message.find(path + ":" + std::to_string(line_of(unsorted, "[850 degC")) + ":"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("electrical_resistivity.points[10]"), std::string::npos) << message;
  EXPECT_NE(message.find("strictly increasing"), std::string::npos) << message;

  // A flow curve that softens with strain: checked across rows, reported at the row.
  const std::string softening =
      replaced(text, "[0.5, 1031.5 MPa], [1, 1055 MPa]", "[0.5, 1031.5 MPa], [1, 1000 MPa]");
  scratch.write("DP1200.yaml", softening);
  message = load_error(path);
  EXPECT_NE(message.find(path + ":" + std::to_string(line_of(softening, "[1, 1000 MPa]")) + ":"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("flow_curves.curves[2].points[8]"), std::string::npos) << message;
  EXPECT_NE(message.find("must not decrease"), std::string::npos) << message;

  // A table left out entirely: named as missing, with its doc.
  const auto start = text.find("density:");
  const auto end = text.find("youngs_modulus:");
  const std::string without_density = text.substr(0, start) + text.substr(end);
  scratch.write("DP1200.yaml", without_density);
  message = load_error(path);
  EXPECT_NE(message.find(path + ": density.points: missing"), std::string::npos) << message;

  // An unknown key gets the closest declared one suggested.
  scratch.write("DP1200.yaml", replaced(text, "latent_heat: 270 kJ/kg", "latent_heet: 270 kJ/kg"));
  message = load_error(path);
  EXPECT_NE(message.find("melting.latent_heet"), std::string::npos) << message;
  EXPECT_NE(message.find("did you mean 'melting.latent_heat'"), std::string::npos) << message;

  // Solidus above liquidus: a relation between keys, reported at the liquidus.
  const std::string inverted = replaced(text, "liquidus: 1515 degC", "liquidus: 1460 degC");
  scratch.write("DP1200.yaml", inverted);
  message = load_error(path);
  EXPECT_NE(message.find(path + ":" + std::to_string(line_of(inverted, "liquidus: 1460")) + ":"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("melting.liquidus"), std::string::npos) << message;
}

TEST(Enthalpy, LatentHeatReleasedBetweenSolidusAndLiquidus) {
  const Material steel = shipped("DP1200");
  const double t_s = steel.solidus();
  const double t_l = steel.liquidus();
  const double latent = steel.latent_heat();
  EXPECT_DOUBLE_EQ(latent, 270e3);

  // Liquid fraction: 0 up to the solidus, 1 from the liquidus, 1/2 halfway (smoothstep).
  EXPECT_DOUBLE_EQ(steel.liquid_fraction(t_s).value, 0.0);
  EXPECT_DOUBLE_EQ(steel.liquid_fraction(t_l).value, 1.0);
  EXPECT_DOUBLE_EQ(steel.liquid_fraction(0.5 * (t_s + t_l)).value, 0.5);

  // The apparent heat capacity dh/dT minus c_p, integrated over the melting range by
  // the midpoint rule, is the latent heat; outside the range it is zero.
  const int n = 20000;
  const double dt = (t_l - t_s) / n;
  double released = 0;
  for (int i = 0; i < n; ++i) {
    const double t = t_s + (i + 0.5) * dt;
    released += (steel.enthalpy(t).slope - steel.specific_heat(t).value) * dt;
  }
  EXPECT_NEAR(released, latent, 1e-6 * latent);
  EXPECT_DOUBLE_EQ(steel.enthalpy(t_s - 1).slope, steel.specific_heat(t_s - 1).value);
  EXPECT_DOUBLE_EQ(steel.enthalpy(t_l + 1).slope, steel.specific_heat(t_l + 1).value);

  // h is a function of T: its jump over the range is sensible heat plus L exactly,
  // and h(20 degC) = 0.
  EXPECT_DOUBLE_EQ(steel.enthalpy(20).value, 0.0);
  const double sensible = steel.data().specific_heat.integral(t_s - 30, t_l + 30);
  EXPECT_NEAR(steel.enthalpy(t_l + 30).value - steel.enthalpy(t_s - 30).value,
              sensible + latent, 1e-9 * (sensible + latent));
  // Constant c_p = 650 J/(kg K) above 900 degC: h(1600) - h(1000) = 650 * 600 + L.
  EXPECT_NEAR(steel.enthalpy(1600).value - steel.enthalpy(1000).value, 650.0 * 600 + latent,
              1e-6);

  // dh/dT against central differences, inside and outside the melting range.
  const double h = 1e-4;
  for (double t : {350.0, 1000.0, t_s + 7.3, 0.5 * (t_s + t_l), t_l - 3.1, 1580.0}) {
    const double difference = (steel.enthalpy(t + h).value - steel.enthalpy(t - h).value) / (2 * h);
    EXPECT_NEAR(steel.enthalpy(t).slope, difference, 1e-6 * std::abs(difference)) << "T " << t;
  }
}

TEST(Material, YieldStressReachesFloorAboveSolidusSmoothly) {
  const Material steel = shipped("DP1200");
  const double t_s = steel.solidus();
  const double width = steel.strength_floor_transition();
  const double floor = steel.strength_floor();
  EXPECT_DOUBLE_EQ(floor, 5e6);
  EXPECT_DOUBLE_EQ(width, 50.0);
  const FlowCurveTable& table = steel.data().flow_curves;

  for (double strain : {0.0, 0.03, 0.4, 2.0}) {
    // At and above the solidus: the floor, perfectly plastic, no T slope.
    for (double t : {t_s, t_s + 1, 1600.0, 2500.0}) {
      const FlowStress s = steel.yield_stress(strain, t);
      EXPECT_DOUBLE_EQ(s.yield_stress, floor);
      EXPECT_DOUBLE_EQ(s.hardening, 0.0);
      EXPECT_DOUBLE_EQ(s.temperature_slope, 0.0);
    }
    // At and below the start of the blend: the flow curves unchanged.
    for (double t : {20.0, 1000.0, t_s - width}) {
      EXPECT_DOUBLE_EQ(steel.yield_stress(strain, t).yield_stress,
                       table.evaluate(strain, t).yield_stress);
    }
    // Halfway: w = 1/2, the mean of table and floor.
    const double mid = t_s - 0.5 * width;
    EXPECT_NEAR(steel.yield_stress(strain, mid).yield_stress,
                0.5 * (table.evaluate(strain, mid).yield_stress + floor), 1e-6);

    // C1 at both ends of the blend: the one-sided slopes agree. A kink would differ
    // by about (sigma_table - floor) / width; a C1 blend differs by h times the
    // curvature 6 (sigma_table - floor) / width^2, i.e. 6 h / width of that scale.
    const double h = 1e-3;
    const double scale = (table.evaluate(strain, t_s - width).yield_stress - floor) / width;
    for (double end : {t_s - width, t_s}) {
      const double below = (steel.yield_stress(strain, end).yield_stress -
                            steel.yield_stress(strain, end - h).yield_stress) / h;
      const double above = (steel.yield_stress(strain, end + h).yield_stress -
                            steel.yield_stress(strain, end).yield_stress) / h;
      EXPECT_NEAR(below, above, 1e-3 * scale) << "end " << end;
    }
    // Temperature slope inside the band against central differences, and monotone.
    double previous = steel.yield_stress(strain, t_s - width).yield_stress;
    for (double t = t_s - width + 2.5; t < t_s; t += 5) {
      const FlowStress s = steel.yield_stress(strain, t);
      const double difference = (steel.yield_stress(strain, t + h).yield_stress -
                                 steel.yield_stress(strain, t - h).yield_stress) / (2 * h);
      EXPECT_NEAR(s.temperature_slope, difference, 1e-6 * std::abs(difference) + 1e-3);
      EXPECT_LT(s.yield_stress, previous);
      previous = s.yield_stress;
    }
  }
}

TEST(Material, ThermalStrainVanishesAtStressFreeTemperature) {
  const Material steel = shipped("DP1200");
  // Eurocode 3 elongation at 1000 degC from 20 degC: 2e-5 * 1000 - 6.2e-3 = 0.0138.
  EXPECT_NEAR(steel.thermal_strain(1000, 20).value, 0.0138, 5e-9);  // 7-digit table
  // Below 750 degC: 1.2e-5 T + 0.4e-8 T^2 - 2.416e-4; at 500 degC 6.7584e-3.
  EXPECT_NEAR(steel.thermal_strain(500, 20).value, 6.7584e-3, 1e-9);
  for (double t0 : {20.0, 350.0, 900.0}) {
    EXPECT_DOUBLE_EQ(steel.thermal_strain(t0, t0).value, 0.0);
  }
  // Relative to another stress-free temperature: a difference of elongations.
  EXPECT_NEAR(steel.thermal_strain(1000, 500).value, 0.0138 - 6.7584e-3, 5e-9);
  const double h = 1e-4;
  for (double t : {130.0, 777.0, 1234.0}) {
    const double difference =
        (steel.thermal_strain(t + h, 20).value - steel.thermal_strain(t - h, 20).value) / (2 * h);
    EXPECT_NEAR(steel.thermal_strain(t, 20).slope, difference, 1e-9);
  }
}

}  // namespace
}  // namespace rsw::materials
