// Transient heat conduction in enthalpy form with contact interfaces; see thermal.hpp.
#include "physics/thermal.hpp"

#include "contact/interface_coupling.hpp"
#include "fem/assembler.hpp"
#include "fem/constraints.hpp"
#include "fem/dof_map.hpp"
#include "fem/fe_values.hpp"
#include "fem/linear_solver.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace rsw::physics {

namespace {
using Matrix4 = Eigen::Matrix<double, 4, 4>;
using Vector4 = Eigen::Matrix<double, 4, 1>;

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The λ_m blend weight w(T) = smoothstep(T; T_m − δ, T_m) (slope) and its integral
// W(T) = ∫_{−∞}^T w dτ (value), K: with s = (T − T_m + δ)/δ clamped to [0, 1],
// W = δ (s³ − s⁴/2) inside the band, 0 below it and δ/2 + (T − T_m) above.
materials::PropertyValue melt_blend(double T, double T_m, double band) {
  const double s = (T - (T_m - band)) / band;
  if (s <= 0) return {0.0, 0.0};
  if (s >= 1) return {0.5 * band + (T - T_m), 1.0};
  return {band * s * s * s * (1 - 0.5 * s), s * s * (3 - 2 * s)};
}
}  // namespace

ThermalSettings thermal_settings(const ThermalParameters& p) {
  ThermalSettings s;
  s.initial_temperature = p.initial_temperature;
  s.water_htc = p.water_htc;
  s.water_temperature = p.water_temperature;
  s.air_htc = p.air_htc;
  s.ambient_temperature = p.ambient_temperature;
  s.melt_conductivity = p.melt_conductivity;
  s.melt_conductivity_band = p.melt_conductivity_band;
  return s;
}

struct Thermal::Impl {
  const fem::Mesh& mesh;
  ThermalSettings settings;
  std::vector<const materials::Material*> body_material;
  std::vector<const materials::Material*> cell_material;
  std::vector<char> melt_switch_cell;  // the cell's body switches to λ_m
  std::vector<char> coefficient_cell;  // k and the melt state are evaluated on the cell (see the constructor)
  std::vector<const materials::Material*> node_material;
  int n_q;

  fem::DofMap dofs;
  fem::Constraints constraints;
  contact::InterfaceCoupling interfaces;  // pairings (the coupling pattern), laws, coupling groups
  const std::vector<contact::InterfacePairing>& pairings = interfaces.pairings();
  const std::vector<std::pair<int, int>>& groups = interfaces.groups();  // (pairing, slave face)
  std::unique_ptr<fem::Assembler> assembler;
  bool implicit_blend;  // the λ_m blend weight follows the Newton iterate (settings)
  fem::LinearSolver solver;
  fem::SparseMatrix K;
  Eigen::VectorXd F;

  std::vector<double> cell_mass;  // ∫ ρ_0 N_a dV_0 per cell and local node, kg
  Eigen::VectorXd nodal_mass;     // kg
  std::vector<fem::BoundaryFace> water_faces, air_faces;
  Eigen::VectorXd fixed_weight;   // 1 on fixed-temperature nodes, hanging nodes interpolated

  // State.
  Eigen::VectorXd T, T_old, peak;      // °C
  Eigen::VectorXd T_previous;          // °C, the committed field before T_old
  double previous_dt = 0;              // s, the step that led to T_old (0: none)
  Eigen::VectorXd H, dH, H_old;        // J/kg and J/(kg K), nodal
  std::vector<char> melt_state;        // per cell Gauss point: k = λ_m this step (sharp switch)
  std::vector<double> conductivity_q;  // k per cell Gauss point, at the solve's starting field
  // The table conductivity at the solve's starting field, per cell Gauss point (the
  // part of k that stays lagged when the λ_m blend is implicit).
  std::vector<double> table_conductivity_q;
  bool new_step = true;
  bool start_given = false;            // set_start() before the next solve
  contact::InterfaceHistory history, trial_history;
  std::vector<std::vector<double>> conductance;  // per pairing point, last evaluation
  fem::CellGeometry geometry;                    // of the configuration of the last solve
  const fem::Mesh& current = geometry.current();
  const std::vector<double>& JxW = geometry.JxW();                     // per cell Gauss point
  const std::vector<Eigen::Vector2d>& grad = geometry.grad();          // ∇N_a per cell Gauss point
  const std::vector<std::array<double, 4>>& shape = geometry.shape();  // N_a at the reference Gauss points
  bool need_matrix = true;                       // kernels compute ∂R/∂T too
  bool factorized = false;                       // the solver holds a factorisation of this step
  long n_solves = 0, n_factorizations = 0;       // summed over the run (solver_counts)
  ThermalEnergy energy;

