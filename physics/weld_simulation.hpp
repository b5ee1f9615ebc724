// The weld run: one run of a weld case from the squeeze to the end of the schedule,
// with its outputs. run_weld() is the entry point; the stages are the methods of
// physics::WeldDriver (weld_driver.hpp).
//
// Stages:
//  1. Squeeze (physics/squeeze): seat the stack under displacement control, then
//     raise the electrode force to F(0) in `solver.squeeze_force_steps` steps.
//  2. Weld stage, t = 0 ... end of current + cool time, on a fixed step schedule
//     (weld_step_times): every breakpoint of the current and force tables, every
//     output time and solver.early_phase_end are step boundaries; no step is longer
//     than solver.early_time_step up to early_phase_end, or solver.time_step after
//     it. The schedule depends on the case's tables and settings only, never on the
//     model parameters. Each step iterates electrical ⇄ thermal to
//     `solver.coupling_tolerance` on the contact state of the last mechanics solve
//     (physics/electro_thermal_step), then solves the mechanics at the step's force
//     and new temperature (physics/mechanics_stepper; staggered coupling).
//
// Outputs, in the output folder (fem/output_folder.hpp: a new folder, an empty one or
// one rsw made before, marked by `.rsw-output`; anything else is refused unless
// `overwrite`, and nothing rsw did not write is removed or replaced). A run first
// removes an earlier run's files there (listed in the marker), writes into
// `partial/` and moves the files into the folder when it has finished: a failed run
// leaves `failure.txt` (and `partial/`) and never a complete-looking result, old or
// new. physics/weld_output.hpp lists the fields:
//   results.h5    signals, squeeze history, contact pressure and gap profiles at output times,
//                 nugget, energy, the resolved config, version, timing (h5py / h5dump)
//   signals.csv   the signals, one row per output time, units in the header
//   fields.pvd    ParaView time series of fields_NNNN.vtm
//   summary.json  status, resolved config, version, timing, iteration counts and the
//                 key results
#pragma once

#include "fem/mesh.hpp"
#include "physics/problem.hpp"

#include <filesystem>
#include <functional>
#include <cmath>
#include <string>
#include <vector>

