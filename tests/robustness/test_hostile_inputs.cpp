// Hostile inputs, as a new user or a data logger would produce them, through the rsw
// program: malformed and extreme weld cases, overrides, signal files, study and
// calibration files and command lines. Each case asserts the exit code (0 done, 1 run
// failed, 2 bad input; README "Exit codes") and the words its message must contain
// (the file, key, value or what is allowed), and that rsw neither crashes nor hangs:
// every command runs under `timeout`, whose 124 fails the case.
#include "cli_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using rsw::testing::read_file;
using rsw::testing::run_command;
using rsw::testing::write_file;

const std::string rsw_binary = RSW_BINARY;
const fs::path source_dir = RSW_SOURCE_DIR;

// The paper's case with `from` replaced by `to` (once; `from` must occur).
std::string with(std::string text, const std::string& from, const std::string& to);
std::string paper_case_with(const std::string& from, const std::string& to) {
  return with(read_file(source_dir / "validation/paper_case/weld.yaml"), from, to);
}

// `text` with `from` replaced by `to` (once; `from` must occur).
std::string with(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("no '" + from + "' to replace");
  return text.replace(at, from.size(), to);
}

// A signal file of a plausible weld: 8 kA after a 10 ms ramp, R(t) rising to 310 µΩ.
std::string signal_rows(const std::string& separator = ", ") {
  std::string rows;
  for (int t = 0; t <= 160; ++t) {
    const double current = t < 10 ? 0.8 * t : (t <= 150 ? 8.0 : 0.0);
    const double resistance = 250e-6 + 60e-6 * std::sin(M_PI * t / 150.0);
    rows += std::to_string(t) + separator + std::to_string(current) + separator +
            std::to_string(current * 1e3 * resistance) + separator + "3" + separator + std::to_string(1e-4 * t) +
            "\n";
  }
  return rows;
}
const std::string signal_header = "time [ms], current [kA], voltage [V], force [kN], displacement [mm]\n";

std::string study_file(const std::string& parameters, const std::string& features = "  - {name: R_beta}\n",
                       const std::string& rest = "") {
  return "study:\n  name: hostile\n  output: out\nparameters:\n" + parameters + "features:\n" + features +
         "model:\n  case: case.yaml\ndesign:\n  kind: lhs\n  n_points: 4\n" + rest;
}
const std::string p1_parameter =
    "  - {name: htc_p1, config_key: contact.electrode_sheet.htc_p1, unit: '1', prior: log10_uniform, lower: 1e-3, "
    "upper: 1e-1}\n";

struct HostileInput {
  std::string name;
  std::vector<std::pair<std::string, std::string>> files;  // name in the case's folder, content
  std::string arguments;                                    // after `rsw`, run in that folder
  int exit_code;
  std::vector<std::string> named;  // each must occur in the output
};

