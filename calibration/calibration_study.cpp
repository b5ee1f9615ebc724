// The calibration section of a study file, the observation files and the likelihood
// built from them; see calibration_study.hpp.
#include "calibration/calibration_study.hpp"
#include "fem/csv.hpp"
#include "fem/text.hpp"

#include "calibration/signal.hpp"

#include "fem/units.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rsw::calibration {
namespace {

using fem::lower;
using fem::trim;

namespace fs = std::filesystem;
using fem::Config;
using fem::Range;

const char* const observations_features_file = "calibration.observations.features_file";

constexpr TrendType all_trends[] = {TrendType::Constant, TrendType::DiagonalQuadratic, TrendType::FullQuadratic};

std::vector<std::string> trend_names() {
  std::vector<std::string> names;
  for (TrendType trend : all_trends) names.emplace_back(trend_name(trend));
  return names;
}

// The trend a schema-checked choice names.
TrendType trend_of(const std::string& name) {
  for (TrendType trend : all_trends)
    if (name == trend_name(trend)) return trend;
  throw std::logic_error("unknown GP trend '" + name + "' passed the schema");
}
const char* const observations_signal_files = "calibration.observations.signal_files";
const char* const noise_kind = "calibration.noise.kind";
const char* const noise_standard_deviations = "calibration.noise.standard_deviations";
const char* const noise_discrepancy = "calibration.noise.discrepancy";
const char* const initial_runs_key = "calibration.initial_runs";

// A default value as the schema shows it: 15 significant digits, no trailing zeros.
std::string shortest(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.15g", value);
  return text;
}




std::string join_names(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) text += (i ? ", " : "") + names[i];
  return text;
}

// The SI unit features are handled in ("1" for a feature of unknown unit).
std::string feature_unit(const std::string& feature) {
  const std::string unit = describe_feature(feature).unit;
  return unit.empty() ? "1" : unit;
}

fs::path resolve(const Study& study, const std::string& text) {
  const fs::path given(text);
  return given.is_absolute() ? given : (fs::absolute(study.file()).parent_path() / given).lexically_normal();
}

// Where the item list[index] was written: the first of its keys given in the file.
std::string item_where(const Config& config, const std::string& list, int index,
                       const std::vector<std::string>& keys) {
  for (const auto& key : keys) {
    const std::string path = fem::item_path(list, index, key);
    if (config.contains(path) && !config.is_default(path)) return config.origin(path).where();
  }
  return config.origin(list).where();
}

// Config::fail, but a key left at its default is located in the study file.
[[noreturn]] void fail_key(const Study& study, const std::string& path, const std::string& requirement) {
  const Config& c = study.config();
  if (!c.is_default(path)) c.fail(path, requirement);
  throw fem::ConfigError(study.file().string() + ": " + path + " = " + c.display(path) + " (the default): " +
                         requirement);
}

// A spread (σ_j or δ_j) of `feature` given as a quantity; SI, without unit offsets.
double read_spread(const Config& config, const std::string& path, const std::string& feature) {
  const std::string unit = feature_unit(feature);
  const std::string example = unit == "1" ? "'0.05'" : "'2 " + unit + "'";
  const std::string expected = "a quantity in units of " + fem::quantity_kind(unit) + " such as " + example +
                               (unit == "1" ? "" : " (a bare number is read in " + unit + ")");
  fem::Quantity quantity;
  try {
    quantity = fem::split_quantity(config.text(path));
  } catch (const fem::UnitError&) {
    config.fail(path, "not a number; expected " + expected);
  }
  const std::string from = quantity.unit.empty() ? unit : quantity.unit;
  if (!fem::is_known_unit(from)) config.fail(path, "unknown unit '" + from + "'; expected " + expected);
  if (!fem::units_convertible(from, unit)) {
    config.fail(path, "is in " + from + " (" + fem::quantity_kind(from) + "), but feature '" + feature + "' is in " +
                          unit + " (" + fem::quantity_kind(unit) + "); expected " + expected);
  }
  // A spread is a difference: drop the offset of affine units (K ↔ degC).
  return fem::convert_units(quantity.value, from, unit) - fem::convert_units(0.0, from, unit);
}

