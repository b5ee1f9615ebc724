// Signals and features (calibration/signal.*, calibration/features.*): the
// Savitzky–Golay filter against its closed form, the weld-stage detection, and every
// feature group on synthetic welds whose curves are cubics in time, so the expected
// values follow analytically (the filter and the Hermite curve reproduce cubics
// exactly). Curves of unusual shape (resistance without interior peak, displacement
// that never rises, temperature still rising at the end) leave exactly the features
// that need the missing shape undefined (NaN with a reason), the others keep their
// closed-form values; input errors still throw. Also the CSV reader: units, errors,
// and like-for-like features.
#include "calibration/features.hpp"
#include "calibration/signal.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>

namespace rsw::calibration {
namespace {

// ---------------------------------------------------------------------------------
// A synthetic weld on a 0.5 ms raw grid from 0 to 130 ms. The current ramps over one
// millisecond around 10 ms and 110 ms, so with a 50 % threshold the weld stage is
// exactly [10, 110] ms. With τ = t − 10 ms:
//   R(τ) = R0 + k [s² (τ − τ_a) − (τ − τ_a)³ / 3]  steepest rise at τ_a, peak at τ_a + s
//   S(τ) = a0 + a1 τ + a2 τ² + a3 τ³
//   T(τ) = 20 + c τ² (3 τ_p − 2 τ) / τ_p³         peak c + 20 at τ_p
constexpr double raw_step = 0.5e-3;
constexpr double weld_start = 10e-3;
constexpr double weld_end = 110e-3;
constexpr double record_end = 130e-3;
constexpr double peak_current = 8e3;

struct ResistanceShape {
  double r0 = 150e-6;     // Ω
  double k = 0.9375;      // Ω/s³
  double tau_a = 30e-3;   // s
  double s = 40e-3;       // s
  double value(double tau) const {
    const double u = tau - tau_a;
    return r0 + k * (s * s * u - u * u * u / 3);
  }
  // ∫ R dτ
  double antiderivative(double tau) const {
    const double u = tau - tau_a;
    return r0 * tau + k * (s * s * u * u / 2 - u * u * u * u / 12);
  }
};

constexpr double s_coefficients[] = {2e-6, 0.9e-3, -5e-3, -4e-3};  // m, m/s, m/s², m/s³
double displacement(double tau) {
  return s_coefficients[0] + tau * (s_coefficients[1] + tau * (s_coefficients[2] + tau * s_coefficients[3]));
}

constexpr double temperature_rise = 1500;  // °C
constexpr double tau_temperature_peak = 100e-3;
double temperature(double tau) {
  const double p = tau_temperature_peak;
  return 20 + temperature_rise * tau * tau * (3 * p - 2 * tau) / (p * p * p);
}

double weld_current(double t) {
  auto ramp = [](double x) { return std::clamp(x, 0.0, 1.0); };
  return peak_current * ramp((t - 9.5e-3) / 1e-3) * ramp((110.5e-3 - t) / 1e-3);
}

struct SyntheticOptions {
  double step = raw_step;  // s, between raw samples
  bool voltage = true;  // else a resistance column
  bool displacement = true;
  bool temperature = true;
  std::function<double(double)> displacement_curve = ::rsw::calibration::displacement;  // S(τ) [m]
  std::function<double(double)> temperature_curve = ::rsw::calibration::temperature;    // T(τ) [°C]
};

// A weld whose dynamic resistance is R(τ), τ the time since the weld start.
Signal synthetic_weld(const std::function<double(double)>& resistance_curve, const SyntheticOptions& options = {}) {
  const int n = static_cast<int>(std::lround(record_end / options.step)) + 1;
  Eigen::VectorXd time(n), current(n), voltage(n), resistance(n), s(n), temp(n);
  for (int i = 0; i < n; ++i) {
    const double t = i * options.step;
    const double tau = t - weld_start;
    time[i] = t;
    current[i] = weld_current(t);
    resistance[i] = resistance_curve(tau);
    voltage[i] = resistance[i] * current[i];
    s[i] = options.displacement_curve(tau);
    temp[i] = options.temperature_curve(tau);
  }
  Signal signal(time);
  signal.add_column(signal_column::current, "A", current);
  if (options.voltage) {
    signal.add_column(signal_column::voltage, "V", voltage);
  } else {
    signal.add_column(signal_column::resistance, "ohm", resistance);
  }
  if (options.displacement) signal.add_column(signal_column::displacement, "m", s);
  if (options.temperature) signal.add_column(signal_column::temperature, "degC", temp);
  return signal;
}

Signal synthetic_weld(const ResistanceShape& shape, const SyntheticOptions& options = {}) {
  return synthetic_weld([shape](double tau) { return shape.value(tau); }, options);
}

// The closed forms below are for the values at the grid points (cell_means = false);
// the cell means of the default have their own tests ("CellMeans").
FeatureSettings half_current_threshold() {
  FeatureSettings settings;
  settings.weld_current_fraction = 0.5;
  settings.cell_means = false;
  return settings;
}

// Relative comparison for features of very different magnitudes.
void expect_relative(double actual, double expected, double tolerance, const std::string& what) {
  EXPECT_NEAR(actual, expected, tolerance * std::abs(expected)) << what;
}

// ---------------------------------------------------------------------------------

TEST(SavitzkyGolay, CubicWindow11CoefficientsMatchClosedForm) {
  const SavitzkyGolayFilter filter(11, 3);
  const double closed_form[] = {-36, 9, 44, 69, 84, 89, 84, 69, 44, 9, -36};
  const Eigen::VectorXd weights = filter.weights(0);
  ASSERT_EQ(weights.size(), 11);
  for (int j = 0; j < 11; ++j) EXPECT_NEAR(weights[j], closed_form[j] / 429, 1e-14) << "j = " << j;
}

TEST(SavitzkyGolay, CubicsPassUnchangedIncludingEdges) {
  const SavitzkyGolayFilter filter(11, 3);
  const double step = 0.25;
  const int n = 30;
  Eigen::VectorXd values(n), slopes(n);
  for (int i = 0; i < n; ++i) {
    const double x = i * step;
    values[i] = 1.5 - 2 * x + 0.7 * x * x - 0.09 * x * x * x;
    slopes[i] = -2 + 1.4 * x - 0.27 * x * x;
  }
  const Eigen::VectorXd smoothed = filter.smooth(values);
  const Eigen::VectorXd smoothed_slope = filter.slope(values, step);
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(smoothed[i], values[i], 1e-12) << "sample " << i;
    EXPECT_NEAR(smoothed_slope[i], slopes[i], 1e-11) << "sample " << i;
  }
}

TEST(SavitzkyGolay, QuarticIsNotPassedUnchanged) {
  // The filter is a cubic fit: a quartic shows that it really smooths.
  const SavitzkyGolayFilter filter(11, 3);
  Eigen::VectorXd values(21);
  for (int i = 0; i < 21; ++i) values[i] = std::pow(i - 10.0, 4);
  const Eigen::VectorXd smoothed = filter.smooth(values);
  // Centre value of the least-squares cubic through j⁴, j = −5..5: Σ w_j j⁴ = −4.3̅ ≠ 0.
  EXPECT_NEAR(smoothed[10], filter.weights(0).dot(values.segment(5, 11)), 1e-12);
  EXPECT_GT(std::abs(smoothed[10] - values[10]), 1.0);
}

TEST(SavitzkyGolay, TooShortSignalIsAnError) {
  const SavitzkyGolayFilter filter(11, 3);
  EXPECT_THROW(filter.smooth(Eigen::VectorXd::Ones(10)), SignalError);
  EXPECT_THROW(SavitzkyGolayFilter(10, 3), std::invalid_argument);
  EXPECT_THROW(SavitzkyGolayFilter(3, 3), std::invalid_argument);
}

TEST(Resampling, LinearInterpolationOntoGridAnchoredAtAGivenTime) {
  Signal signal((Eigen::VectorXd(4) << 0.0, 1.0, 1.5, 4.0).finished());
  signal.add_column("force", "N", (Eigen::VectorXd(4) << 0.0, 2.0, 3.0, 8.0).finished());
  // Anchor 0.25, step 1: grid 0.25, 1.25, 2.25, 3.25 inside [0, 4]; force is 2t.
  const Signal resampled = resample_uniform(signal, 1.0, 0.25);
  ASSERT_EQ(resampled.n_samples(), 4u);
  for (Eigen::Index k = 0; k < 4; ++k) {
    EXPECT_DOUBLE_EQ(resampled.time()[k], 0.25 + static_cast<double>(k));
    EXPECT_DOUBLE_EQ(resampled.column("force")[k], 2 * resampled.time()[k]);
  }
  EXPECT_EQ(resampled.unit("force"), "N");
  EXPECT_DOUBLE_EQ(median_step(signal.time()), 1.0);  // steps 1, 0.5, 2.5
  EXPECT_THROW(resample_uniform(signal, 0, 0), SignalError);
  EXPECT_THROW(Signal((Eigen::VectorXd(3) << 0.0, 1.0, 1.0).finished()), SignalError);
  EXPECT_THROW(signal.add_column("force", "N", Eigen::VectorXd::Zero(4)), SignalError);
  EXPECT_THROW(signal.column("voltage"), SignalError);
}

// x = {0, 2, 0, 4} at t = {0, 1, 2, 4}: over [0.5, 3] the trapezoids 0.5·1.5 + 1·1 + 1·1
// = 2.75, mean 1.1; over [−1, 0.5] (0 before the record) 0 + 0.5·0.5 = 0.25, mean 1/6;
// over [3, 6] (4 after it) 1·3 + 2·4 = 11, mean 11/3; a = b gives the value there.
TEST(AverageLinear, IsExactForThePiecewiseLinearSignalAndClampsOutsideTheRecord) {
  const Eigen::VectorXd t = (Eigen::VectorXd(4) << 0.0, 1.0, 2.0, 4.0).finished();
  const Eigen::VectorXd x = (Eigen::VectorXd(4) << 0.0, 2.0, 0.0, 4.0).finished();
  EXPECT_NEAR(average_linear(t, x, 0.5, 3.0), 1.1, 1e-15);
  EXPECT_NEAR(average_linear(t, x, -1.0, 0.5), 1.0 / 6, 1e-15);
  EXPECT_NEAR(average_linear(t, x, 3.0, 6.0), 11.0 / 3, 1e-15);
  EXPECT_DOUBLE_EQ(average_linear(t, x, 3.0, 3.0), 2.0);
}

// A drop from 1 to 0 between the samples at d and d + h (h = 1 ms) inside the cell
// [0, 1]: the mean is d + h/2, moving in proportion to d, where the value at a grid
// point jumps from 1 to 0 as the drop passes it.
TEST(AverageLinear, ADropInsideTheCellMovesTheMeanInProportionToItsPosition) {
  const int n = 2001;
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, -0.5, 1.5);  // h = 1e-3
  for (const double d : {0.2, 0.5, 0.7}) {
    const Eigen::VectorXd x = t.unaryExpr([d](double ti) { return ti <= d + 1e-9 ? 1.0 : 0.0; });
    EXPECT_NEAR(average_linear(t, x, 0.0, 1.0), d + 0.5e-3, 1e-12) << d;
  }
}