namespace rsw::physics {

// Step boundaries of the weld stage (s), from 0 to the end time: every breakpoint of
// the current and force tables, every output time and the end of the early phase, and
// in between equal steps no longer than solver.early_time_step (up to the early phase's
// end) or solver.time_step (after it).
std::vector<double> weld_step_times(const Problem& problem);

struct Signals {
  std::vector<std::string> names;
  std::vector<std::string> units;
  std::vector<std::string> descriptions;
  std::vector<std::vector<double>> columns;
  int column(const std::string& name) const;  // -1 if absent
  std::size_t n_rows() const { return columns.empty() ? 0 : columns.front().size(); }
  // The largest finite value of a column and its time (the first on ties); found is false
  // if the column is absent or has no finite value. The one "peak" of a signal that the
  // printout and summary.json both report.
  struct Peak {
    bool found = false;
    double value = 0, time = 0;
  };
  Peak maximum(const std::string& name) const;
};

struct RunResult {
  bool success = false;
  std::string message;              // failure reason, naming the stage and step
  std::filesystem::path output_dir;
  Signals signals;
  double wall_time = 0;             // s
  // Wall time per part of the run (s): setup, squeeze, electrical, thermal, mechanics, output.
  std::vector<std::pair<std::string, double>> timing;
  int n_steps = 0;
  bool mirror_symmetry = false;     // the upper half was solved, the lower half its image (solver.mirror_symmetry)
  int n_newton_iterations = 0;
  int n_coupling_iterations = 0;    // electro-thermal iterations, summed over steps
  int n_mechanics_substepped = 0;   // mechanics sub-steps made by halving (mechanics_stepper.hpp)
  int n_mechanics_loose = 0;        // smallest sub-steps accepted at a stalled residual (mechanics_stepper.hpp)
  int n_coupling_retries = 0;       // electro-thermal solves retried (electro_thermal_step.hpp)
  int n_coupling_newton_solves = 0;  // of the steps the first Anderson iteration failed: solved by Newton
  int n_coupling_newton_rescues = 0;  // of which converged
  int n_coupling_splits = 0;        // weld steps (or parts) halved after the coupling failed
  double first_coupling_split_end = std::nan("");  // s, end of the first step solved in parts
  // Linear algebra of the mechanics (gmres_iterations, factorisations, surrogates,
  // lu_factorisations, cell_matrices_scattered, cell_matrices_reused,
  // interior_unknowns, border_unknowns, condensations, condensations_reused; see
  // MechanicsSolverCounts).
  std::vector<std::pair<std::string, long>> mechanics_linear_algebra;
  // Linear algebra of the thermal solves (solves, factorisations; ThermalSolverCounts).
  std::vector<std::pair<std::string, long>> thermal_linear_algebra;
  // Final nugget geometry (d_n_liq, h_n_liq, d_n_sol, h_n_sol, penetration_<sheet>,
  // w_elec, d_indent, t_unmolt; m or fractions) and the energy balance (electrical,
  // stored, removed, imbalance in J; nugget_fraction of the electrical energy held
  // as enthalpy by the nugget when the current stops).
  std::vector<std::pair<std::string, double>> nugget;
  std::vector<std::pair<std::string, double>> energy;
  // Key results at the end of the squeeze.
  double squeeze_displacement = 0;  // m, upper end face travel (negative: down)
  std::vector<std::pair<std::string, double>> squeeze_contact_radius;  // per interface, m
  // Each sheet's material and its solidus and liquidus (degC), the isotherms of the
  // nugget (summary.json "sheets"; tools/paraview_weld.py draws them).
  struct SheetMelting {
    std::string sheet, material;
    double solidus = 0, liquidus = 0;
  };
  std::vector<SheetMelting> sheets;
  std::vector<std::pair<std::string, double>> squeeze_peak_pressure;   // per interface, Pa
  double squeeze_indentation = 0;   // m, sheet_1 top on the axis relative to r = cap radius
  // Warnings of a successful run (e.g. an electrode that reached its solidus with
  // solver.electrode_melting = continue), in the order they arose.
  std::vector<std::string> warnings;
  double electrode_melting_time = std::nan("");  // s, first step with an electrode node at its solidus
  // The worst cell shape of the deformed mesh over the run (squeeze and weld stage):
  // the least corner scaled Jacobian (fem::scaled_jacobian: 1 for a rectangle, 0.87
  // for the 60° corners of the electrode flanks), the weld-stage time it was reached
  // (0: the squeeze), the cell, its body and its centre then. A value ≤ 0 (a folded
  // cell) fails the run.
  struct WorstCell {
    double scaled_jacobian = 1;
    double time = 0;  // s
    int cell = -1;
    std::string body;
    fem::Point centre = fem::Point::Zero();  // m
  } worst_cell;
};

struct Progress {
  std::string stage;  // "squeeze", "weld"
  int step = 0, n_steps = 0;
  double time = 0;    // s, weld-stage time
  double max_temperature = 0;  // °C
  double resistance = 0;       // Ω, V/I (0 without current)
};

// The entries a weld run writes into its output folder ("fields_*": every entry that
// begins so); an earlier run's are removed when a run starts.
const std::vector<std::string>& weld_output_names();

// Runs the case and writes its outputs (see above). Never throws for a failing
// simulation: the failure is in RunResult::message and in failure.txt. Bad input
// (unknown material, a folder it may not use, one in use by another run) throws;
// a refused folder throws fem::OutputFolderError before anything is computed.
// `verbose` prints every coupling and Newton iteration to stderr (a diagnosis aid);
// `overwrite` accepts a non-empty output folder rsw did not make.
RunResult run_weld(const Problem& problem, const std::filesystem::path& output_dir,
                   const std::function<void(const Progress&)>& progress = {}, bool verbose = false,
                   bool overwrite = false);

}  // namespace rsw::physics
