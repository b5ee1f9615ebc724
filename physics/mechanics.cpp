// Mechanics of the stack: B̄ elements with J2 plasticity, penalty contact with
// friction, Newton with line search; see mechanics.hpp.
#include "physics/mechanics.hpp"

#include "contact/mechanical_contact.hpp"
#include "fem/fe_values.hpp"
#include "fem/interior_elimination.hpp"
#include "fem/mirror.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace rsw::physics {

namespace {
using Vector4 = Eigen::Matrix<double, 4, 1>;
using Matrix4 = Eigen::Matrix<double, 4, 4>;
using Matrix48 = Eigen::Matrix<double, 4, 8>;
constexpr double sqrt_half = 0.70710678118654752440;
constexpr double sqrt_three_halves = 1.22474487139158904910;

enum class Control { force, displacement };

using Vector8 = Eigen::Matrix<double, 8, 1>;
using Matrix8 = Eigen::Matrix<double, 8, 8>;
using contact::penalty_pressure;
}  // namespace

struct Mechanics::Impl {
  const fem::Mesh& mesh;
  fem::Mesh current;  // configuration x_n at the start of the step
  MechanicsSettings settings;
  double initial_temperature;
  std::vector<const materials::Material*> cell_material;
  std::vector<double> foundation;  // per body, N/m^4 (0 for supported bodies)

  fem::DofMap dofs;
  int w_dof;
  fem::Constraints force_constraints, displacement_constraints;
  // Contact passes: q < pairings.size() the named pass of mesh interface q (in
  // mesh.interfaces order), then the mirrored passes of the two-pass interfaces.
  std::vector<contact::InterfacePairing> pairings, mirrors;
  std::vector<int> mirror_of;          // per mirrored pass, its interface (pass index)
  // Per mirrored pass and point: the two first-pass points bracketing it in reference
  // r and the weight of the second, to hand it their bonding degree.
  std::vector<std::vector<std::pair<std::array<int, 2>, double>>> mirror_source;
  std::vector<double> normal_penalty;  // per pass, Pa/m
  std::vector<double> area_weight;     // per pass: 1, or 1/2 for both passes of a two-pass interface
  std::vector<std::pair<int, int>> groups;  // (pass, slave face)
  int n_passes() const { return static_cast<int>(pairings.size() + mirrors.size()); }
  const contact::InterfacePairing& pass(int q) const {
    return q < static_cast<int>(pairings.size()) ? pairings[q] : mirrors[q - pairings.size()];
  }
  contact::InterfacePairing& pass(int q) {
    return q < static_cast<int>(pairings.size()) ? pairings[q] : mirrors[q - pairings.size()];
  }
  std::unique_ptr<fem::Assembler> force_assembler, displacement_assembler;
  fem::PreconditionedGmres force_gmres, displacement_gmres;
  fem::InteriorElimination elimination;  // of the force-controlled systems (setup_elimination)
  // Trial tangent and residual of the Newton iterations, kept between calls: a fresh
  // sparse matrix per call of iterate() copied the whole pattern (about 1 ms on the
  // paper's mesh, once per step).
  fem::SparseMatrix K_trial;
  Eigen::VectorXd R_trial;

  int n_q;
  std::vector<Vector4> strain, trial_strain;  // per cell * n_q
  std::vector<materials::J2State> state, trial_state;
  std::vector<Vector4> trial_stress;
  std::vector<std::vector<double>> tau, trial_tau;  // per pairing, per point
  // A bonded point is tied to a fixed material point of the master face. The bonding
  // degree β is the bonded share of the point's area, and each share bonds at rest in
  // the configuration it bonds in, so a tie carries the relative motion since bonding
  // weighted by the degree at each moment: with the relative position d = x_s − x_m,
  // the effective offset
  //     e = e_n + β (d_n − d)          (e_n, d_n: at the last committed step),
  // i.e. e = ∫ β d(−d). The tie holds the tangential part linearly, ε_N (e·t_b), and
  // resists opening only, with the contact's C¹ law mirrored: a tension T = p(e·n_b),
  // p the smoothed penalty pressure of the contact. Compression stays with the
  // contact, so a tie formed while the surfaces were still a little apart does not
  // prop them apart as a strut. n_b, t_b: the pairing's normal and tangent when the
  // tie formed. Where β grows, the new share takes over the friction traction it
  // carried (e_n gains −Δβ τ t_b / ε_N), so the traction is continuous. (Were the
  // whole share β to act on the offset since the tie first formed, a degree rising
  // from 10⁻⁵ to 1 in one step would multiply micrometres of slip at a nearly
  // unbonded point into a 19 kN nodal force; docs/MECHANICS.md.)
  struct Tie {
    bool on = false;
    double degree = 0;  // bonding degree β ∈ [0, 1], never decreasing
    std::array<int, 2> master_nodes{};
    std::array<double, 2> master_weights{};
    Eigen::Vector2d offset = Eigen::Vector2d::Zero();    // e_n
    Eigen::Vector2d relative = Eigen::Vector2d::Zero();  // d_n
    Eigen::Vector2d normal = Eigen::Vector2d::Zero();    // n_b
    Eigen::Vector2d tangent = Eigen::Vector2d::Zero();   // t_b
  };
  std::vector<std::vector<Tie>> ties;  // per pairing, per point
  // The tie's e and d at the last evaluation (committed into Tie::offset, ::relative).
  struct TieTrial {
    Eigen::Vector2d offset = Eigen::Vector2d::Zero(), relative = Eigen::Vector2d::Zero();
  };
  std::vector<std::vector<TieTrial>> tie_trial;

  Eigen::VectorXd increment;    // Δu of the current step (full)
  Eigen::VectorXd last_increment;  // Δu of the last committed step, for the predictor
  double last_load_change = 0;     // ΔF or Δw of that step
  Control last_control = Control::force;
  double load_change = 0;          // ΔF or Δw of the current step
  double predictor_scale = 0;      // set_predictor() for the next force step
  double time_step = 0;            // s, set_time_step(); 0 = rate-independent
  Eigen::VectorXd total;        // u since the start (full)
  Eigen::VectorXd temperature;  // nodal, °C
  Control control = Control::force;
  double force = 0;             // applied (force control)
  bool pairing_within = true;
  bool skip_cells = false, skip_groups = false;  // diagnose() only

  Impl(const fem::Mesh& m, std::vector<const materials::Material*> body_materials, const MechanicsSettings& s,
       double T0)
      : mesh(m),
        current(m),
        settings(s),
        initial_temperature(T0),
        dofs(m, 2, 1),
        w_dof(dofs.extra_dof(0)),
        force_constraints(dofs.n_dofs()),
        displacement_constraints(dofs.n_dofs()),
        n_q(s.n_gauss * s.n_gauss) {
    if (s.n_gauss < 1 || s.n_gauss > 3) throw std::invalid_argument("Mechanics: n_gauss must be 1, 2 or 3");
    if (static_cast<int>(body_materials.size()) != mesh.n_bodies())
      throw std::invalid_argument("Mechanics: one material per body expected");
    for (int e = 0; e < mesh.n_cells(); ++e) cell_material.push_back(body_materials[mesh.cell_body[e]]);

    setup_foundation(settings);
    setup_constraints(settings);
    setup_contact_passes(settings, body_materials, T0);
    setup_assemblers();
    setup_elimination();
    allocate_state(T0);
  }

  // The free unknowns eliminated from the force-controlled Newton systems: those of
  // the nodes farther than settings.interior_elimination_distance from every contact
  // face of their body. Far from its contact faces an electrode stays cold and
  // elastic.
  void setup_elimination() {
    const double reach = settings.interior_elimination_distance;
    if (!(reach > 0)) return;
    std::vector<std::vector<fem::Point>> contact(mesh.n_bodies());  // per body
    for (const auto& [name, pair] : mesh.interfaces)
      for (const auto* side : {&pair.first, &pair.second})
        for (int n : mesh.boundary_nodes(*side)) contact[mesh.node_body[n]].push_back(mesh.nodes[n]);
    std::vector<char> interior(force_constraints.n_free(), 0);
    for (int n = 0; n < mesh.n_nodes(); ++n) {
      const fem::Point& x = mesh.nodes[n];
      const auto& faces = contact[mesh.node_body[n]];
      const bool far = std::none_of(faces.begin(), faces.end(),
                                    [&](const fem::Point& c) { return (x - c).squaredNorm() < reach * reach; });
      if (!far) continue;
      for (int c = 0; c < 2; ++c)
        if (const int f = force_constraints.free_index(dofs.dof(n, c)); f >= 0) interior[f] = 1;
    }
    elimination = fem::InteriorElimination(std::move(interior));
  }

  // Bodies without a support of their own get the seating foundation κ = k / V.
  void setup_foundation(const MechanicsSettings& s) {
    std::vector<char> supported(mesh.n_bodies(), 0);
    for (const auto* b : {&s.fixed_boundary, &s.loaded_boundary})
      for (int n : mesh.boundary_nodes(*b)) supported[mesh.node_body[n]] = 1;
    std::vector<double> volume(mesh.n_bodies(), 0.0);
    fem::CellValues cv(s.n_gauss);
    for (int e = 0; e < mesh.n_cells(); ++e) {
      cv.reinit(mesh, e);
      for (int q = 0; q < cv.n_q(); ++q) volume[mesh.cell_body[e]] += cv.JxW(q);
    }
    foundation.assign(mesh.n_bodies(), 0.0);
    for (int b = 0; b < mesh.n_bodies(); ++b)
      if (!supported[b]) foundation[b] = s.seating_stiffness / volume[b];
  }

