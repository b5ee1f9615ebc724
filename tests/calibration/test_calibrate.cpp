// The calibration run (calibration/calibrate.*) and the calibration section of study
// files (calibration/calibration_study.*):
//   - a linear-Gaussian model calibrated through the evaluation farm gives the evidence
//     (within 10 %) and posterior mean and standard deviation of the closed form
//     (verification; prints its figures);
//   - a calibration killed with SIGKILL mid-batch and resumed reuses every finished run
//     and ends bit for bit like an uninterrupted one; an existing folder needs resume;
//   - a run that leaves a likelihood feature undefined (NaN) is a failed run with the
//     reason, outside the GP; an observed signal with an undefined feature is an error;
//   - observations from signal files and from a features file of the same values give
//     the same likelihood; replicate scatter, relative and given noise, discrepancy;
//   - bad observation files and bad calibration keys are errors naming the file, line,
//     key, value and what is allowed; the shipped twin-experiment studies load.
#include "calibration/calibrate.hpp"
#include "calibration/calibration_study.hpp"
#include "calibration/farm.hpp"
#include "calibration/features.hpp"
#include "calibration/study.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <thread>

namespace rsw::calibration {
namespace {

namespace fs = std::filesystem;

const fs::path source_dir = RSW_SOURCE_DIR;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_calibrate_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

fs::path write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  return path;
}

// y = b + A θ with two parameters and three features; optionally slow.
class LinearModel : public ForwardModel {
 public:
  LinearModel(Eigen::MatrixXd a, Eigen::VectorXd b, double delay = 0) : a_(std::move(a)), b_(std::move(b)), delay_(delay) {}
  std::vector<std::string> parameter_names() const override { return {"p", "q"}; }
  std::vector<std::string> feature_names() const override { return {"y1", "y2", "y3"}; }
  EvaluationResult evaluate(const Eigen::VectorXd& theta) const override {
    if (delay_ > 0) std::this_thread::sleep_for(std::chrono::duration<double>(delay_));
    return EvaluationResult::success(b_ + a_ * theta);
  }

 private:
  Eigen::MatrixXd a_;
  Eigen::VectorXd b_;
  double delay_;
};

// The linear model whose feature y2 is undefined (NaN) for p > p_undefined, as a weld
// feature whose signal lacks the shape it needs.
class PartlyUndefinedLinearModel : public LinearModel {
 public:
  PartlyUndefinedLinearModel(Eigen::MatrixXd a, Eigen::VectorXd b, double p_undefined)
      : LinearModel(std::move(a), std::move(b)), p_undefined_(p_undefined) {}
  EvaluationResult evaluate(const Eigen::VectorXd& theta) const override {
    Eigen::VectorXd y = LinearModel::evaluate(theta).features();
    if (theta(0) > p_undefined_) y(1) = std::numeric_limits<double>::quiet_NaN();
    return EvaluationResult::success(y);
  }

 private:
  double p_undefined_;
};

// The linear model that succeeds with a warning for p > p_warn, as a weld whose
// electrode reaches its solidus.
class WarningLinearModel : public LinearModel {
 public:
  WarningLinearModel(Eigen::MatrixXd a, Eigen::VectorXd b, double p_warn)
      : LinearModel(std::move(a), std::move(b)), p_warn_(p_warn) {}
  EvaluationResult evaluate(const Eigen::VectorXd& theta) const override {
    Eigen::VectorXd y = LinearModel::evaluate(theta).features();
    return EvaluationResult::success(y, theta(0) > p_warn_ ? "electrode above its solidus" : "");
  }

 private:
  double p_warn_;
};

// The linear-Gaussian problem with p ~ U[2, 6], q ~ U[−1, 1] (box volume V = 8), three
// replicates and known σ. ℒ(θ) = ℒ(θ̂) − ½ (θ − θ̂)ᵀ P (θ − θ̂), P = N AᵀΣ⁻¹A and
// θ̂ = P⁻¹ AᵀΣ⁻¹ Σ_k (y_k − b), so with θ̂ far inside the box
//     c = (1/V) ∫ exp ℒ dθ = exp ℒ(θ̂) · 2π / √det P / V,
// the posterior is N(θ̂, P⁻¹), and the truncated mass is below Σ_j erfc(d_j/(√2 sd_j)).
struct LinearGaussianProblem {
  Eigen::MatrixXd a = (Eigen::MatrixXd(3, 2) << 1.0, 0.5, 0.3, 2.0, 0.8, -1.5).finished();
  Eigen::VectorXd b = Eigen::Vector3d(1.0, 2.0, 3.0);
  Eigen::VectorXd sd = Eigen::Vector3d(0.7, 0.7, 0.8);
  Eigen::MatrixXd observations;
  Eigen::Vector2d mode;
  Eigen::Matrix2d precision;
  double log_evidence = 0.0;
  double truncated_mass_bound = 0.0;

  LinearGaussianProblem() {
    const Eigen::Vector2d truth(4.2, 0.1);
    const Eigen::Vector3d y = b + a * truth;
    observations.resize(3, 3);
    observations.row(0) = (y + Eigen::Vector3d(0.5, -0.3, 0.4)).transpose();
    observations.row(1) = (y + Eigen::Vector3d(-0.2, 0.6, -0.5)).transpose();
    observations.row(2) = (y + Eigen::Vector3d(0.1, -0.4, 0.2)).transpose();
    const Eigen::Matrix3d sigma_inverse = sd.cwiseAbs2().cwiseInverse().asDiagonal();
    precision = 3.0 * a.transpose() * sigma_inverse * a;
    const Eigen::Vector3d residual_sum = observations.colwise().sum().transpose() - 3.0 * b;
    mode = precision.ldlt().solve(a.transpose() * sigma_inverse * residual_sum);
    const GaussianLikelihood l = likelihood();
    log_evidence = l.log_likelihood(Eigen::VectorXd(b + a * mode)) + std::log(2.0 * M_PI) -
                   0.5 * std::log(precision.determinant()) - std::log(8.0);
    const Eigen::Matrix2d covariance = precision.inverse();
    const double lower[2] = {2.0, -1.0}, upper[2] = {6.0, 1.0};
    for (int j = 0; j < 2; ++j) {
      const double distance = std::min(mode(j) - lower[j], upper[j] - mode(j));
      truncated_mass_bound += std::erfc(distance / std::sqrt(2.0 * covariance(j, j)));
    }
  }

