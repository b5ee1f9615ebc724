// Posterior by sampling-importance-resampling (SIR) of a prior pool (paper §2.5;
// Smith & Gelfand 1992, "Bayesian statistics without tears"; Rubin 1988).
//
// The pool θ_1 … θ_N is drawn from the prior (uniform on [0,1]^d in the standardised
// space), so the posterior f(θ | Y) ∝ L(θ) f(θ) gives the pool point i the importance
// weight
//     w_i = exp(ℓ_i − max ℓ) / Σ_k exp(ℓ_k − max ℓ),   ℓ_i = ln L(θ_i)  (SBALC: GP mean m),
// formed by log-sum-exp. From the weighted pool:
//   - effective sample size ESS = 1 / Σ w_i² (Kish), always reported;
//   - posterior mean, standard deviation, correlation matrix (weighted moments);
//   - equal-tailed credible intervals: the (1 − level)/2 and (1 + level)/2 quantiles of
//     the weighted empirical distribution of each coordinate (smallest pool value whose
//     cumulative weight reaches the probability);
//   - MAP: the pool point of largest ℓ, optionally refined by maximising a given log
//     density inside [0,1]^d (BOBYQA, optimizer.hpp) from that point;
//   - n_samples posterior draws by systematic resampling of the pool with weights w.
// Moments and quantiles use the weights directly (lower Monte Carlo error than the
// resampled draws, which are for plotting and propagation).
//
// Small-sample warning: when the likelihood is concentrated compared with the pool
// (a narrow posterior, or one in a corner or at an edge of the prior box) only a few
// pool points carry weight, and every figure above rests on them. The result is then
// flagged poorly_resolved, with a message, when
//     ESS < max(ess_min_absolute, ess_min_fraction · N)      (defaults 100 and 1 %),
// instead of silently returning a posterior made of a handful of points.
#pragma once

#include "calibration/sbalc.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace rsw::calibration {

struct PosteriorOptions {
  int n_samples = 0;                // resampled draws; 0: as many as pool points
  std::uint64_t seed = 1;
  double credible_level = 0.95;
  double ess_min_absolute = 100.0;
  double ess_min_fraction = 0.01;
  bool refine_map = true;           // only if a log density is available
};

struct CredibleInterval {
  double lower = 0.0;
  double upper = 0.0;
};

struct PosteriorResult {
  Eigen::MatrixXd samples;   // n_samples × d resampled pool points
  Eigen::VectorXd weights;   // normalised importance weight of each pool point
  double effective_sample_size = 0.0;
  double ess_threshold = 0.0;
  bool poorly_resolved = false;
  std::string warning;       // empty unless poorly_resolved
  Eigen::VectorXd mean;
  Eigen::VectorXd standard_deviation;
  Eigen::MatrixXd correlation;
  double credible_level = 0.0;
  std::vector<CredibleInterval> credible_intervals;  // one per coordinate
  Eigen::VectorXd map_point;
  double map_log_density = 0.0;  // ℓ (or the refined log density) at map_point
  bool map_refined = false;
};

// The weighted quantiles of `values` (weights ≥ 0, summing to 1) at each probability:
// the smallest value whose cumulative weight reaches it.
Eigen::VectorXd weighted_quantiles(const Eigen::VectorXd& values, const Eigen::VectorXd& weights,
                                   const std::vector<double>& probabilities);

class SirPosterior {
 public:
  // pool: N × d prior samples; log_likelihoods: ℓ_i at the pool points (finite or −∞).
  // log_density (optional): ℓ(θ) for refining the MAP; maximised over [0,1]^d.
  SirPosterior(Eigen::MatrixXd pool, Eigen::VectorXd log_likelihoods, PosteriorOptions options = {},
               std::function<double(const Eigen::VectorXd&)> log_density = {});
  // The SBALC pool with ℓ = GP latent mean (weights times the pool's prior/proposal
  // ratio if the pool is adaptive, sbalc.hpp); the MAP is refined on the GP mean.
  explicit SirPosterior(const SbalcResult& sbalc, PosteriorOptions options = {});
  // A pool drawn from a proposal q instead of the prior: log_pool_weights = ln(prior/q)
  // per point (the emulator route's importance pool, tempered_smc.hpp).
  SirPosterior(Eigen::MatrixXd pool, Eigen::VectorXd log_likelihoods, Eigen::VectorXd log_pool_weights,
               PosteriorOptions options, std::function<double(const Eigen::VectorXd&)> log_density = {});

  PosteriorResult run() const;

 private:
  Eigen::MatrixXd pool_;
  Eigen::VectorXd log_likelihoods_;
  Eigen::VectorXd log_pool_weights_;  // ln(prior/proposal) of an adaptive SBALC pool; empty: prior pool
  PosteriorOptions options_;
  std::function<double(const Eigen::VectorXd&)> log_density_;
};

}  // namespace rsw::calibration
