// Weld process driver: squeeze, weld-stage time loop, outputs; see weld_simulation.hpp.
#include "physics/weld_simulation.hpp"

#include "fem/hdf5_file.hpp"
#include "fem/vtk_output.hpp"
#include "materials/material_library.hpp"
#include "meshes/weld_mesh.hpp"
#include "physics/mechanics.hpp"
#include "physics/squeeze.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#ifndef RSW_VERSION
#define RSW_VERSION "unknown"
#endif

namespace rsw::physics {

namespace fs = std::filesystem;

int Signals::column(const std::string& name) const {
  auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

std::vector<double> weld_step_times(const Problem& problem) {
  const double end = problem.schedule.end_time();
  std::set<double> breaks{0.0, end};
  for (const auto* table : {&problem.schedule.current, &problem.schedule.force})
    for (double t : table->time)
      if (t > 0 && t < end) breaks.insert(t);
  const double interval = problem.output.interval;
  for (int k = 1; k * interval < end - 1e-12; ++k) breaks.insert(k * interval);
  // Merge boundaries closer than a nanosecond (rounding of unit conversions).
  std::vector<double> b;
  for (double t : breaks)
    if (b.empty() || t - b.back() > 1e-9) b.push_back(t);
  b.back() = end;
  std::vector<double> times{0.0};
  for (std::size_t i = 0; i + 1 < b.size(); ++i) {
    const int n = std::max(1, static_cast<int>(std::ceil((b[i + 1] - b[i]) / problem.solver.time_step - 1e-9)));
    for (int k = 1; k <= n; ++k) times.push_back(b[i] + (b[i + 1] - b[i]) * k / n);
  }
  return times;
}

namespace {

// Linear interpolation of u_z along a boundary at radius r (nodes sorted by r).
double boundary_uz_at(const fem::Mesh& mesh, const Eigen::VectorXd& u, const std::string& boundary, double r) {
  std::vector<std::pair<double, double>> pts;
  for (int n : mesh.boundary_nodes(boundary)) pts.emplace_back(mesh.nodes[n].x(), u[2 * n + 1]);
  std::sort(pts.begin(), pts.end());
  for (std::size_t i = 0; i + 1 < pts.size(); ++i)
    if (r >= pts[i].first && r <= pts[i + 1].first) {
      const double s = (r - pts[i].first) / (pts[i + 1].first - pts[i].first);
      return (1 - s) * pts[i].second + s * pts[i + 1].second;
    }
  return r <= pts.front().first ? pts.front().second : pts.back().second;
}

// Depth of the electrode imprints: the sheet surface on the axis relative to the
// same surface 1 mm outside the electrode face, mean of the top and bottom sheets.
double indentation(const Problem& problem, const fem::Mesh& mesh, const Eigen::VectorXd& u) {
  const auto& g = problem.geometry;
  const std::string top = g.sheets.front().name + ".top", bottom = g.sheets.back().name + ".bottom";
  const double r_top = 0.5 * g.upper.face_diameter + 1e-3, r_bottom = 0.5 * g.lower.face_diameter + 1e-3;
  const double d_top = boundary_uz_at(mesh, u, top, r_top) - boundary_uz_at(mesh, u, top, 0.0);
  const double d_bottom = boundary_uz_at(mesh, u, bottom, 0.0) - boundary_uz_at(mesh, u, bottom, r_bottom);
  return 0.5 * (d_top + d_bottom);
}

std::string format_seconds(double s) {
  std::ostringstream out;
  out.precision(3);
  out << s << " s";
  return out.str();
}

}  // namespace

namespace {
// Accumulates wall time per named part.
class Stopwatch {
 public:
  explicit Stopwatch(std::vector<std::pair<std::string, double>>& timing) : timing_(timing) {}
  void start(const std::string& part) {
    stop();
    part_ = part;
    t0_ = std::chrono::steady_clock::now();
  }
  void stop() {
    if (part_.empty()) return;
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    auto it = std::find_if(timing_.begin(), timing_.end(), [&](const auto& p) { return p.first == part_; });
    if (it == timing_.end()) timing_.emplace_back(part_, dt);
    else it->second += dt;
    part_.clear();
  }

 private:
  std::vector<std::pair<std::string, double>>& timing_;
  std::string part_;
  std::chrono::steady_clock::time_point t0_;
};
}  // namespace

RunResult run_weld(const Problem& problem, const fs::path& output_dir,
                   const std::function<void(const Progress&)>& progress) {
  const auto t_start = std::chrono::steady_clock::now();
  RunResult result;
  Stopwatch clock(result.timing);
  clock.start("setup");
  result.output_dir = output_dir;
  const fs::path partial = output_dir.string() + ".partial";

  const fem::Mesh mesh = meshes::weld_mesh(problem.geometry, problem.mesh);
  materials::MaterialLibrary library;
  std::vector<materials::Material> materials_of_body;
  materials_of_body.reserve(mesh.n_bodies());
  auto material_name = [&](const std::string& body) -> std::string {
    if (body == "upper_electrode") return problem.geometry.upper.material;
    if (body == "lower_electrode") return problem.geometry.lower.material;
    for (const auto& s : problem.geometry.sheets)
      if (s.name == body) return s.material;
    throw std::logic_error("no material for body " + body);
  };
  for (const auto& body : mesh.body_names) materials_of_body.push_back(library.load(material_name(body)));
  std::vector<const materials::Material*> body_materials;
  for (const auto& m : materials_of_body) body_materials.push_back(&m);

  bool any_current = false;
  for (double I : problem.schedule.current.value) any_current = any_current || I != 0.0;
  if (any_current)
    throw std::runtime_error(
        "this version of rsw simulates the squeeze and the mechanics of the weld stage only: the "
        "current table must be zero (set schedule.current to [[0 ms, 0 kA], [<t> ms, 0 kA]]); the "
        "coupled electro-thermal solve is not available yet");

  fs::remove_all(partial);
  fs::create_directories(partial);

  MechanicsSettings ms;
  ms.friction_coefficient = problem.contact.friction_coefficient;
  ms.penalty_factor = problem.solver.contact_penalty_factor;
  ms.contact_smoothing = problem.solver.contact_smoothing;
  Mechanics mech(mesh, body_materials, ms, problem.thermal.initial_temperature);
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), problem.thermal.initial_temperature);