  GaussianLikelihood likelihood() const {
    return GaussianLikelihood({"y1", "y2", "y3"}, observations,
                              ObservationNoise::given({{"y1", sd(0)}, {"y2", sd(1)}, {"y3", sd(2)}}));
  }

  StudyDesign design() const {
    StudyDesign design;
    design.name = "linear";
    design.kind = "sbalc";
    design.parameters.add(Parameter{"p", "test.p", "1", Prior::uniform(2.0, 6.0)});
    design.parameters.add(Parameter{"q", "test.q", "1", Prior::uniform(-1.0, 1.0)});
    design.feature_names = {"y1", "y2", "y3"};
    design.description = "linear-Gaussian calibration test";
    design.model = "linear y = b + A theta";
    return design;
  }
};

CalibrationOptions test_options(const fs::path& folder, bool resume = false) {
  CalibrationOptions options;
  options.sbalc.pool_size = 20000;  // the default: the Monte Carlo error of ĉ is about 1/√ESS
  options.sbalc.batch_size = 3;
  options.sbalc.max_evaluations = 60;
  options.sbalc.gp.nugget_mode = NuggetMode::Estimated;
  options.posterior.n_samples = 2000;
  options.posterior.credible_level = 0.9;
  options.evaluations_folder = folder;
  options.farm.n_workers = 2;
  options.farm.resume = resume;
  return options;
}

void expect_identical(const CalibrationResult& a, const CalibrationResult& b) {
  ASSERT_EQ(a.evaluations.size(), b.evaluations.size());
  for (std::size_t i = 0; i < a.evaluations.size(); ++i) {
    EXPECT_EQ(a.evaluations[i].theta, b.evaluations[i].theta) << "run " << i;
    EXPECT_EQ(a.evaluations[i].log_likelihood, b.evaluations[i].log_likelihood) << "run " << i;
  }
  EXPECT_EQ(a.log_evidence, b.log_evidence);
  EXPECT_EQ(a.log_evidence_lower, b.log_evidence_lower);
  EXPECT_EQ(a.log_evidence_upper, b.log_evidence_upper);
  EXPECT_EQ(a.converged, b.converged);
  EXPECT_EQ(a.history.size(), b.history.size());
  EXPECT_EQ(a.samples, b.samples);
  EXPECT_EQ(a.mean, b.mean);
  EXPECT_EQ(a.map_point, b.map_point);
}

TEST(Calibrate, LinearGaussianEvidenceAndPosteriorThroughTheFarm) {
  const fs::path dir = fresh_dir("linear");
  const LinearGaussianProblem problem;
  ASSERT_LT(problem.truncated_mass_bound, 1e-4);
  const LinearModel model(problem.a, problem.b);
  const CalibrationResult result =
      Calibration(model, problem.design(), problem.likelihood(), test_options(dir / "evaluations")).run();

  const double error = std::exp(result.log_evidence - problem.log_evidence) - 1.0;
  const Eigen::Matrix2d covariance = problem.precision.inverse();
  std::printf("linear-Gaussian through the farm: ln c exact %.5f, calibration %.5f [%.5f, %.5f], relative error "
              "%+.2f %%, %zu runs in %zu iterations, %s\n",
              problem.log_evidence, result.log_evidence, result.log_evidence_lower, result.log_evidence_upper,
              100.0 * error, result.n_evaluations, result.history.size(), result.stop_reason.c_str());
  std::printf("  mean (%.4f, %.4f) exact (%.4f, %.4f); sd (%.4f, %.4f) exact (%.4f, %.4f); ESS %.0f; MAP (%.4f, %.4f)\n",
              result.mean(0), result.mean(1), problem.mode(0), problem.mode(1), result.standard_deviation(0),
              result.standard_deviation(1), std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1)),
              result.effective_sample_size, result.map_point(0), result.map_point(1));
  EXPECT_TRUE(result.converged) << result.stop_reason;
  EXPECT_LT(std::abs(error), 0.1);
  EXPECT_FALSE(result.poorly_resolved) << result.warning;
  for (int j = 0; j < 2; ++j) {
    const double sd = std::sqrt(covariance(j, j));
    EXPECT_NEAR(result.mean(j), problem.mode(j), 0.15 * sd) << "parameter " << j;
    EXPECT_NEAR(result.standard_deviation(j), sd, 0.15 * sd) << "parameter " << j;
    // 90 % interval of N(θ̂, sd²): θ̂ ± 1.645 sd.
    EXPECT_NEAR(result.credible_lower(j), problem.mode(j) - 1.645 * sd, 0.3 * sd) << "parameter " << j;
    EXPECT_NEAR(result.credible_upper(j), problem.mode(j) + 1.645 * sd, 0.3 * sd) << "parameter " << j;
    EXPECT_NEAR(result.map_point(j), problem.mode(j), 0.2 * sd) << "parameter " << j;
  }
  // Physical units: every draw inside the prior box.
  EXPECT_GE(result.samples.col(0).minCoeff(), 2.0);
  EXPECT_LE(result.samples.col(0).maxCoeff(), 6.0);
  EXPECT_EQ(result.samples.rows(), 2000);
  EXPECT_EQ(result.n_reused, 0u);
  EXPECT_EQ(result.n_failed, 0u);

  // Every run is in a study results file of the folder, one file per batch.
  std::size_t n_recorded = 0, n_files = 0;
  for (const auto& entry : fs::directory_iterator(dir / "evaluations")) {
    const StudyResults stored = read_study_results(entry.path());
    n_recorded += stored.count(StudyResults::Status::ok);
    ++n_files;
  }
  EXPECT_EQ(n_recorded, result.n_evaluations);
  EXPECT_EQ(n_files, result.history.size());  // the initial design, then one batch per iteration but the last
  fs::remove_all(dir);
}

