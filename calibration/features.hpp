// Scalar calibration features of one weld, extracted from its signals (docs/STUDIES.md, "The features";
// paper §2.2–2.3). The same extractor serves simulated signals and measured signal
// files, so simulation and experiment are compared like for like.
//
// Processing (all times below are relative to the weld start t_ws, values in SI):
// 1. Weld stage. I_peak = max |I| over the raw current samples. The weld stage
//    [t_ws, t_we] runs from the first time |I| reaches f·I_peak to the last time it
//    falls below f·I_peak (f = weld_current_fraction, default 0.1), both crossing times
//    linearly interpolated between raw samples (so they move continuously with the
//    data). If the current is above the threshold at the first (last) sample, the
//    record starts (ends) inside the weld stage and t_ws (t_we) is that sample. Errors:
//    no current column, zero current, or |I| ≥ f·I_peak everywhere (no pulse).
// 2. Uniform resampling with step Δt = 1 ms on the grid t_ws + kΔt, anchored at the
//    weld start: each grid value is the mean of the linearly interpolated samples over
//    its cell [t_k − w, t_k + w], w = Δt/2, narrowed symmetrically at the ends of the
//    weld stage (current, voltage, resistance) or of the record (so the first and last
//    values are point values); R = V/I takes the means of V and I. Then Savitzky–Golay smoothing (cubic,
//    window 11; Savitzky & Golay 1964) of values and slopes. The window is counted in
//    samples (paper §2.3), so the grid fixes its span (11 ms): simulated and measured
//    signals share it whatever their own sampling, and are compared like for like.
//    Cell means, not values at the grid points: a finely sampled logger signal's
//    noise and inverter ripple average out instead of aliasing onto the grid, and a
//    fast drop of the simulated resistance (a ring of contact closing, docs/MODEL.md)
//    moves a grid value in proportion to where in its cell it falls, so features vary
//    continuously as parameters shift the drop's time; a simulation should then record
//    its signals at every step (`output.interval: 0`). Signals sampled more coarsely
//    than the grid are interpolated and lose what lies between their samples. The
//    smoothed samples are joined into a C¹
//    cubic Hermite SmoothCurve. Extrema, steepest points, means and line fits are
//    computed on that curve, so they are not quantised to the sample grid.
// 3. Dynamic resistance (needs current and resistance, or current and voltage; R = V/I
//    on the weld-stage grid, which must keep |I| ≥ f·I_peak / 2 — pulsed waveforms with
//    current pauses are rejected). The curve covers the weld stage; trimming 2 ms at
//    each end gives the analysis window [t_s, t_e] = [t_ws + 2 ms, t_we − 2 ms]. After
//    El Ouafi et al. (2012):
//      β: the peak, the maximum of R on [t_v, t_e], where t_v ends a falling start: t_s
//         if R does not fall at t_s, else R's first local minimum (the curve's local
//         extremes, so a cold start resistance above the peak does not hide it). It
//         must lie strictly inside (else β is undefined, see "Undefined features");
//         R_beta varies continuously with the data where the peak is unique;
//      α: first inflection, defined as the point of steepest rise dR/dt on [t_v, t_β]
//         (the maximum of the smoothed slope, located on the curve; if the slope is
//         largest at t_s the inflection lies before the window and α = t_s). It must
//         have dR/dt > 0 (a rising part before the peak), else α is undefined;
//      γ: end of the window, t_gamma = t_e, R_gamma = R(t_e);
//      m_1 = (R_β − R_α)/(t_β − t_α), m_2 = (R_γ − R_β)/(t_γ − t_β) [Ω/s] (chords);
//      R_m = mean of R over the window; dR_1 = R_β − R_α; dR_2 = R_γ − R_β.
//    The maximum of dR/dt varies continuously with the data; a zero of d²R/dt² would
//    need a third smoothed derivative and jumps between several zero crossings.
// 4. Electrode displacement S (paper §2.2; positive when the upper electrode moves
//    away from the lower one, i.e. expansion): curve over the whole record (up to
//    post_weld_window after t_we), S_0 = S(t_ws + 2 ms);
//      S_peak = max S on [t_ws + 2 ms, record end], dS_P = S_peak − S_0;
//      S_end = S at the record end (after current shut-off and partial cooling),
//      dS_net = S_end − S_0;
//      S_dot_exp = slope of the least-squares line through S on [t_ws + 2 ms, t(S_peak)].
// 5. Sheet temperature (column "temperature", the maximum sheet temperature):
//      T_max = max T over the record, t_T_max its time; T_end = T at the record end;
//      T_dot_cool = (T_end − T_max)/(t_end − t_T_max) [K/s], negative while cooling.
// 6. Nugget scalars (d_n_liq, ...) are passed through unchanged when given.
// The record end is the last grid point whose cell ends at or before min(last sample,
// t_we + post_weld_window) (the point itself without cell means). A group whose
// column is absent is left out.
//
// Undefined features. A valid signal whose curve has an unusual shape leaves some
// features without a definition; those, and only those, are reported as NaN with the
// reason, and every other feature keeps its value (a study or calibration decides per
// feature what to do with a NaN, instead of losing the whole weld):
//   - no resistance peak inside [t_s, t_e] (R falls over the whole window, or its
//     maximum after t_v is at t_e: R still rises at the end; or R is flat, its
//     maximum less than 1e-9 of its value above both ends): R_beta, t_beta, R_alpha,
//     t_alpha, m_1, m_2, dR_1, dR_2 are undefined; R_gamma, t_gamma and R_m are defined;
//   - an interior peak but no rise before it (max dR/dt ≤ 0 on [t_v, t_β]): R_alpha,
//     t_alpha, m_1, dR_1 are undefined;
//   - S does not rise after t_ws + 2 ms (its maximum is there): S_dot_exp (a slope over
//     an empty expansion phase) is undefined; dS_P = 0 (no expansion is a measured
//     value, not a missing one), S_end and dS_net are defined;
//   - T peaks at the record end (still heating): T_dot_cool is undefined; T_max,
//     t_T_max and T_end are defined.
// Input errors throw FeatureError (or SignalError from the reader) with the reason: no
// current column or no current pulse, a signal or weld stage too short for the
// smoothing window and the trimming, current pauses in a voltage-only signal, no
// column to extract from, a non-finite nugget scalar.
#pragma once

