// Electrical conduction with contact interfaces; see electrical.hpp.
#include "physics/electrical.hpp"

#include "contact/interface_coupling.hpp"
#include "fem/assembler.hpp"
#include "fem/constraints.hpp"
#include "fem/dof_map.hpp"
#include "fem/fe_values.hpp"
#include "fem/linear_solver.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>

namespace rsw::physics {

namespace {
using Matrix4 = Eigen::Matrix<double, 4, 4>;

// Relative residual |F - K φ| / |F| of the unit-current solve. The preconditioner is
// a factorisation of a nearby K, so the residual is a faithful measure of the error:
// R and the powers agree with a direct solve to about this (measured 4·10⁻¹² on the
// default case, docs/PERFORMANCE.md).
constexpr double linear_tolerance = 1e-10;
// Componentwise backward error (fem::componentwise_backward_error) accepted when the
// relative residual cannot reach linear_tolerance: 10⁴ unit round-offs.
constexpr double backward_error_tolerance = 1e-12;

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}
}  // namespace

PointLocation locate_point(const fem::Mesh& mesh, const fem::Point& point) {
  constexpr double tolerance = 1e-9;
  for (int e = 0; e < mesh.n_cells(); ++e) {
    const auto& c = mesh.cells[e];
    double r0 = 1e300, r1 = -1e300, z0 = 1e300, z1 = -1e300;
    for (int n : c) {
      r0 = std::min(r0, mesh.nodes[n].x());
      r1 = std::max(r1, mesh.nodes[n].x());
      z0 = std::min(z0, mesh.nodes[n].y());
      z1 = std::max(z1, mesh.nodes[n].y());
    }
    const double slack = 1e-9 * std::max(r1 - r0, z1 - z0);
    if (point.x() < r0 - slack || point.x() > r1 + slack || point.y() < z0 - slack || point.y() > z1 + slack) continue;
    // Newton on x(ξ, η) = point from the cell centre.
    Eigen::Vector2d xi = Eigen::Vector2d::Zero();
    for (int it = 0; it < 30; ++it) {
      const auto N = fem::shape_values(xi.x(), xi.y());
      const auto dN = fem::shape_gradients_ref(xi.x(), xi.y());
      Eigen::Vector2d x = Eigen::Vector2d::Zero();
      Eigen::Matrix2d J = Eigen::Matrix2d::Zero();
      for (int a = 0; a < 4; ++a) {
        x += N[a] * mesh.nodes[c[a]];
        J += mesh.nodes[c[a]] * dN[a].transpose();
      }
      const Eigen::Vector2d step = J.inverse() * (point - x);
      xi += step;
      if (step.norm() < 1e-14) break;
    }
    if (std::abs(xi.x()) <= 1 + tolerance && std::abs(xi.y()) <= 1 + tolerance)
      return {e, std::clamp(xi.x(), -1.0, 1.0), std::clamp(xi.y(), -1.0, 1.0)};
  }
  throw std::out_of_range("no cell holds the point (" + std::to_string(point.x()) + ", " +
                          std::to_string(point.y()) + ") m");
}

double interpolate(const fem::Mesh& mesh, const PointLocation& where, const Eigen::VectorXd& nodal) {
  const auto N = fem::shape_values(where.xi, where.eta);
  double u = 0;
  for (int a = 0; a < 4; ++a) u += N[a] * nodal[mesh.cells[where.cell][a]];
  return u;
}

double ElectricalSolution::total_interface_power() const {
  return std::accumulate(interface_power.begin(), interface_power.end(), 0.0);
}

struct Electrical::Impl {
  const fem::Mesh& mesh;
  ElectricalSettings settings;
  std::vector<const materials::Material*> body_material;
  std::vector<const materials::Material*> cell_material;
  std::vector<const materials::Material*> node_material;
  int n_q;

  fem::DofMap dofs;
  int voltage_dof;
  fem::Constraints constraints;
  contact::InterfaceCoupling interfaces;  // pairings (the coupling pattern), laws, coupling groups
  std::unique_ptr<fem::Assembler> assembler;
  // K changes little from one solve to the next (σ(T) and the contact conductances of
  // the next coupling iterate or step): a CHOLMOD factorisation of an earlier K
  // preconditions GMRES, refreshed when it needs more than 6 iterations.
  fem::PreconditionedGmres solver;
  fem::SparseMatrix K;
  Eigen::VectorXd F;
  Eigen::VectorXd last_reduced;  // the last solve's unit-current potential (free dofs), GMRES's start

