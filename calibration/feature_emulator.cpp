// Feature emulators and the emulated likelihood; equations and sources in
// feature_emulator.hpp.
#include "calibration/feature_emulator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace rsw::calibration {

FeatureEmulator::FeatureEmulator(const Eigen::MatrixXd& inputs, const Eigen::MatrixXd& features,
                                 const GaussianProcessOptions& options, const FeatureEmulator* previous,
                                 FeatureWarping warping, const NoisePairs& pairs)
    : warping_(std::move(warping)) {
  if (inputs.rows() != features.rows())
    throw std::invalid_argument("FeatureEmulator: " + std::to_string(inputs.rows()) + " points but " +
                                std::to_string(features.rows()) + " feature rows");
  if (inputs.rows() < 2) throw std::invalid_argument("FeatureEmulator: at least two runs are needed");
  if (!features.allFinite()) throw std::invalid_argument("FeatureEmulator: feature values must be finite");
  for (const auto& [a, b] : pairs) {
    if (a < 0 || b < 0 || a >= inputs.rows() || b >= inputs.rows() || a == b)
      throw std::invalid_argument("FeatureEmulator: a noise pair names a row outside the inputs");
  }
  if (previous != nullptr && previous->n_features() != features.cols())
    throw std::invalid_argument("FeatureEmulator: the previous emulator has another number of features");
  const Eigen::Index p = features.cols();
  const bool warped = warping_.centre.size() > 0;
  if (warped && (warping_.centre.size() != p || warping_.width.size() != p || !(warping_.width.array() > 0.0).all()))
    throw std::invalid_argument("FeatureEmulator: a warping needs a centre and a positive width per feature");
  offsets_.resize(p);
  scales_.resize(p);
  for (Eigen::Index j = 0; j < p; ++j) {
    const Eigen::VectorXd column =
        warped ? Eigen::VectorXd(((features.col(j).array() - warping_.centre(j)) / warping_.width(j)).asinh())
               : Eigen::VectorXd(features.col(j));
    const double mean = column.mean();
    const double variance = (column.array() - mean).square().sum() / static_cast<double>(column.size() - 1);
    offsets_(j) = mean;
    // A feature constant over the runs keeps a unit scale (its GP is then flat).
    scales_(j) = variance > 0.0 ? std::sqrt(variance) : std::max(std::abs(mean), 1.0);
    GaussianProcessOptions feature_options = options;
    feature_options.seed = options.seed + static_cast<std::uint64_t>(j);
    const Eigen::VectorXd outputs = (column.array() - mean).matrix() / scales_(j);
    if (!pairs.empty()) {
      double floor = 0.0;
      for (const auto& [a, b] : pairs) floor += 0.5 * (outputs(a) - outputs(b)) * (outputs(a) - outputs(b));
      floor /= static_cast<double>(pairs.size());
      feature_options.nugget_floor_absolute = std::max(feature_options.nugget_floor_absolute, floor);
    }
    GaussianProcessRegression regression(inputs, outputs, feature_options);
    if (previous != nullptr) {
      const GaussianProcess& before = previous->processes_[static_cast<std::size_t>(j)];
      GaussianProcessHyperparameters warm = before.hyperparameters();
      // The previous fit was on another standardisation: rescale its variances.
      const double ratio = previous->scales_(j) / scales_(j);
      warm.signal_variance *= ratio * ratio;
      warm.noise_variance *= ratio * ratio;
      regression.set_warm_start(warm);
    }
    processes_.push_back(regression.run());
  }
}

