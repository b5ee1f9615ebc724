// Schema declaration, YAML loading, overrides, typed access and exports of
// configuration trees (see config.hpp). The only file that includes yaml-cpp.
//
// Loading works on a copy of the values and swaps it in at the end, so a Config
// that rejected a file or an override still holds its previous, valid values.
#include "fem/config.hpp"
#include "fem/text.hpp"

#include "fem/units.hpp"

#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <utility>

namespace rsw::fem {
namespace {


bool starts_with(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

std::string join_path(const std::string& scope, const std::string& name) {
  return scope.empty() ? name : scope + "." + name;
}

std::string join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string result;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (i > 0) result += separator;
    result += parts[i];
  }
  return result;
}

std::string quoted_list(const std::vector<std::string>& parts) {
  std::vector<std::string> quoted;
  for (const auto& part : parts) quoted.push_back("'" + part + "'");
  return join(quoted, ", ");
}

// "stack.sheets[1].thickness" -> "stack.sheets[].thickness".
std::string schema_path_of(const std::string& concrete) {
  std::string result;
  for (std::size_t i = 0; i < concrete.size(); ++i) {
    result += concrete[i];
    if (concrete[i] == '[') {
      while (i + 1 < concrete.size() && concrete[i + 1] != ']') ++i;
    }
  }
  return result;
}

// A typo is "near" when at most about a third of the name differs.
bool is_near(const std::string& typed, const std::string& candidate) {
  const std::size_t allowed = std::clamp<std::size_t>(typed.size() / 3, 1, 3);
  return edit_distance(typed, candidate) <= allowed;
}

std::string closest(const std::string& typed, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::string::npos;
  for (const auto& candidate : candidates) {
    const std::size_t d = edit_distance(typed, candidate);
    if (d < best_distance && is_near(typed, candidate)) {
      best = candidate;
      best_distance = d;
    }
  }
  return best;
}

// "1e-05" -> "1e-5", "1e+07" -> "1e7".
std::string tidy_exponent(const std::string& text) {
  const auto e = text.find('e');
  if (e == std::string::npos) return text;
  std::string exponent = text.substr(e + 1);
  std::string sign;
  if (!exponent.empty() && (exponent[0] == '+' || exponent[0] == '-')) {
    if (exponent[0] == '-') sign = "-";
    exponent.erase(0, 1);
  }
  exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
  return text.substr(0, e) + "e" + sign + exponent;
}

// Shortest of 15..17 significant digits for which `reads_back(parsed)` holds. 15
// digits hide conversion noise (15.8 mm, not 15.799999999999999 mm); more are used
// only when needed for an exact round trip.
template <class ReadsBack>
std::string format_number(double value, ReadsBack reads_back) {
  std::string text;
  for (int precision = 15; precision <= 17; ++precision) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.*g", precision, value);
    text = buffer;
    if (reads_back(std::strtod(buffer, nullptr))) break;
  }
  return tidy_exponent(text);
}

std::string format_number(double value) {
  return format_number(value, [value](double back) { return back == value; });
}

// Six significant digits, for messages ("28.6479 deg").
std::string format_short(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

std::string with_unit(const std::string& number, const std::string& unit) {
  return unit == "1" ? number : number + " " + unit;
}

// A value in internal units, written in display units so that it reads back exactly.
std::string format_display(double internal, const std::string& unit,
                           const std::string& display_unit) {
  const double shown = convert_units(internal, unit, display_unit);
  const auto reads_back = [&](double back) {
    return convert_units(back, display_unit, unit) == internal;
  };
  return with_unit(format_number(shown, reads_back), display_unit);
}

std::string with_article(const std::string& noun) {
  const char c = noun.empty() ? 'x' : noun[0];
  const bool vowel = c == 'a' || c == 'e' || c == 'i' || c == 'o' || c == 'u';
  return (vowel ? "an " : "a ") + noun;
}

std::string count_phrase(int min_items, int max_items, const std::string& noun) {
  const std::string nouns = noun + "s";
  if (min_items == max_items) {
    return "exactly " + std::to_string(min_items) + " " + (min_items == 1 ? noun : nouns);
  }
  if (max_items == INT_MAX) {
    return min_items == 0 ? "any number of " + nouns
                          : "at least " + std::to_string(min_items) + " " +
                                (min_items == 1 ? noun : nouns);
  }
  if (min_items == 0) return "up to " + std::to_string(max_items) + " " + nouns;
  return std::to_string(min_items) + " to " + std::to_string(max_items) + " " + nouns;
}

std::string describe_node(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined:
      return "nothing";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
  }
  return "an unreadable value";
}

// "case.yaml:3:7" from a yaml-cpp mark (0-based), or just the source without one.
std::string yaml_where(const std::string& source, const YAML::Mark& mark) {
  if (mark.is_null()) return source;
  return source + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

// One "name" or "name[index]" step of a key path.
struct PathStep {
  std::string name;
  int index = -1;
};

// Character classes of user text, checked by loops: std::regex recurses once per
// character and overflows the stack on inputs of some ten thousand characters.
bool is_name_character(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

std::optional<std::vector<PathStep>> parse_path(const std::string& path) {
  std::vector<PathStep> steps;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    const std::string text =
        path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    // name, or name[index] with one to six digits
    const std::size_t bracket = text.find('[');
    const std::string name = text.substr(0, bracket);
    if (name.empty() || !std::all_of(name.begin(), name.end(), is_name_character)) return std::nullopt;
    PathStep step;
    step.name = name;
    if (bracket != std::string::npos) {
      const std::string index = text.substr(bracket + 1);
      if (index.size() < 2 || index.size() > 7 || index.back() != ']' ||
          !std::all_of(index.begin(), index.end() - 1, is_digit))
        return std::nullopt;
      step.index = std::stoi(index.substr(0, index.size() - 1));
    }
    steps.push_back(step);
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return steps;
}

std::string kind_word(const KeySpec& spec) {
  switch (spec.kind) {
    case KeyKind::number:
      return quantity_kind(spec.unit);
    case KeyKind::string:
      return "text";
    default:
      return kind_name(spec.kind);
  }
}

// A number with its units and range: a number key or one table column.
struct NumberRule {
  std::string unit;
  std::string display_unit;
  Range range;
  std::string example;
};

std::string number_example(const std::string& default_text, const std::string& display_unit) {
  try {
    const Quantity q = split_quantity(default_text);
    return q.unit.empty() ? with_unit(trim(default_text), display_unit) : trim(default_text);
  } catch (const UnitError&) {
    return with_unit("1", display_unit);
  }
}

std::string expect_number(const NumberRule& rule) {
  const std::string kind = quantity_kind(rule.unit);
  std::string text = with_article(kind) + " such as '" + rule.example + "'";
  if (rule.display_unit != "1") text += " (a bare number is read in " + rule.display_unit + ")";
  return text;
}

std::string expectation(const ConfigSchema& schema, const KeySpec& spec) {
  switch (spec.kind) {
    case KeyKind::number:
      return expect_number({spec.unit, spec.display_unit, spec.range,
                            number_example(spec.default_value, spec.display_unit)});
    case KeyKind::integer:
      return "an integer such as '" + spec.default_value + "'";
    case KeyKind::boolean:
      return "true or false";
    case KeyKind::string:
      return "a text";
    case KeyKind::identifier:
      return "a name made of letters, digits, '_' and '-', such as '" + spec.default_value +
             "'";
    case KeyKind::choice:
      return "one of " + quoted_list(spec.choices);
    case KeyKind::table: {
      std::vector<std::string> names;
      for (const auto& column : spec.columns) names.push_back(column.name);
      return "a table: a list of rows [" + join(names, ", ") + "] such as " +
             spec.default_value;
    }
    case KeyKind::list:
      return "a list of items, each a map with keys " +
             join(schema.children(spec.path + "[]"), ", ");
  }
  return "";
}

// Range limits as declared: 0.25, 200, 1e7, 1e-5 (exponent form outside [1e-3, 1e5)).
std::string range_bound(double value) {
  const double magnitude = std::abs(value);
  if (magnitude == 0 || (magnitude >= 1e-3 && magnitude < 1e5)) return format_number(value);
  for (int digits = 0; digits < 17; ++digits) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.*e", digits, value);
    if (std::strtod(buffer, nullptr) == value) return tidy_exponent(buffer);
  }
  return format_number(value);
}

}  // namespace

