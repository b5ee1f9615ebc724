// Unit parsing and conversion (fem/units.hpp): the suffixes engineers write in case
// files convert to the internal units (SI, degC, rad), bare numbers are read in the
// unit given, and mismatched units are refused with both kinds named.
#include "fem/units.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

namespace rsw::fem {
namespace {

constexpr double pi = 3.14159265358979323846;

TEST(Units, KiloampereSuffixConvertsToAmpere) {
  EXPECT_DOUBLE_EQ(parse_quantity("8 kA", "A", "kA"), 8000.0);
}

TEST(Units, MillimetreSuffixConvertsToMetre) {
  EXPECT_DOUBLE_EQ(parse_quantity("1.0 mm", "m", "mm"), 1.0e-3);
  EXPECT_DOUBLE_EQ(parse_quantity("1.5mm", "m", "mm"), 1.5e-3);
}

TEST(Units, BareNumberIsReadInTheGivenUnit) {
  EXPECT_DOUBLE_EQ(parse_quantity("1.0", "m", "mm"), 1.0e-3);
  EXPECT_DOUBLE_EQ(parse_quantity("0.5", "1", "1"), 0.5);
  EXPECT_DOUBLE_EQ(parse_quantity("150", "s", "ms"), 0.150);
}

TEST(Units, ForceAndTimeSuffixesConvertToSi) {
  EXPECT_DOUBLE_EQ(parse_quantity("3 kN", "N", "kN"), 3000.0);
  EXPECT_DOUBLE_EQ(parse_quantity("150 ms", "s", "ms"), 0.150);
}

TEST(Units, ResistivityProductUnitConverts) {
  EXPECT_DOUBLE_EQ(parse_quantity("2.1e-6 ohm*m", "ohm*m", "ohm*m"), 2.1e-6);
  EXPECT_NEAR(parse_quantity("2.1 uohm*m", "ohm*m", "ohm*m"), 2.1e-6, 1e-20);
}

TEST(Units, HeatTransferCoefficientAcceptsBothSpellings) {
  EXPECT_DOUBLE_EQ(parse_quantity("20 W/(m^2*K)", "W/(m^2*K)", "W/(m^2*K)"), 20.0);
  EXPECT_DOUBLE_EQ(parse_quantity("4e4 W/m2/K", "W/(m^2*K)", "W/(m^2*K)"), 4e4);
  EXPECT_DOUBLE_EQ(parse_quantity("35 W/(m*K)", "W/(m*K)", "W/(m*K)"), 35.0);
}

TEST(Units, CelsiusStaysCelsiusAndKelvinConvertsWithOffset) {
  EXPECT_DOUBLE_EQ(parse_quantity("1507 degC", "degC", "degC"), 1507.0);
  EXPECT_NEAR(parse_quantity("293.15 K", "degC", "degC"), 20.0, 1e-12);
  EXPECT_NEAR(parse_quantity("20 °C", "degC", "degC"), 20.0, 1e-12);
}

TEST(Units, DegreeConvertsToRadian) {
  EXPECT_NEAR(parse_quantity("120 deg", "rad", "deg"), 2 * pi / 3, 1e-15);
  EXPECT_NEAR(parse_quantity("120", "rad", "deg"), 2 * pi / 3, 1e-15);
  EXPECT_NEAR(parse_quantity("120 °", "rad", "deg"), 2 * pi / 3, 1e-15);
  EXPECT_NEAR(parse_quantity("2 rad", "rad", "deg"), 2.0, 1e-15);
}

TEST(Units, MicroPrefixAcceptsMicroSignGreekMuAndU) {
  EXPECT_NEAR(parse_quantity("1 um", "m", "um"), 1e-6, 1e-21);
  EXPECT_NEAR(parse_quantity("1 µm", "m", "um"), 1e-6, 1e-21);  // U+00B5
  EXPECT_NEAR(parse_quantity("1 μm", "m", "um"), 1e-6, 1e-21);  // U+03BC
}

TEST(Units, OmegaIsOhm) {
  EXPECT_NEAR(parse_quantity("2.1 µΩ·m", "ohm*m", "ohm*m"), 2.1e-6, 1e-20);
  EXPECT_DOUBLE_EQ(parse_quantity("150 µΩ", "ohm", "ohm"), 150e-6);
  EXPECT_DOUBLE_EQ(parse_quantity("3 Ω", "ohm", "ohm"), 3.0);
}

TEST(Units, IncompatibleUnitNamesBothKinds) {
  try {
    parse_quantity("3 kN", "m", "mm");
    FAIL() << "a force was accepted as a length";
  } catch (const UnitError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("kN"), std::string::npos) << message;
    EXPECT_NE(message.find("force"), std::string::npos) << message;
    EXPECT_NE(message.find("length"), std::string::npos) << message;
  }
}

TEST(Units, UnknownUnitIsReported) {
  EXPECT_FALSE(is_known_unit("mmm"));
  try {
    parse_quantity("1 furlongz", "m", "mm");
    FAIL() << "an unknown unit was accepted";
  } catch (const UnitError& e) {
    EXPECT_NE(std::string(e.what()).find("furlongz"), std::string::npos) << e.what();
  }
}

TEST(Units, TextThatIsNotANumberIsRefused) {
  EXPECT_THROW(split_quantity("abc"), UnitError);
  EXPECT_THROW(split_quantity("mm 1"), UnitError);
  EXPECT_THROW(split_quantity(""), UnitError);
  EXPECT_THROW(split_quantity("1e999 mm"), UnitError);
  EXPECT_THROW(parse_quantity("1 2", "m", "mm"), UnitError);
}

TEST(Units, SplitSeparatesNumberAndUnit) {
  const Quantity q = split_quantity("  2.1e-6 ohm*m ");
  EXPECT_DOUBLE_EQ(q.value, 2.1e-6);
  EXPECT_EQ(q.unit, "ohm*m");
  EXPECT_EQ(split_quantity("0.5").unit, "");
  EXPECT_DOUBLE_EQ(split_quantity("-.5e1").value, -5.0);
  // An 'e' not followed by digits starts the unit: 5 eV, not 5e(?)V.
  const Quantity ev = split_quantity("5eV");
  EXPECT_DOUBLE_EQ(ev.value, 5.0);
  EXPECT_EQ(ev.unit, "eV");
}

TEST(Units, AngleIsNotAPlainRatio) {
  EXPECT_FALSE(units_convertible("deg", "1"));
  EXPECT_FALSE(units_convertible("1", "rad"));
  EXPECT_TRUE(units_convertible("deg", "rad"));
  EXPECT_TRUE(units_convertible("%", "1"));
  EXPECT_THROW(parse_quantity("5 deg", "1", "1"), UnitError);
}

TEST(Units, QuantityKindNamesCommonUnits) {
  EXPECT_EQ(quantity_kind("mm"), "length");
  EXPECT_EQ(quantity_kind("kA"), "electric current");
  EXPECT_EQ(quantity_kind("kN"), "force");
  EXPECT_EQ(quantity_kind("ms"), "time");
  EXPECT_EQ(quantity_kind("degC"), "temperature");
  EXPECT_EQ(quantity_kind("deg"), "plane angle");
  EXPECT_EQ(quantity_kind("1"), "dimensionless number");
  EXPECT_EQ(quantity_kind("ohm*m"), "electrical resistivity");
  EXPECT_EQ(quantity_kind("W/m2/K"), "heat transfer coefficient");
  EXPECT_EQ(quantity_kind("W/(m*K)"), "thermal conductivity");
  EXPECT_EQ(quantity_kind("MPa"), "pressure");
}

TEST(Units, ConcurrentConversionsAgree) {
  // UDUNITS-2's parser is not reentrant; the wrapper serialises calls.
  std::vector<std::thread> threads;
  std::vector<int> n_wrong(4, 0);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([t, &n_wrong] {
      for (int i = 0; i < 200; ++i) {
        if (std::abs(parse_quantity("8 kA", "A", "kA") - 8000.0) > 1e-9) ++n_wrong[t];
        if (std::abs(parse_quantity("4e4 W/m2/K", "W/(m^2*K)", "1") - 4e4) > 1e-9) ++n_wrong[t];
      }
    });
  }
  for (auto& thread : threads) thread.join();
  for (int t = 0; t < 4; ++t) EXPECT_EQ(n_wrong[t], 0);
}

