// The coupled weld as a user runs it (rsw simulate on the paper's case, coarse mesh):
// a stored regression reference, the energy balance and readable outputs.
#include "fem/hdf5_file.hpp"
#include "fem/vtk_output.hpp"

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace {
const std::string paper_case = std::string(RSW_SOURCE_DIR) + "/validation/paper_case/weld.yaml";
const std::string coarse_mesh = " --set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1";
const std::string coarse = coarse_mesh + " --set output.interval=10ms";
const std::string coarse_signals_only = coarse_mesh + " --set output.fields=false";  // no field files

int run_command(const std::string& command, std::string& output) {
  const std::string cmd = command + " 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  std::array<char, 4096> buf;
  while (fgets(buf.data(), buf.size(), pipe.get())) output += buf.data();
  return WEXITSTATUS(pclose(pipe.release()));
}

int run_rsw(const std::string& args, std::string& output) {
  return run_command(std::string(RSW_BINARY) + " " + args, output);
}

// The --set arguments of one design point of the Table I studies: the six parameters
// with the keys and units of validation/studies/table1_lhs90*.yaml (film thicknesses
// in m, resistivities in ohm*m, λ_m in W/(m*K)).
std::string table_one_point(const std::string& tf_ss, const std::string& rho_ss, const std::string& tf_es,
                            const std::string& rho_es, const std::string& p1, const std::string& lambda_m) {
  return " --set contact.sheet_sheet.film_thickness=" + tf_ss + "m" +
         " --set \"contact.sheet_sheet.coating_resistivity=" + rho_ss + " ohm*m\"" +
         " --set contact.electrode_sheet.film_thickness=" + tf_es + "m" +
         " --set \"contact.electrode_sheet.coating_resistivity=" + rho_es + " ohm*m\"" +
         " --set contact.electrode_sheet.htc_p1=" + p1 + " --set \"thermal.melt_conductivity=" + lambda_m +
         " W/(m*K)\"";
}

// The reason a failed run wrote into its output folder.
std::string failure_reason(const fs::path& dir) {
  std::ifstream in(dir / "failure.txt");
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Columns of a CSV with a header row ("name [unit]"); lines starting with # skipped.
std::map<std::string, std::vector<double>> read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> names;
  std::map<std::string, std::vector<double>> cols;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    std::vector<std::string> cells;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (names.empty()) {
      names = cells;
      continue;
    }
    for (std::size_t i = 0; i < cells.size() && i < names.size(); ++i)
      cols[names[i]].push_back(cells[i] == "nan" ? std::nan("") : std::stod(cells[i]));
  }
  return cols;
}

// One coarse run of the paper case, shared by the tests below, removed when the test
// process exits; `output` is what rsw printed (stdout and stderr, not a terminal).
struct CoarseRun {
  fs::path dir = fs::temp_directory_path() / ("rsw_weld_" + std::to_string(::getpid()));
  std::string output;
  CoarseRun() {
    fs::remove_all(dir);
    const int status = run_rsw("simulate " + paper_case + " -o " + dir.string() + coarse, output);
    if (status != 0) ADD_FAILURE() << output;
  }
  ~CoarseRun() {
    std::error_code ignored;
    fs::remove_all(dir, ignored);
  }
};
const CoarseRun& coarse_weld() {
  static const CoarseRun run;
  return run;
}
const fs::path& coarse_run() { return coarse_weld().dir; }

// The features (rsw features on its signals.csv) of a coarse signals-only run of the
// paper case with the extra options `sets`, written into `dir`; `summary` receives its
// summary.json when given.
nlohmann::json coarse_features(const fs::path& dir, const std::string& sets, nlohmann::json* summary = nullptr) {
  std::string out;
  const int status = run_rsw("simulate " + paper_case + " -q -o " + dir.string() + coarse_signals_only + sets, out);
  EXPECT_EQ(status, 0) << out;
  std::string fout;
  EXPECT_EQ(run_rsw("features " + (dir / "signals.csv").string() + " -o " + (dir / "features.json").string(), fout), 0)
      << fout;
  std::ifstream fin(dir / "features.json");
  if (summary) {
    std::ifstream sin(dir / "summary.json");
    *summary = nlohmann::json::parse(sin);
  }
  return nlohmann::json::parse(fin).at("features");
}
}  // namespace

TEST(WeldRun, CoarseRunMatchesStoredReference) {
  const auto run = read_csv(coarse_run() / "signals.csv");
  const auto ref = read_csv(std::string(RSW_SOURCE_DIR) + "/tests/data/weld_coarse_reference.csv");
  ASSERT_FALSE(ref.empty()) << "missing tests/data/weld_coarse_reference.csv (tools/regenerate_weld_reference.sh)";
  for (const auto& [name, values] : ref) {
    ASSERT_TRUE(run.count(name)) << name;
    const auto& got = run.at(name);
    ASSERT_EQ(got.size(), values.size()) << name;
    double lo = 1e300, hi = -1e300;
    for (double v : values) lo = std::min(lo, v), hi = std::max(hi, v);
    const double tol = 1e-3 * std::max(hi - lo, 1e-300);
    for (std::size_t i = 0; i < values.size(); ++i)
      EXPECT_NEAR(got[i], values[i], tol) << name << " at row " << i
                                          << " (regenerate only with tools/regenerate_weld_reference.sh)";
  }
}

// Every signal of a coarse run (one thread, signals only), read from results.h5 at full
// precision, equals the stored reference bit for bit. Pins refactorings that must not
// change what the weld computes; a deliberate change regenerates the reference with
// tools/regenerate_weld_reference.sh and says why in its commit. OpenBLAS picks its
// kernels by processor (AVX-512 ones on an Intel Xeon, AVX2 ones on an AMD EPYC of the
// same machine kind), and CHOLMOD's supernodal factorisations round differently with
// each: the run and the reference both use the AVX2 (Haswell) kernels, which every
// x86-64 host of these machines has.
TEST(WeldRun, CoarseRunSignalsAreBitIdenticalToTheStoredReference) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_weld_exact_" + std::to_string(::getpid()));
  std::string out;
  ASSERT_EQ(run_command("OPENBLAS_CORETYPE=Haswell " + std::string(RSW_BINARY) + " --threads 1 simulate " +
                            paper_case + " -q -o " + dir.string() + coarse_signals_only,
                        out),
            0)
      << out;
  std::ifstream in(std::string(RSW_SOURCE_DIR) + "/tests/data/weld_coarse_signals_exact.csv");
  ASSERT_TRUE(in) << "missing tests/data/weld_coarse_signals_exact.csv (tools/regenerate_weld_reference.sh)";
  std::string line;
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    if (names.empty()) {
      while (std::getline(ss, cell, ',')) names.push_back(cell);
      columns.resize(names.size());
      continue;
    }
    for (std::size_t c = 0; std::getline(ss, cell, ','); ++c) columns.at(c).push_back(std::strtod(cell.c_str(), nullptr));
  }
  const rsw::fem::Hdf5File h5(dir / "results.h5", rsw::fem::Hdf5Mode::read);
  EXPECT_EQ(h5.list("/signals").size(), names.size()) << "the signal columns differ from the reference's";
  for (std::size_t c = 0; c < names.size(); ++c) {
    const std::vector<double> got = h5.read_doubles("/signals/" + names[c]);
    ASSERT_EQ(got.size(), columns[c].size()) << names[c];
    for (std::size_t i = 0; i < got.size(); ++i)
      if (!(std::isnan(got[i]) && std::isnan(columns[c][i]))) {
        ASSERT_EQ(got[i], columns[c][i]) << names[c] << " at row " << i << ": differs in the bits";
      }
  }
  fs::remove_all(dir);
}