bool is_plain_name(const std::string& text) {
  return !text.empty() && text.size() <= max_name_length && !is_digit(text[0]) &&
         std::all_of(text.begin(), text.end(), is_name_character);
}

bool is_key_path(const std::string& text) { return parse_path(text).has_value(); }

// ---------------------------------------------------------------------------------
// Ranges, declarations and the schema

const char* kind_name(KeyKind kind) {
  switch (kind) {
    case KeyKind::number:
      return "number";
    case KeyKind::integer:
      return "integer";
    case KeyKind::boolean:
      return "boolean";
    case KeyKind::string:
      return "string";
    case KeyKind::identifier:
      return "identifier";
    case KeyKind::choice:
      return "choice";
    case KeyKind::table:
      return "table";
    case KeyKind::list:
      return "list";
  }
  return "unknown";
}

bool Range::is_any() const { return std::isinf(min) && std::isinf(max); }

bool Range::contains(double value) const {
  // Inclusive bounds forgive a relative 1e-12: "0.5 cm" against a bound of 5 mm must
  // not fail on the last bit of a unit conversion.
  const auto slack = [value](double bound) {
    return 1e-12 * std::max(std::abs(bound), std::abs(value));
  };
  if (!std::isinf(min)) {
    if (min_inclusive ? value < min - slack(min) : value <= min) return false;
  }
  if (!std::isinf(max)) {
    if (max_inclusive ? value > max + slack(max) : value >= max) return false;
  }
  return !std::isnan(value);
}

std::string Range::describe(const std::string& unit) const {
  std::string text;
  if (is_any()) return "any value";
  if (!std::isinf(min) && !std::isinf(max)) {
    text = std::string(min_inclusive ? "[" : "(") + range_bound(min) + ", " +
           range_bound(max) + (max_inclusive ? "]" : ")");
  } else if (!std::isinf(min)) {
    text = std::string(min_inclusive ? ">= " : "> ") + range_bound(min);
  } else {
    text = std::string(max_inclusive ? "<= " : "< ") + range_bound(max);
  }
  return unit == "1" ? text : text + " " + unit;
}

KeyDeclaration& KeyDeclaration::default_value(const std::string& text) {
  spec_.default_value = text;
  return *this;
}

KeyDeclaration& KeyDeclaration::range(const Range& range) {
  spec_.range = range;
  return *this;
}

KeyDeclaration& KeyDeclaration::items(int min_items, int max_items) {
  spec_.min_items = min_items;
  spec_.max_items = max_items;
  return *this;
}

KeyDeclaration& KeyDeclaration::column(const std::string& name, const std::string& unit,
                                       const std::string& display_unit, const Range& range) {
  spec_.columns.push_back({name, unit, display_unit, range});
  return *this;
}

KeyDeclaration& KeyDeclaration::increasing() {
  spec_.increasing = true;
  return *this;
}

KeyDeclaration& KeyDeclaration::doc(const std::string& text) {
  spec_.doc = text;
  return *this;
}

ConfigSchema::ConfigSchema(std::string title, std::string intro)
    : title_(std::move(title)), intro_(std::move(intro)) {}

KeyDeclaration ConfigSchema::declare(const std::string& path, KeyKind kind) {
  static const std::regex path_pattern(R"([a-z][a-z0-9_]*(\[\])?(\.[a-z][a-z0-9_]*(\[\])?)*)");
  if (!std::regex_match(path, path_pattern) ||
      (path.size() >= 2 && path.compare(path.size() - 2, 2, "[]") == 0)) {
    throw std::logic_error("config schema: '" + path +
                           "' is not a key path (snake_case names joined by '.', list "
                           "items as name[].key)");
  }
  if (find(path) != nullptr) {
    throw std::logic_error("config schema: '" + path + "' is declared twice");
  }
  if (is_section(path)) {
    throw std::logic_error("config schema: '" + path + "' is already a section of other keys");
  }
  // Every "a.b[]" on the way must be a declared list; no other prefix may be a key.
  for (std::size_t dot = path.find('.'); dot != std::string::npos;
       dot = path.find('.', dot + 1)) {
    const std::string prefix = path.substr(0, dot);
    const bool list_scope = prefix.size() > 2 && prefix.compare(prefix.size() - 2, 2, "[]") == 0;
    const std::string owner = list_scope ? prefix.substr(0, prefix.size() - 2) : prefix;
    const KeySpec* spec = find(owner);
    if (list_scope && (spec == nullptr || spec->kind != KeyKind::list)) {
      throw std::logic_error("config schema: '" + path + "' needs the list '" + owner +
                             "' declared first");
    }
    if (!list_scope && spec != nullptr) {
      throw std::logic_error("config schema: '" + path + "' lies below the key '" + owner +
                             "'");
    }
  }
  KeySpec spec;
  spec.path = path;
  spec.kind = kind;
  keys_.push_back(spec);
  return KeyDeclaration(keys_.back());
}

KeyDeclaration ConfigSchema::number(const std::string& path, const std::string& unit,
                                    const std::string& display_unit) {
  KeyDeclaration declaration = declare(path, KeyKind::number);
  keys_.back().unit = unit;
  keys_.back().display_unit = display_unit;
  return declaration;
}

KeyDeclaration ConfigSchema::integer(const std::string& path) {
  return declare(path, KeyKind::integer);
}

KeyDeclaration ConfigSchema::boolean(const std::string& path) {
  return declare(path, KeyKind::boolean);
}

KeyDeclaration ConfigSchema::string(const std::string& path) {
  return declare(path, KeyKind::string);
}

KeyDeclaration ConfigSchema::identifier(const std::string& path) {
  return declare(path, KeyKind::identifier);
}

