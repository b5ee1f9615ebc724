// Signals, uniform resampling, Savitzky–Golay smoothing, the Hermite curve through the
// smoothed samples and the CSV reader; see signal.hpp for the definitions.
#include "calibration/signal.hpp"
#include "fem/csv.hpp"
#include "fem/text.hpp"

#include "fem/units.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <utility>

namespace rsw::calibration {
namespace {

using fem::lower;
using fem::trim;

std::string format_number(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}





// Real roots of a x² + b x + c = 0 (one root when the quadratic term is negligible on
// an interval of length `scale`).
std::vector<double> quadratic_roots(double a, double b, double c, double scale) {
  std::vector<double> roots;
  if (std::abs(a) * scale * scale <= 1e-14 * (std::abs(b) * scale + std::abs(c))) {
    if (b != 0) roots.push_back(-c / b);
    return roots;
  }
  const double discriminant = b * b - 4 * a * c;
  if (discriminant < 0) return roots;
  const double q = -0.5 * (b + std::copysign(std::sqrt(discriminant), b));
  if (q != 0) {
    roots.push_back(q / a);
    roots.push_back(c / q);
  } else {
    roots.push_back(0.0);
  }
  return roots;
}

double evaluate_cubic(const Eigen::Vector4d& c, double x) {
  return c[0] + x * (c[1] + x * (c[2] + x * c[3]));
}

double evaluate_cubic_slope(const Eigen::Vector4d& c, double x) {
  return c[1] + x * (2 * c[2] + x * 3 * c[3]);
}

}  // namespace

std::string canonical_unit(const std::string& column_name) {
  static const std::vector<std::pair<std::string, std::string>> units = {
      {signal_column::time, "s"},           {signal_column::current, "A"},
      {signal_column::voltage, "V"},        {signal_column::resistance, "ohm"},
      {signal_column::force, "N"},          {signal_column::displacement, "m"},
      {signal_column::temperature, "degC"},
  };
  for (const auto& [name, unit] : units) {
    if (name == column_name) return unit;
  }
  return "";
}

// ---------------------------------------------------------------------------------
// Signal

Signal::Signal(Eigen::VectorXd time) : time_(std::move(time)) {
  for (Eigen::Index i = 0; i < time_.size(); ++i) {
    if (!std::isfinite(time_[i])) {
      throw SignalError("signal time " + std::to_string(i) + " is not finite");
    }
    if (i > 0 && !(time_[i] > time_[i - 1])) {
      throw SignalError("signal time must increase strictly: t[" + std::to_string(i) +
                        "] = " + format_number(time_[i]) + " s follows " +
                        format_number(time_[i - 1]) + " s");
    }
  }
}

void Signal::add_column(const std::string& name, const std::string& unit,
                        Eigen::VectorXd values) {
  if (name.empty()) throw SignalError("signal column without a name");
  if (name == signal_column::time || has_column(name)) {
    throw SignalError("signal already has a column '" + name + "'");
  }
  if (values.size() != time_.size()) {
    throw SignalError("signal column '" + name + "' has " + std::to_string(values.size()) +
                      " values for " + std::to_string(time_.size()) + " time samples");
  }
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      throw SignalError("signal column '" + name + "' is not finite at t = " +
                        format_number(time_[i]) + " s");
    }
  }
  columns_.push_back({name, unit, std::move(values)});
}

bool Signal::has_column(const std::string& name) const {
  return std::any_of(columns_.begin(), columns_.end(),
                     [&](const Column& column) { return column.name == name; });
}

const Signal::Column& Signal::find(const std::string& name) const {
  for (const auto& column : columns_) {
    if (column.name == name) return column;
  }
  std::string available;
  for (const auto& column : columns_) available += (available.empty() ? "" : ", ") + column.name;
  throw SignalError("signal has no column '" + name + "' (it has: " +
                    (available.empty() ? std::string("none") : available) + ")");
}

const Eigen::VectorXd& Signal::column(const std::string& name) const {
  return find(name).values;
}

const std::string& Signal::unit(const std::string& name) const { return find(name).unit; }

std::vector<std::string> Signal::column_names() const {
  std::vector<std::string> names;
  for (const auto& column : columns_) names.push_back(column.name);
  return names;
}

