// Anderson-accelerated fixed-point iteration through KINSOL; see fixed_point.hpp.
#include "fem/fixed_point.hpp"

#include <kinsol/kinsol.h>
#include <kinsol/kinsol_ls.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_spfgmr.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace rsw::fem {

namespace {

// g = G(u) for a finite u; false, with the reason in `failure`, where u is not finite,
// G fails or throws, or returns a vector of the wrong size or with non-finite entries.
bool call_map(const FixedPointMap& G, const Eigen::VectorXd& u, Eigen::VectorXd& g, std::string& failure,
              const char* iterate) {
  if (!u.allFinite()) {
    failure = std::string("the ") + iterate + " is not finite";
    return false;
  }
  bool ok = false;
  try {
    ok = G(u, g);
  } catch (const std::exception& e) {
    failure = e.what();
    return false;
  }
  if (!ok) {
    if (failure.empty()) failure = "the map could not be evaluated";
    return false;
  }
  if (g.size() != u.size() || !g.allFinite()) {
    failure = "the map returned a vector of the wrong size or with non-finite entries";
    return false;
  }
  return true;
}

struct CallbackData {
  const FixedPointMap* G = nullptr;
  long n = 0;
  Eigen::VectorXd u, g;
  std::string failure;
  // The contraction estimate (settings.estimate_error): the last changes and whether
  // it ended the iteration (the callback then stops KINSOL by returning an error).
  bool estimate_error = false;
  double tolerance = 0;
  std::vector<double> changes;
  bool estimated_converged = false;
};

int evaluate(N_Vector u, N_Vector g, void* user_data) {
  auto* data = static_cast<CallbackData*>(user_data);
  data->u = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer_Serial(u), data->n);
  if (!call_map(*data->G, data->u, data->g, data->failure, "accelerated iterate")) return -1;
  std::copy(data->g.data(), data->g.data() + data->n, N_VGetArrayPointer_Serial(g));
  if (data->estimate_error) {
    auto& c = data->changes;
    c.push_back((data->g - data->u).lpNorm<Eigen::Infinity>());
    const std::size_t k = c.size() - 1;
    if (k >= 2 && c[k - 1] > 0 && c[k - 2] > 0) {
      const double theta = c[k] / c[k - 1], theta_before = c[k - 1] / c[k - 2];
      if (c[k] > data->tolerance && theta <= 0.5 && theta_before <= 0.5 &&
          theta * c[k] / (1 - theta) <= data->tolerance) {
        data->estimated_converged = true;
        return -1;  // stops KINSOL; reported as converged below
      }
    }
  }
  return 0;
}

void silent(int, const char*, const char*, char*, void*) {}

// Newton–Krylov: F(u) = G(u) − u, with an evaluation budget.
struct NewtonData {
  const FixedPointMap* G = nullptr;
  long n = 0;
  int budget = 0, evaluations = 0;
  Eigen::VectorXd u, g;
  std::string failure;
};

int residual(N_Vector u, N_Vector f, void* user_data) {
  auto* data = static_cast<NewtonData*>(user_data);
  if (data->evaluations >= data->budget) {
    data->failure = "no convergence in " + std::to_string(data->budget) + " evaluations";
    return -1;
  }
  ++data->evaluations;
  data->u = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer_Serial(u), data->n);
  if (!call_map(*data->G, data->u, data->g, data->failure, "Newton iterate")) return -1;
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer_Serial(f), data->n) = data->g - data->u;
  return 0;
}

struct Context {
  SUNContext ctx = nullptr;
  Context() { SUNContext_Create(nullptr, &ctx); }
  ~Context() { SUNContext_Free(&ctx); }
};

}  // namespace

