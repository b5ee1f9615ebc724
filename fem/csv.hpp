// The one CSV tokenizer of rsw's file readers (signal files, features files): records
// of a delimited text file, line by line, after RFC 4180 (https://www.rfc-editor.org/rfc/rfc4180):
// - a field may be enclosed in double quotes, and a quote inside it is written twice
//   ("current [kA]", "say ""hi""");
// - blank lines and lines starting with '#' (outside quotes) are skipped;
// - a UTF-8 byte order mark (EF BB BF) before the first line is dropped;
// - the delimiter is ',' unless the header (the first record) has ';' outside quotes and
//   no ',' outside quotes: then ';' (data-logger exports in European locales);
// - numbers are parsed locale-independently; with ';' as delimiter a decimal comma
//   ("1,5") is read as a decimal point.
// Fields are trimmed of blanks outside quotes. A quoted field ends on its line (no line
// breaks inside quotes). Debian's libcsv parses RFC 4180 but has none of the BOM,
// delimiter detection, comment lines or decimal commas above, so this file stands alone.
#pragma once

#include <istream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsw::fem {

// A malformed line; what() names the 1-based column ("column 3: ...") but not the file
// or line, which the reader's caller adds.
class CsvError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// ';' if `header_line` has ';' outside quotes and no ',' outside quotes, else ','.
char detect_csv_delimiter(const std::string& header_line);

// The fields of one line split at `delimiter` with RFC 4180 quoting, each unquoted and
// trimmed outside its quotes. Throws CsvError on an unterminated quote or text between
// a closing quote and the next delimiter.
std::vector<std::string> split_csv_line(const std::string& line, char delimiter);

// One finite number in a field (fem::parse_number); with delimiter ';' a decimal comma
// stands for the decimal point ("1,5" = 1.5).
bool parse_csv_number(const std::string& field, char delimiter, double& value);

class CsvReader {
 public:
  explicit CsvReader(std::istream& in) : in_(in) {}

  // The next record's fields, false at the end of the input. The first record is the
  // header; its line fixes the delimiter. Throws CsvError as split_csv_line does.
  bool next(std::vector<std::string>& fields);
  // next(), its CsvError rethrown as an Error whose message starts "<source>:<line>: ".
  template <class Error>
  bool next_or_throw(std::vector<std::string>& fields, const std::string& source) {
    try {
      return next(fields);
    } catch (const CsvError& error) {
      throw Error(source + ":" + std::to_string(line_number_) + ": " + error.what());
    }
  }
  // 1-based line of the record last returned.
  std::size_t line_number() const { return line_number_; }
  char delimiter() const { return delimiter_; }
  bool parse_number(const std::string& field, double& value) const {
    return parse_csv_number(field, delimiter_, value);
  }

 private:
  std::istream& in_;
  std::size_t line_number_ = 0;
  bool header_seen_ = false;
  char delimiter_ = ',';
};

}  // namespace rsw::fem