  Eigen::VectorXd ground_weight;  // 1 on the ground face, hanging nodes interpolated
  std::vector<int> ground_cells;
  int ground_body = -1;
  int ground_node = -1;  // φ = 0 there, or −V under a mirror: potentials are taken relative to it
  std::vector<std::array<PointLocation, 2>> probes;

  // Inputs of the current solve.
  const Eigen::VectorXd* temperature = nullptr;
  const contact::ContactState* contact = nullptr;
  // Gauss-point data (current configuration): σ of the last assembly, geometry.
  std::vector<double> sigma;
  fem::CellGeometry geometry;
  const std::vector<double>& JxW = geometry.JxW();
  const std::vector<Eigen::Vector2d>& grad = geometry.grad();     // per cell Gauss point, 4 shape functions
  const std::vector<std::array<double, 4>>& shape = geometry.shape();  // N_a at the reference Gauss points

  Impl(const fem::Mesh& m, std::vector<const materials::Material*> materials_of_body, contact::InterfaceModel mdl,
       const ElectricalSettings& s)
      : mesh(m),
        settings(s),
        body_material(std::move(materials_of_body)),
        n_q(s.n_gauss * s.n_gauss),
        dofs(m, 1, 1),
        voltage_dof(dofs.extra_dof(0)),
        constraints(dofs.n_dofs()),
        interfaces(m, std::move(mdl), dofs, s.n_gauss, s.search_margin, "Electrical"),
        geometry(m, s.n_gauss) {
    if (s.n_gauss < 1 || s.n_gauss > 3) throw std::invalid_argument("Electrical: n_gauss must be 1, 2 or 3");
    if (static_cast<int>(body_material.size()) != mesh.n_bodies())
      throw std::invalid_argument("Electrical: one material per body expected");
    for (int e = 0; e < mesh.n_cells(); ++e) cell_material.push_back(body_material[mesh.cell_body[e]]);
    for (int n = 0; n < mesh.n_nodes(); ++n) node_material.push_back(body_material[mesh.node_body[n]]);

    if (!s.mirror.empty() && !fem::are_images(s.mirror, mesh.boundary_nodes(s.ground_boundary),
                                                mesh.boundary_nodes(s.current_boundary)))
      throw std::invalid_argument("Electrical: under a mirror the ground face '" + s.ground_boundary +
                                  "' must be the image of the current face '" + s.current_boundary + "'");
    fem::add_mirror_constraints(constraints, mesh, dofs, s.mirror, {-1.0});  // before the ground
    constraints.add_hanging_nodes(mesh, dofs);
    constraints.constrain_boundary(mesh, dofs, s.ground_boundary, 0, [](const fem::Point&) { return 0.0; });
    for (int n : mesh.boundary_nodes(s.current_boundary)) constraints.add_line(dofs.dof(n, 0), {{voltage_dof, 1.0}});
    constraints.close();

    assembler = std::make_unique<fem::Assembler>(mesh, dofs, constraints, interfaces.dof_groups());
    assembler->set_mirror(s.mirror);
    ground_node = mesh.boundary_nodes(s.ground_boundary).front();

    ground_weight = Eigen::VectorXd::Zero(mesh.n_nodes());
    for (int n : mesh.boundary_nodes(s.ground_boundary)) ground_weight[n] = 1.0;
    for (const auto& h : mesh.hanging_nodes)
      ground_weight[h.node] = 0.5 * (ground_weight[h.parents[0]] + ground_weight[h.parents[1]]);
    for (int e = 0; e < mesh.n_cells(); ++e) {
      bool touches = false;
      for (int n : mesh.cells[e]) touches = touches || ground_weight[n] != 0;
      if (touches) ground_cells.push_back(e);
    }
    ground_body = mesh.node_body[mesh.boundary_nodes(s.ground_boundary).front()];
    for (const auto& probe : s.probes) probes.push_back({locate_point(mesh, probe.upper), locate_point(mesh, probe.lower)});

    sigma.assign(static_cast<std::size_t>(mesh.n_cells()) * n_q, 0.0);
  }

