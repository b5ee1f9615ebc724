// Small text helpers shared by the file readers (config, units, signal files, study
// files): trimming, lower case, splitting a delimited line and a locale-independent
// number parse.
#pragma once

#include <string>
#include <vector>

namespace rsw::fem {

// `text` without leading and trailing blanks (space, tab, CR, LF).
std::string trim(const std::string& text);

// ASCII lower case.
std::string lower(std::string text);

// The fields of one line split at `delimiter`, each trimmed; "a, b,," → {"a", "b", "", ""}.
std::vector<std::string> split_fields(const std::string& line, char delimiter = ',');

// Locale-independent parse of a whole field (std::from_chars, an optional leading '+');
// false unless the field is exactly one finite number.
bool parse_number(const std::string& field, double& value);

}  // namespace rsw::fem
