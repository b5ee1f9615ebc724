// Gaussian log-likelihood of named features (calibration/likelihood.hpp): the three
// ways to set Σ, replicates, the model-discrepancy variance, and matching by name.
// Expected values are computed here term by term from
//     ln L = −½ Σ_k Σ_j (y_kj − M_j)²/Σ_jj − (N_obs/2) Σ_j ln(2π Σ_jj).
#include "calibration/likelihood.hpp"

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
  EXPECT_NEAR(likelihood.log_normalisation(),
              -1.5 * (3.0 * std::log(2.0 * M_PI) + variances.array().log().sum()), 1e-9);
  // The maximum over M is at the replicate mean, and a residual lowers ln L.
  const Eigen::Vector3d mean = y.colwise().mean().transpose();
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

TEST(GaussianLikelihood, DiscrepancyVarianceAddsToMeasurementVariance) {
  const Eigen::MatrixXd y = three_replicates();
  const GaussianLikelihood likelihood(kNames, y, ObservationNoise::relative(0.05), {{"peak_resistance", 4e-11}});
  EXPECT_NEAR(likelihood.variances()(1) - likelihood.measurement_variances()(1), 4e-11, 1e-20);
  EXPECT_EQ(likelihood.variances()(0), likelihood.measurement_variances()(0));
  const Eigen::Vector3d model(5.2e-3, 140e-6, 0.22e-3);
  EXPECT_NEAR(likelihood.log_likelihood(model), reference_log_likelihood(y, model, likelihood.variances()), 1e-9);
  EXPECT_THROW(GaussianLikelihood(kNames, y, ObservationNoise::relative(0.05), {{"weld_time", 1.0}}),
               std::invalid_argument);
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