std::vector<HostileInput> hostile_inputs() {
  const std::string paper = read_file(source_dir / "validation/paper_case/weld.yaml");
  const std::string good_signal = signal_header + signal_rows();
  const std::string long_name(30000, 'x');
  std::vector<HostileInput> c;
  // --- The command line.
  c.push_back({"NoSubcommand", {}, "", 2, {"subcommand"}});
  c.push_back({"MisspeltSubcommand", {}, "simulat case.yaml", 2, {"simulat", "simulate"}});
  c.push_back({"SimulateWithoutCase", {}, "simulate", 2, {"case", "required"}});
  c.push_back({"SimulateMissingCaseFile", {}, "simulate nowhere.yaml", 2, {"nowhere.yaml"}});
  c.push_back({"ThreadsZero", {{"case.yaml", paper}}, "--threads 0 simulate case.yaml", 2, {"threads"}});
  c.push_back({"ThreadsNotANumber", {{"case.yaml", paper}}, "--threads many simulate case.yaml", 2, {"threads", "many"}});
  c.push_back({"SetWithoutEquals", {{"case.yaml", paper}}, "simulate case.yaml --set mesh.base_size", 2,
               {"mesh.base_size", "="}});
  c.push_back({"SetUnknownKey", {{"case.yaml", paper}}, "simulate case.yaml --set mesh.base_sise=1mm", 2,
               {"mesh.base_sise", "mesh.base_size"}});
  c.push_back({"SetOutOfRange", {{"case.yaml", paper}}, "simulate case.yaml --set mesh.weld_zone.levels=40", 2,
               {"mesh.weld_zone.levels", "40"}});
  c.push_back({"SetWrongUnit", {{"case.yaml", paper}}, "simulate case.yaml --set mesh.base_size=1kg", 2,
               {"mesh.base_size", "kg"}});
  c.push_back({"SetNotANumber", {{"case.yaml", paper}}, "simulate case.yaml --set contact.electrode_sheet.htc_p1=abc",
               2, {"contact.electrode_sheet.htc_p1", "abc"}});
  c.push_back({"SetNaN", {{"case.yaml", paper}}, "simulate case.yaml --set contact.electrode_sheet.htc_p1=nan", 2,
               {"contact.electrode_sheet.htc_p1", "nan"}});
  c.push_back({"SetInfinity", {{"case.yaml", paper}}, "simulate case.yaml --set thermal.water_htc=inf", 2,
               {"thermal.water_htc", "inf"}});
  c.push_back({"SetHugeKey", {{"case.yaml", paper}}, "simulate case.yaml --set " + long_name + "=1", 2, {"xxxx"}});
  c.push_back({"SetHugeValue", {{"case.yaml", paper}}, "simulate case.yaml --set case.name=" + long_name, 2,
               {"case.name", "30000 characters", "128"}});
  c.push_back({"OutputIsAFile", {{"case.yaml", paper}, {"taken", "mine"}}, "simulate case.yaml -o taken", 2,
               {"taken"}});
  c.push_back({"FeaturesWithoutFile", {}, "features", 2, {"file"}});
  c.push_back({"StudyWithoutSubcommand", {}, "study", 2, {"subcommand"}});
  c.push_back({"CalibrateMissingStudy", {}, "calibrate nowhere.yaml", 2, {"nowhere.yaml"}});
  c.push_back({"UnknownOption", {{"case.yaml", paper}}, "simulate case.yaml --fast", 2, {"--fast"}});

  // --- Weld case files (`rsw config show` resolves and checks them without running).
  const auto bad_case = [&](const std::string& name, const std::string& text, std::vector<std::string> named) {
    c.push_back({"Case" + name, {{"case.yaml", text}}, "config show case.yaml", 2, std::move(named)});
  };
  // Every key has a default: an empty case is the default weld (docs/CONFIG.md).
  c.push_back({"CaseEmptyIsTheDefaultCase", {{"case.yaml", ""}}, "config show case.yaml", 0, {"name: weld"}});
  bad_case("NotYaml", "\x01\x02\x03\xff\xfe{{{[[[", {"case.yaml"});
  bad_case("TopLevelList", "- a\n- b\n", {"case.yaml"});
  bad_case("TabIndentation", "case:\n\tname: x\n", {"case.yaml", "2"});
  bad_case("UnclosedBracket", paper_case_with("[0 ms, 0 kA]", "[0 ms, 0 kA"), {"case.yaml"});
  bad_case("UnknownTopLevelKey", paper + "\nweldgun: {}\n", {"case.yaml", "weldgun"});
  bad_case("MisspeltKey", paper_case_with("cool_time:", "cooling_time:"), {"case.yaml", "cooling_time"});
  bad_case("NegativeThickness", paper_case_with("thickness: 1.0 mm}", "thickness: -1.0 mm}"),
           {"case.yaml", "thickness", "-1"});
  bad_case("ZeroThickness", paper_case_with("thickness: 1.0 mm}", "thickness: 0 mm}"), {"case.yaml", "thickness"});
  c.push_back({"CaseThicknessWithoutUnitIsInTheDisplayUnit",
               {{"case.yaml", paper_case_with("thickness: 1.0 mm}", "thickness: 1.0}")}}, "config show case.yaml", 0,
               {"thickness: 1 mm"}});
  bad_case("ThicknessInKilograms", paper_case_with("thickness: 1.0 mm}", "thickness: 1.0 kg}"),
           {"case.yaml", "thickness", "kg"});
  c.push_back({"CaseUnknownMaterial", {{"case.yaml", paper_case_with("material: DP1200", "material: DP9999")}},
               "simulate case.yaml", 2, {"DP9999", "CuCrZr, DP1200"}});
  bad_case("NegativeFilm", paper_case_with("film_thickness: 7.0710678e-3 mm", "film_thickness: -1 mm"),
           {"case.yaml", "film_thickness"});
  bad_case("ZeroBaseSize", paper_case_with("base_size: 0.25 mm", "base_size: 0 mm"), {"case.yaml", "base_size"});
  bad_case("NegativeLevels", paper_case_with("levels: 2", "levels: -1"), {"case.yaml", "levels"});
  bad_case("FractionalLevels", paper_case_with("levels: 2", "levels: 1.5"), {"case.yaml", "levels"});
  bad_case("HugeName", paper_case_with("name: paper_case", "name: " + long_name), {"case.yaml", "case.name"});
  bad_case("NaNValue", paper_case_with("htc_p1: 1e-2", "htc_p1: .nan"), {"case.yaml", "htc_p1"});
  bad_case("DuplicateKey", paper_case_with("  name: paper_case\n", "  name: paper_case\n  name: again\n"),
           {"case.yaml", "name"});
  bad_case("TimesGoingBack", paper_case_with("[140 ms, 8 kA]", "[5 ms, 8 kA]"), {"case.yaml", "current"});
  bad_case("CurrentPointNotAPair", paper_case_with("[140 ms, 8 kA]", "[140 ms]"), {"case.yaml", "current"});
  bad_case("CurrentInVolts", paper_case_with("[140 ms, 8 kA]", "[140 ms, 8 V]"), {"case.yaml", "V"});
  bad_case("NegativeCoolTime", paper_case_with("cool_time: 10 ms", "cool_time: -10 ms"), {"case.yaml", "cool_time"});
  bad_case("FrictionAboveRange", paper_case_with("friction_coefficient: 0.3", "friction_coefficient: 50"),
           {"case.yaml", "friction_coefficient", "50"});
  bad_case("ScalarForMapping", paper_case_with("electrodes:", "electrodes: 3\nunused:"), {"case.yaml", "electrodes"});
  bad_case("AbsoluteZero", paper_case_with("initial_temperature: 20 degC", "initial_temperature: -300 degC"),
           {"case.yaml", "initial_temperature"});

  // --- Signal files (`rsw features`).
  const auto signal = [&](const std::string& name, const std::string& text, int code, std::vector<std::string> named) {
    c.push_back({"Signal" + name, {{"weld.csv", text}}, "features weld.csv", code, std::move(named)});
  };
  signal("Empty", "", 2, {"weld.csv"});
  signal("HeaderOnly", signal_header, 2, {"weld.csv"});
  signal("NoCurrentColumn", "time [ms], voltage [V]\n0, 0\n1, 0.001\n", 2, {"weld.csv", "current"});
  signal("TextInANumberColumn", signal_header + "0, 0, 0, 3, 0\n1, eight, 0, 3, 0\n", 2, {"weld.csv", "eight"});
  signal("RaggedRow", signal_header + "0, 0, 0, 3, 0\n1, 0.8, 0.0002\n", 2, {"weld.csv", "3"});
  signal("TimeGoingBack", signal_header + "0, 0, 0, 3, 0\n2, 1, 0.0003, 3, 0\n1, 1, 0.0003, 3, 0\n", 2,
         {"weld.csv", "time"});
  signal("UnknownUnit", "time [fortnights], current [kA], voltage [V], force [kN], displacement [mm]\n" + signal_rows(),
         2, {"weld.csv", "fortnights", "ms?"});
  signal("Binary", std::string("\x00\x01\x02\xff", 4) + "garbage", 2, {"weld.csv"});
  signal("WithByteOrderMark", "\xEF\xBB\xBF" + good_signal, 0, {"R_beta"});
  signal("Semicolons", "time [ms]; current [kA]; voltage [V]; force [kN]; displacement [mm]\n" + signal_rows("; "), 0,
         {"R_beta"});
  signal("QuotedHeader",
         "\"time [ms]\",\"current [kA]\",\"voltage [V]\",\"force [kN]\",\"displacement [mm]\"\n" + signal_rows(","), 0,
         {"R_beta"});
  signal("CurrentInAmperesOverKiloampereData",
         "time [ms], current [A], voltage [V], force [kN], displacement [mm]\n" + signal_rows(), 0, {"warning"});
  c.push_back({"SignalMissingFile", {}, "features absent.csv", 2, {"absent.csv"}});

  // --- Study files (`rsw study show` resolves and checks them without running).
  const auto study = [&](const std::string& name, const std::string& text, std::vector<std::string> named) {
    c.push_back({"Study" + name, {{"case.yaml", paper}, {"study.yaml", text}}, "study show study.yaml", 2,
                 std::move(named)});
  };
  study("Empty", "", {"study.yaml"});
  c.push_back({"StudyRunUnknownFeature",
               {{"case.yaml", paper}, {"study.yaml", study_file(p1_parameter, "  - {name: R_betta}\n")}},
               "study run study.yaml --workers 1", 2, {"study.yaml", "R_betta", "R_beta"}});
  study("PriorBoundsReversed",
        study_file("  - {name: htc_p1, config_key: contact.electrode_sheet.htc_p1, unit: '1', prior: uniform, "
                   "lower: 0.1, upper: 0.01}\n"),
        {"study.yaml", "lower"});
  study("UnknownPriorKind",
        study_file("  - {name: htc_p1, config_key: contact.electrode_sheet.htc_p1, unit: '1', prior: cauchy, "
                   "lower: 0.01, upper: 0.1}\n"),
        {"study.yaml", "cauchy"});
  study("LogPriorThroughZero",
        study_file("  - {name: htc_p1, config_key: contact.electrode_sheet.htc_p1, unit: '1', prior: log10_uniform, "
                   "lower: 0, upper: 0.1}\n"),
        {"study.yaml", "lower"});
  study("DuplicateParameter", study_file(p1_parameter + p1_parameter), {"study.yaml", "htc_p1"});
  study("HugeParameterName",
        study_file("  - {name: " + long_name +
                   ", config_key: contact.electrode_sheet.htc_p1, unit: '1', prior: uniform, lower: 0.01, upper: 0.1}\n"),
        {"study.yaml"});
  c.push_back({"StudyRunWithoutModel",
               {{"study.yaml", "study:\n  name: hostile\nparameters:\n" + p1_parameter +
                                   "features:\n  - {name: R_beta}\ndesign:\n  kind: lhs\n  n_points: 4\n"}},
               "study run study.yaml --workers 1", 2, {"study.yaml", "model.case", "model.command"}});
  study("MissingCase", with(study_file(p1_parameter), "case: case.yaml", "case: nowhere.yaml"), {"nowhere.yaml"});
  study("NegativeDesignSize", with(study_file(p1_parameter), "n_points: 4", "n_points: -4"), {"study.yaml", "n_points"});
  c.push_back({"StudyRunUnknownConfigKey",
               {{"case.yaml", paper},
                {"study.yaml", study_file("  - {name: p, config_key: contact.electrode_sheet.htc_q1, unit: '1', "
                                          "prior: uniform, lower: 0.01, upper: 0.1}\n")}},
               "study run study.yaml --workers 1", 2, {"contact.electrode_sheet.htc_q1"}});

  // --- Calibration sections (`rsw calibrate` checks them before any run).
  const auto calibration = [&](const std::string& name, const std::string& section, std::vector<std::string> named) {
    c.push_back({"Calibration" + name,
                 {{"case.yaml", paper}, {"study.yaml", study_file(p1_parameter, "  - {name: R_beta}\n", section)},
                  {"features.csv", "R_beta\n3.1e-4\n3.0e-4\n"}},
                 "calibrate study.yaml --workers 1", 2, std::move(named)});
  };
  calibration("WithoutObservations", "", {"study.yaml", "calibration"});
  calibration("MissingFeaturesFile", "calibration:\n  observations:\n    features_file: nowhere.csv\n",
              {"nowhere.csv"});
  calibration("UnknownMethod",
              "calibration:\n  method: guess\n  observations:\n    features_file: features.csv\n",
              {"study.yaml", "guess"});
  calibration("UnknownNoiseKind",
              "calibration:\n  observations:\n    features_file: features.csv\n  noise:\n    kind: loud\n",
              {"study.yaml", "loud"});
  calibration("CapBelowTheInitialDesign",
              "calibration:\n  method: emulator\n  observations:\n    features_file: features.csv\n  emulator:\n"
              "    max_evaluations: 5\n",
              {"study.yaml", "max_evaluations"});
  calibration("LogProductOfAnUnknownParameter",
              "calibration:\n  method: emulator\n  observations:\n    features_file: features.csv\n  emulator:\n"
              "    log_products: [{name: r, parameters: htc_p1 * htc_p2}]\n",
              {"study.yaml", "htc_p2", "htc_p1"});
  calibration("LogProductOfOneParameter",
              "calibration:\n  method: emulator\n  observations:\n    features_file: features.csv\n  emulator:\n"
              "    log_products: [{name: r, parameters: htc_p1}]\n",
              {"study.yaml", "two or more"});
  return c;
}

