// Gaussian-process regression (universal kriging) with an optional nugget.
//
// Model (Rasmussen & Williams 2006, "Gaussian Processes for Machine Learning",
// RW below; §2.7 for the explicit trend):
//     y_i = h(x_i)ᵀβ + f(x_i) + ε_i,   f ~ GP(0, σ² c(x, x')),   ε_i ~ N(0, τ²) i.i.d.
// - c is an anisotropic stationary correlation of r² = Σ_j ((x_j − x'_j)/ℓ_j)²:
//     squared exponential  c = exp(−r²/2)                             (RW eq. 4.9)
//     Matérn 5/2           c = (1 + √5 r + 5r²/3) exp(−√5 r)           (RW eq. 4.17)
// - h(x) is the trend basis, evaluated on inputs centred and scaled to [−1, 1] over the
//   training box: constant [1]; diagonal quadratic [1, u_j, u_j²] (1 + 2d terms); full
//   quadratic [1, u_j, u_j u_k (j ≤ k)] (1 + d + d(d+1)/2 terms). A quadratic trend is
//   used only when the data support it (n ≥ n_terms + 2 and a full-rank basis matrix);
//   otherwise the fit falls back to the constant trend and says so (trend_used()).
// - τ² is the nugget: Off (τ² = 0, the GP interpolates), Fixed (given τ²), or Estimated
//   with the other hyperparameters, bounded below by a floor. For a deterministic
//   simulator the nugget stands for reproducible numerical noise that the smooth latent
//   f should not follow (Gramacy & Lee 2012, "Cases for the nugget in modeling computer
//   experiments"); the paper's SBALC failed for want of it (docs/CALIBRATION.md, "The
//   nugget").
//
// With K = σ² C + τ² I (+ jitter, below), the trend coefficients are the generalised
// least-squares estimate β̂ = (HᵀK⁻¹H)⁻¹ HᵀK⁻¹ y (RW eq. 2.42) and the hyperparameters
// η = (ln ℓ_1 … ln ℓ_d, ln σ², [ln τ² when estimated]) maximise the log marginal
// likelihood with β profiled out,
//     ln p(y | η) = −½ (y − Hβ̂)ᵀ K⁻¹ (y − Hβ̂) − ½ ln|K| − (n/2) ln 2π      (RW eq. 2.30),
// whose gradient, since β̂ maximises ln p for fixed η (envelope theorem), is
//     ∂ ln p / ∂η_j = ½ tr((ααᵀ − K⁻¹) ∂K/∂η_j),   α = K⁻¹ (y − Hβ̂)      (RW eq. 5.9),
// with ∂K/∂ln ℓ_j = σ² g(r) (Δx_j/ℓ_j)², g = exp(−r²/2) (SE) or
// (5/3)(1 + √5 r) exp(−√5 r) (Matérn 5/2); ∂K/∂ln σ² = σ² C; ∂K/∂ln τ² = τ² I.
// The maximisation runs L-BFGS (optimizer.hpp) from a heuristic start (ℓ_j = 0.3 ×
// input range, σ² = var(y), τ² = 1e-2 var(y)), an optional warm start and n_restarts
// seeded random starts (uniform in the log bounds), inside bounds relative to the input
// range per dimension and to the sample variance var(y) of the outputs.
//
// K is factorised by Cholesky; if that fails (duplicate points, very long length
// scales) a jitter δ·I is added, δ = 1e-10 · mean(diag K), multiplied by 10 until the
// factorisation succeeds or δ exceeds max_jitter_relative · mean(diag K) (then an
// exception; inside the hyperparameter search such a trial point is skipped). A pivot
// L_ii² below 1e-2 · δ_initial counts as a failure even if Eigen accepts it: it is
// round-off, not information (an exactly duplicated point). The jitter used is
// reported; it is numerical, not part of τ².
//
// Nugget floor: the default relative floor is tiny (1e-10 · var(y)) on purpose. For a
// log-likelihood var(y) is dominated by the far, very negative values (ℒ spans tens to
// thousands of units over the prior box), so a relative floor of the usual 1e-6 would
// already impose a noise of ~1e-3 · sd(y), e.g. 0.03 log-likelihood units, on a
// noise-free problem.
//
// Prediction at x* (RW eqs. 2.25–2.26 with the trend term of eq. 2.42), k* = σ² c(X, x*):
//     m(x*)  = h*ᵀβ̂ + k*ᵀ α
//     s²(x*) = σ² − k*ᵀK⁻¹k* + gᵀ(HᵀK⁻¹H)⁻¹g,   g = h* − HᵀK⁻¹k*
// m and s² are the latent (epistemic) mean and variance of h*ᵀβ + f(x*); the noise
// variance τ² (aleatoric) is returned separately; a new observation has variance s² + τ².
// Units: inputs in the caller's units (rsw: the standardised space [0,1]^d), outputs and
// √τ², √σ² in output units (for SBALC: log-likelihood units).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>