  // Inputs of the current solve.
  double dt = 0;
  const contact::ContactState* contact = nullptr;
  const std::vector<double>* joule = nullptr;
  const std::vector<std::vector<double>>* interface_heat = nullptr;

  Impl(const fem::Mesh& m, std::vector<const materials::Material*> materials_of_body, contact::InterfaceModel mdl,
       const ThermalSettings& s)
      : mesh(m),
        settings(s),
        body_material(std::move(materials_of_body)),
        n_q(s.n_gauss * s.n_gauss),
        dofs(m, 1),
        constraints(dofs.n_dofs()),
        interfaces(m, std::move(mdl), dofs, s.n_gauss, s.search_margin, "Thermal"),
        implicit_blend(s.melt_conductivity > 0 && s.melt_conductivity_band > 0 && s.implicit_melt_blend),
        solver(implicit_blend ? fem::SolverKind::klu : fem::SolverKind::cholmod),
        geometry(m, s.n_gauss) {
    // The unsymmetric tangent (λ_m blend) is factorised by KLU, which refactorises each
    // new tangent of the fixed pattern with the pivot sequence of the last pivoted
    // factorisation (fem::LinearSolver; test
    // LinearSolver.KluRefactorisationKeepsThePivotsAndIsBackwardStable): on the default
    // weld 2.7–3.6 ms per factorisation on the entries ever nonzero (6.4 ms on the
    // whole contact pattern, against UMFPACK's 13 ms), the same fields
    // (docs/PERFORMANCE.md). No iterative refinement: the Newton loop below
    // re-evaluates the true residual after every correction, and a chord step's
    // factorisation is of an earlier tangent anyway.
    if (s.n_gauss < 1 || s.n_gauss > 3) throw std::invalid_argument("Thermal: n_gauss must be 1, 2 or 3");
    if (static_cast<int>(body_material.size()) != mesh.n_bodies())
      throw std::invalid_argument("Thermal: one material per body expected");
    for (int e = 0; e < mesh.n_cells(); ++e) {
      const int b = mesh.cell_body[e];
      cell_material.push_back(body_material[b]);
      melt_switch_cell.push_back(s.melt_conductivity > 0 && mesh.body_names[b].rfind(s.melt_conductivity_prefix, 0) == 0);
    }
    for (int n = 0; n < mesh.n_nodes(); ++n) node_material.push_back(body_material[mesh.node_body[n]]);

    if (!s.mirror.empty()) {
      // A fixed temperature on the lower half must mirror one on the upper half.
      std::vector<double> fixed(mesh.n_nodes(), std::nan(""));
      for (const auto& [name, value] : s.fixed_temperatures)
        for (int n : mesh.boundary_nodes(name)) fixed[n] = value;
      for (int n = 0; n < mesh.n_nodes(); ++n)
        if (s.mirror.is_image(n) && !(fixed[n] == fixed[s.mirror.image_of[n]]) &&
            !(std::isnan(fixed[n]) && std::isnan(fixed[s.mirror.image_of[n]])))
          throw std::invalid_argument("Thermal: under a mirror the fixed temperatures must be symmetric (node " +
                                      std::to_string(n) + " and its image differ)");
    }
    fem::add_mirror_constraints(constraints, mesh, dofs, s.mirror, {1.0});  // before the fixed values
    constraints.add_hanging_nodes(mesh, dofs);
    for (const auto& [name, value] : s.fixed_temperatures) {
      const double v = value;
      constraints.constrain_boundary(mesh, dofs, name, 0, [v](const fem::Point&) { return v; });
    }
    constraints.close();

    for (const auto& pairing : pairings) conductance.emplace_back(pairing.points().size(), 0.0);
    assembler = std::make_unique<fem::Assembler>(mesh, dofs, constraints, interfaces.dof_groups());
    assembler->set_mirror(s.mirror);
    // The conductivities and melt states of a cell the assembler skips (an image cell
    // under a mirror) serve only the reaction at fixed temperatures.
    for (int e = 0; e < mesh.n_cells(); ++e)
      coefficient_cell.push_back(assembler->cell_weight(e) > 0 || !s.fixed_temperatures.empty());
    history = contact::InterfaceHistory(pairings);
    trial_history = history;

    // Lumped capacity on the undeformed mesh: M_a = ∫ ρ_0 N_a dV_0.
    cell_mass.assign(4 * static_cast<std::size_t>(mesh.n_cells()), 0.0);
    nodal_mass = Eigen::VectorXd::Zero(mesh.n_nodes());
    fem::CellValues cv(s.n_gauss);
    for (int e = 0; e < mesh.n_cells(); ++e) {
      cv.reinit(mesh, e);
      const double rho0 = cell_material[e]->density(materials::reference_temperature).value;
      for (int q = 0; q < cv.n_q(); ++q)
        for (int a = 0; a < 4; ++a) cell_mass[4 * e + a] += rho0 * cv.N(q, a) * cv.JxW(q);
      for (int a = 0; a < 4; ++a) nodal_mass[mesh.cells[e][a]] += cell_mass[4 * e + a];
    }

    // Convection boundaries.
    std::vector<std::string> fixed;
    for (const auto& fx : s.fixed_temperatures) fixed.push_back(fx.first);
    for (const auto& [name, faces] : mesh.boundaries) {
      if (std::find(fixed.begin(), fixed.end(), name) != fixed.end()) continue;
      bool adiabatic = false;
      for (const auto& suffix : s.adiabatic_suffixes) adiabatic = adiabatic || ends_with(name, suffix);
      if (adiabatic) continue;
      auto& target = ends_with(name, s.water_suffix) ? water_faces : air_faces;
      target.insert(target.end(), faces.begin(), faces.end());
    }
    fixed_weight = Eigen::VectorXd::Zero(mesh.n_nodes());
    for (const auto& name : fixed)
      for (int n : mesh.boundary_nodes(name)) fixed_weight[n] = 1.0;
    for (const auto& h : mesh.hanging_nodes)
      fixed_weight[h.node] = 0.5 * (fixed_weight[h.parents[0]] + fixed_weight[h.parents[1]]);

    melt_state.assign(static_cast<std::size_t>(mesh.n_cells()) * n_q, 0);
    conductivity_q.assign(melt_state.size(), 0.0);
    table_conductivity_q.assign(melt_state.size(), 0.0);
    set_temperature(Eigen::VectorXd::Constant(mesh.n_nodes(), s.initial_temperature));
  }

