// Piecewise-linear temperature tables and flow-curve tables: values from hand
// interpolation, slopes against finite differences, exact integrals, constant
// extrapolation, and rejection of malformed tables.
#include "materials/property_table.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace rsw::materials {
namespace {

// y = 10 at 0 degC, 30 at 100 degC, 0 at 300 degC.
PropertyTable three_point_table() { return PropertyTable({0.0, 100.0, 300.0}, {10.0, 30.0, 0.0}); }

TEST(PropertyTable, InterpolatesLinearlyAndSlopeMatchesFiniteDifference) {
  const PropertyTable table = three_point_table();
  // Hand interpolation: 10 + 0.2 * 50 = 20; 30 - 0.15 * 100 = 15.
  EXPECT_DOUBLE_EQ(table.evaluate(50).value, 20.0);
  EXPECT_DOUBLE_EQ(table.evaluate(50).slope, 0.2);
  EXPECT_DOUBLE_EQ(table.evaluate(200).value, 15.0);
  EXPECT_DOUBLE_EQ(table.evaluate(200).slope, -0.15);
  // At an interior point: the value there, the slope of the interval above.
  EXPECT_DOUBLE_EQ(table.evaluate(100).value, 30.0);
  EXPECT_DOUBLE_EQ(table.evaluate(100).slope, -0.15);

  const double h = 1e-4;
  for (double t : {3.0, 47.5, 99.0, 101.0, 250.0, 299.0}) {
    const double difference = (table.value(t + h) - table.value(t - h)) / (2 * h);
    EXPECT_NEAR(table.evaluate(t).slope, difference, 1e-9) << "T = " << t;
  }
}

TEST(PropertyTable, HoldsEndValuesOutsideTheRange) {
  const PropertyTable table = three_point_table();
  EXPECT_DOUBLE_EQ(table.evaluate(-40).value, 10.0);
  EXPECT_DOUBLE_EQ(table.evaluate(-40).slope, 0.0);
  EXPECT_DOUBLE_EQ(table.evaluate(1000).value, 0.0);
  EXPECT_DOUBLE_EQ(table.evaluate(1000).slope, 0.0);
  const PropertyTable constant = PropertyTable::constant(7850);
  EXPECT_DOUBLE_EQ(constant.value(-100), 7850);
  EXPECT_DOUBLE_EQ(constant.value(1600), 7850);
  EXPECT_DOUBLE_EQ(constant.evaluate(500).slope, 0.0);
}

TEST(PropertyTable, IntegralIsExactForThePiecewiseLinearFunction) {
  const PropertyTable table = three_point_table();
  // Trapezoids: (10 + 30)/2 * 100 = 2000, (30 + 0)/2 * 200 = 3000.
  EXPECT_DOUBLE_EQ(table.integral(0, 300), 5000.0);
  // Constant extrapolation: 10 * 20 below, 0 above.
  EXPECT_DOUBLE_EQ(table.integral(-20, 0), 200.0);
  EXPECT_DOUBLE_EQ(table.integral(300, 400), 0.0);
  // Partial interval 50..200: (20 + 30)/2 * 50 + (30 + 15)/2 * 100 = 1250 + 2250.
  EXPECT_DOUBLE_EQ(table.integral(50, 200), 3500.0);
  EXPECT_DOUBLE_EQ(table.integral(200, 50), -3500.0);
}

// The interval of a temperature is the one a linear search gives, also at the points,
// one rounding step on either side of them and where points cluster within a bucket
// of the lookup index (a latent-heat peak a few millikelvin wide in a 1500 K table).
TEST(PropertyTable, FindsTheIntervalALinearSearchFindsAtEveryTemperature) {
  std::vector<double> T = {20.0, 400.0, 1450.0};
  for (int k = 1; k <= 40; ++k) T.push_back(1450.0 + 1e-3 * k);
  T.push_back(1460.0);
  T.push_back(1520.0);
  std::vector<double> y(T.size());
  for (std::size_t i = 0; i < T.size(); ++i) y[i] = (i % 2 ? 3.0 : -1.0) * static_cast<double>(i) + 0.1;
  const PropertyTable table(T, y);
  auto expected = [&](double t) {
    std::size_t i = 0;
    while (i + 2 < T.size() && T[i + 1] <= t) ++i;
    const double slope = (y[i + 1] - y[i]) / (T[i + 1] - T[i]);
    return std::pair<double, double>{y[i] + slope * (t - T[i]), slope};
  };
  std::vector<double> probes;
  for (std::size_t i = 0; i + 1 < T.size(); ++i) {
    probes.push_back(T[i]);
    probes.push_back(std::nextafter(T[i], T[i + 1]));
    probes.push_back(std::nextafter(T[i + 1], T[i]));
    probes.push_back(0.5 * (T[i] + T[i + 1]));
  }
  for (int k = 0; k <= 3000; ++k) probes.push_back(20.0 + 0.5 * k);
  for (const double t : probes) {
    if (t >= T.back()) continue;
    const PropertyValue got = table.evaluate(t);
    EXPECT_EQ(got.value, expected(t).first) << "T = " << t;
    EXPECT_EQ(got.slope, expected(t).second) << "T = " << t;
  }
}

TEST(PropertyTable, RejectsMalformedTables) {
  EXPECT_THROW(PropertyTable({0.0, 0.0}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(PropertyTable({100.0, 0.0}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(PropertyTable({0.0, 100.0}, {1.0}), std::invalid_argument);
  EXPECT_THROW(PropertyTable({}, {}), std::invalid_argument);
}

// Curves at 100 degC: (0, 100), (0.1, 200); at 300 degC: (0, 50), (0.1, 150), (0.2, 170).
FlowCurveTable two_curves() {
  return FlowCurveTable({{100.0, {0.0, 0.1}, {100.0, 200.0}},
                         {300.0, {0.0, 0.1, 0.2}, {50.0, 150.0, 170.0}}});
}

TEST(FlowCurveTable, BilinearInStrainAndTemperature) {
  const FlowCurveTable table = two_curves();
  // (0.05, 200 degC): 150 on the lower curve, 100 on the upper, halfway -> 125;
  // both curves harden at 1000 there; dT slope (100 - 150) / 200.
  FlowStress s = table.evaluate(0.05, 200);
  EXPECT_DOUBLE_EQ(s.yield_stress, 125.0);
  EXPECT_DOUBLE_EQ(s.hardening, 1000.0);
  EXPECT_DOUBLE_EQ(s.temperature_slope, -0.25);
  // (0.15, 250 degC): lower curve held at 200 (slope 0), upper 160 (slope 200);
  // weight 3/4 -> 0.25 * 200 + 0.75 * 160 = 170, H = 150, dT = (160 - 200) / 200.
  s = table.evaluate(0.15, 250);
  EXPECT_DOUBLE_EQ(s.yield_stress, 170.0);
  EXPECT_DOUBLE_EQ(s.hardening, 150.0);
  EXPECT_DOUBLE_EQ(s.temperature_slope, -0.2);
  // Outside the temperatures: the nearest curve, no temperature slope.
  EXPECT_DOUBLE_EQ(table.evaluate(0.05, 20).yield_stress, 150.0);
  EXPECT_DOUBLE_EQ(table.evaluate(0.05, 20).temperature_slope, 0.0);
  EXPECT_DOUBLE_EQ(table.evaluate(0.5, 1000).yield_stress, 170.0);
  EXPECT_DOUBLE_EQ(table.evaluate(0.5, 1000).hardening, 0.0);
  // Negative strain reads as zero.
  EXPECT_DOUBLE_EQ(table.evaluate(-1, 100).yield_stress, 100.0);

  const double h = 1e-6;
  for (const auto& [strain, temperature] :
       std::vector<std::pair<double, double>>{{0.03, 150}, {0.12, 280}, {0.17, 210}}) {
    const double d_strain = (table.evaluate(strain + h, temperature).yield_stress -
                             table.evaluate(strain - h, temperature).yield_stress) /
                            (2 * h);
    const double d_temperature = (table.evaluate(strain, temperature + h).yield_stress -
                                  table.evaluate(strain, temperature - h).yield_stress) /
                                 (2 * h);
    EXPECT_NEAR(table.evaluate(strain, temperature).hardening, d_strain, 1e-6);
    EXPECT_NEAR(table.evaluate(strain, temperature).temperature_slope, d_temperature, 1e-6);
  }
}

TEST(FlowCurveTable, RejectsSofteningAndUnsortedCurves) {
  EXPECT_THROW(FlowCurveTable({{20.0, {0.0, 0.1}, {200.0, 150.0}}}), std::invalid_argument);
  EXPECT_THROW(FlowCurveTable({{20.0, {0.1, 0.0}, {100.0, 150.0}}}), std::invalid_argument);
  EXPECT_THROW(FlowCurveTable({{300.0, {0.0}, {100.0}}, {100.0, {0.0}, {50.0}}}),
               std::invalid_argument);
  EXPECT_THROW(FlowCurveTable({{20.0, {0.0}, {0.0}}}), std::invalid_argument);
  EXPECT_THROW(FlowCurveTable(std::vector<FlowCurve>{}), std::invalid_argument);
}

}  // namespace
}  // namespace rsw::materials
