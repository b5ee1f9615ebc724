// Gaussian log-likelihood of named features (calibration/likelihood.hpp): the three
// ways to set Σ, replicates, the model-discrepancy variance, and matching by name.
// Expected values are computed here term by term from
//     ln L = −½ Σ_k Σ_j (y_kj − M_j)²/Σ_jj − (N_obs/2) Σ_j ln(2π Σ_jj)
// without a discrepancy, and with one from the replicates' joint normal density.
#include "calibration/likelihood.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rsw::calibration {
namespace {

// Term-by-term reference with explicit loops.
double reference_log_likelihood(const Eigen::MatrixXd& observations, const Eigen::VectorXd& model,
                                const Eigen::VectorXd& variances) {
  double value = 0.0;
  for (Eigen::Index k = 0; k < observations.rows(); ++k)
    for (Eigen::Index j = 0; j < observations.cols(); ++j) {
      const double r = observations(k, j) - model(j);
      value += -0.5 * r * r / variances(j) - 0.5 * std::log(2.0 * M_PI * variances(j));
    }
  return value;
}

const std::vector<std::string> kNames = {"nugget_diameter", "peak_resistance", "final_displacement"};

Eigen::MatrixXd three_replicates() {
  Eigen::MatrixXd y(3, 3);
  y << 5.1e-3, 152e-6, 0.21e-3,  //
      5.3e-3, 148e-6, 0.19e-3,   //
      4.9e-3, 150e-6, 0.23e-3;
  return y;
}

TEST(GaussianLikelihood, ReplicatesWithGivenSigmaMatchTermByTermSum) {
  const Eigen::MatrixXd y = three_replicates();
  const GaussianLikelihood likelihood(
      kNames, y, ObservationNoise::given({{"nugget_diameter", 0.2e-3}, {"peak_resistance", 5e-6},
                                          {"final_displacement", 0.03e-3}}));
  const Eigen::Vector3d model(5.0e-3, 151e-6, 0.2e-3);
  const Eigen::Vector3d variances(0.2e-3 * 0.2e-3, 5e-6 * 5e-6, 0.03e-3 * 0.03e-3);
  EXPECT_EQ(likelihood.n_replicates(), 3);
  EXPECT_NEAR(likelihood.log_likelihood(model), reference_log_likelihood(y, model, variances), 1e-9);
  // The θ-free part is ln L at the replicate mean, where the mean's residual vanishes;
  // there ln L is largest, and a residual lowers it.
  const Eigen::Vector3d mean = y.colwise().mean().transpose();
  EXPECT_NEAR(likelihood.log_normalisation(), reference_log_likelihood(y, mean, variances), 1e-9);
  EXPECT_GT(likelihood.log_likelihood(mean), likelihood.log_likelihood(model));
}

TEST(GaussianLikelihood, RelativeSigmaUsesObservedMean) {
  const Eigen::MatrixXd y = three_replicates();
  const GaussianLikelihood likelihood(kNames, y, ObservationNoise::relative(0.05));
  const Eigen::Vector3d mean = y.colwise().mean().transpose();
  const Eigen::Vector3d variances = (0.05 * mean).cwiseAbs2();
  EXPECT_TRUE(likelihood.variances().isApprox(variances, 1e-12));
  const Eigen::Vector3d model(5.2e-3, 149e-6, 0.22e-3);
  EXPECT_NEAR(likelihood.log_likelihood(model), reference_log_likelihood(y, model, variances), 1e-9);
}

TEST(GaussianLikelihood, ReplicateScatterUsesSampleStandardDeviation) {
  const Eigen::MatrixXd y = three_replicates();
  const GaussianLikelihood likelihood(kNames, y, ObservationNoise::replicate_scatter());
  // Sample variance with the N − 1 denominator, e.g. nugget diameter: deviations ±0.2e-3, 0.
  EXPECT_NEAR(likelihood.variances()(0), (0.2e-3 * 0.2e-3 * 2.0) / 2.0, 1e-15);
  EXPECT_NEAR(likelihood.variances()(1), (4e-12 + 4e-12) / 2.0, 1e-20);
  EXPECT_THROW(GaussianLikelihood(kNames, y.topRows(1), ObservationNoise::replicate_scatter()),
               std::invalid_argument);
}

// The multivariate normal log-density of the replicates of one feature, covariance
// σ² I + δ² 11ᵀ, by a Cholesky factorisation: the discrepancy shared by the replicates.
double shared_discrepancy_density(const Eigen::VectorXd& y, double model, double sigma2, double delta2) {
  const Eigen::Index n = y.size();
  const Eigen::MatrixXd covariance =
      sigma2 * Eigen::MatrixXd::Identity(n, n) + delta2 * Eigen::MatrixXd::Ones(n, n);
  const Eigen::LLT<Eigen::MatrixXd> llt(covariance);
  const Eigen::VectorXd r = y.array() - model;
  const double log_det = 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
  return -0.5 * r.dot(llt.solve(r)) - 0.5 * (static_cast<double>(n) * std::log(2.0 * M_PI) + log_det);
}

TEST(GaussianLikelihood, DiscrepancyIsSharedByTheReplicatesAsInKennedyOHagan) {
  const Eigen::MatrixXd y = three_replicates();
  const double delta2 = 4e-11;  // (6.3 µΩ)² on peak_resistance
  const GaussianLikelihood likelihood(kNames, y, ObservationNoise::relative(0.05), {{"peak_resistance", delta2}});
  EXPECT_NEAR(likelihood.variances()(1) - likelihood.measurement_variances()(1), delta2, 1e-20);
  EXPECT_EQ(likelihood.discrepancy_variances()(1), delta2);
  EXPECT_EQ(likelihood.variances()(0), likelihood.measurement_variances()(0));
  EXPECT_NEAR(likelihood.mean_variances()(1), likelihood.measurement_variances()(1) / 3.0 + delta2, 1e-24);
  const Eigen::Vector3d model(5.2e-3, 140e-6, 0.22e-3);
  double expected = 0.0;
  for (Eigen::Index j = 0; j < 3; ++j)
    expected += shared_discrepancy_density(y.col(j), model(j), likelihood.measurement_variances()(j),
                                           j == 1 ? delta2 : 0.0);
  EXPECT_NEAR(likelihood.log_likelihood(model), expected, 1e-9);
  // One replicate: the discrepancy simply adds to the variance.
  const GaussianLikelihood single(kNames, y.topRows(1), ObservationNoise::relative(0.05), {{"peak_resistance", delta2}});
  EXPECT_NEAR(single.log_likelihood(model), reference_log_likelihood(y.topRows(1), model, single.variances()), 1e-9);
  EXPECT_THROW(GaussianLikelihood(kNames, y, ObservationNoise::relative(0.05), {{"weld_time", 1.0}}),
               std::invalid_argument);
}

TEST(GaussianLikelihood, ManyReplicatesDoNotAverageTheDiscrepancyAway) {
  // 3 and 300 replicates with the same mean and σ: the curvature of ln L in M,
  // 1/(σ²/N + δ²), is bounded by 1/δ² however many welds are measured.
  const double sigma = 2.0, delta = 0.5;
  for (const int n : {3, 300}) {
    Eigen::MatrixXd y(n, 1);
    for (int k = 0; k < n; ++k) y(k, 0) = 10.0 + (k % 2 == 0 ? 1.0 : -1.0) * (k == n - 1 && n % 2 ? 0.0 : 1.0);
    const GaussianLikelihood likelihood({"f"}, y, ObservationNoise::given({{"f", sigma}}), {{"f", delta * delta}});
    const double m0 = y.mean(), h = 0.1;
    const auto at = [&](double m) { return likelihood.log_likelihood(Eigen::VectorXd::Constant(1, m)); };
    const double curvature = -(at(m0 + h) - 2.0 * at(m0) + at(m0 - h)) / (h * h);
    EXPECT_NEAR(curvature, 1.0 / (sigma * sigma / n + delta * delta), 1e-6 * curvature) << n << " replicates";
    EXPECT_LT(curvature, 1.0 / (delta * delta));
  }
}

TEST(GaussianLikelihood, SeveralReplicatesNeedAPositiveMeasurementSpread) {
  const Eigen::MatrixXd y = three_replicates();
  try {
    GaussianLikelihood(kNames, y, ObservationNoise::relative(0.0),
                       {{"nugget_diameter", 1e-8}, {"peak_resistance", 1e-12}, {"final_displacement", 1e-10}});
    FAIL() << "σ = 0 with three replicates must throw";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("nugget_diameter"), std::string::npos) << error.what();
  }
  EXPECT_NO_THROW(GaussianLikelihood(kNames, y.topRows(1), ObservationNoise::relative(0.0),
                                     {{"nugget_diameter", 1e-8}, {"peak_resistance", 1e-12},
                                      {"final_displacement", 1e-10}}));
}