  void set_temperature(const Eigen::VectorXd& field) {
    T_old = field;
    T_previous = field;
    previous_dt = 0;
    T = field;
    peak = field;
    H_old.resize(mesh.n_nodes());
    for (int n = 0; n < mesh.n_nodes(); ++n) H_old[n] = node_material[n]->enthalpy(T_old[n]).value;
    new_step = true;
  }

  void check_inputs(const contact::ContactState& state, const std::vector<double>& q_v,
                    const std::vector<std::vector<double>>& q_s) const {
    interfaces.check(state);
    for (std::size_t p = 0; p < pairings.size(); ++p)
      if (!q_s.empty() && q_s[p].size() != (*state.pairings)[p].points().size())
        throw std::invalid_argument("Thermal: interface heat of '" + pairings[p].name() + "' has the wrong size");
    if (!q_v.empty() && q_v.size() != melt_state.size())
      throw std::invalid_argument("Thermal: bulk Joule heat must have one value per cell Gauss point");
    if (!q_s.empty() && q_s.size() != pairings.size())
      throw std::invalid_argument("Thermal: interface heat must have one list per interface");
  }

  // The inputs of a solve (checked) and the Gauss-point geometry of its configuration.
  void set_inputs(double step, const std::vector<fem::Point>& positions, const contact::ContactState& state,
                  const std::vector<double>& q_v, const std::vector<std::vector<double>>& q_s) {
    check_inputs(state, q_v, q_s);
    geometry.update(positions);
    dt = step;
    contact = &state;
    joule = &q_v;
    interface_heat = &q_s;
  }

  // The λ_m switch states of paper eq. 3 for the step, at the field T (the step's
  // starting iterate): k = λ_m at the Gauss points of the sheet bodies at or above
  // T_melting.
  void update_melt_states() {
    for (int e = 0; e < mesh.n_cells(); ++e) {
      if (!melt_switch_cell[e] || !coefficient_cell[e]) continue;
      const auto& c = mesh.cells[e];
      const double T_m = cell_material[e]->melting_temperature();
      for (int q = 0; q < n_q; ++q) {
        double Tq = 0;
        for (int a = 0; a < 4; ++a) Tq += shape[q][a] * T[c[a]];
        melt_state[static_cast<std::size_t>(e) * n_q + q] = Tq >= T_m;
      }
    }
  }

  // k at every cell Gauss point for the field T: the table, or λ_m where the step's
  // switch state says so, or the C¹ blend of a smoothing band.
  void update_conductivities() {
    const double lambda_m = settings.melt_conductivity;
    for (int e = 0; e < mesh.n_cells(); ++e) {
      if (!coefficient_cell[e]) continue;
      const auto& c = mesh.cells[e];
      const materials::Material& mat = *cell_material[e];
      const double T_m = mat.melting_temperature();
      for (int q = 0; q < n_q; ++q) {
        const std::size_t k = static_cast<std::size_t>(e) * n_q + q;
        double Tq = 0;
        for (int a = 0; a < 4; ++a) Tq += shape[q][a] * T[c[a]];
        const double table = mat.thermal_conductivity(Tq).value;
        table_conductivity_q[k] = table;
        if (!melt_switch_cell[e]) {
          conductivity_q[k] = table;
        } else if (settings.melt_conductivity_band > 0) {
          const double w = materials::smoothstep(Tq, T_m - settings.melt_conductivity_band, T_m).value;
          conductivity_q[k] = (1 - w) * table + w * lambda_m;
        } else {
          conductivity_q[k] = melt_state[k] ? lambda_m : table;
        }
      }
    }
  }