namespace rsw::calibration {

enum class KernelType { SquaredExponential, Matern52 };
enum class TrendType { Constant, DiagonalQuadratic, FullQuadratic };
enum class NuggetMode { Off, Fixed, Estimated };

// The names of the study keys (calibration.*.kernel, trend, nugget).
const char* kernel_name(KernelType kernel);
const char* trend_name(TrendType trend);
const char* nugget_name(NuggetMode mode);

struct GaussianProcessHyperparameters {
  Eigen::VectorXd length_scales;  // ℓ_j, input units
  double signal_variance = 1.0;   // σ², output units²
  double noise_variance = 0.0;    // τ² (nugget), output units²
};

struct GaussianProcessOptions {
  KernelType kernel = KernelType::Matern52;
  TrendType trend = TrendType::Constant;
  NuggetMode nugget_mode = NuggetMode::Off;
  double fixed_noise_variance = 0.0;         // τ² for NuggetMode::Fixed, output units²
  double nugget_floor_relative = 1e-10;      // Estimated: τ² ≥ floor · var(y) ...
  double nugget_floor_absolute = 0.0;        // ... and τ² ≥ this (output units²)
  double nugget_ceiling_relative = 1.0;      // Estimated: τ² ≤ ceiling · var(y)
  double length_scale_min_relative = 1e-2;   // ℓ_j bounds, × input range of dimension j
  double length_scale_max_relative = 1e1;
  double signal_variance_min_relative = 1e-4;  // σ² bounds, × var(y)
  double signal_variance_max_relative = 1e4;
  int n_restarts = 4;                        // seeded random starts besides the heuristic one
  std::uint64_t seed = 20250101;
  double initial_jitter_relative = 1e-10;    // × mean(diag K)
  double max_jitter_relative = 1e-4;         // × mean(diag K)
};

// Predictions at m points (rows of the input matrix).
struct GaussianProcessPrediction {
  Eigen::VectorXd mean;             // latent mean m(x)
  Eigen::VectorXd latent_variance;  // s²(x) ≥ 0, epistemic
  double noise_variance = 0.0;      // τ², aleatoric, the same at every x
};

// How the hyperparameters were found (empty for a GP conditioned on given values).
struct GaussianProcessFitReport {
  int n_starts = 0;
  int n_evaluations = 0;   // likelihood evaluations over all starts
  int best_start = -1;     // 0 heuristic, 1 warm start if given, then random starts
  std::string optimizer_message;
};

// A GP conditioned on data with fixed hyperparameters (the result object of
// GaussianProcessRegression::run()). Inputs are rows: n × d.
class GaussianProcess {
 public:
  GaussianProcess(Eigen::MatrixXd inputs, Eigen::VectorXd outputs, GaussianProcessOptions options,
                  GaussianProcessHyperparameters hyperparameters);

