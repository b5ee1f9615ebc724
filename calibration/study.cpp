// Study files: the schema, the checks that span several keys (priors, nominal values,
// features, the model's case file or command), and the designs built from them; see
// study.hpp.
#include "calibration/study.hpp"

#include "calibration/calibration_study.hpp"
#include "calibration/command_model.hpp"
#include "calibration/designs.hpp"
#include "calibration/features.hpp"

#include "fem/units.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <utility>

#include <unistd.h>

namespace rsw::calibration {
namespace {

namespace fs = std::filesystem;
using fem::Config;
using fem::ConfigSchema;
using fem::Range;

const char* const intro = R"(A study runs a design of experiments through the forward
model (the weld, or a program: `model.command`): `rsw study run STUDY` evaluates every
point (in parallel, resumable, failures recorded), `rsw study sensitivity STUDY` fits
a sparse PCE per feature and writes Sobol indices, `rsw calibrate STUDY` calibrates
the parameters against the observations of the `calibration` section. See
docs/STUDIES.md for the workflow, MPI and array jobs.

Parameter values (bounds, mean, standard deviation, nominal) are quantities with a
unit, such as `1e-4 mm` or `35 W/(m*K)`; a bare number is read in the parameter's
`unit`, which is also the unit the forward model receives θ in.)";

const std::vector<std::string> prior_choices = {"uniform", "log10_uniform", "normal", "truncated_normal"};

ConfigSchema build_schema() {
  ConfigSchema s("Study configuration", intro);

  s.section("study", "Identity of the study and where its results go.");
  s.identifier("study.name").default_value("study")
      .doc("Name of the study; the results file is <output>/<name>.h5.");
  s.string("study.description").default_value("")
      .doc("Free text echoed into the results file.");
  s.string("study.output").default_value("results")
      .doc("Folder for the results file and tables, relative to the study file's folder (or absolute).");

  s.list("parameters").items(0, 64).default_value("[]")
      .doc("The varied parameters θ, in the order of the design's columns.");
  s.string("parameters[].name").default_value("")
      .doc("Name of the parameter (letters, digits, '_'), used in tables and plots; required.");
  s.string("parameters[].config_key").default_value("")
      .doc("Weld-case config key the value is written to, e.g. contact.sheet_sheet.film_thickness; required "
           "unless model.command.");
  s.string("parameters[].unit").default_value("1")
      .doc("Unit of θ handed to the forward model and of bare numbers below (the config key's internal unit, e.g. m).");
  s.choice("parameters[].prior", prior_choices).default_value("uniform")
      .doc("Prior distribution: uniform and log10_uniform need lower and upper; normal needs mean and "
           "standard_deviation; truncated_normal needs all four.");
  s.string("parameters[].lower").default_value("")
      .doc("Lower bound of the prior, a quantity such as '1e-4 mm' (log10_uniform: > 0).");
  s.string("parameters[].upper").default_value("")
      .doc("Upper bound of the prior, greater than lower.");
  s.string("parameters[].mean").default_value("")
      .doc("Mean of a normal or truncated_normal prior (before truncation).");
  s.string("parameters[].standard_deviation").default_value("")
      .doc("Standard deviation of a normal or truncated_normal prior (before truncation), > 0.");
  s.string("parameters[].nominal").default_value("")
      .doc("Value at the nominal point of one-at-a-time designs; empty: the prior median.");

  s.section("design", "The design of experiments, built in the unit cube and mapped through the priors.");
  s.choice("design.kind", {"lhs", "hammersley", "oat"}).default_value("lhs")
      .doc("lhs: Latin hypercube; hammersley: Hammersley point set; oat: one-at-a-time sweeps around the "
           "nominal point.");
  s.integer("design.n_points").default_value("90").range(Range::closed(2, 1000000))
      .doc("Number of runs of an lhs or hammersley design (paper §2.3: 90).");
  s.integer("design.seed").default_value("1").range(Range::closed(0, 1e9))
      .doc("Seed of the lhs design; the same seed gives the same design on every machine.");
  s.integer("design.maximin_swaps").default_value("0").range(Range::closed(0, 100000000))
      .doc("lhs: coordinate swaps tried to spread the points (Morris-Mitchell maximin); 0: none.");
  s.boolean("design.centred").default_value("false")
      .doc("lhs: put each point at the centre of its stratum instead of a random place in it.");
  s.integer("design.n_levels").default_value("5").range(Range::closed(2, 10000))
      .doc("oat: runs per parameter; with the nominal point the design has 1 + n_parameters * n_levels runs.");
  s.choice("design.oat_levels", {"centred", "endpoints"}).default_value("centred")
      .doc("oat: levels at the prior quantiles (k + 1/2)/n_levels (centred) or k/(n_levels - 1), which "
           "include the prior bounds (endpoints; bounded priors only).");

  s.list("features").items(0, 1000).default_value("[]")
      .doc("Features the forward model returns for each run (docs/STUDIES.md, 'The features'), in this order.");
  s.string("features[].name").default_value("")
      .doc("Feature name, e.g. R_beta, dS_P, T_max, d_n_liq; required.");

  s.section("model", "The forward model: the weld case every run starts from, or a command.");
  s.string("model.case").default_value("")
      .doc("Weld-case file, relative to the study file's folder (or absolute); must exist when given.");
  s.string("model.command").default_value("")
      .doc("Instead of a case: a program run per point, e.g. 'python3 model.py' (docs/STUDIES.md).");
  s.list("model.set").default_value("[]")
      .doc("Config overrides applied to the case for every run, before the parameters.");
  s.string("model.set[].key").default_value("")
      .doc("Weld-case config key, e.g. mesh.weld_zone.levels; required.");
  s.string("model.set[].value").default_value("")
      .doc("Its value as in the case file, e.g. '1' or '0.5 mm'; required.");

  s.section("sensitivity", "Sparse polynomial chaos expansion per feature (hybrid LARS, corrected LOO).");
  s.integer("sensitivity.min_degree").default_value("1").range(Range::closed(1, 30))
      .doc("Lowest total degree of the candidate bases.");
  s.integer("sensitivity.max_degree").default_value("5").range(Range::closed(1, 30))
      .doc("Highest total degree of the candidate bases (paper: 5); at least min_degree.");
  s.number("sensitivity.q_norm", "1", "1").default_value("1").range(Range::open_closed(0, 1))
      .doc("q of the hyperbolic truncation (sum alpha_i^q)^(1/q) <= degree; 1: total degree.");

  declare_calibration_keys(s);
  return s;
}

std::string join_names(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) text += (i ? ", " : "") + names[i];
  return text;
}

