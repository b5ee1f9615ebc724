// rsw_analytic: the `study`, `features` and `calibrate` commands of rsw with the
// analytic forward models of analytic_models.hpp instead of the weld simulator, so the
// CLI, the farm under mpirun, the calibration and the plot scripts are tested end to
// end without running welds. Exit codes as rsw: 2 for input errors (config), 1 for
// other failures.
//
// For posterior-predictive runs of `calibrate` the analytic model is wrapped so that it
// also writes signals: a synthetic record (not a weld) of 8 kA for 150 ms, sampled every
// 0.5 ms, whose dynamic resistance R(t) = (100 + 20 y_1)·(1 + 0.3 sin(π t/150 ms)) µΩ and
// displacement S(t) = 10 y_1 · (t/150 ms) µm during the current follow the first feature
// y_1 of the model at θ, so runs at different θ give visibly different curves.
#include "tests/calibration/analytic_models.hpp"
#include "tools/run_cli.hpp"
#include "tools/calibrate_command.hpp"
#include "tools/study_commands.hpp"

#include "fem/config.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <utility>

namespace {

namespace cal = rsw::calibration;

class AnalyticSignalModel : public cal::ForwardModel {
 public:
  explicit AnalyticSignalModel(std::unique_ptr<cal::ForwardModel> model) : model_(std::move(model)) {}

  std::vector<std::string> parameter_names() const override { return model_->parameter_names(); }
  std::vector<std::string> feature_names() const override { return model_->feature_names(); }
  cal::EvaluationResult evaluate(const Eigen::VectorXd& theta) const override { return model_->evaluate(theta); }

  cal::SignalOutput simulate_signals(const Eigen::VectorXd& theta, const std::filesystem::path& folder) const override {
    const cal::EvaluationResult result = model_->evaluate(theta);
    if (!result.ok()) return cal::SignalOutput::failure(result.failure_reason());
    const double level = result.features()[0];
    std::filesystem::remove_all(folder);
    std::filesystem::create_directories(folder);
    const std::filesystem::path file = folder / "signals.csv";
    std::ofstream out(file);
    out << "# synthetic signals of the analytic test model (tests/calibration/analytic_rsw_main.cpp)\n"
        << "time [ms], current [kA], voltage [V], displacement [mm]\n";
    const double pi = std::acos(-1.0);
    for (int k = 0; k <= 400; ++k) {
      const double t = 0.5 * k - 20.0;  // ms
      const bool on = t >= 0 && t <= 150;
      const double current = on ? 8.0 : 0.0;                                          // kA
      const double resistance = (100 + 20 * level) * (1 + 0.3 * std::sin(pi * std::clamp(t, 0.0, 150.0) / 150));  // µΩ
      const double displacement = 1e-3 * 10 * level * std::clamp(t, 0.0, 150.0) / 150;  // mm
      out << t << ", " << current << ", " << current * resistance * 1e-3 << ", " << displacement << "\n";
    }
    if (!out) return cal::SignalOutput::failure("cannot write " + file.string());
    return cal::SignalOutput::written(file);
  }

 private:
  std::unique_ptr<cal::ForwardModel> model_;
};

std::unique_ptr<cal::ForwardModel> make_analytic_signal_model(const cal::Study& study) {
  return std::make_unique<AnalyticSignalModel>(rsw::testing::make_analytic_model(study));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rsw with analytic forward models (tests only)"};
  app.require_subcommand(1);
  rsw::tools::add_study_commands(app, rsw::testing::make_analytic_model);
  rsw::tools::add_features_command(app);
  rsw::tools::add_calibrate_command(app, make_analytic_signal_model);
  return rsw::tools::run_cli(app, argc, argv);
}