// Reads a list of {feature, <value_key>} items into spreads by feature name.
std::map<std::string, double> read_feature_spreads(const Config& config, const std::string& list,
                                                   const std::string& value_key,
                                                   const std::vector<std::string>& features, bool positive) {
  std::map<std::string, double> spreads;
  for (int k = 0; k < config.n_items(list); ++k) {
    const std::string feature_path = fem::item_path(list, k, "feature");
    const std::string value_path = fem::item_path(list, k, value_key);
    const std::string feature = config.text(feature_path);
    if (feature.empty()) {
      throw fem::ConfigError(item_where(config, list, k, {value_key}) + ": " + feature_path +
                             ": missing; each item names a feature of the study (" + join_names(features) + ")");
    }
    if (std::find(features.begin(), features.end(), feature) == features.end()) {
      config.fail(feature_path, "not a feature of the study; allowed: " + join_names(features));
    }
    if (spreads.count(feature)) config.fail(feature_path, "given twice; each feature once");
    if (config.text(value_path).empty()) {
      throw fem::ConfigError(item_where(config, list, k, {"feature"}) + ": " + value_path + ": missing; give the " +
                             (value_key == "value" ? "standard deviation" : "discrepancy standard deviation") +
                             " of feature '" + feature + "', e.g. " + (value_key + ": 2 " + feature_unit(feature)));
    }
    const double value = read_spread(config, value_path, feature);
    if (positive ? !(value > 0) : !(value >= 0)) config.fail(value_path, positive ? "must be > 0" : "must be >= 0");
    spreads[feature] = value;
  }
  return spreads;
}

}  // namespace

