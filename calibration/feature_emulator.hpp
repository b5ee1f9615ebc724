// Emulators of the features and the likelihood they imply (the "emulator" calibration
// route, emulator_calibration.hpp; docs/CALIBRATION.md, "Two routes").
//
// One GP per feature j (gaussian_process.hpp: Matérn 5/2, a trend, an estimated nugget)
// on the runs' unit-cube points u, fitted to the standardised values (y_j − ȳ_j)/sd_j of
// the runs and mapped back, gives at u the latent mean m_j(u), the latent variance
// s_j²(u) (the emulator's own uncertainty, shrinking as runs are added) and the nugget
// τ_j² (the model's reproducible numerical noise, which no run removes). A feature is
// smooth in θ where the log-likelihood of many features is not: it varies by a few
// tens of per cent over the prior, while ℒ falls by thousands of units.
//
// The likelihood of the observations Y^(k)_j (k = 1 … N replicates, GaussianLikelihood:
// measurement variance σ_j² per replicate, a discrepancy δ_j² shared by all) when the
// model's feature is M_j(u) = m_j(u) + e_j, e_j ~ N(0, s_j²(u) + τ_j²) also shared (one
// model value per θ), is for each feature the Gaussian
// N(Y_j; m_j 1, σ_j² I + (δ_j² + s_j² + τ_j²) 11ᵀ), whose determinant and inverse give,
// with Ȳ_j the replicates' mean, S_j = Σ_k (Y^(k)_j − Ȳ_j)² and v_j = σ_j²/N + δ_j² the
// variance of the replicates' mean,
//     ln L̃(u) = Σ_j [ −S_j/(2σ_j²) − ((N − 1)/2) ln(2π σ_j²) − ½ ln N
//                    − (Ȳ_j − m_j)²/(2 W_j) − ½ ln(2π W_j) ],   W_j = v_j + s_j² + τ_j².
// With s_j = τ_j = 0 this is GaussianLikelihood::log_likelihood at M = m exactly, so the
// route estimates the same posterior and evidence as SBALC where the emulator is exact;
// elsewhere the emulator's uncertainty widens the likelihood instead of biasing it
// (Kennedy & O'Hagan 2001, §4; Higdon et al. 2004, "Combining field data and computer
// simulations for calibration and prediction").
//
// Warping (optional, per feature; Snelson, Rasmussen & Ghahramani 2004, "Warped Gaussian
// processes"). A feature can span a hundred times the data's precision over the prior
// (R_beta of the weld: 300–950 µΩ, against 3.5 µΩ for the mean of three welds), most of
// it in a corner; a stationary GP fitted to that range needs short length scales
// everywhere and stays uncertain where the posterior lives. The GP then learns
//     z = asinh((y − c)/w)       (c the observed mean, w a multiple of its standard error),
// which is linear within a few w of the data and logarithmic beyond, and the prediction
// goes back by the delta method: y = c + w sinh(m_z), s_y = w cosh(m_z) s_z, exact as
// s_z → 0. The nugget is reported at the data (τ_y = w τ_z), where it matters.
// Focusing (optional; history matching's refocusing, Vernon, Goldstein & Bower 2010,
// "Galaxy formation: a Bayesian uncertainty analysis", §4; Andrianakis et al. 2015).
// A feature that spans thousands of times the data's precision over the prior (the
// weld's R_beta: 300–3600 µΩ against 3.5 µΩ) forces one GP over all runs to a large
// signal variance and length scales set by the far corners; where the posterior lives
// it stays uncertain. With a focus, a second emulator learns only the plausible runs,
// those whose features all lie within training_cutoff data standard errors:
//     I_r = max_j |y_rj − Ȳ_j| / √(v_j + τ_j²) ≤ training_cutoff   (τ_j of the global fit),
// and at a point u the prediction is the focused one where the global emulator finds
// u plausible,
//     I(u) = max_j |Ȳ_j − m_j(u)| / √(v_j + s_j²(u) + τ_j²) ≤ cutoff   (3: Pukelsheim's
// three-sigma rule, as Vernon et al.), the global one elsewhere. The training cutoff
// is wider than the cutoff, so the focused emulator has runs beyond the border where it
// is used. Fewer than min_runs plausible runs, or all of them: no focused emulator.
// Units: u dimensionless; m_j, s_j, τ_j, Y, σ in the feature's SI unit.
#pragma once

#include "calibration/gaussian_process.hpp"
#include "calibration/likelihood.hpp"

#include <Eigen/Core>

#include <functional>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace rsw::calibration {

struct FeaturePrediction {
  Eigen::MatrixXd mean;             // m × p, m_j at each point
  Eigen::MatrixXd latent_variance;  // m × p, s_j²
  Eigen::MatrixXd noise_variance;   // m × p, τ_j² (the same in each row without a focus)
};