  // Hanging nodes, the axis, the fixed and loaded end faces, the rigid end face (w);
  // under displacement control w is prescribed too.
  void setup_constraints(const MechanicsSettings& s) {
    for (fem::Constraints* c : {&force_constraints, &displacement_constraints}) {
      fem::add_mirror_constraints(*c, mesh, dofs, s.mirror, {1.0, -1.0});  // before the supports
      c->add_hanging_nodes(mesh, dofs);
      for (const auto& [name, faces] : mesh.boundaries)
        if (name.size() > 5 && name.compare(name.size() - 5, 5, ".axis") == 0)
          c->constrain_boundary(mesh, dofs, name, 0, [](const fem::Point&) { return 0.0; });
      const auto zero = [](const fem::Point&) { return 0.0; };
      c->constrain_boundary(mesh, dofs, s.fixed_boundary, 1, zero);
      if (s.clamp_radially) {
        c->constrain_boundary(mesh, dofs, s.fixed_boundary, 0, zero);
        c->constrain_boundary(mesh, dofs, s.loaded_boundary, 0, zero);
      }
      for (int n : mesh.boundary_nodes(s.loaded_boundary)) c->add_line(dofs.dof(n, 1), {{w_dof, 1.0}});
    }
    displacement_constraints.constrain(w_dof, 0.0);
    force_constraints.close();
    displacement_constraints.close();
  }

  // One contact pass per mesh interface, and a mirrored pass for each two-pass
  // interface, with the normal penalty ε_N and the area weight of each pass.
  //
  // Under a mirror symmetry, an interface whose one side is the image of the other
  // (the sheet/sheet interface in the plane z = 0) keeps its first pass alone, with
  // the whole area: its mirrored pass is that pass's mirror image, which the mirror
  // already adds to the upper half (its coupling groups hold source and image nodes
  // and count half, fem/mirror.hpp). The sum is the same in exact arithmetic (the
  // paper's case: features equal to 2·10⁻¹⁴), but two passes computed apart differ in
  // their rounding, and once the sheets melt that difference decides the weld's path:
  // noise of 2·10⁻¹⁶ on the contact points' radii folded a cell or left worst cells of
  // 0.004–0.22 with both passes, and changes nothing with one (docs/VERIFICATION.md,
  // "Round-off sensitivity").
  void setup_contact_passes(const MechanicsSettings& s, const std::vector<const materials::Material*>& body_materials,
                            double T0) {
    auto mirrored_by_symmetry = [&](const fem::InterfacePair& sides) {
      const std::vector<int> first = mesh.boundary_nodes(sides.first), second = mesh.boundary_nodes(sides.second);
      return fem::are_images(s.mirror, second, first) || fem::are_images(s.mirror, first, second);
    };
    auto two_pass = [&](const std::string& name) {
      return std::find(s.two_pass_interfaces.begin(), s.two_pass_interfaces.end(), name) !=
                 s.two_pass_interfaces.end() &&
             !mirrored_by_symmetry(mesh.interfaces.at(name));
    };
    for (const auto& name : s.two_pass_interfaces)
      if (!mesh.interfaces.count(name)) throw std::out_of_range("two-pass contact: unknown interface '" + name + "'");
    for (const auto& [name, pair] : mesh.interfaces) {
      pairings.emplace_back(mesh, name, s.n_gauss);
      // ε_N = factor · E / h: E of the stiffer side at room temperature, h the finest
      // face on the interface. Fixed for the run (it never depends on the parameters).
      const int b1 = mesh.cell_body[mesh.boundary(pair.first).front().cell];
      const int b2 = mesh.cell_body[mesh.boundary(pair.second).front().cell];
      const double E =
          std::max(body_materials[b1]->youngs_modulus(T0).value, body_materials[b2]->youngs_modulus(T0).value);
      double h = 1e300;
      for (const auto* side : {&pair.first, &pair.second})
        for (const auto& f : mesh.boundary(*side)) {
          auto n = mesh.face_nodes(f);
          h = std::min(h, (mesh.nodes[n[1]] - mesh.nodes[n[0]]).norm());
        }
      normal_penalty.push_back(s.contact_penalty_factor * E / h);
      area_weight.push_back(two_pass(name) ? 0.5 : 1.0);
    }
    for (std::size_t p = 0; p < pairings.size(); ++p) {
      if (area_weight[p] == 1.0) continue;
      mirrors.emplace_back(mesh, pairings[p].name(), s.n_gauss, 0.5e-3, /*mirrored=*/true);
      mirror_of.push_back(static_cast<int>(p));
      normal_penalty.push_back(normal_penalty[p]);
      area_weight.push_back(0.5);
      // Bracketing first-pass points of every mirrored point, in reference r.
      const auto& primary = pairings[p].points();
      std::vector<int> order(primary.size());
      std::iota(order.begin(), order.end(), 0);
      std::sort(order.begin(), order.end(),
                [&](int a, int b) { return primary[a].reference_position.x() < primary[b].reference_position.x(); });
      std::vector<std::pair<std::array<int, 2>, double>> source;
      for (const auto& pt : mirrors.back().points()) {
        const double r = pt.reference_position.x();
        auto it = std::lower_bound(order.begin(), order.end(), r,
                                   [&](int i, double v) { return primary[i].reference_position.x() < v; });
        const int hi = it == order.end() ? order.back() : *it;
        const int lo = it == order.begin() ? order.front() : *(it - 1);
        const double r_lo = primary[lo].reference_position.x(), r_hi = primary[hi].reference_position.x();
        const double w = r_hi > r_lo ? std::clamp((r - r_lo) / (r_hi - r_lo), 0.0, 1.0) : 0.0;
        source.push_back({{lo, hi}, w});
      }
      mirror_source.push_back(std::move(source));
    }
  }

  // One coupling group per slave face of every pass, the friction and tie history of
  // its points, and the assemblers of both controls.
  void setup_assemblers() {
    std::vector<std::vector<int>> dof_groups;
    for (int q = 0; q < n_passes(); ++q) {
      const auto& pairing = pass(q);
      for (int f = 0; f < pairing.n_slave_faces(); ++f) {
        groups.emplace_back(q, f);
        std::vector<int> g;
        for (int n : pairing.coupling_nodes(f)) {
          g.push_back(dofs.dof(n, 0));
          g.push_back(dofs.dof(n, 1));
        }
        dof_groups.push_back(std::move(g));
      }
      tau.emplace_back(pairing.points().size(), 0.0);
      ties.emplace_back(pairing.points().size());
      tie_trial.emplace_back(pairing.points().size());
    }
    trial_tau = tau;
    force_assembler = std::make_unique<fem::Assembler>(mesh, dofs, force_constraints, dof_groups);
    displacement_assembler = std::make_unique<fem::Assembler>(mesh, dofs, displacement_constraints, dof_groups);
    // Within a load step most cells are elastic and return the same matrix in every
    // Newton iteration (elastic_matrix below): only the changed ones are scattered.
    force_assembler->enable_cell_matrix_cache();
    displacement_assembler->enable_cell_matrix_cache();
    force_assembler->set_mirror(settings.mirror);
    displacement_assembler->set_mirror(settings.mirror);
    // The preconditioner's factor is large (6·10⁵ entries on the paper's mesh) and
    // its two triangular solves per GMRES iteration stream it from memory: supernodal,
    // so that it is applied in single precision (fem/linear_solver.hpp).
    force_gmres.set_supernodal(true);
    displacement_gmres.set_supernodal(true);
  }

  // Per-cell caches and per-point state (strain, J2 state, stresses), and the fields.
  void allocate_state(double T0) {
    const std::size_t n_points = static_cast<std::size_t>(mesh.n_cells()) * n_q;
    point_cache.assign(n_points, PointCache{});
    geometry_stamp.assign(mesh.n_cells(), 0);
    temperature_stamp.assign(mesh.n_cells(), 0);
    coefficient_stamp.assign(mesh.n_cells(), 0);
    elastic_matrix.resize(mesh.n_cells());
    elastic_stamp.assign(mesh.n_cells(), 0);
    for (auto& stamps : returned_elastic) stamps.assign(mesh.n_cells(), 0);
    linear_increment.resize(mesh.n_cells());
    linear_force.resize(mesh.n_cells());
    linear_reach.assign(mesh.n_cells(), -1.0);
    linear_stamp.assign(mesh.n_cells(), 0);
    linear_stale.assign(mesh.n_cells(), 0);
    fem::CellValues cv(settings.n_gauss);
    cv.reinit(mesh, 0);
    for (int q = 0; q < n_q; ++q) shape.push_back({cv.N(q, 0), cv.N(q, 1), cv.N(q, 2), cv.N(q, 3)});
    strain.assign(n_points, Vector4::Zero());
    trial_strain = strain;
    state.assign(n_points, materials::J2State{});
    trial_state = state;
    trial_stress.assign(n_points, Vector4::Zero());
    increment = Eigen::VectorXd::Zero(dofs.n_dofs());
    last_increment = increment;
    total = Eigen::VectorXd::Zero(dofs.n_dofs());
    temperature = Eigen::VectorXd::Constant(mesh.n_nodes(), T0);
  }

  std::vector<fem::Point> trial_positions() const {
    std::vector<fem::Point> x = current.nodes;
    for (int n = 0; n < mesh.n_nodes(); ++n) x[n] += Eigen::Vector2d(increment[2 * n], increment[2 * n + 1]);
    return x;
  }

