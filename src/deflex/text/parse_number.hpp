// The one place deflex turns text into numbers. Every reader (CSV, YAML, command-line options,
// key=value specs, robot programs) goes through these, so a number means the same everywhere:
// parsed with std::from_chars, independent of the process locale ("1,5" is never 1.5), the whole
// text consumed, and - for the checked forms - finite and inside the physical range of its field
// (input_ranges.hpp).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace deflex {

/// A decimal floating-point number ("12", "-1.5e3", "+0.25", ".5"), nothing before or after it.
/// "nan", "inf", hexadecimal floats and out-of-range magnitudes (1e999) give nullopt, as does
/// an empty text. Blanks around the text are the caller's to trim.
[[nodiscard]] std::optional<double> parse_double(std::string_view text);

/// A decimal integer ("42", "-3", "+7") that fits in int64, nothing before or after it.
[[nodiscard]] std::optional<std::int64_t> parse_int64(std::string_view text);

/// The text with blanks (space, tab, CR, LF) removed at both ends.
[[nodiscard]] std::string_view trim_view(std::string_view text);

/// The message for a text parse_double() refused: "'abc' is not a number", or "'nan' is not a finite
/// number" for NaN, infinities and magnitudes beyond a double (1e999).
[[nodiscard]] std::string not_a_number(std::string_view text);

/// How a double is written for a message: shortest round-trip form ("1e+308", "0.05").
[[nodiscard]] std::string number_text(double v);

}  // namespace deflex
