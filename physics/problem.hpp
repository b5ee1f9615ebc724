// The weld case: one resistance spot weld described by one YAML file, resolved into
// plain structs in SI units (m, s, A, N, Pa, W, ohm; temperatures in degC, angles in
// rad).
//
// weld_case_schema() declares every key of a case once (default, unit, range, doc);
// docs/CONFIG.md is generated from it. load_problem() reads a case file, applies
// `--set key=value` overrides, checks every value and the relations between values
// (face inside the cap, bore behind the flank, schedule starting at 0, ...), and
// fills a Problem. The schema is the one place a default lives: the structs below
// are value-initialised (zero) and every field is set by make_problem(), and a
// solver setting that mirrors a key takes its default from case_default(). Defaults
// reproduce the paper's case (2 x 1 mm DP1200, CuCrZr R30
// caps, 8 kA for 150 ms, 3 kN; paper §2.1) with contact parameters at the centres of
// the paper's prior (Table I); see the key docs for the reasoning.
#pragma once

#include "fem/config.hpp"
#include "meshes/weld_geometry.hpp"

#include <string>
#include <vector>

namespace rsw::physics {

// y(t) linear between the points (time[i], value[i]) and held constant before the
// first point and after the last one.
struct PiecewiseLinear {
  std::vector<double> time;   // s, strictly increasing
  std::vector<double> value;  // unit of the quantity tabulated
  double at(double t) const;
};

struct Schedule {
  PiecewiseLinear current;  // A, welding current I(t)
  PiecewiseLinear force;    // N, electrode force F(t)
  double cool_time = 0;     // s, the run ends this long after the last current point
  double end_time() const;  // s
};

// Parameters of one interface type in the contact laws: electrical conductance
// h_e = 1 / (rho_contact t_f) with rho_contact = 3 (sigma_soft/sigma_n)(rho_1 + rho_2)/2
// + rho_c (paper eq. 1), and the thermal HTC scaled by P1 (paper eq. 2).
struct InterfaceContact {
  double film_thickness{};       // m, t_f
  double coating_resistivity{};  // ohm*m, rho_c
  double htc_p1{};               // -, P1
};

struct ContactParameters {
  InterfaceContact electrode_sheet;  // both E/S interfaces (upper and lower)
  InterfaceContact sheet_sheet;      // every S/S interface
  double htc_p2{};                   // m, P2 of paper eq. 2
  double htc_p3{};                   // -, P3
  double htc_p4{};                   // -, P4
  double friction_coefficient{};     // -, Coulomb mu
  double bonding_band{};             // K, S/S bonding degree rises over this much below the solidus (0: at once)
  double bonding_gap{};              // m, S/S points farther apart than this do not bond
  bool film_breakdown{};             // rho_c fades with the film breakdown degree
  double film_breakdown_start{};     // degC, the film starts to break down (hotter side)
  double film_breakdown_end{};       // degC, the film is gone
  bool film_replaces_bulk{};         // the interface adds only the resistance in excess of bulk
};

struct ThermalParameters {
  double initial_temperature{};     // degC
  double water_htc{};               // W/(m^2*K), cooling bore wall
  double water_temperature{};       // degC
  double air_htc{};                 // W/(m^2*K), other free surfaces
  double ambient_temperature{};     // degC
  double melt_conductivity{};       // W/(m*K), lambda_m of paper eq. 3
  double melt_conductivity_band{};  // K, blend from the table to lambda_m below T_melting (0: switch)
};

struct SolverSettings {
  double time_step{};                 // s, largest step of the weld stage
  double early_time_step{};           // s, largest step up to early_phase_end
  double early_phase_end{};           // s after the weld start; 0: no early phase
  int squeeze_force_steps{};          // force-controlled squeeze steps
  double seat_step{};                 // m, seating travel per step
  double contact_penalty_factor{};    // -, eps_N = factor * E / h
  double contact_smoothing{};         // m, delta of the C1 penalty law
  bool two_pass_sheet_contact{};      // solver.sheet_contact = two_pass
  double friction_penalty_ratio{};    // -, eps_T = ratio * eps_N (stick stiffness of the regularised friction)
  double coupling_tolerance{};        // K, electro-thermal fixed-point tolerance
  int max_coupling_iterations{};
  int coupling_acceleration_depth{};  // Anderson depth (0: plain fixed-point iteration)
  double mechanics_tolerance{};       // -, Newton's residual tolerance relative to the electrode force
  double mechanics_error_estimate{};  // m, Newton's estimated remaining displacement error that ends a step
  bool stop_on_electrode_melting{};   // fail the run when an electrode reaches its solidus
  bool mirror_symmetry{};             // solver.mirror_symmetry = auto: solve the upper half of a symmetric stack
};

struct OutputSettings {
  std::string directory;
  double interval{};        // s, between output steps (signals); 0: every time step
  double field_interval{};  // s, least time between field outputs
  bool fields{};            // write .vtu field files
};

struct Problem {
  std::string name;
  meshes::StackGeometry geometry;  // sheets named sheet_1 ... sheet_n, top to bottom
  meshes::MeshSettings mesh;
  Schedule schedule;
  ContactParameters contact;
  ThermalParameters thermal;
  SolverSettings solver;
  OutputSettings output;
  std::string resolved_config;  // every key in display units (YAML), for echoing
};

// Every key of a weld case.
fem::ConfigSchema weld_case_schema();

// The default of a number or integer key of the weld case in internal units (e.g.
// "solver.friction_penalty_ratio" -> 0.1): the default of a solver setting that
// mirrors the key.
double case_default(const std::string& key);

// A Problem from a resolved config; checks the relations between keys and throws
// fem::ConfigError naming the key the user set, its value and origin.
Problem make_problem(const fem::Config& config);

// Reads the case file, applies the overrides ("key=value") in order, checks
// everything; throws fem::ConfigError.
Problem load_problem(const std::string& path,
                     const std::vector<std::string>& set_overrides = {});

}  // namespace rsw::physics