void declare_calibration_keys(fem::ConfigSchema& s) {
  s.section("calibration",
            "Bayesian calibration (rsw calibrate): observations, Gaussian noise model, SBALC and the SIR posterior.");
  s.section("calibration.observations",
            "What was measured: a features file or measured signal files (exactly one of the two).");
  s.string(observations_features_file).default_value("")
      .doc("CSV of observed feature vectors, one replicate per row; header 'R_gamma [uohm], ...' (a name without "
           "unit is in SI); relative to the study file's folder.");
  s.list(observations_signal_files).items(0, 100000).default_value("[]")
      .doc("Measured signal files (time [ms], current [kA], voltage [V], ...), one replicate each; their features "
           "come from the same extractor as the simulator's.");
  s.string(std::string(observations_signal_files) + "[].file").default_value("")
      .doc("A signal file, relative to the study file's folder; required.");

  s.section("calibration.noise", "The diagonal covariance Sigma = diag(sigma_j^2 + delta_j^2) of the Gaussian likelihood.");
  s.choice(noise_kind, {"standard_deviations", "relative", "replicate_scatter"}).default_value("replicate_scatter")
      .doc("sigma_j: given per feature (standard_deviations), fraction * |observed mean| (relative), or the sample "
           "standard deviation of the replicates (replicate_scatter; needs two or more).");
  s.number("calibration.noise.fraction", "1", "1").default_value("0.05").range(Range::open_closed(0, 10))
      .doc("relative: sigma_j as a fraction of the absolute observed mean of feature j.");
  s.list(noise_standard_deviations).items(0, 1000).default_value("[]")
      .doc("standard_deviations: sigma_j of every feature of the study.");
  s.string(std::string(noise_standard_deviations) + "[].feature").default_value("")
      .doc("A feature of the study; required.");
  s.string(std::string(noise_standard_deviations) + "[].value").default_value("")
      .doc("Its measurement standard deviation, e.g. '2 uohm' (a bare number is in the feature's SI unit), > 0.");
  s.list(noise_discrepancy).items(0, 1000).default_value("[]")
      .doc("Model-discrepancy spread delta_j, shared by all replicates; 0 if not listed.");
  s.string(std::string(noise_discrepancy) + "[].feature").default_value("")
      .doc("A feature of the study; required.");
  s.string(std::string(noise_discrepancy) + "[].standard_deviation").default_value("")
      .doc("delta_j, e.g. '3 uohm' (a bare number is in the feature's SI unit), >= 0.");

  // The defaults are simulator_sbalc_options() (sbalc.hpp, "Defaults"): the library's
  // SbalcOptions{} with the adaptive pool, the estimated nugget and batches of 4.
  const SbalcOptions defaults = simulator_sbalc_options();
  s.choice("calibration.method", {"sbalc", "emulator"}).default_value("sbalc")
      .doc("sbalc (the paper's, for up to three parameters) or emulator (docs/CALIBRATION.md, 'Two routes').");
  s.section("calibration.sbalc",
            "Streamlined Bayesian active learning cubature of the evidence (Li et al. 2025) with a nugget. The "
            "defaults are the paper's SBALC except pool: adaptive, nugget: estimated and batch_size: 4, chosen for "
            "a noisy finite-element forward model run on parallel workers.");
  s.integer("calibration.sbalc.pool_size").default_value(std::to_string(defaults.pool_size))
      .range(Range::closed(100, 10000000))
      .doc("N_M prior samples for the evidence, its bounds, the learning function and the posterior (paper: 2e4).");
  s.integer("calibration.sbalc.initial_points").default_value(std::to_string(defaults.n_initial))
      .range(Range::closed(2, 100000))
      .doc("n_0 points of the initial Hammersley design (paper: 5).");
  s.integer("calibration.sbalc.batch_size").default_value(std::to_string(defaults.batch_size))
      .range(Range::closed(1, 10000))
      .doc("Points chosen per iteration (kriging believer) and evaluated in parallel; 1: the paper's sequential "
           "SBALC.");
  s.integer("calibration.sbalc.max_evaluations").default_value(std::to_string(defaults.max_evaluations))
      .range(Range::closed(2, 1000000))
      .doc("Cap on forward-model runs, initial design and failed runs included; reaching it means not converged.");
  s.number("calibration.sbalc.tolerance", "1", "1").default_value(shortest(defaults.tolerance))
      .range(Range::open_closed(0, 100))
      .doc("Stop when (c_upper - c_lower)/c is below it twice in a row, with the checks of docs/CALIBRATION.md "
           "(paper: 0.1).");
  s.choice("calibration.sbalc.nugget", {"off", "fixed", "estimated"})
      .default_value(defaults.gp.nugget_mode == NuggetMode::Off     ? "off"
                     : defaults.gp.nugget_mode == NuggetMode::Fixed ? "fixed"
                                                                    : "estimated")
      .doc("Noise variance of the GP of the log-likelihood: off (interpolating, the paper's), fixed "
           "(nugget_standard_deviation) or estimated with the other hyperparameters (docs/CALIBRATION.md, "
           "'The nugget').");
  s.number("calibration.sbalc.nugget_standard_deviation", "1", "1").default_value("0.1")
      .range(Range::greater_than(0))
      .doc("fixed: the noise standard deviation tau of the log-likelihood, in log-likelihood units.");
  s.integer("calibration.sbalc.seed").default_value(std::to_string(defaults.seed)).range(Range::closed(0, 1e9))
      .doc("Seed of the prior pool and the GP restarts; the same seed replays the same sequence of runs.");
  s.choice("calibration.sbalc.failed_runs", {"impute_minimum", "exclude"})
      .default_value(defaults.failed_runs == FailedRunPolicy::exclude ? "exclude" : "impute_minimum")
      .doc("impute_minimum: a failed run enters the GP at the lowest log-likelihood so far; exclude: left out.");
  s.number("calibration.sbalc.log_likelihood_range", "1", "1").default_value(shortest(defaults.log_likelihood_range))
      .range(Range::closed(0, 1e6))
      .doc("The GP sees max(lnL, lnL_max - range); 0: no floor (the paper's).");
  s.choice("calibration.sbalc.pool", {"adaptive", "prior"}).default_value(defaults.adaptive_pool ? "adaptive" : "prior")
      .doc("prior: the paper's pool; adaptive: redrawn around the current posterior when its effective sample "
           "size falls below 2 % of the pool.");
  s.choice("calibration.sbalc.kernel", {"matern52", "squared_exponential"})
      .default_value(defaults.gp.kernel == KernelType::SquaredExponential ? "squared_exponential" : "matern52")
      .doc("Anisotropic GP kernel.");
  s.choice("calibration.sbalc.trend", trend_names())
      .default_value(trend_name(defaults.gp.trend))
      .doc("GP mean function; a quadratic suits a log-likelihood and is used once there are enough points.");

  s.string(initial_runs_key).default_value("")
      .doc("Results (.h5) or study file of a study of this model: its runs start the initial design.");

  const EmulatorCalibrationOptions emulator;
  s.section("calibration.emulator",
            "method: emulator, a GP per feature and Monte Carlo sampling of the posterior they imply "
            "(docs/CALIBRATION.md, 'Two routes').");
  s.integer("calibration.emulator.initial_points").default_value("0").range(Range::closed(0, 100000))
      .doc("Runs of the initial maximin Latin hypercube; 0: ten per parameter.");
  s.integer("calibration.emulator.batch_size").default_value(std::to_string(emulator.batch_size))
      .range(Range::closed(1, 10000))
      .doc("Runs chosen per iteration, run in parallel.");
  s.integer("calibration.emulator.max_evaluations").default_value(std::to_string(emulator.max_evaluations))
      .range(Range::closed(3, 1000000))
      .doc("Cap on runs, initial design and failures included.");
  s.number("calibration.emulator.influence_tolerance", "1", "1").default_value(shortest(emulator.influence_tolerance))
      .range(Range::open_closed(0, 100))
      .doc("Stop when the posterior without the emulators' variance differs by at most this many posterior sd "
           "(5/50/95 % quantiles) ...");
  s.number("calibration.emulator.quantile_tolerance", "1", "1").default_value(shortest(emulator.quantile_tolerance))
      .range(Range::open_closed(0, 100))
      .doc("... and no 5/50/95 % quantile moved by more posterior sd than this, twice in a row.");
  s.integer("calibration.emulator.pool_size").default_value(std::to_string(emulator.pool_size))
      .range(Range::closed(1000, 10000000))
      .doc("Importance samples of the posterior.");
  s.integer("calibration.emulator.particles").default_value(std::to_string(emulator.smc.n_particles))
      .range(Range::closed(100, 1000000))
      .doc("Particles of the tempered SMC sampler.");
  s.integer("calibration.emulator.seed").default_value(std::to_string(emulator.seed)).range(Range::closed(0, 1e9))
      .doc("Seed of the design, GP restarts and samplers.");
  s.choice("calibration.emulator.trend", trend_names())
      .default_value(trend_name(emulator.gp.trend))
      .doc("Mean function of each feature's GP.");
  s.number("calibration.emulator.warping_width", "1", "1").default_value(shortest(emulator.warping_width))
      .range(Range::closed(0, 1e6))
      .doc("GPs learn asinh((y - mean)/w), w in standard errors of the observed mean; 0: off.");
  s.integer("calibration.emulator.noise_pairs").default_value(std::to_string(emulator.noise_pairs))
      .range(Range::closed(0, 100000))
      .doc("Near-duplicates of the best runs; their differences bound each GP's nugget.");
  s.number("calibration.emulator.noise_pair_distance", "1", "1").default_value(shortest(emulator.noise_pair_distance))
      .range(Range{0.0, 0.5, false, false})
      .doc("Their distance in the unit cube.");
  s.list("calibration.emulator.log_products").items(0, 100).default_value("[]")
      .doc("Extra GP inputs: log10 of a product of parameters, scaled to [0, 1] (docs/CALIBRATION.md).");
  s.string("calibration.emulator.log_products[].name").default_value("").doc("Its name; required.");
  s.string("calibration.emulator.log_products[].parameters").default_value("")
      .doc("Parameters joined by '*'; positive bounded priors.");
  s.boolean("calibration.emulator.focus").default_value(emulator.focus ? "true" : "false")
      .doc("Second emulators of the plausible runs (docs/CALIBRATION.md, 'Two routes').");
  s.number("calibration.emulator.focus_cutoff", "1", "1").default_value(shortest(emulator.focus_cutoff))
      .range(Range::open_closed(0, 1000))
      .doc("Plausible point: every feature emulated within this many sd of the data.");
  s.number("calibration.emulator.focus_training_cutoff", "1", "1")
      .default_value(shortest(emulator.focus_training_cutoff))
      .range(Range::open_closed(0, 1000))
      .doc("Plausible run: every feature within this many standard errors; >= focus_cutoff.");
  s.integer("calibration.emulator.focus_min_runs").default_value(std::to_string(emulator.focus_min_runs))
      .range(Range::closed(0, 1000000))
      .doc("Plausible runs needed; 0: 2d + 3.");

  s.section("calibration.posterior", "Sampling-importance-resampling of the prior pool (Smith & Gelfand 1992).");
  s.integer("calibration.posterior.n_samples").default_value("4000").range(Range::closed(10, 10000000))
      .doc("Posterior draws written to <name>_posterior.csv.");
  s.number("calibration.posterior.credible_level", "1", "1").default_value("0.9")
      .range(Range{0.0, 1.0, false, false})
      .doc("Probability of the equal-tailed credible intervals.");
  s.integer("calibration.posterior.n_predictive").default_value("4").range(Range::closed(0, 1000))
      .doc("Posterior samples run through the forward model for predictive signals, besides the posterior mean.");
}

