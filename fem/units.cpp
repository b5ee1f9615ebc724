// UDUNITS-2 behind a small interface: unit spelling normalisation, parsing and
// conversion of config values (see units.hpp for the accepted syntax).
//
// UDUNITS-2's parser keeps global state and is not reentrant, and its status is a
// process-wide variable, so every call into the library holds one mutex. Config
// files hold a few hundred values at most; the lock costs nothing noticeable.
#include "fem/units.hpp"
#include "fem/text.hpp"

#include <udunits2.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

namespace rsw::fem {
namespace {

constexpr const char* default_database = "/usr/share/xml/udunits/udunits2.xml";

struct UnitSystem {
  ut_system* system = nullptr;
  std::mutex mutex;
};

UnitSystem& unit_system() {
  // Read once and never freed: units may be needed until the process ends, and a
  // static destructor would race with other static destructors that still convert.
  static UnitSystem* instance = [] {
    ut_set_error_message_handler(ut_ignore);
    // UDUNITS-2 names the database: UDUNITS2_XML_PATH if set (read by UDUNITS-2, not
    // by rsw), else the path it was built with (Debian: /usr/share/xml/udunits).
    ut_status status = UT_SUCCESS;
    const char* named = ut_get_path_xml(nullptr, &status);
    const std::string path = named != nullptr ? named : default_database;
    ut_system* system = ut_read_xml(path.c_str());
    if (system == nullptr) {
      throw UnitError("cannot read the UDUNITS-2 unit database '" + path +
                      "' (install libudunits2-data, or point UDUNITS2_XML_PATH at "
                      "udunits2.xml)");
    }
    auto* result = new UnitSystem;
    result->system = system;
    return result;
  }();
  return *instance;
}

using UnitPtr = std::unique_ptr<ut_unit, decltype(&ut_free)>;


bool is_word_char(char c) {
  return std::isalpha(static_cast<unsigned char>(c)) != 0 || c == '_';
}

// Rewrites the spellings UDUNITS-2 does not know into ones it does. The input is
// UTF-8; the multi-byte sequences are matched literally.
std::string normalise(const std::string& unit) {
  static const std::vector<std::pair<std::string, std::string>> replacements = {
      {"\xC2\xB0" "C", "degC"},   // °C
      {"\xC2\xB0", "arc_degree"},  // °
      {"\xC2\xB5", "u"},          // µ (micro sign)
      {"\xCE\xBC", "u"},          // μ (Greek mu)
      {"\xCE\xA9", "ohm"},        // Ω (Greek capital omega)
      {"\xE2\x84\xA6", "ohm"},    // Ω (ohm sign)
      {"\xC2\xB7", "*"},          // · (middle dot)
      {"\xC2\xB2", "^2"},         // ²
      {"\xC2\xB3", "^3"},         // ³
  };
  std::string text = trim(unit);
  if (text.empty() || text == "-") return "1";
  for (const auto& [from, to] : replacements) {
    for (auto pos = text.find(from); pos != std::string::npos;
         pos = text.find(from, pos + to.size())) {
      text.replace(pos, from.size(), to);
    }
  }
  // Whole-word 'deg': UDUNITS-2 knows 'degree' and 'arc_degree' but not 'deg'.
  std::string result;
  for (std::size_t i = 0; i < text.size();) {
    if (!is_word_char(text[i])) {
      result += text[i++];
      continue;
    }
    std::size_t end = i;
    while (end < text.size() && is_word_char(text[end])) ++end;
    const std::string word = text.substr(i, end - i);
    result += (word == "deg" || word == "degs") ? "arc_degree" : word;
    i = end;
  }
  return result;
}

std::vector<std::string> words(const std::string& text) {
  std::vector<std::string> result;
  for (std::size_t i = 0; i < text.size();) {
    if (!is_word_char(text[i])) {
      ++i;
      continue;
    }
    std::size_t end = i;
    while (end < text.size() && is_word_char(text[end])) ++end;
    result.push_back(text.substr(i, end - i));
    i = end;
  }
  return result;
}

// UDUNITS-2 makes the radian dimensionless; we tell angles apart by name so that an
// angle and a plain ratio never convert into each other.
bool names_angle(const std::string& normalised_unit) {
  static const char* const angle_words[] = {
      "rad",    "radian", "radians",        "mrad",      "urad",   "arc_degree",
      "degree", "degrees", "angular_degree", "arcdeg",   "arcmin", "arcminute",
      "arcminutes", "arcsec", "arcsecond",  "arcseconds"};
  for (const auto& word : words(normalised_unit)) {
    for (const char* angle : angle_words) {
      if (word == angle) return true;
    }
  }
  return false;
}

// Caller holds the mutex. Returns a null pointer for an unknown unit.
UnitPtr parse_locked(const std::string& normalised_unit) {
  // A unit starting with a number ("1 2", "1.0.5 mm") is a typo, not a scale factor.
  const char first = normalised_unit.empty() ? ' ' : normalised_unit[0];
  if (normalised_unit != "1" && normalised_unit.rfind("1/", 0) != 0 &&
      (std::isdigit(static_cast<unsigned char>(first)) != 0 || first == '.' ||
       first == '+' || first == '-')) {
    return UnitPtr(nullptr, &ut_free);
  }
  return UnitPtr(ut_parse(unit_system().system, normalised_unit.c_str(), UT_UTF8),
                 &ut_free);
}

// UDUNITS calls reciprocal units convertible (Hz and s, K and 1/K); a value may only
// change units within one dimension, i.e. when from/to is dimensionless.
// Caller holds the mutex.
bool same_dimension_locked(const ut_unit* a, const ut_unit* b) {
  if (ut_are_convertible(a, b) == 0) return false;
  UnitPtr ratio(ut_divide(a, b), &ut_free);
  UnitPtr one(ut_get_dimensionless_unit_one(unit_system().system), &ut_free);
  return ratio && ut_are_convertible(ratio.get(), one.get()) != 0;
}

bool convertible_locked(const ut_unit* from, const std::string& from_text,
                        const ut_unit* to, const std::string& to_text) {
  if (!same_dimension_locked(from, to)) return false;
  return names_angle(from_text) == names_angle(to_text);
}

// Caller holds the mutex.
std::string kind_locked(const std::string& normalised_unit) {
  static const std::vector<std::pair<const char*, const char*>> kinds = {
      {"m", "length"},
      {"m^2", "area"},
      {"m^3", "volume"},
      {"s", "time"},
      {"Hz", "frequency"},
      {"m/s", "velocity"},
      {"A", "electric current"},
      {"V", "electric potential"},
      {"ohm", "electrical resistance"},
      {"ohm*m", "electrical resistivity"},
      {"S/m", "electrical conductivity"},
      {"A/m^2", "current density"},
      {"N", "force"},
      {"Pa", "pressure"},
      {"Pa*s", "dynamic viscosity"},
      {"K", "temperature"},
      {"1/K", "thermal expansion coefficient"},
      {"kg", "mass"},
      {"kg/m^3", "density"},
      {"J", "energy"},
      {"J/kg", "specific energy"},
      {"J/(kg*K)", "specific heat capacity"},
      {"W", "power"},
      {"W/m^2", "heat flux"},
      {"W/m^3", "volumetric heat source"},
      {"W/(m*K)", "thermal conductivity"},
      {"W/(m^2*K)", "heat transfer coefficient"},
      {"m^2/s", "diffusivity"},
  };
  const UnitPtr unit = parse_locked(normalised_unit);
  if (!unit) return "unknown unit '" + normalised_unit + "'";
  const UnitPtr one = parse_locked("1");
  if (ut_are_convertible(unit.get(), one.get()) != 0) {
    return names_angle(normalised_unit) ? "plane angle" : "dimensionless number";
  }
  for (const auto& [reference, name] : kinds) {
    const UnitPtr candidate = parse_locked(reference);
    if (candidate && same_dimension_locked(unit.get(), candidate.get())) return name;
  }
  return "quantity in " + normalised_unit;
}

}  // namespace

Quantity split_quantity(const std::string& text) {
  const std::string s = trim(text);
  std::size_t i = 0;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  std::size_t n_digits = 0;
  while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])) != 0) {
    ++i;
    ++n_digits;
  }
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])) != 0) {
      ++i;
      ++n_digits;
    }
  }
  if (n_digits == 0) throw UnitError("'" + s + "' is not a number");
  // An exponent only if digits follow, so that "5eV" reads as 5 eV.
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    std::size_t j = i + 1;
    if (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
    if (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j])) != 0) {
      while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j])) != 0) ++j;
      i = j;
    }
  }
  Quantity quantity;
  errno = 0;
  quantity.value = std::strtod(s.substr(0, i).c_str(), nullptr);
  if (errno == ERANGE || !std::isfinite(quantity.value)) {
    throw UnitError("'" + s + "' is not a finite number");
  }
  quantity.unit = trim(s.substr(i));
  return quantity;
}

