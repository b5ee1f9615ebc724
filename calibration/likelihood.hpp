// Gaussian log-likelihood of named scalar features (paper §2.4; docs/CALIBRATION.md,
// "Likelihood").
//
// With N_obs observed replicates Y^(k) (k = 1 … N_obs) of p features and the model
// response M(θ), each replicate is Y^(k) = M(θ) + δ + e^(k): e^(k) the measurement
// errors, independent between replicates, zero mean, Σ = diag(σ_j²); δ the model's
// discrepancy, zero mean, D = diag(δ_j²), one and the same for every replicate of the
// weld (Kennedy & O'Hagan 2001, "Bayesian calibration of computer models": the
// discrepancy is a function of the inputs, not noise, so replicates do not average it
// away). The replicates of feature j are then jointly Gaussian with covariance
// σ_j² I + δ_j² 11ᵀ, whose inverse and determinant give, with the replicate mean Ȳ_j and
// scatter S_j = Σ_k (Y_j^(k) − Ȳ_j)²,
//     ln L(θ) = Σ_j [ −½ S_j/σ_j² − ½ (N_obs − 1) ln(2πσ_j²)
//                     − ½ (Ȳ_j − M_j)²/v_j − ½ ln(2π N_obs v_j) ],   v_j = σ_j²/N_obs + δ_j²,
// which for δ = 0 is −½ Σ_k r_kᵀ Σ⁻¹ r_k − (N_obs/2) ln det(2πΣ), r_k = Y^(k) − M(θ).
// The normalising terms are constant in θ; they are kept so that the evidence of SBALC
// is the true marginal density of the data. Σ is diagonal because the features are
// scalars of distinct physical origin, not an autocorrelated time series (paper §2.4).
// The measurement standard deviations σ_j come from one of
//   - given values per feature (feature units);
//   - a fraction of the observed mean, σ_j = fraction · |Ȳ_j|;
//   - the scatter of the replicates, σ_j = sample standard deviation (N_obs − 1
//     denominator; needs N_obs ≥ 2).
// δ_j² is an optional fixed model-discrepancy variance per feature. Features are matched
// by name; every σ_j² + δ_j² must be positive and finite, and σ_j² positive when there are
// several replicates; otherwise construction fails naming the feature.
// Units: ln L is dimensionless (log of a density in feature units^(−p·N_obs)).
#pragma once

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

namespace rsw::calibration {

struct ObservationNoise {
  enum class Kind { GivenStandardDeviations, RelativeToObservedMean, ReplicateScatter };
  Kind kind = Kind::ReplicateScatter;
  std::map<std::string, double> standard_deviations;  // GivenStandardDeviations, by feature name
  double relative_fraction = 0.0;                     // RelativeToObservedMean

  static ObservationNoise given(std::map<std::string, double> standard_deviations);
  static ObservationNoise relative(double fraction);
  static ObservationNoise replicate_scatter();
};

// The name of the study key's value (calibration.noise.kind).
const char* noise_kind_name(ObservationNoise::Kind kind);

class GaussianLikelihood {
 public:
  // observations: N_obs × p, column j is feature feature_names[j].
  // discrepancy_variances: δ_j² by feature name (feature units²); features not named get 0;
  // a name that is not an observed feature is an error.
  GaussianLikelihood(std::vector<std::string> feature_names, Eigen::MatrixXd observations, ObservationNoise noise,
                     const std::map<std::string, double>& discrepancy_variances = {});

  // Model features in the order of feature_names(). A NaN (a feature the run's signals
  // leave undefined, features.hpp) or infinite value has no likelihood: throws
  // std::invalid_argument naming the feature; the calibration records such a run as
  // failed (calibrate.hpp), and no value of it reaches the GP.
  double log_likelihood(const Eigen::VectorXd& model_features) const;
  // Model features by name; may contain more features than observed ones (ignored).
  // Throws std::invalid_argument naming the first observed feature that is missing.
  double log_likelihood(const std::vector<std::string>& names, const Eigen::VectorXd& values) const;
  double log_likelihood(const std::map<std::string, double>& model_features) const;

  const std::vector<std::string>& feature_names() const { return feature_names_; }
  int n_features() const { return static_cast<int>(feature_names_.size()); }
  int n_replicates() const { return static_cast<int>(observations_.rows()); }
  const Eigen::MatrixXd& observations() const { return observations_; }
  const Eigen::VectorXd& measurement_variances() const { return measurement_variances_; }  // σ_j²
  const Eigen::VectorXd& discrepancy_variances() const { return discrepancy_variances_; }  // δ_j²
  // σ_j² + δ_j²: the variance of one replicate about M(θ).
  const Eigen::VectorXd& variances() const { return variances_; }
  // The variance of the replicate mean about M(θ), v_j = σ_j²/N_obs + δ_j².
  Eigen::VectorXd mean_variances() const;
  // The terms of ln L constant in θ: Σ_j [−½ S_j/σ_j² − ½ (N_obs − 1) ln(2πσ_j²) − ½ ln(2π N_obs v_j)].
  double log_normalisation() const { return log_normalisation_; }

 private:
  std::vector<std::string> feature_names_;
  Eigen::MatrixXd observations_;
  Eigen::VectorXd measurement_variances_;
  Eigen::VectorXd discrepancy_variances_;
  Eigen::VectorXd variances_;
  Eigen::VectorXd observed_mean_;
  double log_normalisation_ = 0.0;
};

}  // namespace rsw::calibration
