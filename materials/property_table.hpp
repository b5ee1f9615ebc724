// Temperature tables of material properties and 2-D flow-stress tables.
//
// PropertyTable: y(T) piecewise linear between the points (T_i, y_i), T_i strictly
// increasing, held constant outside [T_0, T_last] (constant extrapolation: a table
// that stops at 1200 degC keeps its last value above it; the slope there is 0).
// evaluate() returns y and dy/dT. At an interior point T_i the slope of the segment
// above T_i is returned (the table is only C^0 there; callers that difference
// across a table point see the kink).
//
// FlowCurveTable: sigma_y(eps_p, T) from curves measured at temperatures T_j, each a
// list of points (eps_p_k, sigma_y_k) with eps_p increasing and sigma_y
// non-decreasing. Along each curve sigma_y is piecewise linear in eps_p and constant
// beyond its last strain (perfectly plastic past the data); between neighbouring
// curves it is linear in T (so bilinear on each (eps_p, T) cell when the curves share
// their strain points); outside [T_0, T_last] the nearest curve is used. evaluate()
// returns sigma_y, the hardening modulus H = d sigma_y / d eps_p and
// d sigma_y / dT. Non-decreasing curves give H >= 0, which the J2 return mapping
// relies on for a unique solution.
//
// Units: whatever the caller stores (the material library stores SI: Pa, degC).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace rsw::materials {

// A property and its derivative with respect to temperature.
struct PropertyValue {
  double value = 0;
  double slope = 0;  // d value / dT, per K
};

class PropertyTable {
 public:
  // The constant function y = 0 (an empty table has no meaning; use constant()).
  PropertyTable() : PropertyTable(std::vector<double>{20.0}, std::vector<double>{0.0}) {}
  // Throws std::invalid_argument unless both lists have the same, non-zero length,
  // the temperatures are strictly increasing and every number is finite.
  PropertyTable(std::vector<double> temperatures, std::vector<double> values);
  static PropertyTable constant(double value);

  PropertyValue evaluate(double temperature) const;
  double value(double temperature) const { return evaluate(temperature).value; }

  // Integral of y from `lower` to `upper` (exact for the piecewise-linear function,
  // including the constant extrapolation); negative when upper < lower.
  double integral(double lower, double upper) const;

  const std::vector<double>& temperatures() const { return temperatures_; }
  const std::vector<double>& values() const { return values_; }
  int n_points() const { return static_cast<int>(temperatures_.size()); }

 private:
  // Integral from temperatures_.front() to `temperature`.
  double integral_from_start(double temperature) const;

  std::vector<double> temperatures_;
  std::vector<double> values_;
  std::vector<double> cumulative_;  // integral from temperatures_.front() to T_i
};

// One flow curve: yield stress against equivalent plastic strain at one temperature.
struct FlowCurve {
  double temperature = 0;             // degC
  std::vector<double> plastic_strain;  // -, strictly increasing, >= 0
  std::vector<double> yield_stress;    // Pa, > 0, non-decreasing
};

// Yield stress and its partial derivatives.
struct FlowStress {
  double yield_stress = 0;       // Pa
  double hardening = 0;          // Pa, d sigma_y / d eps_p (>= 0)
  double temperature_slope = 0;  // Pa/K, d sigma_y / dT
};

class FlowCurveTable {
 public:
  FlowCurveTable() = default;
  // Throws std::invalid_argument unless there is at least one curve, temperatures
  // are strictly increasing, and every curve has strictly increasing, non-negative
  // strains and positive, non-decreasing stresses.
  explicit FlowCurveTable(std::vector<FlowCurve> curves);

  // eps_p < 0 is read as 0. At an interior strain or temperature point the slope of
  // the interval above it is returned.
  FlowStress evaluate(double equivalent_plastic_strain, double temperature) const;

  const std::vector<FlowCurve>& curves() const { return curves_; }
  bool empty() const { return curves_.empty(); }

 private:
  std::vector<FlowCurve> curves_;
};

}  // namespace rsw::materials
