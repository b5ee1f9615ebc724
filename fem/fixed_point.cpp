// Anderson-accelerated fixed-point iteration through KINSOL; see fixed_point.hpp.
#include "fem/fixed_point.hpp"

#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace rsw::fem {

namespace {

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
  if (!data->u.allFinite()) {
    data->failure = "the accelerated iterate is not finite";
    return -1;
  }
  bool ok = false;
  try {
    ok = (*data->G)(data->u, data->g);
  } catch (const std::exception& e) {
    data->failure = e.what();
    return -1;
  }
  if (!ok) {
    if (data->failure.empty()) data->failure = "the map could not be evaluated";
    return -1;
  }
  if (data->g.size() != data->n || !data->g.allFinite()) {
    data->failure = "the map returned a vector of the wrong size or with non-finite entries";
    return -1;
  }
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

}  // namespace rsw::fem
