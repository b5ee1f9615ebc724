// Priors, standardisation transforms and the paper's parameter space; see
// parameter_space.hpp. Φ⁻¹: P. J. Acklam's rational approximation (relative error
// 1.15e-9) followed by one Halley step on Φ(z) − p, which brings it to machine precision.
#include "calibration/parameter_space.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rsw::calibration {

const char* prior_kind_name(PriorKind kind) {
  switch (kind) {
    case PriorKind::uniform:
      return "uniform";
    case PriorKind::log10_uniform:
      return "log10_uniform";
    case PriorKind::normal:
      return "normal";
    case PriorKind::truncated_normal:
      return "truncated_normal";
  }
  return "unknown";
}
namespace {

constexpr double infinity = std::numeric_limits<double>::infinity();
constexpr double pi = 3.14159265358979323846;

// Upper tail Q(z) = 1 − Φ(z) without cancellation.
double standard_normal_upper_tail(double z) { return 0.5 * std::erfc(z / std::sqrt(2.0)); }

double acklam_quantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                             -2.759285104469687e+02, 1.383577518672690e+02,
                             -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                             -1.556989798598866e+02, 6.680131188771972e+01,
                             -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                             -2.400758277161838e+00, -2.549732539343734e+00,
                             4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                             2.445134137142996e+00, 3.754408661907416e+00};
  const double p_low = 0.02425;
  if (p < p_low) {
    const double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - p_low) {
    const double q = std::sqrt(-2 * std::log1p(-p));
    return -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  const double q = p - 0.5;
  const double r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

std::string number(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

}  // namespace

double standard_normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

double standard_normal_quantile(double p) {
  require(p >= 0 && p <= 1, "normal quantile needs a probability in [0, 1], got " + number(p));
  if (p == 0) return -infinity;
  if (p == 1) return infinity;
  double z = acklam_quantile(p);
  // Halley step on f(z) = Φ(z) − p, evaluated on the side with the smaller tail.
  const double error = z < 0 ? standard_normal_cdf(z) - p : (1 - p) - standard_normal_upper_tail(z);
  const double u = error * std::sqrt(2 * pi) * std::exp(0.5 * z * z);
  z -= u / (1 + 0.5 * z * u);
  return z;
}

// ---------------------------------------------------------------------------------
// Prior

Prior::Prior(PriorKind kind, double lower, double upper, double mean, double standard_deviation)
    : kind_(kind),
      lower_(lower),
      upper_(upper),
      mean_(mean),
      standard_deviation_(standard_deviation) {}

Prior Prior::uniform(double lower, double upper) {
  require(std::isfinite(lower) && std::isfinite(upper) && lower < upper,
          "uniform prior needs finite bounds lower < upper, got [" + number(lower) + ", " +
              number(upper) + "]");
  return Prior(PriorKind::uniform, lower, upper, 0, 0);
}

Prior Prior::log10_uniform(double lower, double upper) {
  require(std::isfinite(lower) && std::isfinite(upper) && lower > 0 && lower < upper,
          "log10-uniform prior needs finite bounds 0 < lower < upper, got [" + number(lower) +
              ", " + number(upper) + "]");
  return Prior(PriorKind::log10_uniform, lower, upper, 0, 0);
}

Prior Prior::normal(double mean, double standard_deviation) {
  require(std::isfinite(mean) && std::isfinite(standard_deviation) && standard_deviation > 0,
          "normal prior needs a finite mean and a positive standard deviation, got (" +
              number(mean) + ", " + number(standard_deviation) + ")");
  return Prior(PriorKind::normal, -infinity, infinity, mean, standard_deviation);
}

Prior Prior::truncated_normal(double mean, double standard_deviation, double lower,
                              double upper) {
  require(std::isfinite(mean) && std::isfinite(standard_deviation) && standard_deviation > 0,
          "truncated normal prior needs a finite mean and a positive standard deviation");
  require(std::isfinite(lower) && std::isfinite(upper) && lower < upper,
          "truncated normal prior needs finite bounds lower < upper, got [" + number(lower) +
              ", " + number(upper) + "]");
  Prior prior(PriorKind::truncated_normal, lower, upper, mean, standard_deviation);
  const double z_a = (lower - mean) / standard_deviation;
  const double z_b = (upper - mean) / standard_deviation;
  const double mass = z_a > 0 ? standard_normal_upper_tail(z_a) - standard_normal_upper_tail(z_b)
                              : standard_normal_cdf(z_b) - standard_normal_cdf(z_a);
  require(mass > 0, "truncated normal prior: the interval [" + number(lower) + ", " +
                        number(upper) + "] carries no probability in double precision");
  return prior;
}

StandardSpace Prior::standard_space() const {
  return kind_ == PriorKind::normal ? StandardSpace::standard_normal : StandardSpace::unit_interval;
}

double Prior::cdf(double x) const {
  switch (kind_) {
    case PriorKind::uniform:
      if (x <= lower_) return 0;
      if (x >= upper_) return 1;
      return (x - lower_) / (upper_ - lower_);
    case PriorKind::log10_uniform:
      if (x <= lower_) return 0;
      if (x >= upper_) return 1;
      return (std::log10(x) - std::log10(lower_)) / (std::log10(upper_) - std::log10(lower_));
    case PriorKind::normal:
      return standard_normal_cdf((x - mean_) / standard_deviation_);
    case PriorKind::truncated_normal: {
      if (x <= lower_) return 0;
      if (x >= upper_) return 1;
      const double z = (x - mean_) / standard_deviation_;
      const double z_a = (lower_ - mean_) / standard_deviation_;
      const double z_b = (upper_ - mean_) / standard_deviation_;
      if (z_a > 0) {  // upper tail: work with Q = 1 − Φ
        const double q_a = standard_normal_upper_tail(z_a);
        return (q_a - standard_normal_upper_tail(z)) / (q_a - standard_normal_upper_tail(z_b));
      }
      const double p_a = standard_normal_cdf(z_a);
      return (standard_normal_cdf(z) - p_a) / (standard_normal_cdf(z_b) - p_a);
    }
  }
  return 0;
}

double Prior::quantile(double p) const {
  require(p >= 0 && p <= 1, "prior quantile needs a probability in [0, 1], got " + number(p));
  switch (kind_) {
    case PriorKind::uniform:
      return lower_ + p * (upper_ - lower_);
    case PriorKind::log10_uniform: {
      const double log_lower = std::log10(lower_);
      return std::pow(10.0, log_lower + p * (std::log10(upper_) - log_lower));
    }
    case PriorKind::normal:
      return mean_ + standard_deviation_ * standard_normal_quantile(p);
    case PriorKind::truncated_normal: {
      const double z_a = (lower_ - mean_) / standard_deviation_;
      const double z_b = (upper_ - mean_) / standard_deviation_;
      double z = 0;
      if (z_a > 0) {
        const double q_a = standard_normal_upper_tail(z_a);
        const double q = q_a - p * (q_a - standard_normal_upper_tail(z_b));
        z = -standard_normal_quantile(q);
      } else {
        const double p_a = standard_normal_cdf(z_a);
        z = standard_normal_quantile(p_a + p * (standard_normal_cdf(z_b) - p_a));
      }
      const double x = mean_ + standard_deviation_ * z;
      return std::min(std::max(x, lower_), upper_);
    }
  }
  return 0;
}

double Prior::log_density(double x) const {
  if (kind_ != PriorKind::normal && (x < lower_ || x > upper_)) return -infinity;
  switch (kind_) {
    case PriorKind::uniform:
      return -std::log(upper_ - lower_);
    case PriorKind::log10_uniform:
      return -std::log(x * std::log(10.0) * (std::log10(upper_) - std::log10(lower_)));
    case PriorKind::normal:
    case PriorKind::truncated_normal: {
      const double z = (x - mean_) / standard_deviation_;
      double log_mass = 0;
      if (kind_ == PriorKind::truncated_normal) {
        const double z_a = (lower_ - mean_) / standard_deviation_;
        const double z_b = (upper_ - mean_) / standard_deviation_;
        log_mass = std::log(z_a > 0 ? standard_normal_upper_tail(z_a) - standard_normal_upper_tail(z_b)
                                    : standard_normal_cdf(z_b) - standard_normal_cdf(z_a));
      }
      return -0.5 * z * z - std::log(standard_deviation_ * std::sqrt(2 * pi)) - log_mass;
    }
  }
  return -infinity;
}

double Prior::to_standard(double x) const {
  if (kind_ == PriorKind::normal) return (x - mean_) / standard_deviation_;
  return cdf(x);
}

double Prior::to_physical(double s) const {
  if (kind_ == PriorKind::normal) return mean_ + standard_deviation_ * s;
  return quantile(s);
}

std::string Prior::describe() const {
  switch (kind_) {
    case PriorKind::uniform:
      return "uniform [" + number(lower_) + ", " + number(upper_) + "]";
    case PriorKind::log10_uniform:
      return "log10-uniform [" + number(lower_) + ", " + number(upper_) + "]";
    case PriorKind::normal:
      return "normal (mean " + number(mean_) + ", sd " + number(standard_deviation_) + ")";
    case PriorKind::truncated_normal:
      return "truncated normal (mean " + number(mean_) + ", sd " + number(standard_deviation_) +
             ") on [" + number(lower_) + ", " + number(upper_) + "]";
  }
  return "";
}

// ---------------------------------------------------------------------------------
// ParameterSpace

ParameterSpace::ParameterSpace(std::vector<Parameter> parameters) {
  for (auto& parameter : parameters) add(std::move(parameter));
}

void ParameterSpace::add(Parameter parameter) {
  require(!parameter.name.empty(), "a calibration parameter needs a name");
  require(!parameter.config_key.empty(),
          "calibration parameter '" + parameter.name + "' needs a config key");
  for (const auto& other : parameters_) {
    require(other.name != parameter.name, "calibration parameter '" + parameter.name +
                                              "' is defined twice");
    require(other.config_key != parameter.config_key,
            "calibration parameters '" + other.name + "' and '" + parameter.name +
                "' both set config key '" + parameter.config_key + "'");
  }
  parameters_.push_back(std::move(parameter));
}

std::size_t ParameterSpace::index_of(const std::string& name) const {
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    if (parameters_[i].name == name) return i;
  }
  std::string known;
  for (const auto& p : parameters_) known += (known.empty() ? "" : ", ") + p.name;
  throw std::invalid_argument("no calibration parameter '" + name + "' (known: " +
                              (known.empty() ? std::string("none") : known) + ")");
}