std::string with_article(const std::string& noun) {
  const bool vowel = !noun.empty() && std::string("aeiou").find(noun[0]) != std::string::npos;
  return (vowel ? "an " : "a ") + noun;
}

std::string short_number(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

// Where the item `list[index]` was written: the first of its keys given in the file.
std::string item_where(const Config& config, const std::string& list, int index,
                       const std::vector<std::string>& keys) {
  for (const auto& key : keys) {
    const std::string path = fem::item_path(list, index, key);
    if (config.contains(path) && !config.is_default(path)) return config.origin(path).where();
  }
  return config.origin(list).where();
}

[[noreturn]] void missing(const Config& config, const std::string& list, int index,
                          const std::vector<std::string>& located_by, const std::string& key,
                          const std::string& requirement) {
  throw fem::ConfigError(item_where(config, list, index, located_by) + ": " +
                         fem::item_path(list, index, key) + ": missing; " + requirement);
}

bool given(const Config& config, const std::string& path) { return !config.text(path).empty(); }

// A quantity key of a parameter, in the parameter's unit.
double read_quantity(const Config& config, const std::string& path, const std::string& unit) {
  const std::string text = config.text(path);
  const std::string expected = "a quantity in units of " + fem::quantity_kind(unit) + " such as '1 " +
                               (unit == "1" ? std::string() : unit) + "'" +
                               (unit == "1" ? "" : " (a bare number is read in " + unit + ")");
  fem::Quantity quantity;
  try {
    quantity = fem::split_quantity(text);
  } catch (const fem::UnitError&) {
    config.fail(path, "not a number; expected " + expected);
  }
  const std::string from = quantity.unit.empty() ? unit : quantity.unit;
  if (!fem::is_known_unit(from)) config.fail(path, "unknown unit '" + from + "'; expected " + expected);
  if (!fem::units_convertible(from, unit)) {
    config.fail(path, "is " + with_article(fem::quantity_kind(from)) + ", not " + with_article(fem::quantity_kind(unit)) +
                          " (the parameter's unit is " + unit + "); expected " + expected);
  }
  return fem::convert_units(quantity.value, from, unit);
}

struct ParameterEntry {
  Parameter parameter;
  bool has_nominal;
  double nominal;
};

// `command_model`: the study's model is a command, which needs no config keys (a
// parameter without one gets its name).
ParameterEntry read_parameter(const Config& config, int i, bool command_model) {
  const auto key = [i](const std::string& name) { return fem::item_path("parameters", i, name); };
  const std::vector<std::string> located_by = {"name", "config_key", "prior", "lower", "upper", "mean"};
  struct {
    std::string name, config_key, unit;
  } p;

  p.name = config.text(key("name"));
  if (p.name.empty()) missing(config, "parameters", i, located_by, "name", "every parameter needs a name");
  if (!fem::is_plain_name(p.name)) {
    config.fail(key("name"), "not a name; allowed: letters, digits and '_', not starting with a digit, at most " +
                                 std::to_string(fem::max_name_length) + " characters");
  }
  p.config_key = config.text(key("config_key"));
  if (p.config_key.empty() && command_model) p.config_key = p.name;
  if (p.config_key.empty()) {
    missing(config, "parameters", i, located_by, "config_key",
            "every parameter needs the weld-case key it sets, e.g. contact.sheet_sheet.film_thickness (a "
            "model.command needs none)");
  }
  if (!fem::is_key_path(p.config_key)) {
    config.fail(key("config_key"), "not a config key; allowed: names joined by '.', e.g. thermal.melt_conductivity");
  }
  p.unit = config.text(key("unit"));
  if (!fem::is_known_unit(p.unit)) {
    config.fail(key("unit"), "unknown unit; allowed: a UDUNITS-2 unit such as m, ohm*m, W/(m*K), or 1");
  }

  const std::string kind = config.text(key("prior"));
  const bool bounded = kind != "normal";
  const bool gaussian = kind == "normal" || kind == "truncated_normal";
  const std::string needs = kind == "uniform" || kind == "log10_uniform"
                                ? "a " + kind + " prior needs lower and upper"
                            : kind == "normal" ? "a normal prior needs mean and standard_deviation"
                                               : "a truncated_normal prior needs mean, standard_deviation, lower and upper";
  for (const char* bound : {"lower", "upper"}) {
    if (bounded && !given(config, key(bound))) missing(config, "parameters", i, located_by, bound, needs);
    if (!bounded && given(config, key(bound))) {
      config.fail(key(bound), "a normal prior has no bounds; use prior: truncated_normal for a bounded one");
    }
  }
  for (const char* moment : {"mean", "standard_deviation"}) {
    if (gaussian && !given(config, key(moment))) missing(config, "parameters", i, located_by, moment, needs);
    if (!gaussian && given(config, key(moment))) {
      config.fail(key(moment), "not used by a " + kind + " prior; only normal and truncated_normal priors take it");
    }
  }
  double lower = 0, upper = 0, mean = 0, standard_deviation = 0;
  if (bounded) {
    lower = read_quantity(config, key("lower"), p.unit);
    upper = read_quantity(config, key("upper"), p.unit);
    if (kind == "log10_uniform" && !(lower > 0)) {
      config.fail(key("lower"), "a log10_uniform prior needs 0 < lower < upper");
    }
    if (!(upper > lower)) {
      config.fail(key("upper"), "must be greater than lower = " + config.display(key("lower")) + " (" +
                                    short_number(lower) + " " + p.unit + "); allowed: upper > lower");
    }
  }
  if (gaussian) {
    mean = read_quantity(config, key("mean"), p.unit);
    standard_deviation = read_quantity(config, key("standard_deviation"), p.unit);
    if (!(standard_deviation > 0)) config.fail(key("standard_deviation"), "must be > 0");
  }
  const auto make_prior = [&]() {
    try {
      if (kind == "uniform") return Prior::uniform(lower, upper);
      if (kind == "log10_uniform") return Prior::log10_uniform(lower, upper);
      if (kind == "normal") return Prior::normal(mean, standard_deviation);
      return Prior::truncated_normal(mean, standard_deviation, lower, upper);
    } catch (const std::invalid_argument& e) {
      config.fail(key("prior"), e.what());
    }
  };
  ParameterEntry entry{Parameter{p.name, p.config_key, p.unit, make_prior()}, false, 0.0};

  if (given(config, key("nominal"))) {
    entry.has_nominal = true;
    entry.nominal = read_quantity(config, key("nominal"), p.unit);
    if (bounded && (entry.nominal < lower || entry.nominal > upper)) {
      config.fail(key("nominal"), "outside the prior; allowed: [" + config.display(key("lower")) + ", " +
                                      config.display(key("upper")) + "]");
    }
  }
  return entry;
}

}  // namespace