// What `rsw simulate` prints for a log file: progress in tenths of the weld steps, one
// line each (no carriage returns), then the signals' maxima, the nugget and the energy
// balance, each equal to what the run wrote to signals.csv and summary.json.
TEST(WeldRun, SimulatePrintsKeyResultsAndProgressLinesForALog) {
  const std::string& out = coarse_weld().output;
  EXPECT_EQ(out.find('\r'), std::string::npos);
  std::smatch m;
  const std::regex progress(R"(weld: step \d+/\d+, )");
  const auto progress_lines = std::distance(std::sregex_iterator(out.begin(), out.end(), progress), std::sregex_iterator());
  EXPECT_GE(progress_lines, 10);
  EXPECT_LE(progress_lines, 11);

  const auto signals = read_csv(coarse_run() / "signals.csv");
  const auto& R = signals.at("resistance [ohm]");
  double r_max = 0;
  for (double r : R)
    if (std::isfinite(r)) r_max = std::max(r_max, r);
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(dynamic resistance +([0-9.]+) uOhm at ([0-9.]+) ms)"))) << out;
  EXPECT_NEAR(std::stod(m[1]), r_max * 1e6, 5e-4 * r_max * 1e6);
  const auto& S = signals.at("displacement [m]");
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(electrode displacement +([-0-9.]+) um)"))) << out;
  EXPECT_NEAR(std::stod(m[1]), *std::max_element(S.begin(), S.end()) * 1e6, 0.05);

  std::ifstream in(coarse_run() / "summary.json");
  const auto j = nlohmann::json::parse(in);
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(nugget: d_n,liq ([0-9.]+) mm, h_n,liq ([0-9.]+) mm)"))) << out;
  EXPECT_NEAR(std::stod(m[1]), j.at("nugget").at("d_n_liq").get<double>() * 1e3, 5e-4);
  EXPECT_NEAR(std::stod(m[2]), j.at("nugget").at("h_n_liq").get<double>() * 1e3, 5e-4);
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(energy: electrical ([0-9.]+) J = stored ([0-9.]+) J)"))) << out;
  EXPECT_NEAR(std::stod(m[1]), j.at("energy_J").at("electrical").get<double>(), 0.05);
  // One peak resistance: summary.json's is the printed one, at the printed time.
  EXPECT_NEAR(j.at("dynamic_resistance_peak_ohm").get<double>(), r_max, 1e-9 * r_max);  // signals.csv: 10 digits
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(dynamic resistance +([0-9.]+) uOhm at ([0-9.]+) ms)"))) << out;
  EXPECT_NEAR(std::stod(m[2]), j.at("dynamic_resistance_peak_time_s").get<double>() * 1e3, 5e-4);
  EXPECT_NE(out.find("penetration: sheet_1 "), std::string::npos) << out;
}

// tools/plot_weld.py draws a run, with a measured signal file over its resistance and
// displacement; a file it cannot read is an error naming it.
TEST(WeldRun, PlotScriptOverlaysAMeasuredSignalFileAndNamesOneItCannotRead) {
  std::string check;
  if (run_command("/usr/bin/python3 -c 'import matplotlib, h5py, numpy'", check) != 0) {
    GTEST_SKIP() << "/usr/bin/python3 lacks matplotlib, h5py or numpy (run tools/setup.sh): " << check;
  }
  const std::string source = RSW_SOURCE_DIR;
  const std::string script = "/usr/bin/python3 " + source + "/tools/plot_weld.py " + coarse_run().string();
  const fs::path png = coarse_run() / "overlay.png";
  std::string out;
  ASSERT_EQ(run_command(script + " -o " + png.string() + " --measured " + source +
                            "/validation/signals/measured_example.csv",
                        out),
            0)
      << out;
  EXPECT_NE(out.find("overlaid " + source + "/validation/signals/measured_example.csv"), std::string::npos) << out;
  ASSERT_TRUE(fs::exists(png)) << out;
  EXPECT_GT(fs::file_size(png), 10000u);
  out.clear();
  EXPECT_NE(run_command(script + " -o " + png.string() + " --measured " + source + "/README.md", out), 0);
  EXPECT_NE(out.find("plot_weld: " + source + "/README.md: "), std::string::npos) << out;
}

TEST(WeldRun, EnergyBalanceHoldsWithinOnePercent) {
  std::ifstream in(coarse_run() / "summary.json");
  ASSERT_TRUE(in);
  const auto j = nlohmann::json::parse(in);
  const auto& e = j.at("energy_J");
  const double electrical = e.at("electrical"), stored = e.at("stored"), removed = e.at("removed");
  std::printf("energy: electrical %.2f J = stored %.2f J + removed %.2f J (imbalance %.2e J); nugget holds %.1f %%\n",
              electrical, stored, removed, electrical - stored - removed, 100.0 * e.at("nugget_fraction").get<double>());
  EXPECT_GT(electrical, 0.0);
  EXPECT_LT(std::abs(electrical - stored - removed), 0.01 * electrical);
}

// summary.json counts the thermal linear algebra: every weld step factorises its first
// tangent, every factorisation serves at least one solve, and every electro-thermal
// coupling iterate solves at least one thermal correction.
TEST(WeldRun, SummaryCountsThermalSolvesAndFactorisations) {
  std::ifstream in(coarse_run() / "summary.json");
  ASSERT_TRUE(in);
  const auto j = nlohmann::json::parse(in);
  const long steps = j.at("weld_steps"), coupling = j.at("coupling_iterations");
  const long solves = j.at("thermal_linear_algebra").at("solves");
  const long factorisations = j.at("thermal_linear_algebra").at("factorisations");
  EXPECT_GE(factorisations, steps);
  EXPECT_GE(solves, factorisations);
  EXPECT_GE(solves, coupling);
}

