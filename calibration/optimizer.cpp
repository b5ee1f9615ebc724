// NLopt wrapper; see optimizer.hpp.
#include "calibration/optimizer.hpp"

#include <nlopt.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace rsw::calibration {

namespace {

// Value returned to BOBYQA for a failed evaluation: large but finite, so the
// quadratic model stays defined and the method moves away.
constexpr double kPenalty = 1e100;

struct EvaluationContext {
  const ObjectiveFunction* objective = nullptr;
  bool with_gradient = false;
  int n_evaluations = 0;
  Eigen::VectorXd best_x;
  double best_value = std::numeric_limits<double>::infinity();
  bool found = false;
};

double evaluate(unsigned n, const double* x, double* gradient, void* data) {
  auto* context = static_cast<EvaluationContext*>(data);
  ++context->n_evaluations;
  const Eigen::Map<const Eigen::VectorXd> point(x, n);
  Eigen::VectorXd g;
  double value = std::numeric_limits<double>::quiet_NaN();
  try {
    value = (*context->objective)(point, gradient != nullptr ? &g : nullptr);
  } catch (const std::exception&) {
    value = std::numeric_limits<double>::quiet_NaN();
  }
  const bool finite = std::isfinite(value) &&
                      (gradient == nullptr || (g.size() == static_cast<Eigen::Index>(n) && g.allFinite()));
  if (!finite) {
    // L-BFGS cannot step through a hole in the objective: stop it, the caller falls
    // back to BOBYQA from the best point so far.
    if (context->with_gradient) throw nlopt::forced_stop();
    return kPenalty;
  }
  if (value < context->best_value) {
    context->best_value = value;
    context->best_x = point;
    context->found = true;
  }
  if (gradient != nullptr) Eigen::Map<Eigen::VectorXd>(gradient, n) = g;
  return value;
}

std::string status_text(nlopt::result status) {
  switch (status) {
    case nlopt::SUCCESS: return "success";
    case nlopt::STOPVAL_REACHED: return "stop value reached";
    case nlopt::FTOL_REACHED: return "relative f tolerance reached";
    case nlopt::XTOL_REACHED: return "relative x tolerance reached";
    case nlopt::MAXEVAL_REACHED: return "evaluation limit reached";
    case nlopt::MAXTIME_REACHED: return "time limit reached";
    default: return "stopped with status " + std::to_string(static_cast<int>(status));
  }
}

// One local run of `algorithm` from x0; returns a description of how it stopped.
std::string local_run(nlopt::algorithm algorithm, const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
                      const Eigen::VectorXd& upper, const OptimizerOptions& options, EvaluationContext& context,
                      bool& failed) {
  const auto n = static_cast<unsigned>(x0.size());
  nlopt::opt opt(algorithm, n);
  opt.set_lower_bounds(std::vector<double>(lower.data(), lower.data() + n));
  opt.set_upper_bounds(std::vector<double>(upper.data(), upper.data() + n));
  opt.set_min_objective(&evaluate, &context);
  opt.set_xtol_rel(options.relative_tolerance_x);
  opt.set_ftol_rel(options.relative_tolerance_f);
  opt.set_maxeval(options.max_evaluations_per_start);
  std::vector<double> x(x0.data(), x0.data() + n);
  double value = 0.0;
  failed = false;
  try {
    return status_text(opt.optimize(x, value));
  } catch (const nlopt::roundoff_limited&) {
    failed = true;
    return "round-off limited";
  } catch (const nlopt::forced_stop&) {
    failed = true;
    return "non-finite objective";
  } catch (const std::runtime_error& error) {
    failed = true;
    return std::string("NLopt failure: ") + error.what();
  }
}

}  // namespace

BoundedMinimizer::BoundedMinimizer(ObjectiveFunction objective, Eigen::VectorXd lower, Eigen::VectorXd upper,
                                   OptimizerOptions options)
    : objective_(std::move(objective)), lower_(std::move(lower)), upper_(std::move(upper)), options_(options) {
  if (lower_.size() == 0 || lower_.size() != upper_.size())
    throw std::invalid_argument("BoundedMinimizer: lower and upper bounds must be non-empty and of equal size");
  if ((lower_.array() > upper_.array()).any())
    throw std::invalid_argument("BoundedMinimizer: a lower bound exceeds its upper bound");
}

OptimizerResult BoundedMinimizer::run(const std::vector<Eigen::VectorXd>& starts) const {
  if (starts.empty()) throw std::invalid_argument("BoundedMinimizer::run: no start points");
  // BOBYQA needs at least two variables; COBYLA is the derivative-free method for one.
  const nlopt::algorithm derivative_free = lower_.size() >= 2 ? nlopt::LN_BOBYQA : nlopt::LN_COBYLA;
  OptimizerResult result;
  result.value = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < starts.size(); ++i) {
    if (starts[i].size() != lower_.size()) throw std::invalid_argument("BoundedMinimizer::run: start has wrong size");
    const Eigen::VectorXd x0 = starts[i].cwiseMax(lower_).cwiseMin(upper_);
    EvaluationContext context;
    context.objective = &objective_;
    bool failed = false;
    std::string message;
    if (options_.method == OptimizerMethod::Lbfgs) {
      context.with_gradient = true;
      message = local_run(nlopt::LD_LBFGS, x0, lower_, upper_, options_, context, failed);
      if (failed && options_.derivative_free_fallback) {
        ++result.n_fallbacks;
        context.with_gradient = false;
        const Eigen::VectorXd restart = context.found ? context.best_x : x0;
        message = "L-BFGS " + message + "; BOBYQA " +
                  local_run(derivative_free, restart, lower_, upper_, options_, context, failed);
      }
    } else {
      message = local_run(derivative_free, x0, lower_, upper_, options_, context, failed);
    }
    result.n_evaluations += context.n_evaluations;
    if (context.found && context.best_value < result.value) {
      result.value = context.best_value;
      result.x = context.best_x;
      result.found = true;
      result.best_start = static_cast<int>(i);
      result.message = message;
    }
  }
  if (!result.found) result.message = "no start produced a finite objective value";
  return result;
}

}  // namespace rsw::calibration