// sin(2π t/P) sampled 20 times a period: its interpolant is P-periodic, so its mean over
// any window of one period is that over [0, P], the trapezoid sum of a full period: 0.
TEST(AverageLinear, ARippleWhosePeriodIsTheWindowAveragesOut) {
  const double period = 1e-3;
  const int n = 201;
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 0.0, 10 * period);
  const Eigen::VectorXd x = t.unaryExpr([&](double ti) { return std::sin(2 * M_PI * ti / period); });
  for (const double a : {0.0, 1.23e-3, 4.5678e-3}) EXPECT_NEAR(average_linear(t, x, a, a + period), 0.0, 1e-13) << a;
}

// The Savitzky–Golay window counts samples, so the grid the signals are resampled on
// sets the span it smooths over. With the fixed 1 ms grid a weld sampled every 0.25 ms
// and the same weld sampled every 0.05 ms give the same features (with the 50 %
// current threshold the weld starts at 10 ms, a sample of both, and so is every grid
// point after it); with
// each signal's own step as the grid (0.05 ms: 0.55 ms window; 0.25 ms: 2.75 ms) a
// sharp resistance peak, a Gaussian of 1.5 ms width on a falling line here, is
// flattened by different amounts.
TEST(Features, OfOneWeldDoNotDependOnHowFinelyItIsSampled) {
  auto sampled_every = [](double step) {
    const int n = static_cast<int>(std::lround(record_end / step)) + 1;
    Eigen::VectorXd time(n), current(n), resistance(n);
    for (int i = 0; i < n; ++i) {
      time[i] = i * step;
      current[i] = weld_current(time[i]);
      const double x = (time[i] - weld_start - 20e-3) / 1.5e-3;
      resistance[i] = 150e-6 + 100e-6 * std::exp(-x * x) - 0.2e-3 * (time[i] - weld_start);
    }
    Signal signal(time);
    signal.add_column(signal_column::current, "A", current);
    signal.add_column(signal_column::resistance, "ohm", resistance);
    return signal;
  };
  const Signal coarse = sampled_every(0.25e-3), fine = sampled_every(0.05e-3);
  const FeatureSettings grid = half_current_threshold();  // and the default 1 ms grid
  EXPECT_DOUBLE_EQ(grid.resample_step, 1e-3);
  const FeatureValues a = extract_features(coarse, grid), b = extract_features(fine, grid);
  for (const char* name : {feature_name::resistance_beta, feature_name::time_beta, feature_name::resistance_alpha,
                           feature_name::resistance_mean}) {
    EXPECT_NEAR(a.at(name), b.at(name), 1e-9 * std::abs(a.at(name))) << name;
  }
  // The 1 ms grid's 11 ms window flattens the peak (246 µΩ at 20 ms after the weld
  // start) but keeps it above the line under it (146 µΩ there).
  EXPECT_LT(a.at(feature_name::resistance_beta), 246e-6);
  EXPECT_GT(a.at(feature_name::resistance_beta), 146e-6);
  FeatureSettings own_step = half_current_threshold();
  own_step.resample_step = 0;  // each signal's median step
  const double coarse_own = extract_features(coarse, own_step).at(feature_name::resistance_beta);
  const double fine_own = extract_features(fine, own_step).at(feature_name::resistance_beta);
  EXPECT_GT(std::abs(fine_own - coarse_own), 0.005 * fine_own) << fine_own << " " << coarse_own;
}

// y = −(t − 0.37)² (t − 2) = −t³ + 2.74 t² − 1.6169 t + 0.2738: critical points where
// 3t² − 5.48 t + 1.6169 = 0, a minimum at 0.37 and a maximum at 4.37/3.
double cubic_y(double t) { return -(t - 0.37) * (t - 0.37) * (t - 2); }
double cubic_dy(double t) { return -(2 * (t - 0.37) * (t - 2) + (t - 0.37) * (t - 0.37)); }

// The cubic's exact values and slopes at t = 0, 0.1, … (n samples).
SmoothCurve cubic_curve(int n) {
  const double step = 0.1;
  Eigen::VectorXd values(n), slopes(n);
  for (int i = 0; i < n; ++i) {
    values[i] = cubic_y(i * step);
    slopes[i] = cubic_dy(i * step);
  }
  return SmoothCurve(0, step, values, slopes);
}