ConfigSchema study_schema() { return build_schema(); }

FeatureInfo describe_feature(const std::string& name) {
  namespace f = feature_name;
  static const std::map<std::string, std::string> units = {
      {f::resistance_alpha, "ohm"}, {f::resistance_beta, "ohm"}, {f::resistance_gamma, "ohm"},
      {f::time_alpha, "s"}, {f::time_beta, "s"}, {f::time_gamma, "s"},
      {f::slope_before_peak, "ohm/s"}, {f::slope_after_peak, "ohm/s"}, {f::resistance_mean, "ohm"},
      {f::resistance_rise, "ohm"}, {f::resistance_drop, "ohm"},
      {f::displacement_peak_expansion, "m"}, {f::displacement_end, "m"}, {f::displacement_net, "m"},
      {f::displacement_expansion_rate, "m/s"},
      {f::temperature_max, "degC"}, {f::time_temperature_max, "s"}, {f::temperature_end, "degC"},
      {f::cooling_rate, "K/s"},
      {f::nugget_diameter_liquidus, "m"}, {f::nugget_height_liquidus, "m"}, {f::nugget_diameter_solidus, "m"},
      {f::nugget_height_solidus, "m"}, {f::electrode_contact_width, "m"}, {f::indentation_depth, "m"},
      {f::unmolten_thickness, "m"}};
  const std::vector<std::pair<std::string, const std::vector<std::string>*>> groups = {
      {"resistance", &resistance_feature_names()},
      {"displacement", &displacement_feature_names()},
      {"temperature", &temperature_feature_names()},
      {"nugget", &nugget_feature_names()}};
  for (const auto& [group, names] : groups) {
    if (std::find(names->begin(), names->end(), name) != names->end()) {
      const auto unit = units.find(name);
      return {group, unit == units.end() ? "" : unit->second};
    }
  }
  return {"other", ""};
}