// Per feature j: centre c_j and width w_j > 0 of the warping above; empty: none.
struct FeatureWarping {
  Eigen::VectorXd centre, width;
};

// Rows (a, b) of the inputs that are near-duplicates (a noise pair: points a small
// distance δ apart). A smooth feature differs by O(δ) between them; what a rough one
// adds (a mesh's contact jumps, say) does not shrink with δ. The mean of
// (o_a − o_b)²/2 over the pairs, o the GP's standardised output, is then an estimate
// of the noise variance that bounds each feature's nugget τ_j² from below: a design
// too sparse to see the roughness otherwise lets the likelihood choose τ_j ≈ 0 and
// explain it by short length scales and a large emulator variance. The smooth part
// adds about δ² |∇y|²/(2d) to the bound, negligible for a small δ.
using NoisePairs = std::vector<std::pair<Eigen::Index, Eigen::Index>>;

// Inputs the GPs learn from the unit-cube points (m × d in, m × d' out), e.g. the points
// with derived columns appended (calibrate.hpp, log products); empty: the points.
using InputMap = std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)>;

// The focus above: the observed means Ȳ_j, their variances v_j, the two cutoffs and
// the fewest plausible runs a focused emulator is fitted to.
struct FeatureFocus {
  Eigen::VectorXd observed_mean, mean_variances;
  double cutoff = 3.0;
  double training_cutoff = 9.0;
  int min_runs = 30;
};

class FeatureEmulator {
 public:
  // inputs: n × d unit-cube points; features: n × p finite values. `previous` (same p),
  // if given, warm-starts each feature's hyperparameter search.
  // `pairs`, if any, give each feature's nugget floor (NoisePairs above).
  // `focus`, if given, adds the focused emulator (Focusing above).
  FeatureEmulator(const Eigen::MatrixXd& inputs, const Eigen::MatrixXd& features, const GaussianProcessOptions& options,
                  const FeatureEmulator* previous = nullptr, FeatureWarping warping = {}, const NoisePairs& pairs = {},
                  const std::optional<FeatureFocus>& focus = std::nullopt, InputMap map = {});

  FeaturePrediction predict(const Eigen::MatrixXd& points) const;
  // The same hyperparameters conditioned on one more point at each feature's own mean
  // (kriging believer, Ginsbourger et al. 2010): means unchanged, variances shrink near x.
  FeatureEmulator with_believed_point(const Eigen::VectorXd& x) const;

  int n_features() const { return static_cast<int>(processes_.size()); }
  int n_points() const { return processes_.empty() ? 0 : processes_.front().n_points(); }
  const std::vector<GaussianProcess>& processes() const { return processes_; }
  const Eigen::VectorXd& offsets() const { return offsets_; }  // mean of the GP's outputs
  const Eigen::VectorXd& scales() const { return scales_; }    // their sd
  // The focused emulator (null without one) and the rows of the inputs it learned.
  const FeatureEmulator* focused() const { return focused_.get(); }
  const std::vector<Eigen::Index>& focused_rows() const { return focused_rows_; }
  // I(u) of the global emulator at each point (Focusing); empty without a focus.
  Eigen::VectorXd implausibility(const Eigen::MatrixXd& points) const;

 private:
  FeatureEmulator() = default;
  FeaturePrediction predict_global(const Eigen::MatrixXd& points) const;
  Eigen::VectorXd global_noise_variances() const;  // τ_j² of the global fit, feature units
  Eigen::VectorXd implausibility(const FeaturePrediction& global) const;
  std::vector<GaussianProcess> processes_;
  Eigen::VectorXd offsets_, scales_;  // of the GP's outputs (z if warped)
  FeatureWarping warping_;
  InputMap map_;
  std::optional<FeatureFocus> focus_;
  std::shared_ptr<const FeatureEmulator> focused_;
  std::vector<Eigen::Index> focused_rows_;
};

// ln L̃ above for the observations and noise of `likelihood`.
class EmulatedLikelihood {
 public:
  explicit EmulatedLikelihood(const GaussianLikelihood& likelihood);

  // ln L̃ at each point of a prediction (m values).
  Eigen::VectorXd log_likelihood(const FeaturePrediction& prediction) const;
  // v_j = σ_j²/N + δ_j², the variance of the replicates' mean under the noise model.
  const Eigen::VectorXd& mean_variances() const { return mean_variances_; }

 private:
  Eigen::VectorXd observed_mean_, mean_variances_;
  double constant_ = 0.0;  // Σ_j [−S_j/(2σ_j²) − ((N − 1)/2) ln(2π σ_j²) − ½ ln N]
};

}  // namespace rsw::calibration
