// `rsw simulate`: loads a weld case, runs it (physics::run_weld), shows progress on
// stderr (one line rewritten in place on a terminal, a line per tenth of the steps
// otherwise, e.g. in a log file), prints the key results (extremes of the signals on
// the output grid, nugget geometry, energy balance) and says where the results are. A
// folder it may not use exits with code 2 before the run (physics/weld_simulation.hpp);
// a failed simulation exits with code 1 and leaves DIR/failure.txt and DIR/partial/.
#include "tools/simulate_command.hpp"

#include "physics/weld_simulation.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::tools {

namespace {
struct SimulateOptions {
  std::string case_file;
  std::string output_dir;
  std::vector<std::string> overrides;
  bool quiet = false;
  bool verbose = false;
  bool overwrite = false;
};

double value_of(const std::vector<std::pair<std::string, double>>& values, const std::string& name) {
  for (const auto& [key, value] : values)
    if (key == name) return value;
  return std::nan("");
}

// The largest value of a signal on the output grid and its time; NaN samples (the
// resistance without current) are skipped.
void print_signal_maximum(const physics::Signals& signals, const char* name, const char* label, double scale,
                          const char* unit) {
  if (const physics::Signals::Peak peak = signals.maximum(name); peak.found)
    std::printf("  %-28s %.4g %s at %.4g ms\n", label, peak.value * scale, unit, peak.time * 1e3);
}

// Key results of a finished weld: what a welding engineer looks at first.
void print_weld_results(const physics::RunResult& result) {
  std::printf("weld (maxima on the output grid):\n");
  print_signal_maximum(result.signals, "resistance", "dynamic resistance", 1e6, "uOhm");
  print_signal_maximum(result.signals, "displacement", "electrode displacement", 1e6, "um");
  print_signal_maximum(result.signals, "temperature", "sheet temperature", 1.0, "degC");
  const auto& n = result.nugget;
  std::printf("nugget: d_n,liq %.3f mm, h_n,liq %.3f mm, d_n,sol %.3f mm, h_n,sol %.3f mm, indentation %.1f um\n",
              value_of(n, "d_n_liq") * 1e3, value_of(n, "h_n_liq") * 1e3, value_of(n, "d_n_sol") * 1e3,
              value_of(n, "h_n_sol") * 1e3, value_of(n, "d_indent") * 1e6);
  std::printf("  penetration:");
  const char* separator = "";
  for (const auto& [key, value] : n)
    if (key.rfind("penetration_", 0) == 0) {
      std::printf("%s %s %.0f %%", separator, key.substr(12).c_str(), value * 100);
      separator = ",";
    }
  std::printf("\n");
  const auto& e = result.energy;
  std::printf("energy: electrical %.1f J = stored %.1f J + removed %.1f J (imbalance %.2g J); "
              "%.1f %% held by the nugget when the current stops\n",
              value_of(e, "electrical"), value_of(e, "stored"), value_of(e, "removed"), value_of(e, "imbalance"),
              value_of(e, "nugget_fraction") * 100);
}

void run_simulate(const SimulateOptions& options) {
  const physics::Problem problem = physics::load_problem(options.case_file, options.overrides);
  const std::string dir = options.output_dir.empty() ? problem.output.directory : options.output_dir;
  // The weld stage's remaining time, estimated from its mean time per step so far.
  std::chrono::steady_clock::time_point weld_start;
  const bool terminal = isatty(fileno(stderr)) != 0;
  auto progress = [&](const physics::Progress& p) {
    if (options.quiet) return;
    if (p.stage == "squeeze") {
      std::fprintf(stderr, "squeeze: seating and raising the force to %.3g kN ...\n",
                   problem.schedule.force.at(0.0) / 1e3);
      return;
    }
    const auto now = std::chrono::steady_clock::now();
    if (p.step <= 1) weld_start = now;
    const double elapsed = std::chrono::duration<double>(now - weld_start).count();
    const int every = std::max(1, p.n_steps / 10);
    if (!terminal && p.step % every != 0 && p.step != p.n_steps) return;
    char left[40] = "";
    if (p.step > 1)
      std::snprintf(left, sizeof left, ", about %.0f s left", elapsed * (p.n_steps - p.step) / (p.step - 1));
    char resistance[32] = "no current";
    if (p.resistance > 0) std::snprintf(resistance, sizeof resistance, "R %.1f uOhm", p.resistance * 1e6);
    std::fprintf(stderr, "%sweld: step %d/%d, t = %.1f ms, T_max %.0f degC, %s%s%s", terminal ? "\r" : "", p.step,
                 p.n_steps, p.time * 1e3, p.max_temperature, resistance, left, terminal ? "   " : "\n");
  };
  const auto result = physics::run_weld(problem, dir, progress, options.verbose, options.overwrite);
  if (!options.quiet && terminal) std::fprintf(stderr, "\n");
  if (!result.success)
    throw std::runtime_error("simulation failed: " + result.message + " (see " + (std::filesystem::path(dir) / "failure.txt").string() + ")");
  std::printf("%s: done in %.1f s (%d weld steps, %d Newton iterations)\n", problem.name.c_str(), result.wall_time,
              result.n_steps, result.n_newton_iterations);
  std::printf("time:");
  for (const auto& [part, seconds] : result.timing) std::printf(" %s %.2f s,", part.c_str(), seconds);
  std::printf(" total %.2f s\n", result.wall_time);
  for (const auto& w : result.warnings) std::printf("warning: %s\n", w.c_str());
  std::printf("after the squeeze: electrode travel %.2f um, indentation %.2f um\n",
              result.squeeze_displacement * 1e6, result.squeeze_indentation * 1e6);
  for (std::size_t i = 0; i < result.squeeze_contact_radius.size(); ++i)
    std::printf("  %-9s contact radius %.3f mm, peak pressure %.3f GPa\n",
                result.squeeze_contact_radius[i].first.c_str(), result.squeeze_contact_radius[i].second * 1e3,
                result.squeeze_peak_pressure[i].second / 1e9);
  print_weld_results(result);
  std::printf("results in %s/: results.h5, signals.csv, summary.json%s\n", dir.c_str(),
              problem.output.fields ? ", fields.pvd (open in ParaView)" : "");
}
}  // namespace

void add_simulate_command(CLI::App& app) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand("simulate", "Run a weld case and write its results");
  cmd->add_option("case", options->case_file, "Weld-case YAML file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", options->output_dir,
                  "Output folder (default: the case's output.directory): new, empty, or one rsw made before");
  cmd->add_flag("--overwrite", options->overwrite,
                "Write into a non-empty folder rsw did not make (rsw still removes and replaces only its own files)");
  cmd->add_option("--set", options->overrides, "Override a config key: --set key=value (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  cmd->add_flag("-q,--quiet", options->quiet, "No progress output");
  cmd->add_flag("--verbose", options->verbose,
                "Print every electro-thermal coupling and Newton iteration to stderr (diagnosis)");
  cmd->callback([options]() { run_simulate(*options); });
}

}  // namespace rsw::tools