#include "calibration/signal.hpp"

#include <Eigen/Core>

#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rsw::calibration {

class FeatureError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace feature_name {
// Dynamic resistance [Ω], times [s] from the weld start, slopes [Ω/s].
inline constexpr const char* resistance_alpha = "R_alpha";
inline constexpr const char* resistance_beta = "R_beta";
inline constexpr const char* resistance_gamma = "R_gamma";
inline constexpr const char* time_alpha = "t_alpha";
inline constexpr const char* time_beta = "t_beta";
inline constexpr const char* time_gamma = "t_gamma";
inline constexpr const char* slope_before_peak = "m_1";
inline constexpr const char* slope_after_peak = "m_2";
inline constexpr const char* resistance_mean = "R_m";
inline constexpr const char* resistance_rise = "dR_1";
inline constexpr const char* resistance_drop = "dR_2";
// Electrode displacement [m], expansion rate [m/s].
inline constexpr const char* displacement_peak_expansion = "dS_P";
inline constexpr const char* displacement_end = "S_end";
inline constexpr const char* displacement_net = "dS_net";
inline constexpr const char* displacement_expansion_rate = "S_dot_exp";
// Maximum sheet temperature [°C], its time [s], cooling rate [K/s].
inline constexpr const char* temperature_max = "T_max";
inline constexpr const char* time_temperature_max = "t_T_max";
inline constexpr const char* temperature_end = "T_end";
inline constexpr const char* cooling_rate = "T_dot_cool";
// Nugget geometry [m] (physics/nugget.hpp), passed through from the simulator's results.
inline constexpr const char* nugget_diameter_liquidus = "d_n_liq";
inline constexpr const char* nugget_height_liquidus = "h_n_liq";
inline constexpr const char* nugget_diameter_solidus = "d_n_sol";
inline constexpr const char* nugget_height_solidus = "h_n_sol";
inline constexpr const char* electrode_contact_width = "w_elec";
inline constexpr const char* indentation_depth = "d_indent";
inline constexpr const char* unmolten_thickness = "t_unmolt";
}  // namespace feature_name