FixedPointReport solve_fixed_point(const FixedPointMap& G, Eigen::VectorXd& u, const FixedPointSettings& settings) {
  FixedPointReport report;
  const long n = static_cast<long>(u.size());
  if (n == 0) {
    report.converged = true;
    return report;
  }
  Context context;
  CallbackData data;
  data.G = &G;
  data.n = n;
  data.estimate_error = settings.estimate_error;
  data.tolerance = settings.tolerance;

  N_Vector uu = N_VNew_Serial(n, context.ctx);
  N_Vector scale = N_VNew_Serial(n, context.ctx);
  std::copy(u.data(), u.data() + n, N_VGetArrayPointer_Serial(uu));
  N_VConst(1.0, scale);
  void* kin = KINCreate(context.ctx);
  // Anderson depth: at most the number of unknowns, and set before KINInit (which
  // allocates the acceleration workspace).
  KINSetMAA(kin, std::min<long>(std::max(settings.depth, 0), n));
  KINInit(kin, evaluate, uu);
  KINSetUserData(kin, &data);
  KINSetNumMaxIters(kin, std::max(settings.max_iterations, 1));
  KINSetFuncNormTol(kin, settings.tolerance);
  KINSetErrHandlerFn(kin, silent, nullptr);
  KINSetPrintLevel(kin, 0);
  const double beta = std::clamp(settings.damping, 1e-3, 1.0);
  if (beta < 1.0) {
    KINSetDamping(kin, beta);    // plain iteration (depth 0)
    KINSetDampingAA(kin, beta);  // Anderson
  }

  const int flag = KINSol(kin, uu, KIN_FP, scale, scale);
  long iterations = 0;
  double change = 0;
  KINGetNumNonlinSolvIters(kin, &iterations);
  KINGetFuncNorm(kin, &change);
  report.iterations = static_cast<int>(iterations);
  report.change = change;
  report.converged = flag == KIN_SUCCESS || data.estimated_converged;
  if (data.estimated_converged) {
    // KINSOL counts the stopping evaluation as failed; it is the last one made.
    report.iterations = static_cast<int>(data.changes.size());
    report.change = data.changes.back();
    report.estimated = true;
  }
  if (!report.converged) {
    if (flag == KIN_MAXITER_REACHED)
      report.message = "no convergence in " + std::to_string(settings.max_iterations) + " iterations";
    else if (flag == KIN_SYSFUNC_FAIL)
      report.message = data.failure.empty() ? "the map failed" : data.failure;
    else
      report.message = "KINSOL error " + std::to_string(flag);
  }
  // The last point G was evaluated at (KINSOL keeps it in uu unless it went on).
  if (data.u.size() == n) u = data.u;
  KINFree(&kin);
  N_VDestroy(uu);
  N_VDestroy(scale);
  return report;
}

FixedPointReport solve_fixed_point_newton(const FixedPointMap& G, Eigen::VectorXd& u,
                                          const NewtonKrylovSettings& settings) {
  FixedPointReport report;
  const long n = static_cast<long>(u.size());
  if (n == 0) {
    report.converged = true;
    return report;
  }
  Context context;
  NewtonData data;
  data.G = &G;
  data.n = n;
  data.budget = std::max(settings.max_evaluations - 1, 1);  // and the final check
  N_Vector uu = N_VNew_Serial(n, context.ctx);
  N_Vector scale = N_VNew_Serial(n, context.ctx);
  std::copy(u.data(), u.data() + n, N_VGetArrayPointer_Serial(uu));
  N_VConst(1.0, scale);
  SUNLinearSolver ls = SUNLinSol_SPFGMR(uu, SUN_PREC_NONE, std::max(settings.max_krylov, 1), context.ctx);
  void* kin = KINCreate(context.ctx);
  KINInit(kin, residual, uu);
  KINSetUserData(kin, &data);
  KINSetLinearSolver(kin, ls, nullptr);
  KINSetNumMaxIters(kin, data.budget);
  KINSetFuncNormTol(kin, settings.tolerance);
  KINSetScaledStepTol(kin, 1e-3 * settings.tolerance);
  KINSetRelErrFunc(kin, settings.relative_error);
  // KINSOL's default longest step, 1000 |u_0|₂, is none from u_0 = 0.
  KINSetMaxNewtonStep(kin, 1000 * std::max(u.norm(), 1.0));
  KINSetEtaForm(kin, KIN_ETACONSTANT);
  KINSetEtaConstValue(kin, settings.linear_tolerance);
  KINSetErrHandlerFn(kin, silent, nullptr);
  KINSetPrintLevel(kin, 0);
  const int flag = KINSol(kin, uu, KIN_LINESEARCH, scale, scale);
  KINFree(&kin);
  SUNLinSolFree(ls);
  // KINSOL's last evaluation may be a difference quotient or a rejected line-search
  // point: G is evaluated once more at the iterate it returns, so that the caller's
  // state belongs to it, and the test is made there.
  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer_Serial(uu), n);
  N_VDestroy(uu);
  N_VDestroy(scale);
  const bool usable = flag >= 0 || flag == KIN_LINESEARCH_NONCONV || flag == KIN_MAXITER_REACHED;
  if (usable && data.failure.empty() && x.allFinite()) {
    u = x;
    Eigen::VectorXd g;
    ++data.evaluations;
    if (call_map(G, x, g, data.failure, "Newton iterate")) {
      report.change = (g - x).lpNorm<Eigen::Infinity>();
      report.converged = report.change <= settings.tolerance;
    }
  } else if (data.u.size() == n) {
    u = data.u;
  }
  report.iterations = data.evaluations;
  if (!report.converged)
    report.message = !data.failure.empty() ? data.failure
                     : flag < 0            ? "KINSOL error " + std::to_string(flag)
                                           : "the change at KINSOL's solution is above the tolerance";
  return report;
}

}  // namespace rsw::fem
