// The weld process driver; see weld_driver.hpp and weld_simulation.hpp.
#include "physics/weld_driver.hpp"

#include "contact/interface_coupling.hpp"
#include "fem/fe_values.hpp"
#include "meshes/weld_mesh.hpp"
#include "physics/interface_model.hpp"
#include "physics/plausibility.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <utility>

namespace rsw::physics {

namespace fs = std::filesystem;

namespace {
// The largest of a nodal field (any container indexed by node) over one body's nodes.
template <class Values>
double highest_on_body(const fem::Mesh& mesh, const Values& values, int body) {
  double highest = -1e300;
  for (int node = 0; node < mesh.n_nodes(); ++node)
    if (mesh.node_body[node] == body) highest = std::max(highest, static_cast<double>(values[node]));
  return highest;
}


// The material name of a mesh body: the electrodes' and the sheets' materials of the case.
std::string material_of_body(const Problem& problem, const std::string& body) {
  if (body == "upper_electrode") return problem.geometry.upper.material;
  if (body == "lower_electrode") return problem.geometry.lower.material;
  for (const auto& s : problem.geometry.sheets)
    if (s.name == body) return s.material;
  throw std::logic_error("no material for body " + body);
}

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
// same surface 1 mm outside the electrode face, mean of the top and bottom sheets (m).
double indentation(const Problem& problem, const fem::Mesh& mesh, const Eigen::VectorXd& u) {
  const auto& g = problem.geometry;
  const std::string top = g.sheets.front().name + ".top", bottom = g.sheets.back().name + ".bottom";
  const double r_top = 0.5 * g.upper.face_diameter + 1e-3, r_bottom = 0.5 * g.lower.face_diameter + 1e-3;
  const double d_top = boundary_uz_at(mesh, u, top, r_top) - boundary_uz_at(mesh, u, top, 0.0);
  const double d_bottom = boundary_uz_at(mesh, u, bottom, 0.0) - boundary_uz_at(mesh, u, bottom, r_bottom);
  return 0.5 * (d_top + d_bottom);
}

// Enthalpy gained by the nugget (sheet cells whose centre reached the liquidus),
// ∫ ρ_0 (H(T) − H(T_0)) dV (J).
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

WeldDriver::WeldDriver(const Problem& problem, fem::OutputFolder& folder,
                       std::function<void(const Progress&)> progress, bool verbose)
    : problem_(problem),
      folder_(folder),
      partial_(folder.path() / "partial"),
      progress_(std::move(progress)),
      verbose_(verbose),
      clock_(result_.timing),
      nugget_energy_fraction_(std::nan("")) {}

WeldDriver::~WeldDriver() = default;

RunResult WeldDriver::run() {
  t_start_ = std::chrono::steady_clock::now();
  setup();
  if (const std::string failure = squeeze(); !failure.empty()) return fail(failure);
  setup_weld();
  clock_.start("output");
  if (is_output_time(0.0)) {
    record(0.0);
    ++next_output_;
  }
  for (std::size_t k = 1; k < times_.size(); ++k) {
    // Anything a solver throws mid-step (an inverted cell, a failed factorisation)
    // fails the run with the step named, like the failures the step reports.
    try {
      if (const std::string failure = weld_step(k); !failure.empty()) return fail(failure);
    } catch (const std::exception& e) {
      return fail(step_label(k) + ": " + e.what());
    }
  }
  finish();
  return result_;
}

void WeldDriver::collect_counts() {
  if (stepper_) {
    result_.n_newton_iterations += stepper_->newton_iterations();
    result_.n_mechanics_substepped = stepper_->splits();
    result_.n_mechanics_loose = stepper_->loose_substeps();
  }
  if (coupling_) {
    result_.n_coupling_retries = coupling_->retries();
    result_.n_coupling_newton_solves = coupling_->newton_solves();
    result_.n_coupling_newton_rescues = coupling_->newton_rescues();
  }
}

RunResult WeldDriver::fail(const std::string& message) {
  collect_counts();
  result_.success = false;
  result_.message = message;
  if (!electrode_melting_note_.empty())
    result_.message += " (after an electrode had melted, " + electrode_melting_note_ + ")";
  folder_.record("failure.txt");
  std::ofstream(folder_.path() / "failure.txt") << result_.message << "\n";
  result_.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start_).count();
  return result_;
}

bool WeldDriver::is_output_time(double t) const {
  if (problem_.output.interval == 0) return true;  // every step
  return std::abs(t - next_output_ * problem_.output.interval) < 1e-9 || t >= times_.back() - 1e-12;
}

std::string WeldDriver::step_label(std::size_t k) const {
  return "weld stage, step " + std::to_string(k) + " (t = " + std::to_string(times_[k] * 1e3) + " ms)";
}

void WeldDriver::setup() {
  clock_.start("setup");
  result_.output_dir = folder_.path();
  mesh_ = meshes::weld_mesh(problem_.geometry, problem_.mesh);
  // A symmetric stack is solved on its upper half (fem/mirror.hpp); nodes are matched
  // to 1 nm (the finest cells are 60 µm). A one-pass sheet/sheet contact (slave and
  // master sheet) is not symmetric, so its stack is solved whole.
  if (problem_.solver.mirror_symmetry && problem_.solver.two_pass_sheet_contact)
    if (const std::vector<int> bodies = meshes::mirror_bodies(problem_.geometry, mesh_); !bodies.empty())
      mirror_ = fem::find_mirror_symmetry(mesh_, bodies, 1e-9);
  result_.mirror_symmetry = !mirror_.empty();
  materials::MaterialLibrary library;
  materials_.reserve(mesh_.n_bodies());
  for (const auto& body : mesh_.body_names) materials_.push_back(library.load(material_of_body(problem_, body)));
  for (const auto& m : materials_) body_materials_.push_back(&m);
  for (const auto& sh : problem_.geometry.sheets) {
    sheet_bodies_.push_back(mesh_.body_index(sh.name));
    const materials::Material& m = materials_[sheet_bodies_.back()];
    result_.sheets.push_back({sh.name, sh.material, m.solidus(), m.liquidus()});
  }
  for (int b = 0; b < mesh_.n_bodies(); ++b) {
    liquidus_.push_back(body_materials_[b]->liquidus());
    solidus_.push_back(body_materials_[b]->solidus());
  }

  folder_.record("partial");
  fs::create_directories(partial_);

  MechanicsSettings ms;
  ms.friction_coefficient = problem_.contact.friction_coefficient;
  ms.contact_penalty_factor = problem_.solver.contact_penalty_factor;
  ms.contact_smoothing = problem_.solver.contact_smoothing;
  ms.friction_penalty_ratio = problem_.solver.friction_penalty_ratio;
  ms.mechanics_tolerance = problem_.solver.mechanics_tolerance;
  ms.mechanics_error_estimate = problem_.solver.mechanics_error_estimate;
  ms.verbose = verbose_;
  if (problem_.solver.two_pass_sheet_contact)
    for (const auto& [name, pair] : mesh_.interfaces)
      if (pair.kind == meshes::interface_kind::sheet_sheet) ms.two_pass_interfaces.push_back(name);
  ms.mirror = mirror_;
  mech_ = std::make_unique<Mechanics>(mesh_, body_materials_, ms, problem_.thermal.initial_temperature);
}

std::string WeldDriver::check_cells(double t) {
  // The mesh is Lagrangian and never remeshed: where the material flows far (molten
  // metal pressed out at the edge of the sheet/sheet contact) a cell can fold over a
  // corner while its quadrature-point Jacobians stay positive, and the fields on it are
  // meaningless.
  const std::vector<fem::Point>& x = mech_->positions();
  int worst = -1;
  double value = 2;
  for (int e = 0; e < mesh_.n_cells(); ++e)
    if (const double q = fem::scaled_jacobian(x, mesh_.cells[e]); q < value) {
      value = q;
      worst = e;
    }
  auto& w = result_.worst_cell;
  if (worst < 0 || !(value < w.scaled_jacobian || w.cell < 0)) return {};
  w.scaled_jacobian = value;
  w.time = t;
  w.cell = worst;
  w.body = mesh_.body_names[mesh_.cell_body[worst]];
  w.centre.setZero();
  for (int n : mesh_.cells[worst]) w.centre += 0.25 * x[n];
  if (value > 0) return {};
  char text[320];
  std::snprintf(text, sizeof text,
                "the deformed mesh has folded: cell %d of %s at (r, z) = (%.3f, %.3f) mm has a corner with scaled "
                "Jacobian %.3f (<= 0); the material there has moved further than the fixed mesh can follow "
                "(see docs/MODEL.md, Known limitations)",
                worst, w.body.c_str(), w.centre.x() * 1e3, w.centre.y() * 1e3, value);
  return text;
}

std::string WeldDriver::squeeze() {
  if (progress_) progress_({"squeeze", 0, 0, 0.0});
  clock_.start("squeeze");
  const Eigen::VectorXd T = Eigen::VectorXd::Constant(mesh_.n_nodes(), problem_.thermal.initial_temperature);
  SqueezeSettings ss;
  ss.seat_step = problem_.solver.seat_step;
  ss.squeeze_force_steps = problem_.solver.squeeze_force_steps;
  try {
    squeeze_result_ = physics::squeeze(*mech_, problem_.schedule.force.at(0.0), T, ss);
  } catch (const std::exception& e) {
    return std::string("squeeze: ") + e.what();
  }
  for (const auto& s : squeeze_result_.steps) result_.n_newton_iterations += s.iterations;
  if (!squeeze_result_.converged) return "squeeze: " + squeeze_result_.message;
  if (const std::string tangled = check_cells(0.0); !tangled.empty()) return "squeeze: " + tangled;
  result_.squeeze_displacement = mech_->end_face_displacement();
  for (const auto& st : mech_->interface_states()) {
    result_.squeeze_contact_radius.emplace_back(st.name, st.contact_radius);
    result_.squeeze_peak_pressure.emplace_back(st.name, *std::max_element(st.pressure.begin(), st.pressure.end()));
  }
  result_.squeeze_indentation = indentation(problem_, mesh_, mech_->displacement());
  w0_ = mech_->end_face_displacement();
  return {};
}

void WeldDriver::setup_weld() {
  clock_.start("setup");
  model_ = interface_model(mesh_, problem_.contact);
  ElectricalSettings es;
  es.mirror = mirror_;
  electrical_ = std::make_unique<Electrical>(mesh_, body_materials_, model_, es);
  ThermalSettings th = thermal_settings(problem_.thermal);
  th.verbose = verbose_;
  th.mirror = mirror_;
  thermal_ = std::make_unique<Thermal>(mesh_, body_materials_, model_, th);
  CouplingSettings cs;
  cs.acceleration_depth = problem_.solver.coupling_acceleration_depth;
  cs.tolerance = problem_.solver.coupling_tolerance;
  cs.max_iterations = problem_.solver.max_coupling_iterations;
  cs.thermal_tolerance = th.temperature_tolerance;
  coupling_ = std::make_unique<ElectroThermalStep>(mesh_, *electrical_, *thermal_, cs, clock_, verbose_);
  stepper_ = std::make_unique<MechanicsStepper>(*mech_);
  times_ = weld_step_times(problem_);
  result_.n_steps = static_cast<int>(times_.size()) - 1;
  last_.interface_power.assign(mech_->interface_states().size(), 0.0);
  register_signals();
  if (problem_.output.fields)
    fields_ = std::make_unique<WeldFieldWriter>(partial_ / "fields.pvd", problem_.output.field_interval, times_.back());
}

void WeldDriver::register_signals() {
  signals_ = std::make_unique<SignalRecorder<RecordedState>>(result_.signals);
  auto& s = *signals_;
  using S = const RecordedState&;
  s.add("time", "s", "schedule time (0 where the current and force tables start)", [](S r) { return r.time; });
  s.add("current", "A", "welding current", [](S r) { return r.current; });
  s.add("voltage", "V", "voltage between the electrodes",
        [](S r) { return r.have_electrical ? r.voltage : 0.0; });
  s.add("resistance", "ohm", "dynamic resistance, voltage / current (NaN below 1 A)", [](S r) {
    return (r.have_electrical && std::abs(r.current) > 1.0) ? r.voltage / r.current : std::nan("");
  });
  s.add("force", "N", "electrode force", [](S r) { return r.force; });
  s.add("displacement", "m", "electrode displacement S: the upper electrode's end face since the squeeze ended",
        [](S r) { return r.displacement; });
  s.add("temperature", "degC", "highest temperature in the sheets", [](S r) { return r.max_temperature; });
  for (std::size_t i = 0; i < problem_.geometry.sheets.size(); ++i)
    s.add("temperature_" + problem_.geometry.sheets[i].name, "degC",
          "highest temperature in " + problem_.geometry.sheets[i].name,
          [i](S r) { return r.sheet_max_temperature[i]; });
  s.add("d_n_liq", "m", "nugget diameter at the liquidus in the faying plane (peak-temperature field)",
        [](S r) { return r.liquidus.diameter; });
  s.add("h_n_liq", "m", "nugget height at the liquidus on the axis (peak-temperature field)",
        [](S r) { return r.liquidus.height; });
  s.add("d_n_sol", "m", "nugget diameter at the solidus in the faying plane (peak-temperature field)",
        [](S r) { return r.solidus.diameter; });
  s.add("h_n_sol", "m", "nugget height at the solidus on the axis (peak-temperature field)",
        [](S r) { return r.solidus.height; });
  const auto states = mech_->interface_states();
  for (std::size_t i = 0; i < states.size(); ++i)
    s.add("contact_radius_" + states[i].name, "m", "contact radius of interface " + states[i].name,
          [i](S r) { return r.interfaces[i].contact_radius; });
  for (std::size_t i = 0; i < states.size(); ++i)
    s.add("joule_power_" + states[i].name, "W", "Joule heat of interface " + states[i].name + "'s contact resistance",
          [i](S r) { return r.interface_power[i]; });
  s.add("joule_power_bulk", "W", "Joule heat in the bodies", [](S r) { return r.bulk_power; });
  s.add("electrical_energy", "J", "electrical energy delivered, the integral of voltage times current",
        [](S r) { return r.electrical_energy; });
  s.add("stored_energy", "J", "heat stored in the bodies (enthalpy gained)", [](S r) { return r.stored_energy; });
  s.add("removed_energy", "J", "heat removed by the cooling water, the air and fixed temperatures",
        [](S r) { return r.removed_energy; });
  s.add("coupling_iterations", "1", "electro-thermal coupling iterations of the step",
        [](S r) { return static_cast<double>(r.coupling_iterations); });
}

std::vector<double> WeldDriver::peak_temperature() const {
  const Eigen::VectorXd& pk = thermal_->peak_temperature();
  return std::vector<double>(pk.data(), pk.data() + pk.size());
}

void WeldDriver::record(double t) {
  RecordedState r = last_;
  r.time = t;
  r.have_electrical = coupling_->has_electrical_solution();
  r.force = mech_->electrode_force();
  r.displacement = mech_->end_face_displacement() - w0_;
  const Eigen::VectorXd& T = thermal_->committed_temperature();
  r.max_temperature = -1e300;
  for (int b : sheet_bodies_) {
    const double m = highest_on_body(mesh_, T, b);
    r.sheet_max_temperature.push_back(m);
    r.max_temperature = std::max(r.max_temperature, m);
  }
  const auto peak = peak_temperature();
  r.liquidus = measure_nugget(mesh_, mech_->positions(), peak, sheet_bodies_, liquidus_);
  r.solidus = measure_nugget(mesh_, mech_->positions(), peak, sheet_bodies_, solidus_);
  r.interfaces = mech_->interface_states();
  signals_->record(r);
  profiles_.add(t, r.interfaces);
  if (fields_)
    fields_->write_if_due(t, mesh_, *mech_, *thermal_, *electrical_, r.have_electrical, peak);
}

std::string WeldDriver::electrode_melting(const Eigen::VectorXd& T) const {
  for (int n = 0; n < mesh_.n_nodes(); ++n) {
    const int b = mesh_.node_body[n];
    if (std::find(sheet_bodies_.begin(), sheet_bodies_.end(), b) != sheet_bodies_.end()) continue;
    if (!(T[n] < solidus_[b])) {
      char text[320];
      std::snprintf(text, sizeof text,
                    "%s reaches %.0f degC at (r, z) = (%.2f, %.2f) mm, above the solidus of its material (%.0f degC)",
                    mesh_.body_names[b].c_str(), T[n], mech_->positions()[n].x() * 1e3,
                    mech_->positions()[n].y() * 1e3, solidus_[b]);
      return text + std::string(": a melting electrode is outside the model (contact parameters too resistive?)");
    }
  }
  return {};
}

void WeldDriver::account_energy(double I, double dt) {
  // Backward Euler: the end-of-step power times dt.
  last_.current = I;
  if (I != 0.0) {
    const auto& sol = electrical_->solution();
    last_.voltage = sol.voltage;
    last_.electrical_energy += sol.voltage * I * dt;
    last_.bulk_power = sol.bulk_power;
    for (std::size_t p = 0; p < last_.interface_power.size() && p < sol.interface_power.size(); ++p)
      last_.interface_power[p] = sol.interface_power[p];
  } else {
    last_.voltage = 0;
    last_.bulk_power = 0;
    std::fill(last_.interface_power.begin(), last_.interface_power.end(), 0.0);
  }
  last_.stored_energy += thermal_->energy().stored;
  last_.removed_energy += thermal_->energy().removed();
}

void WeldDriver::update_bonding(const Eigen::VectorXd& T) {
  // Sheets fuse where both sides of a sheet/sheet point approach their solidus: the
  // bonding degree β (contact::bonding_degree; the committed thermal history, or this
  // step's temperatures) never decreases, and the mechanics ties the point with the
  // share β of its traction from this step on (Mechanics::set_bonding_degree), so
  // molten sheets never meet across a frictionless contact.
  const auto& bonding = thermal_->interface_history();
  const auto& pairings = mech_->pairings();
  std::vector<std::vector<double>> degree(pairings.size());
  for (std::size_t p = 0; p < pairings.size(); ++p) {
    degree[p].assign(pairings[p].points().size(), 0.0);
    const contact::InterfaceLaw& law = *model_.interfaces[p].law;
    if (!law.bonds()) continue;
    for (std::size_t i = 0; i < degree[p].size(); ++i) {
      const auto& pt = pairings[p].points()[i];
      double& beta = degree[p][i];
      if (static_cast<int>(p) < bonding.n_interfaces()) beta = bonding.degree(static_cast<int>(p), static_cast<int>(i));
      if (beta < 1 && pt.paired) {
        contact::InterfacePoint sides;
        sides.slave = body_materials_[mesh_.node_body[pt.slave_nodes[0]]];
        sides.master = body_materials_[mesh_.node_body[pt.master_nodes[0]]];
        sides.slave_temperature = contact::slave_value(pt, T);
        sides.master_temperature = contact::master_value(pt, T);
        sides.gap = pt.gap;
        beta = std::max(beta, law.bonding_degree(sides));
      }
    }
  }
  mech_->set_bonding_degree(degree);
}

std::string WeldDriver::weld_step(std::size_t k) { return weld_part(k, times_[k - 1], times_[k], 0); }

std::string WeldDriver::weld_part(std::size_t k, double t0, double t, int depth) {
  const double dt = t - t0;
  const double I = problem_.schedule.current.at(t);
  const bool step_end = t == times_[k];
  const contact::ContactState contact = contact_state(*mech_);

  // 1. Electro-thermal fixed point on the contact state of the last mechanics solve.
  // Where it fails (current crowding into a contact edge that heats and conducts
  // better can outrun the fixed point within one step), the part is solved in halves:
  // the schedule itself, and every step where the coupling converges, stay as they are.
  const CoupledStepReport coupled = coupling_->solve(dt, I, mech_->positions(), contact);
  if (!coupled.converged && depth < max_coupling_split) {
    ++result_.n_coupling_splits;
    if (std::isnan(result_.first_coupling_split_end)) result_.first_coupling_split_end = t;
    result_.n_coupling_iterations += coupled.iterations;
    const double mid = 0.5 * (t0 + t);
    if (std::string failure = weld_part(k, t0, mid, depth + 1); !failure.empty()) return failure;
    return weld_part(k, mid, t, depth + 1);
  }
  if (!coupled.converged) {
    // Where an electrode is melting, the failure names it first (the likely cause) and
    // keeps the solver's own message after it.
    const std::string melting = I != 0.0 ? electrode_melting(thermal_->temperature()) : std::string();
    char part[96];
    std::snprintf(part, sizeof part, " (also in parts of 1/%d step; the part ending at %.4f ms)",
                  1 << max_coupling_split, t * 1e3);
    return step_label(k) + ", " + (melting.empty() ? coupled.failure : melting + "; there " + coupled.failure) +
           part;
  }
  const Eigen::VectorXd T_iter = thermal_->temperature();

  // 2. An electrode that melts (sticking, alloying with the sheet) is outside the model.
  // With solver.electrode_melting = continue (the default) the first step where an
  // electrode node reaches its solidus is recorded as a warning and the run goes on,
  // so that the outputs stay continuous across the boundary of that region of the
  // parameters (a failed run is a cliff in the likelihood); with `stop` the run fails.
  // A later failure names the melting electrode.
  if (std::isnan(result_.electrode_melting_time))
    if (const std::string melting = electrode_melting(T_iter); !melting.empty()) {
      if (problem_.solver.stop_on_electrode_melting) return step_label(k) + ": " + melting;
      result_.electrode_melting_time = t;
      char at[64];
      std::snprintf(at, sizeof at, "at t = %.1f ms: ", t * 1e3);
      electrode_melting_note_ = at + melting.substr(0, melting.find(": a melting electrode"));
      result_.warnings.push_back(at + melting + "; the run goes on (solver.electrode_melting = continue)");
    }
  last_.coupling_iterations = coupled.iterations;
  result_.n_coupling_iterations += coupled.iterations;
  account_energy(I, dt);

  if (progress_ && step_end)
    progress_({"weld", static_cast<int>(k), result_.n_steps, t, T_iter.maxCoeff(),
               I != 0.0 ? electrical_->solution().resistance : 0.0});
  if (verbose_)
    std::fprintf(stderr, "step %zu: t = %.1f ms, T_max = %.1f, T(apex) = %.1f, coupling %d\n", k, t * 1e3,
                 T_iter.maxCoeff(), T_iter[mesh_.boundary_nodes("upper_electrode.contact_face").front()],
                 coupled.iterations);

  // 3. Bonding, then the mechanics at the step's force and new temperature.
  update_bonding(T_iter);
  clock_.start("mechanics");
  const MechanicsStepOutcome mech =
      stepper_->advance(dt, problem_.schedule.force.at(t0), problem_.schedule.force.at(t),
                        thermal_->committed_temperature(), T_iter);
  if (!mech.converged)
    return step_label(k) + ", mechanics (also in sub-steps of 1/32 step): " + mech.failure;
  if (mech.loose_residual > 0)
    result_.warnings.push_back(step_label(k) + ": mechanics sub-step accepted with an out-of-balance force of " +
                               std::to_string(mech.loose_residual) + " N (" + mech.loose_message + ")");
  thermal_->commit();
  if (const std::string tangled = check_cells(t); !tangled.empty()) return step_label(k) + ": " + tangled;

  // 4. Outputs, at the end of the step only: the nugget's share of the energy when the
  // current stops, the signals (and fields) at output times.
  if (!step_end) return {};
  if (std::abs(t - problem_.schedule.current.time.back()) < 1e-12)
    nugget_energy_fraction_ = nugget_enthalpy(mesh_, mech_->positions(), thermal_->committed_temperature(),
                                              peak_temperature(), sheet_bodies_, liquidus_, body_materials_,
                                              problem_.thermal.initial_temperature) /
                              last_.electrical_energy;
  if (is_output_time(t)) {
    clock_.start("output");
    record(t);
    if (problem_.output.interval > 0)
      while (next_output_ * problem_.output.interval <= t + 1e-9) ++next_output_;
  }
  return {};
}

void WeldDriver::finish() {
  collect_counts();
  const MechanicsSolverCounts c = mech_->solver_counts();
  result_.mechanics_linear_algebra = {{"gmres_iterations", c.gmres_iterations},
                                      {"factorisations", c.factorisations},
                                      {"surrogates", c.surrogates},
                                      {"lu_factorisations", c.lu_factorisations},
                                      {"cell_matrices_scattered", c.cell_matrices_scattered},
                                      {"cell_matrices_reused", c.cell_matrices_reused},
                                      {"interior_unknowns", c.interior_unknowns},
                                      {"border_unknowns", c.border_unknowns},
                                      {"condensations", c.condensations},
                                      {"condensations_reused", c.condensations_reused}};
  const ThermalSolverCounts t = thermal_->solver_counts();
  result_.thermal_linear_algebra = {{"solves", t.solves}, {"factorisations", t.factorisations}};

  // The final nugget geometry, measured on the interpolated peak temperature.
  const auto peak = peak_temperature();
  const auto liq = measure_nugget(mesh_, mech_->positions(), peak, sheet_bodies_, liquidus_);
  const auto sol = measure_nugget(mesh_, mech_->positions(), peak, sheet_bodies_, solidus_);
  auto& n = result_.nugget;
  n = {{"d_n_liq", liq.diameter}, {"h_n_liq", liq.height}, {"d_n_sol", sol.diameter}, {"h_n_sol", sol.height}};
  for (std::size_t k = 0; k < liq.penetration.size(); ++k)
    n.emplace_back("penetration_" + problem_.geometry.sheets[k].name, liq.penetration[k]);
  double w = 0;
  int n_es = 0;
  for (const auto& st : mech_->interface_states())
    if (mesh_.interfaces.at(st.name).kind == meshes::interface_kind::electrode_sheet) {
      w += 2 * st.contact_radius;
      ++n_es;
    }
  n.emplace_back("w_elec", n_es ? w / n_es : 0.0);
  n.emplace_back("d_indent", indentation(problem_, mesh_, mech_->displacement()));
  n.emplace_back("t_unmolt", liq.unmolten_thickness);

  // Results the solvers reached but an engineer would reject (plausibility.hpp).
  WeldOutcome outcome;
  outcome.nugget_diameter = liq.diameter;
  outcome.melt_extent = liq.extent;
  for (std::size_t k = 0; k < liq.penetration.size(); ++k)
    outcome.penetration.emplace_back(problem_.geometry.sheets[k].name, liq.penetration[k]);
  for (int b : sheet_bodies_)
    outcome.sheets.push_back({mesh_.body_names[b], materials_[b].name(), highest_on_body(mesh_, peak, b),
                              materials_[b].boiling_point()});
  outcome.face_diameter = std::min(problem_.geometry.upper.face_diameter, problem_.geometry.lower.face_diameter);
  outcome.stack_height = problem_.geometry.stack_height();
  for (std::string& warning : plausibility_warnings(outcome)) result_.warnings.push_back(std::move(warning));
  // A step solved in parts is a finer time discretisation of that step, used only where
  // the coupling failed: where that switches on or off between neighbouring parameter
  // values, the features step (by about 0.1 % on the paper's case; docs/VERIFICATION.md,
  // "Smoothness over the prior").
  if (result_.n_coupling_splits > 0) {
    char note[320];
    std::snprintf(note, sizeof note,
                  "numerics: the electro-thermal coupling did not converge on a whole weld step %d time%s (first on the "
                  "step ending at %.2f ms), so those steps were solved in parts: a finer time discretisation "
                  "than where the coupling converges, and features can step slightly between such parameter values",
                  result_.n_coupling_splits, result_.n_coupling_splits == 1 ? "" : "s",
                  result_.first_coupling_split_end * 1e3);
    result_.warnings.emplace_back(note);
  }
  const double e = last_.electrical_energy, stored = last_.stored_energy, removed = last_.removed_energy;
  result_.energy = {{"electrical", e},          {"stored", stored}, {"removed", removed},
                    {"imbalance", e - stored - removed}, {"nugget_fraction", nugget_energy_fraction_}};

  clock_.start("output");
  write_results_h5(partial_ / "results.h5", problem_, result_, squeeze_result_, profiles_, t_start_);
  write_signals_csv(partial_ / "signals.csv", result_.signals);
  clock_.stop();
  result_.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start_).count();
  write_summary_json(partial_ / "summary.json", problem_, result_);
  folder_.install(partial_, "summary.json");  // last: a summary.json means a complete result
  result_.success = true;
}

}  // namespace rsw::physics