// ---------------------------------------------------------------------------------
// Interpolation and resampling

double interpolate_linear(const Eigen::VectorXd& time, const Eigen::VectorXd& values, double t) {
  const Eigen::Index n = time.size();
  if (n == 0) throw SignalError("cannot interpolate an empty signal");
  if (n == 1 || t <= time[0]) return values[0];
  if (t >= time[n - 1]) return values[n - 1];
  const auto upper = std::upper_bound(time.data(), time.data() + n, t);
  const Eigen::Index k = (upper - time.data()) - 1;
  const double weight = (t - time[k]) / (time[k + 1] - time[k]);
  return (1 - weight) * values[k] + weight * values[k + 1];
}

double average_linear(const Eigen::VectorXd& time, const Eigen::VectorXd& values, double a, double b) {
  const Eigen::Index n = time.size();
  if (n == 0) throw SignalError("cannot average an empty signal");
  if (!(b > a)) return interpolate_linear(time, values, a);
  // ∫ over the parts before the first and after the last sample (constant values).
  double integral = 0;
  if (a < time[0]) integral += values[0] * (std::min(b, time[0]) - a);
  if (b > time[n - 1]) integral += values[n - 1] * (b - std::max(a, time[n - 1]));
  // Trapezoids of the segments [t_k, t_k+1] clipped to [a, b].
  const Eigen::Index first = std::max<Eigen::Index>(
      0, (std::upper_bound(time.data(), time.data() + n, a) - time.data()) - 1);
  for (Eigen::Index k = first; k + 1 < n && time[k] < b; ++k) {
    const double lo = std::max(a, time[k]), hi = std::min(b, time[k + 1]);
    if (!(hi > lo)) continue;
    const double slope = (values[k + 1] - values[k]) / (time[k + 1] - time[k]);
    integral += (hi - lo) * (values[k] + slope * (0.5 * (lo + hi) - time[k]));
  }
  return integral / (b - a);
}

double median_step(const Eigen::VectorXd& time) {
  if (time.size() < 2) throw SignalError("a signal needs at least two samples");
  std::vector<double> steps(static_cast<std::size_t>(time.size() - 1));
  for (Eigen::Index i = 0; i + 1 < time.size(); ++i) steps[i] = time[i + 1] - time[i];
  const auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), middle, steps.end());
  return *middle;
}

Signal resample_uniform(const Signal& signal, double step, double anchor_time) {
  if (!(step > 0) || !std::isfinite(step)) {
    throw SignalError("resampling step must be positive, got " + format_number(step) + " s");
  }
  const Eigen::VectorXd& time = signal.time();
  if (time.size() < 2) throw SignalError("a signal needs at least two samples to resample");
  const double tolerance = 1e-9;
  const double k_first = std::ceil((time[0] - anchor_time) / step - tolerance);
  const double k_last = std::floor((time[time.size() - 1] - anchor_time) / step + tolerance);
  if (k_last - k_first < 1) {
    throw SignalError("resampling step " + format_number(step) + " s leaves fewer than two " +
                      "samples in a record of " + format_number(time[time.size() - 1] - time[0]) +
                      " s");
  }
  const auto n = static_cast<Eigen::Index>(k_last - k_first) + 1;
  Eigen::VectorXd grid(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    grid[k] = anchor_time + (k_first + static_cast<double>(k)) * step;
  }
  Signal result(grid);
  for (const auto& name : signal.column_names()) {
    const Eigen::VectorXd& values = signal.column(name);
    Eigen::VectorXd resampled(n);
    for (Eigen::Index k = 0; k < n; ++k) resampled[k] = interpolate_linear(time, values, grid[k]);
    result.add_column(name, signal.unit(name), std::move(resampled));
  }
  return result;
}

// ---------------------------------------------------------------------------------
// Savitzky–Golay filter

