// RFC 4180 records with a BOM, comment lines, ';' delimiters and decimal commas; see csv.hpp.
#include "fem/csv.hpp"

#include "fem/text.hpp"

namespace rsw::fem {

char detect_csv_delimiter(const std::string& header_line) {
  bool quoted = false, comma = false, semicolon = false;
  for (char c : header_line) {
    if (c == '"') quoted = !quoted;
    else if (!quoted && c == ',') comma = true;
    else if (!quoted && c == ';') semicolon = true;
  }
  return semicolon && !comma ? ';' : ',';
}

std::vector<std::string> split_csv_line(const std::string& line, char delimiter) {
  std::vector<std::string> fields;
  std::size_t i = 0;
  const std::size_t n = line.size();
  while (true) {
    const std::string column = "column " + std::to_string(fields.size() + 1) + ": ";
    while (i < n && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::string field;
    if (i < n && line[i] == '"') {
      ++i;
      bool closed = false;
      while (i < n) {
        if (line[i] == '"') {
          if (i + 1 < n && line[i + 1] == '"') {
            field += '"';
            i += 2;
            continue;
          }
          closed = true;
          ++i;
          break;
        }
        field += line[i++];
      }
      if (!closed) throw CsvError(column + "a quoted field has no closing quote (quotes inside are doubled: \"\")");
      while (i < n && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
      if (i < n && line[i] != delimiter) {
        throw CsvError(column + "text after the closing quote of \"" + field + "\"; allowed: the delimiter '" +
                       std::string(1, delimiter) + "'");
      }
    } else {
      const auto end = line.find(delimiter, i);
      field = trim(line.substr(i, end == std::string::npos ? std::string::npos : end - i));
      i = end == std::string::npos ? n : end;
    }
    fields.push_back(std::move(field));
    if (i >= n) break;
    ++i;  // past the delimiter
  }
  return fields;
}

bool parse_csv_number(const std::string& field, char delimiter, double& value) {
  if (delimiter == ';' && field.find(',') != std::string::npos) {
    if (field.find(',') != field.rfind(',') || field.find('.') != std::string::npos) return false;
    std::string point = field;
    point[point.find(',')] = '.';
    return fem::parse_number(point, value);
  }
  return fem::parse_number(field, value);
}

bool CsvReader::next(std::vector<std::string>& fields) {
  std::string line;
  while (std::getline(in_, line)) {
    ++line_number_;
    if (line_number_ == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    const std::string text = trim(line);
    if (text.empty() || text[0] == '#') continue;
    if (!header_seen_) {
      delimiter_ = detect_csv_delimiter(text);
      header_seen_ = true;
    }
    fields = split_csv_line(text, delimiter_);
    return true;
  }
  return false;
}

}  // namespace rsw::fem