TEST(SmoothCurve, ReproducesCubicBetweenSamplesWithExtremaOffTheGrid) {
  auto y = cubic_y;
  auto dy = cubic_dy;
  const SmoothCurve curve = cubic_curve(18);
  EXPECT_NEAR(curve.value(0.537), y(0.537), 1e-14);
  EXPECT_NEAR(curve.slope(1.234), dy(1.234), 1e-13);
  const double root = (5.48 + std::sqrt(5.48 * 5.48 - 12 * 1.6169)) / 6;  // the maximum
  // Over [0.5, 1.49] the maximum is the interior critical point, between samples.
  const CurvePoint peak = curve.trimmed(0.5, 1.49).maximum();
  EXPECT_NEAR(peak.time, root, 1e-12);
  EXPECT_NEAR(peak.value, y(root), 1e-14);
  // Mean over [0.25, 1.05] of the cubic, by its antiderivative.
  auto integral = [](double t) {
    return -t * t * t * t / 4 + 2.74 * t * t * t / 3 - 1.6169 * t * t / 2 + 0.2738 * t;
  };
  EXPECT_NEAR(curve.trimmed(0.25, 1.05).mean(), (integral(1.05) - integral(0.25)) / 0.8, 1e-13);
  EXPECT_THROW(curve.trimmed(-0.1, 0.5), SignalError);
}

TEST(SmoothCurve, FirstMinimumEndsAFallingStartAndIsAbsentWhenTheCurveOnlyFalls) {
  // The cubic above falls on [0, 0.37), has its minimum at 0.37 (between samples 0.3
  // and 0.4), rises to 4.37/3 and falls after it.
  const SmoothCurve curve = cubic_curve(25);
  const std::optional<CurvePoint> valley = curve.first_minimum();
  ASSERT_TRUE(valley.has_value());
  EXPECT_NEAR(valley->time, 0.37, 1e-12);
  EXPECT_NEAR(valley->value, 0.0, 1e-14);
  // Rising at its start: the start itself.
  const std::optional<CurvePoint> rising = curve.trimmed(0.6, 2.0).first_minimum();
  ASSERT_TRUE(rising.has_value());
  EXPECT_DOUBLE_EQ(rising->time, 0.6);
  // Falling over the whole domain [1.6, 2.4] (after the maximum at 4.37/3): none.
  EXPECT_FALSE(curve.trimmed(1.6, 2.4).first_minimum().has_value());
}

TEST(WeldStage, CrossingTimesAreInterpolatedBetweenSamples) {
  const Signal signal = synthetic_weld(ResistanceShape{});
  const WeldStage half = find_weld_stage(signal, 0.5);
  EXPECT_NEAR(half.start, weld_start, 1e-15);
  EXPECT_NEAR(half.end, weld_end, 1e-15);
  EXPECT_DOUBLE_EQ(half.peak_current, peak_current);
  // 10 % of the peak is crossed 0.1 ms into the 1 ms ramps, between raw samples.
  const WeldStage tenth = find_weld_stage(signal, 0.1);
  EXPECT_NEAR(tenth.start, 9.6e-3, 1e-15);
  EXPECT_NEAR(tenth.end, 110.4e-3, 1e-15);
}

TEST(WeldStage, SignalWithoutCurrentPulseIsAnError) {
  Eigen::VectorXd time = Eigen::VectorXd::LinSpaced(50, 0, 49e-3);
  Signal zero(time);
  zero.add_column(signal_column::current, "A", Eigen::VectorXd::Zero(50));
  EXPECT_THROW(find_weld_stage(zero, 0.1), FeatureError);
  Signal constant(time);
  constant.add_column(signal_column::current, "A", Eigen::VectorXd::Constant(50, 8e3));
  try {
    find_weld_stage(constant, 0.1);
    FAIL() << "constant current accepted as a pulse";
  } catch (const FeatureError& error) {
    EXPECT_NE(std::string(error.what()).find("no current pulse"), std::string::npos) << error.what();
  }
  Signal no_current(time);
  no_current.add_column(signal_column::voltage, "V", Eigen::VectorXd::Ones(50));
  EXPECT_THROW(extract_features(no_current), FeatureError);
}

TEST(DynamicResistance, FeaturesOfCubicCurveMatchClosedForm) {
  const ResistanceShape shape;
  const FeatureValues features = extract_features(synthetic_weld(shape), half_current_threshold());
  const double t_alpha = shape.tau_a;
  const double t_beta = shape.tau_a + shape.s;
  const double t_gamma = (weld_end - weld_start) - 2e-3;
  const double r_alpha = shape.value(t_alpha);
  const double r_beta = shape.value(t_beta);
  const double r_gamma = shape.value(t_gamma);
  const double tolerance = 1e-9;
  namespace f = feature_name;
  EXPECT_NEAR(features.at(f::time_alpha), t_alpha, 1e-9);
  EXPECT_NEAR(features.at(f::time_beta), t_beta, 1e-9);
  EXPECT_NEAR(features.at(f::time_gamma), t_gamma, 1e-12);
  expect_relative(features.at(f::resistance_alpha), r_alpha, tolerance, "R_alpha");
  expect_relative(features.at(f::resistance_beta), r_beta, tolerance, "R_beta");
  expect_relative(features.at(f::resistance_gamma), r_gamma, tolerance, "R_gamma");
  expect_relative(features.at(f::slope_before_peak), (r_beta - r_alpha) / (t_beta - t_alpha),
                  tolerance, "m_1");
  expect_relative(features.at(f::slope_after_peak), (r_gamma - r_beta) / (t_gamma - t_beta),
                  tolerance, "m_2");
  const double t_s = 2e-3;
  expect_relative(features.at(f::resistance_mean),
                  (shape.antiderivative(t_gamma) - shape.antiderivative(t_s)) / (t_gamma - t_s),
                  tolerance, "R_m");
  expect_relative(features.at(f::resistance_rise), r_beta - r_alpha, tolerance, "dR_1");
  expect_relative(features.at(f::resistance_drop), r_gamma - r_beta, tolerance, "dR_2");
  EXPECT_EQ(features.names().front(), f::resistance_alpha);
}

// Cell means of the default: for a cubic R sampled every h, the mean of the linear
// interpolant over a cell of width Δ centred on t_k is exactly
//   R(t_k) + c R''(t_k),  c = Δ²/24 (the cell) + h²/12 (the trapezoids),
// itself a cubic, which the filter and the Hermite curve pass unchanged away from the
// two end values (point values). R̃ = R + cR'' = r0 + k(s²u − u³/3 − 2cu), u = τ − τ_a:
// its peak is at u = √(s² − 2c), its steepest rise still at u = 0 with R̃ = r0.
TEST(CellMeans, OfACubicResistanceAddTheCurvatureOfTheCellAndOfTheSampling) {
  const ResistanceShape shape;
  FeatureSettings settings;
  settings.weld_current_fraction = 0.5;
  ASSERT_TRUE(settings.cell_means);
  const FeatureValues features = extract_features(synthetic_weld(shape), settings);
  const double c = 1e-6 / 24 + raw_step * raw_step / 12;
  const double u = std::sqrt(shape.s * shape.s - 2 * c);
  const double r_beta = shape.r0 + shape.k * (shape.s * shape.s * u - u * u * u / 3 - 2 * c * u);
  namespace f = feature_name;
  EXPECT_NEAR(features.at(f::time_beta), shape.tau_a + u, 1e-9);
  expect_relative(features.at(f::resistance_beta), r_beta, 1e-9, "R_beta");
  EXPECT_NEAR(features.at(f::time_alpha), shape.tau_a, 1e-9);
  expect_relative(features.at(f::resistance_alpha), shape.r0, 1e-9, "R_alpha");
  // The shift is real: the values at the grid points give R(τ_a + s).
  EXPECT_GT(std::abs(r_beta - shape.value(shape.tau_a + shape.s)), 1e-6 * r_beta);
}