  // What the cell kernel needs of a cell that does not change within a step, kept per
  // Gauss point: B̄ and JxW on the configuration x_n (until commit() moves it) and the
  // temperature with its thermal strain (until the temperature field is replaced).
  // Each cell is refreshed by the kernel itself when its stamps are out of date, so
  // the parallel assembly writes only its own cell's entries.
  struct PointCache {
    Matrix48 B_bar;
    double JxW = 0;
    double temperature = 0, thermal_strain = 0, thermal_strain_slope = 0;
    materials::J2Coefficients coefficients;  // at this temperature, committed state, time step
  };
  std::vector<PointCache> point_cache;                // per cell * n_q
  std::vector<int> geometry_stamp, temperature_stamp;  // per cell: the generation cached
  int geometry_generation = 1, temperature_generation = 1;
  // J2 coefficients: recomputed after a new temperature, a commit or a new time step.
  std::vector<int> coefficient_stamp;
  int coefficient_generation = 1;
  // ∫ B̄ᵀ D_el B̄ dV of a cell whose Gauss points all stayed elastic, kept until the
  // coefficients change (new temperature, commit, time step): within a step the
  // elastic tangent of a cell is fixed, and most cells (the electrodes, the cold
  // sheet) stay elastic. Bit for bit what the kernel would compute.
  std::vector<Eigen::Matrix<double, 8, 8>> elastic_matrix;
  std::vector<int> elastic_stamp;  // the coefficient generation of elastic_matrix[e]; 0: none
  // Per assembler (force, displacement control): the coefficient generation whose
  // elastic_matrix[e] the cell returned in its last matrix assembly there, 0 if it
  // returned another matrix. While it is current the cell tells the assembler that its
  // matrix is kept (fem::LocalSystem::matrix_kept) instead of copying it out again.
  std::array<std::vector<int>, 2> returned_elastic;
  int assembling = 0;  // evaluate(): 0 force, 1 displacement control
  // Linear update of an elastic cell. Within a step an elastic cell's force is linear
  // in its displacements: f_e(Δu) = f_e(Δu*) − K_e (Δu − Δu*), K_e = elastic_matrix[e],
  // exact while every Gauss point stays elastic. Δu* is the increment of the cell's
  // last full evaluation, where all its points were elastic with equivalent stress
  // q*_q below the yield stress σ_y,q. A later increment keeps every point elastic if
  //     sqrt(3/2) 2G_q |B̄_q (Δu − Δu*)| ≤ sqrt(3/2) 2G_q ‖B̄_q‖_F |Δu − Δu* − t| < 0.99 σ_y,q − q*_q
  // (the deviatoric stress moves by 2G dev(B̄ δu); t the cell's mean axial
  // translation, which B̄ maps to zero), a bound on |Δu − Δu* − t| kept per cell as
  // linear_reach. Such a cell skips its Gauss points: its force and tangent are the
  // linear update (the same to round-off), and its strains and stresses at the final
  // increment are computed once, at the end of the step's Newton iterations and again
  // at commit() if evaluated since (linear_stale). Most cells of a step
  // (the electrodes, the cold sheet) take this path after the step's first evaluation.
  std::vector<Eigen::Matrix<double, 8, 1>> linear_increment, linear_force;  // Δu*_e, f_e(Δu*)
  std::vector<double> linear_reach;  // m; < 0: none
  std::vector<int> linear_stamp;     // the coefficient generation of the above; 0: none
  std::vector<char> linear_stale;    // trial strains and stresses are those of Δu*, not Δu
  std::atomic<long> linear_count{0};  // cell evaluations by linear update
  std::vector<std::array<double, 4>> shape;            // N_a at the Gauss points
  bool need_matrix = true;                             // evaluate(): tangent wanted
  // group_kernel() adds only the friction traction's coupling to the contact pressure,
  // −(∂τ/∂p) k_n A t nᵀ (no force): see preconditioner_surrogate().
  bool friction_coupling_only = false;

  void set_temperature(const Eigen::VectorXd& nodal_temperature) {
    temperature = nodal_temperature;
    ++temperature_generation;
    ++coefficient_generation;
  }

  void refresh_cell(int e) {
    const auto& c = mesh.cells[e];
    const std::size_t k0 = static_cast<std::size_t>(e) * n_q;
    if (geometry_stamp[e] != geometry_generation) {
      thread_local std::unique_ptr<fem::CellValues> scratch;
      if (!scratch || scratch->n_q() != n_q) scratch = std::make_unique<fem::CellValues>(settings.n_gauss);
      fem::CellValues& fv = *scratch;
      fv.reinit(current, e);
      // B̄ (Hughes 1980): the volumetric part of B replaced by its cell average, with the
      // volumetric strain operator b = (∂N/∂r + N/r, ∂N/∂z).
      constexpr int max_q = 9;
      std::array<Eigen::Matrix<double, 1, 8>, max_q> b;
      std::array<Matrix48, max_q> B;
      Eigen::Matrix<double, 1, 8> b_mean = Eigen::Matrix<double, 1, 8>::Zero();
      double volume = 0;
      for (int q = 0; q < n_q; ++q) {
        const double r = fv.point(q).x();
        B[q].setZero();
        for (int a = 0; a < 4; ++a) {
          const Eigen::Vector2d& g = fv.grad_N(q, a);
          const double N = fv.N(q, a);
          B[q](0, 2 * a) = g.x();              // ε_rr = ∂u_r/∂r
          B[q](1, 2 * a + 1) = g.y();          // ε_zz = ∂u_z/∂z
          B[q](2, 2 * a) = N / r;              // ε_θθ = u_r / r
          B[q](3, 2 * a) = sqrt_half * g.y();  // √2 ε_rz = (∂u_r/∂z + ∂u_z/∂r)/√2
          B[q](3, 2 * a + 1) = sqrt_half * g.x();
          b[q](2 * a) = g.x() + N / r;
          b[q](2 * a + 1) = g.y();
        }
        b_mean += b[q] * fv.JxW(q);
        volume += fv.JxW(q);
      }
      b_mean /= volume;
      const Vector4 m(1.0, 1.0, 1.0, 0.0);
      for (int q = 0; q < n_q; ++q) {
        point_cache[k0 + q].B_bar = B[q] + (m / 3.0) * (b_mean - b[q]);
        point_cache[k0 + q].JxW = fv.JxW(q);
      }
      geometry_stamp[e] = geometry_generation;
    }
    if (temperature_stamp[e] != temperature_generation) {
      const materials::Material& mat = *cell_material[e];
      for (int q = 0; q < n_q; ++q) {
        double T = 0;
        for (int a = 0; a < 4; ++a) T += shape[q][a] * temperature[c[a]];
        const materials::J2Input in = materials::j2_input(mat, Vector4::Zero(), T, initial_temperature);
        point_cache[k0 + q].temperature = T;
        point_cache[k0 + q].thermal_strain = in.thermal_strain;
        point_cache[k0 + q].thermal_strain_slope = in.thermal_strain_slope;
      }
      temperature_stamp[e] = temperature_generation;
    }
    if (coefficient_stamp[e] != coefficient_generation) {
      const materials::Material& mat = *cell_material[e];
      for (int q = 0; q < n_q; ++q)
        point_cache[k0 + q].coefficients =
            materials::j2_coefficients(mat, state[k0 + q], point_cache[k0 + q].temperature, time_step);
      coefficient_stamp[e] = coefficient_generation;
    }
  }

  // Stress update of Gauss point k for the cell displacement increment du; the trial
  // strain, state and stress are kept for commit() and the outputs.
  materials::J2Result update_point(const materials::Material& mat, std::size_t k,
                                   const Eigen::Matrix<double, 8, 1>& du) {
    const PointCache& pc = point_cache[k];
    materials::J2Input in;
    in.strain = strain[k] + pc.B_bar * du;
    in.thermal_strain = pc.thermal_strain;
    in.thermal_strain_slope = pc.thermal_strain_slope;
    in.temperature = pc.temperature;
    in.time_step = time_step;
    materials::J2Result result = materials::j2_update(mat, state[k], in, pc.coefficients);
    trial_strain[k] = in.strain;
    trial_state[k] = result.state;
    trial_stress[k] = result.stress;
    return result;
  }