// Names of each group, in the order extract_features() reports them.
const std::vector<std::string>& resistance_feature_names();
const std::vector<std::string>& displacement_feature_names();
const std::vector<std::string>& temperature_feature_names();
const std::vector<std::string>& nugget_feature_names();

struct FeatureSettings {
  double weld_current_fraction = 0.1;  // threshold f of |I| / I_peak for the weld stage
  double resample_step = 1e-3;         // Δt [s] of the feature grid; 0 takes the median step of the raw signal
  // Grid values: means over the cells (default, step 2 above), or the interpolated
  // values at the grid points (the paper's resampling; every feature of a cubic curve
  // then has a closed form).
  bool cell_means = true;
  int smoothing_window = 11;           // Savitzky–Golay window [samples]
  int smoothing_order = 3;             // Savitzky–Golay polynomial order
  double trim_margin = 2e-3;           // [s], trimmed at both ends of the weld stage
  // [s] of record after the weld end used by the displacement and temperature features
  // (lets a long measured hold be compared with a short simulated one).
  double post_weld_window = std::numeric_limits<double>::infinity();
};

struct WeldStage {
  double start = 0;         // t_ws [s], record clock
  double end = 0;           // t_we [s], record clock
  double peak_current = 0;  // I_peak = max |I| [A]
};

// Step 1 above; throws FeatureError.
WeldStage find_weld_stage(const Signal& signal, double current_fraction);

// A feature that the signal's shape leaves undefined, and why (see above).
struct UndefinedFeature {
  std::string name;
  std::string reason;  // e.g. "the dynamic resistance has no peak inside ...; its maximum is at the start: ..."
};

// Named feature values in a fixed order. An undefined feature keeps its place in the
// order with the value NaN, and its reason is listed in undefined(): a NaN here always
// means "undefined for this signal's shape", never a numerical accident.
class FeatureValues {
 public:
  // Throws FeatureError on a duplicate name or a non-finite value.
  void add(const std::string& name, double value);
  // Adds `name` with the value NaN and the reason; throws FeatureError on a duplicate
  // name or an empty reason.
  void add_undefined(const std::string& name, const std::string& reason);
  std::size_t size() const { return names_.size(); }
  const std::vector<std::string>& names() const { return names_; }
  const std::vector<double>& values() const { return values_; }  // NaN for undefined features
  // The undefined features with their reasons, in the order of names().
  const std::vector<UndefinedFeature>& undefined() const { return undefined_; }
  bool has(const std::string& name) const;
  // The reason `name` is undefined; "" if it is defined (or absent).
  std::string undefined_reason(const std::string& name) const;
  // NaN for an undefined feature; throws FeatureError naming the features that exist
  // for a name that was not extracted at all.
  double at(const std::string& name) const;
  // The values of `names`, in that order (for a ForwardModel's feature vector); NaN
  // for undefined features, FeatureError for absent ones, as at().
  Eigen::VectorXd select(const std::vector<std::string>& names) const;

 private:
  std::vector<std::string> names_;
  std::vector<double> values_;
  std::vector<UndefinedFeature> undefined_;
};

// Under which condition the feature `name` is undefined for a valid signal, in general
// terms (the list above), e.g. "the electrode displacement does not rise after the weld
// start" for S_dot_exp; "" for features that are always defined and for names that are
// not features of this list. For reports that see only a stored NaN, such as a study's results
// or a calibration run; extract_features() gives the specific reason of one signal.
std::string why_undefined(const std::string& name);

// All features of this list that `signal` supports, then the `scalars` (nugget geometry, in
// the order given). Features that the curves' shapes leave undefined are NaN with their
// reason in undefined(); input errors throw FeatureError or SignalError with the reason.
FeatureValues extract_features(const Signal& signal, const FeatureSettings& settings = {},
                               const std::vector<std::pair<std::string, double>>& scalars = {});

}  // namespace rsw::calibration