int initial_points(const CalibrationSettings& settings, std::size_t n_parameters) {
  if (settings.method == CalibrationMethod::sbalc) return settings.sbalc.n_initial;
  return settings.emulator.n_initial > 0 ? settings.emulator.n_initial : 10 * static_cast<int>(n_parameters);
}

int max_evaluations(const CalibrationSettings& settings) {
  return settings.method == CalibrationMethod::sbalc ? settings.sbalc.max_evaluations
                                                     : settings.emulator.max_evaluations;
}

CalibrationSettings read_calibration_settings(const Study& study) {
  const Config& c = study.config();
  const std::vector<std::string>& features = study.feature_names();
  CalibrationSettings settings;

  // Observations.
  const std::string features_file = c.text(observations_features_file);
  const int n_signal_files = c.n_items(observations_signal_files);
  if (!features_file.empty() && n_signal_files > 0) {
    c.fail(observations_features_file, "given together with " + std::string(observations_signal_files) + " (" +
                                           c.origin(observations_signal_files).where() +
                                           "); allowed: one of the two");
  }
  if (features_file.empty() && n_signal_files == 0) {
    throw fem::ConfigError(study.file().string() +
                           ": calibration.observations: missing; rsw calibrate needs "
                           "calibration.observations.features_file or calibration.observations.signal_files");
  }
  if (!features_file.empty()) {
    settings.observation_source = ObservationSource::features_file;
    settings.features_file = resolve(study, features_file);
  } else {
    settings.observation_source = ObservationSource::signal_files;
    for (int k = 0; k < n_signal_files; ++k) {
      const std::string path = fem::item_path(observations_signal_files, k, "file");
      if (c.text(path).empty()) {
        throw fem::ConfigError(c.origin(observations_signal_files).where() + ": " + path +
                               ": missing; each item names a signal file, e.g. {file: weld_1.csv}");
      }
      settings.signal_files.push_back(resolve(study, c.text(path)));
    }
  }

  // Noise model.
  const std::string kind = c.text(noise_kind);
  const std::map<std::string, double> given =
      read_feature_spreads(c, noise_standard_deviations, "value", features, true);
  if (kind == "standard_deviations") {
    for (const auto& feature : features) {
      if (!given.count(feature)) {
        const std::string where = c.is_default(noise_standard_deviations) ? c.origin(noise_kind).where()
                                                                          : c.origin(noise_standard_deviations).where();
        throw fem::ConfigError(where + ": " + noise_standard_deviations + ": no standard deviation of feature '" +
                               feature + "'; noise.kind standard_deviations needs one per feature of the study (" +
                               join_names(features) + ")");
      }
    }
    settings.noise = ObservationNoise::given(given);
  } else {
    if (!given.empty()) {
      c.fail(noise_standard_deviations, "only used with noise.kind: standard_deviations, not " + kind);
    }
    settings.noise = kind == "relative" ? ObservationNoise::relative(c.number("calibration.noise.fraction"))
                                        : ObservationNoise::replicate_scatter();
  }
  for (const auto& [feature, spread] :
       read_feature_spreads(c, noise_discrepancy, "standard_deviation", features, false)) {
    settings.discrepancy_variances[feature] = spread * spread;
  }

  // SBALC.
  SbalcOptions& sbalc = settings.sbalc;
  sbalc.pool_size = c.integer("calibration.sbalc.pool_size");
  sbalc.n_initial = c.integer("calibration.sbalc.initial_points");
  sbalc.batch_size = c.integer("calibration.sbalc.batch_size");
  sbalc.max_evaluations = c.integer("calibration.sbalc.max_evaluations");
  sbalc.tolerance = c.number("calibration.sbalc.tolerance");
  sbalc.seed = static_cast<std::uint64_t>(c.integer("calibration.sbalc.seed"));
  if (sbalc.n_initial > sbalc.max_evaluations) {
    c.fail("calibration.sbalc.initial_points",
           "more than calibration.sbalc.max_evaluations = " + c.display("calibration.sbalc.max_evaluations") +
               "; allowed: initial_points <= max_evaluations");
  }
  const std::string nugget = c.text("calibration.sbalc.nugget");
  sbalc.gp.nugget_mode = nugget == "off" ? NuggetMode::Off : nugget == "fixed" ? NuggetMode::Fixed : NuggetMode::Estimated;
  if (sbalc.gp.nugget_mode == NuggetMode::Fixed) {
    const double tau = c.number("calibration.sbalc.nugget_standard_deviation");
    sbalc.gp.fixed_noise_variance = tau * tau;
  }
  sbalc.failed_runs = c.text("calibration.sbalc.failed_runs") == "exclude" ? FailedRunPolicy::exclude
                                                                           : FailedRunPolicy::impute_minimum;
  sbalc.adaptive_pool = c.text("calibration.sbalc.pool") == "adaptive";
  sbalc.log_likelihood_range = c.number("calibration.sbalc.log_likelihood_range");
  sbalc.gp.kernel =
      c.text("calibration.sbalc.kernel") == "squared_exponential" ? KernelType::SquaredExponential : KernelType::Matern52;
  sbalc.gp.trend = trend_of(c.text("calibration.sbalc.trend"));

  // The emulator route.
  settings.method = c.text("calibration.method") == "emulator" ? CalibrationMethod::emulator : CalibrationMethod::sbalc;
  EmulatorCalibrationOptions& emulator = settings.emulator;
  emulator.n_initial = c.integer("calibration.emulator.initial_points");
  emulator.batch_size = c.integer("calibration.emulator.batch_size");
  emulator.max_evaluations = c.integer("calibration.emulator.max_evaluations");
  emulator.influence_tolerance = c.number("calibration.emulator.influence_tolerance");
  emulator.quantile_tolerance = c.number("calibration.emulator.quantile_tolerance");
  emulator.pool_size = c.integer("calibration.emulator.pool_size");
  emulator.smc.n_particles = c.integer("calibration.emulator.particles");
  emulator.seed = static_cast<std::uint64_t>(c.integer("calibration.emulator.seed"));
  emulator.warping_width = c.number("calibration.emulator.warping_width");
  emulator.noise_pairs = c.integer("calibration.emulator.noise_pairs");
  emulator.noise_pair_distance = c.number("calibration.emulator.noise_pair_distance");
  emulator.gp.trend = trend_of(c.text("calibration.emulator.trend"));
  const ParameterSpace& space = study.parameter_space();
  for (int k = 0; k < c.n_items("calibration.emulator.log_products"); ++k) {
    const std::string name_path = fem::item_path("calibration.emulator.log_products", k, "name");
    const std::string parameters_path = fem::item_path("calibration.emulator.log_products", k, "parameters");
    EmulatorCalibrationOptions::LogProduct product;
    product.name = c.text(name_path);
    if (!fem::is_plain_name(product.name)) c.fail(name_path, "a name is required (letters, digits and '_')");
    std::string text = c.text(parameters_path) + "*";
    for (std::size_t star = text.find('*'); star != std::string::npos; star = text.find('*')) {
      const std::string parameter = fem::trim(text.substr(0, star));
      text.erase(0, star + 1);
      std::size_t index = space.n_parameters();
      for (std::size_t i = 0; i < space.n_parameters(); ++i)
        if (space.parameter(i).name == parameter) index = i;
      std::string names;
      for (std::size_t i = 0; i < space.n_parameters(); ++i) names += (i ? ", " : "") + space.parameter(i).name;
      if (index == space.n_parameters())
        c.fail(parameters_path, "'" + parameter + "' is not a parameter of the study; allowed: " + names +
                                    ", joined by '*'");
      const Prior& prior = space.parameter(index).prior;
      if (!(prior.lower() > 0.0) || !std::isfinite(prior.upper()))
        c.fail(parameters_path, "'" + parameter + "' needs a prior bounded above and with a positive lower bound");
      product.parameters.push_back(index);
    }
    if (product.parameters.size() < 2) c.fail(parameters_path, "two or more parameters joined by '*'");
    emulator.log_products.push_back(product);
  }
  emulator.focus = c.boolean("calibration.emulator.focus");
  emulator.focus_cutoff = c.number("calibration.emulator.focus_cutoff");
  emulator.focus_training_cutoff = c.number("calibration.emulator.focus_training_cutoff");
  emulator.focus_min_runs = c.integer("calibration.emulator.focus_min_runs");
  if (emulator.focus_training_cutoff < emulator.focus_cutoff)
    c.fail("calibration.emulator.focus_training_cutoff",
           shortest(emulator.focus_training_cutoff) + " is below calibration.emulator.focus_cutoff (" +
               shortest(emulator.focus_cutoff) + "); allowed: at least focus_cutoff");
  if (settings.method == CalibrationMethod::emulator) {
    const int n_initial = initial_points(settings, study.parameter_space().n_parameters());
    if (n_initial >= emulator.max_evaluations) {
      c.fail("calibration.emulator.max_evaluations",
             "the initial design holds " + std::to_string(n_initial) +
                 " runs (calibration.emulator.initial_points; 0 means ten per parameter); allowed: more than " +
                 std::to_string(n_initial));
    }
  }

  // Posterior.
  settings.posterior.n_samples = c.integer("calibration.posterior.n_samples");
  settings.posterior.credible_level = c.number("calibration.posterior.credible_level");
  settings.posterior.seed = settings.method == CalibrationMethod::sbalc ? sbalc.seed : emulator.seed;
  settings.n_predictive_samples = c.integer("calibration.posterior.n_predictive");

  // Runs of an earlier study.
  if (const std::string text = c.text(initial_runs_key); !text.empty()) {
    const fs::path file = resolve(study, text);
    std::error_code error;
    if (!fs::is_regular_file(file, error)) {
      c.fail(initial_runs_key, "no such file (looked for " + file.string() +
                                   "); allowed: a study results file (.h5) or a study file, relative to the study "
                                   "file's folder");
    }
    if (file.extension() == ".h5") {
      settings.initial_runs = file;
    } else if (fs::equivalent(file, study.file(), error)) {
      settings.initial_runs = study.results_file();
    } else {
      try {
        settings.initial_runs = Study::load(file).results_file();
      } catch (const fem::ConfigError& e) {
        c.fail(initial_runs_key, std::string("not a study results file (.h5), nor a study file: ") + e.what());
      }
    }
    if (!fs::is_regular_file(settings.initial_runs, error)) {
      c.fail(initial_runs_key, "the study's results file " + settings.initial_runs.string() +
                                   " does not exist; run `rsw study run " + file.string() + "` first");
    }
  }
  return settings;
}

