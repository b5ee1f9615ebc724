// Declared, validated configuration trees: the generic machinery behind every input
// file of rsw (weld cases, later studies). It knows nothing about welding.
//
// A ConfigSchema declares each key once: its path ("stack.sheet_radius"; keys of list
// items as "stack.sheets[].thickness"), kind, default (written as a user would write
// it, "1.0 mm"), internal and display unit, allowed range, list or table size limits
// and a one-line doc. A Config is a schema resolved against a YAML file and
// `--set key=value` overrides: every key present, every value checked, numbers
// converted to internal units (SI, except temperatures in degC and angles in rad;
// the schema states the internal unit of each key). A bare number is read in the
// key's display unit.
//
// Every user error throws ConfigError with one message naming where the value came
// from (file:line:column, or --set), the key path, the offending value, and what is
// allowed (range in display units, choices, expected type or kind of quantity).
// Misuse by the program (asking for an undeclared key or the wrong kind) throws
// std::logic_error.
//
// This is the one wrapper around yaml-cpp; units go through fem/units.hpp.
#pragma once

#include <climits>
#include <deque>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rsw::fem {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class KeyKind {
  number,      // real number with a unit
  integer,     // whole number, no unit
  boolean,     // true / false
  string,      // free text
  identifier,  // name made of [A-Za-z0-9_-]
  choice,      // one of a declared list of words
  table,       // rows of numbers, one unit per column (e.g. time, current)
  list,        // items, each a map of the keys declared under "<path>[]."
};

const char* kind_name(KeyKind kind);

// Allowed interval of a number or integer, in the key's display unit.
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_inclusive = true;
  bool max_inclusive = true;

  static Range any() { return {}; }
  static Range closed(double lo, double hi) { return {lo, hi, true, true}; }
  static Range open_closed(double lo, double hi) { return {lo, hi, false, true}; }
  static Range closed_open(double lo, double hi) { return {lo, hi, true, false}; }
  static Range at_least(double lo) { return {lo, Range().max, true, true}; }
  static Range greater_than(double lo) { return {lo, Range().max, false, true}; }

  bool is_any() const;
  bool contains(double value) const;
  // "[0.1, 5] mm", "> 0 ms", "any" (unit "1" is left out).
  std::string describe(const std::string& unit) const;
};

struct TableColumn {
  std::string name;
  std::string unit;          // internal unit
  std::string display_unit;  // unit of bare numbers, of the range and of echoes
  Range range;               // in display_unit
};

struct KeySpec {
  std::string path;
  KeyKind kind = KeyKind::number;
  std::string default_value;  // as a user writes it; YAML flow text for table/list
  std::string unit = "1";           // number: internal unit
  std::string display_unit = "1";   // number: unit of bare numbers, range, echo
  Range range;                      // number, integer: in display_unit
  std::vector<std::string> choices; // choice
  std::vector<TableColumn> columns; // table
  bool increasing = false;          // table: first column strictly increasing
  int min_items = 0;                // list items or table rows
  int max_items = INT_MAX;
  std::string doc;
};

// Chained setters for one key being declared:
//   schema.number("stack.sheet_radius", "m", "mm").default_value("15 mm")
//       .range(Range::open_closed(0, 200)).doc("Radius of the sheets.");
class KeyDeclaration {
 public:
  explicit KeyDeclaration(KeySpec& spec) : spec_(spec) {}
  KeyDeclaration& default_value(const std::string& text);
  KeyDeclaration& range(const Range& range);
  KeyDeclaration& items(int min_items, int max_items);  // list items / table rows
  KeyDeclaration& column(const std::string& name, const std::string& unit,
                         const std::string& display_unit, const Range& range = {});
  KeyDeclaration& increasing();  // table: first column strictly increasing
  KeyDeclaration& doc(const std::string& text);

 private:
  KeySpec& spec_;
};

class ConfigSchema {
 public:
  // `title` heads the Markdown reference; `intro` (Markdown) follows it.
  ConfigSchema(std::string title, std::string intro);

  KeyDeclaration number(const std::string& path, const std::string& unit,
                        const std::string& display_unit);
  KeyDeclaration integer(const std::string& path);
  KeyDeclaration boolean(const std::string& path);
  KeyDeclaration string(const std::string& path);
  KeyDeclaration identifier(const std::string& path);
  KeyDeclaration choice(const std::string& path, const std::vector<std::string>& choices);
  KeyDeclaration table(const std::string& path);
  KeyDeclaration list(const std::string& path);
  // One-line doc of a section (a path prefix such as "contact.electrode_sheet").
  void section(const std::string& path, const std::string& doc);

  // The key declared at `schema_path` ("stack.sheets[].thickness"), or nullptr.
  const KeySpec* find(const std::string& schema_path) const;
  bool is_section(const std::string& schema_path) const;
  // Names directly below a section or list-item scope ("" is the root), in
  // declaration order.
  std::vector<std::string> children(const std::string& scope) const;
  const std::deque<KeySpec>& keys() const { return keys_; }
  const std::string& title() const { return title_; }