SavitzkyGolayFilter::SavitzkyGolayFilter(int window_length, int polynomial_order)
    : window_length_(window_length),
      polynomial_order_(polynomial_order),
      half_width_(window_length / 2) {
  if (window_length < 3 || window_length % 2 == 0 || polynomial_order < 0 ||
      polynomial_order >= window_length) {
    throw std::invalid_argument(
        "Savitzky-Golay filter needs an odd window of at least 3 samples longer than the "
        "polynomial order; got window " +
        std::to_string(window_length) + ", order " + std::to_string(polynomial_order));
  }
  // Vandermonde matrix of the window in the scaled offset s/m ∈ [−1, 1].
  Eigen::MatrixXd vandermonde(window_length_, polynomial_order_ + 1);
  for (int j = 0; j < window_length_; ++j) {
    const double s = static_cast<double>(j - half_width_) / half_width_;
    double power = 1;
    for (int k = 0; k <= polynomial_order_; ++k) {
      vandermonde(j, k) = power;
      power *= s;
    }
  }
  // Least-squares solution for every unit data vector: the pseudo-inverse (VᵀV)⁻¹Vᵀ.
  coefficients_ = vandermonde.colPivHouseholderQr().solve(
      Eigen::MatrixXd::Identity(window_length_, window_length_));
}

Eigen::VectorXd SavitzkyGolayFilter::weights(int position, int derivative_order) const {
  if (position < -half_width_ || position > half_width_) {
    throw std::invalid_argument("Savitzky-Golay position " + std::to_string(position) +
                                " is outside the window [-" + std::to_string(half_width_) +
                                ", " + std::to_string(half_width_) + "]");
  }
  if (derivative_order < 0 || derivative_order > 1) {
    throw std::invalid_argument("Savitzky-Golay weights exist for derivative order 0 or 1");
  }
  const double s = static_cast<double>(position) / half_width_;
  Eigen::VectorXd result = Eigen::VectorXd::Zero(window_length_);
  for (int k = derivative_order; k <= polynomial_order_; ++k) {
    // d/dj (s^k) = k s^(k−1) / m for the sample offset j = m s.
    const double factor = derivative_order == 0
                              ? std::pow(s, k)
                              : k * std::pow(s, k - 1) / static_cast<double>(half_width_);
    result += factor * coefficients_.row(k).transpose();
  }
  return result;
}

Eigen::VectorXd SavitzkyGolayFilter::apply(const Eigen::VectorXd& values,
                                           int derivative_order) const {
  const Eigen::Index n = values.size();
  if (n < window_length_) {
    throw SignalError("Savitzky-Golay smoothing with a window of " +
                      std::to_string(window_length_) + " samples needs at least that many; got " +
                      std::to_string(n));
  }
  Eigen::MatrixXd table(window_length_, window_length_);  // row = position + m
  for (int position = -half_width_; position <= half_width_; ++position) {
    table.row(position + half_width_) = weights(position, derivative_order).transpose();
  }
  Eigen::VectorXd result(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Index start = i - half_width_;
    int position = 0;
    if (i < half_width_) {
      start = 0;
      position = static_cast<int>(i) - half_width_;
    } else if (i > n - 1 - half_width_) {
      start = n - window_length_;
      position = static_cast<int>(i - (n - 1 - half_width_));
    }
    result[i] = table.row(position + half_width_).dot(values.segment(start, window_length_));
  }
  return result;
}

Eigen::VectorXd SavitzkyGolayFilter::smooth(const Eigen::VectorXd& values) const {
  return apply(values, 0);
}

Eigen::VectorXd SavitzkyGolayFilter::slope(const Eigen::VectorXd& values, double step) const {
  if (!(step > 0)) throw std::invalid_argument("Savitzky-Golay slope needs a positive step");
  return apply(values, 1) / step;
}

// ---------------------------------------------------------------------------------
// SmoothCurve

SmoothCurve::SmoothCurve(double t_first, double step, Eigen::VectorXd values,
                         Eigen::VectorXd slopes)
    : t_first_(t_first), step_(step), values_(std::move(values)), slopes_(std::move(slopes)) {
  if (values_.size() < 2 || slopes_.size() != values_.size()) {
    throw SignalError("a smooth curve needs at least two samples, each with a slope");
  }
  if (!(step_ > 0)) throw SignalError("a smooth curve needs a positive sample step");
  begin_ = t_first_;
  end_ = t_first_ + static_cast<double>(values_.size() - 1) * step_;
}

