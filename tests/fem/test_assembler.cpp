// The assembly loop: condensation equals P^T K P formed explicitly, re-assembly reuses
// the pattern, Dirichlet values are exact, and the linear solvers agree.
#include "fem/assembler.hpp"
#include "fem/fe_values.hpp"
#include "fem/linear_solver.hpp"
#include "fem/quadtree.hpp"
#include "fem/threads.hpp"

#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

using namespace rsw;

namespace {
fem::Mesh small_mesh() {
  fem::Quadtree tree(3, 2);
  tree.refine([](const fem::IndexBox& b) { return b.x0 < 1 && b.y0 < 1 ? 2 : 0; });
  tree.balance();
  return tree.build("m", [](double x, double y) { return fem::Point(0.5 + x, y + 0.1 * x * y); },
                    [](double, double, fem::Side s) -> std::string { return s == fem::Side::right ? "right" : "other"; });
}

// Stiffness of -Δ with a unit source.
void laplace_kernel(const fem::Mesh& mesh, int cell, fem::LocalSystem& local) {
  fem::CellValues fv(2);
  fv.reinit(mesh, cell);
  for (int q = 0; q < fv.n_q(); ++q)
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) local.matrix(a, b) += fv.grad_N(q, a).dot(fv.grad_N(q, b)) * fv.JxW(q);
      local.vector(a) += fv.N(q, a) * fv.JxW(q);
    }
}
// small_mesh() with one scalar dof per node, its hanging nodes constrained and the
// inhomogeneous values 1 + y on the right edge.
struct ConstrainedScalarMesh {
  fem::Mesh mesh = small_mesh();
  fem::DofMap dofs{mesh, 1};
  fem::Constraints c{dofs.n_dofs()};
  ConstrainedScalarMesh() {
    c.add_hanging_nodes(mesh, dofs);
    c.constrain_boundary(mesh, dofs, "m.right", 0, [](const fem::Point& p) { return 1.0 + p.y(); });
    c.close();
  }
};

// The problem above with two assemblers of it: `fresh` without, `incremental` with the
// cell-matrix cache.
struct CachedAndFresh : ConstrainedScalarMesh {
  fem::Assembler fresh{mesh, dofs, c}, incremental{mesh, dofs, c};
  CachedAndFresh() { incremental.enable_cell_matrix_cache(); }
};
}  // namespace

TEST(Assembler, CondensedSystemEqualsExplicitProlongation) {
  const ConstrainedScalarMesh problem;
  const fem::Mesh& mesh = problem.mesh;
  const fem::DofMap& dofs = problem.dofs;
  const fem::Constraints& c = problem.c;
  fem::Assembler assembler(mesh, dofs, c);
  fem::SparseMatrix K;
  Eigen::VectorXd F;
  assembler.assemble([&](int e, fem::LocalSystem& l) { laplace_kernel(mesh, e, l); }, K, F);

  // Full system and explicit P, g.
  const int n = dofs.n_dofs();
  Eigen::MatrixXd K_full = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd F_full = Eigen::VectorXd::Zero(n);
  for (int e = 0; e < mesh.n_cells(); ++e) {
    fem::LocalSystem l;
    l.matrix = Eigen::MatrixXd::Zero(4, 4);
    l.vector = Eigen::VectorXd::Zero(4);
    laplace_kernel(mesh, e, l);
    for (int a = 0; a < 4; ++a) {
      F_full[mesh.cells[e][a]] += l.vector[a];
      for (int b = 0; b < 4; ++b) K_full(mesh.cells[e][a], mesh.cells[e][b]) += l.matrix(a, b);
    }
  }
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n, c.n_free());
  Eigen::VectorXd g(n);
  for (int d = 0; d < n; ++d) {
    auto [b, end] = c.expansion(d);
    for (auto it = b; it != end; ++it) P(d, it->dof) += it->weight;
    g[d] = c.inhomogeneity(d);
  }
  const Eigen::MatrixXd K_red = P.transpose() * K_full * P;
  const Eigen::VectorXd F_red = P.transpose() * (F_full - K_full * g);
  EXPECT_LT((Eigen::MatrixXd(K) - K_red).norm(), 1e-12 * K_red.norm());
  EXPECT_LT((F - F_red).norm(), 1e-12 * F_red.norm());

  // Re-assembly into the same matrix gives the same values (pattern reused, zeroed).
  const Eigen::MatrixXd first = Eigen::MatrixXd(K);
  assembler.assemble([&](int e, fem::LocalSystem& l) { laplace_kernel(mesh, e, l); }, K, F);
  EXPECT_EQ((Eigen::MatrixXd(K) - first).norm(), 0.0);
}

