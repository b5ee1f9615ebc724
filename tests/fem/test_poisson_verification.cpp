// Verification of the axisymmetric scalar FE core against closed forms:
// patch test on a distorted 2:1 mesh, manufactured-solution convergence rates on
// uniform, quadtree and mapped quadtree meshes, the NAFEMS axisymmetric benchmark,
// and Holm's constriction resistance. Each test prints its measured figures.
#include "fem/quadtree.hpp"
#include "poisson_solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace rsw;
using rsw::test::PoissonProblem;

namespace {

// Rectangle [r0, r1] x [z0, z1] on an n_r x n_z base grid; `levels(x, y)` gives the
// level wanted for a cell (index box centre); `distort` optionally moves interior
// points (index coordinates -> physical). Boundaries "bottom", "right", "top", "left".
fem::Mesh rectangle(double r0, double r1, double z0, double z1, int n_r, int n_z,
                    const std::function<int(const fem::IndexBox&)>& levels = {},
                    const fem::Quadtree::Map& map_override = {}) {
  fem::Quadtree tree(n_r, n_z);
  if (levels) tree.refine(levels);
  tree.balance();
  fem::Quadtree::Map map = map_override ? map_override : [=](double x, double y) {
    return fem::Point(r0 + (r1 - r0) * x / n_r, z0 + (z1 - z0) * y / n_z);
  };
  return tree.build("block", map, [](double, double, fem::Side s) -> std::string {
    static const char* names[] = {"bottom", "right", "top", "left"};
    return names[static_cast<int>(s)];
  });
}

double slope(double e_coarse, double e_fine) { return std::log2(e_coarse / e_fine); }

}  // namespace

// u = 1 + 2r + 3z solves -Δu = -2/r (axisymmetric Laplacian of 2r is 2/r) and lies in
// the Q1 space on any mesh, so Galerkin must reproduce it to round-off, hanging
// nodes and distorted cells included.
TEST(PoissonVerification, PatchTestIsExactOnDistortedTwoToOneMesh) {
  const int n = 4;
  auto levels = [](const fem::IndexBox& b) { return (b.x0 < 1.5 && b.y0 < 1.5) ? 2 : 0; };
  auto map = [](double x, double y) {
    const double r = 0.25 * x, z = 0.25 * y;
    return fem::Point(r + 0.08 * r * (1 - r) * std::sin(3 * z), z + 0.06 * z * (1 - z) * std::cos(2 * r));
  };
  const fem::Mesh mesh = rectangle(0, 1, 0, 1, n, n, levels, map);
  ASSERT_GT(mesh.hanging_nodes.size(), 0u);
  auto exact = [](const fem::Point& p) { return 1 + 2 * p.x() + 3 * p.y(); };
  PoissonProblem p;
  p.source = [](const fem::Point& x) { return -2.0 / x.x(); };
  for (const char* b : {"block.bottom", "block.right", "block.top"}) p.dirichlet.emplace_back(b, exact);
  const auto sol = test::solve_poisson(mesh, p);
  double worst = 0;
  for (int i = 0; i < mesh.n_nodes(); ++i) worst = std::max(worst, std::abs(sol.u[i] - exact(mesh.nodes[i])));
  std::printf("patch test: %d cells, %zu hanging nodes, max nodal error %.2e\n", mesh.n_cells(),
              mesh.hanging_nodes.size(), worst);
  EXPECT_LT(worst, 1e-11);
}