  auto fail = [&](const std::string& message) {
    result.success = false;
    result.message = message;
    std::ofstream(partial / "failure.txt") << message << "\n";
    result.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    return result;
  };

  // 1. Squeeze.
  if (progress) progress({"squeeze", 0, 0, 0.0});
  clock.start("squeeze");
  SqueezeSettings ss;
  ss.seat_step = problem.solver.seat_step;
  ss.n_force_steps = problem.solver.squeeze_force_steps;
  const auto squeeze_result = squeeze(mech, problem.schedule.force.at(0.0), T, ss);
  for (const auto& s : squeeze_result.steps) result.n_newton_iterations += s.iterations;
  if (!squeeze_result.converged) return fail("squeeze: " + squeeze_result.message);
  result.squeeze_displacement = mech.end_face_displacement();
  for (const auto& st : mech.interface_states()) {
    result.squeeze_contact_radius.emplace_back(st.name, st.contact_radius);
    result.squeeze_peak_pressure.emplace_back(st.name, *std::max_element(st.pressure.begin(), st.pressure.end()));
  }
  result.squeeze_indentation = indentation(problem, mesh, mech.displacement());
  const double w0 = mech.end_face_displacement();

  // 2. Weld stage.
  const std::vector<double> times = weld_step_times(problem);
  result.n_steps = static_cast<int>(times.size()) - 1;
  Signals& sig = result.signals;
  sig.names = {"time", "current", "force", "electrode_displacement"};
  sig.units = {"s", "A", "N", "m"};
  const auto states0 = mech.interface_states();
  for (const auto& st : states0) {
    sig.names.push_back("contact_radius_" + st.name);
    sig.units.push_back("m");
    sig.names.push_back("peak_pressure_" + st.name);
    sig.units.push_back("Pa");
  }
  sig.columns.assign(sig.names.size(), {});