InitialRuns load_initial_runs(const Study& study, const CalibrationSettings& settings) {
  if (settings.initial_runs.empty()) return {};
  StudyDesign design;
  design.name = study.name();
  design.parameters = study.parameter_space();
  design.feature_names = study.feature_names();
  design.model = study.model_fingerprint();
  InitialRuns initial;
  try {
    initial = read_initial_runs(settings.initial_runs, design);
  } catch (const CalibrationError& e) {
    study.config().fail(initial_runs_key, e.what());
  }
  const std::size_t n_design = std::max(
      initial.runs.size(), static_cast<std::size_t>(initial_points(settings, study.parameter_space().n_parameters())));
  if (n_design >= static_cast<std::size_t>(max_evaluations(settings))) {
    fail_key(study,
             settings.method == CalibrationMethod::sbalc ? "calibration.sbalc.max_evaluations"
                                                         : "calibration.emulator.max_evaluations",
             "the initial design holds " + std::to_string(n_design) + " runs of " + settings.initial_runs.string() +
                 " (calibration.initial_runs), and the cap counts them; allowed: more than " +
                 std::to_string(n_design));
  }
  return initial;
}

Observations read_features_file(const fs::path& file, const std::vector<std::string>& feature_names) {
  std::ifstream in(file);
  if (!in) throw ObservationError(file.string() + ": cannot open the features file");
  const std::string name = file.string();

  struct Column {
    std::size_t field = 0;  // position in a row
    double scale = 1, offset = 0;  // SI = scale · value + offset
    std::string header;
  };
  std::vector<Column> columns;  // one per feature, in feature_names order
  std::size_t n_fields = 0;
  Observations observations;
  observations.feature_names = feature_names;
  std::vector<std::vector<double>> rows;

  fem::CsvReader reader(in);
  std::vector<std::string> fields;
  while (reader.next_or_throw<ObservationError>(fields, name)) {
    const std::size_t line_number = reader.line_number();
    const std::string where = name + ":" + std::to_string(line_number) + ": ";

    if (columns.empty()) {
      n_fields = fields.size();
      std::vector<std::string> names, units;
      for (std::size_t i = 0; i < fields.size(); ++i) {
        const std::string& field = fields[i];
        const auto open = field.find('[');
        const auto close = field.find(']');
        std::string column_name = trim(field.substr(0, open)), unit;
        if (open != std::string::npos) {
          if (close == std::string::npos || close < open || !trim(field.substr(close + 1)).empty()) {
            throw ObservationError(where + "column " + std::to_string(i + 1) + " ('" + field +
                                   "'): a header entry is 'name' or 'name [unit]', e.g. 'R_gamma [uohm]'");
          }
          unit = trim(field.substr(open + 1, close - open - 1));
        }
        if (column_name.empty()) {
          throw ObservationError(where + "column " + std::to_string(i + 1) + " ('" + field + "'): no feature name");
        }
        if (std::find(names.begin(), names.end(), column_name) != names.end()) {
          throw ObservationError(where + "column " + std::to_string(i + 1) + ": feature '" + column_name +
                                 "' appears twice");
        }
        names.push_back(column_name);
        units.push_back(unit);
      }
      for (const auto& feature : feature_names) {
        const auto found = std::find(names.begin(), names.end(), feature);
        if (found == names.end()) {
          throw ObservationError(where + "the header has no column for feature '" + feature + "' (columns: " +
                                 join_names(names) + "); allowed: a header with a column for every feature of the "
                                 "study: " + join_names(feature_names));
        }
        Column column;
        column.field = static_cast<std::size_t>(found - names.begin());
        column.header = fields[column.field];
        const std::string si = feature_unit(feature);
        const std::string unit = units[column.field].empty() ? si : units[column.field];
        const std::string label = "column " + std::to_string(column.field + 1) + " ('" + column.header + "')";
        if (!fem::is_known_unit(unit)) throw ObservationError(where + label + ": unknown unit '" + unit + "'");
        if (!fem::units_convertible(unit, si)) {
          throw ObservationError(where + label + ": unit '" + unit + "' measures " + fem::quantity_kind(unit) +
                                 ", but feature '" + feature + "' is in " + si + " (" + fem::quantity_kind(si) + ")");
        }
        column.offset = fem::convert_units(0.0, unit, si);
        column.scale = fem::convert_units(1.0, unit, si) - column.offset;
        columns.push_back(column);
      }
      continue;
    }

    if (fields.size() != n_fields) {
      throw ObservationError(where + "expected " + std::to_string(n_fields) +
                             " values separated by '" + std::string(1, reader.delimiter()) +
                             "' (one per header column), found " + std::to_string(fields.size()));
    }
    std::vector<double> row;
    for (const Column& column : columns) {
      double value = 0;
      if (!reader.parse_number(fields[column.field], value)) {
        throw ObservationError(where + "column " + std::to_string(column.field + 1) + " ('" + column.header + "'): '" +
                               fields[column.field] + "' is not a finite number");
      }
      row.push_back(column.scale * value + column.offset);
    }
    rows.push_back(std::move(row));
    observations.replicate_sources.push_back(name + ":" + std::to_string(line_number));
  }
  if (columns.empty()) throw ObservationError(name + ": no header line (feature names, e.g. 'R_gamma [uohm]')");
  if (rows.empty()) throw ObservationError(name + ": no observations below the header; allowed: one row per replicate");

  observations.values.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(feature_names.size()));
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (std::size_t j = 0; j < feature_names.size(); ++j)
      observations.values(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(j)) = rows[r][j];
  return observations;
}

