// `rsw simulate`: loads a weld case, runs it (physics::run_weld), shows progress on
// stderr and says where the results are. A failed simulation exits with code 1 and
// leaves only DIR.partial/ with failure.txt.
#include "tools/simulate_command.hpp"

#include "physics/weld_simulation.hpp"

#include <chrono>
#include <cstdio>
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
};

void run_simulate(const SimulateOptions& options) {
  const physics::Problem problem = physics::load_problem(options.case_file, options.overrides);
  const std::string dir = options.output_dir.empty() ? problem.output.directory : options.output_dir;
  // The weld stage's remaining time, estimated from its mean time per step so far.
  std::chrono::steady_clock::time_point weld_start;
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
    char left[40] = "";
    if (p.step > 1)
      std::snprintf(left, sizeof left, ", about %.0f s left", elapsed * (p.n_steps - p.step) / (p.step - 1));
    std::fprintf(stderr, "\rweld: step %d/%d, t = %.1f ms, T_max %.0f degC, R %.1f uOhm%s   ", p.step, p.n_steps,
                 p.time * 1e3, p.max_temperature, p.resistance * 1e6, left);
  };
  const auto result = physics::run_weld(problem, dir, progress);
  if (!options.quiet) std::fprintf(stderr, "\n");
  if (!result.success)
    throw std::runtime_error("simulation failed: " + result.message + " (see " + dir + ".partial/failure.txt)");
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
  std::printf("results in %s/: results.h5, signals.csv, summary.json%s\n", dir.c_str(),
              problem.output.fields ? ", fields.pvd (open in ParaView)" : "");
}
}  // namespace

void add_simulate_command(CLI::App& app) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand("simulate", "Run a weld case and write its results");
  cmd->add_option("case", options->case_file, "Weld-case YAML file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", options->output_dir, "Output folder (default: the case's output.directory)");
  cmd->add_option("--set", options->overrides, "Override a config key: --set key=value (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  cmd->add_flag("-q,--quiet", options->quiet, "No progress output");
  cmd->callback([options]() { run_simulate(*options); });
}

}  // namespace rsw::tools
