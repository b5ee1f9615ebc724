// Piecewise-linear temperature tables and flow-curve tables (see property_table.hpp).
// Lookups bisect the sorted point lists (std::upper_bound); tables hold tens of
// points, so no caching of the last interval is needed.
#include "materials/property_table.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rsw::materials {
namespace {

bool all_finite(const std::vector<double>& values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

bool strictly_increasing(const std::vector<double>& values) {
  for (std::size_t i = 1; i < values.size(); ++i) {
    if (!(values[i] > values[i - 1])) return false;
  }
  return true;
}

// Index i of the interval [x_i, x_{i+1}) holding x, for x_0 <= x < x_last.
std::size_t interval_of(const std::vector<double>& points, double x) {
  const auto above = std::upper_bound(points.begin(), points.end(), x);
  return static_cast<std::size_t>(above - points.begin()) - 1;
}

// Value and slope of the piecewise-linear function through (x_i, y_i), constant
// outside the points; at a point, the slope of the interval above it.
PropertyValue interpolate(const std::vector<double>& x, const std::vector<double>& y,
                          double at) {
  if (at < x.front()) return {y.front(), 0.0};
  if (at >= x.back()) return {y.back(), 0.0};
  const std::size_t i = interval_of(x, at);
  const double slope = (y[i + 1] - y[i]) / (x[i + 1] - x[i]);
  return {y[i] + slope * (at - x[i]), slope};
}

}  // namespace

// ---------------------------------------------------------------------------------
// PropertyTable

PropertyTable::PropertyTable(std::vector<double> temperatures, std::vector<double> values)
    : temperatures_(std::move(temperatures)), values_(std::move(values)) {
  if (temperatures_.empty() || temperatures_.size() != values_.size()) {
    throw std::invalid_argument("property table: needs as many values as temperatures (" +
                                std::to_string(temperatures_.size()) + " temperatures, " +
                                std::to_string(values_.size()) + " values), at least one");
  }
  if (!all_finite(temperatures_) || !all_finite(values_)) {
    throw std::invalid_argument("property table: every temperature and value must be finite");
  }
  if (!strictly_increasing(temperatures_)) {
    throw std::invalid_argument("property table: temperatures must be strictly increasing");
  }
  cumulative_.assign(temperatures_.size(), 0.0);
  for (std::size_t i = 1; i < temperatures_.size(); ++i) {
    cumulative_[i] = cumulative_[i - 1] + 0.5 * (values_[i] + values_[i - 1]) *
                                              (temperatures_[i] - temperatures_[i - 1]);
  }
}

PropertyTable PropertyTable::constant(double value) {
  return PropertyTable(std::vector<double>{20.0}, std::vector<double>{value});
}

PropertyValue PropertyTable::evaluate(double temperature) const {
  return interpolate(temperatures_, values_, temperature);
}

double PropertyTable::integral_from_start(double temperature) const {
  const double first = temperatures_.front();
  const double last = temperatures_.back();
  if (temperature <= first) return values_.front() * (temperature - first);
  if (temperature >= last) return cumulative_.back() + values_.back() * (temperature - last);
  const std::size_t i = interval_of(temperatures_, temperature);
  const double y = evaluate(temperature).value;
  return cumulative_[i] + 0.5 * (values_[i] + y) * (temperature - temperatures_[i]);
}

double PropertyTable::integral(double lower, double upper) const {
  return integral_from_start(upper) - integral_from_start(lower);
}

// ---------------------------------------------------------------------------------
// FlowCurveTable

FlowCurveTable::FlowCurveTable(std::vector<FlowCurve> curves) : curves_(std::move(curves)) {
  if (curves_.empty()) throw std::invalid_argument("flow curves: at least one curve needed");
  for (std::size_t j = 0; j < curves_.size(); ++j) {
    const FlowCurve& curve = curves_[j];
    const std::string which =
        "flow curve " + std::to_string(j) + " (" + std::to_string(curve.temperature) + " degC)";
    if (!std::isfinite(curve.temperature)) {
      throw std::invalid_argument("flow curves: temperature of curve " + std::to_string(j) +
                                  " is not finite");
    }
    if (j > 0 && !(curve.temperature > curves_[j - 1].temperature)) {
      throw std::invalid_argument(which + ": curve temperatures must be strictly increasing");
    }
    if (curve.plastic_strain.empty() ||
        curve.plastic_strain.size() != curve.yield_stress.size()) {
      throw std::invalid_argument(which + ": needs as many stresses as strains, at least one");
    }
    if (!all_finite(curve.plastic_strain) || !all_finite(curve.yield_stress)) {
      throw std::invalid_argument(which + ": every strain and stress must be finite");
    }
    if (curve.plastic_strain.front() < 0 || !strictly_increasing(curve.plastic_strain)) {
      throw std::invalid_argument(which +
                                  ": plastic strains must be >= 0 and strictly increasing");
    }
    for (std::size_t k = 0; k < curve.yield_stress.size(); ++k) {
      if (!(curve.yield_stress[k] > 0)) {
        throw std::invalid_argument(which + ": yield stresses must be positive");
      }
      if (k > 0 && curve.yield_stress[k] < curve.yield_stress[k - 1]) {
        throw std::invalid_argument(which +
                                    ": yield stress must not decrease with plastic strain");
      }
    }
  }
}

FlowStress FlowCurveTable::evaluate(double equivalent_plastic_strain, double temperature) const {
  if (curves_.empty()) throw std::logic_error("flow curves: evaluate() on an empty table");
  const double strain = std::max(equivalent_plastic_strain, 0.0);
  const auto along = [strain](const FlowCurve& curve) {
    return interpolate(curve.plastic_strain, curve.yield_stress, strain);
  };
  if (temperature < curves_.front().temperature || curves_.size() == 1) {
    const PropertyValue s = along(curves_.front());
    return {s.value, s.slope, 0.0};
  }
  if (temperature >= curves_.back().temperature) {
    const PropertyValue s = along(curves_.back());
    return {s.value, s.slope, 0.0};
  }
  // Curve j at or below the temperature, j + 1 above it.
  const auto above = std::upper_bound(
      curves_.begin(), curves_.end(), temperature,
      [](double t, const FlowCurve& curve) { return t < curve.temperature; });
  const FlowCurve& upper = *above;
  const FlowCurve& lower = *(above - 1);
  const double width = upper.temperature - lower.temperature;
  const double weight = (temperature - lower.temperature) / width;
  const PropertyValue s_lower = along(lower);
  const PropertyValue s_upper = along(upper);
  return {(1 - weight) * s_lower.value + weight * s_upper.value,
          (1 - weight) * s_lower.slope + weight * s_upper.slope,
          (s_upper.value - s_lower.value) / width};
}

}  // namespace rsw::materials
