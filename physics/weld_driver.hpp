// The weld process driver: one run of a weld case, from the squeeze to the end of
// the schedule, as a sequence of stages (physics/weld_simulation.hpp describes the
// stages and the output files; run_weld() is the entry point).
//
//   WeldDriver driver(problem, output_dir, progress);
//   RunResult result = driver.run();
//
// run() calls, in order:
//   setup()         the mesh, the body materials, the mechanics solver, the output folder
//   squeeze()       seat the stack and raise the force to F(0) (physics/squeeze)
//   setup_weld()    the electrical and thermal solvers, the step schedule, the signal
//                   columns and the field writer
//   weld_step(k)    for every step: the electro-thermal fixed point (ElectroThermalStep,
//                   which owns its retries; where it still fails, the step is solved in
//                   halves, down to 1/16 step, as the mechanics is), the electrode-melting check, the energy
//                   bookkeeping, the sheet/sheet bonding, the mechanics
//                   (MechanicsStepper, which owns the sub-stepping), the recorded outputs
//   finish()        the final nugget and energy balance, then the result files
// The driver writes into `partial/` of its claimed output folder and moves the files
// into the folder when the run has finished. A stage that fails returns its message;
// run() then writes failure.txt into the folder and returns the failed RunResult.
#pragma once

#include "contact/interface_law.hpp"
#include "contact/interface_laws.hpp"
#include "fem/mesh.hpp"
#include "fem/mirror.hpp"
#include "fem/output_folder.hpp"
#include "materials/material_library.hpp"
#include "physics/electrical.hpp"
#include "physics/electro_thermal_step.hpp"
#include "physics/mechanics.hpp"
#include "physics/mechanics_stepper.hpp"
#include "physics/nugget.hpp"
#include "physics/problem.hpp"
#include "physics/signal_recorder.hpp"
#include "physics/squeeze.hpp"
#include "physics/stopwatch.hpp"
#include "physics/thermal.hpp"
#include "physics/weld_output.hpp"
#include "physics/weld_simulation.hpp"

#include <Eigen/Dense>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace rsw::physics {

// What the signal columns read at an output time (computed once per row).
struct RecordedState {
  double time = 0;                          // s
  double current = 0, voltage = 0;          // A, V (of the last step)
  bool have_electrical = false;             // a step with current has run
  double force = 0, displacement = 0;       // N, m (electrode travel since the squeeze)
  double max_temperature = 0;               // °C, over the sheets
  std::vector<double> sheet_max_temperature;  // °C, per sheet
  NuggetSize liquidus, solidus;             // on the peak temperature
  std::vector<InterfaceState> interfaces;
  std::vector<double> interface_power;      // W, Joule heat of each interface (last step)
  double bulk_power = 0;                    // W
  double electrical_energy = 0, stored_energy = 0, removed_energy = 0;  // J, since the weld start
  int coupling_iterations = 0;              // of the last step
};

class WeldDriver {
 public:
  // `verbose`: every coupling and Newton iteration to stderr.
  // `folder`: claimed and cleared of an earlier run's files (run_weld).
  WeldDriver(const Problem& problem, fem::OutputFolder& folder,
             std::function<void(const Progress&)> progress = {}, bool verbose = false);
  ~WeldDriver();
  WeldDriver(const WeldDriver&) = delete;  // the solvers hold references to the mesh
  WeldDriver& operator=(const WeldDriver&) = delete;

  RunResult run();

 private:
  void setup();
  std::string squeeze();
  void setup_weld();
  void register_signals();
  std::string weld_step(std::size_t k);
  // The part [t0, t1] of step k; where its electro-thermal coupling fails, the part is
  // solved as two halves, down to 1/2^max_coupling_split of the step.
  std::string weld_part(std::size_t k, double t0, double t1, int depth);
  static constexpr int max_coupling_split = 4;
  void finish();

  // Copies the solvers' counters (Newton iterations, sub-steps, retries) into the result.
  void collect_counts();
  RunResult fail(const std::string& message);
  // The next output time (every output.interval, every step if it is 0) or the last step.
  bool is_output_time(double t) const;
  // "weld stage, step k (t = … ms)", the prefix of every weld-stage message.
  std::string step_label(std::size_t k) const;
  // A message if an electrode node is at or above its solidus in T (°C).
  std::string electrode_melting(const Eigen::VectorXd& T) const;
  // Updates the worst cell of the deformed mesh (RunResult::worst_cell) at time t;
  // a message if a cell has folded.
  std::string check_cells(double t);
  void update_bonding(const Eigen::VectorXd& T);
  void account_energy(double current, double dt);
  void record(double t);
  std::vector<double> peak_temperature() const;

  const Problem& problem_;
  fem::OutputFolder& folder_;
  std::filesystem::path partial_;
  std::function<void(const Progress&)> progress_;
  bool verbose_ = false;
  std::chrono::steady_clock::time_point t_start_;
  RunResult result_;
  Stopwatch clock_;

  fem::Mesh mesh_;
  fem::MirrorSymmetry mirror_;  // of a symmetric stack (solver.mirror_symmetry = auto), else empty
  std::vector<materials::Material> materials_;         // per body
  std::vector<const materials::Material*> body_materials_;
  std::vector<int> sheet_bodies_;                       // top to bottom
  std::vector<double> liquidus_, solidus_;              // °C, per body
  std::unique_ptr<Mechanics> mech_;
  SqueezeResult squeeze_result_;
  double w0_ = 0;                                       // m, end-face position after the squeeze

  contact::InterfaceModel model_;
  std::unique_ptr<Electrical> electrical_;
  std::unique_ptr<Thermal> thermal_;
  std::unique_ptr<ElectroThermalStep> coupling_;
  std::unique_ptr<MechanicsStepper> stepper_;
  std::vector<double> times_;                           // s, step boundaries

  std::unique_ptr<SignalRecorder<RecordedState>> signals_;
  std::unique_ptr<WeldFieldWriter> fields_;
  ContactProfiles profiles_;
  std::size_t next_output_ = 0;

  RecordedState last_;  // the last step's electrical values and the energies so far
  double nugget_energy_fraction_;
  std::string electrode_melting_note_;  // set when an electrode first reaches its solidus
};

}  // namespace rsw::physics