TEST(WeldRun, FieldsOpenInVtkAndSignalsInHdf5) {
  const auto steps = rsw::fem::read_pvd(coarse_run() / "fields.pvd");
  ASSERT_EQ(steps.size(), 17u);  // 0, 10, ..., 160 ms
  const auto last = rsw::fem::read_vtm(steps[10].file);
  const auto& sheet = last.block("sheet_1");
  for (const char* a : {"temperature", "potential", "peak_temperature", "liquid_fraction", "displacement"})
    EXPECT_EQ(sheet.point_array(a).n_tuples(), sheet.n_points) << a;
  for (const char* a : {"current_density", "joule_heat", "von_mises_stress", "equivalent_plastic_strain"})
    EXPECT_EQ(sheet.cell_array(a).n_tuples(), sheet.n_cells) << a;
  rsw::fem::Hdf5File h5(coarse_run() / "results.h5", rsw::fem::Hdf5Mode::read);
  EXPECT_EQ(h5.read_doubles("/signals/voltage").size(), 17u);
  EXPECT_GT(h5.read_scalar("/nugget/d_n_liq"), 0.0);  // a true scalar, shape ()
  EXPECT_EQ(h5.shape("/nugget/d_n_liq"), std::vector<std::size_t>{});
  // Every dataset carries a description; those with a dimension a unit.
  for (const char* path : {"/signals/voltage", "/signals/temperature", "/nugget/d_n_liq", "/energy/stored",
                           "/squeeze/force", "/run/config"})
    EXPECT_FALSE(h5.string_attribute(path, "description").empty()) << path;
  EXPECT_EQ(h5.string_attribute("/signals/temperature", "unit"), "degC");
  std::string out;
  EXPECT_EQ(std::system(("h5dump -H " + (coarse_run() / "results.h5").string() + " > /dev/null").c_str()), 0);
}

