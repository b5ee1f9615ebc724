// Feature extraction from weld signals; definitions in features.hpp (docs/STUDIES.md, "The features",
// El Ouafi et al. 2012 for the dynamic-resistance geometry, paper §2.2 for the
// displacement and temperature features), including which features a curve's shape
// leaves undefined (NaN with the reason) and which input errors throw.
#include "calibration/features.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

namespace rsw::calibration {
namespace {

std::string milliseconds(double seconds) {
  std::ostringstream out;
  out.precision(6);
  out << seconds * 1e3 << " ms";
  return out.str();
}

std::string number(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

// The grid t_k = t_ws + k·step, k = first..last, of the points inside [lo, hi] (with
// cell means: the points whose whole cell [t_k − step/2, t_k + step/2] is inside).
struct Grid {
  long first = 0, last = -1;
  double step = 0, t_ws = 0;
  double time(long k) const { return t_ws + static_cast<double>(k) * step; }
};
Grid grid_inside(double t_ws, double step, double lo, double hi, bool cell_means) {
  const double margin = cell_means ? 0.5 * step : 0.0;
  return {static_cast<long>(std::ceil((lo + margin - t_ws) / step - 1e-9)),
          static_cast<long>(std::floor((hi - margin - t_ws) / step + 1e-9)), step, t_ws};
}

// Values of `column` on the grid: each the mean of the linearly interpolated samples
// over its cell (signal.hpp, average_linear), or the value at t_k without cell means.
Eigen::VectorXd on_grid(const Signal& signal, const std::string& column, const Grid& grid, bool cell_means) {
  const double w = cell_means ? 0.5 * grid.step : 0.0;
  Eigen::VectorXd values(grid.last - grid.first + 1);
  for (long k = grid.first; k <= grid.last; ++k)
    values[k - grid.first] = average_linear(signal.time(), signal.column(column), grid.time(k) - w, grid.time(k) + w);
  return values;
}

SmoothCurve smooth_curve(const Eigen::VectorXd& values, double t_first, double step,
                         const SavitzkyGolayFilter& filter, const std::string& what) {
  if (values.size() < filter.window_length()) {
    throw FeatureError(what + " spans only " + std::to_string(values.size()) +
                       " samples at a step of " + milliseconds(step) +
                       "; the Savitzky-Golay window needs " +
                       std::to_string(filter.window_length()) + " (signal too short)");
  }
  return SmoothCurve(t_first, step, filter.smooth(values), filter.slope(values, step));
}

void add_resistance_features(const Signal& signal, const WeldStage& stage, double step,
                             const FeatureSettings& settings, const SavitzkyGolayFilter& filter,
                             FeatureValues& features) {
  const double threshold = settings.weld_current_fraction * stage.peak_current;
  const Grid grid = grid_inside(stage.start, step, stage.start, stage.end, settings.cell_means);
  if (grid.last < grid.first + 1) {
    throw FeatureError("the weld stage lasts " + milliseconds(stage.end - stage.start) +
                       ", too short for the resampling step of " + milliseconds(step));
  }
  const Eigen::VectorXd current = on_grid(signal, signal_column::current, grid, settings.cell_means);
  Eigen::VectorXd resistance;
  if (signal.has_column(signal_column::resistance)) {
    resistance = on_grid(signal, signal_column::resistance, grid, settings.cell_means);
  } else {
    resistance = on_grid(signal, signal_column::voltage, grid, settings.cell_means);
    for (Eigen::Index k = 0; k < current.size(); ++k) {
      if (std::abs(current[k]) < 0.5 * threshold) {
        throw FeatureError("the current falls to " + number(current[k]) + " A at " +
                           milliseconds(grid.time(grid.first + k) - stage.start) +
                           " after the weld start, below half the weld-stage threshold; "
                           "pulsed waveforms with current pauses are not supported");
      }
      resistance[k] /= current[k];
    }
  }
  const SmoothCurve curve = smooth_curve(resistance, grid.time(grid.first), step, filter, "the weld stage");

  const double t_s = std::max(stage.start + settings.trim_margin, curve.begin());
  const double t_e = std::min(stage.end - settings.trim_margin, curve.end());
  if (t_e - t_s < 4 * step) {
    throw FeatureError("the weld stage of " + milliseconds(stage.end - stage.start) +
                       " leaves less than four resampling steps after trimming " +
                       milliseconds(settings.trim_margin) + " at each end (signal too short)");
  }
  const SmoothCurve window = curve.trimmed(t_s, t_e);
  const double tolerance = 1e-9 * step;
  const double r_gamma = window.value(t_e);

  namespace f = feature_name;
  // Each feature's value, or NaN and the reason it is undefined; added in the fixed order.
  std::map<std::string, double> value;
  std::map<std::string, std::string> reason;
  value[f::resistance_gamma] = r_gamma;
  value[f::time_gamma] = t_e - stage.start;
  value[f::resistance_mean] = window.mean();

  // β: the highest point after the falling start (if any) ends at its first minimum.
  const std::optional<CurvePoint> valley = window.first_minimum();
  const bool falls_throughout = !valley || valley->time >= t_e - tolerance;
  const CurvePoint beta = falls_throughout ? window.maximum() : window.trimmed(valley->time, t_e).maximum();
  const bool rises_at_end = !falls_throughout && beta.time >= t_e - tolerance;
  // A peak stands above both ends of its search by more than round-off.
  const bool flat = !falls_throughout && !rises_at_end &&
                    !(beta.value - std::max(valley->value, r_gamma) > 1e-9 * std::abs(beta.value));
  if (falls_throughout || beta.time <= valley->time + tolerance || rises_at_end || flat) {
    const std::string why =
        "the dynamic resistance has no peak inside the trimmed weld stage [" + milliseconds(t_s - stage.start) +
        ", " + milliseconds(t_e - stage.start) + "]; " +
        (rises_at_end ? "its maximum is at the end: it still rises at the end"
         : flat       ? "it is flat: its highest point is within 1e-9 of its value of both ends"
                      : "it falls over the whole stage");
    for (const char* name : {f::resistance_beta, f::time_beta, f::resistance_alpha, f::time_alpha,
                             f::slope_before_peak, f::slope_after_peak, f::resistance_rise, f::resistance_drop}) {
      reason[name] = why;
    }
  } else {
    value[f::resistance_beta] = beta.value;
    value[f::time_beta] = beta.time - stage.start;
    value[f::slope_after_peak] = (r_gamma - beta.value) / (t_e - beta.time);
    value[f::resistance_drop] = r_gamma - beta.value;
    const CurvePoint steepest = window.trimmed(valley->time, beta.time).maximum_slope();
    if (!(steepest.value > 0)) {
      const std::string why = "the dynamic resistance does not rise before its peak at " +
                              milliseconds(beta.time - stage.start) + ", so it has no first inflection";
      for (const char* name : {f::resistance_alpha, f::time_alpha, f::slope_before_peak, f::resistance_rise}) {
        reason[name] = why;
      }
    } else {
      const double r_alpha = window.value(steepest.time);
      value[f::resistance_alpha] = r_alpha;
      value[f::time_alpha] = steepest.time - stage.start;
      value[f::slope_before_peak] = (beta.value - r_alpha) / (beta.time - steepest.time);
      value[f::resistance_rise] = beta.value - r_alpha;
    }
  }
  for (const std::string& name : resistance_feature_names()) {
    if (reason.count(name)) {
      features.add_undefined(name, reason[name]);
    } else {
      features.add(name, value.at(name));
    }
  }
}

// The curve of `column` over the whole record, up to the record end of features.hpp.
SmoothCurve record_curve(const Signal& signal, const std::string& column, const WeldStage& stage,
                         double step, const FeatureSettings& settings,
                         const SavitzkyGolayFilter& filter) {
  const Eigen::VectorXd& time = signal.time();
  const double record_end =
      std::min(time[time.size() - 1], stage.end + settings.post_weld_window);
  const Grid grid = grid_inside(stage.start, step, time[0], record_end, settings.cell_means);
  if (grid.last <= grid.first) {
    throw FeatureError("the " + column + " record is shorter than one resampling step");
  }
  return smooth_curve(on_grid(signal, column, grid, settings.cell_means), grid.time(grid.first), step, filter,
                      "the " + column + " record");
}

void add_displacement_features(const Signal& signal, const WeldStage& stage, double step,
                               const FeatureSettings& settings,
                               const SavitzkyGolayFilter& filter, FeatureValues& features) {
  const SmoothCurve curve =
      record_curve(signal, signal_column::displacement, stage, step, settings, filter);
  const double t_s = stage.start + settings.trim_margin;
  if (t_s >= curve.end() - step) {
    throw FeatureError("the displacement record ends before " +
                       milliseconds(settings.trim_margin) + " after the weld start");
  }
  const SmoothCurve after_start = curve.trimmed(t_s, curve.end());
  const double s_0 = curve.value(t_s);
  const CurvePoint peak = after_start.maximum();
  const double s_end = curve.value(curve.end());
  namespace f = feature_name;
  // No rise: dS_P = 0 (peak.value = S_0) is a measured "no expansion", still defined.
  features.add(f::displacement_peak_expansion, peak.value - s_0);
  features.add(f::displacement_end, s_end);
  features.add(f::displacement_net, s_end - s_0);
  if (peak.time <= t_s + 1e-9 * step) {
    features.add_undefined(f::displacement_expansion_rate,
                           "the electrode displacement does not rise after the weld start: its maximum on [" +
                               milliseconds(settings.trim_margin) + ", " + milliseconds(curve.end() - stage.start) +
                               "] is at " + milliseconds(settings.trim_margin) +
                               ", so there is no expansion phase to fit a rate to");
  } else {
    features.add(f::displacement_expansion_rate, curve.trimmed(t_s, peak.time).fit_slope());
  }
}

void add_temperature_features(const Signal& signal, const WeldStage& stage, double step,
                              const FeatureSettings& settings,
                              const SavitzkyGolayFilter& filter, FeatureValues& features) {
  const SmoothCurve curve =
      record_curve(signal, signal_column::temperature, stage, step, settings, filter);
  const CurvePoint peak = curve.maximum();
  const double t_end = curve.end();
  const double temperature_end = curve.value(t_end);
  namespace f = feature_name;
  features.add(f::temperature_max, peak.value);
  features.add(f::time_temperature_max, peak.time - stage.start);
  features.add(f::temperature_end, temperature_end);
  if (peak.time >= t_end - 1e-9 * step) {
    features.add_undefined(f::cooling_rate, "the sheet temperature peaks at the end of the record, " +
                                                milliseconds(t_end - stage.start) +
                                                " after the weld start, so there is no cooling interval");
  } else {
    features.add(f::cooling_rate, (temperature_end - peak.value) / (t_end - peak.time));
  }
}

}  // namespace

const std::vector<std::string>& resistance_feature_names() {
  namespace f = feature_name;
  static const std::vector<std::string> names = {
      f::resistance_alpha,  f::resistance_beta,  f::resistance_gamma, f::time_alpha,
      f::time_beta,         f::time_gamma,       f::slope_before_peak, f::slope_after_peak,
      f::resistance_mean,   f::resistance_rise,  f::resistance_drop};
  return names;
}

const std::vector<std::string>& displacement_feature_names() {
  namespace f = feature_name;
  static const std::vector<std::string> names = {
      f::displacement_peak_expansion, f::displacement_end, f::displacement_net,
      f::displacement_expansion_rate};
  return names;
}

const std::vector<std::string>& temperature_feature_names() {
  namespace f = feature_name;
  static const std::vector<std::string> names = {f::temperature_max, f::time_temperature_max,
                                                 f::temperature_end, f::cooling_rate};
  return names;
}

const std::vector<std::string>& nugget_feature_names() {
  namespace f = feature_name;
  static const std::vector<std::string> names = {
      f::nugget_diameter_liquidus, f::nugget_height_liquidus, f::nugget_diameter_solidus,
      f::nugget_height_solidus,    f::electrode_contact_width, f::indentation_depth,
      f::unmolten_thickness};
  return names;
}

WeldStage find_weld_stage(const Signal& signal, double current_fraction) {
  if (!(current_fraction > 0 && current_fraction < 1)) {
    throw FeatureError("the weld-stage current fraction must lie in (0, 1), got " +
                       number(current_fraction));
  }
  if (!signal.has_column(signal_column::current)) {
    throw FeatureError("the signal has no 'current' column; the weld stage is found from it");
  }
  const Eigen::VectorXd& time = signal.time();
  const Eigen::VectorXd current = signal.column(signal_column::current).cwiseAbs();
  const Eigen::Index n = current.size();
  if (n < 2) throw FeatureError("the signal has fewer than two samples (signal too short)");

  WeldStage stage;
  stage.peak_current = current.maxCoeff();
  if (!(stage.peak_current > 0)) {
    throw FeatureError("no current pulse: the current is zero over the whole record");
  }
  const double threshold = current_fraction * stage.peak_current;
  if ((current.array() >= threshold).all()) {
    throw FeatureError("no current pulse: |I| stays above " + number(100 * current_fraction) +
                       " % of its peak " + number(stage.peak_current) +
                       " A over the whole record, so the weld stage has no start or end");
  }
  Eigen::Index first = 0;
  while (current[first] < threshold) ++first;
  Eigen::Index last = n - 1;
  while (current[last] < threshold) --last;
  auto crossing = [&](Eigen::Index below, Eigen::Index above) {
    const double weight = (threshold - current[below]) / (current[above] - current[below]);
    return time[below] + weight * (time[above] - time[below]);
  };
  stage.start = first == 0 ? time[0] : crossing(first - 1, first);
  stage.end = last == n - 1 ? time[n - 1] : crossing(last + 1, last);
  return stage;
}

std::string why_undefined(const std::string& name) {
  namespace f = feature_name;
  static const std::map<std::string, std::string> conditions = [] {
    const std::string no_peak = "the dynamic resistance has no peak inside the trimmed weld stage";
    std::map<std::string, std::string> c;
    for (const char* name : {f::resistance_beta, f::time_beta, f::slope_after_peak, f::resistance_drop}) {
      c[name] = no_peak;
    }
    for (const char* name : {f::resistance_alpha, f::time_alpha, f::slope_before_peak, f::resistance_rise}) {
      c[name] = no_peak + ", or does not rise before it";
    }
    c[f::displacement_expansion_rate] = "the electrode displacement does not rise after the weld start";
    c[f::cooling_rate] = "the sheet temperature peaks at the end of the record, so there is no cooling interval";
    return c;
  }();
  const auto it = conditions.find(name);
  return it == conditions.end() ? std::string() : it->second;
}

void FeatureValues::add(const std::string& name, double value) {
  if (has(name)) throw FeatureError("feature '" + name + "' is given twice");
  if (!std::isfinite(value)) {
    throw FeatureError("feature '" + name + "' is not finite (" + number(value) + ")");
  }
  names_.push_back(name);
  values_.push_back(value);
}

void FeatureValues::add_undefined(const std::string& name, const std::string& reason) {
  if (has(name)) throw FeatureError("feature '" + name + "' is given twice");
  if (reason.empty()) throw FeatureError("feature '" + name + "' is undefined without a reason");
  names_.push_back(name);
  values_.push_back(std::numeric_limits<double>::quiet_NaN());
  undefined_.push_back({name, reason});
}

std::string FeatureValues::undefined_reason(const std::string& name) const {
  for (const auto& entry : undefined_) {
    if (entry.name == name) return entry.reason;
  }
  return "";
}

bool FeatureValues::has(const std::string& name) const {
  return std::find(names_.begin(), names_.end(), name) != names_.end();
}

double FeatureValues::at(const std::string& name) const {
  const auto it = std::find(names_.begin(), names_.end(), name);
  if (it == names_.end()) {
    std::string available;
    for (const auto& other : names_) available += (available.empty() ? "" : ", ") + other;
    throw FeatureError("no feature '" + name + "' (extracted: " +
                       (available.empty() ? std::string("none") : available) + ")");
  }
  return values_[static_cast<std::size_t>(it - names_.begin())];
}

Eigen::VectorXd FeatureValues::select(const std::vector<std::string>& names) const {
  Eigen::VectorXd result(static_cast<Eigen::Index>(names.size()));
  for (std::size_t i = 0; i < names.size(); ++i) result[static_cast<Eigen::Index>(i)] = at(names[i]);
  return result;
}

FeatureValues extract_features(const Signal& signal, const FeatureSettings& settings,
                               const std::vector<std::pair<std::string, double>>& scalars) {
  if (!(settings.trim_margin >= 0) || !(settings.resample_step >= 0) ||
      !(settings.post_weld_window >= 0)) {
    throw FeatureError("feature settings: trim_margin, resample_step and post_weld_window "
                       "must not be negative");
  }
  const WeldStage stage = find_weld_stage(signal, settings.weld_current_fraction);
  const SavitzkyGolayFilter filter(settings.smoothing_window, settings.smoothing_order);
  const double step =
      settings.resample_step > 0 ? settings.resample_step : median_step(signal.time());

  FeatureValues features;
  const bool has_resistance = signal.has_column(signal_column::resistance) ||
                              signal.has_column(signal_column::voltage);
  if (has_resistance) {
    add_resistance_features(signal, stage, step, settings, filter, features);
  }
  if (signal.has_column(signal_column::displacement)) {
    add_displacement_features(signal, stage, step, settings, filter, features);
  }
  if (signal.has_column(signal_column::temperature)) {
    add_temperature_features(signal, stage, step, settings, filter, features);
  }
  for (const auto& [name, value] : scalars) {
    if (!std::isfinite(value)) throw FeatureError("scalar feature '" + name + "' is not finite");
    features.add(name, value);
  }
  if (features.size() == 0) {
    throw FeatureError("nothing to extract: the signal has none of the columns 'resistance' "
                       "or 'voltage', 'displacement', 'temperature', and no scalars were given");
  }
  return features;
}

}  // namespace rsw::calibration