  // Capacity, conduction and bulk source of one cell; local.vector = −R_e, matrix = ∂R_e/∂T.
  void cell_kernel(int e, fem::LocalSystem& local) {
    const auto& c = mesh.cells[e];
    Matrix4 Ke = Matrix4::Zero();
    Vector4 Re = Vector4::Zero();
    Vector4 Tc;
    for (int a = 0; a < 4; ++a) {
      const int n = c[a];
      Tc[a] = T[n];
      const double m = cell_mass[4 * e + a];
      Re[a] += m * (H[n] - H_old[n]) / dt;  // M_a (H(T_a) − H(T_a^n))/Δt
      Ke(a, a) += m * dH[n] / dt;           // M_a H'(T_a)/Δt
    }
    const bool matrix = need_matrix;
    const bool blend = implicit_blend && melt_switch_cell[e];
    std::array<double, 4> blend_weight{}, blend_integral{};  // w(T_b), W(T_b)
    if (blend) {
      const double T_m = cell_material[e]->melting_temperature();
      for (int b = 0; b < 4; ++b) {
        const auto wb = melt_blend(Tc[b], T_m, settings.melt_conductivity_band);
        blend_weight[b] = wb.slope;
        blend_integral[b] = wb.value;
      }
    }
    for (int q = 0; q < n_q; ++q) {
      const std::size_t k = static_cast<std::size_t>(e) * n_q + q;
      const Eigen::Vector2d* g = &grad[4 * k];
      const std::array<double, 4>& N = shape[q];
      Eigen::Vector2d grad_T = Eigen::Vector2d::Zero();
      for (int a = 0; a < 4; ++a) grad_T += Tc[a] * g[a];
      const double qw = (joule->empty() ? 0.0 : (*joule)[k]) * JxW[k];
      if (blend) {
        // Conduction with the λ_m blend in nodal Kirchhoff form:
        //   q = −k_t ∇T − (λ_m − k_t) ∇(Σ_b N_b W(T_b)),  W(T) = ∫ w dT,
        // k_t the table conductivity at the solve's start (lagged). Its tangent,
        // [k_t + (λ_m − k_t) w(T_b)] ∇N_b·∇N_a, scales the columns of a conduction
        // matrix by positive nodal conductivities: bounded however steep the blend.
        const double table = table_conductivity_q[k];
        const double jump = settings.melt_conductivity - table;
        Eigen::Vector2d grad_W = Eigen::Vector2d::Zero();
        for (int b = 0; b < 4; ++b) grad_W += blend_integral[b] * g[b];
        const Eigen::Vector2d flux = table * grad_T + jump * grad_W;
        for (int a = 0; a < 4; ++a) {
          Re[a] += JxW[k] * flux.dot(g[a]) - qw * N[a];
          if (matrix)
            for (int b = 0; b < 4; ++b) Ke(a, b) += JxW[k] * (table + jump * blend_weight[b]) * g[b].dot(g[a]);
        }
        continue;
      }
      const double kw = conductivity_q[k] * JxW[k];
      for (int a = 0; a < 4; ++a) {
        Re[a] += kw * grad_T.dot(g[a]) - qw * N[a];  // k ∇T·∇N_a − q_v N_a
        if (matrix)
          for (int b = a; b < 4; ++b) Ke(a, b) += kw * g[b].dot(g[a]);  // k ∇N_b·∇N_a
      }
    }
    if (matrix && !blend)
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < a; ++b) Ke(a, b) = Ke(b, a);
    local.matrix += Ke;
    local.vector -= Re;
  }

  // Convection h (T − T_∞) on a boundary face.
  void face_kernel(const fem::BoundaryFace& f, double h, double T_inf, fem::LocalSystem& local, double* heat) {
    thread_local std::unique_ptr<fem::FaceValues> scratch;
    if (!scratch || scratch->n_q() != settings.n_gauss) scratch = std::make_unique<fem::FaceValues>(settings.n_gauss);
    fem::FaceValues& fv = *scratch;
    fv.reinit(current, f.cell, f.face);
    const auto& c = mesh.cells[f.cell];
    for (int q = 0; q < fv.n_q(); ++q) {
      double Tq = 0;
      for (int a = 0; a < 4; ++a) Tq += fv.N(q, a) * T[c[a]];
      const double w = fv.JxW(q);
      if (heat) *heat += h * (Tq - T_inf) * w;
      for (int a = 0; a < 4; ++a) {
        local.vector[a] -= h * (Tq - T_inf) * fv.N(q, a) * w;
        for (int b = 0; b < 4; ++b) local.matrix(a, b) += h * fv.N(q, a) * fv.N(q, b) * w;
      }
    }
  }

  // Conductance h of every pairing point (HTC·χ, or bonded; 0 where unpaired or
  // outside the coupling pattern) at the current T. The solve evaluates it once, at
  // the temperature it starts from: h depends steeply on T near the solidus (σ_d
  // falls to the strength floor) and the table kinks of σ_d and k would make Newton
  // cycle; like σ(T) of the electrical field it is updated by the staggered coupling.
  void interface_conductances() {
    interfaces.conductances(contact::InterfaceField::thermal, *contact, history, T, node_material, conductance);
  }

  // Thermal contact and interface heat at the points of one slave face:
  // R += h (T_s − T_m)(v_s − v_m) A − q_s (v_s + v_m)/2 A.
  void group_kernel(int g, fem::LocalSystem& local, double* interface_power) {
    local.lists_touched = true;
    const auto [p, f] = groups[g];
    const auto& pairing = (*contact->pairings)[p];
    for (int k = 0; k < pairing.n_gauss(); ++k) {
      const int i = f * pairing.n_gauss() + k;
      const auto& pt = pairing.points()[i];
      const double h = conductance[p][i];
      const double q_s = interface_heat->empty() ? 0.0 : (*interface_heat)[p][i];
      if (!pt.paired || (h == 0 && q_s == 0)) continue;
      // The point's four nodes (two slave, two master): local index, jump weight
      // (T_s − T_m) and weight of the half/half split of q_s.
      const contact::PointStencil stencil = contact::point_stencil(pairing, f, pt);
      if (!stencil.in_pattern()) continue;  // outside the pattern: no coupling
      const std::array<int, 4>& node = stencil.node;
      const std::array<double, 4>& jump = stencil.jump;
      const std::array<double, 4> mean{0.5 * pt.slave_weights[0], 0.5 * pt.slave_weights[1],
                                       0.5 * pt.master_weights[0], 0.5 * pt.master_weights[1]};
      const double T_s = contact::slave_value(pt, T);
      const double T_m = contact::master_value(pt, T);
      const double A = pt.area;
      local.touched.insert(local.touched.end(), node.begin(), node.end());
      for (int a = 0; a < 4; ++a) {
        local.vector[node[a]] -= h * (T_s - T_m) * A * jump[a] - q_s * A * mean[a];
        for (int b = 0; b < 4; ++b) local.matrix(node[a], node[b]) += h * A * jump[a] * jump[b];
      }
      if (interface_power) *interface_power += q_s * A;
    }
  }

  // H and H' at every node; an image node (whose T is its source's, by constraint)
  // takes its source's values.
  void nodal_enthalpy() {
    H.resize(mesh.n_nodes());
    dH.resize(mesh.n_nodes());
    for (int n = 0; n < mesh.n_nodes(); ++n) {
      if (settings.mirror.is_image(n)) continue;
      const materials::PropertyValue h = node_material[n]->enthalpy(T[n]);
      H[n] = h.value;
      dH[n] = h.slope;
    }
    if (!settings.mirror.empty())
      for (int n = 0; n < mesh.n_nodes(); ++n)
        if (settings.mirror.is_image(n)) {
          H[n] = H[settings.mirror.image_of[n]];
          dH[n] = dH[settings.mirror.image_of[n]];
        }
  }

  fem::Assembler::Terms terms() {
    fem::Assembler::Terms t;
    t.cells = [this](int e, fem::LocalSystem& l) { cell_kernel(e, l); };
    const double h_w = settings.water_htc, T_w = settings.water_temperature;
    const double h_a = settings.air_htc, T_a = settings.ambient_temperature;
    if (h_w != 0 && !water_faces.empty())
      t.faces.push_back({&water_faces, [this, h_w, T_w](const fem::BoundaryFace& f, fem::LocalSystem& l) {
                           face_kernel(f, h_w, T_w, l, nullptr);
                         }});
    if (h_a != 0 && !air_faces.empty())
      t.faces.push_back({&air_faces, [this, h_a, T_a](const fem::BoundaryFace& f, fem::LocalSystem& l) {
                           face_kernel(f, h_a, T_a, l, nullptr);
                         }});
    if (!groups.empty()) t.groups = [this](int g, fem::LocalSystem& l) { group_kernel(g, l, nullptr); };
    return t;
  }

  // −R and ∂R/∂T of the reduced system at the current T.
  // −R (and ∂R/∂T if `matrix`) of the reduced system at the current T.
  void evaluate(bool matrix) {
    need_matrix = matrix;
    nodal_enthalpy();
    assembler->assemble(terms(), K, F, /*homogeneous=*/true, matrix);
    need_matrix = true;
  }

  // Energy of the step at the converged T.
  void account() {
    energy = ThermalEnergy{};
    for (int n = 0; n < mesh.n_nodes(); ++n) energy.stored += nodal_mass[n] * (H[n] - H_old[n]);
    if (!joule->empty())
      for (std::size_t k = 0; k < JxW.size(); ++k) energy.generated_bulk += (*joule)[k] * JxW[k] * dt;
    fem::LocalSystem scratch;
    const auto boundary_heat = [&](const std::vector<fem::BoundaryFace>& faces, double h, double T_inf) {
      double heat = 0;
      for (const auto& f : faces) {
        scratch.matrix.setZero(4, 4);
        scratch.vector.setZero(4);
        face_kernel(f, h, T_inf, scratch, &heat);
      }
      return heat * dt;
    };
    energy.removed_water = boundary_heat(water_faces, settings.water_htc, settings.water_temperature);
    energy.removed_air = boundary_heat(air_faces, settings.air_htc, settings.ambient_temperature);
    double interface_power = 0;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      const int n = static_cast<int>(pairings[groups[g].first].coupling_nodes(groups[g].second).size());
      scratch.matrix.setZero(n, n);
      scratch.vector.setZero(n);
      group_kernel(static_cast<int>(g), scratch, &interface_power);
    }
    energy.generated_interface = interface_power * dt;
    if (!settings.fixed_temperatures.empty()) energy.removed_fixed = -fixed_reaction() * dt;
  }

  // Heat per unit time supplied through the fixed-temperature boundaries: Σ_a w_a R_a
  // over the full (unconstrained) residual rows, w = 1 on fixed nodes.
  double fixed_reaction() {
    Eigen::VectorXd R = Eigen::VectorXd::Zero(mesh.n_nodes());
    fem::LocalSystem l;
    const fem::Assembler::Terms t = terms();
    for (int e = 0; e < mesh.n_cells(); ++e) {
      l.matrix.setZero(4, 4);
      l.vector.setZero(4);
      t.cells(e, l);
      for (int a = 0; a < 4; ++a) R[mesh.cells[e][a]] -= l.vector[a];
    }
    for (const auto& term : t.faces)
      for (const auto& f : *term.faces) {
        l.matrix.setZero(4, 4);
        l.vector.setZero(4);
        term.kernel(f, l);
        for (int a = 0; a < 4; ++a) R[mesh.cells[f.cell][a]] -= l.vector[a];
      }
    for (std::size_t g = 0; g < groups.size(); ++g) {
      const auto& nodes = pairings[groups[g].first].coupling_nodes(groups[g].second);
      const int n = static_cast<int>(nodes.size());
      l.matrix.setZero(n, n);
      l.vector.setZero(n);
      t.groups(static_cast<int>(g), l);
      for (int a = 0; a < n; ++a) R[nodes[a]] -= l.vector[a];
    }
    return fixed_weight.dot(R);
  }

  // The trial history from the step's temperatures: each paired point's bonding degree
  // (laws that bond) and film breakdown degree, each the largest value reached.
  void update_history() {
    trial_history = history;
    for (std::size_t p = 0; p < pairings.size(); ++p) {
      const contact::InterfaceLaw& law = interfaces.law(p);
      const auto& points = (*contact->pairings)[p].points();
      for (std::size_t i = 0; i < points.size(); ++i) {
        if (!points[i].paired) continue;
        const int ip = static_cast<int>(p), ii = static_cast<int>(i);
        const contact::InterfacePoint pt = interfaces.point(*contact, history, p, i, T, node_material);
        trial_history.raise_breakdown(ip, ii, law.film_breakdown_degree(pt));
        if (law.bonds() && !trial_history.bonded(ip, ii)) trial_history.raise(ip, ii, law.bonding_degree(pt));
      }
    }
  }
};

