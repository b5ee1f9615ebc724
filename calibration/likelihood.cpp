// Gaussian log-likelihood of named features; equations in likelihood.hpp.
#include "calibration/likelihood.hpp"

#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>

namespace rsw::calibration {

const char* noise_kind_name(ObservationNoise::Kind kind) {
  switch (kind) {
    case ObservationNoise::Kind::GivenStandardDeviations:
      return "standard_deviations";
    case ObservationNoise::Kind::RelativeToObservedMean:
      return "relative";
    case ObservationNoise::Kind::ReplicateScatter:
      return "replicate_scatter";
  }
  return "unknown";
}


namespace {

constexpr double kLogTwoPi = 1.8378770664093454835606594728112;

}  // namespace

ObservationNoise ObservationNoise::given(std::map<std::string, double> standard_deviations) {
  ObservationNoise noise;
  noise.kind = Kind::GivenStandardDeviations;
  noise.standard_deviations = std::move(standard_deviations);
  return noise;
}

ObservationNoise ObservationNoise::relative(double fraction) {
  ObservationNoise noise;
  noise.kind = Kind::RelativeToObservedMean;
  noise.relative_fraction = fraction;
  return noise;
}

ObservationNoise ObservationNoise::replicate_scatter() { return ObservationNoise{}; }

GaussianLikelihood::GaussianLikelihood(std::vector<std::string> feature_names, Eigen::MatrixXd observations,
                                       ObservationNoise noise,
                                       const std::map<std::string, double>& discrepancy_variances)
    : feature_names_(std::move(feature_names)), observations_(std::move(observations)) {
  const Eigen::Index p = static_cast<Eigen::Index>(feature_names_.size());
  if (p == 0) throw std::invalid_argument("GaussianLikelihood: no features");
  if (observations_.cols() != p)
    throw std::invalid_argument("GaussianLikelihood: " + std::to_string(p) + " feature names but " +
                                std::to_string(observations_.cols()) + " observation columns");
  if (observations_.rows() == 0) throw std::invalid_argument("GaussianLikelihood: no observations");
  std::set<std::string> seen;
  for (Eigen::Index j = 0; j < p; ++j) {
    if (!seen.insert(feature_names_[j]).second)
      throw std::invalid_argument("GaussianLikelihood: feature '" + feature_names_[j] + "' observed twice");
    if (!observations_.col(j).allFinite())
      throw std::invalid_argument("GaussianLikelihood: non-finite observation of feature '" + feature_names_[j] + "'");
  }
  for (const auto& entry : noise.standard_deviations)
    if (!seen.count(entry.first))
      throw std::invalid_argument("GaussianLikelihood: standard deviation given for '" + entry.first +
                                  "', which is not an observed feature");
  for (const auto& entry : discrepancy_variances)
    if (!seen.count(entry.first))
      throw std::invalid_argument("GaussianLikelihood: discrepancy variance given for '" + entry.first +
                                  "', which is not an observed feature");

  const double n_obs = static_cast<double>(observations_.rows());
  measurement_variances_.resize(p);
  discrepancy_variances_.resize(p);
  variances_.resize(p);
  for (Eigen::Index j = 0; j < p; ++j) {
    const std::string& name = feature_names_[j];
    const double mean = observations_.col(j).mean();
    double sd = 0.0;
    switch (noise.kind) {
      case ObservationNoise::Kind::GivenStandardDeviations: {
        const auto it = noise.standard_deviations.find(name);
        if (it == noise.standard_deviations.end())
          throw std::invalid_argument("GaussianLikelihood: no standard deviation given for feature '" + name + "'");
        sd = it->second;
        break;
      }
      case ObservationNoise::Kind::RelativeToObservedMean:
        sd = noise.relative_fraction * std::abs(mean);
        break;
      case ObservationNoise::Kind::ReplicateScatter:
        if (observations_.rows() < 2)
          throw std::invalid_argument("GaussianLikelihood: replicate scatter of feature '" + name +
                                      "' needs at least two replicates");
        sd = std::sqrt((observations_.col(j).array() - mean).square().sum() / (n_obs - 1.0));
        break;
    }
    const auto discrepancy = discrepancy_variances.find(name);
    const double delta2 = discrepancy == discrepancy_variances.end() ? 0.0 : discrepancy->second;
    if (!(delta2 >= 0.0) || !std::isfinite(delta2))
      throw std::invalid_argument("GaussianLikelihood: discrepancy variance of feature '" + name +
                                  "' must be finite and >= 0, got " + std::to_string(delta2));
    measurement_variances_(j) = sd * sd;
    discrepancy_variances_(j) = delta2;
    variances_(j) = sd * sd + delta2;
    if (!(variances_(j) > 0.0) || !std::isfinite(variances_(j)))
      throw std::invalid_argument("GaussianLikelihood: variance of feature '" + name + "' must be finite and > 0, got " +
                                  std::to_string(variances_(j)));
    if (observations_.rows() > 1 && !(measurement_variances_(j) > 0.0))
      throw std::invalid_argument("GaussianLikelihood: the measurement standard deviation of feature '" + name +
                                  "' is 0, but its " + std::to_string(observations_.rows()) +
                                  " replicates need a positive one (a discrepancy is shared by all replicates)");
  }
  observed_mean_ = observations_.colwise().mean().transpose();
  const Eigen::VectorXd v = mean_variances();
  log_normalisation_ = 0.0;
  for (Eigen::Index j = 0; j < p; ++j) {
    if (observations_.rows() > 1) {
      const double scatter = (observations_.col(j).array() - observed_mean_(j)).square().sum();
      log_normalisation_ += -0.5 * scatter / measurement_variances_(j) -
                            0.5 * (n_obs - 1.0) * (kLogTwoPi + std::log(measurement_variances_(j)));
    }
    log_normalisation_ += -0.5 * (kLogTwoPi + std::log(n_obs * v(j)));
  }
}

Eigen::VectorXd GaussianLikelihood::mean_variances() const {
  return measurement_variances_ / static_cast<double>(observations_.rows()) + discrepancy_variances_;
}

double GaussianLikelihood::log_likelihood(const Eigen::VectorXd& model_features) const {
  if (model_features.size() != static_cast<Eigen::Index>(feature_names_.size()))
    throw std::invalid_argument("GaussianLikelihood: " + std::to_string(model_features.size()) +
                                " model features for " + std::to_string(feature_names_.size()) + " observed ones");
  for (Eigen::Index j = 0; j < model_features.size(); ++j) {
    if (std::isnan(model_features(j)))
      throw std::invalid_argument("GaussianLikelihood: feature '" + feature_names_[j] +
                                  "' is undefined (NaN) for this run, so the run has no likelihood");
    if (!std::isfinite(model_features(j)))
      throw std::invalid_argument("GaussianLikelihood: non-finite model value of feature '" + feature_names_[j] + "'");
  }
  const Eigen::ArrayXd residuals = observed_mean_ - model_features;
  return -0.5 * (residuals.square() / mean_variances().array()).sum() + log_normalisation_;
}

double GaussianLikelihood::log_likelihood(const std::vector<std::string>& names, const Eigen::VectorXd& values) const {
  if (static_cast<Eigen::Index>(names.size()) != values.size())
    throw std::invalid_argument("GaussianLikelihood: " + std::to_string(names.size()) + " names but " +
                                std::to_string(values.size()) + " values");
  std::map<std::string, double> by_name;
  for (std::size_t i = 0; i < names.size(); ++i) by_name[names[i]] = values(static_cast<Eigen::Index>(i));
  return log_likelihood(by_name);
}

double GaussianLikelihood::log_likelihood(const std::map<std::string, double>& model_features) const {
  Eigen::VectorXd ordered(static_cast<Eigen::Index>(feature_names_.size()));
  for (std::size_t j = 0; j < feature_names_.size(); ++j) {
    const auto it = model_features.find(feature_names_[j]);
    if (it == model_features.end())
      throw std::invalid_argument("GaussianLikelihood: model output lacks observed feature '" + feature_names_[j] + "'");
    ordered(static_cast<Eigen::Index>(j)) = it->second;
  }
  return log_likelihood(ordered);
}

}  // namespace rsw::calibration