KeyDeclaration ConfigSchema::choice(const std::string& path,
                                    const std::vector<std::string>& choices) {
  KeyDeclaration declaration = declare(path, KeyKind::choice);
  keys_.back().choices = choices;
  return declaration;
}

KeyDeclaration ConfigSchema::table(const std::string& path) {
  KeyDeclaration declaration = declare(path, KeyKind::table);
  keys_.back().min_items = 1;
  return declaration;
}

KeyDeclaration ConfigSchema::list(const std::string& path) {
  KeyDeclaration declaration = declare(path, KeyKind::list);
  keys_.back().default_value = "[]";
  return declaration;
}

void ConfigSchema::section(const std::string& path, const std::string& doc) {
  for (auto& [known, text] : section_docs_) {
    if (known == path) {
      text = doc;
      return;
    }
  }
  section_docs_.emplace_back(path, doc);
}

const KeySpec* ConfigSchema::find(const std::string& schema_path) const {
  for (const auto& spec : keys_) {
    if (spec.path == schema_path) return &spec;
  }
  return nullptr;
}

bool ConfigSchema::is_section(const std::string& schema_path) const {
  if (schema_path.empty()) return true;
  if (find(schema_path) != nullptr) return false;
  const std::string prefix = schema_path + ".";
  for (const auto& spec : keys_) {
    if (starts_with(spec.path, prefix)) return true;
  }
  return false;
}

std::vector<std::string> ConfigSchema::children(const std::string& scope) const {
  const std::string prefix = scope.empty() ? "" : scope + ".";
  std::vector<std::string> names;
  for (const auto& spec : keys_) {
    if (!starts_with(spec.path, prefix)) continue;
    const std::string rest = spec.path.substr(prefix.size());
    const std::string name = rest.substr(0, rest.find_first_of(".["));
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  return names;
}

void ConfigSchema::validate() const {
  for (const auto& spec : keys_) {
    const auto broken = [&spec](const std::string& what) {
      throw std::logic_error("config schema: key '" + spec.path + "': " + what);
    };
    if (trim(spec.doc).empty()) broken("has no doc");
    if (spec.doc.find('\n') != std::string::npos) broken("doc must be one line");
    if (spec.min_items < 0 || spec.min_items > spec.max_items) broken("bad item limits");
    const auto check_units = [&broken](const std::string& unit, const std::string& display,
                                       const Range& range) {
      if (!is_known_unit(unit)) broken("unknown unit '" + unit + "'");
      if (!units_convertible(display, unit)) {
        broken("display unit '" + display + "' does not convert to '" + unit + "'");
      }
      if (range.min > range.max) broken("empty range");
    };
    switch (spec.kind) {
      case KeyKind::number:
        check_units(spec.unit, spec.display_unit, spec.range);
        break;
      case KeyKind::integer:
        if (spec.range.min > spec.range.max) broken("empty range");
        break;
      case KeyKind::choice:
        if (spec.choices.empty()) broken("no choices");
        break;
      case KeyKind::table:
        if (spec.columns.empty()) broken("table without columns");
        for (const auto& column : spec.columns) {
          check_units(column.unit, column.display_unit, column.range);
        }
        break;
      default:
        break;
    }
  }
}

// ---------------------------------------------------------------------------------
// Markdown and JSON references

std::string ConfigSchema::to_markdown() const {
  const auto cell = [](std::string text) {
    std::string result;
    for (char c : text) {
      if (c == '|') result += "\\|";
      else result += c;
    }
    return result;
  };
  const auto code = [](const std::string& text) { return "`" + text + "`"; };

  std::ostringstream md;
  md << "# " << title_ << "\n\n";
  if (!trim(intro_).empty()) md << trim(intro_) << "\n\n";
  md << R"(## File format

- A file is YAML. Sections are maps of keys; every key is optional and takes its
  default when left out. An unknown key is an error that names the closest
  declared key.
- Numbers carry units: `1.0 mm`, `8 kA`, `3 kN`, `150 ms`, `2.1e-6 ohm*m`,
  `20 W/(m^2*K)` or `4e4 W/m2/K`, `1507 degC`, `120 deg`. Any unit of the same kind
  is accepted and converted (UDUNITS-2 syntax, plus `u` or `µ` for micro and `ohm`
  or `Ω`). A bare number is read in the unit of the *unit* column below
  (`thickness: 1.0` with unit mm means 1.0 mm).
- Values are converted to internal units on reading: SI, except temperatures (°C)
  and angles (radians).
- A list (type *list*) is a YAML sequence of maps; its item keys are listed as
  `list[].key`, and an item's missing keys take their defaults. A table (type
  *table*) is a sequence of rows with one value per column, e.g.
  `[[0 ms, 0 kA], [10 ms, 8 kA]]`.
- A key may also be written as a dotted path, with list items indexed from 0:
  `section.list[1].key: value`.
- `--set key=value` on the command line overrides a key after the file is read;
  overrides apply in order and are checked like file values. The key is a full
  dotted path (`--set 'section.list[1].key=1.2 mm'`); the value is YAML, so a whole
  table or list can be given in flow style (`--set 'section.table=[[0 ms, 0 kA],
  [10 ms, 8 kA]]'`). Setting item n of a list that has n items appends an item with
  default values.
- Errors name the file, line and column (or `--set`), the key, the offending value
  and what is allowed, e.g.
  `case.yaml:7:16: section.key: '7 mm' is out of range; allowed: [0.1, 5] mm`.

)";

  // One table per top-level section, in declaration order; top-level keys first.
  std::vector<std::string> groups;
  for (const auto& spec : keys_) {
    const auto dot = spec.path.find_first_of(".[");
    const std::string group = dot == std::string::npos ? "" : spec.path.substr(0, dot);
    if (std::find(groups.begin(), groups.end(), group) == groups.end()) {
      groups.push_back(group);
    }
  }
  std::stable_partition(groups.begin(), groups.end(),
                        [](const std::string& g) { return g.empty(); });
  for (const auto& group : groups) {
    md << "## " << (group.empty() ? "Top-level keys" : code(group)) << "\n\n";
    for (const auto& [path, text] : section_docs_) {
      if (!group.empty() && path == group) md << text << "\n\n";
    }
    bool any_subsection = false;
    for (const auto& [path, text] : section_docs_) {
      if (!group.empty() && starts_with(path, group + ".")) {
        md << "- " << code(path) << ": " << text << "\n";
        any_subsection = true;
      }
    }
    if (any_subsection) md << "\n";
    md << "| key | type | default | unit | allowed | doc |\n";
    md << "|---|---|---|---|---|---|\n";
    for (const auto& spec : keys_) {
      const bool in_group =
          group.empty() ? spec.path.find_first_of(".[") == std::string::npos
                        : starts_with(spec.path, group + ".") || starts_with(spec.path, group + "[");
      if (!in_group) continue;
      std::string unit = "–";
      std::string allowed;
      std::string default_text = code(spec.default_value);
      switch (spec.kind) {
        case KeyKind::number:
          if (spec.display_unit != "1") unit = spec.display_unit;
          allowed = spec.range.describe(spec.display_unit);
          break;
        case KeyKind::integer:
          allowed = spec.range.describe("1");
          break;
        case KeyKind::boolean:
          allowed = "`true`, `false`";
          break;
        case KeyKind::string:
          allowed = "any text";
          if (spec.default_value.empty()) default_text = "`\"\"`";
          break;
        case KeyKind::identifier:
          allowed = "letters, digits, `_`, `-`";
          break;
        case KeyKind::choice: {
          std::vector<std::string> choices;
          for (const auto& c : spec.choices) choices.push_back(code(c));
          allowed = join(choices, ", ");
          break;
        }
        case KeyKind::table: {
          std::vector<std::string> units;
          std::vector<std::string> names;
          std::vector<std::string> ranges;
          for (const auto& column : spec.columns) {
            units.push_back(column.display_unit == "1" ? "–" : column.display_unit);
            names.push_back(column.name);
            ranges.push_back(column.name + " " + column.range.describe(column.display_unit));
          }
          unit = join(units, ", ");
          allowed = count_phrase(spec.min_items, spec.max_items, "row") + " [" +
                    join(names, ", ") + "]; " + join(ranges, "; ");
          if (spec.increasing) allowed += "; " + spec.columns.front().name + " strictly increasing";
          break;
        }
        case KeyKind::list: {
          const YAML::Node items = YAML::Load(spec.default_value);
          bool all_default = true;
          for (const auto& item : items) {
            if (!(item.IsNull() || (item.IsMap() && item.size() == 0))) all_default = false;
          }
          if (items.size() == 0) default_text = "empty";
          else if (all_default) default_text = std::to_string(items.size()) + " default items";
          allowed = count_phrase(spec.min_items, spec.max_items, "item");
          break;
        }
      }
      md << "| " << code(spec.path) << " | " << kind_word(spec) << " | " << cell(default_text)
         << " | " << cell(unit) << " | " << cell(allowed) << " | " << cell(spec.doc) << " |\n";
    }
    md << "\n";
  }
  std::string text = md.str();
  while (text.size() >= 2 && text.compare(text.size() - 2, 2, "\n\n") == 0) text.pop_back();
  return text;
}