// Manufactured solution u = (1 - r^2) sin(π z) on [0,1]^2:
// -Δu = (4 + π^2 (1 - r^2)) sin(π z); u = 0 on r = 1, z = 0, z = 1; natural on the axis.
TEST(PoissonVerification, ManufacturedSolutionConvergesAtOptimalRates) {
  auto exact = [](const fem::Point& p) { return (1 - p.x() * p.x()) * std::sin(M_PI * p.y()); };
  auto grad = [](const fem::Point& p) {
    return Eigen::Vector2d(-2 * p.x() * std::sin(M_PI * p.y()), M_PI * (1 - p.x() * p.x()) * std::cos(M_PI * p.y()));
  };
  PoissonProblem p;
  p.source = [](const fem::Point& x) { return (4 + M_PI * M_PI * (1 - x.x() * x.x())) * std::sin(M_PI * x.y()); };
  for (const char* b : {"block.bottom", "block.right", "block.top"}) p.dirichlet.emplace_back(b, [](const fem::Point&) { return 0.0; });

  struct Series {
    const char* name;
    std::function<fem::Mesh(int)> make;
  };
  const std::vector<Series> series = {
      {"uniform", [&](int n) { return rectangle(0, 1, 0, 1, n, n); }},
      {"quadtree (left half +1 level)",
       [&](int n) {
         return rectangle(0, 1, 0, 1, n, n, [n](const fem::IndexBox& b) { return b.x1 <= 0.5 * n + 1e-12 ? 1 : 0; });
       }},
      {"mapped quadtree",
       [&](int n) {
         auto map = [n](double x, double y) {
           const double r = x / n, z = y / n;
           return fem::Point(r + 0.1 * r * (1 - r) * std::sin(M_PI * z), z + 0.05 * std::sin(M_PI * z) * r * (1 - r));
         };
         return rectangle(0, 1, 0, 1, n, n, [n](const fem::IndexBox& b) { return b.y1 <= 0.5 * n + 1e-12 ? 1 : 0; },
                          map);
       }},
  };
  for (const auto& s : series) {
    std::vector<test::ErrorNorms> errors;
    std::printf("MMS %s:\n", s.name);
    for (int n : {4, 8, 16, 32}) {
      const fem::Mesh mesh = s.make(n);
      const auto sol = test::solve_poisson(mesh, p);
      errors.push_back(test::error_norms(mesh, sol.u, exact, grad));
      std::printf("  n = %2d: %5d cells, %4zu hanging, L2 %.3e, H1 %.3e", n, mesh.n_cells(),
                  mesh.hanging_nodes.size(), errors.back().l2, errors.back().h1);
      if (errors.size() > 1)
        std::printf(", slopes L2 %.2f H1 %.2f", slope(errors[errors.size() - 2].l2, errors.back().l2),
                    slope(errors[errors.size() - 2].h1, errors.back().h1));
      std::printf("\n");
    }
    const auto& c = errors[errors.size() - 2];
    const auto& f = errors.back();
    EXPECT_NEAR(slope(c.l2, f.l2), 2.0, 0.1) << s.name;
    EXPECT_NEAR(slope(c.h1, f.h1), 1.0, 0.1) << s.name;
  }
}

// NAFEMS axisymmetric benchmark: hollow cylinder r in [0.02, 0.1] m, z in [0, 0.14] m,
// k = 52 W/(m K), 5e5 W/m^2 into the inner face over z in [0.04, 0.10], T = 0 degC on the
// outer face, top and bottom, inner face otherwise insulated. Reference
// T(0.04, 0.04) = 59.82 degC (NAFEMS "Standard benchmark tests for thermal analysis").
TEST(PoissonVerification, NafemsAxisymmetricCylinderMatchesReference) {
  const double reference = 59.82;
  std::printf("NAFEMS axisymmetric cylinder, T(0.04, 0.04):\n");
  double last = 0;
  for (int level = 0; level <= 3; ++level) {
    // Base grid 0.01 m (8 x 14 cells), so z = 0.04 and 0.10 are grid lines.
    fem::Quadtree tree(8, 14);
    tree.refine([level](const fem::IndexBox&) { return level; });
    fem::Mesh mesh = tree.build(
        "cylinder", [](double x, double y) { return fem::Point(0.02 + 0.01 * x, 0.01 * y); },
        [](double x, double y, fem::Side s) -> std::string {
          if (s == fem::Side::left) return (y > 4 && y < 10) ? "heated" : "insulated";
          return "cold";
        });
    PoissonProblem p;
    p.conductivity = 52.0;
    p.dirichlet.emplace_back("cylinder.cold", [](const fem::Point&) { return 0.0; });
    p.inward_flux.emplace_back("cylinder.heated", 5e5);
    const auto sol = test::solve_poisson(mesh, p);
    int probe = -1;
    for (int i = 0; i < mesh.n_nodes(); ++i)
      if ((mesh.nodes[i] - fem::Point(0.04, 0.04)).norm() < 1e-12) probe = i;
    ASSERT_GE(probe, 0);
    last = sol.u[probe];
    std::printf("  h = %.5f m: %5d cells, T = %.3f degC (%.3f %% from reference)\n", 0.01 / (1 << level),
                mesh.n_cells(), last, 100 * (last - reference) / reference);
  }
  EXPECT_NEAR(last, reference, 0.005 * reference);
}