  std::unique_ptr<fem::VtkTimeSeries> series;
  if (problem.output.fields) series = std::make_unique<fem::VtkTimeSeries>(partial / "fields.pvd");
  std::vector<std::vector<std::vector<double>>> profiles_radius(states0.size()), profiles_pressure(states0.size());
  std::vector<double> output_times;

  auto record = [&](double t) {
    const auto states = mech.interface_states();
    std::vector<double> row{t, problem.schedule.current.at(t), mech.electrode_force(), mech.end_face_displacement() - w0};
    for (std::size_t i = 0; i < states.size(); ++i) {
      row.push_back(states[i].contact_radius);
      row.push_back(*std::max_element(states[i].pressure.begin(), states[i].pressure.end()));
      profiles_radius[i].push_back(states[i].radius);
      profiles_pressure[i].push_back(states[i].pressure);
    }
    for (std::size_t c = 0; c < row.size(); ++c) sig.columns[c].push_back(row[c]);
    output_times.push_back(t);
    if (!series) return;
    fem::FieldSet fields;
    const Eigen::VectorXd u = mech.displacement();
    fields.add_point_vector("displacement", std::vector<double>(u.data(), u.data() + u.size()));
    fields.add_point_scalar("temperature", std::vector<double>(T.data(), T.data() + T.size()));
    fields.add_cell_scalar("von_mises_stress", mech.von_mises());
    fields.add_cell_scalar("equivalent_plastic_strain", mech.equivalent_plastic_strain());
    const auto& pairings = mech.pairings();
    for (std::size_t p = 0; p < pairings.size(); ++p) {
      const auto pressure = mech.contact_pressure(static_cast<int>(p));
      const int n_g = pairings[p].n_gauss();
      std::vector<double> face_p(pairings[p].n_slave_faces()), face_g(pairings[p].n_slave_faces());
      for (int f = 0; f < pairings[p].n_slave_faces(); ++f) {
        double sp = 0, sg = 0;
        for (int k = 0; k < n_g; ++k) {
          sp += pressure[f * n_g + k] / n_g;
          const auto& pt = pairings[p].points()[f * n_g + k];
          sg += (pt.paired ? pt.gap : std::nan("")) / n_g;
        }
        face_p[f] = sp;
        face_g[f] = sg;
      }
      fields.add_face_scalar("contact_pressure", pairings[p].slave_boundary(), face_p);
      fields.add_face_scalar("contact_gap", pairings[p].slave_boundary(), face_g);
    }
    series->write_step(t, mesh, fields);
  };