  void cell_kernel(int e, fem::LocalSystem& local) {
    refresh_cell(e);
    const auto& c = mesh.cells[e];
    const materials::Material& mat = *cell_material[e];
    const std::size_t k0 = static_cast<std::size_t>(e) * n_q;
    Eigen::Matrix<double, 8, 1> du;
    for (int a = 0; a < 4; ++a) du.segment<2>(2 * a) = increment.segment<2>(2 * c[a]);
    Eigen::Matrix<double, 8, 8> Ke = Eigen::Matrix<double, 8, 8>::Zero();
    Eigen::Matrix<double, 8, 1> Fe = Eigen::Matrix<double, 8, 1>::Zero();

    const double kappa = control == Control::displacement ? foundation[mesh.cell_body[e]] : 0.0;
    if (kappa == 0 && linear_stamp[e] == coefficient_generation && elastic_stamp[e] == coefficient_generation) {
      const Eigen::Matrix<double, 8, 1> d = du - linear_increment[e];
      const double mean_z = 0.25 * (d[1] + d[3] + d[5] + d[7]);
      double distance = 0;
      for (int a = 0; a < 4; ++a) distance += d[2 * a] * d[2 * a] + (d[2 * a + 1] - mean_z) * (d[2 * a + 1] - mean_z);
      if (distance <= linear_reach[e] * linear_reach[e]) {
        local.vector.noalias() += linear_force[e] - elastic_matrix[e].lazyProduct(d);  // 8 x 8: no GEMV call
        if (need_matrix) {
          int& returned = returned_elastic[assembling][e];
          if (returned == coefficient_generation) {
            local.matrix_kept = true;
          } else {
            local.matrix += elastic_matrix[e];
            returned = coefficient_generation;
          }
        }
        linear_stale[e] = 1;
        linear_count.fetch_add(1, std::memory_order_relaxed);
        return;
      }
    }
    if (kappa > 0)  // seating foundation: body force -κ u_z towards the initial position
      for (int q = 0; q < n_q; ++q) {
        const double w = point_cache[k0 + q].JxW;
        double uz = 0;
        for (int b = 0; b < 4; ++b) uz += shape[q][b] * (total[2 * c[b] + 1] + increment[2 * c[b] + 1]);
        for (int a = 0; a < 4; ++a) {
          Fe[2 * a + 1] -= kappa * uz * shape[q][a] * w;
          for (int b = 0; b < 4; ++b) Ke(2 * a + 1, 2 * b + 1) += kappa * shape[q][a] * shape[q][b] * w;
        }
      }

    std::array<Matrix4, 9> tangent;  // per Gauss point (n_q ≤ 9)
    bool elastic = true;
    double reach = std::numeric_limits<double>::infinity();  // m, see linear_reach
    for (int q = 0; q < n_q; ++q) {
      const std::size_t k = k0 + q;
      const PointCache& pc = point_cache[k];
      const Matrix48& B_bar = pc.B_bar;
      const auto result = update_point(mat, k, du);
      elastic = elastic && !result.yielded;
      if (elastic && settings.linear_elastic_updates) {
        const double scale = sqrt_three_halves * 2 * pc.coefficients.moduli.shear_modulus * B_bar.norm();
        reach = std::min(reach, (0.99 * pc.coefficients.initial.yield_stress - result.equivalent_stress) / scale);
      }
      if (need_matrix) tangent[q] = result.tangent;
      Fe.noalias() -= pc.JxW * (B_bar.transpose() * result.stress);  // -∫ B̄ᵀ σ dV
    }
    if (need_matrix) {
      if (elastic && elastic_stamp[e] == coefficient_generation) {
        Ke += elastic_matrix[e];
      } else {
        Eigen::Matrix<double, 8, 8> Kc = Eigen::Matrix<double, 8, 8>::Zero();
        for (int q = 0; q < n_q; ++q) {
          const PointCache& pc = point_cache[k0 + q];
          const Matrix48 DB = tangent[q] * pc.B_bar;
          Kc.noalias() += pc.JxW * pc.B_bar.transpose().lazyProduct(DB);  // ∫ B̄ᵀ D B̄ dV (8x4x8: below GEMM size)
        }
        Ke += Kc;
        if (elastic) {
          elastic_matrix[e] = Kc;
          elastic_stamp[e] = coefficient_generation;
        }
      }
    }
    linear_stale[e] = 0;
    if (need_matrix)  // the matrix returned below is elastic_matrix[e] exactly when elastic without foundation
      returned_elastic[assembling][e] =
          elastic && kappa == 0 && elastic_stamp[e] == coefficient_generation ? coefficient_generation : 0;
    if (elastic && settings.linear_elastic_updates && kappa == 0 && reach > 0) {
      linear_increment[e] = du;
      linear_force[e] = Fe;
      linear_reach[e] = reach;
      linear_stamp[e] = coefficient_generation;
    } else {
      linear_stamp[e] = 0;
    }
    local.matrix += Ke;
    local.vector += Fe;
  }

  // Strains and stresses at the current increment of the cells whose last evaluation
  // was a linear update (see linear_reach): elastic by construction.
  void refresh_linear_cells() {
    for (int e = 0; e < mesh.n_cells(); ++e) {
      if (!linear_stale[e]) continue;
      const auto& c = mesh.cells[e];
      const materials::Material& mat = *cell_material[e];
      const std::size_t k0 = static_cast<std::size_t>(e) * n_q;
      Eigen::Matrix<double, 8, 1> du;
      for (int a = 0; a < 4; ++a) du.segment<2>(2 * a) = increment.segment<2>(2 * c[a]);
      for (int q = 0; q < n_q; ++q) update_point(mat, k0 + q, du);
      linear_stale[e] = 0;
    }
  }

  // The 8 dofs of one contact point, (slave 0, slave 1, master 0, master 1) × (r, z),
  // located in the coupling system of its slave face.
  struct PointDofs {
    std::array<int, 4> node_of{};  // local node of each of the four nodes
    // False if a node lies outside the face's coupling nodes.
    bool locate(const contact::InterfacePairing& pairing, int f, const std::array<int, 2>& slave,
                const std::array<int, 2>& master) {
      for (int s = 0; s < 2; ++s) {
        node_of[s] = pairing.local_index(f, slave[s]);
        node_of[2 + s] = pairing.local_index(f, master[s]);
      }
      return std::all_of(node_of.begin(), node_of.end(), [](int i) { return i >= 0; });
    }
    void add(fem::LocalSystem& local, const Vector8& v, const Matrix8& m) const {
      for (int i = 0; i < 8; ++i) {
        const int r = 2 * node_of[i / 2] + i % 2;
        local.touched.push_back(r);
        local.vector[r] += v[i];
        for (int j = 0; j < 8; ++j) local.matrix(r, 2 * node_of[j / 2] + j % 2) += m(i, j);
      }
    }
  };

  Eigen::Vector2d node_increment(int node) const { return Eigen::Vector2d(increment[2 * node], increment[2 * node + 1]); }

  // Contact, friction and ties at the points of one slave face. Each point couples
  // four nodes (two slave, two master): its terms are formed on those 8 dofs and
  // added into the face's coupling system at their local positions.
  void group_kernel(int g, fem::LocalSystem& local) {
    local.lists_touched = true;  // PointDofs::add lists the dofs it writes
    const auto [p, f] = groups[g];
    const auto& pairing = pass(p);
    PointDofs point_dofs;
    for (int k = 0; k < pairing.n_gauss(); ++k) {
      const int idx = f * pairing.n_gauss() + k;
      const auto& pt = pairing.points()[idx];
      if (!friction_coupling_only) trial_tau[p][idx] = 0.0;
      const Tie& tie = ties[p][idx];
      if (tie.on && friction_coupling_only) {
        if (tie.degree >= 1) continue;
      } else if (tie.on) {
        if (!point_dofs.locate(pairing, f, pt.slave_nodes, tie.master_nodes)) {
          pairing_within = false;
          continue;
        }
        tie_point(p, idx, point_dofs, local);
      }
      // Friction carries the share 1 − β of a partly bonded point; the contact pressure
      // acts whole, bonded or not (the tie resists opening only).
      const double share = tie.on ? 1 - tie.degree : 1.0;
      if (!pt.paired || pt.gap >= 0) continue;
      if (!point_dofs.locate(pairing, f, pt.slave_nodes, pt.master_nodes)) {
        pairing_within = false;
        continue;
      }
      contact_point(p, idx, share, point_dofs, local);
    }
  }

  // The tie of a bonded point of pass p: d = x_s − x_m at fixed weights is linear, B
  // maps the 8 dofs to d.
  void tie_point(int p, int idx, const PointDofs& point_dofs, fem::LocalSystem& local) {
    const auto& pt = pass(p).points()[idx];
    const Tie& tie = ties[p][idx];
    const double eps_n = normal_penalty[p];
    Eigen::Matrix<double, 2, 8> B;
    for (int s = 0; s < 2; ++s) {
      B.block<2, 2>(0, 2 * s) = pt.slave_weights[s] * Eigen::Matrix2d::Identity();
      B.block<2, 2>(0, 4 + 2 * s) = -tie.master_weights[s] * Eigen::Matrix2d::Identity();
    }
    Eigen::Vector2d d = pt.position;
    for (int s = 0; s < 2; ++s)
      d -= tie.master_weights[s] * (current.nodes[tie.master_nodes[s]] + node_increment(tie.master_nodes[s]));
    // On the slave side: ε_N (e·t_b) t_b − T n_b, with ∂e/∂u = −β B and
    // ∂T/∂(e·n_b) = −k (k = −dp/dg ≥ 0 of the penalty law).
    const double beta = tie.degree;
    const Eigen::Vector2d e = tie.offset + beta * (tie.relative - d);
    tie_trial[p][idx] = {e, d};
    const auto [tension, k_tension] = contact::penalty_pressure(e.dot(tie.normal), eps_n, settings.contact_smoothing);
    const Eigen::Vector2d traction = eps_n * e.dot(tie.tangent) * tie.tangent - tension * tie.normal;
    const Eigen::Matrix2d stiffness =
        eps_n * tie.tangent * tie.tangent.transpose() + k_tension * tie.normal * tie.normal.transpose();
    const double A_tie = area_weight[p] * pt.reference_area;
    point_dofs.add(local, A_tie * B.transpose() * traction, beta * A_tie * B.transpose() * stiffness * B);
  }