  // h_e at every pairing point (0 where unpaired, open or outside the pattern).
  void interface_conductances(const contact::InterfaceHistory& history, std::vector<std::vector<double>>& out) const {
    interfaces.conductances(contact::InterfaceField::electrical, *contact, history, *temperature, node_material, out);
  }

  // Every body must reach the ground body through conducting interface points.
  void check_current_path(const std::vector<std::vector<double>>& h) const {
    std::vector<int> parent(mesh.n_bodies());
    std::iota(parent.begin(), parent.end(), 0);
    for (std::size_t p = 0; p < interfaces.size(); ++p) {
      const auto& points = (*contact->pairings)[p].points();
      for (std::size_t i = 0; i < points.size(); ++i)
        if (h[p][i] > 0) {
          const int a = find_root(parent, mesh.node_body[points[i].slave_nodes[0]]);
          const int b = find_root(parent, mesh.node_body[points[i].master_nodes[0]]);
          parent[a] = b;
        }
    }
    const int ground = find_root(parent, ground_body);
    for (int b = 0; b < mesh.n_bodies(); ++b)
      if (find_root(parent, b) != ground)
        throw std::runtime_error("Electrical: body '" + mesh.body_names[b] +
                                 "' has no conducting path to the ground face (no closed contact)");
  }

  // T at Gauss point q of cell e.
  double gauss_temperature(int e, int q) const {
    double Tq = 0;
    for (int a = 0; a < 4; ++a) Tq += shape[q][a] * (*temperature)[mesh.cells[e][a]];
    return Tq;
  }

  // ∫ σ ∇N_a·∇N_b dV with σ = 1/ρ_e(T) at each Gauss point.
  void cell_kernel(int e, fem::LocalSystem& local) {
    const materials::Material& mat = *cell_material[e];
    Matrix4 Ke = Matrix4::Zero();
    for (int q = 0; q < n_q; ++q) {
      const std::size_t k = static_cast<std::size_t>(e) * n_q + q;
      sigma[k] = 1.0 / mat.electrical_resistivity(gauss_temperature(e, q)).value;
      const double w = sigma[k] * JxW[k];
      const Eigen::Vector2d* g = &grad[4 * k];
      for (int a = 0; a < 4; ++a)
        for (int b = a; b < 4; ++b) Ke(a, b) += w * g[a].dot(g[b]);
    }
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < a; ++b) Ke(a, b) = Ke(b, a);
    local.matrix += Ke;
  }

  // Σ_points h_e A (v_s − v_m)(φ_s − φ_m) over the points of one slave face.
  void group_kernel(int g, const std::vector<std::vector<double>>& h, fem::LocalSystem& local) const {
    local.lists_touched = true;
    const auto [p, f] = interfaces.groups()[g];
    const auto& pairing = (*contact->pairings)[p];
    for (int k = 0; k < pairing.n_gauss(); ++k) {
      const int i = f * pairing.n_gauss() + k;
      if (h[p][i] == 0) continue;
      const auto& pt = pairing.points()[i];
      // The point's four nodes (two slave, two master) and their jump weights φ_s − φ_m.
      const contact::PointStencil stencil = contact::point_stencil(pairing, f, pt);
      const std::array<int, 4>& node = stencil.node;
      const std::array<double, 4>& jump = stencil.jump;
      const double c = h[p][i] * pt.area;
      local.touched.insert(local.touched.end(), node.begin(), node.end());
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) local.matrix(node[a], node[b]) += c * jump[a] * jump[b];
    }
  }

};

Electrical::Electrical(const fem::Mesh& mesh, std::vector<const materials::Material*> body_materials,
                       contact::InterfaceModel model, const ElectricalSettings& settings)
    : impl_(std::make_unique<Impl>(mesh, std::move(body_materials), std::move(model), settings)) {}

Electrical::~Electrical() = default;

int Electrical::n_gauss() const { return impl_->settings.n_gauss; }