std::string ConfigSchema::to_json() const {
  using Json = nlohmann::ordered_json;
  const auto range_json = [](const Range& range, const std::string& unit) {
    Json json = Json::object();
    if (!std::isinf(range.min)) {
      json["min"] = range.min;
      json["min_inclusive"] = range.min_inclusive;
    }
    if (!std::isinf(range.max)) {
      json["max"] = range.max;
      json["max_inclusive"] = range.max_inclusive;
    }
    json["unit"] = unit;
    return json;
  };
  Json root;
  root["title"] = title_;
  root["sections"] = Json::object();
  for (const auto& [path, doc] : section_docs_) root["sections"][path] = doc;
  root["keys"] = Json::array();
  for (const auto& spec : keys_) {
    Json key;
    key["path"] = spec.path;
    key["kind"] = kind_name(spec.kind);
    key["default"] = spec.default_value;
    switch (spec.kind) {
      case KeyKind::number:
        key["quantity"] = quantity_kind(spec.unit);
        key["unit"] = spec.unit;
        key["display_unit"] = spec.display_unit;
        key["range"] = range_json(spec.range, spec.display_unit);
        break;
      case KeyKind::integer:
        key["range"] = range_json(spec.range, "1");
        break;
      case KeyKind::choice:
        key["choices"] = spec.choices;
        break;
      case KeyKind::table:
        key["columns"] = Json::array();
        for (const auto& column : spec.columns) {
          key["columns"].push_back({{"name", column.name},
                                    {"quantity", quantity_kind(column.unit)},
                                    {"unit", column.unit},
                                    {"display_unit", column.display_unit},
                                    {"range", range_json(column.range, column.display_unit)}});
        }
        key["increasing"] = spec.increasing;
        break;
      default:
        break;
    }
    if (spec.kind == KeyKind::table || spec.kind == KeyKind::list) {
      key["min_items"] = spec.min_items;
      if (spec.max_items != INT_MAX) key["max_items"] = spec.max_items;
    }
    key["doc"] = spec.doc;
    root["keys"].push_back(key);
  }
  return root.dump(2) + "\n";
}

std::string ConfigSchema::to_json_schema() const {
  using Json = nlohmann::ordered_json;
  // A number bare (in the display unit, within the range) or as text with a unit.
  const auto number_schema = [](const Range& range, const std::string& display_unit) {
    Json bare = {{"type", "number"}};
    if (!std::isinf(range.min)) bare[range.min_inclusive ? "minimum" : "exclusiveMinimum"] = range.min;
    if (!std::isinf(range.max)) bare[range.max_inclusive ? "maximum" : "exclusiveMaximum"] = range.max;
    Json with_unit = {{"type", "string"},
                      {"pattern", R"(^\s*[-+]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][-+]?[0-9]+)?(\s*\S.*)?$)"}};
    return Json{{"anyOf", Json::array({bare, with_unit})},
                {"description", "bare numbers in " + display_unit + "; or a number and a unit"}};
  };
  const auto new_object = [](const std::string& description) {
    Json object = {{"type", "object"}, {"additionalProperties", false}, {"properties", Json::object()}};
    if (!description.empty()) object["description"] = description;
    return object;
  };
  const auto section_doc = [this](const std::string& path) {
    for (const auto& [section, doc] : section_docs_)
      if (section == path) return doc;
    return std::string();
  };
  Json root = {{"$schema", "http://json-schema.org/draft-07/schema#"},
               {"title", title_},
               {"type", "object"},
               {"additionalProperties", false},
               {"properties", Json::object()}};
  for (const auto& spec : keys_) {
    Json* node = &root;
    std::string prefix;
    std::size_t start = 0;
    while (true) {
      const std::size_t dot = spec.path.find('.', start);
      if (dot == std::string::npos) break;
      std::string segment = spec.path.substr(start, dot - start);
      prefix += (prefix.empty() ? "" : ".") + segment;
      const bool items = segment.size() > 2 && segment.compare(segment.size() - 2, 2, "[]") == 0;
      if (items) segment.resize(segment.size() - 2);
      Json& properties = (*node)["properties"];
      if (items) {
        Json& list = properties[segment];
        if (!list.contains("items")) list["items"] = new_object("");
        node = &list["items"];
      } else {
        if (!properties.contains(segment)) properties[segment] = new_object(section_doc(prefix));
        node = &properties[segment];
      }
      start = dot + 1;
    }
    const std::string name = spec.path.substr(start);
    Json leaf;
    switch (spec.kind) {
      case KeyKind::number:
        leaf = number_schema(spec.range, spec.display_unit);
        break;
      case KeyKind::integer:
        leaf = {{"type", "integer"}};
        if (!std::isinf(spec.range.min)) leaf[spec.range.min_inclusive ? "minimum" : "exclusiveMinimum"] = spec.range.min;
        if (!std::isinf(spec.range.max)) leaf[spec.range.max_inclusive ? "maximum" : "exclusiveMaximum"] = spec.range.max;
        break;
      case KeyKind::boolean:
        leaf = {{"type", "boolean"}};
        break;
      case KeyKind::string:
        leaf = {{"type", "string"}};
        break;
      case KeyKind::identifier:
        leaf = {{"type", "string"}, {"pattern", "^[A-Za-z0-9_-]+$"}, {"maxLength", max_name_length}};
        break;
      case KeyKind::choice:
        leaf = {{"enum", spec.choices}};
        break;
      case KeyKind::table: {
        Json row = {{"type", "array"}, {"items", Json::array()}};
        for (const auto& column : spec.columns) row["items"].push_back(number_schema(column.range, column.display_unit));
        row["minItems"] = spec.columns.size();
        row["maxItems"] = spec.columns.size();
        leaf = {{"type", "array"}, {"items", row}};
        break;
      }
      case KeyKind::list: {
        Json& existing = (*node)["properties"][name];
        leaf = {{"type", "array"}, {"items", existing.contains("items") ? existing["items"] : new_object("")}};
        break;
      }
    }
    if (spec.kind == KeyKind::table || spec.kind == KeyKind::list) {
      if (spec.min_items > 0) leaf["minItems"] = spec.min_items;
      if (spec.max_items != INT_MAX) leaf["maxItems"] = spec.max_items;
    }
    const std::string unit_note = leaf.contains("description") ? " (" + leaf["description"].get<std::string>() + ")" : "";
    leaf["description"] = spec.doc + unit_note;
    if (spec.kind == KeyKind::integer && !spec.default_value.empty()) {
      leaf["default"] = std::stoll(spec.default_value);
    } else if (spec.kind == KeyKind::boolean) {
      leaf["default"] = spec.default_value == "true";
    } else if (spec.kind != KeyKind::table && spec.kind != KeyKind::list) {
      leaf["default"] = spec.default_value;
    }
    (*node)["properties"][name] = leaf;
  }
  return root.dump(2) + "\n";
}