// Inverter ripple on R: 1 kHz, 20 µΩ, sampled every 0.05 ms. Cell means over the 1 ms
// grid average it out of every interior value, so the peak and inflection features
// equal the ripple-free weld's; the values at the grid points see sin(φ) of every
// period, a constant offset A sin φ on R_β (aliasing).
TEST(CellMeans, InverterRippleAtTheGridFrequencyLeavesThePeakFeaturesUnmoved) {
  const ResistanceShape shape;
  const double amplitude = 20e-6, phase = 0.3;
  SyntheticOptions fine;
  fine.step = 0.05e-3;
  const Signal clean = synthetic_weld(shape, fine);
  const Signal ripple = synthetic_weld(
      [&](double tau) { return shape.value(tau) + amplitude * std::sin(2 * M_PI * 1e3 * tau + phase); }, fine);
  FeatureSettings means;
  means.weld_current_fraction = 0.5;
  namespace f = feature_name;
  const FeatureValues a = extract_features(clean, means), b = extract_features(ripple, means);
  for (const char* name : {f::resistance_beta, f::time_beta, f::resistance_alpha, f::time_alpha})
    EXPECT_NEAR(b.at(name), a.at(name), 1e-9 * std::abs(a.at(name))) << name;
  const FeatureSettings points = half_current_threshold();
  const double offset = extract_features(ripple, points).at(f::resistance_beta) -
                        extract_features(clean, points).at(f::resistance_beta);
  EXPECT_NEAR(offset, amplitude * std::sin(phase), 1e-3 * amplitude);
}

TEST(DynamicResistance, InflectionAndPeakTimesAreNotQuantisedToTheSampleGrid) {
  // Shifting the curve by 0.13 ms (a quarter of a sample step and more) shifts t_alpha
  // and t_beta by exactly that, not by whole samples.
  ResistanceShape shifted;
  shifted.tau_a += 0.13e-3;
  const FeatureValues base = extract_features(synthetic_weld(ResistanceShape{}), half_current_threshold());
  const FeatureValues moved = extract_features(synthetic_weld(shifted), half_current_threshold());
  namespace f = feature_name;
  EXPECT_NEAR(moved.at(f::time_alpha) - base.at(f::time_alpha), 0.13e-3, 1e-9);
  EXPECT_NEAR(moved.at(f::time_beta) - base.at(f::time_beta), 0.13e-3, 1e-9);
  EXPECT_NEAR(moved.at(f::resistance_beta), base.at(f::resistance_beta), 1e-9 * base.at(f::resistance_beta));
}

TEST(DynamicResistance, MeasurementNoiseMovesPeakEndAndMeanFeaturesOnlySlightly) {
  // 0.5 µΩ white noise on the voltage-derived resistance (a 40 µΩ rise): the smoothed
  // peak, end and mean stay within a few tenths of a µΩ. The peak is flat, R'' = −2ks =
  // −0.075 Ω/s², so smoothed noise of σ√(89/429) ≈ 0.23 µΩ moves its time by up to
  // about √(2·0.23 µΩ/0.075 Ω/s²) ≈ 2.5 ms: times are the noise-sensitive features.
  const ResistanceShape shape;
  Signal clean = synthetic_weld(shape);
  std::mt19937_64 rng(99);
  std::normal_distribution<double> noise(0, 0.5e-6);
  Eigen::VectorXd voltage = clean.column(signal_column::voltage);
  const Eigen::VectorXd& current = clean.column(signal_column::current);
  for (Eigen::Index i = 0; i < voltage.size(); ++i) voltage[i] += noise(rng) * current[i];
  Signal noisy(clean.time());
  noisy.add_column(signal_column::current, "A", current);
  noisy.add_column(signal_column::voltage, "V", voltage);
  const FeatureValues a = extract_features(clean, half_current_threshold());
  const FeatureValues b = extract_features(noisy, half_current_threshold());
  namespace f = feature_name;
  EXPECT_NEAR(b.at(f::resistance_beta), a.at(f::resistance_beta), 0.4e-6);
  EXPECT_NEAR(b.at(f::resistance_gamma), a.at(f::resistance_gamma), 0.4e-6);
  EXPECT_NEAR(b.at(f::resistance_mean), a.at(f::resistance_mean), 0.1e-6);
  EXPECT_NEAR(b.at(f::time_beta), a.at(f::time_beta), 5e-3);
  EXPECT_LT(b.at(f::time_alpha), b.at(f::time_beta));
}

TEST(DynamicResistance, ResistanceColumnGivesTheSameFeaturesAsVoltage) {
  SyntheticOptions from_resistance;
  from_resistance.voltage = false;
  const FeatureValues a = extract_features(synthetic_weld(ResistanceShape{}), half_current_threshold());
  const FeatureValues b =
      extract_features(synthetic_weld(ResistanceShape{}, from_resistance), half_current_threshold());
  ASSERT_EQ(a.names(), b.names());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a.values()[i], b.values()[i], 1e-9 * std::abs(a.values()[i]) + 1e-15) << a.names()[i];
  }
}

// The features without a definition when R has no interior peak, and the others.
const std::vector<std::string> peak_features = {"R_beta", "t_beta", "R_alpha", "t_alpha",
                                                "m_1",    "m_2",    "dR_1",    "dR_2"};