TEST(GaussianLikelihood, MatchesModelFeaturesByNameAndNamesAMissingOne) {
  const Eigen::MatrixXd y = three_replicates();
  const GaussianLikelihood likelihood(kNames, y, ObservationNoise::relative(0.05));
  const Eigen::Vector3d ordered(5.2e-3, 149e-6, 0.22e-3);
  // The model reports more features, in another order.
  const std::vector<std::string> model_names = {"peak_temperature", "final_displacement", "nugget_diameter",
                                                "peak_resistance"};
  const Eigen::Vector4d model_values(1500.0, 0.22e-3, 5.2e-3, 149e-6);
  EXPECT_DOUBLE_EQ(likelihood.log_likelihood(model_names, model_values), likelihood.log_likelihood(ordered));
  try {
    likelihood.log_likelihood({"nugget_diameter", "final_displacement"}, Eigen::Vector2d(5.2e-3, 0.22e-3));
    FAIL() << "a missing feature must throw";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("peak_resistance"), std::string::npos) << error.what();
  }
}

TEST(GaussianLikelihood, UndefinedModelFeatureHasNoLikelihoodAndNamesTheFeature) {
  const GaussianLikelihood likelihood(kNames, three_replicates(), ObservationNoise::relative(0.05));
  try {
    likelihood.log_likelihood(Eigen::Vector3d(5.2e-3, std::numeric_limits<double>::quiet_NaN(), 0.22e-3));
    FAIL() << "a NaN model feature must throw";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("feature 'peak_resistance' is undefined (NaN) for this run"),
              std::string::npos) << error.what();
  }
  EXPECT_THROW(likelihood.log_likelihood(Eigen::Vector3d(5.2e-3, 149e-6, std::numeric_limits<double>::infinity())),
               std::invalid_argument);
}

TEST(GaussianLikelihood, ZeroVarianceIsRejectedNamingTheFeature) {
  Eigen::MatrixXd y = three_replicates();
  y.col(2).setConstant(0.2e-3);  // no scatter
  try {
    GaussianLikelihood(kNames, y, ObservationNoise::replicate_scatter());
    FAIL() << "zero scatter must throw";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("final_displacement"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace rsw::calibration