// A cell kernel that throws (an inverted cell) inside the parallel colour loop: the
// exception reaches the caller, whatever the thread count, instead of terminating the
// process (an exception may not leave an OpenMP region).
// A coupling group's kernel that lists the dofs it writes (LocalSystem::touched) is
// zeroed and scattered over those rows and columns only: K and F are those of the
// whole-matrix scan to the bit, on groups of free, hanging (constrained) and fixed
// dofs, and a second assembly with other kernels' entries finds the group matrices
// zeroed again, also after a kernel threw.
TEST(Assembler, GroupKernelListingItsDofsGivesTheWholeMatrixAssembly) {
  ConstrainedScalarMesh s;
  std::vector<int> hanging;
  for (const auto& h : s.mesh.hanging_nodes) hanging.push_back(h.node);
  ASSERT_GE(hanging.size(), 2u);
  const int n = s.dofs.n_dofs();
  // Three groups of 24 dofs: every third dof, a run with the hanging nodes, the last ones.
  std::vector<std::vector<int>> groups(3);
  for (int d = 0; d < 24; ++d) {
    groups[0].push_back((3 * d) % n);
    groups[1].push_back(d < 2 ? hanging[d] : (d * 7 + 1) % n);
    groups[2].push_back(n - 1 - d);
  }
  for (auto& g : groups) {
    std::sort(g.begin(), g.end());
    g.erase(std::unique(g.begin(), g.end()), g.end());
  }
  // Each group couples two sets of four local dofs (shifted by `shift`), with values
  // that differ per entry and a zero among them.
  auto kernel = [&](int shift, bool list) {
    return [&groups, shift, list](int g, fem::LocalSystem& local) {
      local.lists_touched = list;
      const int size = static_cast<int>(groups[g].size());
      for (int set = 0; set < 2; ++set) {
        std::array<int, 4> node{};
        for (int a = 0; a < 4; ++a) node[a] = (shift + 5 * set + 3 * a + g) % size;
        if (list) local.touched.insert(local.touched.end(), node.begin(), node.end());
        for (int a = 0; a < 4; ++a) {
          local.vector[node[a]] += 0.5 + a + set;
          for (int b = 0; b < 4; ++b)
            local.matrix(node[a], node[b]) += (a == 1 && b == 2) ? 0.0 : 1.0 + 0.1 * a + 0.01 * b + g + 0.3 * set;
        }
      }
    };
  };
  fem::Assembler assembler(s.mesh, s.dofs, s.c, groups);
  auto assemble = [&](int shift, bool list, fem::SparseMatrix& K, Eigen::VectorXd& F) {
    fem::Assembler::Terms terms;
    terms.cells = [&](int e, fem::LocalSystem& l) { laplace_kernel(s.mesh, e, l); };
    terms.groups = kernel(shift, list);
    assembler.assemble(terms, K, F);
  };
  for (int shift : {0, 2}) {
    fem::SparseMatrix K_whole, K_listed;
    Eigen::VectorXd F_whole, F_listed;
    assemble(shift, false, K_whole, F_whole);
    assemble(shift, true, K_listed, F_listed);
    ASSERT_EQ(K_whole.nonZeros(), K_listed.nonZeros());
    EXPECT_TRUE(std::equal(K_whole.valuePtr(), K_whole.valuePtr() + K_whole.nonZeros(), K_listed.valuePtr()))
        << "shift " << shift;
    EXPECT_EQ(F_whole, F_listed) << "shift " << shift;
    // The groups add to K: the listed assembly is not the cells' alone.
    fem::SparseMatrix K_cells;
    Eigen::VectorXd F_cells;
    fem::Assembler::Terms cells_only;
    cells_only.cells = [&](int e, fem::LocalSystem& l) { laplace_kernel(s.mesh, e, l); };
    assembler.assemble(cells_only, K_cells, F_cells);
    EXPECT_GT((Eigen::MatrixXd(K_listed) - Eigen::MatrixXd(K_cells)).norm(), 1.0);
  }
  // A kernel that throws after writing leaves no entries behind for the next assembly.
  fem::SparseMatrix K_whole, K_after;
  Eigen::VectorXd F_whole, F_after;
  assemble(0, false, K_whole, F_whole);
  fem::Assembler::Terms throwing;
  throwing.cells = [&](int e, fem::LocalSystem& l) { laplace_kernel(s.mesh, e, l); };
  throwing.groups = [&](int g, fem::LocalSystem& local) {
    kernel(1, true)(g, local);
    if (g == 1) throw std::runtime_error("group kernel failed");
  };
  EXPECT_THROW(assembler.assemble(throwing, K_after, F_after), std::runtime_error);
  assemble(0, true, K_after, F_after);
  EXPECT_TRUE(std::equal(K_whole.valuePtr(), K_whole.valuePtr() + K_whole.nonZeros(), K_after.valuePtr()));
  EXPECT_EQ(F_whole, F_after);
}

TEST(Assembler, ExceptionOfACellKernelReachesTheCaller) {
  const fem::Mesh mesh = small_mesh();
  fem::DofMap dofs(mesh, 1);
  fem::Constraints c(dofs.n_dofs());
  c.add_hanging_nodes(mesh, dofs);
  c.close();
  fem::Assembler assembler(mesh, dofs, c);
  fem::SparseMatrix K;
  Eigen::VectorXd F;
  const int bad = mesh.n_cells() / 2;
  for (const int threads : {1, 2}) {
    fem::use_threads(threads);
    EXPECT_THROW(assembler.assemble(
                     [&](int e, fem::LocalSystem& l) {
                       if (e == bad) throw std::runtime_error("cell " + std::to_string(e) + " is inverted");
                       laplace_kernel(mesh, e, l);
                     },
                     K, F),
                 std::runtime_error);
  }
  fem::use_threads(1);
}

// With two threads the cell loop runs on both (its region is a fem::TeamRegion; any
// other region runs on the calling thread alone), and the result is the one-thread one
// to round-off (the cells along the block border are added after the blocks).
TEST(Assembler, TwoThreadsShareTheCellLoopAndGiveTheOneThreadResult) {
  const ConstrainedScalarMesh p;
  const fem::Mesh& mesh = p.mesh;
  fem::Assembler assembler(mesh, p.dofs, p.c);
  fem::SparseMatrix K1, K2;
  Eigen::VectorXd F1, F2;
  fem::use_threads(1);
  assembler.assemble([&](int e, fem::LocalSystem& l) { laplace_kernel(mesh, e, l); }, K1, F1);
  fem::use_threads(2);
  std::atomic<int> seen{0};  // bit t: thread t ran a cell kernel
  assembler.assemble(
      [&](int e, fem::LocalSystem& l) {
        seen.fetch_or(1 << omp_get_thread_num());
        laplace_kernel(mesh, e, l);
      },
      K2, F2);
  fem::use_threads(1);
  EXPECT_EQ(seen.load(), 3);
  EXPECT_LE((Eigen::MatrixXd(K2) - Eigen::MatrixXd(K1)).norm(), 1e-14 * Eigen::MatrixXd(K1).norm());
  EXPECT_LE((F2 - F1).norm(), 1e-14 * F1.norm());
}