// ---------------------------------------------------------------------------------
// Origins, tables, paths

std::string ConfigOrigin::where() const {
  if (line <= 0) return source;
  return source + ":" + std::to_string(line) + ":" + std::to_string(column);
}

std::vector<double> ConfigTable::column(int index) const {
  std::vector<double> values;
  values.reserve(rows.size());
  for (const auto& row : rows) values.push_back(row.at(static_cast<std::size_t>(index)));
  return values;
}

std::string item_path(const std::string& list_path, int index, const std::string& key) {
  std::string path = list_path + "[" + std::to_string(index) + "]";
  return key.empty() ? path : path + "." + key;
}

// ---------------------------------------------------------------------------------
// Loading: YAML nodes -> checked values

struct Config::Loader {
  const ConfigSchema& schema;
  std::map<std::string, Value>& values;
  std::string source;
  bool use_marks;  // file positions mean something (not for --set or defaults)

  ConfigOrigin origin_of(const YAML::Node& node) const {
    ConfigOrigin origin{source, 0, 0};
    if (use_marks) {
      const YAML::Mark mark = node.Mark();
      if (!mark.is_null()) {
        origin.line = mark.line + 1;
        origin.column = mark.column + 1;
      }
    }
    return origin;
  }

  [[noreturn]] static void fail(const ConfigOrigin& origin, const std::string& key,
                                const std::string& message) {
    throw ConfigError(origin.where() + ": " + (key.empty() ? "(top level)" : key) + ": " +
                      message);
  }

  std::string scalar(const std::string& key, const YAML::Node& node,
                     const ConfigOrigin& origin, const std::string& expected) const {
    if (node.IsNull()) fail(origin, key, "no value given; expected " + expected);
    if (!node.IsScalar()) fail(origin, key, "expected " + expected + ", got " + describe_node(node));
    return trim(node.Scalar());
  }

  double read_number(const NumberRule& rule, const std::string& key, const YAML::Node& node,
                     const ConfigOrigin& origin) const {
    const std::string expected = expect_number(rule);
    const std::string text = scalar(key, node, origin, expected);
    Quantity quantity;
    try {
      quantity = split_quantity(text);
    } catch (const UnitError&) {
      fail(origin, key, "'" + text + "' is not a number; expected " + expected);
    }
    const std::string unit = quantity.unit.empty() ? rule.display_unit : quantity.unit;
    if (!is_known_unit(unit)) {
      fail(origin, key, "'" + text + "' has an unknown unit '" + unit + "'; expected " + expected);
    }
    if (!units_convertible(unit, rule.unit)) {
      fail(origin, key, "'" + text + "' is " + with_article(quantity_kind(unit)) + ", not " +
                            with_article(quantity_kind(rule.unit)) + "; expected " + expected);
    }
    const double shown = convert_units(quantity.value, unit, rule.display_unit);
    if (!rule.range.contains(shown)) {
      const bool same_unit = quantity.unit.empty() || quantity.unit == rule.display_unit;
      fail(origin, key,
           "'" + text + "'" +
               (same_unit ? "" : " (" + with_unit(format_short(shown), rule.display_unit) + ")") +
               " is out of range; allowed: " + rule.range.describe(rule.display_unit));
    }
    return convert_units(quantity.value, unit, rule.unit);
  }