std::vector<std::string> known_feature_names() {
  std::vector<std::string> names;
  for (const auto* group : {&resistance_feature_names(), &displacement_feature_names(),
                            &temperature_feature_names(), &nugget_feature_names()}) {
    names.insert(names.end(), group->begin(), group->end());
  }
  return names;
}

Study Study::load(const fs::path& file, const std::vector<std::string>& overrides) {
  return Study(fem::load_config(study_schema(), file.string(), overrides), file);
}

Study::Study(Config config, fs::path file) : config_(std::move(config)), file_(std::move(file)) {
  const Config& c = config_;
  const fs::path folder = fs::absolute(file_).parent_path();
  name_ = c.text("study.name");

  // Parameters and priors.
  const int n_parameters = c.n_items("parameters");
  if (n_parameters == 0) {
    throw fem::ConfigError(file_.string() + ": parameters: missing; a study needs at least one parameter");
  }
  std::vector<ParameterEntry> entries;
  for (int i = 0; i < n_parameters; ++i) {
    entries.push_back(read_parameter(c, i, !c.text("model.command").empty()));
    for (int j = 0; j < i; ++j) {
      const auto& earlier = entries[static_cast<std::size_t>(j)].parameter;
      const auto& now = entries.back().parameter;
      if (now.name == earlier.name) {
        c.fail(fem::item_path("parameters", i, "name"),
               "given twice (also parameters[" + std::to_string(j) + "]); parameter names must be unique");
      }
      if (now.config_key == earlier.config_key) {
        c.fail(fem::item_path("parameters", i, "config_key"),
               "set twice (also by parameters[" + std::to_string(j) + "], '" + earlier.name +
                   "'); each parameter sets its own key");
      }
    }
  }
  nominal_.resize(n_parameters);
  for (int i = 0; i < n_parameters; ++i) {
    const ParameterEntry& entry = entries[static_cast<std::size_t>(i)];
    parameters_.add(entry.parameter);
    nominal_[i] = entry.has_nominal ? entry.nominal : entry.parameter.prior.quantile(0.5);
  }

  // Features.
  const int n_features = c.n_items("features");
  if (n_features == 0) {
    throw fem::ConfigError(file_.string() + ": features: missing; a study needs at least one feature, e.g. "
                           "features: [{name: R_beta}]");
  }
  for (int k = 0; k < n_features; ++k) {
    const std::string path = fem::item_path("features", k, "name");
    const std::string name = c.text(path);
    if (name.empty()) missing(c, "features", k, {"name"}, "name", "every feature item needs a name, e.g. {name: R_beta}");
    if (!fem::is_plain_name(name)) {
      c.fail(path, "not a feature name; allowed: letters, digits and '_', e.g. " + join_names(known_feature_names()));
    }
    if (std::find(features_.begin(), features_.end(), name) != features_.end()) {
      c.fail(path, "listed twice; each feature once");
    }
    features_.push_back(name);
  }

  // Design.
  const std::string kind = c.text("design.kind");
  design_.kind = kind == "lhs" ? DesignKind::lhs : kind == "hammersley" ? DesignKind::hammersley : DesignKind::oat;
  design_.n_points = static_cast<std::size_t>(c.integer("design.n_points"));
  design_.seed = static_cast<std::uint64_t>(c.integer("design.seed"));
  design_.maximin_swaps = static_cast<std::size_t>(c.integer("design.maximin_swaps"));
  design_.centred = c.boolean("design.centred");
  design_.n_levels = static_cast<std::size_t>(c.integer("design.n_levels"));
  if (design_.kind == DesignKind::oat && c.text("design.oat_levels") == "endpoints") {
    for (int i = 0; i < n_parameters; ++i) {
      if (parameters_.parameter(static_cast<std::size_t>(i)).prior.kind() == PriorKind::normal) {
        c.fail("design.oat_levels", "parameter '" + parameters_.parameter(static_cast<std::size_t>(i)).name +
                                        "' has an unbounded normal prior; use centred levels");
      }
    }
  }

  // Forward model.
  const std::string case_text = c.text("model.case");
  const std::string command_text = c.text("model.command");
  if (!command_text.empty()) {
    if (!case_text.empty()) {
      c.fail("model.command", "given together with model.case (" + c.origin("model.case").where() +
                                  "); allowed: one of the two, a weld case or a command");
    }
    if (c.n_items("model.set") > 0) {
      c.fail("model.command", "given together with model.set (" + c.origin("model.set").where() +
                                  "), which overrides keys of a weld case; a command takes none");
    }
    model_kind_ = ModelKind::command;
    try {
      command_words_ = split_command_line(command_text);
    } catch (const std::invalid_argument& e) {
      c.fail("model.command", std::string(e.what()).substr(command_text.size() + 4));
    }
    for (std::size_t k = 0; k < command_words_.size(); ++k) {
      const fs::path word(command_words_[k]);
      const fs::path here = word.is_absolute() ? word : (folder / word).lexically_normal();
      std::error_code error;
      const bool exists = !command_words_[k].empty() && fs::exists(here, error);
      const bool names_path = k == 0 ? (exists || command_words_[k].find('/') != std::string::npos) : exists;
      command_.push_back(names_path && !word.is_absolute() ? here.string() : command_words_[k]);
      if (exists && !word.is_absolute() && fs::is_regular_file(here, error)) command_files_.push_back(k);
      if (k > 0 || !names_path) continue;  // a bare program name: looked up on PATH by the caller
      const std::string allowed = "; allowed: an executable file (relative to the study file's folder, or "
                                  "absolute), or a program on PATH, then its arguments, e.g. 'python3 model.py'";
      if (!exists) c.fail("model.command", "no program " + here.string() + allowed);
      if (!fs::is_regular_file(here, error) || ::access(here.c_str(), X_OK) != 0) {
        c.fail("model.command", "the program " + here.string() + " is not an executable file (chmod +x, or name "
                                "its interpreter first, e.g. 'python3 " + command_words_[0] + "')" + allowed);
      }
    }
  }
  if (!case_text.empty()) {
    const fs::path given_path(case_text);
    case_file_ = given_path.is_absolute() ? given_path : (folder / given_path).lexically_normal();
    if (!fs::is_regular_file(case_file_)) {
      c.fail("model.case", "no such file (looked for " + case_file_.string() +
                               "); allowed: a weld-case file, relative to the study file's folder");
    }
  }
  for (int k = 0; k < c.n_items("model.set"); ++k) {
    const std::string key_path = fem::item_path("model.set", k, "key");
    const std::string value_path = fem::item_path("model.set", k, "value");
    const std::string key = c.text(key_path);
    if (key.empty()) missing(c, "model.set", k, {"value"}, "key", "each override needs a key and a value");
    if (!fem::is_key_path(key)) c.fail(key_path, "not a config key; allowed: names joined by '.'");
    if (c.text(value_path).empty()) missing(c, "model.set", k, {"key"}, "value", "each override needs a value");
    for (std::size_t i = 0; i < parameters_.n_parameters(); ++i) {
      if (parameters_.parameter(i).config_key == key) {
        c.fail(key_path, "is set by parameter '" + parameters_.parameter(i).name +
                             "' in every run; an override would be overwritten");
      }
    }
    model_overrides_.push_back(key + "=" + c.text(value_path));
  }

  // Output and sensitivity.
  const fs::path output(c.text("study.output"));
  output_folder_ = output.is_absolute() ? output : (folder / output).lexically_normal();
  pce_options_.min_degree = c.integer("sensitivity.min_degree");
  pce_options_.max_degree = c.integer("sensitivity.max_degree");
  pce_options_.q_norm = c.number("sensitivity.q_norm");
  if (pce_options_.max_degree < pce_options_.min_degree) {
    c.fail("sensitivity.max_degree", "must be at least sensitivity.min_degree = " + c.display("sensitivity.min_degree"));
  }
}