// Incremental cell matrices: a sequence of assemblies in which some cells change
// their matrix (scaled by a per-cell factor) and the others repeat theirs. Each result
// equals a fresh assembly of the same kernels by an assembler without the cache (to
// round-off), the unchanged cells are not scattered, a kernel that throws halfway
// through leaves the next assembly correct, and so do 2 threads and more than 64
// assemblies (the periodic rebuild).
TEST(Assembler, IncrementalCellMatricesEqualAFreshAssembly) {
  CachedAndFresh problem;
  const fem::Mesh& mesh = problem.mesh;
  fem::Assembler &fresh = problem.fresh, &incremental = problem.incremental;
  const int n_cells = mesh.n_cells();
  std::vector<double> scale(n_cells, 1.0);
  auto kernel = [&](int e, fem::LocalSystem& l) {
    laplace_kernel(mesh, e, l);
    l.matrix *= scale[e];
  };
  fem::SparseMatrix K_fresh, K;
  Eigen::VectorXd F_fresh, F;
  long scattered = 0, reused = 0;
  for (int round = 0; round < 70; ++round) {
    fem::use_threads(round % 2 + 1);
    int changed = 0;
    if (round > 0)
      for (int e = 0; e < n_cells; ++e)
        if ((e * 7 + round) % 5 == 0) {
          scale[e] = 1.0 + 0.1 * ((e + round) % 11);
          ++changed;
        }
    if (round == 30 || round == 64) {  // a kernel throws halfway (round 64: in a rebuild)
      EXPECT_THROW(incremental.assemble(
                       [&](int e, fem::LocalSystem& l) {
                         if (e == n_cells / 2) throw std::runtime_error("cell is inverted");
                         kernel(e, l);
                       },
                       K, F),
                   std::runtime_error);
      scattered = incremental.cell_matrices_scattered();
      reused = incremental.cell_matrices_reused();
    }
    fresh.assemble(kernel, K_fresh, F_fresh);
    incremental.assemble(kernel, K, F);
    ASSERT_EQ(K.nonZeros(), K_fresh.nonZeros());
    const Eigen::MatrixXd difference = Eigen::MatrixXd(K) - Eigen::MatrixXd(K_fresh);
    EXPECT_LT(difference.norm(), 1e-13 * Eigen::MatrixXd(K_fresh).norm()) << "round " << round;
    EXPECT_EQ((F - F_fresh).norm(), 0.0) << "round " << round;
    // A changed cell is scattered; the others only in the rebuilds (the first assembly
    // and every 64th, which the throw of round 64 interrupted so that it is repeated).
    const long new_scattered = incremental.cell_matrices_scattered() - scattered;
    const long new_reused = incremental.cell_matrices_reused() - reused;
    scattered = incremental.cell_matrices_scattered();
    reused = incremental.cell_matrices_reused();
    EXPECT_EQ(new_scattered + new_reused, n_cells);
    if (round == 0 || round == 64)
      EXPECT_EQ(new_scattered, n_cells) << "round " << round;
    else
      EXPECT_LE(new_scattered, changed) << "round " << round;
  }
  fem::use_threads(1);
  EXPECT_GT(reused, 40L * n_cells);
  // Residual-only assemblies bypass the cache and leave it correct.
  Eigen::VectorXd R;
  fem::SparseMatrix unused;
  incremental.assemble(fem::Assembler::Terms{kernel, {}, {}}, unused, R, false, /*assemble_matrix=*/false);
  scale[0] = 3.0;
  fresh.assemble(kernel, K_fresh, F_fresh);
  incremental.assemble(kernel, K, F);
  EXPECT_LT((Eigen::MatrixXd(K) - Eigen::MatrixXd(K_fresh)).norm(), 1e-13 * Eigen::MatrixXd(K_fresh).norm());
}

// Kept cell matrices: a kernel that says its matrix is the one it returned last
// (LocalSystem::matrix_kept) instead of forming it gives the fresh assembly of the
// formed matrices (to round-off, F exactly), through the rebuilds of the cache (the
// first assembly, every 64th, and the one after a kernel threw), on one thread and
// on two. Kept cells count as reused. An assembler without the cache refuses a kept
// matrix.
TEST(Assembler, KeptCellMatricesEqualAFreshAssembly) {
  CachedAndFresh problem;
  const fem::Mesh& mesh = problem.mesh;
  fem::Assembler &fresh = problem.fresh, &incremental = problem.incremental;
  const int n_cells = mesh.n_cells();
  std::vector<double> scale(n_cells, 1.0), returned(n_cells, 0.0);  // 0: nothing returned yet
  auto formed = [&](int e, fem::LocalSystem& l) {
    laplace_kernel(mesh, e, l);
    l.matrix *= scale[e];
  };
  auto keeping = [&](int e, fem::LocalSystem& l) {
    formed(e, l);
    if (returned[e] == scale[e]) {
      l.matrix.setZero();  // not formed: the assembler must use its own copy
      l.matrix_kept = true;
    }
    returned[e] = scale[e];
  };
  fem::SparseMatrix K_fresh, K;
  Eigen::VectorXd F_fresh, F;
  long kept = 0;
  for (int round = 0; round < 70; ++round) {
    fem::use_threads(round % 2 + 1);
    if (round > 0)
      for (int e = 0; e < n_cells; ++e)
        if ((e * 3 + round) % 4 == 0) scale[e] = 1.0 + 0.1 * ((e + round) % 7);
    if (round == 20 || round == 63) {  // a kernel throws halfway (round 63: before a rebuild)
      EXPECT_THROW(incremental.assemble(
                       [&](int e, fem::LocalSystem& l) {
                         if (e == n_cells / 2) throw std::runtime_error("cell is inverted");
                         keeping(e, l);
                       },
                       K, F),
                   std::runtime_error);
    }
    for (int e = 0; e < n_cells; ++e) kept += returned[e] == scale[e];
    fresh.assemble(formed, K_fresh, F_fresh);
    incremental.assemble(keeping, K, F);
    const Eigen::MatrixXd difference = Eigen::MatrixXd(K) - Eigen::MatrixXd(K_fresh);
    EXPECT_LT(difference.norm(), 1e-13 * Eigen::MatrixXd(K_fresh).norm()) << "round " << round;
    EXPECT_EQ((F - F_fresh).norm(), 0.0) << "round " << round;
  }
  fem::use_threads(1);
  EXPECT_GT(kept, 30L * n_cells);
  EXPECT_GE(incremental.cell_matrices_reused(), kept - 3L * n_cells);  // less the rebuilds' cells
  EXPECT_THROW(fresh.assemble(
                   [&](int e, fem::LocalSystem& l) {
                     formed(e, l);
                     l.matrix_kept = true;
                   },
                   K_fresh, F_fresh),
               std::logic_error);
}