std::vector<std::string> undefined_names(const FeatureValues& features) {
  std::vector<std::string> names;
  for (const auto& entry : features.undefined()) names.push_back(entry.name);
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string> sorted(std::vector<std::string> names) {
  std::sort(names.begin(), names.end());
  return names;
}

TEST(DynamicResistance, FallingResistanceLeavesPeakFeaturesUndefinedWithReasonAndKeepsEndAndMean) {
  // Steepest rise at τ = −50 ms and peak at −10 ms, before the weld: over the weld stage
  // R falls monotonically from about 152 to 108 µΩ.
  ResistanceShape falling;
  falling.k = 0.05;
  falling.tau_a = -50e-3;
  const FeatureValues features = extract_features(synthetic_weld(falling), half_current_threshold());
  namespace f = feature_name;
  EXPECT_EQ(undefined_names(features), sorted(peak_features));
  for (const auto& name : peak_features) {
    EXPECT_TRUE(std::isnan(features.at(name))) << name;
    const std::string reason = features.undefined_reason(name);
    EXPECT_NE(reason.find("the dynamic resistance has no peak inside the trimmed weld stage [2 ms, 98 ms]"),
              std::string::npos) << name << ": " << reason;
    EXPECT_NE(reason.find("it falls over the whole stage"), std::string::npos) << reason;
    EXPECT_EQ(reason.rfind(why_undefined(f::resistance_beta), 0), 0u) << reason;  // the general condition first
  }
  // R_gamma, t_gamma and R_m do not need a peak: their closed-form values.
  const double t_gamma = (weld_end - weld_start) - 2e-3, t_s = 2e-3;
  expect_relative(features.at(f::resistance_gamma), falling.value(t_gamma), 1e-9, "R_gamma");
  EXPECT_NEAR(features.at(f::time_gamma), t_gamma, 1e-12);
  expect_relative(features.at(f::resistance_mean),
                  (falling.antiderivative(t_gamma) - falling.antiderivative(t_s)) / (t_gamma - t_s), 1e-9, "R_m");
  // The order of the names does not change; select() gives NaN in place.
  EXPECT_EQ(features.names().front(), f::resistance_alpha);
  const Eigen::VectorXd selected = features.select({f::resistance_gamma, f::resistance_beta, f::temperature_max});
  EXPECT_TRUE(std::isfinite(selected[0]));
  EXPECT_TRUE(std::isnan(selected[1]));
  EXPECT_TRUE(std::isfinite(selected[2]));
  // The other groups are untouched.
  EXPECT_TRUE(std::isfinite(features.at(f::displacement_expansion_rate)));
  EXPECT_TRUE(std::isfinite(features.at(f::cooling_rate)));
}

TEST(DynamicResistance, PeakBelowAFallingStartIsTheMaximumAfterTheFirstMinimum) {
  // R = r0 + k (s² u − u³/3), u = τ − τ_a: minimum at u = −s, peak r0 + (2/3) k s³ at
  // u = s, steepest rise r0 at u = 0. With s = 20 ms and τ_a = 50 ms the window
  // [2, 98] ms starts at u = −48 ms < −2s, where R is above the peak (R(−2s) equals
  // it): a cold start resistance above the β peak, common on real welds. The cubic
  // passes the smoothing unchanged, so the features take their closed-form values.
  ResistanceShape dip;
  dip.s = 20e-3;
  dip.tau_a = 50e-3;
  const FeatureValues features = extract_features(synthetic_weld(dip), half_current_threshold());
  namespace f = feature_name;
  ASSERT_GT(dip.value(2e-3), dip.value(dip.tau_a + dip.s));  // the start lies above the peak
  EXPECT_TRUE(features.undefined().empty());
  const double r_beta = dip.r0 + 2.0 / 3.0 * dip.k * dip.s * dip.s * dip.s;
  expect_relative(features.at(f::resistance_beta), r_beta, 1e-9, "R_beta");
  EXPECT_NEAR(features.at(f::time_beta), dip.tau_a + dip.s, 1e-9);
  expect_relative(features.at(f::resistance_alpha), dip.r0, 1e-9, "R_alpha");
  EXPECT_NEAR(features.at(f::time_alpha), dip.tau_a, 1e-9);
  expect_relative(features.at(f::resistance_rise), r_beta - dip.r0, 1e-8, "dR_1");
}

TEST(DynamicResistance, OfSeveralPeaksTheHighestIsBetaNotTheFirst) {
  // R = r0 + a sin(2πτ/T) + bτ, T = 40 ms: peaks near τ = 10, 50 and 90 ms, each bT =
  // 80 µΩ above the one before, inside the window [2, 98] ms. R rises at 2 ms, so β is
  // the window's maximum, the last peak. The smoothing (cubic, 11 samples of 1 ms)
  // passes bτ and scales the sine by g = Σ_k c_k cos(kω), ω = 2π · 1 ms/T,
  // c_k = (267 − 15k²)/1287 (k = −5…5). Then R' = 0 at τ* = 90 ms + (T/2π) δ with
  // sin δ = bT/(2π g a), and R_β = r0 + g a cos δ + bτ*.
  const double r0 = 150e-6, a = 50e-6, b = 2e-3, period = 40e-3;
  const Signal weld = synthetic_weld(
      [&](double tau) { return r0 + a * std::sin(2 * M_PI * tau / period) + b * tau; });
  const FeatureValues features = extract_features(weld, half_current_threshold());
  namespace f = feature_name;
  double gain = 0;
  for (int k = -5; k <= 5; ++k) gain += (267.0 - 15.0 * k * k) / 1287.0 * std::cos(k * 2 * M_PI * 1e-3 / period);
  const double delta = std::asin(b * period / (2 * M_PI * gain * a));
  const double t_beta = 90e-3 + period / (2 * M_PI) * delta;
  EXPECT_NEAR(features.at(f::time_beta), t_beta, 0.05e-3);
  EXPECT_NEAR(features.at(f::resistance_beta), r0 + gain * a * std::cos(delta) + b * t_beta, 0.01e-6);
}

// Expulsion: molten metal leaves the nugget and R drops at once, here by D = 30 µΩ at
// τ_x = 85 ms, after the cubic's peak at 70 ms. The drop reaches the smoothed curve
// only through the grid values whose cells it falls in or after (τ ≥ 84.5 ms) and the
// filter's half-width of 5 samples, so the peak and the inflection keep their
// closed-form values (point values, exact) and R_γ at 98 ms, more than 5.5 ms after
// the drop, is R(98 ms) − D.
TEST(DynamicResistance, ExpulsionDropAfterThePeakLowersOnlyTheEndResistance) {
  const ResistanceShape shape;
  const double drop = 30e-6, tau_x = 85e-3;
  const Signal weld = synthetic_weld([&](double tau) { return shape.value(tau) - (tau > tau_x ? drop : 0.0); });
  namespace f = feature_name;
  const FeatureValues features = extract_features(weld, half_current_threshold());
  expect_relative(features.at(f::resistance_beta), shape.value(shape.tau_a + shape.s), 1e-9, "R_beta");
  EXPECT_NEAR(features.at(f::time_beta), shape.tau_a + shape.s, 1e-9);
  expect_relative(features.at(f::resistance_alpha), shape.r0, 1e-9, "R_alpha");
  expect_relative(features.at(f::resistance_gamma), shape.value(98e-3) - drop, 1e-9, "R_gamma");
  // The cell means of the default see the same: the drop's cells lie after 79.5 ms.
  FeatureSettings means;
  means.weld_current_fraction = 0.5;
  const FeatureValues averaged = extract_features(weld, means);
  const FeatureValues clean = extract_features(synthetic_weld(shape), means);
  EXPECT_NEAR(averaged.at(f::resistance_beta), clean.at(f::resistance_beta), 1e-9 * clean.at(f::resistance_beta));
  EXPECT_NEAR(averaged.at(f::resistance_gamma), clean.at(f::resistance_gamma) - drop, 1e-9 * clean.at(f::resistance_gamma));
}

// A flat curve (a weld whose resistance does not change) has no peak: β and the
// features built on it are undefined with the reason, γ and the mean are the value.
TEST(DynamicResistance, FlatCurveHasNoPeakAndKeepsItsValue) {
  const double r0 = 120e-6;
  const FeatureValues features = extract_features(synthetic_weld([&](double) { return r0; }), FeatureSettings{});
  namespace f = feature_name;
  EXPECT_TRUE(std::isnan(features.at(f::resistance_beta)));
  EXPECT_NE(features.undefined_reason(f::resistance_beta).find("no peak"), std::string::npos)
      << features.undefined_reason(f::resistance_beta);
  EXPECT_NEAR(features.at(f::resistance_gamma), r0, 1e-15);
  EXPECT_NEAR(features.at(f::resistance_mean), r0, 1e-15);
}

// White logger noise of sd σ = 10 µΩ sampled at 50 kHz (h = 0.02 ms; 5 kHz and above):
// a cell mean of the 50 samples in 1 ms has sd ≈ σ/√50, the filter's value at a point
// sd √(89/429) of that, so R_β moves by at most 4 · 0.46 σ/√50 ≈ 2.6 µΩ (4 sd) from
// the clean curve's; point values keep sd 0.46 σ per smoothed value, and the peak of a
// noisy curve is biased upwards.
TEST(CellMeans, WhiteNoiseAtFiftyKilohertzMovesThePeakByLessThanItsAveragedSpread) {
  const ResistanceShape shape;
  const double sigma = 10e-6;
  SyntheticOptions fine;
  fine.step = 0.02e-3;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, sigma);
  std::map<long, double> draws;  // one draw per raw sample time
  const Signal noisy = synthetic_weld(
      [&](double tau) {
        const long i = std::lround(tau / fine.step);
        auto it = draws.find(i);
        if (it == draws.end()) it = draws.emplace(i, noise(rng)).first;
        return shape.value(tau) + it->second;
      },
      fine);
  FeatureSettings means;
  means.weld_current_fraction = 0.5;
  namespace f = feature_name;
  const double clean = extract_features(synthetic_weld(shape, fine), means).at(f::resistance_beta);
  const double averaged = extract_features(noisy, means).at(f::resistance_beta);
  EXPECT_LT(std::abs(averaged - clean), 4 * std::sqrt(89.0 / 429.0) * sigma / std::sqrt(50.0));
}

TEST(DynamicResistance, ResistanceStillRisingAtTheEndHasNoPeakAndSaysSo) {
  // Minimum at −10 ms, steepest rise at 50 ms, peak at 110 ms: R rises over the whole
  // trimmed weld stage [2, 98] ms, from about 109 to 191 µΩ.
  ResistanceShape rising;
  rising.k = 0.3;
  rising.tau_a = 50e-3;
  rising.s = 60e-3;
  const FeatureValues features = extract_features(synthetic_weld(rising), half_current_threshold());
  EXPECT_EQ(undefined_names(features), sorted(peak_features));
  const std::string reason = features.undefined_reason(feature_name::resistance_beta);
  EXPECT_NE(reason.find("no peak"), std::string::npos) << reason;
  EXPECT_NE(reason.find("its maximum is at the end: it still rises at the end"), std::string::npos) << reason;
  expect_relative(features.at(feature_name::resistance_gamma), rising.value((weld_end - weld_start) - 2e-3), 1e-9,
                  "R_gamma");
  EXPECT_TRUE(std::isfinite(features.at(feature_name::resistance_mean)));
}

