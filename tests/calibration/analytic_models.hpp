// Analytic forward models for the farm, study and CLI tests: cheap functions with known
// answers standing in for the weld simulator, with switches that make them slow, fail,
// throw, crash or hang on chosen inputs.
//
// - Ishigami (Ishigami & Homma 1990), θ ∈ [−π, π]³:
//     f = sin θ1 + a sin² θ2 + b θ3⁴ sin θ1,  a = 7, b = 0.1
//   S = (0.3139, 0.4424, 0), S_T = (0.5576, 0.4424, 0.2437), S_13 = 0.2437
//   (docs/CALIBRATION.md, "Verification").
// - Smooth: any number of parameters and features, y_k = Σ_i cos((k + 1)(i + 1) θ_i / 7)
//   + (k + 1) θ_1, a deterministic function whose every value is bit-reproducible.
// Behaviour switches act on θ_1 (the first parameter): above fail_above the run returns
// a failure; above throw_above evaluate() throws; above crash_above the process aborts;
// above hang_above it sleeps for an hour (for run time limits); above undefined_above
// the run succeeds but its first feature is NaN (undefined, as a weld feature whose
// signal lacks the shape it needs). Every evaluation first sleeps `delay` seconds.
#pragma once

#include "calibration/forward_model.hpp"
#include "calibration/study.hpp"

#include "fem/config.hpp"

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace rsw::testing {

struct AnalyticBehaviour {
  double delay = 0;  // [s] per evaluation
  double fail_above = std::numeric_limits<double>::infinity();
  double throw_above = std::numeric_limits<double>::infinity();
  double crash_above = std::numeric_limits<double>::infinity();
  double hang_above = std::numeric_limits<double>::infinity();
  double undefined_above = std::numeric_limits<double>::infinity();
};

enum class AnalyticFunction { ishigami, smooth };

class AnalyticModel : public calibration::ForwardModel {
 public:
  AnalyticModel(AnalyticFunction function, std::vector<std::string> parameters, std::vector<std::string> features,
                AnalyticBehaviour behaviour = {})
      : function_(function), parameters_(std::move(parameters)), features_(std::move(features)),
        behaviour_(behaviour) {
    if (function_ == AnalyticFunction::ishigami && (parameters_.size() != 3 || features_.size() != 1)) {
      throw std::invalid_argument("the Ishigami model has 3 parameters and 1 feature");
    }
  }

  std::vector<std::string> parameter_names() const override { return parameters_; }
  std::vector<std::string> feature_names() const override { return features_; }

  calibration::EvaluationResult evaluate(const Eigen::VectorXd& theta) const override {
    if (behaviour_.delay > 0) std::this_thread::sleep_for(std::chrono::duration<double>(behaviour_.delay));
    const double first = theta[0];
    if (first > behaviour_.hang_above) std::this_thread::sleep_for(std::chrono::hours(1));
    if (first > behaviour_.crash_above) {
      const rlimit no_core_file{0, 0};
      setrlimit(RLIMIT_CORE, &no_core_file);
      std::abort();
    }
    if (first > behaviour_.throw_above) throw std::runtime_error("analytic model: thrown on purpose");
    if (first > behaviour_.fail_above) {
      return calibration::EvaluationResult::failure("analytic model: no convergence above " +
                                                    std::to_string(behaviour_.fail_above));
    }
    Eigen::VectorXd y(static_cast<Eigen::Index>(features_.size()));
    if (function_ == AnalyticFunction::ishigami) {
      y[0] = std::sin(theta[0]) + 7 * std::sin(theta[1]) * std::sin(theta[1]) +
             0.1 * std::pow(theta[2], 4) * std::sin(theta[0]);
    } else {
      for (Eigen::Index k = 0; k < y.size(); ++k) {
        double sum = static_cast<double>(k + 1) * theta[0];
        for (Eigen::Index i = 0; i < theta.size(); ++i) {
          sum += std::cos(static_cast<double>((k + 1) * (i + 1)) * theta[i] / 7.0);
        }
        y[k] = sum;
      }
    }
    if (first > behaviour_.undefined_above) y[0] = std::numeric_limits<double>::quiet_NaN();
    return calibration::EvaluationResult::success(y);
  }

 private:
  AnalyticFunction function_;
  std::vector<std::string> parameters_;
  std::vector<std::string> features_;
  AnalyticBehaviour behaviour_;
};

// The "weld case" of an analytic study: a small YAML file naming the function and the
// behaviour switches, e.g.
//   analytic: {function: ishigami, delay: 20 ms, fail_above: 2.5}
inline fem::ConfigSchema analytic_case_schema() {
  fem::ConfigSchema s("Analytic test model", "Stands in for the weld case in tests.");
  s.choice("analytic.function", {"ishigami", "smooth"}).default_value("smooth")
      .doc("The analytic function.");
  s.number("analytic.delay", "s", "ms").default_value("0 ms").range(fem::Range::closed(0, 1e6))
      .doc("Sleep before each evaluation.");
  for (const char* key : {"fail_above", "throw_above", "crash_above", "hang_above", "undefined_above"}) {
    s.number(std::string("analytic.") + key, "1", "1").default_value("1e300")
        .doc("Threshold on the first parameter for this misbehaviour.");
  }
  return s;
}

inline std::unique_ptr<calibration::ForwardModel> make_analytic_model(const calibration::Study& study) {
  if (study.case_file().empty()) throw std::runtime_error("an analytic study needs model.case");
  const fem::Config config = fem::load_config(analytic_case_schema(), study.case_file().string());
  AnalyticBehaviour behaviour;
  behaviour.delay = config.number("analytic.delay");
  behaviour.fail_above = config.number("analytic.fail_above");
  behaviour.throw_above = config.number("analytic.throw_above");
  behaviour.crash_above = config.number("analytic.crash_above");
  behaviour.hang_above = config.number("analytic.hang_above");
  behaviour.undefined_above = config.number("analytic.undefined_above");
  const AnalyticFunction function =
      config.text("analytic.function") == "ishigami" ? AnalyticFunction::ishigami : AnalyticFunction::smooth;
  return std::make_unique<AnalyticModel>(function, study.parameter_space().names(), study.feature_names(),
                                         behaviour);
}

}  // namespace rsw::testing