Thermal::Thermal(const fem::Mesh& mesh, std::vector<const materials::Material*> body_materials,
                 contact::InterfaceModel model, const ThermalSettings& settings)
    : impl_(std::make_unique<Impl>(mesh, std::move(body_materials), std::move(model), settings)) {}

Thermal::~Thermal() = default;

void Thermal::set_temperature(const Eigen::VectorXd& nodal_temperature) {
  if (nodal_temperature.size() != impl_->mesh.n_nodes())
    throw std::invalid_argument("Thermal: one temperature per node expected");
  impl_->set_temperature(nodal_temperature);
}

ThermalStepReport Thermal::solve(double dt, const std::vector<fem::Point>& positions,
                                 const contact::ContactState& contact, const std::vector<double>& joule_heat,
                                 const std::vector<std::vector<double>>& interface_heat, double tolerance_override) {
  Impl& m = *impl_;
  if (!(dt > 0)) throw std::invalid_argument("Thermal: the time step must be positive");
  if (static_cast<int>(positions.size()) != m.mesh.n_nodes())
    throw std::invalid_argument("Thermal: one position per node expected");
  m.set_inputs(dt, positions, contact, joule_heat, interface_heat);
  // A new step factorises afresh; further calls of the step (staggered coupling)
  // start from the step's last factorisation.
  bool refactor = m.new_step || !m.factorized;
  const bool first_solve_of_step = m.new_step;
  if (m.new_step && !m.start_given) m.T = predicted_temperature(dt);
  m.start_given = false;
  // Fixed values and hanging nodes exactly satisfied; Newton corrections keep them.
  m.T = m.constraints.distribute(m.constraints.restrict_to_free(m.T));
  m.new_step = false;
  // Coefficients at the starting field: the λ_m switch once per step, k and h per solve.
  if (first_solve_of_step) m.update_melt_states();
  m.update_conductivities();
  m.interface_conductances();

  ThermalStepReport report;
  const double tolerance = tolerance_override > 0 ? tolerance_override : m.settings.temperature_tolerance;
  m.evaluate(refactor);
  double previous_norm = 0;
  for (int it = 1; it <= m.settings.max_iterations; ++it) {
    report.iterations = it;
    Eigen::VectorXd step;
    try {
      if (refactor) {
        m.solver.factorize(m.K);
        m.factorized = true;
        ++report.factorizations;
        ++m.n_factorizations;
      }
      step = m.constraints.distribute(m.solver.solve(m.F), /*homogeneous=*/true);
      ++m.n_solves;
    } catch (const std::exception& e) {
      report.message = std::string("linear solve failed: ") + e.what();
      m.factorized = false;
      return report;
    }
    const double step_norm = step.lpNorm<Eigen::Infinity>();
    // Chord steps (the last factorisation) while the corrections shrink at least
    // fourfold per iteration; else refactorise. Measured on the default weld: a size
    // limit on chord steps (refactorise above 1 K, or 10 K) cost 20 % (10 %) more
    // thermal time for the same fields. Chord steps while the corrections only halve
    // saved about 0.6 s of the default weld's 6.4–6.8 s, but stalled the Newton
    // iteration at melting onsets: 19 instead of 9 failed runs in the coarse Table I
    // study (test WeldRun.ThermalNewtonConvergesThroughTheMeltingOnsetAtAResistiveSheetFilm,
    // docs/PERFORMANCE.md). The tangent is assembled only when it will be factorised.
    refactor = it > 1 && step_norm > 0.25 * previous_norm;
    previous_norm = step_norm;
    // Backtracking on |R|₂ while the step is large (the S-shaped enthalpy of a narrow
    // melting range can make full Newton steps cycle); steps within 100 times the
    // strict tolerance (round-off level) are taken whole. "Large" is measured against
    // the strict tolerance even when this solve's own is looser: with the coupling's
    // loosest 0.1 K, 100 × 0.1 K = 10 K steps went unchecked, as wide as copper's
    // melting range, and a lower-electrode node cycled 1066 → 1079 → 1066 °C for 40
    // iterations (coarse Table I study, run 39, with a hardened copper).
    const Eigen::VectorXd base = m.T;
    const double norm0 = m.F.norm();
    const double whole_step = 100 * std::min(tolerance, m.settings.temperature_tolerance);
    // A correction within the tolerance ends the iteration where it lands, with no
    // residual evaluated there (a third of the evaluations of a default weld, whose
    // coupling iterates end on such a step): only the enthalpy that account() sums is
    // brought up to the final field. The next solve evaluates its own start.
    if (step_norm <= tolerance && step_norm <= whole_step) {
      m.T = base + step;
      m.nodal_enthalpy();
      report.correction = step_norm;
      report.converged = true;
      if (m.settings.verbose)
        std::fprintf(stderr, "  thermal newton %2d: |dT| = %.3e K, accepted, factorisations %d\n", it, step_norm,
                     report.factorizations);
      break;
    }
    double alpha = 1.0;
    for (int ls = 0; ls < 8; ++ls) {
      m.T = base + alpha * step;
      m.evaluate(refactor);
      if (step_norm <= whole_step || m.F.norm() <= (1 - 1e-4 * alpha) * norm0 || ls == 7) break;
      alpha *= 0.5;
    }
    report.correction = alpha * step_norm;
    if (alpha < 1 && !refactor) {  // a damped step: refactorise at the accepted point
      refactor = true;
      m.evaluate(true);
    }
    if (m.settings.verbose) {
      Eigen::Index worst = 0;
      step.cwiseAbs().maxCoeff(&worst);
      std::fprintf(stderr,
                   "  thermal newton %2d: |dT| = %.3e K at node %d (%.4f, %.4f) mm, T = %.1f degC; alpha = %.3f, "
                   "|R| = %.3e W, factorisations %d\n",
                   it, step_norm, static_cast<int>(worst), 1e3 * m.current.nodes[worst].x(),
                   1e3 * m.current.nodes[worst].y(), m.T[worst], alpha, m.F.lpNorm<Eigen::Infinity>(),
                   report.factorizations);
    }
    if (alpha == 1.0 && step_norm <= tolerance) {
      report.converged = true;
      break;
    }
  }
  if (!report.converged)
    report.message = "Newton did not converge in " + std::to_string(m.settings.max_iterations) +
                     " iterations (last correction " + std::to_string(report.correction) + " K)";
  m.account();
  m.update_history();
  return report;
}

