// Priors and the parameter space (calibration/parameter_space.*): CDFs against their
// closed forms, physical ↔ standardised round trips for every prior kind, densities
// that integrate to one, and the paper's Table I in SI units.
#include "calibration/parameter_space.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rsw::calibration {
namespace {

// ∫ exp(log_density) over [a, b] by composite Simpson in the variable x = g(v).
template <class Transform, class Jacobian>
double integrate_density(const Prior& prior, double v_lower, double v_upper, Transform x_of,
                         Jacobian dx_dv, int n_intervals = 20000) {
  const double h = (v_upper - v_lower) / n_intervals;
  double sum = 0;
  for (int i = 0; i <= n_intervals; ++i) {
    const double v = i == n_intervals ? v_upper : v_lower + i * h;  // the last node exactly at the bound
    const double weight = (i == 0 || i == n_intervals) ? 1 : (i % 2 == 1 ? 4 : 2);
    sum += weight * std::exp(prior.log_density(x_of(v))) * dx_dv(v);
  }
  return sum * h / 3;
}

TEST(Prior, Log10UniformCdfIsLinearInLog10) {
  const Prior prior = Prior::log10_uniform(1e-7, 5e-4);
  const double span = std::log10(5e-4) - std::log10(1e-7);
  for (double x : {1e-7, 3e-7, 1e-6, 2.5e-5, 5e-4}) {
    EXPECT_NEAR(prior.cdf(x), (std::log10(x) + 7) / span, 1e-14) << x;
  }
  EXPECT_NEAR(prior.cdf(std::sqrt(1e-7 * 5e-4)), 0.5, 1e-14);  // the geometric midpoint
  EXPECT_EQ(prior.cdf(1e-8), 0);
  EXPECT_EQ(prior.cdf(1), 1);
  EXPECT_NEAR(prior.quantile(0.5), std::sqrt(1e-7 * 5e-4), 1e-18);
  EXPECT_EQ(prior.standard_space(), StandardSpace::unit_interval);
  // Density 1 / (x ln 10 · span): equal mass per decade.
  EXPECT_NEAR(std::exp(prior.log_density(1e-6)), 1 / (1e-6 * std::log(10.0) * span), 1e-3);
  EXPECT_EQ(prior.log_density(1e-3), -std::numeric_limits<double>::infinity());
}

TEST(Prior, TransformsRoundTripForEveryKind) {
  const Prior priors[] = {Prior::uniform(35, 200), Prior::log10_uniform(1e-3, 1e-1),
                          Prior::normal(2.1e-6, 3e-7), Prior::truncated_normal(100, 30, 35, 200),
                          Prior::truncated_normal(0, 1, 5, 6)};  // far upper tail
  for (const Prior& prior : priors) {
    for (double p : {1e-9, 0.01, 0.3, 0.5, 0.77, 0.999}) {
      const double x = prior.quantile(p);
      EXPECT_NEAR(prior.cdf(x), p, 1e-14 + 1e-12 * p)
          << prior.describe() << " p = " << p;
      const double s = prior.to_standard(x);
      EXPECT_NEAR(prior.to_physical(s), x, 1e-12 * std::abs(x) + 1e-300) << prior.describe();
    }
  }
  // A normal prior is standardised to z, not to a probability.
  const Prior normal = Prior::normal(10, 2);
  EXPECT_EQ(normal.standard_space(), StandardSpace::standard_normal);
  EXPECT_DOUBLE_EQ(normal.to_standard(13), 1.5);
  EXPECT_DOUBLE_EQ(normal.to_physical(-0.5), 9);
}

TEST(Prior, StandardNormalQuantileIsAccurateToMachinePrecision) {
  EXPECT_NEAR(standard_normal_quantile(0.975), 1.959963984540054, 1e-15);
  EXPECT_NEAR(standard_normal_quantile(0.5), 0, 1e-16);
  EXPECT_NEAR(standard_normal_quantile(1e-10), -6.361340902404056, 1e-13);
  for (double p : {1e-300, 1e-20, 0.02, 0.02425, 0.1, 0.6, 0.97575, 0.99, 1 - 1e-12}) {
    const double z = standard_normal_quantile(p);
    const double back = z < 0 ? standard_normal_cdf(z) : 1 - 0.5 * std::erfc(z / std::sqrt(2.0));
    EXPECT_NEAR(back, p, 1e-12 * std::min(p, 1 - p) + (p > 0.5 ? 3e-16 : 0)) << "p = " << p;
  }
  EXPECT_EQ(standard_normal_quantile(0), -std::numeric_limits<double>::infinity());
  EXPECT_THROW(standard_normal_quantile(1.5), std::invalid_argument);
}

TEST(Prior, TruncatedNormalCdfMatchesItsDefinition) {
  const Prior prior = Prior::truncated_normal(100, 30, 35, 200);
  auto phi = [](double x) { return standard_normal_cdf((x - 100) / 30); };
  for (double x : {40.0, 99.0, 150.0, 199.0}) {
    EXPECT_NEAR(prior.cdf(x), (phi(x) - phi(35)) / (phi(200) - phi(35)), 1e-14) << x;
  }
  // Far upper tail [5σ, 6σ]: Φ(5) and Φ(6) round to nearly 1, the tail form does not.
  const Prior tail = Prior::truncated_normal(0, 1, 5, 6);
  const double median = tail.quantile(0.5);
  EXPECT_GT(median, 5);
  EXPECT_LT(median, 5.2);
  EXPECT_NEAR(tail.cdf(median), 0.5, 1e-12);
}

TEST(Prior, DensitiesIntegrateToOne) {
  const Prior log_uniform = Prior::log10_uniform(1e-3, 1e-1);
  // In v = log10 x: dx = x ln 10 dv.
  EXPECT_NEAR(integrate_density(
                  log_uniform, -3, -1, [](double v) { return std::pow(10.0, v); },
                  [](double v) { return std::pow(10.0, v) * std::log(10.0); }),
              1, 1e-10);
  const Prior truncated = Prior::truncated_normal(100, 30, 35, 200);
  auto identity = [](double v) { return v; };
  auto one = [](double) { return 1.0; };
  EXPECT_NEAR(integrate_density(truncated, 35, 200, identity, one), 1, 1e-10);
  EXPECT_NEAR(integrate_density(Prior::normal(2, 0.5), -8, 12, identity, one), 1, 1e-10);
  EXPECT_NEAR(integrate_density(Prior::uniform(35, 200), 35, 200, identity, one), 1, 1e-12);
}

TEST(Prior, InvalidRangesAreRejected) {
  EXPECT_THROW(Prior::uniform(2, 1), std::invalid_argument);
  EXPECT_THROW(Prior::log10_uniform(0, 1), std::invalid_argument);
  EXPECT_THROW(Prior::normal(0, 0), std::invalid_argument);
  EXPECT_THROW(Prior::truncated_normal(0, 1, 40, 41), std::invalid_argument);  // no mass
  EXPECT_THROW(Prior::uniform(0, std::numeric_limits<double>::infinity()), std::invalid_argument);
}

TEST(ParameterSpace, PaperTableOneIsInSiUnitsWithConfigKeys) {
  const ParameterSpace space = paper_parameter_space();
  ASSERT_EQ(space.n_parameters(), 6u);
  const Parameter& film = space.parameter("film_thickness_ss");
  EXPECT_EQ(film.config_key, "contact.sheet_sheet.film_thickness");
  EXPECT_EQ(film.prior.kind(), PriorKind::log10_uniform);
  EXPECT_DOUBLE_EQ(film.prior.lower(), 1e-4 * 1e-3);  // 1e-4 mm
  EXPECT_DOUBLE_EQ(film.prior.upper(), 5e-1 * 1e-3);  // 5e-1 mm
  EXPECT_EQ(space.parameter("film_thickness_es").config_key, "contact.electrode_sheet.film_thickness");
  EXPECT_EQ(space.parameter("coating_resistivity_ss").prior.lower(), 5e-7);
  EXPECT_EQ(space.parameter("coating_resistivity_es").prior.upper(), 5e-5);
  EXPECT_EQ(space.parameter("htc_p1").config_key, "contact.electrode_sheet.htc_p1");
  EXPECT_EQ(space.parameter("htc_p1").prior.upper(), 1e-1);
  const Parameter& melt = space.parameter("melt_conductivity");
  EXPECT_EQ(melt.config_key, "thermal.melt_conductivity");
  EXPECT_EQ(melt.prior.kind(), PriorKind::uniform);
  EXPECT_EQ(melt.prior.lower(), 35);
  EXPECT_EQ(melt.prior.upper(), 200);
  EXPECT_EQ(space.index_of("htc_p1"), 4u);
  EXPECT_THROW(space.index_of("P1"), std::invalid_argument);
}

TEST(ParameterSpace, PointsMapThroughTheInverseCdfAndBack) {
  ParameterSpace space({{"a", "x.a", "1", Prior::log10_uniform(1e-3, 1e-1)},
                        {"b", "x.b", "1", Prior::normal(5, 2)},
                        {"c", "x.c", "1", Prior::uniform(35, 200)}});
  const Eigen::Vector3d unit(0.5, 0.975, 0.2);
  const Eigen::VectorXd standard = space.unit_to_standard(unit);
  EXPECT_DOUBLE_EQ(standard[0], 0.5);
  EXPECT_NEAR(standard[1], 1.959963984540054, 1e-15);
  const Eigen::VectorXd physical = space.to_physical(standard);
  EXPECT_NEAR(physical[0], 1e-2, 1e-16);
  EXPECT_NEAR(physical[1], 5 + 2 * 1.959963984540054, 1e-14);
  EXPECT_NEAR(physical[2], 68, 1e-13);
  EXPECT_NEAR((space.to_standard(physical) - standard).norm(), 0, 1e-14);

  Eigen::MatrixXd rows(2, 3);
  rows << 0.1, -1, 0.9, 0.7, 0.3, 0.05;
  const Eigen::MatrixXd back = space.points_to_standard(space.points_to_physical(rows));
  EXPECT_NEAR((back - rows).norm(), 0, 1e-13);
  EXPECT_EQ(space.standard_spaces()[1], StandardSpace::standard_normal);

  const auto assignments = space.config_assignments(physical);
  ASSERT_EQ(assignments.size(), 3u);
  EXPECT_EQ(assignments[2].first, "x.c");
  EXPECT_EQ(assignments[2].second, physical[2]);
  EXPECT_NEAR(space.log_prior_density(physical),
              space.parameter(0).prior.log_density(physical[0]) +
                  space.parameter(1).prior.log_density(physical[1]) - std::log(165.0),
              1e-12);
  EXPECT_THROW(space.to_physical(Eigen::Vector2d(0.5, 0.5)), std::invalid_argument);
}

TEST(ParameterSpace, DuplicateNamesAndConfigKeysAreRejected) {
  ParameterSpace space;
  space.add({"a", "x.a", "1", Prior::uniform(0, 1)});
  EXPECT_THROW(space.add({"a", "x.b", "1", Prior::uniform(0, 1)}), std::invalid_argument);
  EXPECT_THROW(space.add({"b", "x.a", "1", Prior::uniform(0, 1)}), std::invalid_argument);
  EXPECT_THROW(space.add({"", "x.c", "1", Prior::uniform(0, 1)}), std::invalid_argument);
}

}  // namespace
}  // namespace rsw::calibration
