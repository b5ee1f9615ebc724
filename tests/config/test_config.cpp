// The generic config machinery (fem/config.hpp) on a small schema that knows nothing
// about welding: defaults, units, typed access, every class of bad input (each error
// must name where, which key, which value and what is allowed), --set overrides,
// the resolved-YAML echo and the schema exports.
#include "fem/config.hpp"

#include "tests/config/test_files.hpp"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

namespace rsw::fem {
namespace {

constexpr double pi = 3.14159265358979323846;

ConfigSchema part_schema() {
  ConfigSchema s("Part reference", "A test schema.");
  s.section("part", "One part.");
  s.number("part.length", "m", "mm").default_value("2 mm").range(Range::closed(0.1, 5))
      .doc("Length of the part.");
  s.number("part.temperature", "degC", "degC").default_value("20 degC")
      .range(Range::closed(-50, 500)).doc("Temperature.");
  s.number("part.angle", "rad", "deg").default_value("90 deg")
      .range(Range::open_closed(0, 180)).doc("Angle.");
  s.number("part.ratio", "1", "1").default_value("0.3").range(Range::closed(0, 1))
      .doc("A ratio.");
  s.integer("part.count").default_value("2").range(Range::closed(0, 4)).doc("A count.");
  s.boolean("part.enabled").default_value("true").doc("A switch.");
  s.string("part.label").default_value("first part").doc("A label.");
  s.identifier("part.material").default_value("DP1200").doc("A material name.");
  s.choice("part.mode", {"fast", "accurate"}).default_value("fast").doc("A mode.");
  s.list("part.layers").items(2, 3).default_value("[{}, {thickness: 1.5 mm}]")
      .doc("Layers, top to bottom.");
  s.identifier("part.layers[].material").default_value("steel").doc("Layer material.");
  s.number("part.layers[].thickness", "m", "mm").default_value("1 mm")
      .range(Range::closed(0.1, 5)).doc("Layer thickness.");
  s.section("load", "Loads.");
  s.table("load.current")
      .column("time", "s", "ms", Range::at_least(0))
      .column("current", "A", "kA", Range::closed(0, 100))
      .items(2, 100).increasing()
      .default_value("[[0 ms, 0 kA], [10 ms, 8 kA]]")
      .doc("Current over time.");
  s.list("load.boxes").items(0, 2).doc("Boxes.");
  s.number("load.boxes[].size", "m", "mm").default_value("1 mm")
      .range(Range::greater_than(0)).doc("Box size.");
  s.integer("load.boxes[].levels").default_value("1").range(Range::closed(0, 4))
      .doc("Box levels.");
  return s;
}

std::string write_file(const std::string& name, const std::string& text) {
  return rsw::test::write_test_file(name, text);
}

// The message of the ConfigError thrown by `action`, or a test failure.
template <class Action>
std::string error_of(Action action) {
  try {
    action();
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ConfigError thrown";
  return "";
}

std::string load_error(const std::string& yaml, const std::vector<std::string>& sets = {}) {
  const std::string path = write_file("case.yaml", yaml);
  return error_of([&] { load_config(part_schema(), path, sets); });
}

#define EXPECT_HAS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "missing '" << (part) << "' in: " << (text)

TEST(Config, DefaultsAreResolvedInInternalUnits) {
  const Config c(part_schema());
  EXPECT_DOUBLE_EQ(c.number("part.length"), 2e-3);
  EXPECT_DOUBLE_EQ(c.number("part.temperature"), 20.0);
  EXPECT_NEAR(c.number("part.angle"), pi / 2, 1e-15);
  EXPECT_DOUBLE_EQ(c.number("part.ratio"), 0.3);
  EXPECT_EQ(c.integer("part.count"), 2);
  EXPECT_TRUE(c.boolean("part.enabled"));
  EXPECT_EQ(c.text("part.label"), "first part");
  EXPECT_EQ(c.text("part.mode"), "fast");
  ASSERT_EQ(c.n_items("part.layers"), 2);
  EXPECT_DOUBLE_EQ(c.number("part.layers[0].thickness"), 1e-3);
  EXPECT_DOUBLE_EQ(c.number(item_path("part.layers", 1, "thickness")), 1.5e-3);
  EXPECT_EQ(c.text("part.layers[1].material"), "steel");
  EXPECT_EQ(c.n_items("load.boxes"), 0);
  const ConfigTable& current = c.table("load.current");
  ASSERT_EQ(current.n_rows(), 2);
  EXPECT_DOUBLE_EQ(current.rows[1][0], 0.010);
  EXPECT_DOUBLE_EQ(current.rows[1][1], 8000.0);
  EXPECT_EQ(current.column(1), (std::vector<double>{0.0, 8000.0}));
  EXPECT_TRUE(c.is_default("part.length"));
}

TEST(Config, FileValuesReplaceDefaultsAndConvertUnits) {
  const std::string path = write_file("values.yaml", R"(
part:
  length: 0.3 cm
  temperature: 300 K
  angle: 1 rad
  count: 3
  enabled: no
  label: "second: part"
  mode: accurate
  layers:
    - {thickness: 2 mm, material: copper}
    - {}
    - thickness: 500 um
load:
  current: [[0 ms, 0 kA], [5 ms, 4000 A], [0.02 s, 6 kA]]
  boxes:
    - {size: 2 mm, levels: 3}
)");
  const Config c = load_config(part_schema(), path);
  EXPECT_NEAR(c.number("part.length"), 3e-3, 1e-18);
  EXPECT_NEAR(c.number("part.temperature"), 26.85, 1e-12);
  EXPECT_DOUBLE_EQ(c.number("part.angle"), 1.0);
  EXPECT_EQ(c.integer("part.count"), 3);
  EXPECT_FALSE(c.boolean("part.enabled"));
  EXPECT_EQ(c.text("part.label"), "second: part");
  EXPECT_EQ(c.text("part.mode"), "accurate");
  ASSERT_EQ(c.n_items("part.layers"), 3);
  EXPECT_EQ(c.text("part.layers[0].material"), "copper");
  EXPECT_DOUBLE_EQ(c.number("part.layers[1].thickness"), 1e-3);  // item default
  EXPECT_DOUBLE_EQ(c.number("part.layers[2].thickness"), 0.5e-3);
  EXPECT_DOUBLE_EQ(c.table("load.current").rows[2][0], 0.02);
  EXPECT_DOUBLE_EQ(c.table("load.current").rows[1][1], 4000.0);
  EXPECT_EQ(c.integer("load.boxes[0].levels"), 3);
  EXPECT_EQ(c.origin("part.count").where(), path + ":6:10");
  EXPECT_FALSE(c.is_default("part.count"));
}

TEST(Config, BareNumberIsReadInDisplayUnit) {
  const std::string path = write_file("bare.yaml", "part: {length: 1.5, angle: 45}\n");
  const Config c = load_config(part_schema(), path);
  EXPECT_DOUBLE_EQ(c.number("part.length"), 1.5e-3);
  EXPECT_NEAR(c.number("part.angle"), pi / 4, 1e-15);
}

TEST(Config, DottedKeysInFileAddressNestedValues) {
  const std::string path =
      write_file("dotted.yaml", "part.length: 3 mm\npart.layers[1].thickness: 2 mm\n");
  const Config c = load_config(part_schema(), path);
  EXPECT_DOUBLE_EQ(c.number("part.length"), 3e-3);
  EXPECT_DOUBLE_EQ(c.number("part.layers[1].thickness"), 2e-3);
}

TEST(Config, EmptyFileGivesDefaults) {
  const std::string path = write_file("empty.yaml", "# nothing\n");
  EXPECT_DOUBLE_EQ(load_config(part_schema(), path).number("part.length"), 2e-3);
}

// --- every class of bad input ----------------------------------------------------

TEST(Config, MissingFileNamesFile) {
  const std::string message =
      error_of([] { load_config(part_schema(), "/nonexistent/case.yaml"); });
  EXPECT_HAS(message, "/nonexistent/case.yaml");
  EXPECT_HAS(message, "cannot open");
}

TEST(Config, MalformedYamlNamesFileLineAndColumn) {
  const std::string message = load_error("part:\n  length: 1 mm\n   count: 2\n");
  EXPECT_HAS(message, "case.yaml:3:");
  EXPECT_HAS(message, ": malformed YAML: illegal map value");
}

TEST(Config, UnknownKeySuggestsClosestKey) {
  const std::string message = load_error("part:\n  lenght: 3 mm\n");
  EXPECT_HAS(message, "case.yaml:2:3: part.lenght: unknown key");
  EXPECT_HAS(message, "did you mean 'part.length'?");
  EXPECT_HAS(message, "Keys allowed in 'part': length, temperature");
}

TEST(Config, UnknownKeyInWrongSectionSuggestsWhereItLives) {
  const std::string message = load_error("load:\n  length: 3 mm\n");
  EXPECT_HAS(message, "case.yaml:2:3: load.length: unknown key");
  EXPECT_HAS(message, "did you mean 'part.length'?");
}

TEST(Config, UnknownKeyInListItemNamesItem) {
  const std::string message = load_error("part:\n  layers:\n    - {thicknes: 1 mm}\n    - {}\n");
  EXPECT_HAS(message, "case.yaml:3:8: part.layers[0].thicknes: unknown key");
  EXPECT_HAS(message, "did you mean 'part.layers[0].thickness'?");
}

TEST(Config, MapWhereNumberExpectedNamesKeyAndExpectedKind) {
  const std::string message = load_error("part:\n  length: {value: 3}\n");
  EXPECT_HAS(message, "case.yaml:2:11: part.length:");
  EXPECT_HAS(message, "expected a length such as '2 mm'");
  EXPECT_HAS(message, "got a map");
}

TEST(Config, TextThatIsNotANumberNamesValueAndExample) {
  const std::string message = load_error("part:\n  length: long\n");
  EXPECT_HAS(message, "case.yaml:2:11: part.length: 'long' is not a number");
  EXPECT_HAS(message, "a length such as '2 mm'");
  EXPECT_HAS(message, "bare number is read in mm");
}

TEST(Config, IncompatibleUnitNamesBothKindsAndExample) {
  const std::string message = load_error("part:\n  length: 3 kN\n");
  EXPECT_HAS(message, "case.yaml:2:11: part.length: '3 kN' is a force, not a length");
  EXPECT_HAS(message, "such as '2 mm'");
}

TEST(Config, UnknownUnitNamesTheUnit) {
  const std::string message = load_error("part:\n  length: 3 mmm\n");
  EXPECT_HAS(message, "case.yaml:2:11: part.length: '3 mmm' has an unknown unit 'mmm'");
  EXPECT_HAS(message, "a length");
}

TEST(Config, OutOfRangeNamesKeyValueAndRange) {
  const std::string message = load_error("part:\n  length: 7 mm\n");
  EXPECT_HAS(message, "case.yaml:2:11: part.length: '7 mm' is out of range; allowed: [0.1, 5] mm");
}

TEST(Config, OutOfRangeInOtherUnitShowsDisplayValue) {
  const std::string message = load_error("part:\n  length: 0.7 cm\n");
  EXPECT_HAS(message, "'0.7 cm' (7 mm) is out of range; allowed: [0.1, 5] mm");
}

TEST(Config, InclusiveBoundAllowsConversionNoise) {
  const std::string path = write_file("bound.yaml", "part: {length: 0.5 cm}\n");
  EXPECT_NEAR(load_config(part_schema(), path).number("part.length"), 5e-3, 1e-15);
}

TEST(Config, ExclusiveBoundIsNamedAsOpen) {
  const std::string message = load_error("part:\n  angle: 0 deg\n");
  EXPECT_HAS(message, "part.angle: '0 deg' is out of range; allowed: (0, 180] deg");
}

TEST(Config, ListLengthOutsideLimitsNamesCountAndAllowed) {
  const std::string message =
      load_error("part:\n  layers:\n    - {}\n    - {}\n    - {}\n    - {}\n");
  EXPECT_HAS(message, "case.yaml:3:5: part.layers: 4 items given; allowed: 2 to 3 items");
}

TEST(Config, ListItemThatIsNotAMapNamesItem) {
  const std::string message = load_error("part:\n  layers: [{}, 3 mm]\n");
  EXPECT_HAS(message, "part.layers[1]: expected a map with keys material, thickness, got '3 mm'");
}

TEST(Config, NonMonotoneTableTimesNameRowValueAndRule) {
  const std::string message = load_error(
      "load:\n  current:\n    - [0 ms, 0 kA]\n    - [10 ms, 8 kA]\n    - [10 ms, 6 kA]\n");
  EXPECT_HAS(message, "case.yaml:5:8: load.current[2][0] (time): '10 ms' does not come after "
                      "the previous row's 10 ms; time must be strictly increasing");
}

TEST(Config, TableRowOfWrongLengthNamesRow) {
  const std::string message = load_error("load:\n  current: [[0 ms, 0 kA], [10 ms]]\n");
  EXPECT_HAS(message, "load.current[1]: a row of 1 values is not a row [time, current]");
}

TEST(Config, TableCellOutOfRangeNamesCellAndRange) {
  const std::string message = load_error("load:\n  current: [[0 ms, 0 kA], [10 ms, 150 kA]]\n");
  EXPECT_HAS(message, "load.current[1][1] (current): '150 kA' is out of range; allowed: [0, 100] kA");
}

TEST(Config, TableWithTooFewRowsNamesCount) {
  const std::string message = load_error("load:\n  current: [[0 ms, 0 kA]]\n");
  EXPECT_HAS(message, "load.current: 1 row given; allowed: 2 to 100 rows");
}

TEST(Config, BadChoiceListsChoicesAndSuggests) {
  const std::string message = load_error("part:\n  mode: acurate\n");
  EXPECT_HAS(message, "case.yaml:2:9: part.mode: 'acurate' is not an allowed choice; allowed: "
                      "'fast', 'accurate' (did you mean 'accurate'?)");
}

TEST(Config, BadIdentifierNamesAllowedCharacters) {
  const std::string message = load_error("part:\n  material: DP 1200\n");
  EXPECT_HAS(message, "part.material: 'DP 1200' is not a name; expected a name made of letters, "
                      "digits, '_' and '-'");
}

TEST(Config, IntegerRejectsFractionAndRange) {
  EXPECT_HAS(load_error("part: {count: 2.5}\n"), "part.count: '2.5' is not an integer");
  EXPECT_HAS(load_error("part: {count: 7}\n"), "part.count: '7' is out of range; allowed: [0, 4]");
}

TEST(Config, BooleanRejectsOtherWords) {
  EXPECT_HAS(load_error("part: {enabled: maybe}\n"),
             "part.enabled: 'maybe' is not a boolean; expected true or false");
}

TEST(Config, MissingValueIsNamed) {
  EXPECT_HAS(load_error("part:\n  length:\n"), "case.yaml:2:3: part.length: no value given");
}

TEST(Config, DuplicateKeyNamesFirstPlace) {
  const std::string message = load_error("part:\n  length: 1 mm\n  length: 2 mm\n");
  EXPECT_HAS(message, "case.yaml:3:3: part.length: key given twice (first at ");
  EXPECT_HAS(message, "case.yaml:2:3)");
}

TEST(Config, SectionThatIsNotAMapNamesKeys) {
  EXPECT_HAS(load_error("part: 3\n"), "part: expected a map with keys length, temperature");
}

// --- --set overrides -------------------------------------------------------------

TEST(Config, SetOverridesScalar) {
  Config c(part_schema());
  c.apply_override("part.length=3.5 mm");
  c.apply_override("part.mode = accurate");
  EXPECT_DOUBLE_EQ(c.number("part.length"), 3.5e-3);
  EXPECT_EQ(c.text("part.mode"), "accurate");
  EXPECT_EQ(c.origin("part.length").where(), "--set");
}

TEST(Config, SetOverridesAfterFile) {
  const std::string path = write_file("set.yaml", "part: {length: 3 mm}\n");
  const Config c = load_config(part_schema(), path, {"part.length=4 mm"});
  EXPECT_DOUBLE_EQ(c.number("part.length"), 4e-3);
}

TEST(Config, SetOverridesListItem) {
  Config c(part_schema());
  c.apply_override("part.layers[1].thickness=1.2 mm");
  EXPECT_DOUBLE_EQ(c.number("part.layers[1].thickness"), 1.2e-3);
  EXPECT_DOUBLE_EQ(c.number("part.layers[0].thickness"), 1e-3);
}

TEST(Config, SetReplacesWholeTableFromFlowText) {
  Config c(part_schema());
  c.apply_override("load.current=[[0 ms, 0 kA], [10 ms, 8 kA], [20 ms, 0 kA]]");
  const ConfigTable& t = c.table("load.current");
  ASSERT_EQ(t.n_rows(), 3);
  EXPECT_DOUBLE_EQ(t.rows[2][0], 0.020);
  EXPECT_DOUBLE_EQ(t.rows[1][1], 8000.0);
}

TEST(Config, SetReplacesWholeList) {
  Config c(part_schema());
  c.apply_override("part.layers=[{thickness: 2 mm}, {}, {material: copper}]");
  ASSERT_EQ(c.n_items("part.layers"), 3);
  EXPECT_DOUBLE_EQ(c.number("part.layers[0].thickness"), 2e-3);
  EXPECT_EQ(c.text("part.layers[2].material"), "copper");
}

TEST(Config, SetOnePastEndAppendsItemWithDefaults) {
  Config c(part_schema());
  c.apply_override("load.boxes[0].levels=3");
  ASSERT_EQ(c.n_items("load.boxes"), 1);
  EXPECT_EQ(c.integer("load.boxes[0].levels"), 3);
  EXPECT_DOUBLE_EQ(c.number("load.boxes[0].size"), 1e-3);
}

TEST(Config, SetPastEndNamesListSize) {
  Config c(part_schema());
  const std::string message = error_of([&] { c.apply_override("part.layers[5].thickness=1 mm"); });
  EXPECT_HAS(message, "--set: part.layers[5]: index 5 is past the end of a list of 2 items; "
                      "index 2 appends an item");
}

TEST(Config, SetUnknownKeyNamesSetAndSuggests) {
  Config c(part_schema());
  const std::string message = error_of([&] { c.apply_override("part.lenth=3 mm"); });
  EXPECT_HAS(message, "--set: part.lenth: unknown key; did you mean 'part.length'?");
}

TEST(Config, SetBadValueNamesSetKeyValueAndRange) {
  Config c(part_schema());
  const std::string message = error_of([&] { c.apply_override("part.layers[0].thickness=9 mm"); });
  EXPECT_HAS(message, "--set: part.layers[0].thickness: '9 mm' is out of range; allowed: [0.1, 5] mm");
}

TEST(Config, SetBadTableNamesSetAndRow) {
  Config c(part_schema());
  const std::string message =
      error_of([&] { c.apply_override("load.current=[[0 ms, 0 kA], [0 ms, 1 kA]]"); });
  EXPECT_HAS(message, "--set: load.current[1][0] (time): '0 ms' does not come after");
}

TEST(Config, SetWithoutEqualsIsRejected) {
  Config c(part_schema());
  EXPECT_HAS(error_of([&] { c.apply_override("part.length"); }),
             "--set: 'part.length' is not of the form key=value");
}

TEST(Config, SetIndexOnNonListIsRejected) {
  Config c(part_schema());
  EXPECT_HAS(error_of([&] { c.apply_override("part.length[0]=1 mm"); }),
             "'part.length' is a number, not a list");
}

TEST(Config, SetBelowListWithoutIndexShowsItemSyntax) {
  Config c(part_schema());
  EXPECT_HAS(error_of([&] { c.apply_override("part.layers.thickness=1 mm"); }),
             "--set: part.layers.thickness: 'part.layers' is a list and has no keys below it; "
             "address an item as part.layers[0].thickness");
}

TEST(Config, FailedOverrideLeavesConfigUnchanged) {
  Config c(part_schema());
  EXPECT_THROW(c.apply_override("load.boxes=[{size: 1 mm}, {size: -1 mm}]"), ConfigError);
  EXPECT_EQ(c.n_items("load.boxes"), 0);
  EXPECT_THROW(c.apply_override("load.boxes[0].levels=9"), ConfigError);
  EXPECT_EQ(c.n_items("load.boxes"), 0);
}

TEST(Config, SetNumberChecksRangeInInternalUnits) {
  Config c(part_schema());
  c.set_number("part.length", 4e-3);
  EXPECT_DOUBLE_EQ(c.number("part.length"), 4e-3);
  EXPECT_HAS(error_of([&] { c.set_number("part.length", 6e-3, "study"); }),
             "study: part.length: '6 mm' is out of range; allowed: [0.1, 5] mm");
}

// --- checks across keys, access errors ---------------------------------------------

TEST(Config, FailNamesOriginKeyValueAndRequirement) {
  const std::string path = write_file("cross.yaml", "part:\n  length: 4 mm\n");
  const Config c = load_config(part_schema(), path);
  EXPECT_HAS(error_of([&] { c.fail("part.length", "must be shorter than " + c.describe("part.layers[0].thickness")); }),
             "cross.yaml:2:11: part.length = 4 mm: must be shorter than part.layers[0].thickness = 1 mm (default)");
}

TEST(Config, TableRowHasItsOwnOrigin) {
  const std::string path =
      write_file("rows.yaml", "load:\n  current:\n    - [0 ms, 0 kA]\n    - [12 ms, 3 kA]\n");
  const Config c = load_config(part_schema(), path);
  EXPECT_EQ(c.origin("load.current[1]").where(), path + ":4:7");
  EXPECT_EQ(c.display("load.current[1]"), "[12 ms, 3 kA]");
}

TEST(Config, AccessToUndeclaredKeyOrWrongKindIsLogicError) {
  const Config c(part_schema());
  EXPECT_THROW(c.number("part.width"), std::logic_error);
  EXPECT_THROW(c.number("part.count"), std::logic_error);
  EXPECT_THROW(c.number("part.layers[2].thickness"), std::logic_error);
}

// --- echo and exports ----------------------------------------------------------------

TEST(Config, ResolvedYamlShowsEveryKeyInDisplayUnits) {
  Config c(part_schema());
  c.apply_override("part.length=0.25 cm");
  const std::string yaml = c.to_yaml();
  EXPECT_HAS(yaml, "length: 2.5 mm");
  EXPECT_HAS(yaml, "angle: 90 deg");
  EXPECT_HAS(yaml, "temperature: 20 degC");
  EXPECT_HAS(yaml, "current: [[0 ms, 0 kA], [10 ms, 8 kA]]");
  EXPECT_HAS(yaml, "boxes: []");
  EXPECT_HAS(yaml, "thickness: 1.5 mm");
}

TEST(Config, ResolvedYamlLoadsBackToTheSameValues) {
  Config c(part_schema());
  c.apply_override("part.length=0.3333333333333333 cm");
  c.apply_override("part.angle=1 rad");
  c.apply_override("part.label='a: b # c'");  // YAML: text with ": " is quoted
  c.apply_override("load.boxes[0].size=0.1234 in");
  const std::string path = write_file("echo.yaml", c.to_yaml());
  const Config back = load_config(part_schema(), path);
  EXPECT_EQ(back.number("part.length"), c.number("part.length"));
  EXPECT_EQ(back.number("part.angle"), c.number("part.angle"));
  EXPECT_EQ(back.number("load.boxes[0].size"), c.number("load.boxes[0].size"));
  EXPECT_EQ(back.text("part.label"), c.text("part.label"));
  EXPECT_EQ(back.to_yaml(), c.to_yaml());
}

TEST(ConfigSchema, MarkdownHasATablePerSectionWithEveryKey) {
  const std::string md = part_schema().to_markdown();
  EXPECT_HAS(md, "# Part reference");
  EXPECT_HAS(md, "## `part`");
  EXPECT_HAS(md, "## `load`");
  EXPECT_HAS(md, "| key | type | default | unit | allowed | doc |");
  EXPECT_HAS(md, "| `part.length` | length | `2 mm` | mm | [0.1, 5] mm | Length of the part. |");
  EXPECT_HAS(md, "| `part.layers[].thickness` | length |");
  EXPECT_HAS(md, "| `part.mode` | choice | `fast` | – | `fast`, `accurate` |");
  EXPECT_HAS(md, "2 to 100 rows [time, current]; time >= 0 ms; current [0, 100] kA; time strictly increasing");
}

TEST(ConfigSchema, JsonListsEveryKeyWithUnitsAndRanges) {
  const auto json = nlohmann::json::parse(part_schema().to_json());
  EXPECT_EQ(json["title"], "Part reference");
  ASSERT_EQ(json["keys"].size(), part_schema().keys().size());
  const auto& length = json["keys"][0];
  EXPECT_EQ(length["path"], "part.length");
  EXPECT_EQ(length["unit"], "m");
  EXPECT_EQ(length["display_unit"], "mm");
  EXPECT_EQ(length["range"]["max"], 5.0);
  EXPECT_EQ(length["quantity"], "length");
}

TEST(ConfigSchema, DeclaringAKeyTwiceIsALogicError) {
  ConfigSchema s("t", "");
  s.number("a.b", "m", "mm").default_value("1 mm").doc("x");
  EXPECT_THROW(s.number("a.b", "m", "mm"), std::logic_error);
  EXPECT_THROW(s.number("a", "m", "mm"), std::logic_error);      // a is a section
  EXPECT_THROW(s.number("a.b.c", "m", "mm"), std::logic_error);  // a.b is a key
  EXPECT_THROW(s.number("x[].y", "m", "mm"), std::logic_error);  // x is no list
  EXPECT_THROW(s.number("Bad.Name", "m", "mm"), std::logic_error);
}

TEST(ConfigSchema, BrokenDeclarationFailsOnFirstUse) {
  ConfigSchema no_doc("t", "");
  no_doc.number("a", "m", "mm").default_value("1 mm");
  EXPECT_THROW(Config{no_doc}, std::logic_error);
  ConfigSchema bad_unit("t", "");
  bad_unit.number("a", "m", "kA").default_value("1 mm").doc("x");
  EXPECT_THROW(Config{bad_unit}, std::logic_error);
  ConfigSchema bad_default("t", "");
  bad_default.number("a", "m", "mm").default_value("9 mm").range(Range::closed(0, 1)).doc("x");
  EXPECT_THROW(Config{bad_default}, std::logic_error);
}

}  // namespace
}  // namespace rsw::fem