// Holm constriction: current from an equipotential spot of radius a on the end of a
// long cylinder of radius b flows to its far end. Total resistance
// R = ρ L / (π b^2) + ρ / (4a) ψ(a/b), with ψ(ε) = 1 - 1.40925 ε + 0.29591 ε^3
// + 0.05254 ε^5 + 0.02105 ε^7 + 0.01107 ε^9 (Roberts' series for a flux tube, as
// quoted by Timsit, "Electrical contact resistance: properties of stationary
// interfaces", IEEE Trans. CPT 22 (1999)). ρ = 2.5e-7 Ω m, a = 2.5 mm, b = 12.5 mm
// (ε = 0.2), L = 50 mm. The spot edge is singular, so convergence needs local
// refinement: the error must fall as the cells around the edge refine.
TEST(PoissonVerification, HolmConstrictionApproachesClosedFormUnderLocalRefinement) {
  const double rho = 2.5e-7, a = 2.5e-3, b = 12.5e-3, L = 50e-3, V = 1.0;
  const double eps = a / b;
  const double psi = 1 - 1.40925 * eps + 0.29591 * std::pow(eps, 3) + 0.05254 * std::pow(eps, 5) +
                     0.02105 * std::pow(eps, 7) + 0.01107 * std::pow(eps, 9);
  const double R_c = rho / (4 * a) * psi;
  std::printf("Holm constriction, rho/(4a) psi = %.4f uOhm (psi = %.5f); two half-spaces rho/(2a) = %.1f uOhm\n",
              R_c * 1e6, psi, rho / (2 * a) * 1e6);
  std::vector<double> errors;
  for (int level = 0; level <= 4; ++level) {
    // Base cells 0.625 mm (20 x 80); refine towards the spot edge (r = a, z = 0).
    const double h = 0.625e-3;
    fem::Quadtree tree(20, 80);
    tree.refine([&](const fem::IndexBox& box) {
      const double r0 = box.x0 * h, r1 = box.x1 * h, z0 = box.y0 * h;
      int want = 0;
      for (int k = 1; k <= 2 * level; ++k) {
        const double reach = 4 * a / (1 << k);
        if (r1 > a - reach && r0 < a + reach && z0 < reach) want = std::min(k, level * 2);
      }
      return want;
    });
    tree.balance();
    fem::Mesh mesh = tree.build(
        "rod", [h](double x, double y) { return fem::Point(x * h, y * h); },
        [&](double x, double y, fem::Side s) -> std::string {
          if (s == fem::Side::bottom) return x * h < a ? "spot" : "insulated";
          if (s == fem::Side::top) return "far_end";
          return "insulated";
        });
    PoissonProblem p;
    p.conductivity = 1.0 / rho;
    p.dirichlet.emplace_back("rod.spot", [](const fem::Point&) { return 0.0; });
    p.dirichlet.emplace_back("rod.far_end", [V](const fem::Point&) { return V; });
    const auto sol = test::solve_poisson(mesh, p);
    const double I = test::boundary_outflow(mesh, p, sol.u, "rod.spot");
    const double R_num = V / std::abs(I) - rho * L / (M_PI * b * b);
    errors.push_back(std::abs(R_num - R_c) / R_c);
    std::printf("  refinement %d: %6d cells, min edge %.4f mm, R_c = %.4f uOhm, error %.3f %%\n", 2 * level,
                mesh.n_cells(), fem::mesh_stats(mesh).min_edge * 1e3, R_num * 1e6, 100 * errors.back());
  }
  for (std::size_t k = 1; k < errors.size(); ++k) EXPECT_LT(errors[k], errors[k - 1]);
  EXPECT_LT(errors.back(), 0.01);
}