Observations features_of_signal_files(const std::vector<fs::path>& files, const std::vector<std::string>& feature_names,
                                      const FeatureSettings& settings) {
  if (files.empty()) throw ObservationError("no signal files");
  Observations observations;
  observations.feature_names = feature_names;
  observations.values.resize(static_cast<Eigen::Index>(files.size()), static_cast<Eigen::Index>(feature_names.size()));
  for (std::size_t r = 0; r < files.size(); ++r) {
    const std::string name = files[r].string();
    FeatureValues values;
    try {
      if (!fs::is_regular_file(files[r])) throw SignalError("no such file");
      values = extract_features(read_signal_csv(name, observations.warnings), settings);
    } catch (const FeatureError& e) {
      throw ObservationError(name + ": " + e.what());
    } catch (const SignalError& e) {
      const std::string message = e.what();
      throw ObservationError(message.rfind(name, 0) == 0 ? message : name + ": " + message);
    }
    for (std::size_t j = 0; j < feature_names.size(); ++j) {
      if (!values.has(feature_names[j])) {
        throw ObservationError(name + ": the signals give no feature '" + feature_names[j] + "' (they give: " +
                               join_names(values.names()) + "); features that are not in the signals (nugget "
                               "geometry, say) need observations.features_file");
      }
      const std::string undefined = values.undefined_reason(feature_names[j]);
      if (!undefined.empty()) {
        throw ObservationError(name + ": feature '" + feature_names[j] + "' is undefined for this signal: " +
                               undefined + "; an observation needs every feature of the calibration");
      }
      observations.values(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(j)) = values.at(feature_names[j]);
    }
    observations.replicate_sources.push_back(name);
  }
  return observations;
}

