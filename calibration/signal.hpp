// Process signals of one weld (simulated or measured): a time column and named value
// columns with units, and the signal processing the feature extractor applies to them.
//
// - Signal: time t [s] (strictly increasing) and columns in SI units (temperatures in
//   °C). Canonical column names are listed in `signal_column`; the feature extractor
//   looks columns up by these names.
// - resample_uniform: linear interpolation onto t_k = anchor + k·Δt inside the record.
// - SavitzkyGolayFilter (Savitzky & Golay 1964): a polynomial of order p fitted by
//   least squares to each window of 2m + 1 samples; the smoothed value (or slope) is the
//   fitted polynomial's value (or derivative) at the window centre. The weights are the
//   rows of the least-squares pseudo-inverse (VᵀV)⁻¹Vᵀ of the window's Vandermonde
//   matrix, computed here, not tabulated. For p = 3, m = 5 the centre weights are
//   [−36, 9, 44, 69, 84, 89, 84, 69, 44, 9, −36]/429. Edges: the first (last) m samples
//   take the value of the polynomial fitted to the first (last) full window at their
//   own position, so a polynomial of order ≤ p passes unchanged everywhere.
// - SmoothCurve: the smoothed samples and their Savitzky–Golay slopes joined by cubic
//   Hermite pieces. Between samples it is C¹ and reproduces cubics exactly, so peaks,
//   steepest points, means and fitted slopes are found on the curve, not snapped to the
//   sample grid: features then vary continuously with the data. trimmed() narrows the
//   curve's domain (the 2 ms margins of calibration/features.hpp).
// - read_signal_csv: measured signal files, header "time [ms], current [kA], ...",
//   converted to SI through fem/units.hpp (UDUNITS-2).
#pragma once