  GaussianProcessPrediction predict(const Eigen::MatrixXd& points) const;
  GaussianProcessPrediction predict(const Eigen::VectorXd& point) const;

  // The same hyperparameters, conditioned on one more observation (kriging believer).
  GaussianProcess with_added_point(const Eigen::VectorXd& x, double y) const;

  int n_points() const { return static_cast<int>(inputs_.rows()); }
  int dimension() const { return static_cast<int>(inputs_.cols()); }
  const Eigen::MatrixXd& inputs() const { return inputs_; }
  const Eigen::VectorXd& outputs() const { return outputs_; }
  const GaussianProcessOptions& options() const { return options_; }
  const GaussianProcessHyperparameters& hyperparameters() const { return hyperparameters_; }
  TrendType trend_used() const { return trend_used_; }
  const Eigen::VectorXd& trend_coefficients() const { return beta_; }  // β̂, on the scaled inputs
  double jitter() const { return jitter_; }                           // δ added to diag K
  double log_marginal_likelihood() const { return log_marginal_likelihood_; }
  const GaussianProcessFitReport& fit_report() const { return fit_report_; }

 private:
  friend class GaussianProcessRegression;

  Eigen::MatrixXd inputs_;
  Eigen::VectorXd outputs_;
  GaussianProcessOptions options_;
  GaussianProcessHyperparameters hyperparameters_;
  TrendType trend_used_ = TrendType::Constant;
  Eigen::VectorXd trend_center_, trend_half_range_;
  Eigen::MatrixXd cholesky_;       // lower L, L Lᵀ = K + δI
  Eigen::MatrixXd whitened_trend_; // F = L⁻¹H
  Eigen::MatrixXd trend_r_;        // upper R with FᵀF = RᵀR
  Eigen::VectorXd beta_;
  Eigen::VectorXd alpha_;          // K⁻¹ (y − Hβ̂)
  double jitter_ = 0.0;
  double log_marginal_likelihood_ = 0.0;
  GaussianProcessFitReport fit_report_;
};

// Hyperparameter estimation: construct → run() → GaussianProcess.
class GaussianProcessRegression {
 public:
  GaussianProcessRegression(Eigen::MatrixXd inputs, Eigen::VectorXd outputs, GaussianProcessOptions options = {});

  // An extra start for the maximisation (e.g. the previous fit in an active-learning
  // loop), clipped into the bounds.
  void set_warm_start(const GaussianProcessHyperparameters& hyperparameters) { warm_start_ = hyperparameters; }

  GaussianProcess run() const;

  // η = (ln ℓ_1 … ln ℓ_d, ln σ², [ln τ² if NuggetMode::Estimated]).
  int n_hyperparameters() const;
  Eigen::VectorXd to_log_vector(const GaussianProcessHyperparameters& hyperparameters) const;
  GaussianProcessHyperparameters from_log_vector(const Eigen::VectorXd& eta) const;
  const Eigen::VectorXd& log_lower_bounds() const { return log_lower_; }
  const Eigen::VectorXd& log_upper_bounds() const { return log_upper_; }

  // ln p(y | η) and, if gradient != nullptr, ∂ ln p / ∂η. Returns −∞ if K cannot be
  // factorised within the jitter cap.
  double log_marginal_likelihood(const Eigen::VectorXd& eta, Eigen::VectorXd* gradient = nullptr) const;

  TrendType trend_used() const { return trend_used_; }

 private:
  Eigen::MatrixXd inputs_;
  Eigen::VectorXd outputs_;
  GaussianProcessOptions options_;
  TrendType trend_used_ = TrendType::Constant;
  Eigen::VectorXd trend_center_, trend_half_range_;
  Eigen::MatrixXd trend_basis_;  // H, n × p
  Eigen::VectorXd input_range_;
  double output_variance_ = 1.0;
  Eigen::VectorXd log_lower_, log_upper_;
  GaussianProcessHyperparameters warm_start_;  // used when its length_scales are set
};

}  // namespace rsw::calibration