TEST(UnitsDeathTest, DatabasePathComesFromEnvironment) {
  // A fresh process, so that the database is read after the variable is set.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        setenv("UDUNITS2_XML_PATH", "/nonexistent/udunits2.xml", 1);
        try {
          parse_quantity("1 mm", "m", "mm");
        } catch (const UnitError& e) {
          const std::string message = e.what();
          std::exit(message.find("/nonexistent/udunits2.xml") != std::string::npos ? 3 : 4);
        }
        std::exit(5);
      },
      testing::ExitedWithCode(3), "");
}

}  // namespace
}  // namespace rsw::fem

// UDUNITS treats reciprocal units as convertible (it would turn 2 Hz into 0.5 s);
// a config value may only change units within one dimension.
TEST(Units, ReciprocalUnitsDoNotConvert) {
  EXPECT_FALSE(rsw::fem::units_convertible("Hz", "s"));
  EXPECT_FALSE(rsw::fem::units_convertible("K", "1/K"));
  EXPECT_FALSE(rsw::fem::units_convertible("m", "m^-1"));
  EXPECT_TRUE(rsw::fem::is_known_unit("1/K"));
  EXPECT_TRUE(rsw::fem::units_convertible("1/K", "K^-1"));
  EXPECT_THROW(rsw::fem::convert_units(2.0, "Hz", "s"), std::runtime_error);
}