TEST(LinearSolver, CholmodUmfpackAndKluAgreeAndDirichletValuesAreExact) {
  const ConstrainedScalarMesh problem;
  const fem::Mesh& mesh = problem.mesh;
  const fem::DofMap& dofs = problem.dofs;
  const fem::Constraints& c = problem.c;
  fem::Assembler assembler(mesh, dofs, c);
  fem::SparseMatrix K;
  Eigen::VectorXd F;
  assembler.assemble([&](int e, fem::LocalSystem& l) { laplace_kernel(mesh, e, l); }, K, F);
  Eigen::VectorXd x[3];
  int k = 0;
  for (auto kind : {fem::SolverKind::cholmod, fem::SolverKind::umfpack, fem::SolverKind::klu}) {
    fem::LinearSolver solver(kind);
    x[k] = c.distribute(solver.solve(K, F));
    EXPECT_LT((K * c.restrict_to_free(x[k]) - F).norm(), 1e-10 * F.norm()) << fem::to_string(kind);
    ++k;
  }
  EXPECT_LT((x[0] - x[1]).norm(), 1e-10 * x[0].norm());
  EXPECT_LT((x[0] - x[2]).norm(), 1e-10 * x[0].norm());
  for (int node : mesh.boundary_nodes("m.right")) EXPECT_DOUBLE_EQ(x[0][node], 1.0 + mesh.nodes[node].y());
}

TEST(LinearSolver, SingularMatrixIsReported) {
  fem::SparseMatrix A(2, 2);
  A.insert(0, 0) = 1.0;
  A.insert(1, 1) = 0.0;
  A.makeCompressed();
  fem::LinearSolver solver(fem::SolverKind::cholmod);
  EXPECT_THROW(solver.factorize(A), std::runtime_error);
}

// ω = max_i |b − A x|_i / (|A||x| + |b|)_i for A = [[2, 1], [1, 3]], b = (3, 4) and
// x = (1 + δ, 1): r = (−2δ, −δ), |A||x| + |b| = (6 + 2δ, 8 + δ), so ω = 2δ/(6 + 2δ).
// Scaling a row of A and of b by 10¹² leaves ω as it is (the relative residual of
// such a system is dominated by the large rows; see the chain below).
TEST(LinearSolver, BackwardErrorIsOettliPragerAndBlindToRowScaling) {
  const double delta = 1e-3;
  fem::SparseMatrix A(2, 2);
  A.insert(0, 0) = 2;
  A.insert(0, 1) = 1;
  A.insert(1, 0) = 1;
  A.insert(1, 1) = 3;
  A.makeCompressed();
  const Eigen::Vector2d b(3, 4), x(1 + delta, 1);
  EXPECT_NEAR(fem::componentwise_backward_error(A, x, b), 2 * delta / (6 + 2 * delta), 1e-15);
  EXPECT_EQ(fem::componentwise_backward_error(A, Eigen::Vector2d(1, 1), b), 0.0);
  fem::SparseMatrix scaled = A;
  scaled.coeffRef(0, 0) *= 1e12;
  scaled.coeffRef(0, 1) *= 1e12;
  const Eigen::Vector2d b_scaled(3e12, 4);
  EXPECT_NEAR(fem::componentwise_backward_error(scaled, x, b_scaled), 2 * delta / (6 + 2 * delta), 1e-15);
  // |r_i| <= (|A||x| + |b|)_i always, so ω <= 1, with 1 for x = 0 (nothing explained).
  EXPECT_EQ(fem::componentwise_backward_error(A, Eigen::Vector2d::Zero(), b), 1.0);
}

