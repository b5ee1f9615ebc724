// Feature emulators and the emulated likelihood; equations and sources in
// feature_emulator.hpp.
#include "calibration/feature_emulator.hpp"

#include "fem/threads.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace rsw::calibration {

FeatureEmulator::FeatureEmulator(const Eigen::MatrixXd& inputs, const Eigen::MatrixXd& features,
                                 const GaussianProcessOptions& options, const FeatureEmulator* previous,
                                 FeatureWarping warping, const NoisePairs& pairs,
                                 const std::optional<FeatureFocus>& focus, InputMap map)
    : warping_(std::move(warping)), map_(std::move(map)) {
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
  const Eigen::MatrixXd gp_inputs = map_ ? map_(inputs) : inputs;
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
    GaussianProcessRegression regression(gp_inputs, outputs, feature_options);
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
  if (!focus) return;
  if (focus->observed_mean.size() != p || focus->mean_variances.size() != p ||
      !(focus->mean_variances.array() > 0.0).all())
    throw std::invalid_argument("FeatureEmulator: a focus needs an observed mean and a positive variance per feature");
  if (!(focus->cutoff > 0.0) || !(focus->training_cutoff >= focus->cutoff))
    throw std::invalid_argument("FeatureEmulator: a focus needs 0 < cutoff <= training_cutoff");
  focus_ = focus;
  // The plausible runs, by their own features against the data and the global nugget.
  const Eigen::VectorXd allowed = (focus->mean_variances + global_noise_variances()).cwiseSqrt();
  std::vector<Eigen::Index> rows;
  for (Eigen::Index r = 0; r < features.rows(); ++r) {
    const double implausible =
        ((features.row(r).transpose() - focus->observed_mean).cwiseAbs().cwiseQuotient(allowed)).maxCoeff();
    if (implausible <= focus->training_cutoff) rows.push_back(r);
  }
  const auto n_rows = static_cast<Eigen::Index>(rows.size());
  if (n_rows < std::max(focus->min_runs, 2) || n_rows == inputs.rows()) return;
  Eigen::MatrixXd focused_inputs(n_rows, inputs.cols()), focused_features(n_rows, p);
  std::vector<Eigen::Index> new_row(static_cast<std::size_t>(inputs.rows()), -1);
  for (Eigen::Index k = 0; k < n_rows; ++k) {
    const Eigen::Index r = rows[static_cast<std::size_t>(k)];
    focused_inputs.row(k) = inputs.row(r);
    focused_features.row(k) = features.row(r);
    new_row[static_cast<std::size_t>(r)] = k;
  }
  NoisePairs focused_pairs;
  for (const auto& [a, b] : pairs) {
    const Eigen::Index fa = new_row[static_cast<std::size_t>(a)], fb = new_row[static_cast<std::size_t>(b)];
    if (fa >= 0 && fb >= 0) focused_pairs.emplace_back(fa, fb);
  }
  const FeatureEmulator* warm = previous != nullptr ? previous->focused() : nullptr;
  focused_ = std::make_shared<const FeatureEmulator>(focused_inputs, focused_features, options, warm, warping_,
                                                     focused_pairs, std::nullopt, map_);
  focused_rows_ = std::move(rows);
}

Eigen::VectorXd FeatureEmulator::global_noise_variances() const {
  const auto p = static_cast<Eigen::Index>(processes_.size());
  const bool warped = warping_.centre.size() > 0;
  Eigen::VectorXd noise(p);
  for (Eigen::Index j = 0; j < p; ++j) {
    const double at_data = warped ? warping_.width(j) : 1.0;  // dy/dz at z = 0
    noise(j) = processes_[static_cast<std::size_t>(j)].hyperparameters().noise_variance * scales_(j) * scales_(j) *
               at_data * at_data;
  }
  return noise;
}

Eigen::VectorXd FeatureEmulator::implausibility(const FeaturePrediction& global) const {
  if (!focus_) return {};
  const Eigen::ArrayXXd total = global.latent_variance.array() + global.noise_variance.array() +
                                focus_->mean_variances.transpose().replicate(global.mean.rows(), 1).array();
  const Eigen::ArrayXXd residual =
      (focus_->observed_mean.transpose().replicate(global.mean.rows(), 1) - global.mean).array().abs();
  return (residual / total.sqrt()).rowwise().maxCoeff().matrix();
}

Eigen::VectorXd FeatureEmulator::implausibility(const Eigen::MatrixXd& points) const {
  return implausibility(predict_global(points));
}