void Study::set_output_folder(const fs::path& folder) { output_folder_ = fs::absolute(folder).lexically_normal(); }

fs::path Study::results_file() const { return output_folder_ / (name_ + ".h5"); }

namespace {

// "fnv1a64:<16 hex digits>" of a file's bytes: FNV-1a, 64 bit (Fowler, Noll, Vo), enough
// to notice an edited case file or script. `key` names the study key for a read error.
std::string file_hash(const Config& config, const std::string& key, const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) config.fail(key, "cannot be read (" + file.string() + ")");
  std::uint64_t hash = 14695981039346656037ull;
  char c;
  while (in.get(c)) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  std::ostringstream text;
  text << "fnv1a64:" << std::hex << std::setw(16) << std::setfill('0') << hash;
  return text.str();
}

}  // namespace

std::string Study::model_fingerprint() const {
  std::ostringstream text;
  if (model_kind_ == ModelKind::command) {
    text << "command";
    for (const auto& word : command_words_) text << " " << word;
    for (std::size_t k = 0; k < command_files_.size(); ++k) {
      const std::size_t word = command_files_[k];
      text << (k ? ", " : "; ") << command_words_[word] << " "
           << file_hash(config_, "model.command", command_[word]);
    }
    return text.str();
  }
  text << "case ";
  if (case_file_.empty()) {
    text << "none";
  } else {
    text << file_hash(config_, "model.case", case_file_);
  }
  text << "; set";
  if (model_overrides_.empty()) text << " nothing";
  for (std::size_t k = 0; k < model_overrides_.size(); ++k) text << (k ? ", " : " ") << model_overrides_[k];
  return text.str();
}

