// One weld step of the electro-thermal coupling with its retry policy; see
// electro_thermal_step.hpp.
#include "physics/electro_thermal_step.hpp"

#include "fem/fixed_point.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <utility>

namespace rsw::physics {

ElectroThermalStep::ElectroThermalStep(const fem::Mesh& mesh, Electrical& electrical, Thermal& thermal,
                                       const CouplingSettings& settings, Stopwatch& clock, bool verbose)
    : mesh_(mesh), electrical_(electrical), thermal_(thermal), settings_(settings), clock_(clock), verbose_(verbose) {}

bool ElectroThermalStep::evaluate(const Eigen::VectorXd& T_in, Eigen::VectorXd& T_out) {
  std::vector<double> joule;
  std::vector<std::vector<double>> interface_heat;
  if (current_ != 0.0) {
    clock_.start("electrical");
    try {
      const auto& sol = electrical_.solve(*positions_, T_in, current_, *contact_, thermal_.interface_history());
      joule = sol.joule_heat;
      interface_heat = sol.interface_heat;
    } catch (const std::exception& e) {
      failure_ = std::string("electrical: ") + e.what();
      return false;
    }
    have_electrical_ = true;
  }
  clock_.start("thermal");
  thermal_.set_start(T_in);
  const double tolerance = current_ == 0.0 || exact_inner_
                               ? settings_.thermal_tolerance
                               : std::max(settings_.thermal_tolerance, std::min(0.1, 1e-3 * last_change_));
  const auto report = thermal_.solve(dt_, *positions_, *contact_, joule, interface_heat, tolerance);
  if (!report.converged) {
    failure_ = "thermal: " + report.message;
    return false;
  }
  T_out = thermal_.temperature();
  last_change_ = (T_out - T_in).lpNorm<Eigen::Infinity>();
  if (verbose_) {
    Eigen::Index worst = 0;
    const double change = (T_out - T_in).cwiseAbs().maxCoeff(&worst);
    std::fprintf(stderr, "  coupling: change %.3e K at %s (%.4f, %.4f) mm, T = %.1f degC\n", change,
                 mesh_.body_names[mesh_.node_body[worst]].c_str(), (*positions_)[worst].x() * 1e3,
                 (*positions_)[worst].y() * 1e3, T_out[worst]);
  }
  return true;
}

CoupledStepReport ElectroThermalStep::solve(double dt, double current, const std::vector<fem::Point>& positions,
                                            const contact::ContactState& contact) {
  dt_ = dt;
  current_ = current;
  positions_ = &positions;
  contact_ = &contact;
  last_change_ = std::numeric_limits<double>::infinity();
  failure_.clear();
  const fem::FixedPointMap G = [this](const Eigen::VectorXd& T_in, Eigen::VectorXd& T_out) {
    return evaluate(T_in, T_out);
  };
  CoupledStepReport report;
  Eigen::VectorXd T_iter = thermal_.predicted_temperature(dt);
  if (current == 0.0) {
    Eigen::VectorXd T_out;
    report.converged = G(T_iter, T_out);
    report.iterations = 1;
    report.failure = failure_;
    return report;
  }
  fem::FixedPointSettings fp;
  fp.tolerance = settings_.tolerance;
  fp.max_iterations = settings_.max_iterations;
  fp.estimate_error = true;  // fem/fixed_point.hpp: the iterate that would only confirm is saved
  const int depth = settings_.acceleration_depth;
  const int other_depth = depth == 0 ? 0 : (depth > 2 ? 2 : 5);
  std::vector<std::pair<int, double>> attempts;
  for (const double beta : {1.0, 0.7, 0.4})
    for (const int d : {depth, other_depth})
      if (std::find(attempts.begin(), attempts.end(), std::make_pair(d, beta)) == attempts.end())
        attempts.emplace_back(d, beta);
  const Eigen::VectorXd T_guess = T_iter;
  fem::FixedPointReport coupling;
  for (std::size_t attempt = 0; attempt < attempts.size(); ++attempt) {
    if (attempt > 0) ++retries_;
    T_iter = T_guess;
    fp.depth = attempts[attempt].first;
    fp.damping = attempts[attempt].second;
    failure_.clear();
    last_change_ = std::numeric_limits<double>::infinity();
    coupling = fem::solve_fixed_point(G, T_iter, fp);
    report.iterations += coupling.iterations;
    if (coupling.converged || !failure_.empty()) break;
    if (attempt == 0) {
      // Newton's method from the step's start. A field solve that fails at one of its
      // iterates (far from the fixed point) ends it, not the step: the Anderson
      // retries follow.
      ++newton_solves_;
      fem::NewtonKrylovSettings newton;
      newton.tolerance = settings_.tolerance;
      newton.max_evaluations = newton_budget();
      T_iter = T_guess;
      exact_inner_ = true;
      const fem::FixedPointReport solved = fem::solve_fixed_point_newton(G, T_iter, newton);
      exact_inner_ = false;
      report.iterations += solved.iterations;
      if (verbose_)
        std::fprintf(stderr, "  coupling: Newton %s after %d evaluations (change %.3e K)%s%s\n",
                     solved.converged ? "converged" : "failed", solved.iterations, solved.change,
                     solved.converged ? "" : ": ", solved.converged ? "" : solved.message.c_str());
      if (solved.converged) {
        ++newton_rescues_;
        coupling = solved;
        break;
      }
      failure_.clear();
    }
  }
  report.converged = coupling.converged;
  if (!report.converged)
    report.failure = failure_.empty()
                         ? "electro-thermal coupling did not converge in " + std::to_string(settings_.max_iterations) +
                               " iterations, also by Newton's method (" + std::to_string(newton_budget()) +
                               " evaluations)," +
                               (other_depth != depth ? " with Anderson depth " + std::to_string(other_depth) + " and"
                                                     : std::string()) +
                               " with damping 0.7 and 0.4 (last change " + std::to_string(coupling.change) + " K)"
                         : failure_;
  return report;
}

}  // namespace rsw::physics
