// Physical units of configuration values: split "8 kA" into number and unit, and
// convert between units of the same kind of quantity.
//
// This is the one wrapper around UDUNITS-2 (Unidata); no other file includes it.
// Unit syntax is UDUNITS-2's: products with '*', '.' or a space, quotients with '/',
// powers as m^2 or m2, prefixes (k, M, m, u, n, ...). On top of it we accept the
// spellings engineers type: 'µ' or 'μ' for micro, 'Ω' for ohm, '·' for '*',
// '²'/'³' for powers, and 'deg' for the arc degree (UDUNITS-2 itself knows only
// 'degree', 'arc_degree' and '°'). Temperatures convert with their offsets
// (1507 degC = 1780.15 K). UDUNITS-2 treats the radian as dimensionless; we keep
// angles apart from plain numbers, so '5 deg' is never accepted as a ratio and '0.5'
// with unit '1' never as an angle.
//
// The unit database is read once, on first use (thread-safe), from the file named by
// the environment variable UDUNITS2_XML_PATH if it is set, else from Debian's
// /usr/share/xml/udunits/udunits2.xml. UDUNITS-2's own stderr messages are silenced;
// every failure is reported as a UnitError instead.
#pragma once

#include <stdexcept>
#include <string>

namespace rsw::fem {

class UnitError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A number and the unit text that followed it; `unit` is empty for a bare number.
struct Quantity {
  double value = 0;
  std::string unit;
};

// Splits "2.1e-6 ohm*m" into {2.1e-6, "ohm*m"} and "0.5" into {0.5, ""}. The number
// must come first and be finite; throws UnitError otherwise.
Quantity split_quantity(const std::string& text);

// True if `unit` is a unit UDUNITS-2 (with our extra spellings) understands.
// The empty string and "1" mean dimensionless.
bool is_known_unit(const std::string& unit);

// True if both units are known and measure the same kind of quantity.
bool units_convertible(const std::string& from, const std::string& to);

// `value` in unit `from`, expressed in unit `to` (offsets included, e.g. degC -> K).
// Throws UnitError naming the units and their kinds if they are unknown or
// incompatible.
double convert_units(double value, const std::string& from, const std::string& to);

// What `unit` measures, in words for messages: "length", "electric current",
// "temperature", "plane angle", "dimensionless number", ... Falls back to
// "quantity in <unit>" for combinations without a name.
std::string quantity_kind(const std::string& unit);

// Reads "8 kA" as a value in `unit`; a bare number is taken to be in `bare_unit`.
// Throws UnitError if the text is not a number, the unit is unknown or the unit is
// not convertible to `unit`.
double parse_quantity(const std::string& text, const std::string& unit,
                      const std::string& bare_unit);

}  // namespace rsw::fem
