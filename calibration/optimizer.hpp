// Bounded minimisation: the one wrapper around NLopt in rsw.
//
// Minimises f(x) over the box lower ≤ x ≤ upper from each of several given start
// points and returns the best point found. With a gradient the method is L-BFGS
// (NLopt LD_LBFGS, Liu & Nocedal 1989); when a gradient-based run stops with an
// error (round-off limited, non-finite values, line-search failure) the same start is
// continued derivative-free with BOBYQA (NLopt LN_BOBYQA, Powell 2009). Without a
// gradient, BOBYQA is used throughout. The objective may return a non-finite value
// (e.g. a failed Cholesky factorisation in a trial point); such points are treated as
// +∞ and never returned. The best finite point seen over all evaluations of all starts
// is the result, so an early NLopt stop never loses a good point. Deterministic:
// starts are run in the order given.
#pragma once

#include <Eigen/Core>

#include <functional>
#include <string>
#include <vector>

namespace rsw::calibration {

// f(x); when gradient != nullptr it must also be filled with ∂f/∂x (same size as x).
using ObjectiveFunction = std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd* gradient)>;

enum class OptimizerMethod {
  Lbfgs,           // gradient-based, with derivative-free fallback per start
  DerivativeFree,  // BOBYQA only; the objective is never asked for a gradient
};

struct OptimizerOptions {
  OptimizerMethod method = OptimizerMethod::Lbfgs;
  int max_evaluations_per_start = 300;
  double relative_tolerance_x = 1e-8;
  double relative_tolerance_f = 1e-10;
  bool derivative_free_fallback = true;  // only used with Lbfgs
};

struct OptimizerResult {
  Eigen::VectorXd x;        // best point found (inside the bounds)
  double value = 0.0;       // f(x)
  bool found = false;       // false if no evaluation returned a finite value
  int best_start = -1;      // index of the start that produced x
  int n_evaluations = 0;    // over all starts, including fallbacks
  int n_fallbacks = 0;      // starts continued derivative-free
  std::string message;      // NLopt status of the best start
};

class BoundedMinimizer {
 public:
  BoundedMinimizer(ObjectiveFunction objective, Eigen::VectorXd lower, Eigen::VectorXd upper,
                   OptimizerOptions options = {});

  // Runs one local minimisation per start (each start is clipped into the box).
  OptimizerResult run(const std::vector<Eigen::VectorXd>& starts) const;

 private:
  ObjectiveFunction objective_;
  Eigen::VectorXd lower_;
  Eigen::VectorXd upper_;
  OptimizerOptions options_;
};

}  // namespace rsw::calibration