// The electrodes press on the sheets throughout, so the electrode/sheet contact radii
// stay positive and do not shrink while the current flows (the contact grows as the
// sheets soften), also once the contact reaches the last paired points near the face
// edge.
TEST(WeldRun, ElectrodeContactRadiusStaysPositiveUnderForce) {
  const auto run = read_csv(coarse_run() / "signals.csv");
  for (const char* name : {"contact_radius_es_upper [m]", "contact_radius_es_lower [m]"}) {
    ASSERT_TRUE(run.count(name)) << name;
    const auto& radius = run.at(name);
    const auto& current = run.at("current [A]");
    for (std::size_t i = 1; i < radius.size(); ++i) {
      EXPECT_GT(radius[i], 0.5e-3) << name << " at row " << i;
      if (current[i] > 0 && current[i - 1] > 0) {
        EXPECT_GE(radius[i], radius[i - 1] - 1e-6) << name << " at row " << i;
      }
    }
  }
  std::ifstream in(coarse_run() / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_GT(j.at("nugget").at("w_elec").get<double>(), 2 * 0.5e-3);
}

// The sheet/sheet contact radius covers the fused region: inside the nugget the
// sheets are bonded (held in slight tension by the expanding melt, a gap of
// nanometres), and bonded points count as closed. At the end of the coarse weld the
// radius reaches at least 90 % of the solidus nugget's radius (it stopped at 1.6 of
// 2.8 mm when only compressed points counted).
TEST(WeldRun, SheetContactRadiusCoversTheFusedNugget) {
  const auto run = read_csv(coarse_run() / "signals.csv");
  const double radius = run.at("contact_radius_ss_1_2 [m]").back();
  const double nugget = 0.5 * run.at("d_n_sol [m]").back();
  EXPECT_GT(nugget, 2e-3);
  EXPECT_GT(radius, 0.9 * nugget) << "S/S contact radius " << radius << " m, nugget radius " << nugget << " m";
  EXPECT_LT(radius, 1.2 * nugget);
}

// A very resistive electrode/sheet film that does not break down (t_f = 0.03 mm,
// contact.film_breakdown=false) heats the electrode face to the CuCrZr solidus about
// 19 ms into the weld. By default the run records that as a
// warning (summary.json, results.h5) and finishes; with solver.electrode_melting=stop
// it fails there, naming the electrode.
TEST(WeldRun, ElectrodeReachingSolidusWarnsOrStopsAsConfigured) {
  const std::string args = " -q" + coarse_signals_only +
                           " --set contact.electrode_sheet.film_thickness=0.03mm --set contact.film_breakdown=false"
                           " --set \"schedule.current=[[0 ms,0 kA],[10 ms,8 kA],[30 ms,8 kA],[31 ms,0 kA]]\""
                           " --set \"schedule.force=[[0 ms,3 kN],[31 ms,3 kN]]\" --set schedule.cool_time=0ms";
  const fs::path base = fs::temp_directory_path() / ("rsw_melting_" + std::to_string(::getpid()));
  std::string out;
  ASSERT_EQ(run_rsw("simulate " + paper_case + " -o " + (base / "continue").string() + args, out), 0) << out;
  EXPECT_NE(out.find("warning: at t = "), std::string::npos) << out;
  std::ifstream in(base / "continue" / "summary.json");
  const auto j = nlohmann::json::parse(in);
  // The electrode's warning first; the film also burns the nugget through the stack
  // (the plausibility guard's warnings follow, ExtremeSchedule... below).
  ASSERT_GE(j.at("warnings").size(), 1u);
  EXPECT_NE(j.at("warnings")[0].get<std::string>().find("above the solidus"), std::string::npos);
  for (std::size_t k = 1; k < j.at("warnings").size(); ++k) {
    const std::string w = j.at("warnings")[k].get<std::string>();
    EXPECT_TRUE(w.rfind("plausibility: ", 0) == 0 || w.rfind("numerics: ", 0) == 0) << w;
  }
  const double t_melt = j.at("electrode_melting_time_s").get<double>();
  EXPECT_GT(t_melt, 0.010);
  EXPECT_LT(t_melt, 0.031);
  rsw::fem::Hdf5File h5(base / "continue" / "results.h5", rsw::fem::Hdf5Mode::read);
  EXPECT_EQ(h5.read_doubles("/signals/voltage").size(), read_csv(base / "continue" / "signals.csv").at("time [s]").size());

  out.clear();
  EXPECT_NE(run_rsw("simulate " + paper_case + " -o " + (base / "stop").string() + args +
                        " --set solver.electrode_melting=stop", out), 0);
  EXPECT_NE(out.find("above the solidus of its material"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(base / "stop" / "summary.json"));
  fs::remove_all(base);
}

// A weld step whose electro-thermal coupling fails whole is solved in parts, a finer
// time discretisation than its neighbours' in the parameters get: the run says so. With
// at most 3 coupling iterations per attempt (the default allows 60) steps that need
// more are split; summary.json counts the splits and carries one "numerics: " warning
// with that count and the end of the first such step; the same weld with the default
// budget splits none and has no such warning.
TEST(WeldRun, StepsSolvedInPartsAreReportedAsANumericsWarning) {
  const std::string args = " -q" + coarse_signals_only +
                           " --set \"schedule.current=[[0 ms,0 kA],[10 ms,8 kA],[30 ms,8 kA],[31 ms,0 kA]]\""
                           " --set \"schedule.force=[[0 ms,3 kN],[31 ms,3 kN]]\" --set schedule.cool_time=0ms";
  const fs::path base = fs::temp_directory_path() / ("rsw_split_" + std::to_string(::getpid()));
  const auto numerics_warnings = [](const nlohmann::json& j) {
    std::vector<std::string> found;
    for (const auto& w : j.at("warnings"))
      if (w.get<std::string>().rfind("numerics: ", 0) == 0) found.push_back(w.get<std::string>());
    return found;
  };
  std::string out;
  ASSERT_EQ(run_rsw("simulate " + paper_case + " -o " + (base / "split").string() + args +
                        " --set solver.max_coupling_iterations=3", out), 0) << out;
  std::ifstream in(base / "split" / "summary.json");
  const auto j = nlohmann::json::parse(in);
  const int splits = j.at("coupling_substep_splits").get<int>();
  ASSERT_GT(splits, 0);
  const auto warned = numerics_warnings(j);
  ASSERT_EQ(warned.size(), 1u) << j.at("warnings").dump(1);
  EXPECT_NE(warned[0].find("did not converge on a whole weld step " + std::to_string(splits) + " time"),
            std::string::npos) << warned[0];
  EXPECT_NE(warned[0].find(" ms), so those steps were solved in parts"), std::string::npos) << warned[0];

  ASSERT_EQ(run_rsw("simulate " + paper_case + " -o " + (base / "whole").string() + args, out), 0) << out;
  std::ifstream in_whole(base / "whole" / "summary.json");
  const auto whole = nlohmann::json::parse(in_whole);
  EXPECT_EQ(whole.at("coupling_substep_splits").get<int>(), 0);
  EXPECT_TRUE(numerics_warnings(whole).empty()) << whole.at("warnings").dump(1);
  fs::remove_all(base);
}

// 14 kA for 50 ms (the issue's extreme schedule, shortened) passes every bound of the
// plausibility guard (physics/plausibility.hpp) on the coarse mesh: the nugget 6.5 mm
// under a 5.5 mm face and 2.3 mm tall in a 2 mm stack, the sheets above iron's boiling
// point. The run succeeds; summary.json and results.h5 carry one warning per bound.
TEST(WeldRun, ExtremeScheduleSucceedsWithAWarningPerImplausibleResult) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_implausible_" + std::to_string(::getpid()));
  std::string out;
  ASSERT_EQ(run_rsw("simulate " + paper_case + " -q -o " + dir.string() + coarse_signals_only +
                        " --set output.interval=10ms"
                        " --set \"schedule.current=[[0 ms,0 kA],[10 ms,14 kA],[60 ms,14 kA],[61 ms,0 kA]]\""
                        " --set \"schedule.force=[[0 ms,3 kN],[61 ms,3 kN]]\" --set schedule.cool_time=0ms",
                    out),
            0)
      << out;
  std::ifstream in(dir / "summary.json");
  const auto j = nlohmann::json::parse(in);
  std::vector<std::string> implausible;
  for (const auto& w : j.at("warnings"))
    if (w.get<std::string>().rfind("plausibility: ", 0) == 0) implausible.push_back(w.get<std::string>());
  ASSERT_EQ(implausible.size(), 6u) << j.at("warnings").dump(1);
  EXPECT_NE(implausible[0].find("wider than the electrode face (5.50 mm)"), std::string::npos) << implausible[0];
  EXPECT_NE(implausible[1].find("taller than the sheet stack (2.00 mm)"), std::string::npos) << implausible[1];
  EXPECT_NE(implausible[2].find("penetrates sheet_1"), std::string::npos) << implausible[2];
  EXPECT_NE(implausible[3].find("penetrates sheet_2"), std::string::npos) << implausible[3];
  EXPECT_NE(implausible[4].find("above the boiling point of its material (2861 degC, DP1200)"), std::string::npos)
      << implausible[4];
  EXPECT_NE(implausible[5].find("sheet_2 reaches"), std::string::npos) << implausible[5];
  EXPECT_GT(j.at("nugget").at("d_n_liq").get<double>(), 5.5e-3);
  const rsw::fem::Hdf5File h5(dir / "results.h5", rsw::fem::Hdf5Mode::read);
  const std::string stored = h5.string_attribute("/run", "warnings");
  for (const auto& w : implausible) EXPECT_NE(stored.find(w), std::string::npos) << w;
  EXPECT_NE(out.find("warning: plausibility: the nugget"), std::string::npos) << out;
  fs::remove_all(dir);
}

// The same schedule as a two-run study: both runs succeed and the study's run table
// (CSV and JSON) carries each run's plausibility warnings.
TEST(WeldRun, StudyRunTableCarriesThePlausibilityWarningsOfEachRun) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_implausible_study_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "hot.yaml") << "study: {name: hot, description: two short 14 kA welds, output: out}\n"
                                     "parameters:\n"
                                     "  - {name: film_thickness_es, config_key: contact.electrode_sheet.film_thickness,"
                                     " unit: m, prior: log10_uniform, lower: 1e-4 mm, upper: 1e-3 mm}\n"
                                     "design: {kind: lhs, n_points: 2, seed: 1}\n"
                                     "features: [{name: T_max}]\n"
                                     "model:\n"
                                     "  case: " << paper_case << "\n"
                                     "  set:\n"
                                     "    - {key: mesh.base_size, value: 0.5 mm}\n"
                                     "    - {key: mesh.weld_zone.levels, value: '1'}\n"
                                     "    - {key: output.fields, value: 'false'}\n"
                                     "    - {key: output.interval, value: 10 ms}\n"
                                     "    - {key: schedule.current, value: '[[0 ms,0 kA],[10 ms,14 kA],[60 ms,14 kA],[61 ms,0 kA]]'}\n"
                                     "    - {key: schedule.force, value: '[[0 ms,3 kN],[61 ms,3 kN]]'}\n"
                                     "    - {key: schedule.cool_time, value: 0 ms}\n";
  std::string out;
  ASSERT_EQ(run_rsw("study run " + (dir / "hot.yaml").string() + " --workers 2 -q", out), 0) << out;
  std::ifstream in(dir / "out" / "hot_runs.json");
  const auto runs = nlohmann::json::parse(in).at("runs");
  ASSERT_EQ(runs.size(), 2u);
  for (const auto& run : runs) {
    EXPECT_EQ(run.at("status"), "ok");
    const std::string warnings = run.value("warnings", "");
    EXPECT_NE(warnings.find("plausibility: the nugget (d_n_liq"), std::string::npos) << warnings;
    EXPECT_NE(warnings.find("above the boiling point"), std::string::npos) << warnings;
  }
  std::ifstream csv(dir / "out" / "hot_runs.csv");
  const std::string table((std::istreambuf_iterator<char>(csv)), std::istreambuf_iterator<char>());
  std::size_t rows = 0;
  for (std::size_t at = table.find("plausibility: sheet_1 reaches"); at != std::string::npos;
       at = table.find("plausibility: sheet_1 reaches", at + 1))
    ++rows;
  EXPECT_EQ(rows, 2u) << table;
  fs::remove_all(dir);
}