Eigen::VectorXd Thermal::predicted_temperature(double dt) const {
  const Impl& m = *impl_;
  Eigen::VectorXd T = m.T_old;
  if (m.settings.extrapolate && m.previous_dt > 0) T += (m.T_old - m.T_previous) * (dt / m.previous_dt);
  return T;
}

void Thermal::set_start(const Eigen::VectorXd& nodal_temperature) {
  Impl& m = *impl_;
  if (nodal_temperature.size() != m.mesh.n_nodes())
    throw std::invalid_argument("Thermal::set_start: one temperature per node expected");
  m.T = nodal_temperature;
  m.start_given = true;
}

void Thermal::commit() {
  Impl& m = *impl_;
  m.start_given = false;
  m.T_previous = m.T_old;
  m.previous_dt = m.dt;
  m.T_old = m.T;
  m.peak = m.peak.cwiseMax(m.T);
  for (int n = 0; n < m.mesh.n_nodes(); ++n) m.H_old[n] = m.node_material[n]->enthalpy(m.T_old[n]).value;
  m.history = m.trial_history;
  m.new_step = true;
  m.factorized = false;
}

const Eigen::VectorXd& Thermal::temperature() const { return impl_->T; }
const Eigen::VectorXd& Thermal::committed_temperature() const { return impl_->T_old; }
const Eigen::VectorXd& Thermal::peak_temperature() const { return impl_->peak; }