  // Normal contact and friction (the share `share` of it) of a penetrating point of pass p.
  void contact_point(int p, int idx, double share, const PointDofs& point_dofs, fem::LocalSystem& local) {
    const auto& pt = pass(p).points()[idx];
    const double eps_n = normal_penalty[p];
    const double eps_t = settings.friction_penalty_ratio * eps_n;
    const double mu = settings.friction_coefficient;
    // Nv, Tv: the gap and slip operators (g' = Nvᵀ u', slip' = Tvᵀ u' at fixed geometry).
    Vector8 Nv, Tv, du;
    for (int s = 0; s < 2; ++s) {
      Nv.segment<2>(2 * s) = pt.slave_weights[s] * pt.normal;
      Tv.segment<2>(2 * s) = pt.slave_weights[s] * pt.tangent;
      Nv.segment<2>(4 + 2 * s) = -pt.master_weights[s] * pt.normal;
      Tv.segment<2>(4 + 2 * s) = -pt.master_weights[s] * pt.tangent;
      du.segment<2>(2 * s) = node_increment(pt.slave_nodes[s]);
      du.segment<2>(4 + 2 * s) = node_increment(pt.master_nodes[s]);
    }
    // Tractions act on the undeformed area: the surface stretch is small, and no area
    // derivative enters the tangent.
    const double A = area_weight[p] * pt.reference_area;
    const auto [pressure, k_n] = contact::penalty_pressure(pt.gap, eps_n, settings.contact_smoothing);
    Vector8 force = pressure * A * Nv;                        // contact force on both sides
    Matrix8 stiffness = k_n * A * Nv * Nv.transpose();        // -∂f/∂u
    Vector8 friction_force = Vector8::Zero();                 // its friction part
    Matrix8 friction_stiffness = Matrix8::Zero();
    // Geometric terms: the normal n, the tangent t and the master weights (1 − η, η)
    // move with the master face e = x_2 − x_1 (length L) and with the projection η:
    //   δn = t (n·δe)/L,  δt = −n (n·δe)/L,  δη = −(Tvᵀ δu + g (n·δe)/L)/L,
    // with n·δe = −Dvᵀ δu, Dv = (0, 0, n, −n), Dt = (0, 0, t, −t). Hence
    //   δNv = −(Tv Dvᵀ + Dv Tvᵀ + (g/L) Dv Dvᵀ) δu / L,
    //   δTv = (Nv Dvᵀ − Dt Tvᵀ − (g/L) Dt Dvᵀ) δu / L.
    // Where the closest point is a master node shared by two faces (nodal normal)
    // these terms do not apply; there the slave point lies within |g| of the node and
    // the terms they would replace are of order |g|/L.
    const bool geometric = !pt.node_normal;
    Vector8 Dv = Vector8::Zero(), Dt = Vector8::Zero();
    double L = 1, gL = 0;
    if (geometric) {
      L = ((current.nodes[pt.master_nodes[1]] + node_increment(pt.master_nodes[1])) -
           (current.nodes[pt.master_nodes[0]] + node_increment(pt.master_nodes[0])))
              .norm();
      gL = pt.gap / L;
      Dv.segment<2>(4) = pt.normal;
      Dv.segment<2>(6) = -pt.normal;
      Dt.segment<2>(4) = pt.tangent;
      Dt.segment<2>(6) = -pt.tangent;
      stiffness += (pressure * A / L) * (Tv * Dv.transpose() + Dv * Tv.transpose() + gL * Dv * Dv.transpose());
    }
    if (mu > 0 && pressure > 0) {
      // Regularised Coulomb friction (contact/mechanical_contact.hpp) on the trial
      // traction τ_trial = τ_n + ε_T Δs.
      const double slip = Tv.dot(du);  // tangential slip increment
      const auto friction = contact::regularised_coulomb(tau[p][idx] + eps_t * slip, mu, pressure);
      if (friction_coupling_only) {
        point_dofs.add(local, Vector8::Zero(), -share * friction.d_pressure * k_n * A * Tv * Nv.transpose());
        return;
      }
      trial_tau[p][idx] = friction.traction;
      friction_force = -friction.traction * A * Tv;  // friction opposes the slip
      // ∂slip/∂u = Tvᵀ + duᵀ ∂Tv/∂u; ∂p/∂u = −k_n Nvᵀ.
      Vector8 dslip = Tv;
      if (geometric) dslip += (du.dot(Nv) * Dv - du.dot(Dt) * (Tv + gL * Dv)) / L;
      friction_stiffness = friction.d_trial * eps_t * A * Tv * dslip.transpose();
      friction_stiffness -= friction.d_pressure * k_n * A * Tv * Nv.transpose();
      if (geometric)
        friction_stiffness +=
            (friction.traction * A / L) * (Nv * Dv.transpose() - Dt * Tv.transpose() - gL * Dt * Dv.transpose());
    }
    if (!friction_coupling_only) point_dofs.add(local, force + share * friction_force, stiffness + share * friction_stiffness);
  }

  // Under a mirror, the values of image cells (never evaluated) from their sources.
  void from_sources(std::vector<double>& cell_values) const {
    if (settings.mirror.empty()) return;
    for (int e = 0; e < mesh.n_cells(); ++e)
      if (settings.mirror.cell_source[e] >= 0) cell_values[e] = cell_values[settings.mirror.cell_source[e]];
  }

  // Reduced residual (and tangent) at the current increment.
  void evaluate(Control ctrl, fem::SparseMatrix& K, Eigen::VectorXd& R, bool matrix) {
    const std::vector<fem::Point> x = trial_positions();
    for (int q = 0; q < n_passes(); ++q)
      if (!pass(q).update(x)) pairing_within = false;
    const fem::Assembler& assembler = ctrl == Control::force ? *force_assembler : *displacement_assembler;
    fem::Assembler::Terms terms;
    if (!skip_cells) terms.cells = [this](int e, fem::LocalSystem& l) { cell_kernel(e, l); };
    if (!skip_groups) terms.groups = [this](int g, fem::LocalSystem& l) { group_kernel(g, l); };
    for (const auto& [boundary, pressure] : settings.pressure_loads) {
      const double p = pressure;
      terms.faces.push_back({&mesh.boundary(boundary), [this, p](const fem::BoundaryFace& f, fem::LocalSystem& l) {
                               fem::FaceValues fv(settings.n_gauss);
                               fv.reinit(current, f.cell, f.face);
                               for (int q = 0; q < fv.n_q(); ++q)
                                 for (int a = 0; a < 4; ++a)  // traction t = -p n
                                   l.vector.segment<2>(2 * a) -= p * fv.normal(q) * fv.N(q, a) * fv.JxW(q);
                             }});
    }
    need_matrix = matrix;
    assembling = ctrl == Control::force ? 0 : 1;
    assembler.assemble(terms, K, R, /*homogeneous=*/true, matrix);
    need_matrix = true;
    if (ctrl == Control::force) {
      Eigen::VectorXd f_ext = Eigen::VectorXd::Zero(dofs.n_dofs());
      f_ext[w_dof] = -force;  // the electrode presses down on the stack
      R += force_constraints.condense(f_ext);
    }
  }

  // A matrix near the tangent K (evaluated at the current increment) whose symmetric
  // part is positive definite, for the GMRES preconditioner where K's is not
  // (fem::PreconditionedGmres): K without the friction traction's coupling to the
  // contact pressure. At a sliding point that term, μ k_n A t nᵀ, has no symmetric
  // counterpart, and the symmetric part of the point's normal/tangential block
  // [[k_n, μk_n/2], [μk_n/2, k_t]] is indefinite once the sliding stiffness k_t falls
  // below μ² k_n / 4 (measured: with friction the paper's mesh needed 26 LU
  // factorisations of K per weld, frictionless none).
  const fem::SparseMatrix& preconditioner_surrogate(Control ctrl, const fem::SparseMatrix& K) {
    const fem::Assembler& assembler = ctrl == Control::force ? *force_assembler : *displacement_assembler;
    fem::Assembler::Terms terms;
    terms.groups = [this](int g, fem::LocalSystem& l) { group_kernel(g, l); };
    Eigen::VectorXd unused;
    friction_coupling_only = true;
    assembler.assemble(terms, surrogate_coupling, unused, /*homogeneous=*/true, /*assemble_matrix=*/true);
    friction_coupling_only = false;
    surrogate = K;
    const double* c = surrogate_coupling.valuePtr();
    double* v = surrogate.valuePtr();
    for (Eigen::Index i = 0; i < surrogate.nonZeros(); ++i) v[i] -= c[i];
    return surrogate;
  }
  fem::SparseMatrix surrogate, surrogate_coupling;  // preconditioner_surrogate()'s result and scratch