SmoothCurve SmoothCurve::trimmed(double t_begin, double t_end) const {
  const double tolerance = 1e-9 * step_;
  if (!(t_begin < t_end) || t_begin < begin_ - tolerance || t_end > end_ + tolerance) {
    throw SignalError("cannot trim the curve on [" + format_number(begin_) + ", " +
                      format_number(end_) + "] s to [" + format_number(t_begin) + ", " +
                      format_number(t_end) + "] s");
  }
  SmoothCurve result = *this;
  result.begin_ = std::max(t_begin, begin_);
  result.end_ = std::min(t_end, end_);
  return result;
}

Eigen::Index SmoothCurve::piece_index(double t) const {
  const auto k = static_cast<Eigen::Index>(std::floor((t - t_first_) / step_));
  return std::clamp<Eigen::Index>(k, 0, values_.size() - 2);
}

Eigen::Vector4d SmoothCurve::piece(Eigen::Index k) const {
  const double h = step_;
  const double y0 = values_[k];
  const double y1 = values_[k + 1];
  const double d0 = slopes_[k];
  const double d1 = slopes_[k + 1];
  const double secant = (y1 - y0) / h;
  return {y0, d0, (3 * secant - 2 * d0 - d1) / h, (d0 + d1 - 2 * secant) / (h * h)};
}

template <class Visit>
void SmoothCurve::for_each_piece(Visit&& visit) const {
  const Eigen::Index k_begin = piece_index(begin_);
  const Eigen::Index k_end = piece_index(end_);
  for (Eigen::Index k = k_begin; k <= k_end; ++k) {
    const double t_k = t_first_ + static_cast<double>(k) * step_;
    const double x0 = std::max(begin_ - t_k, 0.0);
    const double x1 = std::min(end_ - t_k, step_);
    if (x1 > x0) visit(k, t_k, piece(k), x0, x1);
  }
}

double SmoothCurve::value(double t) const {
  const Eigen::Index k = piece_index(t);
  return evaluate_cubic(piece(k), t - (t_first_ + static_cast<double>(k) * step_));
}

double SmoothCurve::slope(double t) const {
  const Eigen::Index k = piece_index(t);
  return evaluate_cubic_slope(piece(k), t - (t_first_ + static_cast<double>(k) * step_));
}

CurvePoint SmoothCurve::maximum() const {
  CurvePoint best{begin_, value(begin_)};
  auto consider = [&](double t, double y) {
    if (y > best.value) best = {t, y};
  };
  for_each_piece([&](Eigen::Index, double t_k, const Eigen::Vector4d& c, double x0, double x1) {
    // Critical points p'(x) = c1 + 2 c2 x + 3 c3 x² = 0 with p''(x) < 0.
    for (double x : quadratic_roots(3 * c[3], 2 * c[2], c[1], step_)) {
      if (x > x0 && x < x1 && 2 * c[2] + 6 * c[3] * x < 0) consider(t_k + x, evaluate_cubic(c, x));
    }
    consider(t_k + x1, evaluate_cubic(c, x1));
  });
  return best;
}

CurvePoint SmoothCurve::maximum_slope() const {
  CurvePoint best{begin_, slope(begin_)};
  auto consider = [&](double t, double s) {
    if (s > best.value) best = {t, s};
  };
  for_each_piece([&](Eigen::Index, double t_k, const Eigen::Vector4d& c, double x0, double x1) {
    // The slope is the quadratic c1 + 2 c2 x + 3 c3 x²; its vertex is a maximum if c3 < 0.
    if (c[3] < 0) {
      const double x = -c[2] / (3 * c[3]);
      if (x > x0 && x < x1) consider(t_k + x, evaluate_cubic_slope(c, x));
    }
    consider(t_k + x1, evaluate_cubic_slope(c, x1));
  });
  return best;
}

std::optional<CurvePoint> SmoothCurve::first_minimum() const {
  if (slope(begin_) >= 0) return CurvePoint{begin_, value(begin_)};
  std::optional<CurvePoint> found;
  for_each_piece([&](Eigen::Index, double t_k, const Eigen::Vector4d& c, double x0, double x1) {
    if (found) return;
    // Critical points p'(x) = 0 with p''(x) > 0, the earliest in the piece first.
    double first = std::numeric_limits<double>::infinity();
    for (double x : quadratic_roots(3 * c[3], 2 * c[2], c[1], step_)) {
      if (x > x0 && x <= x1 && 2 * c[2] + 6 * c[3] * x > 0) first = std::min(first, x);
    }
    if (std::isfinite(first)) found = CurvePoint{t_k + first, evaluate_cubic(c, first)};
  });
  return found;
}