  // `key_origin` places errors about an empty value: YAML marks a missing value at
  // the token after it, often on the next line.
  void assign(const KeySpec& spec, const std::string& key, const YAML::Node& node,
              const ConfigOrigin& key_origin) {
    const ConfigOrigin origin = node.IsNull() ? key_origin : origin_of(node);
    const std::string expected = expectation(schema, spec);
    Value value;
    value.kind = spec.kind;
    value.origin = origin;
    switch (spec.kind) {
      case KeyKind::number:
        value.number = read_number({spec.unit, spec.display_unit, spec.range,
                                    number_example(spec.default_value, spec.display_unit)},
                                   key, node, origin);
        break;
      case KeyKind::integer: {
        const std::string text = scalar(key, node, origin, expected);
        const std::size_t sign = !text.empty() && (text[0] == '+' || text[0] == '-') ? 1 : 0;
        if (text.size() <= sign || text.size() - sign > 15 || !std::all_of(text.begin() + sign, text.end(), is_digit)) {
          fail(origin, key, "'" + text + "' is not an integer; expected " + expected);
        }
        value.integer = std::stoll(text);
        if (!spec.range.contains(static_cast<double>(value.integer))) {
          fail(origin, key, "'" + text + "' is out of range; allowed: " + spec.range.describe("1"));
        }
        break;
      }
      case KeyKind::boolean: {
        const std::string text = scalar(key, node, origin, expected);
        std::string lower = text;
        std::transform(lower.begin(), lower.end(), lower.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (lower == "true" || lower == "yes" || lower == "on") {
          value.boolean = true;
        } else if (lower == "false" || lower == "no" || lower == "off") {
          value.boolean = false;
        } else {
          fail(origin, key, "'" + text + "' is not a boolean; expected " + expected);
        }
        break;
      }
      case KeyKind::string:
        if (node.IsNull()) fail(origin, key, "no value given; expected " + expected);
        if (!node.IsScalar()) fail(origin, key, "expected " + expected + ", got " + describe_node(node));
        value.text = node.Scalar();
        break;
      case KeyKind::identifier: {
        value.text = scalar(key, node, origin, expected);
        if (value.text.size() > max_name_length) {
          fail(origin, key, "a name of " + std::to_string(value.text.size()) + " characters; allowed: at most " +
                                std::to_string(max_name_length));
        }
        if (value.text.empty() || !std::all_of(value.text.begin(), value.text.end(),
                                               [](char c) { return is_name_character(c) || c == '-'; })) {
          fail(origin, key, "'" + value.text + "' is not a name; expected " + expected);
        }
        break;
      }
      case KeyKind::choice: {
        value.text = scalar(key, node, origin, expected);
        if (std::find(spec.choices.begin(), spec.choices.end(), value.text) == spec.choices.end()) {
          const std::string near = closest(value.text, spec.choices);
          fail(origin, key, "'" + value.text + "' is not an allowed choice; allowed: " +
                                quoted_list(spec.choices) +
                                (near.empty() ? "" : " (did you mean '" + near + "'?)"));
        }
        break;
      }
      case KeyKind::table:
        read_table(spec, key, node, origin, value);
        break;
      case KeyKind::list:
        assign_list(spec, key, node, origin);
        return;
    }
    values[key] = value;
  }

  void read_table(const KeySpec& spec, const std::string& key, const YAML::Node& node,
                  const ConfigOrigin& origin, Value& value) const {
    const std::string expected = expectation(schema, spec);
    if (!node.IsSequence()) fail(origin, key, "expected " + expected + ", got " + describe_node(node));
    const int n_rows = static_cast<int>(node.size());
    if (n_rows < spec.min_items || n_rows > spec.max_items) {
      fail(origin, key, std::to_string(n_rows) + (n_rows == 1 ? " row" : " rows") +
                            " given; allowed: " +
                            count_phrase(spec.min_items, spec.max_items, "row"));
    }
    std::vector<std::string> names;
    for (const auto& column : spec.columns) names.push_back(column.name);
    value.table.column_names = names;
    int r = 0;
    for (const auto& row : node) {
      const std::string row_key = key + "[" + std::to_string(r) + "]";
      const ConfigOrigin row_origin = origin_of(row);
      if (!row.IsSequence() || row.size() != spec.columns.size()) {
        fail(row_origin, row_key,
             (row.IsSequence() ? "a row of " + std::to_string(row.size()) + " values"
                               : describe_node(row)) +
                 " is not a row [" + join(names, ", ") + "] of " +
                 std::to_string(spec.columns.size()) + " values; expected " + expected);
      }
      std::vector<double> cells;
      int c = 0;
      for (const auto& cell : row) {
        const TableColumn& column = spec.columns[static_cast<std::size_t>(c)];
        const std::string cell_key =
            row_key + "[" + std::to_string(c) + "] (" + column.name + ")";
        const ConfigOrigin cell_origin = origin_of(cell);
        NumberRule rule{column.unit, column.display_unit, column.range, ""};
        rule.example = number_example(
            c == 0 && spec.increasing ? "10" : "1", column.display_unit);
        const double number = read_number(rule, cell_key, cell, cell_origin);
        if (spec.increasing && c == 0 && r > 0 && !(number > value.table.rows.back()[0])) {
          fail(cell_origin, cell_key,
               "'" + trim(cell.Scalar()) + "' does not come after the previous row's " +
                   format_display(value.table.rows.back()[0], column.unit, column.display_unit) +
                   "; " + column.name + " must be strictly increasing");
        }
        cells.push_back(number);
        ++c;
      }
      value.table.rows.push_back(cells);
      value.row_origins.push_back(row_origin);
      ++r;
    }
  }

  void erase_items(const std::string& key) {
    const std::string prefix = key + "[";
    for (auto it = values.lower_bound(prefix); it != values.end() && starts_with(it->first, prefix);) {
      it = values.erase(it);
    }
  }

  void assign_list(const KeySpec& spec, const std::string& key, const YAML::Node& node,
                   const ConfigOrigin& origin) {
    const std::string expected = expectation(schema, spec);
    if (!node.IsNull() && !node.IsSequence()) {
      fail(origin, key, "expected " + expected + ", got " + describe_node(node));
    }
    const int n = node.IsNull() ? 0 : static_cast<int>(node.size());
    if (n < spec.min_items || n > spec.max_items) {
      fail(origin, key, std::to_string(n) + (n == 1 ? " item" : " items") + " given; allowed: " +
                            count_phrase(spec.min_items, spec.max_items, "item"));
    }
    erase_items(key);
    Value list;
    list.kind = KeyKind::list;
    list.n_items = n;
    list.origin = origin;
    values[key] = list;
    if (n == 0) return;
    int i = 0;
    for (const auto& item : node) {
      const std::string item_key = item_path(key, i);
      fill_defaults(spec.path + "[]", item_key);
      load_item(spec, item_key, item);
      ++i;
    }
  }

  void load_item(const KeySpec& spec, const std::string& item_key, const YAML::Node& item) {
    if (item.IsNull()) return;
    if (!item.IsMap()) {
      fail(origin_of(item), item_key,
           "expected a map with keys " + join(schema.children(spec.path + "[]"), ", ") +
               ", got " + describe_node(item));
    }
    load_map(item, spec.path + "[]", item_key);
  }

  // Every key of a scope at its default; lists get their default items.
  void fill_defaults(const std::string& scope, const std::string& concrete_scope) {
    Loader defaults{schema, values, "default", false};
    const std::string prefix = scope.empty() ? "" : scope + ".";
    for (const auto& spec : schema.keys()) {
      if (!starts_with(spec.path, prefix)) continue;
      const std::string rest = spec.path.substr(prefix.size());
      if (rest.find('[') != std::string::npos) continue;  // inside a nested list
      const std::string key = join_path(concrete_scope, rest);
      YAML::Node node;
      if (spec.kind == KeyKind::table || spec.kind == KeyKind::list) {
        try {
          node = YAML::Load(spec.default_value);
        } catch (const YAML::Exception& e) {
          fail({"default"}, key, "default '" + spec.default_value + "' is not YAML: " + e.msg);
        }
      } else {
        node = YAML::Node(spec.default_value);
      }
      defaults.assign(spec, key, node, ConfigOrigin{"default", 0, 0});
    }
  }

  void load_map(const YAML::Node& node, const std::string& scope,
                const std::string& concrete_scope) {
    if (node.IsNull()) return;
    if (!node.IsMap()) {
      fail(origin_of(node), concrete_scope,
           "expected a map with keys " + join(schema.children(scope), ", ") + ", got " +
               describe_node(node));
    }
    std::map<std::string, ConfigOrigin> seen;
    for (const auto& entry : node) {
      const ConfigOrigin key_origin = origin_of(entry.first);
      if (!entry.first.IsScalar()) {
        fail(key_origin, concrete_scope, "a key must be a name, got " + describe_node(entry.first));
      }
      const std::string name = trim(entry.first.Scalar());
      const auto [previous, inserted] = seen.emplace(name, key_origin);
      if (!inserted) {
        fail(key_origin, join_path(concrete_scope, name),
             "key given twice (first at " + previous->second.where() + ")");
      }
      walk(scope, concrete_scope, name, entry.second, key_origin);
    }
  }

  [[noreturn]] void unknown_key(const std::string& scope, const std::string& concrete_scope,
                                const std::string& name, const ConfigOrigin& origin) const {
    const std::vector<std::string> siblings = schema.children(scope);
    std::string suggestion;
    const std::string near = closest(name, siblings);
    if (!near.empty()) {
      suggestion = join_path(concrete_scope, near);
    } else {
      // Perhaps the right name in the wrong section: match on the last name.
      std::vector<std::string> elsewhere;
      for (const auto& spec : schema.keys()) {
        const std::string leaf = spec.path.substr(spec.path.find_last_of('.') + 1);
        if ((leaf == name || is_near(name, leaf)) && elsewhere.size() < 3) {
          elsewhere.push_back(spec.path);
        }
      }
      suggestion = join(elsewhere, "' or '");
    }
    std::string message = "unknown key";
    if (!suggestion.empty()) message += "; did you mean '" + suggestion + "'?";
    message += std::string(" Keys allowed ") +
               (concrete_scope.empty() ? "at the top level" : "in '" + concrete_scope + "'") +
               ": " + join(siblings, ", ");
    fail(origin, join_path(concrete_scope, name), message);
  }

  // Sets the value at `path` (dotted, with [index] on lists) below a scope.
  void walk(std::string scope, std::string concrete_scope, const std::string& path,
            const YAML::Node& node, const ConfigOrigin& key_origin) {
    const auto steps = parse_path(path);
    if (!steps) {
      fail(key_origin, join_path(concrete_scope, path),
           "not a key path; expected names joined by '.', list items as name[index]");
    }
    for (std::size_t i = 0; i < steps->size(); ++i) {
      const PathStep& step = (*steps)[i];
      const bool last = i + 1 == steps->size();
      const std::string schema_path = join_path(scope, step.name);
      const std::string key = join_path(concrete_scope, step.name);
      const KeySpec* spec = schema.find(schema_path);
      if (spec == nullptr && !schema.is_section(schema_path)) {
        unknown_key(scope, concrete_scope, step.name, key_origin);
      }
      if (step.index >= 0) {
        if (spec == nullptr || spec->kind != KeyKind::list) {
          fail(key_origin, key + "[" + std::to_string(step.index) + "]",
               "'" + key + "' is " + (spec ? with_article(kind_name(spec->kind)) : "a section") +
                   ", not a list; only list items take an index");
        }
        Value& list = values.at(key);
        const int n = list.n_items;
        if (step.index > n || (step.index == n && n >= spec->max_items)) {
          fail(key_origin, item_path(key, step.index),
               "index " + std::to_string(step.index) + " is past the end of a list of " +
                   std::to_string(n) + (n == 1 ? " item" : " items") +
                   (n < spec->max_items ? "; index " + std::to_string(n) + " appends an item"
                                        : ", the most allowed (" +
                                              count_phrase(spec->min_items, spec->max_items, "item") +
                                              ")"));
        }
        if (step.index == n) {
          ++list.n_items;
          list.origin = key_origin;
          fill_defaults(schema_path + "[]", item_path(key, n));
        }
        scope = schema_path + "[]";
        concrete_scope = item_path(key, step.index);
        if (last) load_item(*spec, concrete_scope, node);
        continue;
      }
      if (spec != nullptr) {
        if (!last) {
          const std::string below = key + "." + (*steps)[i + 1].name;
          fail(key_origin, below,
               "'" + key + "' is " + with_article(kind_name(spec->kind)) +
                   " and has no keys below it" +
                   (spec->kind == KeyKind::list
                        ? "; address an item as " + item_path(key, 0, (*steps)[i + 1].name)
                        : ""));
        }
        assign(*spec, key, node, key_origin);
        return;
      }
      scope = schema_path;
      concrete_scope = key;
      if (last) load_map(node, scope, concrete_scope);
    }
  }
};

// ---------------------------------------------------------------------------------
// Config

Config::Config(ConfigSchema schema) : schema_(std::move(schema)) {
  schema_.validate();
  try {
    Loader loader{schema_, values_, "default", false};
    loader.fill_defaults("", "");
  } catch (const ConfigError& e) {
    throw std::logic_error(std::string("config schema: bad default: ") + e.what());
  }
}

const Config::Value& Config::value(const std::string& path, KeyKind kind) const {
  const auto it = values_.find(path);
  if (it == values_.end()) {
    throw std::logic_error("config: no key '" + path + "' in " + schema_.title());
  }
  const KeyKind actual = it->second.kind;
  const bool textual = [](KeyKind k) {
    return k == KeyKind::string || k == KeyKind::identifier || k == KeyKind::choice;
  }(actual);
  if (actual != kind && !(kind == KeyKind::string && textual)) {
    throw std::logic_error("config: key '" + path + "' is " + with_article(kind_name(actual)) +
                           ", not " + with_article(kind_name(kind)));
  }
  return it->second;
}

double Config::number(const std::string& path) const { return value(path, KeyKind::number).number; }

int Config::integer(const std::string& path) const {
  return static_cast<int>(value(path, KeyKind::integer).integer);
}

bool Config::boolean(const std::string& path) const {
  return value(path, KeyKind::boolean).boolean;
}

const std::string& Config::text(const std::string& path) const {
  return value(path, KeyKind::string).text;
}

const ConfigTable& Config::table(const std::string& path) const {
  return value(path, KeyKind::table).table;
}

int Config::n_items(const std::string& list_path) const {
  return value(list_path, KeyKind::list).n_items;
}

bool Config::contains(const std::string& path) const { return values_.count(path) > 0; }

void Config::merge_file(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    throw ConfigError(file + ": cannot open config file: " + std::strerror(errno));
  }
  std::ostringstream text;
  text << in.rdbuf();
  merge_text(text.str(), file);
}

