// Weld process driver: squeeze, weld-stage time loop, outputs; see weld_simulation.hpp.
#include "physics/weld_simulation.hpp"

#include "fem/hdf5_file.hpp"
#include "fem/vtk_output.hpp"
#include "materials/material_library.hpp"
#include "meshes/weld_mesh.hpp"
#include "physics/electrical.hpp"
#include "physics/mechanics.hpp"
#include "physics/nugget.hpp"
#include "physics/squeeze.hpp"
#include "physics/thermal.hpp"

#include "fem/fe_values.hpp"
#include "fem/fixed_point.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
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
  const double early_end = problem.solver.early_phase_end;
  if (early_end > 0 && early_end < end) breaks.insert(early_end);
  // Merge boundaries closer than a nanosecond (rounding of unit conversions).
  std::vector<double> b;
  for (double t : breaks)
    if (b.empty() || t - b.back() > 1e-9) b.push_back(t);
  b.back() = end;
  std::vector<double> times{0.0};
  for (std::size_t i = 0; i + 1 < b.size(); ++i) {
    const bool early = b[i + 1] <= early_end * (1 + 1e-12);
    const double largest = early ? std::min(problem.solver.time_step, problem.solver.early_time_step)
                                 : problem.solver.time_step;
    const int n = std::max(1, static_cast<int>(std::ceil((b[i + 1] - b[i]) / largest - 1e-9)));
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

// Enthalpy gained by the nugget (sheet cells whose centre reached the liquidus),
// ∫ ρ_0 (H(T) − H(T_0)) dV, J.
double nugget_enthalpy(const fem::Mesh& mesh, const std::vector<fem::Point>& positions, const Eigen::VectorXd& T,
                       const std::vector<double>& peak, const std::vector<int>& sheet_bodies,
                       const std::vector<double>& liquidus, const std::vector<const materials::Material*>& mats,
                       double T0) {
  fem::Mesh current = mesh;
  current.nodes = positions;
  fem::CellValues cv(2);
  double energy = 0;
  for (int e = 0; e < mesh.n_cells(); ++e) {
    const int b = mesh.cell_body[e];
    if (std::find(sheet_bodies.begin(), sheet_bodies.end(), b) == sheet_bodies.end()) continue;
    const auto& c = mesh.cells[e];
    const double peak_centre = 0.25 * (peak[c[0]] + peak[c[1]] + peak[c[2]] + peak[c[3]]);
    if (peak_centre < liquidus[b]) continue;
    cv.reinit(current, e);
    const double rho0 = mats[b]->density(20.0).value;
    const double H0 = mats[b]->enthalpy(T0).value;
    for (int q = 0; q < cv.n_q(); ++q) {
      double Tq = 0;
      for (int a = 0; a < 4; ++a) Tq += cv.N(q, a) * T[c[a]];
      energy += rho0 * (mats[b]->enthalpy(Tq).value - H0) * cv.JxW(q);
    }
  }
  return energy;
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

  fs::remove_all(partial);
  fs::create_directories(partial);

  MechanicsSettings ms;
  ms.friction_coefficient = problem.contact.friction_coefficient;
  ms.penalty_factor = problem.solver.contact_penalty_factor;
  ms.contact_smoothing = problem.solver.contact_smoothing;
  ms.tangential_penalty_ratio = problem.solver.friction_penalty_ratio;
  ms.residual_tolerance = problem.solver.mechanics_tolerance;
  ms.error_estimate_tolerance = problem.solver.mechanics_error_estimate;
  if (problem.solver.two_pass_sheet_contact)
    for (const auto& [name, pair] : mesh.interfaces)
      if (name.rfind("ss_", 0) == 0) ms.two_pass_interfaces.push_back(name);
  Mechanics mech(mesh, body_materials, ms, problem.thermal.initial_temperature);
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh.n_nodes(), problem.thermal.initial_temperature);

  // Set when an electrode first reaches its solidus (the run goes on): a later failure
  // (mechanics, an inverted cell of the molten face, the coupling) is most likely its
  // consequence, and the failure message says so.
  std::string electrode_melting_note;
  auto fail = [&](const std::string& message) {
    result.success = false;
    result.message = message;
    if (!electrode_melting_note.empty())
      result.message += " (after an electrode had melted, " + electrode_melting_note + ")";
    std::ofstream(partial / "failure.txt") << result.message << "\n";
    result.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    return result;
  };

  // The deformed mesh's worst cell (RunResult::worst_cell), checked after every
  // committed mechanics step. The mesh is Lagrangian and never remeshed: where the
  // material flows far (molten metal pressed out at the edge of the sheet/sheet
  // contact) a cell can fold over a corner while its quadrature-point Jacobians stay
  // positive, and the fields on it are meaningless. Returns the failure message then.
  auto check_cells = [&](double t) -> std::string {
    const std::vector<fem::Point>& x = mech.positions();
    int worst = -1;
    double value = 2;
    for (int e = 0; e < mesh.n_cells(); ++e)
      if (const double q = fem::scaled_jacobian(x, mesh.cells[e]); q < value) {
        value = q;
        worst = e;
      }
    if (worst < 0 || !(value < result.worst_cell.scaled_jacobian || result.worst_cell.cell < 0)) return {};
    auto& w = result.worst_cell;
    w.scaled_jacobian = value;
    w.time = t;
    w.cell = worst;
    w.body = mesh.body_names[mesh.cell_body[worst]];
    w.centre.setZero();
    for (int n : mesh.cells[worst]) w.centre += 0.25 * x[n];
    if (value > 0) return {};
    char text[320];
    std::snprintf(text, sizeof text,
                  "the deformed mesh has folded: cell %d of %s at (r, z) = (%.3f, %.3f) mm has a corner with scaled "
                  "Jacobian %.3f (<= 0); the material there has moved further than the fixed mesh can follow "
                  "(see docs/MODEL.md, Known limitations)",
                  worst, w.body.c_str(), w.centre.x() * 1e3, w.centre.y() * 1e3, value);
    return text;
  };

  // 1. Squeeze.
  if (progress) progress({"squeeze", 0, 0, 0.0});
  clock.start("squeeze");
  SqueezeSettings ss;
  ss.seat_step = problem.solver.seat_step;
  ss.n_force_steps = problem.solver.squeeze_force_steps;
  SqueezeResult squeeze_result;
  try {
    squeeze_result = squeeze(mech, problem.schedule.force.at(0.0), T, ss);
  } catch (const std::exception& e) {
    return fail(std::string("squeeze: ") + e.what());
  }
  for (const auto& s : squeeze_result.steps) result.n_newton_iterations += s.iterations;
  if (!squeeze_result.converged) return fail("squeeze: " + squeeze_result.message);
  if (const std::string tangled = check_cells(0.0); !tangled.empty()) return fail("squeeze: " + tangled);
  result.squeeze_displacement = mech.end_face_displacement();
  for (const auto& st : mech.interface_states()) {
    result.squeeze_contact_radius.emplace_back(st.name, st.contact_radius);
    result.squeeze_peak_pressure.emplace_back(st.name, *std::max_element(st.pressure.begin(), st.pressure.end()));
  }
  result.squeeze_indentation = indentation(problem, mesh, mech.displacement());
  const double w0 = mech.end_face_displacement();

  // 2. Weld stage: per step, electrical ⇄ thermal fixed-point iterations on the
  // contact state of the last mechanics solve, then the mechanics at the new
  // temperature (staggered; the interface laws see the contact pressure one step late).
  clock.start("setup");
  const contact::InterfaceModel model = interface_model(mesh, problem.contact);
  Electrical electrical(mesh, body_materials, model);
  ThermalSettings th = thermal_settings(problem.thermal);
  const double thermal_tolerance = th.temperature_tolerance;
  Thermal thermal(mesh, body_materials, model, th);
  std::vector<int> sheet_bodies;
  for (const auto& sh : problem.geometry.sheets) sheet_bodies.push_back(mesh.body_index(sh.name));
  std::vector<double> liquidus(mesh.n_bodies()), solidus(mesh.n_bodies());
  for (int b = 0; b < mesh.n_bodies(); ++b) {
    liquidus[b] = body_materials[b]->liquidus();
    solidus[b] = body_materials[b]->solidus();
  }

  const std::vector<double> times = weld_step_times(problem);
  result.n_steps = static_cast<int>(times.size()) - 1;
  Signals& sig = result.signals;
  const auto states0 = mech.interface_states();
  std::vector<std::pair<std::string, std::string>> columns = {
      {"time", "s"}, {"current", "A"}, {"voltage", "V"}, {"resistance", "ohm"}, {"force", "N"},
      {"displacement", "m"}, {"temperature", "degC"}};
  for (const auto& sh : problem.geometry.sheets) columns.push_back({"temperature_" + sh.name, "degC"});
  for (const char* c : {"d_n_liq", "h_n_liq", "d_n_sol", "h_n_sol"}) columns.push_back({c, "m"});
  for (const auto& st : states0) columns.push_back({"contact_radius_" + st.name, "m"});
  for (const auto& st : states0) columns.push_back({"joule_power_" + st.name, "W"});
  for (const auto& c : std::vector<std::pair<std::string, std::string>>{
           {"joule_power_bulk", "W"}, {"electrical_energy", "J"}, {"stored_energy", "J"},
           {"removed_energy", "J"}, {"coupling_iterations", "1"}})
    columns.push_back(c);
  for (const auto& [n, u] : columns) {
    sig.names.push_back(n);
    sig.units.push_back(u);
  }
  sig.columns.assign(sig.names.size(), {});

  std::unique_ptr<fem::VtkTimeSeries> series;
  if (problem.output.fields) series = std::make_unique<fem::VtkTimeSeries>(partial / "fields.pvd");
  std::vector<std::vector<std::vector<double>>> profiles_radius(states0.size()), profiles_pressure(states0.size());
  std::vector<double> output_times;
  double electrical_energy = 0, stored_energy = 0, removed_energy = 0;
  double last_voltage = 0, last_current = 0;
  int last_coupling = 0;
  std::vector<double> last_interface_power(states0.size(), 0.0);
  double last_bulk_power = 0;
  bool have_electrical = false;

  auto peak_vector = [&]() {
    const Eigen::VectorXd& pk = thermal.peak_temperature();
    return std::vector<double>(pk.data(), pk.data() + pk.size());
  };
  // Fields at the first output step, then at output steps at least
  // output.field_interval after the last field output, and at the last step.
  double last_field_output = -std::numeric_limits<double>::infinity();
  auto is_field_output = [&](double t) {
    if (t < last_field_output + problem.output.field_interval - 1e-9 && t < times.back() - 1e-12) return false;
    last_field_output = t;
    return true;
  };
  auto record = [&](double t) {
    const auto states = mech.interface_states();
    const Eigen::VectorXd& T = thermal.committed_temperature();
    std::vector<double> row{t, last_current, have_electrical ? last_voltage : 0.0,
                            (have_electrical && std::abs(last_current) > 1.0) ? last_voltage / last_current
                                                                               : std::nan(""),
                            mech.electrode_force(), mech.end_face_displacement() - w0};
    double t_all = -1e300;
    std::vector<double> t_sheet;
    for (int b : sheet_bodies) {
      double m = -1e300;
      for (int n = 0; n < mesh.n_nodes(); ++n)
        if (mesh.node_body[n] == b) m = std::max(m, T[n]);
      t_sheet.push_back(m);
      t_all = std::max(t_all, m);
    }
    row.push_back(t_all);
    row.insert(row.end(), t_sheet.begin(), t_sheet.end());
    const auto peak = peak_vector();
    const auto liq = measure_nugget(mesh, mech.positions(), peak, sheet_bodies, liquidus);
    const auto sol = measure_nugget(mesh, mech.positions(), peak, sheet_bodies, solidus);
    row.insert(row.end(), {liq.diameter, liq.height, sol.diameter, sol.height});
    for (const auto& st : states) row.push_back(st.contact_radius);
    for (double pw : last_interface_power) row.push_back(pw);
    row.insert(row.end(), {last_bulk_power, electrical_energy, stored_energy, removed_energy,
                           static_cast<double>(last_coupling)});
    for (std::size_t i = 0; i < states.size(); ++i) {
      profiles_radius[i].push_back(states[i].radius);
      profiles_pressure[i].push_back(states[i].pressure);
    }
    for (std::size_t c = 0; c < row.size(); ++c) sig.columns[c].push_back(row[c]);
    output_times.push_back(t);
    if (!series || !is_field_output(t)) return;
    fem::FieldSet fields;
    const Eigen::VectorXd u = mech.displacement();
    fields.add_point_vector("displacement", std::vector<double>(u.data(), u.data() + u.size()));
    fields.add_point_scalar("temperature", std::vector<double>(T.data(), T.data() + T.size()));
    fields.add_point_scalar("peak_temperature", peak);
    const Eigen::VectorXd fl = thermal.liquid_fraction();
    fields.add_point_scalar("liquid_fraction", std::vector<double>(fl.data(), fl.data() + fl.size()));
    if (have_electrical) {
      const Eigen::VectorXd& phi = electrical.solution().potential;
      fields.add_point_scalar("potential", std::vector<double>(phi.data(), phi.data() + phi.size()));
      fields.add_cell_scalar("joule_heat", electrical.cell_joule_heat());
      std::vector<double> j;
      for (const auto& v : electrical.cell_current_density()) {
        j.push_back(v.x());
        j.push_back(v.y());
      }
      fields.add_cell_vector("current_density", j);
    } else {
      fields.add_point_scalar("potential", std::vector<double>(mesh.n_nodes(), 0.0));
      fields.add_cell_scalar("joule_heat", std::vector<double>(mesh.n_cells(), 0.0));
      fields.add_cell_vector("current_density", std::vector<double>(2 * mesh.n_cells(), 0.0));
    }
    fields.add_cell_scalar("von_mises_stress", mech.von_mises());
    fields.add_cell_scalar("equivalent_plastic_strain", mech.equivalent_plastic_strain());
    const auto& pairings = mech.pairings();
    const auto& htc = thermal.interface_conductance();
    for (std::size_t p = 0; p < pairings.size(); ++p) {
      const auto pressure = mech.contact_pressure(static_cast<int>(p));
      const int n_g = pairings[p].n_gauss();
      const int n_f = pairings[p].n_slave_faces();
      std::vector<double> face_p(n_f, 0.0), face_g(n_f, 0.0), face_he(n_f, 0.0), face_htc(n_f, 0.0);
      for (int f = 0; f < n_f; ++f)
        for (int k = 0; k < n_g; ++k) {
          const int i = f * n_g + k;
          const auto& pt = pairings[p].points()[i];
          face_p[f] += pressure[i] / n_g;
          face_g[f] += (pt.paired ? pt.gap : std::nan("")) / n_g;
          if (have_electrical && p < electrical.solution().interface_conductance.size())
            face_he[f] += electrical.solution().interface_conductance[p][i] / n_g;
          if (p < htc.size() && i < static_cast<int>(htc[p].size())) face_htc[f] += htc[p][i] / n_g;
        }
      const std::string& b = pairings[p].slave_boundary();
      fields.add_face_scalar("contact_pressure", b, face_p);
      fields.add_face_scalar("contact_gap", b, face_g);
      fields.add_face_scalar("electrical_conductance", b, face_he);
      fields.add_face_scalar("thermal_conductance", b, face_htc);
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
  const double current_end = problem.schedule.current.time.back();
  // An electrode that melts (sticking, alloying with the sheet) is outside the model.
  // By default (solver.electrode_melting = continue) the first step where an electrode
  // node reaches its solidus is recorded as a warning and the run goes on, so that the
  // outputs stay continuous across the boundary of that region of the parameters
  // (calibration needs that: a failed run is a cliff in the likelihood); with `stop`
  // the run fails there. Where the coupling fails while an electrode is at its
  // solidus, the failure names the melting electrode. Measured: high E/S film
  // resistances t_f·ρ_c (above ~3·10⁻¹¹ Ω·m²) and E/S thermal conductances
  // (P1 ≥ 0.04 in the default case, coarse mesh).
  auto electrode_melting = [&](const Eigen::VectorXd& T) -> std::string {
    for (int n = 0; n < mesh.n_nodes(); ++n) {
      const int b = mesh.node_body[n];
      if (std::find(sheet_bodies.begin(), sheet_bodies.end(), b) != sheet_bodies.end()) continue;
      if (!(T[n] < solidus[b])) {
        char text[320];
        std::snprintf(text, sizeof text,
                      "%s reaches %.0f degC at (r, z) = (%.2f, %.2f) mm, above the solidus of its material "
                      "(%.0f degC)",
                      mesh.body_names[b].c_str(), T[n], mech.positions()[n].x() * 1e3, mech.positions()[n].y() * 1e3,
                      solidus[b]);
        return text + std::string(": a melting electrode is outside the model (contact parameters too resistive?)");
      }
    }
    return {};
  };
  double nugget_energy_fraction = std::nan("");
  double last_mechanics_step = 0;  // s, the last committed mechanics (sub-)step of the weld stage
  double resistance_peak = 0;      // Ω, over every weld step with current (not only output steps)
  for (std::size_t k = 1; k < times.size(); ++k) {
    // Anything a solver throws mid-step (an inverted cell, a failed factorisation)
    // fails the run with the step named, like the failures reported above.
    try {
      const double t = times[k], dt = times[k] - times[k - 1];
      const double I = problem.schedule.current.at(t);
      const contact::ContactState contact = contact_state(mech);
      // Electro-thermal fixed point of the step, T = G(T): the electrical field with
      // σ(T) and h_e at T, then the thermal step with that Joule heat, its coefficients
      // (k, HTC) also at T. Anderson-accelerated (KINSOL): plain iteration runs away
      // where the current crowds into a contact edge that heats, softens and conducts
      // better. Converged when an iterate changes by at most coupling_tolerance; the
      // thermal and electrical states then belong to the last evaluated T.
      Eigen::VectorXd T_iter = thermal.predicted_temperature(dt);
      std::string coupling_failure;
      // Inexact inner solves: a coupling iterate that moved by Δ K is solved to 10⁻³ Δ
      // (never looser than 0.1 K, never tighter than the thermal default): far from
      // the fixed point the field is needed only roughly; the converged iterate
      // (Δ ≤ coupling_tolerance) is solved as tightly as a lone thermal step.
      double last_change = std::numeric_limits<double>::infinity();
      auto coupled_step = [&](const Eigen::VectorXd& T_in, Eigen::VectorXd& T_out) {
        std::vector<double> joule;
        std::vector<std::vector<double>> interface_heat;
        if (I != 0.0) {
          clock.start("electrical");
          try {
            const auto& sol = electrical.solve(mech.positions(), T_in, I, contact, thermal.bonding());
            joule = sol.joule_heat;
            interface_heat = sol.interface_heat;
          } catch (const std::exception& e) {
            coupling_failure = std::string("electrical: ") + e.what();
            return false;
          }
          have_electrical = true;
        }
        clock.start("thermal");
        thermal.set_start(T_in);
        const double tolerance =
            I == 0.0 ? thermal_tolerance : std::max(thermal_tolerance, std::min(0.1, 1e-3 * last_change));
        const auto report = thermal.solve(dt, mech.positions(), contact, joule, interface_heat, tolerance);
        if (!report.converged) {
          coupling_failure = "thermal: " + report.message;
          return false;
        }
        T_out = thermal.temperature();
        last_change = (T_out - T_in).lpNorm<Eigen::Infinity>();
        if (std::getenv("RSW_VERBOSE")) {
          Eigen::Index worst = 0;
          const double change = (T_out - T_in).cwiseAbs().maxCoeff(&worst);
          std::fprintf(stderr, "  coupling: change %.3e K at %s (%.4f, %.4f) mm, T = %.1f degC\n", change,
                       mesh.body_names[mesh.node_body[worst]].c_str(), mech.positions()[worst].x() * 1e3,
                       mech.positions()[worst].y() * 1e3, T_out[worst]);
        }
        return true;
      };
      int it = 1;
      if (I == 0.0) {
        // No current: no coupling; one thermal step.
        Eigen::VectorXd T_out;
        if (!coupled_step(T_iter, T_out))
          return fail("weld stage, step " + std::to_string(k) + " (t = " + std::to_string(t * 1e3) + " ms), " +
                      coupling_failure);
      } else {
        fem::FixedPointSettings fp;
        fp.depth = problem.solver.coupling_acceleration_depth;
        fp.tolerance = problem.solver.coupling_tolerance;
        fp.max_iterations = problem.solver.max_coupling_iterations;
        fp.estimate_error = true;  // fem/fixed_point.hpp: the iterate that would only confirm is saved
        // Retries: where the iteration cycles (kinks of tabulated properties at a contact
        // edge that heats, measured on the paper's mesh at 16 ms), the step is solved
        // again from its start with the other Anderson depth (2, or 5 if 2 was
        // configured), then with damping 0.7 and 0.4 at both depths. Measured on the
        // coupling failures of the paper-mesh Table I study (docs/PERFORMANCE.md): depths
        // 5 and 2 each rescued about half of them, mostly different ones. Only the path
        // to the fixed point changes, not the point (to the tolerance).
        const int depth = problem.solver.coupling_acceleration_depth;
        const int other_depth = depth == 0 ? 0 : (depth > 2 ? 2 : 5);
        std::vector<std::pair<int, double>> attempts;
        for (const double beta : {1.0, 0.7, 0.4})
          for (const int d : {depth, other_depth})
            if (std::find(attempts.begin(), attempts.end(), std::make_pair(d, beta)) == attempts.end())
              attempts.emplace_back(d, beta);
        const Eigen::VectorXd T_guess = T_iter;
        fem::FixedPointReport coupling;
        it = 0;
        for (std::size_t attempt = 0; attempt < attempts.size(); ++attempt) {
          if (attempt > 0) ++result.n_coupling_retries;
          T_iter = T_guess;
          fp.depth = attempts[attempt].first;
          fp.damping = attempts[attempt].second;
          coupling_failure.clear();
          last_change = std::numeric_limits<double>::infinity();
          coupling = fem::solve_fixed_point(coupled_step, T_iter, fp);
          it += coupling.iterations;
          if (coupling.converged || !coupling_failure.empty()) break;
        }
        // A failed coupling says what failed; where an electrode is melting at that
        // point, the failure names it first (the likely cause) and keeps the solver's
        // own message after it.
        if (!coupling.converged) {
          const std::string solver_failure =
              coupling_failure.empty()
                  ? "electro-thermal coupling did not converge in " +
                        std::to_string(problem.solver.max_coupling_iterations) + " iterations, also" +
                        (other_depth != depth ? " with Anderson depth " + std::to_string(other_depth) + " and"
                                              : std::string()) +
                        " with damping 0.7 and 0.4 (last change " + std::to_string(coupling.change) + " K)"
                  : coupling_failure;
          const std::string melting = electrode_melting(thermal.temperature());
          return fail("weld stage, step " + std::to_string(k) + " (t = " + std::to_string(t * 1e3) + " ms), " +
                      (melting.empty() ? solver_failure : melting + "; there " + solver_failure));
        }
      }
      T_iter = thermal.temperature();
      if (std::isnan(result.electrode_melting_time))
        if (const std::string melting = electrode_melting(T_iter); !melting.empty()) {
          if (problem.solver.stop_on_electrode_melting)
            return fail("weld stage, step " + std::to_string(k) + " (t = " + std::to_string(t * 1e3) + " ms): " + melting);
          result.electrode_melting_time = t;
          char at[64];
          std::snprintf(at, sizeof at, "at t = %.1f ms: ", t * 1e3);
          electrode_melting_note = at + melting.substr(0, melting.find(": a melting electrode"));
          result.warnings.push_back(at + melting + "; the run goes on (solver.electrode_melting = continue)");
        }
      last_coupling = it;
      result.n_coupling_iterations += last_coupling;
      // Energy bookkeeping of the step (backward Euler: end-of-step power times dt).
      last_current = I;
      if (I != 0.0) {
        const auto& sol = electrical.solution();
        resistance_peak = std::max(resistance_peak, sol.resistance);
        last_voltage = sol.voltage;
        electrical_energy += sol.voltage * I * dt;
        last_bulk_power = sol.bulk_power;
        for (std::size_t p = 0; p < last_interface_power.size() && p < sol.interface_power.size(); ++p)
          last_interface_power[p] = sol.interface_power[p];
      } else {
        last_voltage = 0;
        last_bulk_power = 0;
        std::fill(last_interface_power.begin(), last_interface_power.end(), 0.0);
      }
      stored_energy += thermal.energy().stored;
      removed_energy += thermal.energy().removed();

      if (progress)
        progress({"weld", static_cast<int>(k), result.n_steps, t, T_iter.maxCoeff(),
                  I != 0.0 ? electrical.solution().resistance : 0.0});
      if (std::getenv("RSW_VERBOSE"))
        std::fprintf(stderr, "step %zu: t = %.1f ms, T_max = %.1f, T(apex) = %.1f, coupling %d\n", k, t * 1e3,
                     T_iter.maxCoeff(), T_iter[mesh.boundary_nodes("upper_electrode.contact_face").front()], it);
      // Sheets fuse where both sides of a sheet/sheet point approach their solidus: the
      // bonding degree β (contact::bonding_degree; the committed thermal history, or
      // this step's temperatures) never decreases, and the mechanics ties the point with
      // the share β of its traction from this step on (Mechanics::set_bonding_degree),
      // so molten sheets never meet across a frictionless contact.
      {
        const auto& bonding = thermal.bonding();
        const auto& pairings = mech.pairings();
        std::vector<std::vector<double>> degree(pairings.size());
        for (std::size_t p = 0; p < pairings.size(); ++p) {
          degree[p].assign(pairings[p].points().size(), 0.0);
          if (pairings[p].name().rfind("ss_", 0) != 0) continue;
          for (std::size_t i = 0; i < degree[p].size(); ++i) {
            const auto& pt = pairings[p].points()[i];
            double& beta = degree[p][i];
            if (static_cast<int>(p) < bonding.n_interfaces())
              beta = bonding.degree(static_cast<int>(p), static_cast<int>(i));
            if (beta < 1 && pt.paired) {
              const double Ts = pt.slave_weights[0] * T_iter[pt.slave_nodes[0]] + pt.slave_weights[1] * T_iter[pt.slave_nodes[1]];
              const double Tm = pt.master_weights[0] * T_iter[pt.master_nodes[0]] + pt.master_weights[1] * T_iter[pt.master_nodes[1]];
              beta = std::max(beta, contact::bonding_degree_at_gap(Ts, solidus[mesh.node_body[pt.slave_nodes[0]]], Tm,
                                                                   solidus[mesh.node_body[pt.master_nodes[0]]],
                                                                   model.bonding_band, pt.gap,
                                                                   model.bonding_gap));
            }
          }
        }
        mech.set_bonding_degree(degree);
      }
      clock.start("mechanics");
      // The mechanics follows the temperature and force changes of the step; where
      // Newton fails (the first melting makes the material collapse within a step) the
      // failed part is halved, down to 1/32 of the step, with linearly interpolated
      // temperature and force. Steps that converge are never subdivided. A 1/32 sub-step
      // whose Newton iteration stalls with an out-of-balance force below 10⁻⁵ of the
      // load (100× the tolerance; measured: 0.004–0.012 N at 3 kN, contact points at the
      // E/S face whose projection switches between master segments) is accepted with a
      // warning instead of failing the run.
      double loose_residual = 0;
      std::string loose_message;
      {
        const Eigen::VectorXd T_start = thermal.committed_temperature();
        const double F_start = problem.schedule.force.at(times[k - 1]), F_end = problem.schedule.force.at(t);
        MechanicsStepReport report;
        std::function<bool(double, double, int)> advance = [&](double s0, double s1, int depth) {
          const double length = (s1 - s0) * dt;
          if (last_mechanics_step > 0) mech.set_predictor(length / last_mechanics_step);
          mech.set_time_step(length);
          report = mech.solve_force_step(F_start + s1 * (F_end - F_start), T_start + s1 * (T_iter - T_start));
          result.n_newton_iterations += report.iterations;
          if (report.converged) {
            mech.commit();
            last_mechanics_step = length;
            return true;
          }
          if (depth == 5) {
            const double load = std::max(std::abs(F_start + s1 * (F_end - F_start)), 1e3);
            if (report.residual > 1e-5 * load) return false;
            mech.commit();
            last_mechanics_step = length;
            ++result.n_mechanics_loose;
            if (report.residual > loose_residual) {
              loose_residual = report.residual;
              loose_message = report.message;
            }
            return true;
          }
          ++result.n_mechanics_substepped;
          const double mid = 0.5 * (s0 + s1);
          return advance(s0, mid, depth + 1) && advance(mid, s1, depth + 1);
        };
        if (!advance(0.0, 1.0, 0))
          return fail("weld stage, step " + std::to_string(k) + " (t = " + std::to_string(t * 1e3) +
                      " ms), mechanics (also in sub-steps of 1/32 step): " + report.message);
        if (loose_residual > 0)
          result.warnings.push_back("weld stage, step " + std::to_string(k) + " (t = " + std::to_string(t * 1e3) +
                                    " ms): mechanics sub-step accepted with an out-of-balance force of " +
                                    std::to_string(loose_residual) + " N (" + loose_message + ")");
      }
      thermal.commit();
      if (const std::string tangled = check_cells(t); !tangled.empty())
        return fail("weld stage, step " + std::to_string(k) + " (t = " + std::to_string(t * 1e3) + " ms): " + tangled);

      if (std::abs(t - current_end) < 1e-12)
        nugget_energy_fraction = nugget_enthalpy(mesh, mech.positions(), thermal.committed_temperature(),
                                                 peak_vector(), sheet_bodies, liquidus, body_materials,
                                                 problem.thermal.initial_temperature) /
                                 electrical_energy;
      if (is_output(t)) {
        clock.start("output");
        record(t);
        while (next_output * problem.output.interval <= t + 1e-9) ++next_output;
      }
    } catch (const std::exception& e) {
      return fail("weld stage, step " + std::to_string(k) + " (t = " + std::to_string(times[k] * 1e3) + " ms): " +
                  e.what());
    }
  }
  {
    const MechanicsSolverCounts c = mech.solver_counts();
    result.mechanics_linear_algebra = {{"gmres_iterations", c.gmres_iterations},
                                       {"factorisations", c.factorisations},
                                       {"surrogates", c.surrogates},
                                       {"lu_factorisations", c.lu_factorisations},
                                       {"cell_matrices_scattered", c.cell_matrices_scattered},
                                       {"cell_matrices_reused", c.cell_matrices_reused}};
    const ThermalSolverCounts t = thermal.solver_counts();
    result.thermal_linear_algebra = {{"solves", t.solves}, {"factorisations", t.factorisations}};
  }
  // Final nugget geometry (MODEL.md §8).
  {
    const auto peak = peak_vector();
    const auto liq = measure_nugget(mesh, mech.positions(), peak, sheet_bodies, liquidus);
    const auto sol = measure_nugget(mesh, mech.positions(), peak, sheet_bodies, solidus);
    auto& n = result.nugget;
    n = {{"d_n_liq", liq.diameter}, {"h_n_liq", liq.height}, {"d_n_sol", sol.diameter}, {"h_n_sol", sol.height}};
    for (std::size_t k = 0; k < liq.penetration.size(); ++k)
      n.emplace_back("penetration_" + problem.geometry.sheets[k].name, liq.penetration[k]);
    double w = 0;
    int n_es = 0;
    for (const auto& st : mech.interface_states())
      if (st.name.rfind("es_", 0) == 0) {
        w += 2 * st.contact_radius;
        ++n_es;
      }
    n.emplace_back("w_elec", n_es ? w / n_es : 0.0);
    n.emplace_back("d_indent", indentation(problem, mesh, mech.displacement()));
    n.emplace_back("t_unmolt", liq.unmolten_thickness);
    result.energy = {{"electrical", electrical_energy}, {"stored", stored_energy}, {"removed", removed_energy},
                     {"imbalance", electrical_energy - stored_energy - removed_energy},
                     {"nugget_fraction", nugget_energy_fraction}};
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
    for (const auto& [name, value] : result.nugget) {
      h5.write("/nugget/" + name, std::vector<double>{value});
      h5.set_attribute("/nugget/" + name, "unit", std::string(name.rfind("penetration", 0) == 0 ? "1" : "m"));
    }
    for (const auto& [name, value] : result.energy) {
      h5.write("/energy/" + name, std::vector<double>{value});
      h5.set_attribute("/energy/" + name, "unit", std::string(name == "nugget_fraction" ? "1" : "J"));
    }
    h5.write_string("/run/config", problem.resolved_config);
    h5.set_attribute("/run", "version", std::string(RSW_VERSION));
    h5.set_attribute("/run", "case", problem.name);
    h5.set_attribute("/run", "wall_time", std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
    h5.set_attribute("/run", "squeeze_indentation", result.squeeze_indentation);
    h5.set_attribute("/run", "electrode_melting_time", result.electrode_melting_time);
    h5.set_attribute("/run", "worst_cell_scaled_jacobian", result.worst_cell.scaled_jacobian);
    h5.set_attribute("/run", "worst_cell_time", result.worst_cell.time);
    h5.set_attribute("/run", "worst_cell_body", result.worst_cell.body);
    h5.set_attribute("/run", "worst_cell_r", result.worst_cell.centre.x());
    h5.set_attribute("/run", "worst_cell_z", result.worst_cell.centre.y());
    std::string warnings;
    for (const auto& w : result.warnings) warnings += (warnings.empty() ? "" : "\n") + w;
    h5.set_attribute("/run", "warnings", warnings);
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
    j["coupling_iterations"] = result.n_coupling_iterations;
    j["mechanics_substep_splits"] = result.n_mechanics_substepped;
    j["mechanics_loose_substeps"] = result.n_mechanics_loose;
    j["coupling_retries"] = result.n_coupling_retries;
    for (const auto& [name, count] : result.mechanics_linear_algebra) j["mechanics_linear_algebra"][name] = count;
    for (const auto& [name, count] : result.thermal_linear_algebra) j["thermal_linear_algebra"][name] = count;
    for (const auto& [name, value] : result.nugget) j["nugget"][name] = value;
    for (const auto& [name, value] : result.energy) j["energy_J"][name] = value;
    j["dynamic_resistance_peak_ohm"] = resistance_peak;  // over all weld steps
    j["squeeze"]["electrode_displacement_m"] = result.squeeze_displacement;
    j["squeeze"]["indentation_m"] = result.squeeze_indentation;
    for (const auto& [name, r] : result.squeeze_contact_radius) j["squeeze"]["contact_radius_m"][name] = r;
    for (const auto& [name, p] : result.squeeze_peak_pressure) j["squeeze"]["peak_pressure_Pa"][name] = p;
    j["warnings"] = result.warnings;
    if (!std::isnan(result.electrode_melting_time)) j["electrode_melting_time_s"] = result.electrode_melting_time;
    j["worst_cell"] = {{"scaled_jacobian", result.worst_cell.scaled_jacobian},
                       {"time_s", result.worst_cell.time},
                       {"cell", result.worst_cell.cell},
                       {"body", result.worst_cell.body},
                       {"r_m", result.worst_cell.centre.x()},
                       {"z_m", result.worst_cell.centre.y()}};
    j["config_yaml"] = problem.resolved_config;
    std::ofstream(partial / "summary.json") << j.dump(2) << "\n";
  }
  fs::remove_all(output_dir);
  fs::rename(partial, output_dir);
  result.success = true;
  return result;
}

}  // namespace rsw::physics