  // Checks units, ranges, defaults and docs of every key; throws std::logic_error.
  // Called by Config's constructor, so a broken schema fails on first use.
  void validate() const;

  // Reference of every key, a table per top-level section: key, type, default,
  // unit, allowed, doc.
  std::string to_markdown() const;
  // The same as JSON: {"title", "keys": [{"path", "kind", "default", ...}]}.
  std::string to_json() const;
  // JSON Schema (draft-07) of a config file: nested objects, no unknown keys, numbers bare
  // (in the display unit, within the range) or with a unit, choices, tables, lists. For
  // editors that check YAML against a schema; the loader's checks remain the authority.
  std::string to_json_schema() const;

 private:
  KeyDeclaration declare(const std::string& path, KeyKind kind);

  std::string title_;
  std::string intro_;
  std::deque<KeySpec> keys_;  // deque: declarations hold references while chaining
  std::vector<std::pair<std::string, std::string>> section_docs_;  // declaration order
};

// Where a value came from: a file position, "--set", "default", or another source.
struct ConfigOrigin {
  std::string source;
  int line = 0;    // 1-based; 0 when the source has no lines
  int column = 0;  // 1-based
  std::string where() const;  // "weld.yaml:12:5", "--set", "default"
};

// Rows of numbers in internal units, one entry per declared column.
struct ConfigTable {
  std::vector<std::string> column_names;
  std::vector<std::vector<double>> rows;
  int n_rows() const { return static_cast<int>(rows.size()); }
  std::vector<double> column(int index) const;
};

// "stack.sheets", 1, "thickness" -> "stack.sheets[1].thickness".
std::string item_path(const std::string& list_path, int index, const std::string& key = "");

// The longest name rsw accepts (names become folder and file names; NAME_MAX is 255).
constexpr std::size_t max_name_length = 128;
// A name of letters, digits and '_', not starting with a digit, at most max_name_length
// characters (study, parameter and feature names).
bool is_plain_name(const std::string& text);
// A config key path: names of letters, digits and '_' joined by '.', each optionally
// indexed as name[n] (n of one to six digits).
bool is_key_path(const std::string& text);

class Config {
 public:
  // Every key at its default.
  explicit Config(ConfigSchema schema);

  const ConfigSchema& schema() const { return schema_; }

  // Values by concrete path ("stack.sheets[1].thickness"), in internal units.
  double number(const std::string& path) const;
  int integer(const std::string& path) const;
  bool boolean(const std::string& path) const;
  const std::string& text(const std::string& path) const;  // string, identifier, choice
  const ConfigTable& table(const std::string& path) const;
  int n_items(const std::string& list_path) const;
  bool contains(const std::string& path) const;

  // Reads a YAML file over the current values (keys it leaves out keep theirs).
  void merge_file(const std::string& file);
  // Same for YAML text; `source` names it in messages.
  void merge_text(const std::string& yaml_text, const std::string& source);
  // "key=value", the value in YAML (so tables and lists may be given in flow style).
  // Errors name the source as --set.
  void apply_override(const std::string& assignment);
  // Sets one key (or a section or list item, from a YAML map) from YAML text.
  void set(const std::string& path, const std::string& yaml_value,
           const std::string& source = "--set");
  // Sets a number key to a value in its internal unit, range-checked.
  void set_number(const std::string& path, double value,
                  const std::string& source = "set_number");

  // For checks that involve several keys: where a value came from, its value in
  // display units ("15.8 mm"), "key = value (where)", and an error in the standard
  // form "<where>: <key> = <value>: <requirement>". A table row may be named as
  // "schedule.current[2]".
  const ConfigOrigin& origin(const std::string& path) const;
  bool is_default(const std::string& path) const;
  std::string display(const std::string& path) const;
  std::string describe(const std::string& path) const;
  [[noreturn]] void fail(const std::string& path, const std::string& requirement) const;

  // Every key with its value in display units, as YAML that loads back to the same
  // values.
  std::string to_yaml() const;

 private:
  struct Value {
    KeyKind kind = KeyKind::number;
    double number = 0;
    long long integer = 0;
    bool boolean = false;
    std::string text;
    ConfigTable table;
    std::vector<ConfigOrigin> row_origins;
    int n_items = 0;
    ConfigOrigin origin;
  };
  struct Loader;  // the YAML side, in config.cpp
  friend struct Loader;

  const Value& value(const std::string& path, KeyKind kind) const;

  ConfigSchema schema_;
  std::map<std::string, Value> values_;  // by concrete path; lists hold their size
};

// Defaults, then the file, then each override in order.
Config load_config(const ConfigSchema& schema, const std::string& file,
                   const std::vector<std::string>& overrides = {});

}  // namespace rsw::fem