void Config::merge_text(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(yaml_where(source, e.mark) + ": malformed YAML: " + e.msg);
  }
  std::map<std::string, Value> values = values_;
  Loader loader{schema_, values, source, true};
  try {
    loader.load_map(root, "", "");
  } catch (const YAML::Exception& e) {
    throw ConfigError(yaml_where(source, e.mark) + ": " + e.msg);
  }
  values_.swap(values);
}

void Config::apply_override(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || trim(assignment.substr(0, eq)).empty()) {
    throw ConfigError("--set: '" + assignment +
                      "' is not of the form key=value (e.g. section.key=1.0 mm)");
  }
  set(trim(assignment.substr(0, eq)), trim(assignment.substr(eq + 1)), "--set");
}

void Config::set(const std::string& path, const std::string& yaml_value,
                 const std::string& source) {
  YAML::Node node;
  try {
    node = YAML::Load(yaml_value);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(source + ": " + path + ": '" + yaml_value + "' is not valid YAML (" +
                      e.msg + ")");
  }
  std::map<std::string, Value> values = values_;
  Loader loader{schema_, values, source, false};
  loader.walk("", "", path, node, ConfigOrigin{source, 0, 0});
  values_.swap(values);
}

void Config::set_number(const std::string& path, double value, const std::string& source) {
  const KeySpec* spec = schema_.find(schema_path_of(path));
  const auto it = values_.find(path);
  if (spec == nullptr || it == values_.end()) {
    throw ConfigError(source + ": " + path + ": unknown key");
  }
  if (spec->kind != KeyKind::number) {
    throw ConfigError(source + ": " + path + ": is " + with_article(kind_name(spec->kind)) +
                      ", not a number");
  }
  const double shown = std::isfinite(value)
                           ? convert_units(value, spec->unit, spec->display_unit)
                           : value;
  if (!std::isfinite(shown) || !spec->range.contains(shown)) {
    throw ConfigError(source + ": " + path + ": '" +
                      with_unit(format_short(shown), spec->display_unit) +
                      "' is out of range; allowed: " + spec->range.describe(spec->display_unit));
  }
  it->second.number = value;
  it->second.origin = ConfigOrigin{source, 0, 0};
}