  // Debug aid (MechanicsSettings::verbose): compares the tangent with a finite difference of the
  // residual along the Newton direction and names the node with the worst mismatch.
  void diagnose(Control ctrl, const Eigen::VectorXd& base, const Eigen::VectorXd& step, fem::SparseMatrix& K) {
    fem::Constraints& cons = ctrl == Control::force ? force_constraints : displacement_constraints;
    fem::SparseMatrix K0;
    Eigen::VectorXd R0, R1, dummy;
    increment = base;
    evaluate(ctrl, K0, R0, true);
    // A perturbation of 1 nm at the largest nodal move: a fixed factor on Newton steps
    // of 10⁻¹⁰ m moved nodes by 10⁻¹⁶ m, within a few last bits of their coordinates
    // (about 4·10⁻¹⁹ m at r = 3 mm), and the check reported round-off as tangent error.
    const double h = 1e-9 / std::max(step.lpNorm<Eigen::Infinity>(), 1e-300);
    increment = base + h * step;
    fem::SparseMatrix K1;
    evaluate(ctrl, K1, R1, false);
    const Eigen::VectorXd y = cons.restrict_to_free(step);
    const Eigen::VectorXd fd = -(R1 - R0) / h, lin = K0 * y;
    Eigen::Index worst;
    (fd - lin).cwiseAbs().maxCoeff(&worst);
    int dof = -1;
    for (int d = 0; d < dofs.n_dofs(); ++d)
      if (cons.free_index(d) == worst) dof = d;
    const int node = dof / 2;
    for (int part = 0; part < 2; ++part) {
      skip_cells = part == 1;
      skip_groups = part == 0;
      fem::SparseMatrix Ka, Kb;
      Eigen::VectorXd Ra, Rb;
      increment = base;
      evaluate(ctrl, Ka, Ra, true);
      increment = base + h * step;
      evaluate(ctrl, Kb, Rb, false);
      const Eigen::VectorXd f = -(Ra - Rb) / h * -1.0, l = Ka * y;
      std::fprintf(stderr, "    %s only: |fd - K d| / |K d| = %.3e\n", part == 0 ? "cells" : "contact",
                   (-(Rb - Ra) / h - l).norm() / std::max(l.norm(), 1e-300));
      (void)f;
    }
    skip_cells = skip_groups = false;
    std::fprintf(stderr, "  tangent check: |fd - K d| / |K d| = %.3e; worst at dof %d (node %d, body %s, r = %.4f mm, "
                 "z = %.4f mm, T = %.0f): fd %.4e, K d %.4e\n",
                 (fd - lin).norm() / lin.norm(), dof, node,
                 node < mesh.n_nodes() ? mesh.body_names[mesh.node_body[node]].c_str() : "extra",
                 node < mesh.n_nodes() ? mesh.nodes[node].x() * 1e3 : 0.0,
                 node < mesh.n_nodes() ? mesh.nodes[node].y() * 1e3 : 0.0,
                 node < mesh.n_nodes() ? temperature[node] : 0.0, fd[worst], lin[worst]);
  }

  // Outcome of Newton iterations on one target (see newton()).
  enum class Outcome { converged, stalled, out_of_iterations, failed };

  // Newton iterations on R(Δu) − (1 − s) R_0 = 0 from the current increment until the
  // ∞-norm is below `tolerance`, at most `max_iterations`. The linear systems are
  // solved by GMRES preconditioned with a factorisation of an earlier tangent
  // (fem::PreconditionedGmres), refactorised when it needs many iterations. Each
  // full step is evaluated with its tangent (accepted almost always); a full step that
  // does not reduce |R|₂ (Armijo) is halved, down to 1/64, with residual-only
  // evaluations. If no length reduces |R|₂ the iterations stop (stalled) at the last
  // accepted point: the Newton direction is then useless (a contact point closing or a
  // plastic point unloading far inside the step), and smaller targets s are needed.
  Outcome iterate(Control ctrl, const Eigen::VectorXd& R0, double s, double tolerance, int max_iterations,
                  fem::SparseMatrix& K, Eigen::VectorXd& R, MechanicsStepReport& report) {
    fem::Constraints& cons = ctrl == Control::force ? force_constraints : displacement_constraints;
    fem::PreconditionedGmres& gmres = ctrl == Control::force ? force_gmres : displacement_gmres;
    const double shift = 1 - s;
    auto target = [&](const Eigen::VectorXd& r) -> Eigen::VectorXd { return shift == 0 ? r : r - shift * R0; };
    Eigen::VectorXd Rs = target(R);
    Eigen::VectorXd best = increment;  // the iterate of least |R − (1 − s) R_0|₂
    double best_norm = Rs.norm();
    int misses = 0;                    // consecutive steps without descent
    double previous_norm = 0;          // |R − (1 − s) R_0|₂ before the last step
    double previous_correction = 0;    // m, ∞-norm of the last full Newton step (0: none or damped)
    for (int it = 1; it <= max_iterations; ++it) {
      ++report.iterations;
      // Linear tolerance η (relative), after Eisenstat and Walker (SIAM J. Sci.
      // Comput. 17 (1996) 16–32, choice 2): η = 0.9 (|R_k|/|R_k−1|)², at most 10⁻²,
      // 10⁻⁴ on the first iteration. The step that the quadratic model ‖R_k‖∞
      // (|R_k|/|R_k−1|)² expects to reach the tolerance is solved to 1 % of it, so the
      // linear error does not cost an extra Newton iteration. Only the path depends on
      // η: convergence is judged on the true residual.
      const double norm_now = std::max(Rs.norm(), 1e-300);
      const double final_eta = 0.01 * tolerance / norm_now;
      double eta = 1e-4;
      if (previous_norm > 0) {
        const double ratio = norm_now / previous_norm;
        const bool last = Rs.lpNorm<Eigen::Infinity>() * ratio * ratio <= tolerance;
        eta = last ? final_eta : std::min(1e-2, 0.9 * ratio * ratio);
      }
      eta = std::min(1e-2, std::max({1e-10, eta, std::min(final_eta, 1e-4)}));
      previous_norm = norm_now;
      Eigen::VectorXd dy;
      try {
        if (ctrl == Control::force && elimination.prepare(K)) {
          // GMRES on the unknowns that remain, to the same absolute residual (η |R|; GMRES
          // stops at half its tolerance, so an interior residual below 1 % of 0.5 η |R| is
          // dropped: InteriorElimination::reduce).
          const Eigen::VectorXd r = elimination.reduce(Rs, 0.01 * 0.5 * eta * Rs.norm());
          Eigen::VectorXd dy_reduced;
          gmres.solve_refreshing(elimination.reduced(), r, dy_reduced, eta * Rs.norm() / std::max(r.norm(), 1e-300),
                                 /*refresh_after=*/10, /*max_iterations=*/40, [&]() -> const fem::SparseMatrix& {
                                   return elimination.reduce_matrix(preconditioner_surrogate(ctrl, K));
                                 });
          dy = elimination.expand(Rs, dy_reduced);
        } else {
          gmres.solve_refreshing(K, Rs, dy, eta, /*refresh_after=*/10, /*max_iterations=*/40,
                                 [&]() -> const fem::SparseMatrix& { return preconditioner_surrogate(ctrl, K); });
        }
      } catch (const std::exception& e) {
        report.message = std::string("linear solve failed: ") + e.what();
        return Outcome::failed;
      }
      const Eigen::VectorXd step = cons.distribute(dy, /*homogeneous=*/true);
      const Eigen::VectorXd base = increment;
      const double norm2 = Rs.norm();
      double alpha = 1.0;
      increment = base + step;
      evaluate(ctrl, K_trial, R_trial, true);
      if (target(R_trial).norm() <= (1 - 1e-4) * norm2) {
        K.swap(K_trial);  // Eigen 3.4.0 SparseMatrix has no move: std::swap would copy it three times
        R.swap(R_trial);
      } else {
        bool descent = false;
        while (!descent && alpha > 1.0 / 64) {
          alpha *= 0.5;
          increment = base + alpha * step;
          evaluate(ctrl, K_trial, R_trial, false);
          descent = target(R_trial).norm() <= (1 - 1e-4 * alpha) * norm2;
        }
        if (descent) {
          misses = 0;
        } else {
          // No descent: the residual has a kink close by (a plastic point switching to
          // unloading, a contact point closing, stick turning to slip) that the tangent
          // does not see. A few short steps usually cross it; more mean the direction
          // is useless, and the iteration returns to the best point seen.
          if (settings.verbose) diagnose(ctrl, base, step, K);
          if (++misses > 4) {
            increment = best;
            evaluate(ctrl, K, R, true);
            if (settings.verbose)
              std::fprintf(stderr, "  newton %2d: s = %.4f, stalled at |R| = %.3e N (no descent along the Newton step)\n",
                           report.iterations, s, target(R).lpNorm<Eigen::Infinity>());
            return Outcome::stalled;
          }
          increment = base + alpha * step;
        }
        evaluate(ctrl, K, R, true);
      }
      Rs = target(R);
      if (Rs.norm() < best_norm) {
        best_norm = Rs.norm();
        best = increment;
      }
      const double norm = Rs.lpNorm<Eigen::Infinity>();
      const double correction = (alpha * step).lpNorm<Eigen::Infinity>();
      report.residual = norm;
      if (settings.verbose)
        std::fprintf(stderr, "  newton %2d: s = %.4f, |R| = %.3e N, alpha = %.3f, |du| = %.3e m\n", report.iterations, s,
                     norm, alpha, correction);
      if (norm <= tolerance || (correction <= settings.displacement_tolerance && norm <= 1e3 * tolerance))
        return Outcome::converged;
      // Error estimate of the converging iteration (Deuflhard, Newton Methods for
      // Nonlinear Problems, Springer 2004, §2.1): once two full steps in a row contract
      // superlinearly, the next correction, about |Δu_k|² / |Δu_k−1|, bounds the
      // iterate's remaining error. Below settings.mechanics_error_estimate the step is
      // accepted without the iteration that would only confirm it, while the residual
      // is within 10² of its tolerance.
      if (alpha == 1.0 && previous_correction > 0 && correction < 0.1 * previous_correction &&
          correction * correction / previous_correction <= settings.mechanics_error_estimate &&
          norm <= 1e2 * tolerance)
        return Outcome::converged;
      previous_correction = alpha == 1.0 ? correction : 0.0;
    }
    return Outcome::out_of_iterations;
  }

