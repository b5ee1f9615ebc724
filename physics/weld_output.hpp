// The weld run's output files: the field time series (ParaView), the contact profiles
// at output times, and results.h5, signals.csv and summary.json.
//
// Fields (fields.pvd, one fields_NNNN.vtm per written time): nodal displacement (m),
// temperature and peak temperature (°C), liquid fraction, potential (V); per cell the
// Joule heat (W/m³), current density (A/m²), von Mises stress (Pa) and equivalent
// plastic strain; per slave face of each interface the contact pressure (Pa), gap (m)
// and the electrical (S/m²) and thermal (W/(m²·K)) conductances, each the mean over
// the face's Gauss points. Written at the first output time, then at output times at
// least output.field_interval after the last written one, and at the last step.
#pragma once

#include "fem/mesh.hpp"
#include "fem/vtk_output.hpp"
#include "physics/electrical.hpp"
#include "physics/mechanics.hpp"
#include "physics/problem.hpp"
#include "physics/squeeze.hpp"
#include "physics/thermal.hpp"
#include "physics/weld_simulation.hpp"

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace rsw::physics {

class WeldFieldWriter {
 public:
  // `end_time`: the last step's time (s), always written.
  WeldFieldWriter(const std::filesystem::path& pvd, double field_interval, double end_time);

  // Writes the fields at time t (s) if it is due (see above). `electrical` is read only
  // if `have_electrical` (a step with current has run; zeros before).
  void write_if_due(double t, const fem::Mesh& mesh, const Mechanics& mech, const Thermal& thermal,
                    const Electrical& electrical, bool have_electrical, const std::vector<double>& peak);

 private:
  fem::VtkTimeSeries series_;
  double field_interval_, end_time_;
  double last_written_;
};

// The contact state of each interface at the output times: radius and pressure of
// every slave point (m, Pa).
struct ContactProfiles {
  std::vector<double> times;  // s
  std::vector<std::string> names;
  // [interface][output time][point]; gap > 0 open, NaN where a point has no partner
  std::vector<std::vector<std::vector<double>>> radius, pressure, gap;

  void add(double t, const std::vector<InterfaceState>& states);
};

// results.h5: signals, squeeze history, contact profiles, nugget, energy, the resolved
// case and the run's attributes (version, wall time since t_start, worst cell, warnings).
void write_results_h5(const std::filesystem::path& file, const Problem& problem, const RunResult& result,
                      const SqueezeResult& squeeze, const ContactProfiles& profiles,
                      std::chrono::steady_clock::time_point t_start);

// signals.csv: one row per output time, a `name [unit]` header.
void write_signals_csv(const std::filesystem::path& file, const Signals& signals);

// summary.json: status, timing, counts, nugget, energy, squeeze, warnings, worst cell and
// the resolved case.
void write_summary_json(const std::filesystem::path& file, const Problem& problem, const RunResult& result);

}  // namespace rsw::physics