// With a still more resistive film (t_f = 0.3 mm) the upper electrode's face melts at
// about 7 ms; the run goes on (the default). A current raised tenfold at 31 ms then makes
// it fail for certain (at 31 ms: whichever stage gives way first). The failure message
// says when and where the electrode had first melted, whatever stage fails, because the
// failure most likely follows from it. (The film alone does not fail the run reliably:
// such a run fails or runs through on round-off, e.g. at 27 ms with
// solver.friction_penalty_ratio = 1, at 149 ms with the default, not at all with
// t_f = 0.5 mm.)
TEST(WeldRun, FailureAfterElectrodeMeltingSaysWhenTheElectrodeMelted) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_melted_" + std::to_string(::getpid()));
  std::string out;
  EXPECT_NE(run_rsw("simulate " + paper_case + " -q -o " + dir.string() + coarse_signals_only +
                        " --set contact.electrode_sheet.film_thickness=0.3mm"
                        " --set 'schedule.current=[[0 ms, 0 kA], [10 ms, 8 kA], [30 ms, 8 kA], [31 ms, 80 kA],"
                        " [150 ms, 80 kA], [151 ms, 0 kA]]'",
                    out),
            0);
  const std::string failure = failure_reason(dir);
  EXPECT_NE(failure.find("after an electrode had melted, at t = "), std::string::npos) << failure;
  EXPECT_NE(out.find("after an electrode had melted, at t = "), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
  fs::remove_all(dir);
}

// Design point 58 of the coarse Table I study (a resistive S/S film, t_f = 0.088 mm,
// and the E/S film of a clean face): the sheets start to melt at the S/S contact 14–15
// ms into the weld, and the thermal Newton must converge there. With chord steps kept
// while the corrections only halve it stalls at 15 ms, 40 iterations with corrections
// of 7.7 K, and so do nine more runs of that study (19 of 90 fail against 9);
// refactorising unless they shrink fourfold converges. Whether
// this one point stalls depends on round-off (it ran through with the schedule cut
// after 21 ms); the study's count does not. The whole weld, as in the study (~3 s).
TEST(WeldRun, ThermalNewtonConvergesThroughTheMeltingOnsetAtAResistiveSheetFilm) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_point58_" + std::to_string(::getpid()));
  std::string out;
  EXPECT_EQ(run_rsw("simulate " + paper_case + " -q -o " + dir.string() + coarse_signals_only +
                        " --set output.interval=1ms" +
                        table_one_point("8.7696639927009923e-05", "1.6688925344824186e-06",
                                        "4.9795985381882547e-07", "5.5068530847861315e-07",
                                        "0.010228694543108116", "161.21747493158483"),
                    out),
            0)
      << out;
  const auto run = read_csv(dir / "signals.csv");
  EXPECT_GT(run.at("d_n_liq [m]").back(), 0.0);  // the sheets did melt
  fs::remove_all(dir);
}

// Design point 20 of the coarse Table I study (a resistive E/S film: t_f,E/S =
// 1.5·10⁻⁵ m, ρ_c,E/S = 1.6·10⁻⁵ Ω·m) melts the upper electrode's face at 9.8 ms and
// goes on (solver.electrode_melting = continue). At 18.5 ms the thermal Newton
// iteration of a loose coupling iterate (tolerance 0.1 K) cycled for 40 iterations
// with corrections of about 8 K: corrections below 100 times the solve's tolerance
// were taken whole without the descent check, and 10 K is as wide as copper's melting
// range, where the S-shaped enthalpy sends a full step past the root. The descent check
// now skips only corrections within 100 times the strict tolerance, and the weld
// finishes. (~3.5 s, the whole coarse weld as in the study.)
TEST(WeldRun, ThermalNewtonChecksDescentOfCorrectionsAsWideAsAMeltingRange) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_point20_" + std::to_string(::getpid()));
  std::string out;
  EXPECT_EQ(run_rsw("simulate " + paper_case + " -q -o " + dir.string() + coarse_signals_only +
                        " --set output.interval=1ms" +
                        table_one_point("2.404566119469432e-07", "8.6811045628913567e-07",
                                        "1.4596888669164112e-05", "1.5741863193175545e-05",
                                        "0.043405289627226999", "142.25126753931374"),
                    out),
            0)
      << out;
  const auto run = read_csv(dir / "signals.csv");
  EXPECT_NEAR(run.at("time [s]").back(), 0.160, 1e-9);  // the whole schedule
  std::ifstream summary(dir / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("a melting electrode is outside the model"), std::string::npos);  // the warning stays
  fs::remove_all(dir);
}

// The coarse Table I study (90 welds over the paper's prior, about 2 min on two cores)
// as a check of robustness: a solver change that leaves the default weld equal to
// 10⁻⁶ can still change which runs of the prior finish (a thermal chord policy that
// stalls at melting onsets fails 19, one of them, design point 58, with no melting
// electrode; looser GMRES tolerances in the mechanics fail 2: docs/PERFORMANCE.md).
// Every run it fails must have melted an electrode first (the resistive end of the
// E/S film prior, outside the model), and at most 2 may fail: the current build fails
// 1, whose electrode melts 4 ms into the weld and whose fate depends on round-off
// (docs/STUDIES.md).
TEST(WeldRun, CoarseTableOneStudyFailsOnlyRunsWhoseElectrodeMelted) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_study_" + std::to_string(::getpid()));
  std::string out;
  ASSERT_EQ(run_rsw("study run " + std::string(RSW_SOURCE_DIR) +
                        "/validation/studies/table1_lhs90_coarse.yaml --workers 2 -q -o " + dir.string(),
                    out),
            0)
      << out;
  std::smatch done;
  ASSERT_TRUE(std::regex_search(out, done, std::regex(R"(90/90 runs done .*, (\d+) failed)"))) << out;
  const int failed = std::stoi(done[1]);
  EXPECT_LE(failed, 2) << out;
  int reasons = 0;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);)
    if (line.find("failed run ") != std::string::npos) {
      ++reasons;
      EXPECT_TRUE(line.find("after an electrode had melted") != std::string::npos ||
                  line.find("above the solidus of its material") != std::string::npos)
          << line;
    }
  EXPECT_EQ(reasons, failed) << out;
  fs::remove_all(dir);
}