class HostileInputs : public ::testing::TestWithParam<HostileInput> {};

TEST_P(HostileInputs, EndWithTheirExitCodeAndAMessageNamingTheProblem) {
  const HostileInput& input = GetParam();
  const fs::path folder = rsw::testing::fresh_dir("rsw_hostile", input.name);
  for (const auto& [name, text] : input.files) write_file(folder / name, text);
  const auto result = run_command("cd '" + folder.string() + "' && timeout 60 " + rsw_binary + " " + input.arguments);
  const std::string shown = result.output.size() > 2000 ? result.output.substr(0, 2000) + " ..." : result.output;
  EXPECT_NE(result.status, 124) << "hung: " << shown;
  EXPECT_LT(result.status, 128) << "killed by a signal: " << shown;
  EXPECT_EQ(result.status, input.exit_code) << shown;
  for (const std::string& word : input.named) EXPECT_NE(result.output.find(word), std::string::npos)
      << "'" << word << "' not in: " << shown;
  fs::remove_all(folder);
}

INSTANTIATE_TEST_SUITE_P(Rsw, HostileInputs, ::testing::ValuesIn(hostile_inputs()),
                         [](const ::testing::TestParamInfo<HostileInput>& info) { return info.param.name; });

TEST(HostileInputs, AreSixtyOrMore) { EXPECT_GE(hostile_inputs().size(), 60u); }

}  // namespace