TEST(Calibrate, KilledAndResumedCalibrationEqualsUninterruptedOne) {
  const fs::path dir = fresh_dir("killed");
  const LinearGaussianProblem problem;
  const LinearModel slow(problem.a, problem.b, 0.02);
  const std::size_t n_before_kill = 12;  // the initial 5, two batches of 3, one run of the next

  // The calibration runs in a child process, killed with SIGKILL once n_before_kill runs
  // are in the files; the child waits inside the farm's result callback after the last
  // one, so the kill lands between two appends while the other worker is busy.
  int report[2];
  ASSERT_EQ(::pipe(report), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(report[0]);
    CalibrationOptions options = test_options(dir / "killed");
    options.farm.stop_on_interrupt = false;
    std::size_t n_reported = 0;
    options.farm.on_result = [&](const RunRecord&) {
      const char byte = 1;
      if (::write(report[1], &byte, 1) != 1) _exit(3);
      if (++n_reported == n_before_kill) ::pause();
    };
    try {
      Calibration(slow, problem.design(), problem.likelihood(), options).run();
    } catch (...) {
      _exit(4);
    }
    _exit(5);
  }
  ::close(report[1]);
  std::size_t n_seen = 0;
  char byte = 0;
  while (n_seen < n_before_kill && ::read(report[0], &byte, 1) == 1) ++n_seen;
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ::close(report[0]);
  ASSERT_EQ(n_seen, n_before_kill);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);

  // Without resume the folder is refused; with it the finished runs are reused.
  try {
    Calibration(slow, problem.design(), problem.likelihood(), test_options(dir / "killed")).run();
    ADD_FAILURE() << "an existing calibration folder was reused without resume";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("exists already; continue the calibration with --resume"), std::string::npos)
        << e.what();
  }
  const CalibrationResult resumed =
      Calibration(slow, problem.design(), problem.likelihood(), test_options(dir / "killed", true)).run();
  EXPECT_EQ(resumed.n_reused, n_before_kill);

  const LinearModel fast(problem.a, problem.b);
  const CalibrationResult whole =
      Calibration(fast, problem.design(), problem.likelihood(), test_options(dir / "whole")).run();
  std::printf("killed after %zu runs, resumed: %zu runs (%zu reused); uninterrupted: %zu runs\n", n_before_kill,
              resumed.n_evaluations, resumed.n_reused, whole.n_evaluations);
  expect_identical(resumed, whole);

  // A second resume runs nothing and gives the same result again.
  const CalibrationResult again =
      Calibration(slow, problem.design(), problem.likelihood(), test_options(dir / "killed", true)).run();
  EXPECT_EQ(again.n_reused, again.n_evaluations);
  expect_identical(again, whole);
  fs::remove_all(dir);
}

TEST(Calibrate, CalibrationStoppedAtTheCapCarriesSbalcsWarnings) {
  const fs::path dir = fresh_dir("capped");
  const LinearGaussianProblem problem;
  const LinearModel model(problem.a, problem.b);
  CalibrationOptions options = test_options(dir / "evaluations");
  options.sbalc.max_evaluations = 8;  // the initial design and one batch: too few to converge
  const CalibrationResult result = Calibration(model, problem.design(), problem.likelihood(), options).run();
  EXPECT_FALSE(result.converged);
  // SBALC's warnings first (ending with why it stopped), then the posterior's if any.
  const std::size_t n_sbalc = result.warnings.size() - (result.poorly_resolved ? 1 : 0);
  ASSERT_GE(n_sbalc, 1u);
  EXPECT_NE(result.warnings[n_sbalc - 1].find("not converged: evaluation cap of 8 reached"), std::string::npos)
      << result.warnings[n_sbalc - 1];
  EXPECT_GT(result.pool_ess, 0.0);
  EXPECT_DOUBLE_EQ(result.pool_ess_threshold, 200.0);  // max(100, 1 % of 20 000)
  EXPECT_GT(result.pool_relative_error, 0.0);
  if (result.poorly_resolved) {
    EXPECT_EQ(result.warnings.back(), "posterior: " + result.warning);
  }
  fs::remove_all(dir);
}

