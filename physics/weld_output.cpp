// The weld run's output files; see weld_output.hpp.
#include "physics/weld_output.hpp"

#include "fem/hdf5_file.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>

#include "rsw_git_commit.hpp"

#ifndef RSW_VERSION
#define RSW_VERSION "unknown"
#endif

namespace rsw::physics {

namespace fs = std::filesystem;

WeldFieldWriter::WeldFieldWriter(const fs::path& pvd, double field_interval, double end_time)
    : series_(pvd),
      field_interval_(field_interval),
      end_time_(end_time),
      last_written_(-std::numeric_limits<double>::infinity()) {}

void WeldFieldWriter::write_if_due(double t, const fem::Mesh& mesh, const Mechanics& mech, const Thermal& thermal,
                                   const Electrical& electrical, bool have_electrical,
                                   const std::vector<double>& peak) {
  if (t < last_written_ + field_interval_ - 1e-9 && t < end_time_ - 1e-12) return;
  last_written_ = t;
  const Eigen::VectorXd& T = thermal.committed_temperature();
  fem::FieldSet fields;
  const Eigen::VectorXd u = mech.displacement();
  fields.add_point_vector("displacement", std::vector<double>(u.data(), u.data() + u.size()), "m");
  fields.add_point_scalar("temperature", std::vector<double>(T.data(), T.data() + T.size()), "degC");
  fields.add_point_scalar("peak_temperature", peak, "degC");
  const Eigen::VectorXd fl = thermal.liquid_fraction();
  fields.add_point_scalar("liquid_fraction", std::vector<double>(fl.data(), fl.data() + fl.size()), "1");
  if (have_electrical) {
    const Eigen::VectorXd& phi = electrical.solution().potential;
    fields.add_point_scalar("potential", std::vector<double>(phi.data(), phi.data() + phi.size()), "V");
    fields.add_cell_scalar("joule_heat", electrical.cell_joule_heat(), "W/m^3");
    std::vector<double> j;
    for (const auto& v : electrical.cell_current_density()) {
      j.push_back(v.x());
      j.push_back(v.y());
    }
    fields.add_cell_vector("current_density", j, "A/m^2");
  } else {
    fields.add_point_scalar("potential", std::vector<double>(mesh.n_nodes(), 0.0), "V");
    fields.add_cell_scalar("joule_heat", std::vector<double>(mesh.n_cells(), 0.0), "W/m^3");
    fields.add_cell_vector("current_density", std::vector<double>(2 * mesh.n_cells(), 0.0), "A/m^2");
  }
  fields.add_cell_scalar("von_mises_stress", mech.von_mises(), "Pa");
  fields.add_cell_scalar("equivalent_plastic_strain", mech.equivalent_plastic_strain(), "1");
  const auto& pairings = mech.pairings();
  const auto& htc = thermal.interface_conductance();
  std::set<std::string> slave_sides;
  for (const auto& pairing : pairings) slave_sides.insert(pairing.slave_boundary());
  for (std::size_t p = 0; p < pairings.size(); ++p) {
    const auto pressure = mech.contact_pressure(static_cast<int>(p));
    const auto& points = pairings[p].points();
    const int n_g = pairings[p].n_gauss();
    const int n_f = pairings[p].n_slave_faces();
    // Per contact point: pressure, gap (NaN where unpaired), the two conductances.
    const auto n_points = points.size();
    std::vector<double> point_he(n_points, 0.0), point_htc(n_points, 0.0);
    for (std::size_t i = 0; i < n_points; ++i) {
      if (have_electrical && p < electrical.solution().interface_conductance.size())
        point_he[i] = electrical.solution().interface_conductance[p][i];
      if (p < htc.size() && i < htc[p].size()) point_htc[i] = htc[p][i];
    }
    std::vector<double> face_p(n_f, 0.0), face_g(n_f, 0.0), face_he(n_f, 0.0), face_htc(n_f, 0.0);
    for (int f = 0; f < n_f; ++f)
      for (int k = 0; k < n_g; ++k) {
        const int i = f * n_g + k;
        face_p[f] += pressure[i] / n_g;
        face_g[f] += (points[i].paired ? points[i].gap : std::nan("")) / n_g;
        face_he[f] += point_he[i] / n_g;
        face_htc[f] += point_htc[i] / n_g;
      }
    const std::string& b = pairings[p].slave_boundary();
    fields.add_face_scalar("contact_pressure", b, face_p, "Pa");
    fields.add_face_scalar("contact_gap", b, face_g, "m");
    fields.add_face_scalar("electrical_conductance", b, face_he, "S/m^2");
    fields.add_face_scalar("thermal_conductance", b, face_htc, "W/(m^2*K)");
    // The master side, unless another pairing has it as its slave side (two-pass
    // contact): each face the area-weighted mean of the paired points projected onto it;
    // a face no point projects onto has no contact (0) and no gap (NaN).
    const std::string& m = pairings[p].master_boundary();
    if (slave_sides.count(m)) continue;
    const std::size_t n_m = mesh.boundary(m).size();
    std::vector<double> area(n_m, 0.0), m_p(n_m, 0.0), m_g(n_m, 0.0), m_he(n_m, 0.0), m_htc(n_m, 0.0);
    for (std::size_t i = 0; i < n_points; ++i) {
      const auto& pt = points[i];
      if (!pt.paired || pt.master_face < 0 || static_cast<std::size_t>(pt.master_face) >= n_m) continue;
      const auto f = static_cast<std::size_t>(pt.master_face);
      area[f] += pt.area;
      m_p[f] += pt.area * pressure[i];
      m_g[f] += pt.area * pt.gap;
      m_he[f] += pt.area * point_he[i];
      m_htc[f] += pt.area * point_htc[i];
    }
    for (std::size_t f = 0; f < n_m; ++f) {
      const double a = area[f];
      m_p[f] = a > 0.0 ? m_p[f] / a : 0.0;
      m_g[f] = a > 0.0 ? m_g[f] / a : std::nan("");
      m_he[f] = a > 0.0 ? m_he[f] / a : 0.0;
      m_htc[f] = a > 0.0 ? m_htc[f] / a : 0.0;
    }
    fields.add_face_scalar("contact_pressure", m, m_p, "Pa");
    fields.add_face_scalar("contact_gap", m, m_g, "m");
    fields.add_face_scalar("electrical_conductance", m, m_he, "S/m^2");
    fields.add_face_scalar("thermal_conductance", m, m_htc, "W/(m^2*K)");
  }
  series_.write_step(t, mesh, fields);
}

void ContactProfiles::add(double t, const std::vector<InterfaceState>& states) {
  if (names.empty())
    for (const auto& st : states) names.push_back(st.name);
  radius.resize(states.size());
  pressure.resize(states.size());
  gap.resize(states.size());
  for (std::size_t i = 0; i < states.size(); ++i) {
    radius[i].push_back(states[i].radius);
    pressure[i].push_back(states[i].pressure);
    gap[i].push_back(states[i].gap);
  }
  times.push_back(t);
}

namespace {
// One line on each of the run's final nugget and energy values (results.h5).
std::string nugget_description(const std::string& name) {
  static const std::map<std::string, std::string> known = {
      {"d_n_liq", "nugget diameter at the liquidus in the faying plane, at the end (peak-temperature field)"},
      {"h_n_liq", "nugget height at the liquidus on the axis, at the end (peak-temperature field)"},
      {"d_n_sol", "nugget diameter at the solidus in the faying plane, at the end (peak-temperature field)"},
      {"h_n_sol", "nugget height at the solidus on the axis, at the end (peak-temperature field)"},
      {"w_elec", "electrode/sheet contact width at the end: twice the mean contact radius of those interfaces"},
      {"d_indent", "indentation depth of the electrodes at the end"},
      {"t_unmolt", "unmolten thickness on the axis: the smaller distance from the liquidus nugget to the outer surfaces"}};
  if (const auto it = known.find(name); it != known.end()) return it->second;
  if (name.rfind("penetration_", 0) == 0)
    return "z-extent of the liquidus region (surface melt included) inside " + name.substr(12) +
           ", over its thickness on the axis";
  return name;
}

std::string energy_description(const std::string& name) {
  static const std::map<std::string, std::string> known = {
      {"electrical", "electrical energy delivered over the run"},
      {"stored", "heat stored in the bodies over the run (enthalpy gained)"},
      {"removed", "heat removed by the cooling water, the air and fixed temperatures over the run"},
      {"imbalance", "electrical - stored - removed: the energy balance's error"},
      {"nugget_fraction", "share of the electrical energy held in the nugget when the current stops"}};
  if (const auto it = known.find(name); it != known.end()) return it->second;
  return name;
}

fem::RowMajorMatrix to_matrix(const std::vector<std::vector<double>>& rows) {
  fem::RowMajorMatrix m;
  m.n_rows = rows.size();
  m.n_cols = rows.empty() ? 0 : rows.front().size();
  for (const auto& row : rows) m.values.insert(m.values.end(), row.begin(), row.end());
  return m;
}
}  // namespace

void write_results_h5(const fs::path& file, const Problem& problem, const RunResult& result,
                      const SqueezeResult& squeeze, const ContactProfiles& profiles,
                      std::chrono::steady_clock::time_point t_start) {
  const Signals& sig = result.signals;
  fem::Hdf5File h5(file, fem::Hdf5Mode::truncate);
  const auto describe = [&h5](const std::string& path, const std::string& unit, const std::string& description) {
    if (!unit.empty()) h5.set_attribute(path, "unit", unit);
    h5.set_attribute(path, "description", description);
  };
  for (std::size_t c = 0; c < sig.names.size(); ++c) {
    h5.write("/signals/" + sig.names[c], sig.columns[c]);
    describe("/signals/" + sig.names[c], sig.units[c],
             (c < sig.descriptions.size() ? sig.descriptions[c] : sig.names[c]) + ", at each output time");
  }
  std::vector<double> sq_force, sq_disp, sq_iter;
  for (const auto& s : squeeze.steps) {
    sq_force.push_back(s.force);
    sq_disp.push_back(s.displacement);
    sq_iter.push_back(s.iterations);
  }
  h5.write("/squeeze/force", sq_force);
  describe("/squeeze/force", "N", "electrode force at each squeeze step");
  h5.write("/squeeze/displacement", sq_disp);
  describe("/squeeze/displacement", "m", "upper electrode end-face displacement at each squeeze step");
  h5.write("/squeeze/newton_iterations", sq_iter);
  describe("/squeeze/newton_iterations", "1", "Newton iterations of each squeeze step");
  h5.write("/contact/output_times", profiles.times);
  describe("/contact/output_times", "s", "times of the rows of the contact profiles");
  for (std::size_t i = 0; i < profiles.names.size(); ++i) {
    const std::string g = "/contact/" + profiles.names[i];
    const std::string where = " of interface " + profiles.names[i] + ": a row per output time, a column per contact point";
    h5.write(g + "/radius", to_matrix(profiles.radius[i]));
    describe(g + "/radius", "m", "radius of the contact points" + where);
    h5.write(g + "/pressure", to_matrix(profiles.pressure[i]));
    describe(g + "/pressure", "Pa", "contact pressure" + where);
    h5.write(g + "/gap", to_matrix(profiles.gap[i]));
    describe(g + "/gap", "m", "normal gap (negative: penetration)" + where);
  }
  for (const auto& [name, value] : result.nugget) {
    h5.write_scalar("/nugget/" + name, value);
    describe("/nugget/" + name, name.rfind("penetration_", 0) == 0 ? "1" : "m", nugget_description(name));
  }
  for (const auto& [name, value] : result.energy) {
    h5.write_scalar("/energy/" + name, value);
    describe("/energy/" + name, name == "nugget_fraction" ? "1" : "J", energy_description(name));
  }
  h5.write_string("/run/config", problem.resolved_config);
  describe("/run/config", "", "the resolved weld case: every key, in display units (YAML)");
  h5.set_attribute("/run", "version", std::string(RSW_VERSION));
  h5.set_attribute("/run", "git_commit", std::string(RSW_GIT_COMMIT));
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

void write_signals_csv(const fs::path& file, const Signals& sig) {
  std::ofstream csv(file);
  for (std::size_t c = 0; c < sig.names.size(); ++c) csv << (c ? "," : "") << sig.names[c] << " [" << sig.units[c] << "]";
  csv << "\n";
  csv.precision(10);
  for (std::size_t r = 0; r < sig.n_rows(); ++r) {
    for (std::size_t c = 0; c < sig.names.size(); ++c) csv << (c ? "," : "") << sig.columns[c][r];
    csv << "\n";
  }
}

void write_summary_json(const fs::path& file, const Problem& problem, const RunResult& result) {
  nlohmann::json j;
  j["status"] = "success";
  for (const auto& [part, seconds] : result.timing) j["timing_s"][part] = seconds;
  j["version"] = RSW_VERSION;
  j["git_commit"] = RSW_GIT_COMMIT;
  j["case"] = problem.name;
  j["wall_time_s"] = result.wall_time;
  j["weld_steps"] = result.n_steps;
  j["mirror_symmetry"] = result.mirror_symmetry;
  j["newton_iterations"] = result.n_newton_iterations;
  j["coupling_iterations"] = result.n_coupling_iterations;
  j["mechanics_substep_splits"] = result.n_mechanics_substepped;
  j["mechanics_loose_substeps"] = result.n_mechanics_loose;
  j["coupling_retries"] = result.n_coupling_retries;
  j["coupling_newton_solves"] = result.n_coupling_newton_solves;
  j["coupling_newton_rescues"] = result.n_coupling_newton_rescues;
  j["coupling_substep_splits"] = result.n_coupling_splits;
  for (const auto& [name, count] : result.mechanics_linear_algebra) j["mechanics_linear_algebra"][name] = count;
  for (const auto& [name, count] : result.thermal_linear_algebra) j["thermal_linear_algebra"][name] = count;
  for (const auto& [name, value] : result.nugget) j["nugget"][name] = value;
  for (const auto& s : result.sheets)
    j["sheets"][s.sheet] = {{"material", s.material}, {"solidus_degC", s.solidus}, {"liquidus_degC", s.liquidus}};
  for (const auto& [name, value] : result.energy) j["energy_J"][name] = value;
  // The same peak as `rsw simulate` prints: the largest V/I of the signals (output times).
  if (const Signals::Peak peak = result.signals.maximum("resistance"); peak.found) {
    j["dynamic_resistance_peak_ohm"] = peak.value;
    j["dynamic_resistance_peak_time_s"] = peak.time;
  }
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
  std::ofstream(file) << j.dump(2) << "\n";
}

}  // namespace rsw::physics