TEST(Displacement, FeaturesOfCubicCurveMatchClosedForm) {
  const FeatureValues features = extract_features(synthetic_weld(ResistanceShape{}), half_current_threshold());
  // Peak: S'(τ) = a1 + 2 a2 τ + 3 a3 τ² = 0, positive root.
  const double a1 = s_coefficients[1], a2 = s_coefficients[2], a3 = s_coefficients[3];
  const double tau_peak = (-2 * a2 - std::sqrt(4 * a2 * a2 - 12 * a3 * a1)) / (6 * a3);
  ASSERT_GT(tau_peak, 2e-3);
  ASSERT_LT(tau_peak, record_end - weld_start);
  const double t_s = 2e-3;
  const double tau_end = record_end - weld_start;
  const double s_0 = displacement(t_s);
  // Least-squares slope over [t_s, τ_peak]: 12 ∫ (τ − τ̄) S dτ / L³, integrated exactly:
  // ∫ (τ − τ̄) τ^j dτ = [τ^(j+2)/(j+2) − τ̄ τ^(j+1)/(j+1)].
  const double length = tau_peak - t_s;
  const double mid = 0.5 * (tau_peak + t_s);
  double moment = 0;
  for (int j = 0; j < 4; ++j) {
    auto primitive = [&](double tau) {
      return std::pow(tau, j + 2) / (j + 2) - mid * std::pow(tau, j + 1) / (j + 1);
    };
    moment += s_coefficients[j] * (primitive(tau_peak) - primitive(t_s));
  }
  const double fitted_slope = 12 * moment / (length * length * length);
  namespace f = feature_name;
  expect_relative(features.at(f::displacement_peak_expansion), displacement(tau_peak) - s_0, 1e-9, "dS_P");
  expect_relative(features.at(f::displacement_end), displacement(tau_end), 1e-9, "S_end");
  expect_relative(features.at(f::displacement_net), displacement(tau_end) - s_0, 1e-9, "dS_net");
  expect_relative(features.at(f::displacement_expansion_rate), fitted_slope, 1e-9, "S_dot_exp");
}

TEST(Temperature, FeaturesOfCubicCurveMatchClosedForm) {
  const FeatureValues features = extract_features(synthetic_weld(ResistanceShape{}), half_current_threshold());
  const double tau_end = record_end - weld_start;
  const double t_max = 20 + temperature_rise;
  namespace f = feature_name;
  expect_relative(features.at(f::temperature_max), t_max, 1e-12, "T_max");
  EXPECT_NEAR(features.at(f::time_temperature_max), tau_temperature_peak, 1e-9);
  expect_relative(features.at(f::temperature_end), temperature(tau_end), 1e-12, "T_end");
  expect_relative(features.at(f::cooling_rate),
                  (temperature(tau_end) - t_max) / (tau_end - tau_temperature_peak), 1e-9, "T_dot_cool");
}

TEST(Displacement, CurveThatNeverRisesHasUndefinedExpansionRateAndZeroPeakExpansion) {
  // S falls linearly from the weld start: no expansion phase. dS_P = 0 is a value (no
  // expansion), S_end and dS_net are defined, the rate of an empty phase is not.
  SyntheticOptions options;
  options.displacement_curve = [](double tau) { return 2e-6 - 0.2e-3 * tau; };
  const FeatureValues features = extract_features(synthetic_weld(ResistanceShape{}, options), half_current_threshold());
  namespace f = feature_name;
  const double tau_end = record_end - weld_start, t_s = 2e-3;
  EXPECT_EQ(undefined_names(features), std::vector<std::string>{f::displacement_expansion_rate});
  EXPECT_TRUE(std::isnan(features.at(f::displacement_expansion_rate)));
  const std::string reason = features.undefined_reason(f::displacement_expansion_rate);
  EXPECT_EQ(reason.rfind(why_undefined(f::displacement_expansion_rate), 0), 0u) << reason;
  EXPECT_NE(reason.find("is at 2 ms"), std::string::npos) << reason;
  EXPECT_EQ(features.at(f::displacement_peak_expansion), 0.0);
  expect_relative(features.at(f::displacement_end), 2e-6 - 0.2e-3 * tau_end, 1e-9, "S_end");
  expect_relative(features.at(f::displacement_net), -0.2e-3 * (tau_end - t_s), 1e-9, "dS_net");
  EXPECT_TRUE(std::isfinite(features.at(f::resistance_beta)));  // the other groups keep their values
  EXPECT_TRUE(std::isfinite(features.at(f::cooling_rate)));
}

TEST(Temperature, TemperatureStillRisingAtTheEndHasUndefinedCoolingRateOnly) {
  // The cubic of the synthetic weld with its peak at 200 ms, after the record end (120 ms
  // after the weld start): T rises to the last sample.
  SyntheticOptions options;
  const auto rising = [](double tau) {
    const double p = 200e-3;
    return 20 + temperature_rise * tau * tau * (3 * p - 2 * tau) / (p * p * p);
  };
  options.temperature_curve = rising;
  const FeatureValues features = extract_features(synthetic_weld(ResistanceShape{}, options), half_current_threshold());
  namespace f = feature_name;
  const double tau_end = record_end - weld_start;
  EXPECT_EQ(undefined_names(features), std::vector<std::string>{f::cooling_rate});
  const std::string reason = features.undefined_reason(f::cooling_rate);
  EXPECT_NE(reason.find("the sheet temperature peaks at the end of the record, 120 ms after the weld start"),
            std::string::npos) << reason;
  expect_relative(features.at(f::temperature_max), rising(tau_end), 1e-12, "T_max");
  EXPECT_NEAR(features.at(f::time_temperature_max), tau_end, 1e-12);
  expect_relative(features.at(f::temperature_end), rising(tau_end), 1e-12, "T_end");
  EXPECT_TRUE(std::isfinite(features.at(f::resistance_beta)));
  EXPECT_TRUE(std::isfinite(features.at(f::displacement_expansion_rate)));
}

TEST(Features, UndefinedFeatureIsNaNWithItsReasonAndKeepsItsPlace) {
  FeatureValues features;
  features.add("a", 1.0);
  features.add_undefined("b", "no peak");
  features.add("c", 3.0);
  EXPECT_EQ(features.names(), (std::vector<std::string>{"a", "b", "c"}));
  ASSERT_EQ(features.undefined().size(), 1u);
  EXPECT_EQ(features.undefined()[0].name, "b");
  EXPECT_EQ(features.undefined()[0].reason, "no peak");
  EXPECT_EQ(features.undefined_reason("b"), "no peak");
  EXPECT_EQ(features.undefined_reason("a"), "");
  EXPECT_TRUE(std::isnan(features.at("b")));
  EXPECT_TRUE(std::isnan(features.values()[1]));
  const Eigen::VectorXd selected = features.select({"c", "b"});
  EXPECT_EQ(selected[0], 3.0);
  EXPECT_TRUE(std::isnan(selected[1]));
  EXPECT_THROW(features.select({"d"}), FeatureError);  // absent is still an error
  EXPECT_THROW(features.add_undefined("a", "again"), FeatureError);
  EXPECT_THROW(features.add_undefined("e", ""), FeatureError);  // a NaN always has a reason
  EXPECT_THROW(features.add("f", std::numeric_limits<double>::quiet_NaN()), FeatureError);
  EXPECT_THROW(features.add("g", std::numeric_limits<double>::infinity()), FeatureError);
}