#include <Eigen/Core>

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::calibration {

class SignalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Canonical column names and their SI units.
namespace signal_column {
inline constexpr const char* time = "time";                  // s
inline constexpr const char* current = "current";            // A (welding current)
inline constexpr const char* voltage = "voltage";            // V (electrode tip voltage)
inline constexpr const char* resistance = "resistance";      // Ω (dynamic resistance)
inline constexpr const char* force = "force";                // N (electrode force)
inline constexpr const char* displacement = "displacement";  // m (upper electrode, S(t))
inline constexpr const char* temperature = "temperature";    // °C (max sheet temperature)
}  // namespace signal_column

// SI unit of a canonical column ("A" for "current", "degC" for "temperature"); empty for
// names that are not canonical.
std::string canonical_unit(const std::string& column_name);

class Signal {
 public:
  // `time` in seconds, finite and strictly increasing; throws SignalError otherwise.
  explicit Signal(Eigen::VectorXd time);

  // Adds a column of n_samples() finite values; `unit` is its SI unit text.
  // Throws SignalError on a duplicate name, a size mismatch or a non-finite value.
  void add_column(const std::string& name, const std::string& unit, Eigen::VectorXd values);

  std::size_t n_samples() const { return static_cast<std::size_t>(time_.size()); }
  const Eigen::VectorXd& time() const { return time_; }
  bool has_column(const std::string& name) const;
  // Throws SignalError naming the columns that do exist.
  const Eigen::VectorXd& column(const std::string& name) const;
  const std::string& unit(const std::string& name) const;
  std::vector<std::string> column_names() const;  // in insertion order

 private:
  struct Column {
    std::string name;
    std::string unit;
    Eigen::VectorXd values;
  };
  const Column& find(const std::string& name) const;

  Eigen::VectorXd time_;
  std::vector<Column> columns_;
};

// Value of the piecewise-linear interpolant of (time, values) at t; t is clamped to
// [time(0), time(n−1)].
double interpolate_linear(const Eigen::VectorXd& time, const Eigen::VectorXd& values, double t);

// Mean of that interpolant over [a, b] (a < b), (1/(b − a)) ∫_a^b x(t) dt, exact for
// the piecewise-linear x (outside the record x is clamped to its end values). a = b
// gives the value at a. The feature extractor's grid values: a jump in the samples
// between a and b moves the mean in proportion to where it lies, and a ripple whose
// period divides b − a averages out instead of aliasing.
double average_linear(const Eigen::VectorXd& time, const Eigen::VectorXd& values, double a, double b);

// Median of the sample spacings of `time` (at least two samples).
double median_step(const Eigen::VectorXd& time);

// Every column linearly interpolated onto t_k = anchor_time + k·step for all integers k
// with t_k inside [time(0), time(n−1)] (a grid point within 1e-9·step of an end counts
// as inside). Throws SignalError if step ≤ 0 or the grid has fewer than two points.
Signal resample_uniform(const Signal& signal, double step, double anchor_time);

class SavitzkyGolayFilter {
 public:
  // Odd window_length > polynomial_order ≥ 0; throws std::invalid_argument otherwise.
  explicit SavitzkyGolayFilter(int window_length = 11, int polynomial_order = 3);

  int window_length() const { return window_length_; }
  int polynomial_order() const { return polynomial_order_; }

  // Weights w with (smoothed value at window offset `position`) = Σ_j w_j y_j over the
  // window's samples, position in [−m, m] (0 is the centre). derivative_order 0 gives
  // the value, 1 the slope per sample step.
  Eigen::VectorXd weights(int position, int derivative_order = 0) const;

  // Smoothed values of uniformly spaced samples (edges as described above).
  // Throws SignalError if values has fewer than window_length() samples.
  Eigen::VectorXd smooth(const Eigen::VectorXd& values) const;
  // Slope dy/dt of the same fits; `step` is the sample spacing.
  Eigen::VectorXd slope(const Eigen::VectorXd& values, double step) const;

 private:
  Eigen::VectorXd apply(const Eigen::VectorXd& values, int derivative_order) const;

  int window_length_;
  int polynomial_order_;
  int half_width_;
  // coefficients_ row k maps window samples to the k-th power-series coefficient of the
  // fitted polynomial in the scaled offset s / half_width_.
  Eigen::MatrixXd coefficients_;
};

struct CurvePoint {
  double time = 0;   // s
  double value = 0;  // the curve's value, or its slope for maximum_slope()
};

class SmoothCurve {
 public:
  // Samples y_k at t_first + k·step with slopes dy/dt; the domain is the sample range.
  SmoothCurve(double t_first, double step, Eigen::VectorXd values, Eigen::VectorXd slopes);

  double begin() const { return begin_; }
  double end() const { return end_; }

  // The same curve on [t_begin, t_end] ⊆ [begin(), end()]; throws SignalError otherwise.
  SmoothCurve trimmed(double t_begin, double t_end) const;

  // Value and slope at t ∈ [begin(), end()].
  double value(double t) const;
  double slope(double t) const;

  // Global maximum of the curve over its domain (the first one on ties).
  CurvePoint maximum() const;
  // Point of steepest rise over the domain: the maximum of the slope.
  CurvePoint maximum_slope() const;
  // End of a falling start: begin() if the curve does not fall there (slope ≥ 0), else
  // its first local minimum (slope turning from negative to positive); none if it
  // falls over the whole domain.
  std::optional<CurvePoint> first_minimum() const;
  // (1 / (end − begin)) ∫ y dt.
  double mean() const;
  // Slope of the least-squares straight line through the curve over the domain:
  // ∫ (t − t̄) y dt / ∫ (t − t̄)² dt, t̄ the domain midpoint.
  double fit_slope() const;

 private:
  // Power-series coefficients c0..c3 of the Hermite piece on [t_k, t_k+1] in x = t − t_k.
  Eigen::Vector4d piece(Eigen::Index k) const;
  Eigen::Index piece_index(double t) const;
  // Visits every piece overlapping the domain with its local sub-interval [x0, x1].
  template <class Visit>
  void for_each_piece(Visit&& visit) const;

  double t_first_;
  double step_;
  Eigen::VectorXd values_;
  Eigen::VectorXd slopes_;
  double begin_;
  double end_;
};

// Reads a measured signal file, records as fem/csv.hpp reads them (RFC 4180 quotes, a
// UTF-8 BOM, '#' comment lines, ',' or ';' delimiters, decimal commas with ';'); the
// first record is the header, one "name [unit]" per column, e.g.
//     time [ms], current [kA], voltage [V], force [kN], displacement [mm]
// Names are matched case-insensitively against the canonical column names
// ("resistance [uOhm]" may stand in for voltage); other names are kept as written.
// Values are converted to SI (temperatures to °C) with fem/units.hpp. A time column is
// required. Every error is a SignalError naming the file, the line and the column.
Signal read_signal_csv(const std::string& path);

// The same, appending to `warnings` one line per implausible value that suggests a unit
// mix-up in the header (not an error: the file reads), each naming the file and the
// column as written, e.g. "column 'current [A]' has a peak |I| of 8 A, outside
// 100 A .. 100 kA of a spot weld: kA?":
// - the current's peak |I| below 100 A or above 100 kA;
// - the dynamic resistance (the resistance column, else voltage/current) with a median
//   above 10 mΩ or below 1 µΩ over the weld stage, taken here as the samples with
//   |I| ≥ 0.1 I_peak (the extractor's default threshold; all samples without current).
// Spot welds carry 1–50 kA and 20–1000 µΩ, so these bounds leave room on both sides.
Signal read_signal_csv(const std::string& path, std::vector<std::string>& warnings);

}  // namespace rsw::calibration