  // Newton's method for the step from the predictor Δu_0. First on the step itself;
  // if that stalls, by continuation in the step's initial out-of-balance force R_0 =
  // R(Δu_0): R(Δu) = (1 − s) R_0 is solved for s rising from 0 (solved by Δu_0) to 1
  // (the step), in increments that grow after a success and shrink after a stall.
  // Nothing is committed between the targets: the material and friction history stay
  // those of the start of the step, so the solution at s = 1 is the step's own, as if
  // Newton had found it directly. (Sub-steps of the driver, by contrast, commit
  // intermediate states.) Intermediate targets are solved loosely (1 % of |R_0|).
  // `K_start` and `R_start`, if given, are the evaluation at the starting increment
  // (with pairing_within set by it): Newton takes them over instead of evaluating again.
  MechanicsStepReport newton(Control ctrl, double load_scale, fem::SparseMatrix* K_start = nullptr,
                             Eigen::VectorXd* R_start = nullptr) {
    MechanicsStepReport report;
    fem::SparseMatrix K;
    Eigen::VectorXd R;
    const double tolerance = settings.mechanics_tolerance * std::max(load_scale, 1.0);
    const Eigen::VectorXd start = increment;
    if (K_start && R_start) {
      K.swap(*K_start);
      R.swap(*R_start);
    } else {
      pairing_within = true;
      evaluate(ctrl, K, R, true);
    }
    report.residual = R.lpNorm<Eigen::Infinity>();
    const Eigen::VectorXd R0 = R;
    Outcome outcome = report.residual <= tolerance ? Outcome::converged
                                                   : iterate(ctrl, R0, 1.0, tolerance, settings.max_iterations, K, R, report);
    if (outcome == Outcome::stalled) {
      increment = start;
      evaluate(ctrl, K, R, true);
      const double stage_tolerance = std::max(tolerance, 1e-2 * R0.lpNorm<Eigen::Infinity>());
      double s_done = 0, ds = 0.25;
      while (outcome != Outcome::failed && report.iterations < settings.max_continuation_iterations) {
        const double s = std::min(1.0, s_done + ds);
        const Eigen::VectorXd saved = increment;
        const int budget = std::min(settings.max_iterations,
                                    settings.max_continuation_iterations - report.iterations);
        outcome = iterate(ctrl, R0, s, s == 1.0 ? tolerance : stage_tolerance, budget, K, R, report);
        if (outcome == Outcome::converged) {
          if (s == 1.0) break;
          s_done = s;
          ds *= 2;
        } else if (outcome != Outcome::failed) {
          increment = saved;
          evaluate(ctrl, K, R, true);
          ds *= 0.25;
          if (ds < 1.0 / 4096) break;
        }
      }
      if (outcome != Outcome::converged && outcome != Outcome::failed)
        report.message = "Newton stalled (continuation in the out-of-balance force reached s = " +
                         std::to_string(s_done) + "; residual " + std::to_string(report.residual) + " N)";
    }
    report.converged = outcome == Outcome::converged;
    refresh_linear_cells();  // strains and stresses of the final increment everywhere
    // The residual of the state the step ends in (the last evaluation is always there).
    if (!report.converged && outcome != Outcome::failed) report.residual = R.lpNorm<Eigen::Infinity>();
    if (outcome == Outcome::out_of_iterations)
      report.message = "Newton did not converge in " + std::to_string(settings.max_iterations) +
                       " iterations (residual " + std::to_string(report.residual) + " N)";
    if (!pairing_within)
      report.message += std::string(report.message.empty() ? "" : "; ") +
                        "a contact point slid beyond its search margin";
    return report;
  }

  // Initial guess: the last step's increment scaled to this step's load change (same
  // control); for a first displacement step, the loaded body moved rigidly by Δw.
  void predict(Control ctrl, double change) {
    load_change = change;
    if (last_control == ctrl && last_load_change != 0 && change != 0) {
      increment = last_increment * (change / last_load_change);
      return;
    }
    increment.setZero();
    if (ctrl == Control::displacement) {
      const int body = mesh.node_body[mesh.boundary_nodes(settings.loaded_boundary).front()];
      for (int n = 0; n < mesh.n_nodes(); ++n)
        if (mesh.node_body[n] == body) increment[2 * n + 1] = change;
      increment[w_dof] = change;
      // Under a mirror the image of the loaded body moves the other way.
      if (!settings.mirror.empty())
        increment = displacement_constraints.distribute(displacement_constraints.restrict_to_free(increment));
    }
  }

  // Axial force through the upper end face at the current increment (N, > 0 pressing):
  // the force-control residual with no applied load is the end face's internal force.
  double end_face_force() {
    const double saved = force;
    force = 0;
    fem::SparseMatrix K;
    Eigen::VectorXd R;
    evaluate(Control::force, K, R, false);
    force = saved;
    const int w_free = force_constraints.free_index(w_dof);
    return R[w_free];
  }
};

Mechanics::Mechanics(const fem::Mesh& mesh, std::vector<const materials::Material*> body_materials,
                     const MechanicsSettings& settings, double initial_temperature)
    : impl_(std::make_unique<Impl>(mesh, std::move(body_materials), settings, initial_temperature)),
      positions_(mesh.nodes) {
  if (settings.mirror.empty()) return;
  if (!fem::are_images(settings.mirror, mesh.boundary_nodes(settings.fixed_boundary),
                       mesh.boundary_nodes(settings.loaded_boundary)))
    throw std::invalid_argument("Mechanics: under a mirror the fixed boundary '" + settings.fixed_boundary +
                                "' must be the image of the loaded boundary '" + settings.loaded_boundary + "'");
  approach_per_w_ = 2;
}

Mechanics::~Mechanics() = default;

MechanicsSolverCounts Mechanics::solver_counts() const {
  MechanicsSolverCounts c;
  for (const auto* gmres : {&impl_->force_gmres, &impl_->displacement_gmres}) {
    c.gmres_iterations += gmres->n_iterations();
    c.factorisations += gmres->n_factorizations();
    c.surrogates += gmres->n_surrogates();
    c.lu_factorisations += gmres->n_full_factorizations();
  }
  for (const auto* assembler : {impl_->force_assembler.get(), impl_->displacement_assembler.get()}) {
    c.cell_matrices_scattered += assembler->cell_matrices_scattered();
    c.cell_matrices_reused += assembler->cell_matrices_reused();
  }
  c.condensations = impl_->elimination.n_condensations();
  c.condensations_reused = impl_->elimination.n_reuses();
  c.interior_unknowns = impl_->elimination.n_interior();
  c.border_unknowns = impl_->elimination.n_border();
  return c;
}

MechanicsStepReport Mechanics::solve_force_step(double force, const Eigen::VectorXd& nodal_temperature) {
  Impl& m = *impl_;
  m.set_temperature(nodal_temperature);
  m.control = Control::force;
  m.force = force;
  m.predict(Control::force, force - force_);
  if (m.predictor_scale > 0 && m.last_control == Control::force && m.last_increment.size() == m.increment.size()) {
    // The alternative guess: the last increment scaled (at constant force the
    // temperature, and with it the thermal strain, moves on smoothly from step to
    // step); the one with the smaller residual starts Newton. The converged step does
    // not depend on the choice. The alternative, which wins in most steps, is
    // evaluated with its tangent, and Newton starts from that evaluation.
    fem::SparseMatrix unused, K_alternative;
    Eigen::VectorXd R_rule, R_alternative;
    m.evaluate(Control::force, unused, R_rule, false);
    const Eigen::VectorXd rule = m.increment;
    m.increment = m.last_increment * m.predictor_scale;
    m.pairing_within = true;
    m.evaluate(Control::force, K_alternative, R_alternative, true);
    m.predictor_scale = 0;
    if (R_alternative.norm() < R_rule.norm()) {
      auto report = m.newton(Control::force, std::abs(force), &K_alternative, &R_alternative);
      force_ = force;
      return report;
    }
    m.increment = rule;
  }
  m.predictor_scale = 0;
  auto report = m.newton(Control::force, std::abs(force));
  force_ = force;
  return report;
}

MechanicsStepReport Mechanics::solve_displacement_step(double w, const Eigen::VectorXd& nodal_temperature) {
  Impl& m = *impl_;
  m.set_temperature(nodal_temperature);
  m.control = Control::displacement;
  w /= approach_per_w_;  // the loaded face's share of the approach
  m.displacement_constraints.set_value(m.w_dof, w - w_);
  m.displacement_constraints.close();
  m.predict(Control::displacement, w - w_);
  // Load scale for the tolerance: the force of the previous step, or a nominal 1 kN.
  auto report = m.newton(Control::displacement, std::max(std::abs(force_), 1e3));
  force_ = m.end_face_force();
  return report;
}

void Mechanics::set_predictor(double scale) { impl_->predictor_scale = scale; }

void Mechanics::set_time_step(double seconds) {
  if (seconds != impl_->time_step) ++impl_->coefficient_generation;
  impl_->time_step = seconds;
}

void Mechanics::commit() {
  Impl& m = *impl_;
  m.refresh_linear_cells();
  m.strain = m.trial_strain;
  m.state = m.trial_state;
  m.tau = m.trial_tau;
  for (std::size_t q = 0; q < m.ties.size(); ++q)
    for (std::size_t i = 0; i < m.ties[q].size(); ++i)
      if (m.ties[q][i].on) {
        m.ties[q][i].offset = m.tie_trial[q][i].offset;
        m.ties[q][i].relative = m.tie_trial[q][i].relative;
      }
  m.total += m.increment;
  m.last_increment = m.increment;
  m.last_load_change = m.load_change;
  m.last_control = m.control;
  for (int n = 0; n < m.mesh.n_nodes(); ++n)
    m.current.nodes[n] += Eigen::Vector2d(m.increment[2 * n], m.increment[2 * n + 1]);
  ++m.geometry_generation;
  ++m.coefficient_generation;
  w_ += m.increment[m.w_dof];
  m.increment.setZero();
  positions_ = m.current.nodes;
  if (!m.settings.mirror.empty())
    for (auto& x : positions_) x.y() += w_;  // the rigid shift that puts the fixed end face back
}

