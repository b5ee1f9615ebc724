// The weld run's entry point and step schedule; see weld_simulation.hpp. The stages
// of a run are the class WeldDriver (weld_driver.hpp).
#include "physics/weld_simulation.hpp"

#include "physics/weld_driver.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace rsw::physics {

namespace fs = std::filesystem;

int Signals::column(const std::string& name) const {
  auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

Signals::Peak Signals::maximum(const std::string& name) const {
  const int c = column(name), t = column("time");
  Peak peak;
  if (c < 0 || t < 0) return peak;
  for (std::size_t i = 0; i < n_rows(); ++i) {
    const double value = columns[c][i];
    if (std::isfinite(value) && (!peak.found || value > peak.value)) peak = {true, value, columns[t][i]};
  }
  return peak;
}

std::vector<double> weld_step_times(const Problem& problem) {
  const double end = problem.schedule.end_time();
  std::set<double> breaks{0.0, end};
  for (const auto* table : {&problem.schedule.current, &problem.schedule.force})
    for (double t : table->time)
      if (t > 0 && t < end) breaks.insert(t);
  const double interval = problem.output.interval;
  if (interval > 0)
    for (int k = 1; k * interval < end - 1e-12; ++k) breaks.insert(k * interval);
  const double early_end = problem.solver.early_phase_end;
  if (early_end > 0 && early_end < end) breaks.insert(early_end);
  // Merge boundaries closer than a nanosecond (rounding of unit conversions).
  std::vector<double> b;
  for (double t : breaks)
    if (b.empty() || t - b.back() > 1e-9) b.push_back(t);
  b.back() = end;
  std::vector<double> times{0.0};
  for (std::size_t i = 0; i + 1 < b.size(); ++i) {
    const bool early = b[i + 1] <= early_end * (1 + 1e-12);
    const double largest = early ? std::min(problem.solver.time_step, problem.solver.early_time_step)
                                 : problem.solver.time_step;
    const int n = std::max(1, static_cast<int>(std::ceil((b[i + 1] - b[i]) / largest - 1e-9)));
    for (int k = 1; k <= n; ++k) times.push_back(b[i] + (b[i + 1] - b[i]) * k / n);
  }
  return times;
}

const std::vector<std::string>& weld_output_names() {
  static const std::vector<std::string> names = {"results.h5", "signals.csv", "summary.json", "fields.pvd",
                                                 "fields_*",   "failure.txt", "partial"};
  return names;
}

RunResult run_weld(const Problem& problem, const fs::path& output_dir,
                   const std::function<void(const Progress&)>& progress, bool verbose, bool overwrite) {
  fem::OutputFolderOptions options;
  options.kind = "simulate";
  options.overwrite = overwrite;
  fem::OutputFolder folder(output_dir, options);
  folder.clear(weld_output_names());
  WeldDriver driver(problem, folder, progress, verbose);
  return driver.run();
}

}  // namespace rsw::physics
