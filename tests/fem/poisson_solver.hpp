// Test driver: steady scalar diffusion -∇·(k ∇u) = f on an fem::Mesh, with
// Dirichlet values and prescribed inward fluxes on named boundaries, assembled by
// the one assembly loop and solved with CHOLMOD. Used by the verification tests
// (patch test, manufactured solutions, NAFEMS, Holm constriction); the physics
// kernels of the weld model live in physics/, not here.
#pragma once

#include "fem/assembler.hpp"
#include "fem/constraints.hpp"
#include "fem/dof_map.hpp"
#include "fem/fe_values.hpp"
#include "fem/linear_solver.hpp"

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace rsw::test {

using ScalarFunction = std::function<double(const fem::Point&)>;

struct PoissonProblem {
  fem::CoordinateSystem coords = fem::CoordinateSystem::axisymmetric;
  double conductivity = 1.0;
  ScalarFunction source;  // f, may be empty
  std::vector<std::pair<std::string, ScalarFunction>> dirichlet;
  std::vector<std::pair<std::string, double>> inward_flux;  // q = k ∂u/∂(-n) on a boundary
  int n_gauss = 2;
};

struct PoissonSolution {
  Eigen::VectorXd u;  // nodal values, hanging nodes included
  int n_free = 0;
};

inline PoissonSolution solve_poisson(const fem::Mesh& mesh, const PoissonProblem& p) {
  fem::DofMap dofs(mesh, 1);
  fem::Constraints constraints(dofs.n_dofs());
  constraints.add_hanging_nodes(mesh, dofs);
  for (const auto& [name, g] : p.dirichlet) constraints.constrain_boundary(mesh, dofs, name, 0, g);
  constraints.close();
  fem::Assembler assembler(mesh, dofs, constraints);

  auto cell_kernel = [&](int cell, fem::LocalSystem& local) {
    fem::CellValues fv(p.n_gauss, p.coords);
    fv.reinit(mesh, cell);
    for (int q = 0; q < fv.n_q(); ++q) {
      const double f = p.source ? p.source(fv.point(q)) : 0.0;
      for (int a = 0; a < 4; ++a) {
        // (k ∇N_a · ∇N_b) dV: conduction; (f N_a) dV: source
        for (int b = 0; b < 4; ++b)
          local.matrix(a, b) += p.conductivity * fv.grad_N(q, a).dot(fv.grad_N(q, b)) * fv.JxW(q);
        local.vector(a) += f * fv.N(q, a) * fv.JxW(q);
      }
    }
  };
  std::vector<fem::Assembler::FaceTerm> faces;
  for (const auto& [name, q_in] : p.inward_flux) {
    const double flux = q_in;
    faces.push_back({&mesh.boundary(name), [&mesh, &p, flux](const fem::BoundaryFace& f, fem::LocalSystem& local) {
                       fem::FaceValues fv(p.n_gauss, p.coords);
                       fv.reinit(mesh, f.cell, f.face);
                       for (int q = 0; q < fv.n_q(); ++q)
                         for (int a = 0; a < 4; ++a) local.vector(a) += flux * fv.N(q, a) * fv.JxW(q);  // (q N_a) dA
                     }});
  }
  fem::SparseMatrix K;
  Eigen::VectorXd F;
  assembler.assemble(cell_kernel, faces, K, F);
  fem::LinearSolver solver(fem::SolverKind::cholmod);
  const Eigen::VectorXd y = solver.solve(K, F);
  return {constraints.distribute(y), constraints.n_free()};
}

// Flux leaving the domain through a Dirichlet boundary, ∫_Γ (-k ∇u)·n dA, computed
// as the reaction -(∫ k ∇u·∇w dV - ∫ f w dV) for the conforming test function w that
// is 1 on the nodes of `boundary` and 0 elsewhere (more accurate than differentiating
// u on the boundary).
inline double boundary_outflow(const fem::Mesh& mesh, const PoissonProblem& p, const Eigen::VectorXd& u,
                               const std::string& boundary) {
  Eigen::VectorXd w = Eigen::VectorXd::Zero(mesh.n_nodes());
  for (int n : mesh.boundary_nodes(boundary)) w[n] = 1.0;
  for (const auto& h : mesh.hanging_nodes) w[h.node] = 0.5 * (w[h.parents[0]] + w[h.parents[1]]);
  double total = 0;
  fem::CellValues fv(p.n_gauss, p.coords);
  for (int e = 0; e < mesh.n_cells(); ++e) {
    const auto& c = mesh.cells[e];
    if (w[c[0]] == 0 && w[c[1]] == 0 && w[c[2]] == 0 && w[c[3]] == 0) continue;
    fv.reinit(mesh, e);
    for (int q = 0; q < fv.n_q(); ++q) {
      Eigen::Vector2d grad_u = Eigen::Vector2d::Zero(), grad_w = Eigen::Vector2d::Zero();
      double w_q = 0;
      for (int a = 0; a < 4; ++a) {
        grad_u += u[c[a]] * fv.grad_N(q, a);
        grad_w += w[c[a]] * fv.grad_N(q, a);
        w_q += w[c[a]] * fv.N(q, a);
      }
      const double f = p.source ? p.source(fv.point(q)) : 0.0;
      total += (p.conductivity * grad_u.dot(grad_w) - f * w_q) * fv.JxW(q);
    }
  }
  return -total;
}

// L2 and H1-seminorm errors against an exact solution, with a 4x4 Gauss rule.
struct ErrorNorms {
  double l2 = 0, h1 = 0;
};
inline ErrorNorms error_norms(const fem::Mesh& mesh, const Eigen::VectorXd& u, const ScalarFunction& exact,
                              const std::function<Eigen::Vector2d(const fem::Point&)>& exact_grad,
                              fem::CoordinateSystem coords = fem::CoordinateSystem::axisymmetric) {
  fem::CellValues fv(4, coords);
  double l2 = 0, h1 = 0;
  for (int e = 0; e < mesh.n_cells(); ++e) {
    fv.reinit(mesh, e);
    const auto& c = mesh.cells[e];
    for (int q = 0; q < fv.n_q(); ++q) {
      double uh = 0;
      Eigen::Vector2d gh = Eigen::Vector2d::Zero();
      for (int a = 0; a < 4; ++a) {
        uh += u[c[a]] * fv.N(q, a);
        gh += u[c[a]] * fv.grad_N(q, a);
      }
      l2 += std::pow(uh - exact(fv.point(q)), 2) * fv.JxW(q);
      h1 += (gh - exact_grad(fv.point(q))).squaredNorm() * fv.JxW(q);
    }
  }
  return {std::sqrt(l2), std::sqrt(h1)};
}

}  // namespace rsw::test