const ElectricalSolution& Electrical::solve(const std::vector<fem::Point>& positions,
                                            const Eigen::VectorXd& nodal_temperature, double current,
                                            const contact::ContactState& contact,
                                            const contact::InterfaceHistory& history) {
  Impl& m = *impl_;
  const fem::Mesh& mesh = m.mesh;
  if (static_cast<int>(positions.size()) != mesh.n_nodes() || nodal_temperature.size() != mesh.n_nodes())
    throw std::invalid_argument("Electrical: positions and temperatures must have one entry per node");
  m.interfaces.check(contact);
  m.geometry.update(positions);
  m.temperature = &nodal_temperature;
  m.contact = &contact;
  ElectricalSolution& sol = solution_;
  m.interface_conductances(history, sol.interface_conductance);
  m.check_current_path(sol.interface_conductance);

  // Unit current: the load 1 A on the voltage dof.
  fem::Assembler::Terms terms;
  terms.cells = [&m](int e, fem::LocalSystem& l) { m.cell_kernel(e, l); };
  terms.groups = [&m, &sol](int g, fem::LocalSystem& l) { m.group_kernel(g, sol.interface_conductance, l); };
  m.assembler->assemble(terms, m.K, m.F);
  Eigen::VectorXd load = Eigen::VectorXd::Zero(m.dofs.n_dofs());
  load[m.voltage_dof] = 1.0;
  m.F += m.constraints.condense(load);
  // GMRES starts from the last solve's unit-current potential: between coupling
  // iterations and steps it changes by little, so fewer iterations reach the same
  // residual.
  Eigen::VectorXd& reduced = m.last_reduced;
  try {
    m.solver.solve_refreshing(m.K, m.F, reduced, linear_tolerance, /*refresh_after=*/6, /*max_iterations=*/30, {},
                              /*from_x=*/true);
  } catch (const std::runtime_error& e) {
    // Even a fresh factorisation stalls above the tolerance: the entries of K span too
    // many decades for a relative residual of 10⁻¹⁰ in double precision (a badly
    // sheared cell next to the S/S contact edge, bonded points conducting 10³ times
    // the bulk beside a very resistive film). The iterate is then taken if it is as
    // accurate as a backward-stable direct solve of this K can be: its componentwise
    // backward error is within backward_error_tolerance (2–3·10⁻¹⁶ measured where the
    // relative residual stalled at 10⁻⁷–10⁻⁶). How well K itself represents the field
    // is another matter: a cell that folds fails the run (physics/weld_simulation).
    const double omega = fem::componentwise_backward_error(m.K, reduced, m.F);
    if (!(omega <= backward_error_tolerance)) {
      char text[128];
      std::snprintf(text, sizeof text, "; componentwise backward error %.3g, above %.0e", omega,
                    backward_error_tolerance);
      throw std::runtime_error(e.what() + std::string(text));
    }
  }
  const Eigen::VectorXd unit = m.constraints.distribute(reduced);

  sol.current = current;
  const double ground = unit[m.ground_node];  // 0, or −V under a mirror
  sol.resistance = unit[m.voltage_dof] - ground;
  sol.voltage = current * sol.resistance;
  sol.potential = current * (unit.head(mesh.n_nodes()).array() - ground).matrix();
  const Eigen::VectorXd& phi = sol.potential;

  // Bulk Joule heat σ|∇φ|² at the Gauss points of the assembly.
  const int n_q = m.n_q;
  sol.joule_heat.assign(static_cast<std::size_t>(mesh.n_cells()) * n_q, 0.0);
  sol.bulk_power = 0;
  for (int e = 0; e < mesh.n_cells(); ++e) {
    const auto& c = mesh.cells[e];
    const bool assembled = m.assembler->cell_weight(e) != 0.0;  // set σ at its Gauss points
    for (int q = 0; q < n_q; ++q) {
      const std::size_t k = static_cast<std::size_t>(e) * n_q + q;
      if (!assembled) m.sigma[k] = 1.0 / m.cell_material[e]->electrical_resistivity(m.gauss_temperature(e, q)).value;
      Eigen::Vector2d g = Eigen::Vector2d::Zero();
      for (int a = 0; a < 4; ++a) g += phi[c[a]] * m.grad[4 * k + a];
      sol.joule_heat[k] = m.sigma[k] * g.squaredNorm();
      sol.bulk_power += sol.joule_heat[k] * m.JxW[k];
    }
  }

  // Interfaces: current slave → master and Joule heat h_e Δφ².
  const std::size_t n_interfaces = m.interfaces.size();
  sol.interface_heat.resize(n_interfaces);
  sol.interface_current.assign(n_interfaces, 0.0);
  sol.interface_power.assign(n_interfaces, 0.0);
  for (std::size_t p = 0; p < n_interfaces; ++p) {
    const auto& points = (*contact.pairings)[p].points();
    sol.interface_heat[p].assign(points.size(), 0.0);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double h = sol.interface_conductance[p][i];
      if (h == 0) continue;
      const auto& pt = points[i];
      const double jump = contact::jump(pt, phi);
      sol.interface_heat[p][i] = contact::interface_joule_heat(h, jump).value;
      sol.interface_current[p] += h * jump * pt.area;
      sol.interface_power[p] += sol.interface_heat[p][i] * pt.area;
    }
  }

  // Current leaving through the ground face: −∫ σ ∇φ·∇w dV (consistent reaction).
  double reaction = 0;
  for (int e : m.ground_cells) {
    const auto& c = mesh.cells[e];
    for (int q = 0; q < n_q; ++q) {
      const std::size_t k = static_cast<std::size_t>(e) * n_q + q;
      Eigen::Vector2d gphi = Eigen::Vector2d::Zero(), gw = Eigen::Vector2d::Zero();
      for (int a = 0; a < 4; ++a) {
        gphi += phi[c[a]] * m.grad[4 * k + a];
        gw += m.ground_weight[c[a]] * m.grad[4 * k + a];
      }
      reaction += m.sigma[k] * gphi.dot(gw) * m.JxW[k];
    }
  }
  sol.ground_current = -reaction;

  sol.probe_voltage.clear();
  sol.probe_resistance.clear();
  for (const auto& probe : m.probes) {
    const double unit_drop = interpolate(mesh, probe[0], unit) - interpolate(mesh, probe[1], unit);
    sol.probe_voltage.push_back(current * unit_drop);
    sol.probe_resistance.push_back(unit_drop);
  }
  return sol;
}