bool is_known_unit(const std::string& unit) {
  const std::string normalised = normalise(unit);
  UnitSystem& units = unit_system();
  const std::lock_guard<std::mutex> lock(units.mutex);
  return static_cast<bool>(parse_locked(normalised));
}

bool units_convertible(const std::string& from, const std::string& to) {
  const std::string from_text = normalise(from);
  const std::string to_text = normalise(to);
  UnitSystem& units = unit_system();
  const std::lock_guard<std::mutex> lock(units.mutex);
  const UnitPtr from_unit = parse_locked(from_text);
  const UnitPtr to_unit = parse_locked(to_text);
  return from_unit && to_unit &&
         convertible_locked(from_unit.get(), from_text, to_unit.get(), to_text);
}

double convert_units(double value, const std::string& from, const std::string& to) {
  const std::string from_text = normalise(from);
  const std::string to_text = normalise(to);
  UnitSystem& units = unit_system();
  const std::lock_guard<std::mutex> lock(units.mutex);
  const UnitPtr from_unit = parse_locked(from_text);
  if (!from_unit) throw UnitError("unknown unit '" + trim(from) + "'");
  const UnitPtr to_unit = parse_locked(to_text);
  if (!to_unit) throw UnitError("unknown unit '" + trim(to) + "'");
  if (!convertible_locked(from_unit.get(), from_text, to_unit.get(), to_text)) {
    throw UnitError("unit '" + trim(from) + "' (" + kind_locked(from_text) +
                    ") cannot be converted to '" + trim(to) + "' (" +
                    kind_locked(to_text) + ")");
  }
  cv_converter* converter = ut_get_converter(from_unit.get(), to_unit.get());
  if (converter == nullptr) {
    throw UnitError("no conversion from '" + trim(from) + "' to '" + trim(to) + "'");
  }
  const double result = cv_convert_double(converter, value);
  cv_free(converter);
  return result;
}

std::string quantity_kind(const std::string& unit) {
  const std::string normalised = normalise(unit);
  UnitSystem& units = unit_system();
  const std::lock_guard<std::mutex> lock(units.mutex);
  return kind_locked(normalised);
}

double parse_quantity(const std::string& text, const std::string& unit,
                      const std::string& bare_unit) {
  const Quantity quantity = split_quantity(text);
  return convert_units(quantity.value, quantity.unit.empty() ? bare_unit : quantity.unit,
                       unit);
}

}  // namespace rsw::fem