Eigen::VectorXd Thermal::liquid_fraction() const {
  const Impl& m = *impl_;
  Eigen::VectorXd f(m.mesh.n_nodes());
  for (int n = 0; n < m.mesh.n_nodes(); ++n) f[n] = m.node_material[n]->liquid_fraction(m.T[n]).value;
  return f;
}

const ThermalEnergy& Thermal::energy() const { return impl_->energy; }

ThermalSolverCounts Thermal::solver_counts() const { return {impl_->n_solves, impl_->n_factorizations}; }

void Thermal::residual_and_tangent(double dt, const std::vector<fem::Point>& positions,
                                   const contact::ContactState& contact, const std::vector<double>& joule_heat,
                                   const std::vector<std::vector<double>>& interface_heat,
                                   const Eigen::VectorXd& reference, const Eigen::VectorXd& reduced,
                                   Eigen::VectorXd& residual, Eigen::SparseMatrix<double>& tangent) {
  Impl& m = *impl_;
  m.set_inputs(dt, positions, contact, joule_heat, interface_heat);
  // The solver's state is left as it was.
  const Eigen::VectorXd saved_T = m.T;
  const std::vector<char> saved_states = m.melt_state;
  const std::vector<double> saved_k = m.conductivity_q;
  const std::vector<std::vector<double>> saved_h = m.conductance;
  m.T = reference;
  m.update_melt_states();
  m.update_conductivities();
  m.interface_conductances();
  m.T = m.constraints.distribute(reduced);
  m.evaluate(true);
  residual = -m.F;
  tangent = m.K;
  m.T = saved_T;
  m.melt_state = saved_states;
  m.conductivity_q = saved_k;
  m.conductance = saved_h;
  m.factorized = false;  // K now holds the tangent at `reduced`
}

Eigen::VectorXd Thermal::free_values(const Eigen::VectorXd& nodal_temperature) const {
  return impl_->constraints.restrict_to_free(nodal_temperature);
}

Eigen::VectorXd Thermal::nodal_values(const Eigen::VectorXd& free) const {
  return impl_->constraints.distribute(free);
}
const contact::InterfaceHistory& Thermal::interface_history() const { return impl_->history; }
const std::vector<std::vector<double>>& Thermal::interface_conductance() const { return impl_->conductance; }

}  // namespace rsw::physics