void Study::check_model_inputs(const ForwardModel& model, const Eigen::MatrixXd& points) const {
  const std::size_t d = parameters_.n_parameters();
  auto describe = [&](const Eigen::VectorXd& theta) {
    std::ostringstream text;
    text.precision(6);
    for (std::size_t i = 0; i < d; ++i)
      text << (i ? ", " : "") << parameters_.parameter(i).name << " = " << theta[static_cast<Eigen::Index>(i)];
    return text.str();
  };
  auto check = [&](const Eigen::VectorXd& theta, const std::string& where) {
    try {
      model.check_input(theta);
    } catch (const std::exception& e) {
      throw fem::ConfigError(file_.string() + ": study '" + name_ + "': the model does not take " + where + " (" + describe(theta) +
                             "): " + e.what() + "; nothing was run");
    }
  };
  // Each parameter at the ends of its prior (the 1e-6 and 1 - 1e-6 quantiles, the bounds
  // of a bounded prior to within that), the others at their medians.
  Eigen::VectorXd median(static_cast<Eigen::Index>(d));
  for (std::size_t i = 0; i < d; ++i) median[static_cast<Eigen::Index>(i)] = parameters_.parameter(i).prior.quantile(0.5);
  check(median, "the prior's medians");
  for (std::size_t i = 0; i < d; ++i) {
    for (const double u : {1e-6, 1 - 1e-6}) {
      Eigen::VectorXd theta = median;
      theta[static_cast<Eigen::Index>(i)] = parameters_.parameter(i).prior.quantile(u);
      check(theta, parameters_.parameter(i).name + (u < 0.5 ? " at its prior's lower end" : " at its prior's upper end"));
    }
  }
  for (Eigen::Index r = 0; r < points.rows(); ++r) check(points.row(r).transpose(), "design point " + std::to_string(r));
}