std::vector<double> Electrical::cell_joule_heat() const {
  const Impl& m = *impl_;
  std::vector<double> out(m.mesh.n_cells(), 0.0);
  if (solution_.joule_heat.empty()) return out;
  for (int e = 0; e < m.mesh.n_cells(); ++e) {
    double volume = 0;
    for (int q = 0; q < m.n_q; ++q) {
      const std::size_t k = static_cast<std::size_t>(e) * m.n_q + q;
      out[e] += solution_.joule_heat[k] * m.JxW[k];
      volume += m.JxW[k];
    }
    out[e] /= volume;
  }
  return out;
}

std::vector<Eigen::Vector2d> Electrical::cell_current_density() const {
  const Impl& m = *impl_;
  std::vector<Eigen::Vector2d> out(m.mesh.n_cells(), Eigen::Vector2d::Zero());
  if (solution_.potential.size() == 0) return out;
  const Eigen::VectorXd& phi = solution_.potential;
  for (int e = 0; e < m.mesh.n_cells(); ++e) {
    const auto& c = m.mesh.cells[e];
    double volume = 0;
    for (int q = 0; q < m.n_q; ++q) {
      const std::size_t k = static_cast<std::size_t>(e) * m.n_q + q;
      Eigen::Vector2d g = Eigen::Vector2d::Zero();
      for (int a = 0; a < 4; ++a) g += phi[c[a]] * m.grad[4 * k + a];
      out[e] -= m.sigma[k] * g * m.JxW[k];
      volume += m.JxW[k];
    }
    out[e] /= volume;
  }
  return out;
}

contact::ContactState contact_state(const Mechanics& mechanics) {
  contact::ContactState state;
  state.pairings = &mechanics.pairings();
  for (std::size_t p = 0; p < mechanics.pairings().size(); ++p)
    state.pressure.push_back(mechanics.contact_pressure(static_cast<int>(p)));
  return state;
}

}  // namespace rsw::physics
