// Calibration parameters θ: names, the config key each one sets, priors, and the
// transforms between physical and standardised space (docs/CALIBRATION.md, "Parameters
// and priors").
//
// Priors and their standardised variable s:
//   uniform [a, b]:            F(x) = (x − a)/(b − a),                           s = F(x) ∈ [0, 1]
//   log10-uniform [a, b]:      F(x) = (log10 x − log10 a)/(log10 b − log10 a),  s = F(x) ∈ [0, 1]
//   normal (μ, σ):             s = (x − μ)/σ, a standard normal variable
//   truncated normal (μ, σ, [a, b]):
//                              F(x) = (Φ(z) − Φ(z_a))/(Φ(z_b) − Φ(z_a)), z = (x − μ)/σ,
//                              s = F(x) ∈ [0, 1]
// so every bounded prior becomes uniform on [0, 1] (Legendre polynomials, designs in the
// unit cube) and the normal prior becomes standard normal (Hermite polynomials). The
// way back is the inverse CDF (isoprobabilistic transform). Φ is computed from erfc;
// Φ⁻¹ by Acklam's rational approximation refined by one Halley step (full double
// precision). Tails of the truncated normal are evaluated on the side where the
// probabilities are not rounded away.
//
// Values are in the parameter's unit (SI). The paper's Table I (film thickness in mm
// there) is paper_parameter_space(), in metres.
#pragma once

#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace rsw::calibration {

// The standardised space of one parameter.
enum class StandardSpace { unit_interval, standard_normal };

enum class PriorKind { uniform, log10_uniform, normal, truncated_normal };
// The name of a prior kind in study files and result files ("uniform", "log10_uniform",
// "normal", "truncated_normal").
const char* prior_kind_name(PriorKind kind);

double standard_normal_cdf(double z);
// Φ⁻¹(p) for p ∈ (0, 1); ±∞ at p = 0, 1; throws std::invalid_argument outside [0, 1].
double standard_normal_quantile(double p);

class Prior {
 public:
  // Each factory throws std::invalid_argument for empty or non-finite ranges, a
  // non-positive log10-uniform bound or a non-positive standard deviation.
  static Prior uniform(double lower, double upper);
  static Prior log10_uniform(double lower, double upper);
  static Prior normal(double mean, double standard_deviation);
  static Prior truncated_normal(double mean, double standard_deviation, double lower,
                                double upper);

  PriorKind kind() const { return kind_; }
  StandardSpace standard_space() const;
  double lower() const { return lower_; }  // −∞ for a normal prior
  double upper() const { return upper_; }  // +∞ for a normal prior

  double cdf(double x) const;
  // Inverse CDF, p ∈ [0, 1].
  double quantile(double p) const;
  // log of the probability density at x; −∞ outside the support.
  double log_density(double x) const;

  // Physical value → standardised value s (see above) and back.
  double to_standard(double x) const;
  double to_physical(double s) const;

  // E.g. "log10-uniform [1e-07, 0.0005]".
  std::string describe() const;

 private:
  Prior(PriorKind kind, double lower, double upper, double mean, double standard_deviation);

  PriorKind kind_;
  double lower_;
  double upper_;
  double mean_;                // normal priors
  double standard_deviation_;  // normal priors
};

struct Parameter {
  std::string name;        // e.g. "htc_p1"
  std::string config_key;  // config path the value is written to, e.g. "contact.electrode_sheet.htc_p1"
  std::string unit;        // unit of the physical value (SI), "1" for a plain number
  Prior prior;
};

class ParameterSpace {
 public:
  ParameterSpace() = default;
  // Throws std::invalid_argument on an empty or duplicate name or config key.
  explicit ParameterSpace(std::vector<Parameter> parameters);
  void add(Parameter parameter);

  std::size_t n_parameters() const { return parameters_.size(); }
  const Parameter& parameter(std::size_t index) const { return parameters_.at(index); }
  // Throws std::invalid_argument naming the known parameters.
  const Parameter& parameter(const std::string& name) const;
  std::size_t index_of(const std::string& name) const;
  std::vector<std::string> names() const;
  std::vector<StandardSpace> standard_spaces() const;

  // One point; sizes must equal n_parameters() (std::invalid_argument otherwise).
  Eigen::VectorXd to_standard(const Eigen::VectorXd& physical) const;
  Eigen::VectorXd to_physical(const Eigen::VectorXd& standard) const;
  // u ∈ (0, 1)^d (a design point) → standardised space: identity for unit-interval
  // parameters, Φ⁻¹(u) for standard-normal ones.
  Eigen::VectorXd unit_to_standard(const Eigen::VectorXd& unit_point) const;

  // The same for many points, one per row.
  Eigen::MatrixXd points_to_standard(const Eigen::MatrixXd& physical) const;
  Eigen::MatrixXd points_to_physical(const Eigen::MatrixXd& standard) const;
  Eigen::MatrixXd unit_points_to_standard(const Eigen::MatrixXd& unit_points) const;

  // Σ log prior densities at a physical point (priors are independent).
  double log_prior_density(const Eigen::VectorXd& physical) const;

  // (config key, physical value) for every parameter: the overrides one run needs.
  std::vector<std::pair<std::string, double>> config_assignments(
      const Eigen::VectorXd& physical) const;

 private:
  void check_size(const Eigen::VectorXd& point, const char* what) const;
  std::vector<Parameter> parameters_;
};

// The six parameters and priors of the paper's Table I, in SI units:
//   film_thickness_ss       contact.sheet_sheet.film_thickness           m     log10-U [1e-7, 5e-4]
//   coating_resistivity_ss  contact.sheet_sheet.coating_resistivity      ohm*m log10-U [5e-7, 5e-5]
//   film_thickness_es       contact.electrode_sheet.film_thickness       m     log10-U [1e-7, 5e-4]
//   coating_resistivity_es  contact.electrode_sheet.coating_resistivity  ohm*m log10-U [5e-7, 5e-5]
//   htc_p1                  contact.electrode_sheet.htc_p1               1     log10-U [1e-3, 1e-1]
//   melt_conductivity       thermal.melt_conductivity                    W/(m*K) U [35, 200]
// (Table I gives the film thickness in mm: [1e-4, 5e-1] mm.) The upper and lower E/S
// interfaces share their parameters (symmetric stack-up, paper §2.1.3).
ParameterSpace paper_parameter_space();

}  // namespace rsw::calibration