TEST(Features, WhyUndefinedNamesTheConditionOfExactlyTheShapeDependentFeatures) {
  std::vector<std::string> conditional;
  for (const auto* group : {&resistance_feature_names(), &displacement_feature_names(), &temperature_feature_names(),
                            &nugget_feature_names()}) {
    for (const auto& name : *group) {
      if (!why_undefined(name).empty()) conditional.push_back(name);
    }
  }
  std::vector<std::string> expected = peak_features;
  expected.push_back(feature_name::displacement_expansion_rate);
  expected.push_back(feature_name::cooling_rate);
  EXPECT_EQ(sorted(conditional), sorted(expected));
  EXPECT_EQ(why_undefined("no_such_feature"), "");
  EXPECT_NE(why_undefined(feature_name::resistance_alpha).find("or does not rise before it"), std::string::npos);
}

TEST(Features, CurrentPauseInAVoltageOnlySignalIsStillAnError) {
  // The current drops to zero for 3 ms in the middle of the weld: R = V/I is undefined
  // there, an input error (pulsed waveforms are not supported), not an undefined feature.
  Signal weld = synthetic_weld(ResistanceShape{});
  Eigen::VectorXd current = weld.column(signal_column::current);
  Eigen::VectorXd voltage = weld.column(signal_column::voltage);
  for (Eigen::Index i = 0; i < current.size(); ++i) {
    if (weld.time()[i] >= 50e-3 && weld.time()[i] <= 53e-3) current[i] = voltage[i] = 0;
  }
  Signal paused(weld.time());
  paused.add_column(signal_column::current, "A", current);
  paused.add_column(signal_column::voltage, "V", voltage);
  try {
    extract_features(paused, half_current_threshold());
    FAIL() << "a current pause was accepted";
  } catch (const FeatureError& error) {
    EXPECT_NE(std::string(error.what()).find("current pauses are not supported"), std::string::npos) << error.what();
  }
}

TEST(Features, PostWeldWindowMovesTheRecordEnd) {
  FeatureSettings settings = half_current_threshold();
  settings.post_weld_window = 5e-3;  // record end 115 ms: 105 ms after the weld start
  const FeatureValues features = extract_features(synthetic_weld(ResistanceShape{}), settings);
  EXPECT_NEAR(features.at(feature_name::temperature_end), temperature(105e-3), 1e-9);
  EXPECT_NEAR(features.at(feature_name::displacement_end), displacement(105e-3), 1e-15);
}

TEST(Features, GroupsFollowTheColumnsAndNuggetScalarsPassThrough) {
  SyntheticOptions resistance_only;
  resistance_only.displacement = false;
  resistance_only.temperature = false;
  const std::vector<std::pair<std::string, double>> nugget = {
      {feature_name::nugget_diameter_liquidus, 5.1e-3}, {feature_name::indentation_depth, 42e-6}};
  const FeatureValues features = extract_features(synthetic_weld(ResistanceShape{}, resistance_only),
                                                  half_current_threshold(), nugget);
  std::vector<std::string> expected = resistance_feature_names();
  expected.push_back(feature_name::nugget_diameter_liquidus);
  expected.push_back(feature_name::indentation_depth);
  EXPECT_EQ(features.names(), expected);
  EXPECT_EQ(features.at(feature_name::nugget_diameter_liquidus), 5.1e-3);
  EXPECT_THROW(features.at(feature_name::temperature_max), FeatureError);
  const Eigen::VectorXd selected =
      features.select({feature_name::indentation_depth, feature_name::nugget_diameter_liquidus});
  EXPECT_EQ(selected[0], 42e-6);
  EXPECT_EQ(selected[1], 5.1e-3);
}

TEST(Features, TooShortWeldStageIsAnError) {
  // A 4 ms pulse sampled every 0.5 ms: the weld stage (10 % crossings at 3.55 and
  // 8.45 ms) holds 10 samples, fewer than the smoothing window of 11.
  const int n = 40;
  Eigen::VectorXd time(n), current(n), voltage(n);
  for (int i = 0; i < n; ++i) {
    time[i] = i * raw_step;
    current[i] = (time[i] >= 4e-3 && time[i] <= 8e-3) ? 8e3 : 0;
    voltage[i] = 1e-4 * current[i];
  }
  Signal signal(time);
  signal.add_column(signal_column::current, "A", current);
  signal.add_column(signal_column::voltage, "V", voltage);
  try {
    extract_features(signal);
    FAIL() << "a 4 ms weld stage was accepted";
  } catch (const FeatureError& error) {
    EXPECT_NE(std::string(error.what()).find("too short"), std::string::npos) << error.what();
  }
}

// ---------------------------------------------------------------------------------
// CSV reader

class SignalCsv : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    directory_ = std::filesystem::temp_directory_path() /
                 ("rsw_test_signal_" + std::to_string(::getpid()) + "_" + info->name());
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::string write(const std::string& name, const std::string& text) {
    const auto path = directory_ / name;
    std::ofstream(path) << text;
    return path.string();
  }

  std::filesystem::path directory_;
};

// The error message of reading `path`, or "" if it reads.
std::string read_error(const std::string& path) {
  try {
    read_signal_csv(path);
  } catch (const SignalError& error) {
    return error.what();
  }
  return "";
}

TEST_F(SignalCsv, ReadsEngineeringUnitsIntoSi) {
  const std::string path = write("weld.csv",
                                 "# measured on rig 2\n"
                                 "time [ms], Current [kA], voltage [mV], force [kN], displacement [um], "
                                 "temperature [K]\n"
                                 "0, 0, 0, 3.0, 0, 293.15\n"
                                 "\n"
                                 "0.5, 8.0, 1200, 3.1, 12.5, 1773.15\n");
  const Signal signal = read_signal_csv(path);
  ASSERT_EQ(signal.n_samples(), 2u);
  EXPECT_DOUBLE_EQ(signal.time()[1], 0.5e-3);
  EXPECT_DOUBLE_EQ(signal.column(signal_column::current)[1], 8e3);
  EXPECT_DOUBLE_EQ(signal.column(signal_column::voltage)[1], 1.2);
  EXPECT_DOUBLE_EQ(signal.column(signal_column::force)[1], 3.1e3);
  EXPECT_NEAR(signal.column(signal_column::displacement)[1], 12.5e-6, 1e-18);
  EXPECT_NEAR(signal.column(signal_column::temperature)[0], 20, 1e-9);
  EXPECT_NEAR(signal.column(signal_column::temperature)[1], 1500, 1e-9);
  EXPECT_EQ(signal.unit(signal_column::force), "N");
  EXPECT_EQ(signal.unit(signal_column::temperature), "degC");
}

// rsw simulate writes R = V/I as nan where no current flows: with voltage and current
// present the resistance column is left out (the extractor forms V/I); without them,
// and in any other column, nan is an error naming the line and the column.
TEST_F(SignalCsv, NanResistanceIsReplacedByVoltageOverCurrent) {
  const Signal signal = read_signal_csv(write(
      "sim.csv", "time [s],current [A],voltage [V],resistance [ohm]\n0,0,0,nan\n0.001,8000,1.6,0.0002\n"));
  EXPECT_FALSE(signal.has_column(signal_column::resistance));
  EXPECT_DOUBLE_EQ(signal.column(signal_column::voltage)[1], 1.6);
  const std::string alone = read_error(write("alone.csv", "time [s],current [A],resistance [ohm]\n0,0,nan\n0.001,1,2\n"));
  EXPECT_NE(alone.find("alone.csv:2"), std::string::npos) << alone;
  EXPECT_NE(alone.find("'nan' in a resistance column needs voltage and current columns"), std::string::npos) << alone;
  const std::string other = read_error(write("other.csv", "time [s],current [A],voltage [V]\n0,nan,0\n0.001,1,2\n"));
  EXPECT_NE(other.find("'nan' is not a finite number ('nan' is read only in a resistance column)"), std::string::npos)
      << other;
}