double SmoothCurve::mean() const {
  double integral = 0;
  for_each_piece([&](Eigen::Index, double, const Eigen::Vector4d& c, double x0, double x1) {
    for (int j = 0; j < 4; ++j) {
      integral += c[j] * (std::pow(x1, j + 1) - std::pow(x0, j + 1)) / (j + 1);
    }
  });
  return integral / (end_ - begin_);
}

double SmoothCurve::fit_slope() const {
  const double midpoint = 0.5 * (begin_ + end_);
  const double length = end_ - begin_;
  double moment = 0;  // ∫ (t − t̄) y dt
  for_each_piece([&](Eigen::Index, double t_k, const Eigen::Vector4d& c, double x0, double x1) {
    const double offset = t_k - midpoint;
    for (int j = 0; j < 4; ++j) {
      moment += c[j] * (offset * (std::pow(x1, j + 1) - std::pow(x0, j + 1)) / (j + 1) +
                        (std::pow(x1, j + 2) - std::pow(x0, j + 2)) / (j + 2));
    }
  });
  return moment / (length * length * length / 12);
}

// ---------------------------------------------------------------------------------
// CSV reader

Signal read_signal_csv(const std::string& path) {
  std::vector<std::string> warnings;
  return read_signal_csv(path, warnings);
}