// A very resistive S/S film (run 76 of the paper-mesh Table I study: t_f,S/S = 5.6·10⁻⁵ m,
// ρ_c,S/S = 1.8·10⁻⁵ Ω·m) melts the sheets first at the edge of their contact. With the
// one-pass S/S contact, and the sheets bonding across any gap (contact.bonding_gap
// 1 mm), the bottom cell of sheet_1 beyond the edge of the bonded region, 62.5 µm on
// the paper's mesh (r ≈ 2 mm), is sheared until one corner folds, 50 ms into the weld,
// while its quadrature-point Jacobians stay positive. (With the default bonding gap of 1 µm this
// weld finishes, its worst cell at 0.53.) Without the check such a run would go on for
// tens of milliseconds on the folded cell, whose conductance entries grow to 10¹³
// times the others'. The run must fail there, saying where and when, and leave no
// summary that looks valid. (~25 s: the paper's mesh; the coarse mesh's 125 µm cells
// do not fold. Uniform 1 ms steps and the 1 µm contact start of the law this case was
// found with; with the default 30 µm the same weld folds a cell of sheet_2 at
// r = 2.36 mm, 118 ms into the weld.)
TEST(WeldRun, FoldedCellFailsTheRunSayingWhereAndWhen) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_folded_" + std::to_string(::getpid()));
  std::string out;
  EXPECT_NE(run_rsw("simulate " + paper_case + " -q -o " + dir.string() +
                        " --set output.fields=false --set solver.sheet_contact=one_pass --set solver.early_phase_end=0ms"
                        " --set solver.contact_smoothing=1um"
                        " --set contact.sheet_sheet.htc_p1=0.0044651318755885372 --set contact.bonding_gap=1000um" +
                        table_one_point("5.6475400103189882e-05", "1.8492459486106656e-05",
                                        "2.5620235367893057e-07", "5.9803569934488761e-07",
                                        "0.0044651318755885372", "86.956956302646873"),
                    out),
            0);
  const std::string failure = failure_reason(dir);
  EXPECT_NE(failure.find("the deformed mesh has folded: cell"), std::string::npos) << failure;
  // where: a sheet cell at the edge of the bonded region, r ≈ 2 mm (the stack is
  // symmetric about the interface, so which sheet folds first is round-off)
  double r = 0, z = 0;
  int sheet = 0;
  const auto at = failure.find("of sheet_");
  ASSERT_NE(at, std::string::npos) << failure;
  ASSERT_EQ(std::sscanf(failure.c_str() + at, "of sheet_%d at (r, z) = (%lf, %lf)", &sheet, &r, &z), 3) << failure;
  EXPECT_TRUE(sheet == 1 || sheet == 2) << failure;
  EXPECT_GT(r, 1.9) << failure;
  EXPECT_LT(r, 2.1) << failure;
  // when: with uniform 1 ms steps, weld step n ends at n ms
  int step = 0;
  double t_ms = 0;
  const auto when = failure.find("weld stage, step ");
  ASSERT_NE(when, std::string::npos) << failure;
  ASSERT_EQ(std::sscanf(failure.c_str() + when, "weld stage, step %d (t = %lf ms)", &step, &t_ms), 2) << failure;
  EXPECT_GT(step, 20) << failure;
  EXPECT_DOUBLE_EQ(t_ms, step) << failure;
  EXPECT_NE(out.find("the deformed mesh has folded"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
  fs::remove_all(dir);
}

// Smoothness in the parameters (docs/MODEL.md, "Known limitations"; the paper's
// Fig. 6), measured where calibration needs it:
// R_γ, T_max (features of the signal file) and d_n,sol (summary.json) at five values
// of the E/S thermal contact constant P1 spaced 0.01 apart in log10 around the
// default (1e-2), coarse mesh. A smooth response has second differences of order
// f''·h², numerical noise (elements counted, a step schedule or mesh that moves with
// θ, loose tolerances) second differences of the noise's size whatever h. The
// spacing is 0.01, not 0.02: R_γ rises steeply just below the default and levels off
// at log10 P1 ≈ −1.98 (12 runs 0.01 apart from −2.06: 111.0, 111.7, 112.5, 113.4,
// 114.1, 114.7, 115.6, 116.4, 116.9, 117.04, 117.09, 117.15 µΩ: a smooth knee, where
// the end-of-weld growth of the E/S contact stops reaching the end of the feature
// window), and at 0.02 the knee's curvature alone gives 13 % of the change over the
// prior. Measured: R_γ 1.4 %, T_max, d_n,sol and h_n,liq (on the axis) 0.1–0.2 % of
// their change over the whole prior, P1 from 1e-3 to 1e-1; the remainder is of contact-front and bonding
// events that happen per point and per time step. The bound, 10 %, is the
// resolution a Gaussian-process surrogate with a nugget needs to see the trend.
TEST(WeldRun, NumericalNoiseInP1IsSmallAgainstTheChangeOverThePrior) {
  const fs::path base = fs::temp_directory_path() / ("rsw_smooth_" + std::to_string(::getpid()));
  auto features_at = [&](double p1, const std::string& tag) {
    char value[32];
    std::snprintf(value, sizeof value, "%.12g", p1);
    nlohmann::json summary;
    const auto features =
        coarse_features(base / tag, std::string(" --set contact.electrode_sheet.htc_p1=") + value, &summary);
    return std::array<double, 4>{features.at("R_gamma").at("value").get<double>(),
                                 features.at("T_max").at("value").get<double>(),
                                 summary.at("nugget").at("d_n_sol").get<double>(),
                                 summary.at("nugget").at("h_n_liq").get<double>()};
  };
  std::vector<std::array<double, 4>> sweep;
  for (int k = 0; k < 5; ++k) sweep.push_back(features_at(std::pow(10.0, -2.0 + 0.01 * k), "p" + std::to_string(k)));
  const auto low = features_at(1e-3, "low"), high = features_at(1e-1, "high");
  const char* names[] = {"R_gamma", "T_max", "d_n_sol", "h_n_liq"};
  for (int f = 0; f < 4; ++f) {
    double noise = 0;
    for (int k = 0; k + 2 < 5; ++k)
      noise = std::max(noise, std::abs(sweep[k + 2][f] - 2 * sweep[k + 1][f] + sweep[k][f]));
    const double change = std::abs(high[f] - low[f]);
    EXPECT_GT(change, 0.0) << names[f];
    EXPECT_LT(noise, 0.1 * change) << names[f] << ": largest second difference " << noise
                                   << ", change over the prior " << change;
    std::printf("%s: largest second difference %.4g, change over the prior %.4g (%.1f %%)\n", names[f], noise, change,
                100 * noise / change);
  }
  fs::remove_all(base);
}

// Backward Euler is first order in the time step, and so is the coupled weld: the
// coarse case at uniform steps (no early phase) of 1, 0.5 and 0.25 ms (the table
// breakpoints and output times are steps in every run) gives observed orders
// log2(|f(1) − f(½)| / |f(½) − f(¼)|) of 0.77 for the electrical energy ∫VI dt and 1.18
// for R_α, the point of steepest rise. The peak R_β and the mean
// R_m of the 1 ms signals (orders 0.81 and 0.75 there) are not asserted: on this mesh
// the contact fronts advance by whole cell faces, each a step in R (docs/
// VERIFICATION.md, "Time-step error"); they are printed with the error of uniform 1 ms
// steps, f(1) − f(0) with f(0) extrapolated at first order as 2 f(¼) − f(½).
TEST(WeldRun, ElectricalEnergyAndResistanceRiseConvergeAtFirstOrderInTheTimeStep) {
  const fs::path base = fs::temp_directory_path() / ("rsw_dt_" + std::to_string(::getpid()));
  const char* names[] = {"electrical energy", "R_alpha", "R_beta", "R_m"};
  auto features_at = [&](const std::string& step) {
    nlohmann::json summary;
    const auto features =
        coarse_features(base / step, " --set solver.early_phase_end=0ms --set solver.time_step=" + step + "ms", &summary);
    return std::array<double, 4>{summary.at("energy_J").at("electrical").get<double>(),
                                 features.at(names[1]).at("value").get<double>(),
                                 features.at(names[2]).at("value").get<double>(),
                                 features.at(names[3]).at("value").get<double>()};
  };
  const auto f1 = features_at("1"), f2 = features_at("0.5"), f4 = features_at("0.25");
  for (int k = 0; k < 4; ++k) {
    const double d1 = f1[k] - f2[k], d2 = f2[k] - f4[k];
    ASSERT_NE(d2, 0.0) << names[k];
    const double order = std::log2(std::abs(d1 / d2));
    const double limit = 2 * f4[k] - f2[k];
    std::printf("%s: %.6g, %.6g, %.6g at 1, 0.5, 0.25 ms; observed order %.2f; error at 1 ms %.2f %%\n", names[k],
                f1[k], f2[k], f4[k], order, 100 * (f1[k] - limit) / limit);
    EXPECT_GT(d1 * d2, 0.0) << names[k] << ": the differences change sign (" << d1 << ", " << d2 << ")";
    if (k >= 2) continue;
    EXPECT_GT(order, 0.7) << names[k];
    EXPECT_LT(order, 1.7) << names[k];
  }
  fs::remove_all(base);
}

// One feature extractor for simulated and measured signals: rsw features reads the
// signals.csv that rsw simulate writes (its resistance column is nan where no current
// flows; V/I is formed from the voltage and current columns instead).
TEST(WeldRun, FeaturesReadTheSimulatedSignalFile) {
  std::string out;
  ASSERT_EQ(run_rsw("features " + (coarse_run() / "signals.csv").string(), out), 0) << out;
  EXPECT_NE(out.find("R_beta"), std::string::npos) << out;
  EXPECT_NE(out.find("dS_P"), std::string::npos) << out;
}

// The melt's numerical regularisation (docs/MECHANICS.md, "Rate dependence";
// materials/data/DP1200.yaml): the sheet steel's strength floor and its viscosity at the
// solidus stand in for a liquid that has neither. The displacement signal must not
// depend on them: with the shipped 5 MPa and 0.3 MPa·s, the peak expansion and the final
// displacement of the coarse weld stay within 5 % of a copy with 2 MPa and 0.01 MPa·s
// (validation/melt_regularisation/README.md; 20 MPa and 1 MPa·s are 10 % off).
TEST(WeldRun, DisplacementWithinFivePercentOfItsValueWithoutMeltRegularisation) {
  const fs::path base = fs::temp_directory_path() / ("rsw_melt_reg_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base / "materials");
  std::ifstream in(std::string(RSW_SOURCE_DIR) + "/materials/data/DP1200.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto replace_once = [&text](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << "DP1200.yaml no longer holds '" << from << "'";
    ASSERT_EQ(text.find(from, at + 1), std::string::npos) << "'" << from << "' twice in DP1200.yaml";
    text.replace(at, from.size(), to);
  };
  replace_once("\nname: DP1200\n", "\nname: DP1200_unregularised\n");
  replace_once("\n  yield_stress: 5 MPa\n", "\n  yield_stress: 2 MPa\n");
  replace_once("\n    - [1470 degC, 0.3 MPa*s]\n", "\n    - [1470 degC, 0.01 MPa*s]\n");
  std::ofstream(base / "materials" / "DP1200_unregularised.yaml") << text;

  const auto shipped = coarse_features(base / "shipped", "");
  ASSERT_EQ(::setenv("RSW_MATERIALS_PATH", (base / "materials").c_str(), 1), 0);
  const auto limit = coarse_features(base / "unregularised",
                                     " --set 'stack.sheets=[{material: DP1200_unregularised, thickness: 1.0 mm}, "
                                     "{material: DP1200_unregularised, thickness: 1.0 mm}]'");
  ::unsetenv("RSW_MATERIALS_PATH");
  for (const char* name : {"dS_P", "S_end"}) {
    const double a = shipped.at(name).at("value").get<double>(), b = limit.at(name).at("value").get<double>();
    std::printf("%s: %.2f um shipped, %.2f um without regularisation (%+.1f %%)\n", name, a * 1e6, b * 1e6,
                100 * (a / b - 1));
    EXPECT_LT(std::abs(a / b - 1), 0.05) << name;
  }
  fs::remove_all(base);
}

// A step whose electro-thermal coupling does not converge is solved in halves (down to
// 1/16 step) and the run goes on; the schedule and the output times stay as they are.
// Design point 13 of the Table I study (a resistive E/S film, t_f = 0.48 mm, ρ_c =
// 1.5·10⁻⁵ Ω·m) on the coarse mesh, with the coupling capped at 8 iterations, needs
// such halves in several steps; its features stay within 1 % of the same weld with
// the default cap (60), which needs none, and its signals keep the same times.
TEST(WeldRun, CouplingThatFailsInAStepIsSolvedInHalvesWithTheSameResult) {
  const fs::path base = fs::temp_directory_path() / ("rsw_halves_" + std::to_string(::getpid()));
  const std::string films =
      " --set contact.electrode_sheet.film_thickness=0.4814mm"
      " --set contact.electrode_sheet.coating_resistivity=1.519e-5ohm*m"
      " --set contact.electrode_sheet.htc_p1=0.008342"
      " --set contact.sheet_sheet.film_thickness=0.0168mm"
      " --set contact.sheet_sheet.coating_resistivity=6.33e-7ohm*m";
  nlohmann::json whole_summary, halves_summary;
  const auto whole = coarse_features(base / "whole", films, &whole_summary);
  const auto halves = coarse_features(base / "halves", films + " --set solver.max_coupling_iterations=8", &halves_summary);
  EXPECT_EQ(whole_summary.at("coupling_substep_splits").get<int>(), 0);
  EXPECT_GT(halves_summary.at("coupling_substep_splits").get<int>(), 0);
  std::printf("coupling capped at 8 iterations: %d halved parts\n",
              halves_summary.at("coupling_substep_splits").get<int>());
  for (const char* name : {"R_beta", "R_gamma", "dS_P", "T_max", "T_end"}) {
    const double a = whole.at(name).at("value").get<double>(), b = halves.at(name).at("value").get<double>();
    std::printf("%s: %.6g whole steps, %.6g with halves (%+.2f %%)\n", name, a, b, 100 * (b / a - 1));
    EXPECT_LT(std::abs(b / a - 1), 0.01) << name;
  }
  for (const char* name : {"d_n_liq", "h_n_liq"}) {
    const double a = whole_summary.at("nugget").at(name).get<double>(), b = halves_summary.at("nugget").at(name).get<double>();
    std::printf("%s: %.6g whole steps, %.6g with halves (%+.2f %%)\n", name, a, b, 100 * (b / a - 1));
    EXPECT_LT(std::abs(b / a - 1), 0.01) << name;
  }
  EXPECT_EQ(read_csv(base / "whole" / "signals.csv").at("time [s]"),
            read_csv(base / "halves" / "signals.csv").at("time [s]"));
  fs::remove_all(base);
}

// Where a step's Anderson iteration does not converge, Newton's method on T − G(T)
// (physics/electro_thermal_step.hpp) solves it before any other retry, so the step
// keeps its length. Design point 85 of the Table I study on the coarse mesh has one
// such step: Newton converges there, no Anderson retry and no halves are needed, and
// the weld's energy balances (electrical = stored + removed) to 10⁻⁷ of its energy,
// as the welds of that study whose steps all converge at once do (1.3·10⁻⁸ here, at
// most 7·10⁻⁸ among them).
TEST(WeldRun, CouplingStepThatAndersonCannotSolveIsSolvedWholeByNewton) {
  const fs::path base = fs::temp_directory_path() / ("rsw_newton_" + std::to_string(::getpid()));
  const std::string point =
      " --set contact.sheet_sheet.film_thickness=7.924078053928453e-07m"
      " --set 'contact.sheet_sheet.coating_resistivity=1.3205149757123101e-05ohm*m'"
      " --set contact.electrode_sheet.film_thickness=0.0001187305645988809m"
      " --set 'contact.electrode_sheet.coating_resistivity=3.179198417006697e-06ohm*m'"
      " --set contact.electrode_sheet.htc_p1=0.0017877863889798917"
      " --set 'thermal.melt_conductivity=133.33143871981588W/(m*K)'";
  nlohmann::json summary;
  coarse_features(base, point, &summary);
  const int solves = summary.at("coupling_newton_solves").get<int>();
  std::printf("Newton solves %d, rescues %d, retries %d, halved parts %d\n", solves,
              summary.at("coupling_newton_rescues").get<int>(), summary.at("coupling_retries").get<int>(),
              summary.at("coupling_substep_splits").get<int>());
  EXPECT_GE(solves, 1);
  EXPECT_EQ(summary.at("coupling_newton_rescues").get<int>(), solves);
  EXPECT_EQ(summary.at("coupling_retries").get<int>(), 0);
  EXPECT_EQ(summary.at("coupling_substep_splits").get<int>(), 0);
  const auto& energy = summary.at("energy_J");
  EXPECT_LT(std::abs(energy.at("imbalance").get<double>()), 1e-7 * energy.at("electrical").get<double>());
  fs::remove_all(base);
}

// The paper's stack is symmetric about its faying plane, so rsw solves its upper half
// (solver.mirror_symmetry = auto, fem/mirror.hpp). Both runs solve the same discrete
// equations, each to the solvers' tolerances (out-of-balance force 10⁻⁶ of the
// electrode force, coupling 10⁻² K), which moves a feature by about 10⁻⁵ of itself:
// every feature and nugget measure of the half solve is the whole stack's to 10⁻⁴,
// the lower electrode's contact is the upper one's. A stack of unequal sheets is
// solved whole.
TEST(WeldRun, SymmetricStackSolvedOnItsUpperHalfGivesTheWholeStacksResults) {
  const fs::path base = fs::temp_directory_path() / ("rsw_mirror_" + std::to_string(::getpid()));
  nlohmann::json half_summary, whole_summary, unequal_summary;
  const auto half = coarse_features(base / "half", "", &half_summary);
  const auto whole = coarse_features(base / "whole", " --set solver.mirror_symmetry=off", &whole_summary);
  EXPECT_TRUE(half_summary.at("mirror_symmetry").get<bool>());
  EXPECT_FALSE(whole_summary.at("mirror_symmetry").get<bool>());
  for (const auto& [name, entry] : whole.items()) {
    const double a = entry.at("value").get<double>(), b = half.at(name).at("value").get<double>();
    EXPECT_NEAR(b, a, 1e-4 * std::abs(a) + 1e-12) << name;
  }
  for (const auto& [name, value] : whole_summary.at("nugget").items())
    EXPECT_NEAR(half_summary.at("nugget").at(name).get<double>(), value.get<double>(),
                1e-4 * std::abs(value.get<double>()))
        << name;
  const auto& radius = half_summary.at("squeeze").at("contact_radius_m");
  EXPECT_NEAR(radius.at("es_lower").get<double>(), radius.at("es_upper").get<double>(), 1e-12);
  EXPECT_NEAR(half_summary.at("squeeze").at("electrode_displacement_m").get<double>(),
              whole_summary.at("squeeze").at("electrode_displacement_m").get<double>(), 1e-9);
  std::printf("wall time: %.2f s on the upper half, %.2f s on the whole stack\n",
              half_summary.at("wall_time_s").get<double>(), whole_summary.at("wall_time_s").get<double>());

  coarse_features(base / "unequal",
                  " --set 'stack.sheets=[{material: DP1200, thickness: 1.0 mm}, {material: DP1200, thickness: 1.2 mm}]'",
                  &unequal_summary);
  EXPECT_FALSE(unequal_summary.at("mirror_symmetry").get<bool>());
  fs::remove_all(base);
}