TEST(Calibrate, ResumeRefusesRunsOfAnotherModelSetUp) {
  const fs::path dir = fresh_dir("other_model");
  const LinearGaussianProblem problem;
  const LinearModel model(problem.a, problem.b);
  CalibrationOptions options = test_options(dir / "evaluations");
  options.sbalc.max_evaluations = 8;
  Calibration(model, problem.design(), problem.likelihood(), options).run();
  StudyDesign other = problem.design();
  other.model = "another case file";
  options.farm.resume = true;
  try {
    Calibration(model, other, problem.likelihood(), options).run();
    ADD_FAILURE() << "runs of another model set-up were reused";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("holds runs of another set-up: remove it to start again"), std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

TEST(Calibrate, RunWithUndefinedLikelihoodFeatureIsAFailedRunOutsideTheGp) {
  const fs::path dir = fresh_dir("undefined_feature");
  const LinearGaussianProblem problem;
  // y2 undefined above p = 5.2: the initial Hammersley design (p = 2.4, 3.2, 4.0, 4.8,
  // 5.6) has one such run; the posterior mode (p ≈ 4.2) lies where all are defined.
  const PartlyUndefinedLinearModel model(problem.a, problem.b, 5.2);
  CalibrationOptions options = test_options(dir / "evaluations");
  options.sbalc.max_evaluations = 14;
  const CalibrationResult result = Calibration(model, problem.design(), problem.likelihood(), options).run();

  std::size_t n_undefined = 0, n_ok = 0;
  for (const CalibrationEvaluation& run : result.evaluations) {
    if (run.theta(0) > 5.2) {
      ++n_undefined;
      EXPECT_FALSE(run.ok);
      EXPECT_EQ(run.failure_reason, "feature y2 undefined: the model returned NaN");
      EXPECT_TRUE(std::isnan(run.log_likelihood));
      EXPECT_TRUE(std::isnan(run.features(1)));
      EXPECT_TRUE(std::isfinite(run.features(0)));  // the defined features are kept
    } else {
      ++n_ok;
      EXPECT_TRUE(run.ok) << run.failure_reason;
      EXPECT_TRUE(std::isfinite(run.log_likelihood));
    }
  }
  EXPECT_GE(n_undefined, 1u);
  EXPECT_EQ(result.n_failed, n_undefined);
  // Only the runs with a likelihood are in the GP, and none of its values is NaN.
  EXPECT_EQ(static_cast<std::size_t>(result.design_unit.rows()), n_ok);
  EXPECT_TRUE(result.design_log_likelihoods.allFinite());
  EXPECT_TRUE(result.mean.allFinite());

  // The farm's files keep those runs as ok runs with the NaN (a study would use their
  // defined features); only the likelihood treats them as failed.
  std::size_t n_stored_nan = 0;
  for (const auto& entry : fs::directory_iterator(dir / "evaluations")) {
    const StudyResults stored = read_study_results(entry.path());
    for (std::size_t i = 0; i < stored.n_points(); ++i) {
      EXPECT_EQ(stored.status[i], StudyResults::Status::ok);
      if (std::isnan(stored.features(static_cast<Eigen::Index>(i), 1))) ++n_stored_nan;
    }
  }
  EXPECT_EQ(n_stored_nan, n_undefined);

  // Resumed, the cached runs go through the same check.
  options.farm.resume = true;
  const CalibrationResult resumed = Calibration(model, problem.design(), problem.likelihood(), options).run();
  EXPECT_EQ(resumed.n_reused, resumed.n_evaluations);
  EXPECT_EQ(resumed.n_failed, n_undefined);
  fs::remove_all(dir);
}

TEST(Calibrate, WarningsOfOkRunsAreKeptPerEvaluationAlsoWhenResumed) {
  const fs::path dir = fresh_dir("warnings");
  const LinearGaussianProblem problem;
  const WarningLinearModel model(problem.a, problem.b, 5.2);
  CalibrationOptions options = test_options(dir / "evaluations");
  options.sbalc.max_evaluations = 12;
  const CalibrationResult result = Calibration(model, problem.design(), problem.likelihood(), options).run();
  std::size_t n_warned = 0;
  for (const CalibrationEvaluation& run : result.evaluations) {
    EXPECT_TRUE(run.ok) << run.failure_reason;  // a warning does not fail a run
    EXPECT_EQ(run.warnings, run.theta(0) > 5.2 ? "electrode above its solidus" : "");
    n_warned += run.warnings.empty() ? 0 : 1;
  }
  EXPECT_GE(n_warned, 1u);  // the initial design has p = 5.6
  EXPECT_EQ(result.n_failed, 0u);

  options.farm.resume = true;
  const CalibrationResult resumed = Calibration(model, problem.design(), problem.likelihood(), options).run();
  ASSERT_EQ(resumed.evaluations.size(), result.evaluations.size());
  for (std::size_t r = 0; r < resumed.evaluations.size(); ++r) {
    EXPECT_TRUE(resumed.evaluations[r].reused);
    EXPECT_EQ(resumed.evaluations[r].warnings, result.evaluations[r].warnings);
  }
  fs::remove_all(dir);
}

TEST(Calibrate, UndefinedFeaturesWithTheSameConditionShareOneReason) {
  // Weld features that are NaN are explained by the condition that leaves them
  // undefined (features.hpp, why_undefined), grouped by condition.
  class NoPeakModel : public ForwardModel {
   public:
    std::vector<std::string> parameter_names() const override { return {"p", "q"}; }
    std::vector<std::string> feature_names() const override { return {"R_beta", "t_beta", "R_m"}; }
    EvaluationResult evaluate(const Eigen::VectorXd& theta) const override {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      if (theta(0) > 5.0) return EvaluationResult::success(Eigen::Vector3d(nan, nan, 150e-6 + 1e-6 * theta(1)));
      return EvaluationResult::success(Eigen::Vector3d(180e-6 + 1e-6 * theta(0), 0.05 + 0.001 * theta(1), 150e-6));
    }
  };
  const fs::path dir = fresh_dir("no_peak");
  StudyDesign design = LinearGaussianProblem().design();
  design.feature_names = {"R_beta", "t_beta", "R_m"};
  const Eigen::MatrixXd observed = (Eigen::MatrixXd(2, 3) << 184e-6, 0.05, 150e-6, 185e-6, 0.0502, 150.5e-6).finished();
  const GaussianLikelihood likelihood(design.feature_names, observed, ObservationNoise::relative(0.05));
  CalibrationOptions options = test_options(dir / "evaluations");
  options.sbalc.max_evaluations = 6;
  const CalibrationResult result = Calibration(NoPeakModel(), design, likelihood, options).run();
  std::size_t n_failed = 0;
  for (const CalibrationEvaluation& run : result.evaluations) {
    if (run.ok) continue;
    ++n_failed;
    EXPECT_EQ(run.failure_reason,
              "features R_beta, t_beta undefined: the dynamic resistance has no peak inside the trimmed weld stage");
  }
  EXPECT_GE(n_failed, 1u);
  fs::remove_all(dir);
}

TEST(CalibrationStudy, ObservedSignalWithAnUndefinedFeatureIsAnErrorWithTheReason) {
  const fs::path dir = fresh_dir("undefined_observation");
  // Resistance falling over the whole weld: no peak, so R_beta is undefined; R_gamma is not.
  std::ostringstream text;
  text << "time [ms], current [kA], voltage [V]\n";
  for (int k = 0; k <= 800; ++k) {
    const double t = -20.0 + 0.2 * k;
    const double current = t < 0 || t > 120 ? 0.0 : 8.0;
    const double resistance = 200.0 - 0.5 * std::max(t, 0.0);  // µΩ
    char row[96];
    std::snprintf(row, sizeof row, "%.1f, %.3f, %.8f\n", t, current, current * resistance * 1e-3);
    text << row;
  }
  const fs::path falling = write_file(dir / "falling.csv", text.str());
  const Observations defined = features_of_signal_files({falling}, {"R_gamma", "R_m"});
  EXPECT_TRUE(defined.values.allFinite());
  try {
    features_of_signal_files({falling}, {"R_gamma", "R_beta"});
    ADD_FAILURE() << "an undefined observed feature was accepted";
  } catch (const ObservationError& e) {
    EXPECT_NE(std::string(e.what()).find(falling.string() + ": feature 'R_beta' is undefined for this signal: the "
                                         "dynamic resistance has no peak inside the trimmed weld stage"),
              std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

// Film thickness t log10-uniform on [1e-7, 5e-4] m (3.699 decades), resistivity rho on
// [5e-7, 5e-5] ohm m (2 decades), a uniform third parameter c on [1, 3]. The log product
// z = (log10 t + log10 rho - log10(5e-14)) / log10(2.5e-8 / 5e-14) is linear in u for
// log10-uniform priors: z = (3.699 u_t + 2 u_rho) / 5.699; for t * c it is not.
TEST(Calibrate, LogProductsAppendTheScaledLogOfEachProductToThePoint) {
  ParameterSpace space;
  space.add(Parameter{"t", "test.t", "m", Prior::log10_uniform(1e-7, 5e-4)});
  space.add(Parameter{"rho", "test.rho", "ohm*m", Prior::log10_uniform(5e-7, 5e-5)});
  space.add(Parameter{"c", "test.c", "1", Prior::uniform(1.0, 3.0)});
  const InputMap map = log_product_map(space, {{"r", {0, 1}}, {"tc", {0, 2}}});
  Eigen::MatrixXd points(3, 3);
  points << 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.3, 0.8, 0.5;
  const Eigen::MatrixXd mapped = map(points);
  ASSERT_EQ(mapped.rows(), 3);
  ASSERT_EQ(mapped.cols(), 5);
  EXPECT_EQ(mapped.leftCols(3), points);
  const double decades_t = std::log10(5e-4 / 1e-7), decades_rho = 2.0;
  EXPECT_NEAR(mapped(0, 3), 0.0, 1e-12);
  EXPECT_NEAR(mapped(1, 3), 1.0, 1e-12);
  EXPECT_NEAR(mapped(2, 3), (decades_t * 0.3 + decades_rho * 0.8) / (decades_t + decades_rho), 1e-12);
  // t * c at u = (0.3, -, 0.5): t = 1e-7 * 10^(0.3 decades_t), c = 2.
  const double low = std::log10(1e-7 * 1.0), high = std::log10(5e-4 * 3.0);
  EXPECT_NEAR(mapped(2, 4), (std::log10(1e-7 * std::pow(10.0, 0.3 * decades_t) * 2.0) - low) / (high - low), 1e-12);
}

TEST(Calibrate, UnitPointsMapThroughThePriorsAndStayFinite) {
  ParameterSpace space;
  space.add(Parameter{"a", "test.a", "1", Prior::log10_uniform(1e-3, 1e-1)});
  space.add(Parameter{"b", "test.b", "1", Prior::normal(5.0, 2.0)});
  const Eigen::VectorXd middle = unit_to_physical(space, Eigen::Vector2d(0.5, 0.5));
  EXPECT_NEAR(middle(0), 1e-2, 1e-15);
  EXPECT_NEAR(middle(1), 5.0, 1e-12);
  const Eigen::VectorXd corner = unit_to_physical(space, Eigen::Vector2d(0.0, 0.0));
  EXPECT_NEAR(corner(0), 1e-3, 1e-15);
  EXPECT_TRUE(std::isfinite(corner(1)));
  EXPECT_TRUE(std::isfinite(unit_to_physical(space, Eigen::Vector2d(1.0, 1.0))(1)));
}

// --- observations and the calibration section ------------------------------------------

// A weld-like signal file (after tools/make_example_signal.py, without noise): 8 kA for
// 150 ms, dynamic resistance rising to a peak near 180 µΩ · scale and falling, electrode
// expansion of about 33 µm · expansion.
fs::path write_signal(const fs::path& path, double scale, double expansion) {
  std::ostringstream text;
  text << "# synthetic test signal\ntime [ms], current [kA], voltage [V], force [kN], displacement [mm]\n";
  for (int k = 0; k <= 1350; ++k) {
    const double t = -20.0 + 0.2 * k;
    const double up = std::clamp(t / 10.0, 0.0, 1.0), down = std::clamp((150.0 - t) / 10.0, 0.0, 1.0);
    const double current = t < 0 ? 0.0 : 8.0 * std::min(up, down);
    const double tw = std::max(t, 0.0);
    const double resistance = scale * (96.0 + 87.0 / (1.0 + std::exp(-(tw - 24.0) / 6.0)) -
                                       48.0 * (1.0 - std::exp(-std::max(tw - 44.0, 0.0) / 70.0)) +
                                       45.0 * std::exp(-tw / 3.0));
    const double heat = std::clamp(t, 0.0, 150.0);
    const double growth = (1.0 - std::exp(-heat / 60.0)) / (1.0 - std::exp(-150.0 / 60.0));
    const double after = std::max(t - 150.0, 0.0);
    const double displacement = expansion * 0.0335 *
                                (t <= 150.0 ? std::pow(growth, 1.3) : 0.3 + 0.7 * std::exp(-after / 28.0));
    char row[160];
    std::snprintf(row, sizeof row, "%.1f, %.6f, %.8f, 3.0, %.8f\n", t, current, current * resistance * 1e-3,
                  displacement);
    text << row;
  }
  return write_file(path, text.str());
}

// A study of two features, the given calibration section, and no forward model.
fs::path write_study(const fs::path& dir, const std::string& calibration,
                     const std::string& features = "features: [{name: R_beta}, {name: dS_P}]\n") {
  return write_file(dir / "study.yaml", "study: {name: obs}\n"
                                        "parameters: [{name: a, config_key: test.a, prior: uniform, lower: 0, upper: 1}]\n" +
                                            features + calibration);
}

std::string settings_error(const fs::path& study_file) {
  try {
    const Study study = Study::load(study_file);
    const CalibrationSettings settings = read_calibration_settings(study);
    const Observations observations = load_observations(study, settings);
    make_likelihood(study, settings, observations);
  } catch (const fem::ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(CalibrationStudy, SignalFilesAndFeaturesFileGiveTheSameLikelihood) {
  const fs::path dir = fresh_dir("same_likelihood");
  std::vector<fs::path> signals;
  for (int k = 0; k < 3; ++k) {
    signals.push_back(write_signal(dir / ("weld_" + std::to_string(k + 1) + ".csv"), 1.0 + 0.01 * (k - 1), 1.0 - 0.02 * k));
  }
  const std::vector<std::string> features = {"R_beta", "R_gamma", "dS_P"};
  const Observations from_signals = features_of_signal_files(signals, features);
  ASSERT_EQ(from_signals.values.rows(), 3);
  EXPECT_NEAR(from_signals.values(1, 0), 180e-6, 5e-6);  // the peak near 180 µΩ
  EXPECT_NEAR(from_signals.values(1, 2), 32e-6, 4e-6);   // the expansion near 33 µm

  // The same values as a features file, in other units and column order, with an extra
  // column; and the same study with either source.
  std::ostringstream table;
  table << "# features of weld_1..3.csv\ndS_P [um], extra, R_gamma [uohm], R_beta [uohm]\n";
  table.precision(17);
  for (int k = 0; k < 3; ++k) {
    table << from_signals.values(k, 2) * 1e6 << ", 7, " << from_signals.values(k, 1) * 1e6 << ", "
          << from_signals.values(k, 0) * 1e6 << "\n";
  }
  write_file(dir / "features.csv", table.str());
  const std::string feature_list = "features: [{name: R_beta}, {name: R_gamma}, {name: dS_P}]\n";
  const std::string noise = "  noise: {kind: replicate_scatter, discrepancy: [{feature: R_gamma, standard_deviation: 1 uohm}]}\n";
  const Study by_file = Study::load(
      write_study(dir, "calibration:\n  observations: {features_file: features.csv}\n" + noise, feature_list));
  const CalibrationSettings file_settings = read_calibration_settings(by_file);
  const GaussianLikelihood file_likelihood =
      make_likelihood(by_file, file_settings, load_observations(by_file, file_settings));
  const Study by_signals = Study::load(write_study(
      dir, "calibration:\n  observations:\n    signal_files: [{file: weld_1.csv}, {file: weld_2.csv}, {file: weld_3.csv}]\n" + noise,
      feature_list));
  const CalibrationSettings signal_settings = read_calibration_settings(by_signals);
  EXPECT_EQ(signal_settings.observation_source, ObservationSource::signal_files);
  EXPECT_EQ(signal_settings.signal_files[0], dir / "weld_1.csv");
  const GaussianLikelihood signal_likelihood =
      make_likelihood(by_signals, signal_settings, load_observations(by_signals, signal_settings));

  for (Eigen::Index j = 0; j < 3; ++j) {
    EXPECT_NEAR(file_likelihood.variances()(j), signal_likelihood.variances()(j), 1e-12 * signal_likelihood.variances()(j));
  }
  const Eigen::Vector3d model(181e-6, 150e-6, 31e-6);
  const double l_file = file_likelihood.log_likelihood(model), l_signals = signal_likelihood.log_likelihood(model);
  std::printf("ln L from the features file %.12g, from the signal files %.12g\n", l_file, l_signals);
  EXPECT_NEAR(l_file, l_signals, 1e-9 * std::abs(l_signals));
  fs::remove_all(dir);
}

// The features file goes through the same CSV reader as the signal files.
TEST(CalibrationStudy, FeaturesFileMayBeALoggerExportWithSemicolonsAndDecimalCommas) {
  const fs::path dir = fresh_dir("semicolon");
  write_file(dir / "obs.csv", "\xEF\xBB\xBF\"R_beta [uohm]\";\"dS_P [um]\"\n180,5;30\n184;33,25\n");
  const Study study = Study::load(write_study(dir, "calibration:\n  observations: {features_file: obs.csv}\n"));
  const Observations observations = load_observations(study, read_calibration_settings(study));
  ASSERT_EQ(observations.values.rows(), 2);
  EXPECT_NEAR(observations.values(0, 0), 180.5e-6, 1e-15);
  EXPECT_NEAR(observations.values(1, 1), 33.25e-6, 1e-15);
  fs::remove_all(dir);
}

TEST(CalibrationStudy, ObservedSignalWithAnImplausibleUnitWarnsAndStillGivesFeatures) {
  const fs::path dir = fresh_dir("ampere_observation");
  // 8 kA written as "8" under "current [A]": a peak of 8 A.
  std::ostringstream text;
  text << "time [ms], current [A], voltage [V]\n";
  for (int k = 0; k <= 800; ++k) {
    const double t = -20.0 + 0.2 * k;
    const double current = t < 0 || t > 120 ? 0.0 : 8.0;
    char row[96];
    std::snprintf(row, sizeof row, "%.1f, %.3f, %.8f\n", t, current, current * (200.0 - 0.5 * std::max(t, 0.0)) * 1e-3);
    text << row;
  }
  const fs::path file = write_file(dir / "ampere.csv", text.str());
  const Observations observations = features_of_signal_files({file}, {"R_gamma"});
  EXPECT_TRUE(observations.values.allFinite());
  ASSERT_EQ(observations.warnings.size(), 2u);
  EXPECT_EQ(observations.warnings[0].find(file.string() + ": column 'current [A]' has a peak |I| of 8 A"), 0u)
      << observations.warnings[0];
  fs::remove_all(dir);
}

TEST(CalibrationStudy, NoiseModelsGiveTheirVariances) {
  const fs::path dir = fresh_dir("noise");
  write_file(dir / "obs.csv", "R_beta [uohm], dS_P [um]\n180, 30\n184, 33\n179, 31\n181, 34\n");
  const auto likelihood_of = [&](const std::string& noise) {
    const Study study = Study::load(write_study(dir, "calibration:\n  observations: {features_file: obs.csv}\n" + noise));
    const CalibrationSettings settings = read_calibration_settings(study);
    return make_likelihood(study, settings, load_observations(study, settings));
  };
  // Replicate scatter: the sample standard deviation (N − 1), plus the discrepancy δ².
  const GaussianLikelihood scatter = likelihood_of(
      "  noise: {kind: replicate_scatter, discrepancy: [{feature: dS_P, standard_deviation: 2 um}]}\n");
  const Eigen::Vector4d r_beta(180e-6, 184e-6, 179e-6, 181e-6), ds_p(30e-6, 33e-6, 31e-6, 34e-6);
  const auto sample_variance = [](const Eigen::Vector4d& v) { return (v.array() - v.mean()).square().sum() / 3.0; };
  EXPECT_NEAR(scatter.measurement_variances()(0), sample_variance(r_beta), 1e-9 * sample_variance(r_beta));
  EXPECT_NEAR(scatter.measurement_variances()(1), sample_variance(ds_p), 1e-9 * sample_variance(ds_p));
  EXPECT_NEAR(scatter.variances()(1), sample_variance(ds_p) + 4e-12, 1e-9 * sample_variance(ds_p));
  EXPECT_EQ(scatter.n_replicates(), 4);

  // Relative: σ_j = fraction · |mean|.
  const GaussianLikelihood relative = likelihood_of("  noise: {kind: relative, fraction: 0.02}\n");
  EXPECT_NEAR(std::sqrt(relative.variances()(0)), 0.02 * r_beta.mean(), 1e-15);

  // Given, in any unit of the feature's kind; a bare number is SI.
  const GaussianLikelihood given = likelihood_of(
      "  noise:\n    kind: standard_deviations\n    standard_deviations: [{feature: R_beta, value: 2 uohm}, "
      "{feature: dS_P, value: 1.5e-6}]\n");
  EXPECT_NEAR(std::sqrt(given.variances()(0)), 2e-6, 1e-18);
  EXPECT_NEAR(std::sqrt(given.variances()(1)), 1.5e-6, 1e-18);

  // A temperature spread is a difference: 2 K is 2 degC, not −271.15.
  write_file(dir / "temperature.csv", "T_max [K]\n1800\n1810\n");
  const Study study = Study::load(write_study(
      dir,
      "calibration:\n  observations: {features_file: temperature.csv}\n  noise:\n    kind: standard_deviations\n"
      "    standard_deviations: [{feature: T_max, value: 2 K}]\n",
      "features: [{name: T_max}]\n"));
  const CalibrationSettings settings = read_calibration_settings(study);
  const Observations observations = load_observations(study, settings);
  EXPECT_NEAR(observations.values(0, 0), 1800 - 273.15, 1e-9);  // values convert with the offset
  EXPECT_NEAR(std::sqrt(make_likelihood(study, settings, observations).variances()(0)), 2.0, 1e-12);
  fs::remove_all(dir);
}

TEST(CalibrationStudy, BadObservationFilesNameFileLineAndWhatIsAllowed) {
  const fs::path dir = fresh_dir("bad_observations");
  const auto error_for = [&](const std::string& table) {
    write_file(dir / "obs.csv", table);
    return settings_error(write_study(dir, "calibration:\n  observations: {features_file: obs.csv}\n"));
  };
  const std::string file = (dir / "obs.csv").string();
  std::string message = error_for("# comment\nR_beta [uohm], R_gamma [uohm]\n180, 150\n");
  EXPECT_NE(message.find("study.yaml:5:33: calibration.observations.features_file = obs.csv: " + file +
                         ":2: the header has no column for feature 'dS_P' (columns: R_beta, R_gamma); allowed: a "
                         "header with a column for every feature of the study: R_beta, dS_P"),
            std::string::npos)
      << message;
  message = error_for("R_beta [uohm], dS_P [um]\n180, 30\n181, abc\n");
  EXPECT_NE(message.find(file + ":3: column 2 ('dS_P [um]'): 'abc' is not a finite number"), std::string::npos) << message;
  message = error_for("R_beta [uohm], dS_P [um]\n180, 30, 4\n");
  EXPECT_NE(message.find(file + ":2: expected 2 values separated by ',' (one per header column), found 3"),
            std::string::npos)
      << message;
  message = error_for("R_beta [uohm], dS_P [um]\n");
  EXPECT_NE(message.find(file + ": no observations below the header; allowed: one row per replicate"), std::string::npos)
      << message;
  message = error_for("R_beta [mm], dS_P [um]\n180, 30\n");
  EXPECT_NE(message.find(file + ":1: column 1 ('R_beta [mm]'): unit 'mm' measures length, but feature 'R_beta' is in "
                                "ohm (electrical resistance)"),
            std::string::npos)
      << message;
  message = settings_error(write_study(dir, "calibration:\n  observations: {features_file: missing.csv}\n"));
  EXPECT_NE(message.find((dir / "missing.csv").string() + ": cannot open the features file"), std::string::npos)
      << message;

  // Signal files: a feature the signals cannot give, a file without a current pulse.
  write_signal(dir / "weld.csv", 1.0, 1.0);
  message = settings_error(write_study(dir, "calibration:\n  observations: {signal_files: [{file: weld.csv}]}\n",
                                       "features: [{name: R_beta}, {name: d_n_liq}]\n"));
  EXPECT_NE(message.find("calibration.observations.signal_files[0].file = weld.csv: " + (dir / "weld.csv").string() +
                         ": the signals give no feature 'd_n_liq'"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("need observations.features_file"), std::string::npos) << message;
  std::string flat = "time [ms], current [kA], voltage [V]\n";
  for (int k = 0; k < 50; ++k) flat += std::to_string(k) + ", 0, 0\n";
  write_file(dir / "flat.csv", flat);
  message = settings_error(write_study(dir, "calibration:\n  observations: {signal_files: [{file: flat.csv}]}\n"));
  EXPECT_NE(message.find((dir / "flat.csv").string() + ": no current pulse"), std::string::npos) << message;
  fs::remove_all(dir);
}

TEST(CalibrationStudy, BadCalibrationKeysNameKeyValueAndAllowed) {
  const fs::path dir = fresh_dir("bad_keys");
  write_file(dir / "obs.csv", "R_beta [uohm], dS_P [um]\n180, 30\n");
  write_signal(dir / "weld.csv", 1.0, 1.0);
  std::string message = settings_error(write_study(
      dir, "calibration:\n  observations: {features_file: obs.csv, signal_files: [{file: weld.csv}]}\n"));
  EXPECT_NE(message.find("calibration.observations.features_file = obs.csv: given together with "
                         "calibration.observations.signal_files"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("allowed: one of the two"), std::string::npos) << message;
  message = settings_error(write_study(dir, "calibration: {sbalc: {pool_size: 5000}}\n"));
  EXPECT_NE(message.find("calibration.observations: missing; rsw calibrate needs calibration.observations.features_file "
                         "or calibration.observations.signal_files"),
            std::string::npos)
      << message;
  message = settings_error(write_study(
      dir, "calibration:\n  observations: {features_file: obs.csv}\n  noise:\n    kind: standard_deviations\n"
           "    standard_deviations: [{feature: R_beta, value: 2 uohm}]\n"));
  EXPECT_NE(message.find("no standard deviation of feature 'dS_P'; noise.kind standard_deviations needs one per "
                         "feature of the study (R_beta, dS_P)"),
            std::string::npos)
      << message;
  message = settings_error(write_study(
      dir, "calibration:\n  observations: {features_file: obs.csv}\n  noise:\n"
           "    discrepancy: [{feature: T_max, standard_deviation: 5 K}]\n"));
  EXPECT_NE(message.find("calibration.noise.discrepancy[0].feature = T_max: not a feature of the study; allowed: "
                         "R_beta, dS_P"),
            std::string::npos)
      << message;
  message = settings_error(write_study(
      dir, "calibration:\n  observations: {features_file: obs.csv}\n  noise:\n    kind: standard_deviations\n"
           "    standard_deviations: [{feature: R_beta, value: 2 mm}, {feature: dS_P, value: 1 um}]\n"));
  EXPECT_NE(message.find("calibration.noise.standard_deviations[0].value = 2 mm: is in mm (length), but feature "
                         "'R_beta' is in ohm (electrical resistance)"),
            std::string::npos)
      << message;
  message = settings_error(write_study(
      dir, "calibration:\n  observations: {features_file: obs.csv}\n  sbalc: {initial_points: 20, max_evaluations: 10}\n"));
  EXPECT_NE(message.find("calibration.sbalc.initial_points = 20: more than calibration.sbalc.max_evaluations = 10"),
            std::string::npos)
      << message;
  message = settings_error(write_study(dir, "calibration:\n  observations: {features_file: obs.csv}\n  sbalc: "
                                            "{nugget: sometimes}\n"));
  EXPECT_NE(message.find("calibration.sbalc.nugget"), std::string::npos) << message;
  EXPECT_NE(message.find("'sometimes' is not an allowed choice; allowed: 'off', 'fixed', 'estimated'"),
            std::string::npos)
      << message;
  // One replicate has no scatter.
  message = settings_error(write_study(dir, "calibration:\n  observations: {features_file: obs.csv}\n"));
  EXPECT_NE(message.find("study.yaml: calibration.noise.kind = replicate_scatter (the default): replicate_scatter "
                         "needs two or more replicates; the observations hold 1"),
            std::string::npos)
      << message;
  fs::remove_all(dir);
}

TEST(CalibrationStudy, DefaultsFollowThePaper) {
  const fs::path dir = fresh_dir("defaults");
  const Study study = Study::load(write_study(dir, "calibration: {observations: {features_file: obs.csv}}\n"));
  const CalibrationSettings settings = read_calibration_settings(study);
  EXPECT_EQ(settings.sbalc.pool_size, 20000);        // paper §2.5: N_M = 2e4
  EXPECT_EQ(settings.sbalc.n_initial, 5);            // n_0 = 5 Hammersley points
  EXPECT_DOUBLE_EQ(settings.sbalc.tolerance, 0.1);
  EXPECT_EQ(settings.sbalc.gp.nugget_mode, NuggetMode::Estimated);
  EXPECT_EQ(settings.noise.kind, ObservationNoise::Kind::ReplicateScatter);
  EXPECT_DOUBLE_EQ(settings.posterior.credible_level, 0.9);
  EXPECT_EQ(settings.features_file, dir / "obs.csv");
  fs::remove_all(dir);
}

// The study defaults are simulator_sbalc_options(): the library's SbalcOptions{} except
// for the three documented differences (sbalc.hpp, "Defaults").
TEST(CalibrationStudy, SbalcDefaultsAreTheLibrarysExceptTheDocumentedThree) {
  const fs::path dir = fresh_dir("sbalc_defaults");
  const Study study = Study::load(write_study(dir, "calibration: {observations: {features_file: obs.csv}}\n"));
  const SbalcOptions read = read_calibration_settings(study).sbalc;
  const SbalcOptions simulator = simulator_sbalc_options();
  const SbalcOptions library;
  EXPECT_TRUE(read.adaptive_pool);
  EXPECT_EQ(read.gp.nugget_mode, NuggetMode::Estimated);
  EXPECT_EQ(read.batch_size, 4);
  EXPECT_FALSE(library.adaptive_pool);
  EXPECT_EQ(library.gp.nugget_mode, NuggetMode::Off);
  EXPECT_EQ(library.batch_size, 1);
  for (const SbalcOptions* expected : {&simulator, &library}) {
    EXPECT_EQ(read.pool_size, expected->pool_size);
    EXPECT_EQ(read.n_initial, expected->n_initial);
    EXPECT_EQ(read.seed, expected->seed);
    EXPECT_EQ(read.max_evaluations, expected->max_evaluations);
    EXPECT_DOUBLE_EQ(read.tolerance, expected->tolerance);
    EXPECT_EQ(read.n_consecutive, expected->n_consecutive);
    EXPECT_DOUBLE_EQ(read.bound_width, expected->bound_width);
    EXPECT_EQ(read.failed_runs, expected->failed_runs);
    EXPECT_DOUBLE_EQ(read.log_likelihood_range, expected->log_likelihood_range);
    EXPECT_DOUBLE_EQ(read.min_pool_ess, expected->min_pool_ess);
    EXPECT_DOUBLE_EQ(read.min_pool_ess_fraction, expected->min_pool_ess_fraction);
    EXPECT_DOUBLE_EQ(read.max_noise_tolerance_factor, expected->max_noise_tolerance_factor);
    EXPECT_EQ(read.noise_aware_tolerance, expected->noise_aware_tolerance);
    EXPECT_EQ(read.gp.kernel, expected->gp.kernel);
    EXPECT_EQ(read.gp.trend, expected->gp.trend);
  }
  EXPECT_EQ(read.adaptive_pool, simulator.adaptive_pool);
  EXPECT_EQ(read.gp.nugget_mode, simulator.gp.nugget_mode);
  EXPECT_EQ(read.batch_size, simulator.batch_size);
  fs::remove_all(dir);
}

TEST(CalibrationStudy, TwinStudiesLoad) {
  const Study p1 = Study::load(source_dir / "validation/twin/twin_p1.yaml");
  const CalibrationSettings p1_settings = read_calibration_settings(p1);
  EXPECT_EQ(p1.parameter_space().names(), std::vector<std::string>({"htc_p1"}));
  EXPECT_EQ(p1.parameter_space().parameter(0).prior.kind(), PriorKind::log10_uniform);
  EXPECT_DOUBLE_EQ(p1.parameter_space().parameter(0).prior.lower(), 1e-3);
  EXPECT_DOUBLE_EQ(p1.parameter_space().parameter(0).prior.upper(), 1e-1);
  EXPECT_EQ(p1.feature_names(), std::vector<std::string>({"R_gamma"}));
  EXPECT_EQ(p1_settings.observation_source, ObservationSource::signal_files);
  EXPECT_EQ(p1_settings.signal_files.size(), 3u);
  EXPECT_EQ(p1_settings.signal_files[0], source_dir / "validation/twin/data/measured_1.csv");

  const Study multi = Study::load(source_dir / "validation/twin/twin_multi.yaml");
  const CalibrationSettings multi_settings = read_calibration_settings(multi);
  EXPECT_EQ(multi.parameter_space().names(),
            std::vector<std::string>({"htc_p1", "melt_conductivity", "film_thickness_es"}));
  EXPECT_EQ(multi.feature_names(), std::vector<std::string>({"R_beta", "R_gamma", "dS_P", "d_n_liq"}));
  for (const auto& name : multi.feature_names()) EXPECT_NE(describe_feature(name).group, "other") << name;
  EXPECT_NEAR(multi.parameter_space().parameter(2).prior.upper(), 5e-4, 1e-18);  // 5e-1 mm in m
  EXPECT_EQ(multi_settings.observation_source, ObservationSource::features_file);
  EXPECT_EQ(multi_settings.noise.kind, ObservationNoise::Kind::ReplicateScatter);
  EXPECT_EQ(multi.model_overrides(),
            std::vector<std::string>({"mesh.base_size=0.5 mm", "mesh.weld_zone.levels=1", "output.interval=0 ms",
                                      "output.fields=false"}));
}

}  // namespace
}  // namespace rsw::calibration
