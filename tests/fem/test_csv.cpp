// The CSV tokenizer (fem/csv.hpp): RFC 4180 quoting, a UTF-8 BOM, comment lines, the ';'
// delimiter detected from the header, decimal commas only with ';'.
#include "fem/csv.hpp"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

using rsw::fem::CsvError;
using rsw::fem::CsvReader;
using Fields = std::vector<std::string>;

TEST(Csv, SplitsQuotedFieldsWithDoubledQuotesAndDelimitersInside) {
  EXPECT_EQ(rsw::fem::split_csv_line(R"("time [ms]", "say ""hi""" ,"a,b",plain , )", ','),
            (Fields{"time [ms]", "say \"hi\"", "a,b", "plain", ""}));
  EXPECT_EQ(rsw::fem::split_csv_line(R"("";x)", ';'), (Fields{"", "x"}));
}

TEST(Csv, MalformedQuotesNameTheColumn) {
  try {
    rsw::fem::split_csv_line(R"(a, "b)", ',');
    FAIL() << "an unterminated quote was accepted";
  } catch (const CsvError& error) {
    EXPECT_NE(std::string(error.what()).find("column 2: a quoted field has no closing quote"), std::string::npos)
        << error.what();
  }
  try {
    rsw::fem::split_csv_line(R"(a;b;"c"d)", ';');
    FAIL() << "text after a closing quote was accepted";
  } catch (const CsvError& error) {
    EXPECT_NE(std::string(error.what()).find("column 3: text after the closing quote"), std::string::npos)
        << error.what();
  }
}

TEST(Csv, DetectsTheSemicolonDelimiterFromTheHeaderOnly) {
  EXPECT_EQ(rsw::fem::detect_csv_delimiter("time [ms];current [kA]"), ';');
  EXPECT_EQ(rsw::fem::detect_csv_delimiter("time [ms],current [kA]"), ',');
  // A comma inside quotes does not count; a ';' next to an outside comma gives ','.
  EXPECT_EQ(rsw::fem::detect_csv_delimiter(R"("a,b";c)"), ';');
  EXPECT_EQ(rsw::fem::detect_csv_delimiter("a;b,c"), ',');
  EXPECT_EQ(rsw::fem::detect_csv_delimiter("time [ms]"), ',');
}

TEST(Csv, ReadsDecimalCommasOnlyWithTheSemicolonDelimiter) {
  double value = 0;
  EXPECT_TRUE(rsw::fem::parse_csv_number("1,5", ';', value));
  EXPECT_DOUBLE_EQ(value, 1.5);
  EXPECT_TRUE(rsw::fem::parse_csv_number("-2.25", ';', value));
  EXPECT_DOUBLE_EQ(value, -2.25);
  EXPECT_TRUE(rsw::fem::parse_csv_number("3,5e-3", ';', value));
  EXPECT_DOUBLE_EQ(value, 3.5e-3);
  EXPECT_FALSE(rsw::fem::parse_csv_number("1,5", ',', value));
  EXPECT_FALSE(rsw::fem::parse_csv_number("1.000,5", ';', value));  // no thousands separators
  EXPECT_FALSE(rsw::fem::parse_csv_number("1,0,5", ';', value));
}

TEST(Csv, ReaderDropsTheBomSkipsCommentsAndCountsLines) {
  std::istringstream in("\xEF\xBB\xBF\"time [ms]\";\"current [kA]\"\n# logger 7\n\n0;1,5\n 0,5 ; 2\n");
  CsvReader reader(in);
  Fields fields;
  ASSERT_TRUE(reader.next(fields));
  EXPECT_EQ(fields, (Fields{"time [ms]", "current [kA]"}));
  EXPECT_EQ(reader.line_number(), 1u);
  EXPECT_EQ(reader.delimiter(), ';');
  ASSERT_TRUE(reader.next(fields));
  EXPECT_EQ(fields, (Fields{"0", "1,5"}));
  EXPECT_EQ(reader.line_number(), 4u);
  ASSERT_TRUE(reader.next(fields));
  EXPECT_EQ(fields, (Fields{"0,5", "2"}));
  double value = 0;
  EXPECT_TRUE(reader.parse_number(fields[0], value));
  EXPECT_DOUBLE_EQ(value, 0.5);
  EXPECT_EQ(reader.line_number(), 5u);
  EXPECT_FALSE(reader.next(fields));
}