Signal read_signal_csv(const std::string& path, std::vector<std::string>& warnings) {
  std::ifstream in(path);
  if (!in) throw SignalError("cannot open signal file '" + path + "'");

  struct ColumnSpec {
    std::string header;  // as written, for messages
    std::string name;
    std::string unit;
    double scale = 1;  // SI value = scale · value + offset
    double offset = 0;
    std::string si_unit;
  };
  std::vector<ColumnSpec> columns;
  std::vector<std::vector<double>> data;
  std::vector<std::size_t> data_lines;

  auto where = [&](std::size_t line_number) {
    return path + ":" + std::to_string(line_number) + ": ";
  };
  auto column_label = [&](std::size_t index) {
    return "column " + std::to_string(index + 1) + " ('" + columns[index].header + "')";
  };

  fem::CsvReader reader(in);
  std::vector<std::string> fields;
  while (reader.next_or_throw<SignalError>(fields, path)) {
    const std::size_t line_number = reader.line_number();

    if (columns.empty()) {
      for (std::size_t i = 0; i < fields.size(); ++i) {
        const std::string& field = fields[i];
        const auto open = field.find('[');
        const auto close = field.find(']', open == std::string::npos ? 0 : open);
        const std::string label = "column " + std::to_string(i + 1) + " ('" + field + "')";
        if (open == std::string::npos || close == std::string::npos ||
            !trim(field.substr(close + 1)).empty()) {
          throw SignalError(where(line_number) + label +
                            ": a header entry must be 'name [unit]', e.g. 'time [ms]' " +
                            "('[-]' for a plain number)");
        }
        ColumnSpec spec;
        spec.header = field;
        spec.name = trim(field.substr(0, open));
        spec.unit = trim(field.substr(open + 1, close - open - 1));
        if (spec.name.empty()) throw SignalError(where(line_number) + label + ": no column name");
        if (!canonical_unit(lower(spec.name)).empty()) spec.name = lower(spec.name);
        for (const auto& other : columns) {
          if (other.name == spec.name) {
            throw SignalError(where(line_number) + label + ": column '" + spec.name +
                              "' appears twice");
          }
        }
        columns.push_back(spec);
        ColumnSpec& column = columns.back();
        try {
          if (!fem::is_known_unit(column.unit)) {
            throw SignalError(where(line_number) + column_label(i) + ": unknown unit '" +
                              column.unit + "'");
          }
          column.si_unit = canonical_unit(column.name);
          if (column.si_unit.empty()) {
            static const char* const si_units[] = {"s",  "A",  "V", "ohm", "N",   "m",  "degC",
                                                   "Pa", "W", "J", "kg",  "m/s", "1"};
            for (const char* candidate : si_units) {
              if (fem::units_convertible(column.unit, candidate)) {
                column.si_unit = candidate;
                break;
              }
            }
            if (column.si_unit.empty()) {
              throw SignalError(where(line_number) + column_label(i) + ": unit '" + column.unit +
                                "' (" + fem::quantity_kind(column.unit) +
                                ") has no SI counterpart the signal reader knows");
            }
          } else if (!fem::units_convertible(column.unit, column.si_unit)) {
            throw SignalError(where(line_number) + column_label(i) + ": unit '" + column.unit +
                              "' measures " + fem::quantity_kind(column.unit) + ", but '" +
                              column.name + "' needs " + fem::quantity_kind(column.si_unit) +
                              " (e.g. '" + column.si_unit + "')");
          }
          // Unit conversions are affine (temperatures carry an offset).
          column.offset = fem::convert_units(0.0, column.unit, column.si_unit);
          column.scale = fem::convert_units(1.0, column.unit, column.si_unit) - column.offset;
        } catch (const fem::UnitError& error) {
          throw SignalError(where(line_number) + column_label(i) + ": " + error.what());
        }
      }
      if (std::none_of(columns.begin(), columns.end(),
                       [](const ColumnSpec& c) { return c.name == signal_column::time; })) {
        throw SignalError(where(line_number) + "the header has no 'time [unit]' column");
      }
      continue;
    }

    if (fields.size() != columns.size()) {
      throw SignalError(where(line_number) + "expected " + std::to_string(columns.size()) +
                        " values separated by '" + std::string(1, reader.delimiter()) +
                        "' (one per header column), found " +
                        std::to_string(fields.size()));
    }
    std::vector<double> row(fields.size());
    for (std::size_t i = 0; i < fields.size(); ++i) {
      double value = 0;
      if (lower(trim(fields[i])) == "nan" && columns[i].name == signal_column::resistance) {
        // rsw simulate writes R = V/I as nan where no current flows; see below.
        row[i] = std::nan("");
        continue;
      }
      if (!reader.parse_number(fields[i], value)) {
        throw SignalError(where(line_number) + column_label(i) + ": '" + fields[i] +
                          "' is not a finite number" +
                          (columns[i].name == signal_column::resistance ? "" : " ('nan' is read only in a resistance column)"));
      }
      row[i] = value;
    }
    data.push_back(std::move(row));
    data_lines.push_back(line_number);
  }

  if (columns.empty()) throw SignalError(path + ": no header line ('time [ms], current [kA], ...')");
  if (data.size() < 2) {
    throw SignalError(path + ": a signal needs at least two data rows, found " +
                      std::to_string(data.size()));
  }

  const auto n = static_cast<Eigen::Index>(data.size());
  std::size_t time_index = 0;
  while (columns[time_index].name != signal_column::time) ++time_index;
  Eigen::VectorXd time(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double raw = data[k][time_index];
    if (k > 0 && !(raw > data[k - 1][time_index])) {
      throw SignalError(where(data_lines[k]) + column_label(time_index) + ": time " +
                        format_number(raw) + " does not increase past the previous row's " +
                        format_number(data[k - 1][time_index]));
    }
    time[k] = columns[time_index].scale * raw + columns[time_index].offset;
  }
  Signal signal(time);
  const auto has = [&](const char* name) {
    return std::any_of(columns.begin(), columns.end(), [&](const ColumnSpec& c) { return c.name == name; });
  };
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (i == time_index) continue;
    // A resistance column with nan rows (no current there, as rsw simulate writes it)
    // is left out when voltage and current are given: the extractor forms V/I itself.
    // (Only resistance columns can hold nan: the row parser rejects it elsewhere.)
    const auto first_nan = std::find_if(data.begin(), data.end(), [i](const std::vector<double>& r) { return std::isnan(r[i]); });
    if (first_nan != data.end()) {
      if (has(signal_column::voltage) && has(signal_column::current)) continue;
      throw SignalError(where(data_lines[static_cast<std::size_t>(first_nan - data.begin())]) + column_label(i) +
                        ": 'nan' in a resistance column needs voltage and current columns to replace it");
    }
    Eigen::VectorXd values(n);
    for (Eigen::Index k = 0; k < n; ++k) values[k] = columns[i].scale * data[k][i] + columns[i].offset;
    signal.add_column(columns[i].name, columns[i].si_unit, std::move(values));
  }

  // Plausibility of the units (see signal.hpp).
  const auto header_of = [&](const char* name) {
    for (const auto& column : columns)
      if (column.name == name) return column;
    return ColumnSpec{};
  };
  // The first of `candidates` in which the column's raw numbers would land in
  // [lower, upper] (SI), as " <unit>?", or "" if none does.
  const auto likely_unit = [](const ColumnSpec& column, double raw, double lower, double upper,
                              std::initializer_list<const char*> candidates) {
    for (const char* candidate : candidates) {
      if (candidate == column.unit) continue;
      const double si = fem::convert_units(raw, candidate, column.si_unit);
      if (si >= lower && si <= upper) return std::string(": ") + candidate + "?";
    }
    return std::string();
  };
  if (n > 1) {  // A weld record lasts milliseconds to seconds; hours mean a wrong time unit.
    const ColumnSpec column = header_of(signal_column::time);
    const double span = signal.time()[n - 1] - signal.time()[0];
    if (span > 600.0) {
      const double raw = span / column.scale;
      throw SignalError(path + ": column '" + column.header + "' spans " + format_number(raw) + " " + column.unit +
                        " = " + format_number(span) + " s, beyond the 10 min of any weld record" +
                        likely_unit(column, raw, 1e-3, 600.0, {"ms", "s", "us"}));
    }
  }
  std::vector<bool> in_stage(static_cast<std::size_t>(n), true);
  if (signal.has_column(signal_column::current)) {
    const ColumnSpec column = header_of(signal_column::current);
    const Eigen::VectorXd& current = signal.column(signal_column::current);
    const double peak = current.cwiseAbs().maxCoeff();
    if ((peak > 0 && peak < 100) || peak > 100e3) {  // no current at all is the extractor's error
      const double raw = (peak - column.offset) / column.scale;
      warnings.push_back(path + ": column '" + column.header + "' has a peak |I| of " + format_number(raw) + " " +
                         column.unit + ", outside 100 A .. 100 kA of a spot weld" +
                         likely_unit(column, raw, 100, 100e3, {"kA", "A", "mA", "MA"}));
    }
    for (Eigen::Index k = 0; k < n; ++k) in_stage[static_cast<std::size_t>(k)] = std::abs(current[k]) >= 0.1 * peak;
  }
  std::vector<double> resistance;
  std::string source;
  ColumnSpec resistance_column;
  if (signal.has_column(signal_column::resistance)) {
    resistance_column = header_of(signal_column::resistance);
    source = "column '" + resistance_column.header + "'";
    for (Eigen::Index k = 0; k < n; ++k)
      if (in_stage[static_cast<std::size_t>(k)]) resistance.push_back(signal.column(signal_column::resistance)[k]);
  } else if (signal.has_column(signal_column::voltage) && signal.has_column(signal_column::current)) {
    source = "voltage/current ('" + header_of(signal_column::voltage).header + "' / '" +
             header_of(signal_column::current).header + "')";
    for (Eigen::Index k = 0; k < n; ++k) {
      const double current = signal.column(signal_column::current)[k];
      if (in_stage[static_cast<std::size_t>(k)] && current != 0)
        resistance.push_back(signal.column(signal_column::voltage)[k] / current);
    }
  }
  if (!resistance.empty()) {
    const auto middle = resistance.begin() + static_cast<std::ptrdiff_t>(resistance.size() / 2);
    std::nth_element(resistance.begin(), middle, resistance.end());
    const double median = std::abs(*middle);
    if (median > 10e-3 || median < 1e-6) {
      std::string hint;
      if (!resistance_column.header.empty()) {
        hint = likely_unit(resistance_column, (median - resistance_column.offset) / resistance_column.scale, 1e-6,
                           10e-3, {"uohm", "mohm", "ohm"});
      } else {
        hint = median > 10e-3 ? ": current in kA written as A, or voltage in mV written as V?"
                              : ": current in A written as kA, or voltage in V written as mV?";
      }
      warnings.push_back(path + ": the dynamic resistance from " + source + " has a weld-stage median of " +
                         format_number(median * 1e6) + " uohm, outside 1 uohm .. 10 mohm of a spot weld" + hint);
    }
  }
  return signal;
}

}  // namespace rsw::calibration