// An unsymmetric, diagonally weighted conduction matrix: a 2D five-point Laplacian of
// n × n nodes with conductivities spanning 10⁶, an upwind-like skew term (share
// `skew` of each downward coupling, as the λ_m blend's tangent adds) and a capacity
// `capacity` times the local conductivity on the diagonal.
fem::SparseMatrix skewed_conduction(int n, double skew, double capacity) {
  auto id = [n](int i, int j) { return i * n + j; };
  auto k = [](int i, int j) { return std::pow(10.0, 6.0 * ((i * 7 + j * 3) % 11) / 10.0); };
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int p = id(i, j);
      double diagonal = capacity * k(i, j);  // capacity / dt
      const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
      for (int m = 0; m < 4; ++m) {
        const int a = i + di[m], b = j + dj[m];
        if (a < 0 || a >= n || b < 0 || b >= n) continue;
        const double c = std::sqrt(k(i, j) * k(a, b));
        diagonal += c;
        t.emplace_back(p, id(a, b), -c + (m == 0 ? skew * c : 0.0));  // unsymmetric part
      }
      t.emplace_back(p, p, diagonal);
    }
  fem::SparseMatrix A(n * n, n * n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

Eigen::VectorXd scaled_sine(const fem::SparseMatrix& A) {
  Eigen::VectorXd b(A.rows());
  for (Eigen::Index p = 0; p < b.size(); ++p) b[p] = std::sin(0.37 * p) * A.coeff(p, p);
  return b;
}

// x solves A x = b to round-off componentwise backward error (below 10⁻¹⁴) and agrees
// with another solver's y to 10⁻¹⁰; prints both figures.
void expect_round_off_solution(const fem::SparseMatrix& A, const Eigen::VectorXd& b, const Eigen::VectorXd& x,
                               const Eigen::VectorXd& y, const char* what, const char* other) {
  const double omega = fem::componentwise_backward_error(A, x, b);
  std::printf("%s: backward error %.3e, difference to %s %.3e\n", what, omega, other, (x - y).norm() / y.norm());
  EXPECT_LT(omega, 1e-14);
  EXPECT_LT((x - y).norm() / y.norm(), 1e-10);
}

// The thermal solver's LU runs without iterative refinement (physics/thermal.cpp): a
// skewed conduction matrix is solved to round-off componentwise backward error by
// UMFPACK's LU alone, and agrees with KLU's solve of the same matrix to 10⁻¹⁰.
TEST(LinearSolver, UmfpackWithoutRefinementIsBackwardStable) {
  const fem::SparseMatrix A = skewed_conduction(40, 0.3, 1e-3);
  const Eigen::VectorXd b = scaled_sine(A);
  fem::LinearSolver umfpack(fem::SolverKind::umfpack), klu(fem::SolverKind::klu);
  umfpack.set_refinement_steps(0);
  const Eigen::VectorXd x = umfpack.solve(A, b), y = klu.solve(A, b);
  expect_round_off_solution(A, b, x, y, "unsymmetric conduction", "KLU");
}

// The thermal tangent changes its values, not its pattern, from one factorisation to
// the next: KLU refactorises with the pivot sequence of the last pivoted
// factorisation. A matrix with other capacities and skew is solved to round-off
// componentwise backward error with the kept pivots, and agrees with a fresh
// factorisation to 10⁻¹⁰.
TEST(LinearSolver, KluRefactorisationKeepsThePivotsAndIsBackwardStable) {
  const fem::SparseMatrix A1 = skewed_conduction(40, 0.3, 1e-3), A2 = skewed_conduction(40, 0.45, 3e-3);
  const Eigen::VectorXd b = scaled_sine(A2);
  fem::LinearSolver kept(fem::SolverKind::klu), fresh(fem::SolverKind::klu);
  kept.factorize(A1);
  EXPECT_FALSE(kept.kept_pivots());
  kept.factorize(A2);
  EXPECT_TRUE(kept.kept_pivots());
  const Eigen::VectorXd x = kept.solve(b), y = fresh.solve(A2, b);
  expect_round_off_solution(A2, b, x, y, "KLU with kept pivots", "a fresh factorisation");
}

// GMRES right-preconditioned with the Cholesky factor of the symmetric part of a
// skewed conduction matrix (whose pattern is symmetric, its values not) reaches a
// relative residual of 10⁻¹² and the direct LU solution to 10⁻¹⁰, in more than one
// iteration (the factor is not the matrix's). With a preconditioner from another
// matrix of the pattern it still converges, judged on the true residual. A matrix
// whose pattern is not symmetric (one entry without its mirror) takes the general
// symmetric part and converges too.
TEST(PreconditionedGmres, SolvesUnsymmetricSystemsWithTheFactorOfASymmetricPart) {
  const fem::SparseMatrix A = skewed_conduction(30, 0.3, 1e-3), A_old = skewed_conduction(30, 0.2, 2e-3);
  const Eigen::VectorXd b = scaled_sine(A);
  fem::LinearSolver lu(fem::SolverKind::umfpack);
  const Eigen::VectorXd exact = lu.solve(A, b);
  fem::PreconditionedGmres gmres;
  Eigen::VectorXd x;
  gmres.set_preconditioner(A);
  const auto fresh = gmres.solve(A, b, x, 1e-12, 100);
  EXPECT_TRUE(fresh.converged);
  EXPECT_GT(fresh.iterations, 1);
  EXPECT_LT((x - exact).norm() / exact.norm(), 1e-10);
  gmres.set_preconditioner(A_old);
  const auto stale = gmres.solve(A, b, x, 1e-12, 100);
  EXPECT_TRUE(stale.converged);
  EXPECT_LE((b - A * x).norm() / b.norm(), 1e-12);
  EXPECT_LT((x - exact).norm() / exact.norm(), 1e-10);
  std::printf("GMRES iterations: fresh symmetric-part factor %d, another matrix's %d\n", fresh.iterations,
              stale.iterations);

  // The same values with an explicit zero at (0, 29) and none at (29, 0): the general
  // path forms the same symmetric part, so the same iterations and solution.
  fem::SparseMatrix Z = A;
  Z.coeffRef(0, 29) = 0.0;
  Z.makeCompressed();
  const Eigen::VectorXd x_fresh = [&] {
    gmres.set_preconditioner(A);
    Eigen::VectorXd y;
    gmres.solve(A, b, y, 1e-12, 100);
    return y;
  }();
  gmres.set_preconditioner(Z);
  const auto zero = gmres.solve(Z, b, x, 1e-12, 100);
  EXPECT_EQ(zero.iterations, fresh.iterations);
  EXPECT_LT((x - x_fresh).norm() / x_fresh.norm(), 1e-13);

  fem::SparseMatrix B = A;
  B.coeffRef(0, 29) = -1e-3 * B.coeff(0, 0);  // no entry (29, 0): the pattern is not symmetric
  B.makeCompressed();
  const Eigen::VectorXd exact_B = lu.solve(B, b);
  gmres.set_preconditioner(B);
  const auto general = gmres.solve(B, b, x, 1e-12, 100);
  EXPECT_TRUE(general.converged);
  EXPECT_LT((x - exact_B).norm() / exact_B.norm(), 1e-10);

  // The same with a supernodal factor, which reads the other triangle: B's
  // preconditioner is that of B with the missing entry (29, 0) stored as zero.
  fem::PreconditionedGmres supernodal;
  supernodal.set_supernodal(true);
  supernodal.set_single_precision(false);
  fem::SparseMatrix B_full = B;
  B_full.coeffRef(29, 0) = 0.0;
  B_full.makeCompressed();
  Eigen::VectorXd y_general, y_full;
  supernodal.set_preconditioner(B);
  const auto upper_general = supernodal.solve(B, b, y_general, 1e-12, 100);
  supernodal.set_preconditioner(B_full);
  const auto upper_full = supernodal.solve(B, b, y_full, 1e-12, 100);
  EXPECT_TRUE(upper_general.converged);
  EXPECT_EQ(upper_general.iterations, upper_full.iterations);
  EXPECT_LT((y_general - exact_B).norm() / exact_B.norm(), 1e-10);
  EXPECT_LT((y_general - y_full).norm() / y_full.norm(), 1e-13);
}

// Started from a nearby solution, GMRES solves for the correction to the same
// absolute residual: the result meets the tolerance against the exact solution in
// fewer iterations; a start that meets the tolerance already costs none and is kept;
// a start that is not finite, or of another size, is ignored (GMRES starts from 0).
TEST(PreconditionedGmres, StartFromANearbySolutionSolvesForTheCorrection) {
  const fem::SparseMatrix A = skewed_conduction(30, 0.3, 1e-3), A_near = skewed_conduction(30, 0.3, 1.001e-3);
  const Eigen::VectorXd b = scaled_sine(A);
  fem::LinearSolver lu(fem::SolverKind::umfpack);
  const Eigen::VectorXd exact = lu.solve(A, b);
  fem::PreconditionedGmres gmres;
  gmres.set_preconditioner(skewed_conduction(30, 0.2, 2e-3));  // another matrix's factor
  Eigen::VectorXd cold;
  const auto from_zero = gmres.solve(A, b, cold, 1e-10, 100);
  ASSERT_TRUE(from_zero.converged);

  Eigen::VectorXd warm = lu.solve(A_near, b);  // the solution of a nearby matrix
  const double start_residual = (b - A * warm).norm() / b.norm();
  ASSERT_GT(start_residual, 1e-8);
  const auto from_near = gmres.solve(A, b, warm, 1e-10, 100, /*from_x=*/true);
  EXPECT_TRUE(from_near.converged);
  EXPECT_LE((b - A * warm).norm() / b.norm(), 1e-10);
  EXPECT_LT((warm - exact).norm() / exact.norm(), 1e-8);
  EXPECT_LT(from_near.iterations, from_zero.iterations);
  std::printf("GMRES iterations from 0: %d; from a solution with relative residual %.1e: %d\n", from_zero.iterations,
              start_residual, from_near.iterations);

  Eigen::VectorXd converged = exact;
  const auto none = gmres.solve(A, b, converged, 1e-10, 100, /*from_x=*/true);
  EXPECT_TRUE(none.converged);
  EXPECT_EQ(none.iterations, 0);
  EXPECT_EQ(converged, exact);

  Eigen::VectorXd not_finite = exact;
  not_finite[3] = std::nan("");
  const auto restarted = gmres.solve(A, b, not_finite, 1e-10, 100, /*from_x=*/true);
  EXPECT_EQ(restarted.iterations, from_zero.iterations);
  EXPECT_EQ(not_finite, cold);
  Eigen::VectorXd short_start = Eigen::VectorXd::Ones(5);
  EXPECT_EQ(gmres.solve(A, b, short_start, 1e-10, 100, /*from_x=*/true).iterations, from_zero.iterations);
}

// A 3D seven-point conduction matrix of n³ nodes, conductivities spanning 10³ and the
// share `skew` of each coupling in x added unsymmetrically: its Cholesky factor fills
// in enough for CHOLMOD to factorise supernodally, like the mechanics tangent.
fem::SparseMatrix skewed_conduction_3d(int n, double skew) {
  auto id = [n](int i, int j, int k) { return (i * n + j) * n + k; };
  auto c = [](int i, int j, int k) { return std::pow(10.0, 3.0 * ((i * 5 + j * 3 + k) % 7) / 6.0); };
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const int p = id(i, j, k);
        double diagonal = 1e-3 * c(i, j, k);
        const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (int m = 0; m < 6; ++m) {
          const int a = i + d[m][0], b = j + d[m][1], e = k + d[m][2];
          if (a < 0 || a >= n || b < 0 || b >= n || e < 0 || e >= n) continue;
          const double g = std::sqrt(c(i, j, k) * c(a, b, e));
          diagonal += g;
          t.emplace_back(p, id(a, b, e), -g + (m == 0 ? skew * g : 0.0));
        }
        t.emplace_back(p, p, diagonal);
      }
  fem::SparseMatrix A(n * n * n, n * n * n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}


// A supernodal symmetric-part factor is applied in single precision: GMRES with it
// reaches a relative residual of 10⁻¹² and the direct LU solution to 10⁻¹⁰, as with
// the double-precision factor, in at most three more iterations. On the symmetric
// matrix itself each iteration gains about the float round-off, so two or three
// iterations reach 10⁻¹² (a wrong factor copy would not converge at all); where a
// fresh float factor cannot converge within the allowed iterations, the refreshing
// solve repeats with the double factor. A scalar 2D conduction matrix, factorised
// column by column, stays in double precision, unless supernodal factors are asked
// for (set_supernodal).
TEST(PreconditionedGmres, SinglePrecisionFactorGivesTheDoublePrecisionSolution) {
  const fem::SparseMatrix A = skewed_conduction_3d(16, 0.2), S = skewed_conduction_3d(16, 0.0);
  const Eigen::VectorXd b = scaled_sine(A);
  fem::LinearSolver lu(fem::SolverKind::umfpack);
  const Eigen::VectorXd exact = lu.solve(A, b);
  fem::PreconditionedGmres single, full;
  full.set_single_precision(false);
  single.set_preconditioner(A);
  full.set_preconditioner(A);
  ASSERT_TRUE(single.single_precision_active());
  EXPECT_FALSE(full.single_precision_active());
  Eigen::VectorXd x, y;
  const auto in_float = single.solve(A, b, x, 1e-12, 100), in_double = full.solve(A, b, y, 1e-12, 100);
  EXPECT_TRUE(in_float.converged);
  EXPECT_TRUE(in_double.converged);
  EXPECT_LT((x - exact).norm() / exact.norm(), 1e-10);
  EXPECT_LT((y - exact).norm() / exact.norm(), 1e-10);
  EXPECT_LE(in_float.iterations, in_double.iterations + 3);

  single.set_preconditioner(S);
  full.set_preconditioner(S);
  const Eigen::VectorXd c = scaled_sine(S);
  const auto own_float = single.solve(S, c, x, 1e-12, 100), own_double = full.solve(S, c, y, 1e-12, 100);
  EXPECT_TRUE(own_float.converged);
  EXPECT_LE(own_float.iterations, 3);
  EXPECT_EQ(own_double.iterations, 1);
  EXPECT_LT((x - y).norm() / y.norm(), 1e-11);
  std::printf("GMRES iterations, float / double factor: unsymmetric %d / %d, symmetric %d / %d\n",
              in_float.iterations, in_double.iterations, own_float.iterations, own_double.iterations);

  // One iteration allowed: a float factor gains at most about float's round-off
  // (6·10⁻⁸) per iteration, so it needs two or three for 10⁻¹², and the refreshing
  // solve falls back to the double factor of the fresh factorisation, which needs one.
  fem::PreconditionedGmres fallback;
  Eigen::VectorXd u;
  const auto rescued = fallback.solve_refreshing(S, c, u, 1e-12, 10, 1);
  EXPECT_TRUE(rescued.converged);
  EXPECT_EQ(rescued.iterations, 1);
  EXPECT_FALSE(fallback.single_precision_active());
  EXPECT_LT((u - y).norm() / y.norm(), 1e-11);

  const fem::SparseMatrix P = skewed_conduction(30, 0.3, 1e-3);
  single.set_preconditioner(P);
  EXPECT_FALSE(single.single_precision_active());
  // Asked to factorise supernodally, it does so, and applies the factor in float.
  single.set_supernodal(true);
  single.set_preconditioner(P);
  EXPECT_TRUE(single.single_precision_active());
  const Eigen::VectorXd d = scaled_sine(P);
  const Eigen::VectorXd direct = lu.solve(P, d);
  EXPECT_TRUE(single.solve(P, d, x, 1e-12, 100).converged);
  EXPECT_LT((x - direct).norm() / direct.norm(), 1e-10);
}

// A positive definite 3D conduction matrix K (factorised supernodally, like the
// mechanics tangent, where CHOLMOD detects an indefinite matrix) plus four large
// one-sided couplings C between neighbours (the shape of a sliding friction point's
// μ k_n t nᵀ): each c is four times the geometric mean of its two diagonal entries, so
// the symmetric part of A = K + C is indefinite and, without a surrogate, the
// preconditioner is A's LU. With the surrogate K the preconditioner is K's Cholesky
// factor (in single precision), and GMRES on A reaches the LU solution to 10⁻¹⁰ in
// at most four iterations more than the rank of C. A surrogate that is itself
// indefinite (A) falls back to the LU.
TEST(PreconditionedGmres, SurrogateWithPositiveDefiniteSymmetricPartReplacesTheLu) {
  const fem::SparseMatrix K = skewed_conduction_3d(16, 0.0);
  fem::SparseMatrix A = K;
  const int couplings[] = {100, 1000, 2000, 3000};  // p couples to p + 1, its neighbour in k
  for (const int p : couplings) {
    const double c = 4.0 * std::sqrt(K.coeff(p, p) * K.coeff(p + 1, p + 1));
    A.coeffRef(p, p + 1) += c;  // an entry of the pattern: no new nonzero
  }
  ASSERT_EQ(A.nonZeros(), K.nonZeros());
  const Eigen::VectorXd b = scaled_sine(A);
  fem::LinearSolver lu(fem::SolverKind::umfpack);
  const Eigen::VectorXd exact = lu.solve(A, b);

  fem::PreconditionedGmres plain;
  plain.set_preconditioner(A);
  EXPECT_EQ(plain.n_full_factorizations(), 1);

  fem::PreconditionedGmres with_surrogate;
  int formed = 0;
  Eigen::VectorXd x;
  const auto report = with_surrogate.solve_refreshing(A, b, x, 1e-12, 10, 100, [&]() -> const fem::SparseMatrix& {
    ++formed;
    return K;
  });
  EXPECT_EQ(formed, 1);
  EXPECT_EQ(with_surrogate.n_surrogates(), 1);
  EXPECT_EQ(with_surrogate.n_full_factorizations(), 0);
  EXPECT_TRUE(with_surrogate.single_precision_active());
  EXPECT_TRUE(report.converged);
  EXPECT_LE(report.iterations, 4 + 4);
  EXPECT_LT((x - exact).norm() / exact.norm(), 1e-10);
  std::printf("surrogate preconditioner: %d GMRES iterations, difference to LU %.2e\n", report.iterations,
              (x - exact).norm() / exact.norm());

  fem::PreconditionedGmres indefinite;
  indefinite.set_preconditioner(A, [&]() -> const fem::SparseMatrix& { return A; });
  EXPECT_EQ(indefinite.n_surrogates(), 1);
  EXPECT_EQ(indefinite.n_full_factorizations(), 1);
}

// Kept pivots that no longer work are dropped: [[1, 1], [1, 2]] pivots on its
// diagonal; [[0, 1], [1, 2]] has a zero there, so KLU pivots afresh (rows swapped) and
// solves [[0, 1], [1, 2]] x = (1, 3) exactly: x = (1, 1).
TEST(LinearSolver, KluPivotsAfreshWhereTheKeptPivotsFail) {
  fem::SparseMatrix A(2, 2);
  A.insert(0, 0) = 1;
  A.insert(0, 1) = 1;
  A.insert(1, 0) = 1;
  A.insert(1, 1) = 2;
  A.makeCompressed();
  fem::LinearSolver solver(fem::SolverKind::klu);
  solver.factorize(A);
  A.coeffRef(0, 0) = 0;
  solver.factorize(A);
  EXPECT_FALSE(solver.kept_pivots());
  const Eigen::VectorXd x = solver.solve(Eigen::Vector2d(1, 3));
  EXPECT_NEAR(x[0], 1.0, 1e-15);
  EXPECT_NEAR(x[1], 1.0, 1e-15);
  // A singular matrix of the same pattern is reported, not solved.
  A.coeffRef(1, 0) = 0;
  EXPECT_THROW(solver.factorize(A), std::runtime_error);
}

// A chain of n conductors alternating 10¹⁴ and 1 S, grounded at one end, with 1 A
// into the other: entries spanning 10¹⁴. CHOLMOD's solution is the closed form to
// round-off, yet its relative residual |b − A x|/|b| is of order 1 (the rounding of
// φ ≈ 100 V in rows of 10¹⁴ S); its componentwise backward error is round-off
// (Cholesky is backward stable). That is why the electrical solve judges a stalled
// GMRES by the backward error.
TEST(LinearSolver, DirectSolveOfWildlyScaledChainHasRoundOffBackwardError) {
  const int n = 200;
  std::vector<Eigen::Triplet<double>> t;
  auto g = [](int k) { return k % 2 == 0 ? 1e14 : 1.0; };  // conductor k joins nodes k−1 and k
  for (int k = 0; k < n; ++k) {
    // node k (unknown) sits between conductor k (to node k−1, node −1 grounded) and k+1
    t.emplace_back(k, k, g(k) + (k + 1 < n ? g(k + 1) : 0.0));
    if (k + 1 < n) {
      t.emplace_back(k, k + 1, -g(k + 1));
      t.emplace_back(k + 1, k, -g(k + 1));
    }
  }
  fem::SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  b[n - 1] = 1.0;
  fem::LinearSolver solver(fem::SolverKind::cholmod);
  const Eigen::VectorXd x = solver.solve(A, b);
  // Closed form: the current 1 A flows through every conductor, so φ_k = Σ_{j≤k} 1/g(j).
  double phi = 0, worst = 0;
  for (int k = 0; k < n; ++k) {
    phi += 1 / g(k);
    worst = std::max(worst, std::abs(x[k] - phi) / phi);
  }
  const double omega = fem::componentwise_backward_error(A, x, b);
  std::printf("chain: relative residual %.3e, backward error %.3e, worst relative error of phi %.3e\n",
              (b - A * x).norm() / b.norm(), omega, worst);
  EXPECT_LT(omega, 1e-14);
  EXPECT_LT(worst, 1e-12);
  EXPECT_GT((b - A * x).norm() / b.norm(), 1e-6);
}


// An assembled contact pattern holds couplings that are never used (exact zeros).
// A symmetric positive definite conduction matrix with 40 such zero couplings
// between distant nodes (and their mirrors) is factorised on the pattern of its
// nonzero entries: each solver's solution equals that of the matrix without them
// bit for bit (the same matrix is factorised) after one analysis, and new values of
// the same nonzeros need none. A coupling that becomes nonzero (c between nodes p and
// q, with c added to both diagonals) is taken in by a second analysis, and the
// solution is that of a fresh solver to 10⁻¹²; when it returns to zero it stays in
// the factorised pattern (no third analysis) and the solution is still exact.
TEST(LinearSolver, FactorisesOnlyTheEntriesThatWereEverNonzero) {
  const int n = 30;
  const fem::SparseMatrix plain = skewed_conduction(n, 0.0, 1e-3);
  std::vector<Eigen::Triplet<double>> t;
  for (int k = 0; k < plain.outerSize(); ++k)
    for (fem::SparseMatrix::InnerIterator it(plain, k); it; ++it) t.emplace_back(it.row(), it.col(), it.value());
  std::vector<std::pair<int, int>> unused;
  for (int k = 0; k < 40; ++k) unused.push_back({k * 7, n * n - 1 - k * 11});
  for (const auto& [p, q] : unused) {
    t.emplace_back(p, q, 0.0);
    t.emplace_back(q, p, 0.0);
  }
  fem::SparseMatrix padded(n * n, n * n);
  padded.setFromTriplets(t.begin(), t.end());
  ASSERT_EQ(padded.nonZeros(), plain.nonZeros() + 80);
  const Eigen::VectorXd b = scaled_sine(plain);
  for (auto kind : {fem::SolverKind::cholmod, fem::SolverKind::umfpack, fem::SolverKind::klu}) {
    fem::LinearSolver solver(kind), reference(kind);
    EXPECT_EQ(solver.solve(padded, b), reference.solve(plain, b)) << fem::to_string(kind);
    EXPECT_EQ(solver.n_analyses(), 1) << fem::to_string(kind);
    fem::SparseMatrix scaled = 2.0 * padded;
    EXPECT_EQ(solver.solve(scaled, b), reference.solve(2.0 * plain, b)) << fem::to_string(kind);
    EXPECT_EQ(solver.n_analyses(), 1) << fem::to_string(kind);

    const auto [p, q] = unused[5];
    fem::SparseMatrix coupled = padded;
    const double c = coupled.coeff(p, p);
    coupled.coeffRef(p, q) = coupled.coeffRef(q, p) = -c;
    coupled.coeffRef(p, p) += c;
    coupled.coeffRef(q, q) += c;
    ASSERT_EQ(coupled.nonZeros(), padded.nonZeros());
    fem::LinearSolver fresh(kind);
    const Eigen::VectorXd x = solver.solve(coupled, b), y = fresh.solve(coupled, b);
    EXPECT_EQ(solver.n_analyses(), 2) << fem::to_string(kind);
    EXPECT_LT((x - y).norm(), 1e-12 * y.norm()) << fem::to_string(kind);
    EXPECT_GT((x - reference.solve(plain, b)).norm(), 1e-6 * y.norm()) << "the coupling changes the solution";
    const Eigen::VectorXd z = solver.solve(padded, b), w = reference.solve(plain, b);
    EXPECT_EQ(solver.n_analyses(), 2) << fem::to_string(kind);
    EXPECT_LT((z - w).norm(), 1e-12 * w.norm()) << fem::to_string(kind);
  }
}