  std::size_t next_output = 0;
  auto is_output = [&](double t) {
    const double interval = problem.output.interval;
    return std::abs(t - next_output * interval) < 1e-9 || t >= times.back() - 1e-12;
  };
  clock.start("output");
  if (is_output(0.0)) {
    record(0.0);
    ++next_output;
  }
  for (std::size_t k = 1; k < times.size(); ++k) {
    const double t = times[k];
    if (progress) progress({"weld", static_cast<int>(k), result.n_steps, t});
    clock.start("mechanics");
    const auto report = mech.solve_force_step(problem.schedule.force.at(t), T);
    result.n_newton_iterations += report.iterations;
    if (!report.converged)
      return fail("weld stage, step " + std::to_string(k) + " (t = " + std::to_string(t * 1e3) +
                  " ms), mechanics: " + report.message);
    mech.commit();
    if (is_output(t)) {
      clock.start("output");
      record(t);
      while (next_output * problem.output.interval <= t + 1e-9) ++next_output;
    }
  }
  // Outputs.
  clock.start("output");
  {
    fem::Hdf5File h5(partial / "results.h5", fem::Hdf5Mode::truncate);
    for (std::size_t c = 0; c < sig.names.size(); ++c) {
      h5.write("/signals/" + sig.names[c], sig.columns[c]);
      h5.set_attribute("/signals/" + sig.names[c], "unit", sig.units[c]);
    }
    std::vector<double> sq_force, sq_disp, sq_iter;
    for (const auto& s : squeeze_result.steps) {
      sq_force.push_back(s.force);
      sq_disp.push_back(s.displacement);
      sq_iter.push_back(s.iterations);
    }
    h5.write("/squeeze/force", sq_force);
    h5.set_attribute("/squeeze/force", "unit", std::string("N"));
    h5.write("/squeeze/displacement", sq_disp);
    h5.set_attribute("/squeeze/displacement", "unit", std::string("m"));
    h5.write("/squeeze/newton_iterations", sq_iter);
    h5.write("/contact/output_times", output_times);
    for (std::size_t i = 0; i < states0.size(); ++i) {
      const auto to_matrix = [](const std::vector<std::vector<double>>& rows) {
        fem::RowMajorMatrix m;
        m.n_rows = rows.size();
        m.n_cols = rows.empty() ? 0 : rows.front().size();
        for (const auto& row : rows) m.values.insert(m.values.end(), row.begin(), row.end());
        return m;
      };
      const std::string g = "/contact/" + states0[i].name;
      h5.write(g + "/radius", to_matrix(profiles_radius[i]));
      h5.set_attribute(g + "/radius", "unit", std::string("m"));
      h5.write(g + "/pressure", to_matrix(profiles_pressure[i]));
      h5.set_attribute(g + "/pressure", "unit", std::string("Pa"));
    }
    h5.write_string("/run/config", problem.resolved_config);
    h5.set_attribute("/run", "version", std::string(RSW_VERSION));
    h5.set_attribute("/run", "case", problem.name);
    h5.set_attribute("/run", "wall_time", std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
    h5.set_attribute("/run", "squeeze_indentation", result.squeeze_indentation);
  }
  {
    std::ofstream csv(partial / "signals.csv");
    for (std::size_t c = 0; c < sig.names.size(); ++c)
      csv << (c ? "," : "") << sig.names[c] << " [" << sig.units[c] << "]";
    csv << "\n";
    csv.precision(10);
    for (std::size_t r = 0; r < sig.n_rows(); ++r) {
      for (std::size_t c = 0; c < sig.names.size(); ++c) csv << (c ? "," : "") << sig.columns[c][r];
      csv << "\n";
    }
  }
  clock.stop();
  result.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  {
    nlohmann::json j;
    j["status"] = "success";
    for (const auto& [part, seconds] : result.timing) j["timing_s"][part] = seconds;
    j["version"] = RSW_VERSION;
    j["case"] = problem.name;
    j["wall_time_s"] = result.wall_time;
    j["weld_steps"] = result.n_steps;
    j["newton_iterations"] = result.n_newton_iterations;
    j["squeeze"]["electrode_displacement_m"] = result.squeeze_displacement;
    j["squeeze"]["indentation_m"] = result.squeeze_indentation;
    for (const auto& [name, r] : result.squeeze_contact_radius) j["squeeze"]["contact_radius_m"][name] = r;
    for (const auto& [name, p] : result.squeeze_peak_pressure) j["squeeze"]["peak_pressure_Pa"][name] = p;
    j["config_yaml"] = problem.resolved_config;
    std::ofstream(partial / "summary.json") << j.dump(2) << "\n";
  }
  fs::remove_all(output_dir);
  fs::rename(partial, output_dir);
  result.success = true;
  return result;
}

}  // namespace rsw::physics