const Parameter& ParameterSpace::parameter(const std::string& name) const {
  return parameters_[index_of(name)];
}

std::vector<std::string> ParameterSpace::names() const {
  std::vector<std::string> result;
  for (const auto& p : parameters_) result.push_back(p.name);
  return result;
}

std::vector<StandardSpace> ParameterSpace::standard_spaces() const {
  std::vector<StandardSpace> result;
  for (const auto& p : parameters_) result.push_back(p.prior.standard_space());
  return result;
}

void ParameterSpace::check_size(const Eigen::VectorXd& point, const char* what) const {
  require(static_cast<std::size_t>(point.size()) == parameters_.size(),
          std::string(what) + " point has " + std::to_string(point.size()) + " entries for " +
              std::to_string(parameters_.size()) + " parameters");
}

Eigen::VectorXd ParameterSpace::to_standard(const Eigen::VectorXd& physical) const {
  check_size(physical, "physical");
  Eigen::VectorXd result(physical.size());
  for (Eigen::Index i = 0; i < physical.size(); ++i) {
    result[i] = parameters_[static_cast<std::size_t>(i)].prior.to_standard(physical[i]);
  }
  return result;
}

Eigen::VectorXd ParameterSpace::to_physical(const Eigen::VectorXd& standard) const {
  check_size(standard, "standardised");
  Eigen::VectorXd result(standard.size());
  for (Eigen::Index i = 0; i < standard.size(); ++i) {
    result[i] = parameters_[static_cast<std::size_t>(i)].prior.to_physical(standard[i]);
  }
  return result;
}