TEST_F(SignalCsv, ResistanceMayReplaceVoltage) {
  const Signal signal = read_signal_csv(
      write("r.csv", "time [s], current [A], resistance [µΩ]\n0, 1, 150\n0.001, 2, 160.5\n"));
  EXPECT_FALSE(signal.has_column(signal_column::voltage));
  EXPECT_NEAR(signal.column(signal_column::resistance)[1], 160.5e-6, 1e-18);
}

// Data-logger exports: a UTF-8 BOM, quoted headers, ';' between fields and decimal commas.
TEST_F(SignalCsv, ReadsSemicolonSeparatedFilesWithDecimalCommas) {
  const Signal signal = read_signal_csv(write("logger.csv",
                                              "\xEF\xBB\xBF\"time [ms]\";\"current [kA]\";\"voltage [V]\"\n"
                                              "0;0;0\n"
                                              "0,5;8,25;1,2\n"));
  ASSERT_EQ(signal.n_samples(), 2u);
  EXPECT_DOUBLE_EQ(signal.time()[1], 0.5e-3);
  EXPECT_DOUBLE_EQ(signal.column(signal_column::current)[1], 8250);
  EXPECT_DOUBLE_EQ(signal.column(signal_column::voltage)[1], 1.2);
}

TEST_F(SignalCsv, ReadsQuotedHeadersWithCommasAndDoubledQuotes) {
  const Signal signal = read_signal_csv(write(
      "quoted.csv", "\"time [ms]\",\"current [kA]\",\"gun \"\"B\"\", left [N]\"\n0,1,2\n1,3,4\n"));
  EXPECT_DOUBLE_EQ(signal.column(signal_column::current)[1], 3000);
  ASSERT_TRUE(signal.has_column("gun \"B\", left"));
  EXPECT_DOUBLE_EQ(signal.column("gun \"B\", left")[1], 4);
}

TEST_F(SignalCsv, DecimalCommasNeedTheSemicolonDelimiter) {
  // With ',' between fields "0,5" is two fields: the row has one value too many.
  std::string message = read_error(write("comma.csv", "time [ms], current [kA]\n0, 0\n0,5, 8\n"));
  EXPECT_NE(message.find(":3: expected 2 values separated by ','"), std::string::npos) << message;
  message = read_error(write("quote.csv", "time [ms];current [kA]\n0;0\n1;\"8\n"));
  EXPECT_NE(message.find("quote.csv:3: column 2: a quoted field has no closing quote"), std::string::npos)
      << message;
}

// A unit mix-up in the header reads, with a warning naming the column and the likely unit.
std::vector<std::string> warnings_of(const std::string& path) {
  std::vector<std::string> warnings;
  read_signal_csv(path, warnings);
  return warnings;
}

TEST_F(SignalCsv, CurrentInKiloampereWrittenAsAmpereIsAWarningNotAnError) {
  // 8 "A" peak; R = V/I = 1.6 V / 8 A = 0.2 Ω = 200000 µΩ on the weld stage.
  const std::string path = write("ampere.csv", "time [ms], current [A], voltage [V]\n0, 0, 0\n1, 8, 1.6\n2, 8, 1.6\n");
  const std::vector<std::string> warnings = warnings_of(path);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0], path + ": column 'current [A]' has a peak |I| of 8 A, outside 100 A .. 100 kA of a spot "
                                "weld: kA?");
  EXPECT_EQ(warnings[1], path + ": the dynamic resistance from voltage/current ('voltage [V]' / 'current [A]') has a "
                                "weld-stage median of 200000 uohm, outside 1 uohm .. 10 mohm of a spot weld: current "
                                "in kA written as A, or voltage in mV written as V?");
  // The same numbers with the right unit: 8 kA, 1.6 V / 8000 A = 200 µΩ, no warning.
  EXPECT_TRUE(warnings_of(write("kiloampere.csv", "time [ms], current [kA], voltage [V]\n0, 0, 0\n1, 8, 1.6\n"
                                                  "2, 8, 1.6\n")).empty());
}

TEST_F(SignalCsv, ResistanceInTheWrongUnitIsAWarningWithTheLikelyUnit) {
  // 180 read as mΩ is 0.18 Ω, above 10 mΩ; as µΩ (180e-6 Ω) it would be plausible.
  const std::string path =
      write("milliohm.csv", "time [ms]; current [kA]; resistance [mohm]\n0;8;180\n1;8;182\n2;8;184\n");
  const std::vector<std::string> warnings = warnings_of(path);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], path + ": the dynamic resistance from column 'resistance [mohm]' has a weld-stage median "
                                "of 182000 uohm, outside 1 uohm .. 10 mohm of a spot weld: uohm?");
}

TEST_F(SignalCsv, ErrorsNameFileLineAndColumn) {
  const std::string bad_number = write("bad_number.csv",
                                       "time [ms], current [kA]\n0, 0\n0.5, 8..0\n");
  std::string message = read_error(bad_number);
  EXPECT_NE(message.find(bad_number + ":3:"), std::string::npos) << message;
  EXPECT_NE(message.find("column 2 ('current [kA]')"), std::string::npos) << message;
  EXPECT_NE(message.find("8..0"), std::string::npos) << message;

  message = read_error(write("wrong_kind.csv", "time [ms], current [mm]\n0, 0\n1, 1\n"));
  EXPECT_NE(message.find(":1: column 2"), std::string::npos) << message;
  EXPECT_NE(message.find("electric current"), std::string::npos) << message;

  message = read_error(write("no_unit.csv", "time, current [kA]\n0, 0\n1, 1\n"));
  EXPECT_NE(message.find(":1: column 1 ('time')"), std::string::npos) << message;

  message = read_error(write("unknown_unit.csv", "time [ms], current [kQ]\n0, 0\n1, 1\n"));
  EXPECT_NE(message.find("unknown unit 'kQ'"), std::string::npos) << message;

  message = read_error(write("short_row.csv", "time [ms], current [kA]\n0, 0\n1\n"));
  EXPECT_NE(message.find(":3: expected 2"), std::string::npos) << message;

  message = read_error(write("backwards.csv", "time [ms], current [kA]\n0, 0\n1, 1\n1, 2\n"));
  EXPECT_NE(message.find(":4: column 1 ('time [ms]')"), std::string::npos) << message;

  message = read_error(write("no_time.csv", "current [kA]\n0\n1\n"));
  EXPECT_NE(message.find("no 'time [unit]' column"), std::string::npos) << message;

  message = read_error((directory_ / "missing.csv").string());
  EXPECT_NE(message.find("cannot open"), std::string::npos) << message;
}

TEST_F(SignalCsv, FeaturesFromFileMatchTheInMemorySignal) {
  // Simulation and experiment go through the same extractor: the synthetic weld written
  // in engineering units and read back gives the same features.
  const Signal signal = synthetic_weld(ResistanceShape{});
  std::ostringstream text;
  text.precision(17);
  text << "time [ms], current [kA], voltage [V], displacement [mm], temperature [degC]\n";
  for (std::size_t i = 0; i < signal.n_samples(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    text << signal.time()[k] * 1e3 << ", " << signal.column(signal_column::current)[k] * 1e-3 << ", "
         << signal.column(signal_column::voltage)[k] << ", "
         << signal.column(signal_column::displacement)[k] * 1e3 << ", "
         << signal.column(signal_column::temperature)[k] << "\n";
  }
  const FeatureValues from_memory = extract_features(signal, half_current_threshold());
  const FeatureValues from_file =
      extract_features(read_signal_csv(write("synthetic.csv", text.str())), half_current_threshold());
  ASSERT_EQ(from_memory.names(), from_file.names());
  for (std::size_t i = 0; i < from_memory.size(); ++i) {
    EXPECT_NEAR(from_file.values()[i], from_memory.values()[i],
                1e-8 * std::abs(from_memory.values()[i]) + 1e-15)
        << from_memory.names()[i];
  }
}

}  // namespace
}  // namespace rsw::calibration