StudyDesign Study::design() const {
  StudyDesign design;
  design.model = model_fingerprint();
  design.name = name_;
  design.parameters = parameters_;
  design.feature_names = features_;
  for (const auto& name : features_) design.feature_info.push_back(describe_feature(name));
  design.description = config_.to_yaml();
  const std::size_t d = parameters_.n_parameters();
  switch (design_.kind) {
    case DesignKind::lhs: {
      design.kind = "lhs";
      LatinHypercubeOptions options;
      options.centred = design_.centred;
      options.n_maximin_swaps = design_.maximin_swaps;
      const Eigen::MatrixXd unit = latin_hypercube(design_.n_points, d, design_.seed, options);
      design.points = parameters_.points_to_physical(parameters_.unit_points_to_standard(unit));
      break;
    }
    case DesignKind::hammersley: {
      design.kind = "hammersley";
      const Eigen::MatrixXd unit = hammersley(design_.n_points, d);
      design.points = parameters_.points_to_physical(parameters_.unit_points_to_standard(unit));
      break;
    }
    case DesignKind::oat: {
      design.kind = "oat";
      const bool endpoints = config_.text("design.oat_levels") == "endpoints";
      const auto n = static_cast<Eigen::Index>(design_.n_levels);
      Eigen::VectorXd unit_levels = centred_levels(design_.n_levels);
      if (endpoints) unit_levels = Eigen::VectorXd::LinSpaced(n, 0.0, 1.0);
      std::vector<std::size_t> dimensions;
      std::vector<Eigen::VectorXd> levels;
      for (std::size_t i = 0; i < d; ++i) {
        Eigen::VectorXd physical(n);
        for (Eigen::Index k = 0; k < n; ++k) physical[k] = parameters_.parameter(i).prior.quantile(unit_levels[k]);
        dimensions.push_back(i);
        levels.push_back(physical);
      }
      const OneAtATimeDesign sweeps = one_at_a_time(nominal_, dimensions, levels);
      design.points.resize(sweeps.points.rows() + 1, static_cast<Eigen::Index>(d));
      design.points.row(0) = nominal_.transpose();
      design.points.bottomRows(sweeps.points.rows()) = sweeps.points;
      design.swept_parameter.push_back(-1);
      for (const auto dimension : sweeps.swept_dimension) design.swept_parameter.push_back(static_cast<int>(dimension));
      break;
    }
  }
  return design;
}

}  // namespace rsw::calibration