FeaturePrediction FeatureEmulator::predict(const Eigen::MatrixXd& points) const {
  FeaturePrediction prediction;
  const auto p = static_cast<Eigen::Index>(processes_.size());
  const Eigen::Index m = points.rows();
  prediction.mean.resize(m, p);
  prediction.latent_variance.resize(m, p);
  prediction.noise_variance.resize(p);
  const bool warped = warping_.centre.size() > 0;
  for (Eigen::Index j = 0; j < p; ++j) {
    const double at_data = warped ? warping_.width(j) : 1.0;  // dy/dz at z = 0
    prediction.noise_variance(j) = processes_[static_cast<std::size_t>(j)].hyperparameters().noise_variance *
                                   scales_(j) * scales_(j) * at_data * at_data;
  }
  // Blocks of points on the process's threads; Eigen runs serially inside the region,
  // so each block is computed the same way whatever the thread count.
  constexpr Eigen::Index block = 128;
  const Eigen::Index n_blocks = (m + block - 1) / block;
#pragma omp parallel for schedule(dynamic) if (n_blocks > 1)
  for (Eigen::Index b = 0; b < n_blocks; ++b) {
    const Eigen::Index start = b * block, rows = std::min(block, m - start);
    const Eigen::MatrixXd chunk = points.middleRows(start, rows);
    for (Eigen::Index j = 0; j < p; ++j) {
      const GaussianProcessPrediction one = processes_[static_cast<std::size_t>(j)].predict(chunk);
      const double scale = scales_(j);
      const Eigen::ArrayXd mean = one.mean.array() * scale + offsets_(j);
      const Eigen::ArrayXd variance = one.latent_variance.array() * (scale * scale);
      if (warped) {
        const double c = warping_.centre(j), w = warping_.width(j);
        prediction.mean.col(j).segment(start, rows) = (c + w * mean.sinh()).matrix();
        prediction.latent_variance.col(j).segment(start, rows) = (variance * (w * mean.cosh()).square()).matrix();
      } else {
        prediction.mean.col(j).segment(start, rows) = mean.matrix();
        prediction.latent_variance.col(j).segment(start, rows) = variance.matrix();
      }
    }
  }
  return prediction;
}

FeatureEmulator FeatureEmulator::with_believed_point(const Eigen::VectorXd& x) const {
  FeatureEmulator believed;
  believed.offsets_ = offsets_;
  believed.scales_ = scales_;
  believed.warping_ = warping_;
  for (const GaussianProcess& process : processes_) {
    believed.processes_.push_back(process.with_added_point(x, process.predict(x).mean(0)));
  }
  return believed;
}

EmulatedLikelihood::EmulatedLikelihood(const GaussianLikelihood& likelihood) {
  const Eigen::MatrixXd& y = likelihood.observations();
  const Eigen::VectorXd& variances = likelihood.variances();
  const auto n = static_cast<double>(y.rows());
  observed_mean_ = y.colwise().mean().transpose();
  mean_variances_ = variances / n;
  constant_ = 0.0;
  for (Eigen::Index j = 0; j < y.cols(); ++j) {
    const double scatter = (y.col(j).array() - observed_mean_(j)).square().sum();
    constant_ += -0.5 * scatter / variances(j) - 0.5 * (n - 1.0) * std::log(2.0 * M_PI * variances(j)) -
                 0.5 * std::log(n);
  }
}

Eigen::VectorXd EmulatedLikelihood::log_likelihood(const FeaturePrediction& prediction) const {
  if (prediction.mean.cols() != observed_mean_.size())
    throw std::invalid_argument("EmulatedLikelihood: the prediction has " + std::to_string(prediction.mean.cols()) +
                                " features, the observations " + std::to_string(observed_mean_.size()));
  Eigen::VectorXd values = Eigen::VectorXd::Constant(prediction.mean.rows(), constant_);
  for (Eigen::Index j = 0; j < observed_mean_.size(); ++j) {
    const Eigen::ArrayXd total =
        prediction.latent_variance.col(j).array() + (mean_variances_(j) + prediction.noise_variance(j));
    const Eigen::ArrayXd residual = observed_mean_(j) - prediction.mean.col(j).array();
    values.array() -= 0.5 * residual.square() / total + 0.5 * (2.0 * M_PI * total).log();
  }
  return values;
}

}  // namespace rsw::calibration