Observations load_observations(const Study& study, const CalibrationSettings& settings) {
  const Config& c = study.config();
  // An error names the study key, where it was set and its value, then the file's own.
  const auto fail = [&c](const std::string& key, const ObservationError& e) {
    throw fem::ConfigError(c.origin(key).where() + ": " + key + " = " + c.display(key) + ": " + e.what());
  };
  if (settings.observation_source == ObservationSource::features_file) {
    try {
      return read_features_file(settings.features_file, study.feature_names());
    } catch (const ObservationError& e) {
      fail(observations_features_file, e);
    }
  }
  Observations observations;
  observations.feature_names = study.feature_names();
  observations.values.resize(static_cast<Eigen::Index>(settings.signal_files.size()),
                             static_cast<Eigen::Index>(observations.feature_names.size()));
  for (std::size_t k = 0; k < settings.signal_files.size(); ++k) {
    try {
      const Observations one = features_of_signal_files({settings.signal_files[k]}, study.feature_names());
      observations.values.row(static_cast<Eigen::Index>(k)) = one.values.row(0);
      observations.replicate_sources.push_back(one.replicate_sources[0]);
      observations.warnings.insert(observations.warnings.end(), one.warnings.begin(), one.warnings.end());
    } catch (const ObservationError& e) {
      fail(fem::item_path(observations_signal_files, static_cast<int>(k), "file"), e);
    }
  }
  return observations;
}

GaussianLikelihood make_likelihood(const Study& study, const CalibrationSettings& settings,
                                   const Observations& observations) {
  if (settings.noise.kind == ObservationNoise::Kind::ReplicateScatter && observations.values.rows() < 2) {
    fail_key(study, noise_kind, "replicate_scatter needs two or more replicates; the observations hold " +
                           std::to_string(observations.values.rows()) +
                           "; allowed: more replicates, or noise.kind standard_deviations or relative");
  }
  try {
    return GaussianLikelihood(observations.feature_names, observations.values, settings.noise,
                              settings.discrepancy_variances);
  } catch (const std::invalid_argument& e) {
    std::string message = e.what();
    const std::string prefix = "GaussianLikelihood: ";
    if (message.rfind(prefix, 0) == 0) message = message.substr(prefix.size());
    fail_key(study, noise_kind, message + " (the noise model gives it no spread; give noise standard deviations or a "
                                        "discrepancy for it)");
  }
}

}  // namespace rsw::calibration