FeaturePrediction FeatureEmulator::predict(const Eigen::MatrixXd& points) const {
  FeaturePrediction prediction = predict_global(points);
  if (!focused_) return prediction;
  const Eigen::VectorXd implausible = implausibility(prediction);
  std::vector<Eigen::Index> plausible;
  for (Eigen::Index r = 0; r < points.rows(); ++r)
    if (implausible(r) <= focus_->cutoff) plausible.push_back(r);
  if (plausible.empty()) return prediction;
  Eigen::MatrixXd inside(static_cast<Eigen::Index>(plausible.size()), points.cols());
  for (std::size_t k = 0; k < plausible.size(); ++k) inside.row(static_cast<Eigen::Index>(k)) = points.row(plausible[k]);
  const FeaturePrediction local = focused_->predict(inside);
  for (std::size_t k = 0; k < plausible.size(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    prediction.mean.row(plausible[k]) = local.mean.row(row);
    prediction.latent_variance.row(plausible[k]) = local.latent_variance.row(row);
    prediction.noise_variance.row(plausible[k]) = local.noise_variance.row(row);
  }
  return prediction;
}

FeaturePrediction FeatureEmulator::predict_global(const Eigen::MatrixXd& points) const {
  FeaturePrediction prediction;
  const auto p = static_cast<Eigen::Index>(processes_.size());
  const Eigen::Index m = points.rows();
  prediction.mean.resize(m, p);
  prediction.latent_variance.resize(m, p);
  prediction.noise_variance = global_noise_variances().transpose().replicate(m, 1);
  const bool warped = warping_.centre.size() > 0;
  const Eigen::MatrixXd gp_points = map_ ? map_(points) : points;
  // Blocks of points on the process's threads; Eigen runs serially inside the region,
  // so each block is computed the same way whatever the thread count.
  constexpr Eigen::Index block = 128;
  const Eigen::Index n_blocks = (m + block - 1) / block;
  const fem::TeamRegion team;  // the process's threads (fem/threads.hpp)
#pragma omp parallel for schedule(dynamic) if (n_blocks > 1)
  for (Eigen::Index b = 0; b < n_blocks; ++b) {
    const Eigen::Index start = b * block, rows = std::min(block, m - start);
    const Eigen::MatrixXd chunk = gp_points.middleRows(start, rows);
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
  believed.map_ = map_;
  believed.focus_ = focus_;
  believed.focused_rows_ = focused_rows_;
  if (focused_) believed.focused_ = std::make_shared<const FeatureEmulator>(focused_->with_believed_point(x));
  const Eigen::VectorXd gx = map_ ? Eigen::VectorXd(map_(Eigen::MatrixXd(x.transpose())).row(0).transpose()) : x;
  for (const GaussianProcess& process : processes_) {
    believed.processes_.push_back(process.with_added_point(gx, process.predict(gx).mean(0)));
  }
  return believed;
}

EmulatedLikelihood::EmulatedLikelihood(const GaussianLikelihood& likelihood) {
  // ln L of likelihood.hpp with the replicate mean's variance v_j widened by the
  // emulator's; its θ-free terms are the likelihood's less the ½ ln(2π N v_j) that the
  // widened variance replaces.
  observed_mean_ = likelihood.observations().colwise().mean().transpose();
  mean_variances_ = likelihood.mean_variances();
  const auto n = static_cast<double>(likelihood.n_replicates());
  constant_ = likelihood.log_normalisation() + 0.5 * (2.0 * M_PI * n * mean_variances_.array()).log().sum() -
              0.5 * static_cast<double>(mean_variances_.size()) * std::log(n);
}

Eigen::VectorXd EmulatedLikelihood::log_likelihood(const FeaturePrediction& prediction) const {
  if (prediction.mean.cols() != observed_mean_.size())
    throw std::invalid_argument("EmulatedLikelihood: the prediction has " + std::to_string(prediction.mean.cols()) +
                                " features, the observations " + std::to_string(observed_mean_.size()));
  Eigen::VectorXd values = Eigen::VectorXd::Constant(prediction.mean.rows(), constant_);
  for (Eigen::Index j = 0; j < observed_mean_.size(); ++j) {
    const Eigen::ArrayXd total =
        prediction.latent_variance.col(j).array() + prediction.noise_variance.col(j).array() + mean_variances_(j);
    const Eigen::ArrayXd residual = observed_mean_(j) - prediction.mean.col(j).array();
    values.array() -= 0.5 * residual.square() / total + 0.5 * (2.0 * M_PI * total).log();
  }
  return values;
}

}  // namespace rsw::calibration