Eigen::VectorXd ParameterSpace::unit_to_standard(const Eigen::VectorXd& unit_point) const {
  check_size(unit_point, "unit-cube");
  Eigen::VectorXd result(unit_point.size());
  for (Eigen::Index i = 0; i < unit_point.size(); ++i) {
    const double u = unit_point[i];
    require(u >= 0 && u <= 1, "unit-cube point coordinate " + std::to_string(i) + " = " +
                                  number(u) + " is outside [0, 1]");
    result[i] = parameters_[static_cast<std::size_t>(i)].prior.standard_space() ==
                        StandardSpace::standard_normal
                    ? standard_normal_quantile(u)
                    : u;
  }
  return result;
}

Eigen::MatrixXd ParameterSpace::points_to_standard(const Eigen::MatrixXd& physical) const {
  Eigen::MatrixXd result(physical.rows(), physical.cols());
  for (Eigen::Index r = 0; r < physical.rows(); ++r) {
    result.row(r) = to_standard(physical.row(r).transpose()).transpose();
  }
  return result;
}

Eigen::MatrixXd ParameterSpace::points_to_physical(const Eigen::MatrixXd& standard) const {
  Eigen::MatrixXd result(standard.rows(), standard.cols());
  for (Eigen::Index r = 0; r < standard.rows(); ++r) {
    result.row(r) = to_physical(standard.row(r).transpose()).transpose();
  }
  return result;
}