Eigen::VectorXd Mechanics::displacement() const {
  Eigen::VectorXd u = impl_->total.head(2 * impl_->mesh.n_nodes());
  if (!impl_->settings.mirror.empty())
    for (int n = 0; n < impl_->mesh.n_nodes(); ++n) u[2 * n + 1] += w_;
  return u;
}

std::vector<InterfaceState> Mechanics::interface_states() const {
  std::vector<InterfaceState> out;
  const Impl& m = *impl_;
  for (std::size_t p = 0; p < m.pairings.size(); ++p) {
    const auto& pairing = m.pairings[p];
    InterfaceState s;
    s.name = pairing.name();
    std::vector<int> order(pairing.points().size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      return pairing.points()[a].position.x() < pairing.points()[b].position.x();
    });
    // Bonded points count as closed for the contact radius: the gap of a point with
    // bonding degree β enters as (1 − β) g + β min(g, 0), so a fused region held in
    // slight tension (g of a few nm) is inside the radius, continuously in β.
    std::vector<double> closure;
    for (int i : order) {
      const auto& pt = pairing.points()[i];
      const double pressure =
          pt.paired ? penalty_pressure(pt.gap, m.normal_penalty[p], m.settings.contact_smoothing).pressure : 0.0;
      s.radius.push_back(pt.position.x());
      s.pressure.push_back(pressure);
      s.gap.push_back(pt.paired ? pt.gap : std::nan(""));
      s.shear.push_back(m.tau[p][i]);
      s.normal_force += pressure * pt.reference_area;
      const double beta = m.ties[p][i].on ? m.ties[p][i].degree : 0.0;
      closure.push_back(pt.paired ? (1 - beta) * pt.gap + beta * std::min(pt.gap, 0.0) : std::nan(""));
    }
    // Outermost zero crossing of that gap, interpolated between points; where the
    // contact reaches the last paired point (no open point follows it), that point.
    for (std::size_t i = 0; i < closure.size(); ++i) {
      const double g0 = closure[i];
      if (std::isnan(g0) || g0 > 0) continue;
      const double g1 = i + 1 < closure.size() ? closure[i + 1] : std::nan("");
      s.contact_radius = g1 > 0 ? s.radius[i] + (s.radius[i + 1] - s.radius[i]) * g0 / (g0 - g1) : s.radius[i];
    }
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<double> Mechanics::von_mises() const {
  const Impl& m = *impl_;
  std::vector<double> out(m.mesh.n_cells(), 0.0);
  for (int e = 0; e < m.mesh.n_cells(); ++e) {
    for (int q = 0; q < m.n_q; ++q) {
      const Vector4& s = m.trial_stress[static_cast<std::size_t>(e) * m.n_q + q];
      const double p = (s[0] + s[1] + s[2]) / 3.0;
      const Vector4 dev(s[0] - p, s[1] - p, s[2] - p, s[3]);
      out[e] += std::sqrt(1.5 * dev.squaredNorm());  // Mandel: s:s = |dev|^2
    }
    out[e] /= m.n_q;
  }
  m.from_sources(out);
  return out;
}

std::vector<double> Mechanics::equivalent_plastic_strain() const {
  const Impl& m = *impl_;
  std::vector<double> out(m.mesh.n_cells(), 0.0);
  for (int e = 0; e < m.mesh.n_cells(); ++e) {
    for (int q = 0; q < m.n_q; ++q)
      out[e] += m.state[static_cast<std::size_t>(e) * m.n_q + q].equivalent_plastic_strain;
    out[e] /= m.n_q;
  }
  m.from_sources(out);
  return out;
}

long Mechanics::linear_cell_updates() const { return impl_->linear_count.load(); }

std::vector<PointStress> Mechanics::point_stresses() const {
  const Impl& m = *impl_;
  std::vector<PointStress> out;
  fem::CellValues fv(m.settings.n_gauss);
  const fem::MirrorSymmetry& mirror = m.settings.mirror;
  const double shift = mirror.empty() ? 0.0 : w_;
  for (int e = 0; e < m.mesh.n_cells(); ++e) {
    // An image cell's points are its source's reflected (u_z and τ_rz change sign).
    const int source = mirror.empty() ? -1 : mirror.cell_source[e];
    fv.reinit(m.current, source < 0 ? e : source);
    for (int q = 0; q < m.n_q; ++q) {
      PointStress p{fv.point(q), m.trial_stress[static_cast<std::size_t>(source < 0 ? e : source) * m.n_q + q]};
      if (source >= 0) {
        p.position.y() = -p.position.y();
        p.stress[3] = -p.stress[3];
      }
      p.position.y() += shift;
      out.push_back(p);
    }
  }
  return out;
}

double Mechanics::normal_penalty(const std::string& interface) const {
  for (std::size_t p = 0; p < impl_->pairings.size(); ++p)
    if (impl_->pairings[p].name() == interface) return impl_->normal_penalty[p];
  throw std::out_of_range("unknown interface '" + interface + "'");
}

const std::vector<contact::InterfacePairing>& Mechanics::pairings() const { return impl_->pairings; }

void Mechanics::set_bonded(const std::vector<std::vector<char>>& bonded) {
  std::vector<std::vector<double>> degree(bonded.size());
  for (std::size_t p = 0; p < bonded.size(); ++p)
    for (char b : bonded[p]) degree[p].push_back(b ? 1.0 : 0.0);
  set_bonding_degree(degree);
}

void Mechanics::set_bonding_degree(const std::vector<std::vector<double>>& degree) {
  Impl& m = *impl_;
  auto apply = [&m](int q, std::size_t i, double value) {
    auto& tie = m.ties[q][i];
    const auto& pt = m.pass(q).points()[i];
    // The share Δβ that bonds now takes over the committed friction traction it
    // carried, −τ t (the slave side's traction in group_kernel): e_n gains
    // −Δβ τ t_b / ε_N, so the traction is continuous (the contact pressure acts on).
    const double friction_offset = m.tau[q][i] / m.normal_penalty[q];
    if (tie.on) {
      const double grown = std::min(1.0, value) - tie.degree;
      if (grown > 0) {
        tie.offset -= grown * friction_offset * tie.tangent;
        tie.degree += grown;
        m.tie_trial[q][i].offset = tie.offset;
      }
      return;
    }
    if (!(value > 0) || !pt.paired) return;
    // Bond in the state reached: no tension, and the share β of the friction traction.
    tie.degree = std::min(1.0, value);
    tie.on = true;
    tie.master_nodes = pt.master_nodes;
    tie.master_weights = pt.master_weights;
    tie.normal = pt.normal;
    tie.tangent = pt.tangent;
    const Eigen::Vector2d x_m = pt.master_weights[0] * m.current.nodes[pt.master_nodes[0]] +
                                pt.master_weights[1] * m.current.nodes[pt.master_nodes[1]];
    tie.relative = pt.position - x_m;
    tie.offset = -tie.degree * friction_offset * tie.tangent;
    m.tie_trial[q][i] = {tie.offset, tie.relative};
  };
  for (std::size_t p = 0; p < m.pairings.size() && p < degree.size(); ++p)
    for (std::size_t i = 0; i < m.pairings[p].points().size() && i < degree[p].size(); ++i)
      apply(static_cast<int>(p), i, degree[p][i]);
  // A mirrored pass takes the degree of the first-pass points it lies between.
  for (std::size_t k = 0; k < m.mirrors.size(); ++k) {
    const std::size_t p = static_cast<std::size_t>(m.mirror_of[k]);
    if (p >= degree.size()) continue;
    for (std::size_t i = 0; i < m.mirror_source[k].size(); ++i) {
      const auto& [pair, w] = m.mirror_source[k][i];
      if (static_cast<std::size_t>(std::max(pair[0], pair[1])) >= degree[p].size()) continue;
      apply(static_cast<int>(m.pairings.size() + k), i, (1 - w) * degree[p][pair[0]] + w * degree[p][pair[1]]);
    }
  }
}

std::vector<double> Mechanics::contact_pressure(int p) const {
  const Impl& m = *impl_;
  std::vector<double> out;
  const auto& points = m.pairings.at(p).points();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& pt = points[i];
    // Compression is the contact's alone, bonded or not (a tie resists opening only).
    out.push_back(pt.paired ? penalty_pressure(pt.gap, m.normal_penalty[p], m.settings.contact_smoothing).pressure : 0.0);
  }
  return out;
}

void Mechanics::residual_and_tangent(const Eigen::VectorXd& increment, double force,
                                     const Eigen::VectorXd& nodal_temperature, Eigen::VectorXd& residual,
                                     fem::SparseMatrix& tangent) {
  Impl& m = *impl_;
  m.set_temperature(nodal_temperature);
  m.force = force;
  m.control = Control::force;
  m.increment = increment;
  m.evaluate(Control::force, tangent, residual, true);
}

int Mechanics::n_free_force_control() const { return impl_->force_constraints.n_free(); }

Eigen::VectorXd Mechanics::full_increment(const Eigen::VectorXd& reduced) const {
  return impl_->force_constraints.distribute(reduced, true);
}

}  // namespace rsw::physics
