// GP regression (calibration/gaussian_process.hpp) and the optimiser behind it
// (calibration/optimizer.hpp): interpolation without a nugget, robustness to duplicate
// points (jitter escalation), recovery of an injected noise variance by the estimated
// nugget, and the analytic marginal-likelihood gradient against finite differences.
#include "calibration/gaussian_process.hpp"
#include "calibration/optimizer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

namespace rsw::calibration {
namespace {

double uniform01(std::mt19937_64& generator) { return static_cast<double>(generator() >> 11) * 0x1.0p-53; }

double standard_normal(std::mt19937_64& generator) {  // Box–Muller
  const double u1 = 1.0 - uniform01(generator);
  const double u2 = uniform01(generator);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

Eigen::MatrixXd random_points(int n, int d, std::uint64_t seed) {
  std::mt19937_64 generator(seed);
  Eigen::MatrixXd x(n, d);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < d; ++j) x(i, j) = uniform01(generator);
  return x;
}

// A rank-1 lattice (Fibonacci, 34 points) covering [0,1]² evenly.
Eigen::MatrixXd fibonacci_lattice() {
  Eigen::MatrixXd x(34, 2);
  for (int i = 0; i < 34; ++i) {
    x(i, 0) = (i + 0.5) / 34.0;
    x(i, 1) = std::fmod((i * 21 + 0.5) / 34.0, 1.0);
  }
  return x;
}

double smooth_function(const Eigen::VectorXd& x) { return std::sin(3.0 * x(0)) + std::cos(2.0 * x(1)) * x(0) + x(1) * x(1); }

Eigen::VectorXd evaluate(const Eigen::MatrixXd& x, double (*f)(const Eigen::VectorXd&)) {
  Eigen::VectorXd y(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) y(i) = f(x.row(i).transpose());
  return y;
}

TEST(GaussianProcess, InterpolatesNoiseFreeFunction) {
  // Without a nugget the posterior mean passes through the data and the latent variance
  // vanishes there; between points a smooth function is reproduced closely.
  const Eigen::MatrixXd x = fibonacci_lattice();
  const Eigen::VectorXd y = evaluate(x, smooth_function);
  const double range = y.maxCoeff() - y.minCoeff();
  const Eigen::MatrixXd test_points = random_points(200, 2, 7);
  const Eigen::VectorXd truth = evaluate(test_points, smooth_function);
  for (const KernelType kernel : {KernelType::SquaredExponential, KernelType::Matern52}) {
    GaussianProcessOptions options;
    options.kernel = kernel;
    const GaussianProcess gp = GaussianProcessRegression(x, y, options).run();
    const GaussianProcessPrediction at_data = gp.predict(x);
    const GaussianProcessPrediction at_test = gp.predict(test_points);
    const double data_error = (at_data.mean - y).cwiseAbs().maxCoeff();
    const double test_error = (at_test.mean - truth).cwiseAbs().maxCoeff();
    std::printf("kernel %s: max error at data %.2e, between data %.2e (range %.3f), jitter %.1e\n",
                kernel == KernelType::Matern52 ? "Matern52" : "SE", data_error, test_error, range, gp.jitter());
    EXPECT_LT(data_error, 1e-5 * range);
    EXPECT_LT(at_data.latent_variance.maxCoeff(), 1e-6 * gp.hyperparameters().signal_variance);
    EXPECT_EQ(at_data.noise_variance, 0.0);
    EXPECT_LT(test_error, 0.02 * range);
  }
}

TEST(GaussianProcess, DuplicatePointsDoNotBreakFactorisation) {
  // Every point twice, squared-exponential kernel, no nugget: K is exactly singular.
  // The jitter escalation must factorise it, report the jitter, and still interpolate.
  const Eigen::MatrixXd base = random_points(12, 2, 3);
  Eigen::MatrixXd x(24, 2);
  x << base, base;
  const Eigen::VectorXd y = evaluate(x, smooth_function);
  GaussianProcessOptions options;
  options.kernel = KernelType::SquaredExponential;
  const GaussianProcess gp = GaussianProcessRegression(x, y, options).run();
  const GaussianProcessPrediction prediction = gp.predict(x);
  std::printf("jitter used %.3e (mean diagonal %.3e)\n", gp.jitter(), gp.hyperparameters().signal_variance);
  EXPECT_GT(gp.jitter(), 0.0);
  EXPECT_LE(gp.jitter(), options.max_jitter_relative * gp.hyperparameters().signal_variance * 1.000001);
  EXPECT_TRUE(prediction.mean.allFinite());
  EXPECT_TRUE(prediction.latent_variance.allFinite());
  EXPECT_LT((prediction.mean - y).cwiseAbs().maxCoeff(), 1e-3 * (y.maxCoeff() - y.minCoeff()));
}

TEST(GaussianProcess, EstimatedNuggetRecoversInjectedNoiseVariance) {
  // y = f(x) + ε, ε ~ N(0, 0.1²): the estimated nugget τ² must match 0.01 within a factor
  // of 2, and the latent mean must be closer to f than the data are.
  const double noise_sd = 0.1;
  const Eigen::MatrixXd x = random_points(120, 1, 11);
  std::mt19937_64 generator(5);
  Eigen::VectorXd f(x.rows()), y(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    f(i) = std::sin(6.0 * x(i, 0)) + 0.5 * x(i, 0);
    y(i) = f(i) + noise_sd * standard_normal(generator);
  }
  GaussianProcessOptions options;
  options.nugget_mode = NuggetMode::Estimated;
  const GaussianProcess gp = GaussianProcessRegression(x, y, options).run();
  const double tau2 = gp.hyperparameters().noise_variance;
  const GaussianProcessPrediction prediction = gp.predict(x);
  const double latent_rms = std::sqrt((prediction.mean - f).squaredNorm() / x.rows());
  std::printf("injected noise variance %.4f, estimated %.4f (ratio %.3f); latent rms error %.4f\n",
              noise_sd * noise_sd, tau2, tau2 / (noise_sd * noise_sd), latent_rms);
  EXPECT_GT(tau2, 0.5 * noise_sd * noise_sd);
  EXPECT_LT(tau2, 2.0 * noise_sd * noise_sd);
  EXPECT_EQ(prediction.noise_variance, tau2);
  EXPECT_LT(latent_rms, 0.5 * noise_sd);
  // Latent variance at the data is well below the noise variance: the GP averages.
  EXPECT_LT(prediction.latent_variance.maxCoeff(), tau2);
}

TEST(GaussianProcess, LogMarginalLikelihoodGradientMatchesFiniteDifferences) {
  const Eigen::MatrixXd x = random_points(15, 2, 21);
  const Eigen::VectorXd y = evaluate(x, smooth_function);
  for (const KernelType kernel : {KernelType::SquaredExponential, KernelType::Matern52}) {
    for (const TrendType trend : {TrendType::Constant, TrendType::DiagonalQuadratic, TrendType::FullQuadratic}) {
      GaussianProcessOptions options;
      options.kernel = kernel;
      options.trend = trend;
      options.nugget_mode = NuggetMode::Estimated;
      const GaussianProcessRegression regression(x, y, options);
      ASSERT_EQ(regression.trend_used(), trend);
      GaussianProcessHyperparameters h;
      h.length_scales = Eigen::Vector2d(0.35, 0.6);
      h.signal_variance = 0.8;
      h.noise_variance = 3e-3;
      const Eigen::VectorXd eta = regression.to_log_vector(h);
      Eigen::VectorXd gradient;
      regression.log_marginal_likelihood(eta, &gradient);
      ASSERT_EQ(gradient.size(), 4);
      for (Eigen::Index j = 0; j < eta.size(); ++j) {
        const double step = 1e-5;
        Eigen::VectorXd plus = eta, minus = eta;
        plus(j) += step;
        minus(j) -= step;
        const double fd =
            (regression.log_marginal_likelihood(plus) - regression.log_marginal_likelihood(minus)) / (2.0 * step);
        EXPECT_NEAR(gradient(j), fd, 1e-6 * std::max(1.0, std::abs(fd)))
            << "kernel " << static_cast<int>(kernel) << " trend " << static_cast<int>(trend) << " component " << j;
      }
    }
  }
}

TEST(GaussianProcess, QuadraticTrendFallsBackToConstantWithTooFewPoints) {
  // A full quadratic in 2-D has 6 terms; 5 points cannot support it.
  const Eigen::MatrixXd x = random_points(5, 2, 2);
  const Eigen::VectorXd y = evaluate(x, smooth_function);
  GaussianProcessOptions options;
  options.trend = TrendType::FullQuadratic;
  const GaussianProcess gp = GaussianProcessRegression(x, y, options).run();
  EXPECT_EQ(gp.trend_used(), TrendType::Constant);
  EXPECT_EQ(gp.trend_coefficients().size(), 1);
}

TEST(BoundedMinimizer, FindsRosenbrockMinimumWithAndWithoutGradient) {
  // f = (1 − x)² + 100 (y − x²)², minimum 0 at (1, 1); NaN for x < −1.5 forces the
  // L-BFGS runs that step there onto the derivative-free fallback.
  const ObjectiveFunction rosenbrock = [](const Eigen::VectorXd& v, Eigen::VectorXd* gradient) {
    if (v(0) < -1.5) return std::numeric_limits<double>::quiet_NaN();
    const double a = 1.0 - v(0), b = v(1) - v(0) * v(0);
    if (gradient != nullptr) *gradient = Eigen::Vector2d(-2.0 * a - 400.0 * v(0) * b, 200.0 * b);
    return a * a + 100.0 * b * b;
  };
  const std::vector<Eigen::VectorXd> starts = {Eigen::Vector2d(-1.2, 1.0), Eigen::Vector2d(0.0, -1.0),
                                               Eigen::Vector2d(-1.49, 1.9)};
  for (const OptimizerMethod method : {OptimizerMethod::Lbfgs, OptimizerMethod::DerivativeFree}) {
    OptimizerOptions options;
    options.method = method;
    options.max_evaluations_per_start = 2000;
    const OptimizerResult result =
        BoundedMinimizer(rosenbrock, Eigen::Vector2d(-2.0, -2.0), Eigen::Vector2d(2.0, 2.0), options).run(starts);
    ASSERT_TRUE(result.found);
    EXPECT_NEAR(result.x(0), 1.0, 1e-3);
    EXPECT_NEAR(result.x(1), 1.0, 2e-3);
    EXPECT_LT(result.value, 1e-6);
  }
}

}  // namespace
}  // namespace rsw::calibration
