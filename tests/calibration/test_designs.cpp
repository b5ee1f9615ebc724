// Designs of experiments (calibration/designs.*): the Latin property, reproducibility
// from the seed, the maximin improvement, the Hammersley construction and its strict
// interior, one-at-a-time sweeps.
#include "calibration/designs.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <set>
#include <stdexcept>

namespace rsw::calibration {
namespace {

void expect_latin(const Eigen::MatrixXd& points) {
  const Eigen::Index n = points.rows();
  for (Eigen::Index j = 0; j < points.cols(); ++j) {
    std::set<long> strata;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double x = points(i, j);
      ASSERT_GT(x, 0);
      ASSERT_LT(x, 1);
      strata.insert(static_cast<long>(std::floor(x * static_cast<double>(n))));
    }
    EXPECT_EQ(static_cast<Eigen::Index>(strata.size()), n) << "dimension " << j;
  }
}

TEST(Lhs, EachStratumHitOncePerDimension) {
  expect_latin(latin_hypercube(90, 6, 2024));
  LatinHypercubeOptions maximin;
  maximin.n_maximin_swaps = 2000;
  expect_latin(latin_hypercube(90, 6, 2024, maximin));
  LatinHypercubeOptions centred;
  centred.centred = true;
  const Eigen::MatrixXd midpoints = latin_hypercube(10, 3, 1, centred);
  expect_latin(midpoints);
  for (Eigen::Index i = 0; i < midpoints.size(); ++i) {
    const double scaled = midpoints.data()[i] * 10 - 0.5;
    EXPECT_NEAR(scaled, std::round(scaled), 1e-12);
  }
}

TEST(Lhs, SameSeedSameDesign) {
  LatinHypercubeOptions maximin;
  maximin.n_maximin_swaps = 500;
  EXPECT_EQ(latin_hypercube(40, 4, 7, maximin), latin_hypercube(40, 4, 7, maximin));
  EXPECT_NE(latin_hypercube(40, 4, 7), latin_hypercube(40, 4, 8));
  // Pinned values: the draws are our own (not std distributions), so they are the same
  // with every standard library.
  const Eigen::MatrixXd design = latin_hypercube(3, 2, 42);
  Eigen::MatrixXd pinned(3, 2);
  pinned << 0.25071506691600892, 0.79096256648539498,  //
      0.37875756121081233, 0.42462470057905694,        //
      0.96775632214279284, 0.13009029380476453;
  EXPECT_NEAR((design - pinned).cwiseAbs().maxCoeff(), 0, 1e-15);
}

TEST(Lhs, MaximinSwapsIncreaseTheSmallestDistance) {
  const Eigen::MatrixXd plain = latin_hypercube(50, 3, 11);
  LatinHypercubeOptions maximin;
  maximin.n_maximin_swaps = 5000;
  const Eigen::MatrixXd improved = latin_hypercube(50, 3, 11, maximin);
  const double before = minimum_distance(plain);
  const double after = minimum_distance(improved);
  std::cout << "[ figures  ] LHS 50 x 3 minimum distance: plain " << before << ", after 5000 "
            << "maximin swaps " << after << "\n";
  EXPECT_GT(after, 1.5 * before);
}

TEST(Hammersley, CoordinatesStrictlyInsideUnitCube) {
  for (std::size_t n : {1u, 2u, 5u, 7u, 64u, 100u}) {
    const Eigen::MatrixXd points = hammersley(n, 6);
    EXPECT_GT(points.minCoeff(), 0) << "n = " << n;
    EXPECT_LT(points.maxCoeff(), 1) << "n = " << n;
  }
}

TEST(Hammersley, FirstCoordinateIsCentredGridOthersShiftedRadicalInverses) {
  const Eigen::MatrixXd points = hammersley(8, 3);
  // Base 2 for dimension 2: 0, 1/2, 1/4, 3/4, 1/8, 5/8, 3/8, 7/8, shifted by 1/16.
  const double van_der_corput[] = {0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875};
  for (int i = 0; i < 8; ++i) {
    EXPECT_DOUBLE_EQ(points(i, 0), (i + 0.5) / 8);
    EXPECT_DOUBLE_EQ(points(i, 1), van_der_corput[i] + 1.0 / 16);
    // Base 3, n = 8 < 9 = 3²: spacing 1/9, shift 1/18.
    EXPECT_NEAR(points(i, 2), radical_inverse(static_cast<std::uint64_t>(i), 3) + 1.0 / 18, 1e-15);
  }
  EXPECT_NEAR(radical_inverse(5, 3), 2.0 / 3 + 1.0 / 9, 1e-15);  // 5 = 12 in base 3
  EXPECT_EQ(first_primes(6), (std::vector<std::uint64_t>{2, 3, 5, 7, 11, 13}));
}

TEST(OneAtATime, SweepsOneCoordinateAtATime) {
  const Eigen::Vector3d nominal(0.2, 0.5, 0.8);
  const OneAtATimeDesign design =
      one_at_a_time(nominal, {2, 0}, {centred_levels(4), Eigen::Vector2d(0.0, 1.0)});
  ASSERT_EQ(design.points.rows(), 6);
  for (Eigen::Index r = 0; r < 6; ++r) {
    const std::size_t swept = design.swept_dimension[static_cast<std::size_t>(r)];
    for (Eigen::Index j = 0; j < 3; ++j) {
      if (static_cast<std::size_t>(j) != swept) {
        EXPECT_EQ(design.points(r, j), nominal[j]);
      }
    }
  }
  EXPECT_EQ(design.points(0, 2), 0.125);
  EXPECT_EQ(design.points(3, 2), 0.875);
  EXPECT_EQ(design.points(5, 0), 1.0);
  EXPECT_THROW(one_at_a_time(nominal, {3}, {centred_levels(2)}), std::invalid_argument);
}

TEST(RandomPoints, AreInsideTheOpenCubeAndReproducible) {
  const Eigen::MatrixXd points = random_unit_points(1000, 4, 3);
  EXPECT_GT(points.minCoeff(), 0);
  EXPECT_LT(points.maxCoeff(), 1);
  EXPECT_NEAR(points.mean(), 0.5, 0.02);
  EXPECT_EQ(points, random_unit_points(1000, 4, 3));
}

}  // namespace
}  // namespace rsw::calibration