namespace {

// "schedule.current[2]" -> {"schedule.current", 2}; index -1 if not of that form.
std::pair<std::string, int> split_row(const std::string& path) {
  const auto open = path.find_last_of('[');
  if (open == std::string::npos || path.back() != ']') return {path, -1};
  const std::string digits = path.substr(open + 1, path.size() - open - 2);
  if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) {
    return {path, -1};
  }
  return {path.substr(0, open), std::stoi(digits)};
}

}  // namespace

const ConfigOrigin& Config::origin(const std::string& path) const {
  const auto it = values_.find(path);
  if (it != values_.end()) return it->second.origin;
  const auto [table_path, row] = split_row(path);
  const Value& table = value(table_path, KeyKind::table);
  if (row < 0 || row >= static_cast<int>(table.row_origins.size())) {
    throw std::logic_error("config: no row '" + path + "'");
  }
  return table.row_origins[static_cast<std::size_t>(row)];
}

bool Config::is_default(const std::string& path) const { return origin(path).source == "default"; }

std::string Config::display(const std::string& path) const {
  const auto row_text = [](const KeySpec& spec, const std::vector<double>& row) {
    std::vector<std::string> cells;
    for (std::size_t c = 0; c < row.size(); ++c) {
      cells.push_back(format_display(row[c], spec.columns[c].unit, spec.columns[c].display_unit));
    }
    return "[" + join(cells, ", ") + "]";
  };
  const auto it = values_.find(path);
  if (it == values_.end()) {
    const auto [table_path, row] = split_row(path);
    const ConfigTable& table = this->table(table_path);
    if (row < 0 || row >= table.n_rows()) throw std::logic_error("config: no row '" + path + "'");
    return row_text(*schema_.find(schema_path_of(table_path)),
                    table.rows[static_cast<std::size_t>(row)]);
  }
  const Value& v = it->second;
  const KeySpec& spec = *schema_.find(schema_path_of(path));
  switch (v.kind) {
    case KeyKind::number:
      return format_display(v.number, spec.unit, spec.display_unit);
    case KeyKind::integer:
      return std::to_string(v.integer);
    case KeyKind::boolean:
      return v.boolean ? "true" : "false";
    case KeyKind::string:
    case KeyKind::identifier:
    case KeyKind::choice:
      return v.text.empty() ? "''" : v.text;
    case KeyKind::table: {
      std::vector<std::string> rows;
      for (const auto& row : v.table.rows) rows.push_back(row_text(spec, row));
      return "[" + join(rows, ", ") + "]";
    }
    case KeyKind::list:
      return std::to_string(v.n_items) + (v.n_items == 1 ? " item" : " items");
  }
  return "";
}

std::string Config::describe(const std::string& path) const {
  return path + " = " + display(path) + " (" + origin(path).where() + ")";
}

void Config::fail(const std::string& path, const std::string& requirement) const {
  throw ConfigError(origin(path).where() + ": " + path + " = " + display(path) + ": " +
                    requirement);
}

namespace {

void emit_scope(YAML::Emitter& out, const Config& config, const std::string& scope,
                const std::string& concrete_scope) {
  const ConfigSchema& schema = config.schema();
  out << YAML::BeginMap;
  for (const auto& name : schema.children(scope)) {
    const std::string schema_path = join_path(scope, name);
    const std::string key = join_path(concrete_scope, name);
    out << YAML::Key << name << YAML::Value;
    const KeySpec* spec = schema.find(schema_path);
    if (spec == nullptr) {
      emit_scope(out, config, schema_path, key);
      continue;
    }
    switch (spec->kind) {
      case KeyKind::integer:
        out << config.integer(key);
        break;
      case KeyKind::boolean:
        out << config.boolean(key);
        break;
      case KeyKind::table: {
        const ConfigTable& table = config.table(key);
        out << YAML::Flow << YAML::BeginSeq;
        for (const auto& row : table.rows) {
          out << YAML::Flow << YAML::BeginSeq;
          for (std::size_t c = 0; c < row.size(); ++c) {
            out << format_display(row[c], spec->columns[c].unit, spec->columns[c].display_unit);
          }
          out << YAML::EndSeq;
        }
        out << YAML::EndSeq;
        break;
      }
      case KeyKind::list: {
        const int n = config.n_items(key);
        if (n == 0) {
          out << YAML::Flow << YAML::BeginSeq << YAML::EndSeq;
          break;
        }
        out << YAML::BeginSeq;
        for (int i = 0; i < n; ++i) emit_scope(out, config, schema_path + "[]", item_path(key, i));
        out << YAML::EndSeq;
        break;
      }
      case KeyKind::string:
      case KeyKind::identifier:
      case KeyKind::choice:
        out << config.text(key);
        break;
      case KeyKind::number:
        out << config.display(key);
        break;
    }
  }
  out << YAML::EndMap;
}

}  // namespace

std::string Config::to_yaml() const {
  YAML::Emitter out;
  out << YAML::Comment(schema_.title() + ", resolved: every key, values in display units");
  out << YAML::Newline;
  emit_scope(out, *this, "", "");
  return std::string(out.c_str()) + "\n";
}

Config load_config(const ConfigSchema& schema, const std::string& file,
                   const std::vector<std::string>& overrides) {
  Config config(schema);
  config.merge_file(file);
  for (const auto& assignment : overrides) config.apply_override(assignment);
  return config;
}

}  // namespace rsw::fem