Eigen::MatrixXd ParameterSpace::unit_points_to_standard(const Eigen::MatrixXd& unit_points) const {
  Eigen::MatrixXd result(unit_points.rows(), unit_points.cols());
  for (Eigen::Index r = 0; r < unit_points.rows(); ++r) {
    result.row(r) = unit_to_standard(unit_points.row(r).transpose()).transpose();
  }
  return result;
}

double ParameterSpace::log_prior_density(const Eigen::VectorXd& physical) const {
  check_size(physical, "physical");
  double sum = 0;
  for (Eigen::Index i = 0; i < physical.size(); ++i) {
    sum += parameters_[static_cast<std::size_t>(i)].prior.log_density(physical[i]);
  }
  return sum;
}

std::vector<std::pair<std::string, double>> ParameterSpace::config_assignments(
    const Eigen::VectorXd& physical) const {
  check_size(physical, "physical");
  std::vector<std::pair<std::string, double>> result;
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    result.emplace_back(parameters_[i].config_key, physical[static_cast<Eigen::Index>(i)]);
  }
  return result;
}

ParameterSpace paper_parameter_space() {
  // Table I of the paper; film thickness converted from mm to m.
  return ParameterSpace({
      {"film_thickness_ss", "contact.sheet_sheet.film_thickness", "m",
       Prior::log10_uniform(1e-7, 5e-4)},
      {"coating_resistivity_ss", "contact.sheet_sheet.coating_resistivity", "ohm*m",
       Prior::log10_uniform(5e-7, 5e-5)},
      {"film_thickness_es", "contact.electrode_sheet.film_thickness", "m",
       Prior::log10_uniform(1e-7, 5e-4)},
      {"coating_resistivity_es", "contact.electrode_sheet.coating_resistivity", "ohm*m",
       Prior::log10_uniform(5e-7, 5e-5)},
      {"htc_p1", "contact.electrode_sheet.htc_p1", "1", Prior::log10_uniform(1e-3, 1e-1)},
      {"melt_conductivity", "thermal.melt_conductivity", "W/(m*K)", Prior::uniform(35, 200)},
  });
}

}  // namespace rsw::calibration
