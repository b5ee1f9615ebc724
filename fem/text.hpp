// Small text helpers shared by the file readers and writers (config, units, signal
// files, study and calibration results): trimming, lower case, a locale-independent
// number parse (reading CSV records: fem/csv.hpp); CSV cells, numbers as text, a text file.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace rsw::fem {

// `text` without leading and trailing blanks (space, tab, CR, LF).
std::string trim(const std::string& text);

// ASCII lower case.
std::string lower(std::string text);

// Levenshtein distance: the fewest single-character insertions, deletions and
// substitutions that turn `a` into `b` (for "did you mean" suggestions).
std::size_t edit_distance(const std::string& a, const std::string& b);

// Locale-independent parse of a whole field (std::from_chars, an optional leading '+');
// false unless the field is exactly one finite number.
bool parse_number(const std::string& field, double& value);

// A CSV cell: `text` as is, or in quotes (a quote doubled) when it holds a comma, a
// quote or a line break.
std::string csv_text(const std::string& text);

// `value` with `precision` significant digits ("nan" for NaN and infinities).
std::string number_text(double value, int precision = 17);

// Writes `text` to `path` (binary, replacing the file); throws std::runtime_error naming it.
void write_text_file(const std::filesystem::path& path, const std::string& text);

}  // namespace rsw::fem
