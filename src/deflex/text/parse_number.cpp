// Locale-independent number parsing (std::from_chars) for every deflex reader.
#include "deflex/text/parse_number.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <system_error>

#include <fmt/format.h>

namespace deflex {

std::string_view trim_view(std::string_view text) {
  constexpr std::string_view kBlanks = " \t\r\n";
  const auto b = text.find_first_not_of(kBlanks);
  if (b == std::string_view::npos) {
    return {};
  }
  const auto e = text.find_last_not_of(kBlanks);
  return text.substr(b, e - b + 1);
}

std::optional<double> parse_double(std::string_view text) {
  // from_chars takes no leading '+'; users write "+0.5" in files, so accept exactly one.
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
    if (!text.empty() && (text.front() == '+' || text.front() == '-')) {
      return std::nullopt;
    }
  }
  if (text.empty()) {
    return std::nullopt;
  }
  // Only decimal digits, a point, a sign and an exponent: from_chars would also take "nan",
  // "inf" and "infinity", which are not values of any deflex field.
  for (const char c : text) {
    const bool ok = (c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E';
    if (!ok) {
      return std::nullopt;
    }
  }
  double v = 0.0;
  const char* end = text.data() + text.size();
  const auto r = std::from_chars(text.data(), end, v, std::chars_format::general);
  if (r.ec != std::errc() || r.ptr != end || !std::isfinite(v)) {
    return std::nullopt;  // includes result_out_of_range (1e999, and 1e-999 underflow)
  }
  return v;
}

std::optional<std::int64_t> parse_int64(std::string_view text) {
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
    if (!text.empty() && text.front() == '-') {
      return std::nullopt;
    }
  }
  if (text.empty()) {
    return std::nullopt;
  }
  std::int64_t v = 0;
  const char* end = text.data() + text.size();
  const auto r = std::from_chars(text.data(), end, v, 10);
  if (r.ec != std::errc() || r.ptr != end) {
    return std::nullopt;
  }
  return v;
}

std::string not_a_number(std::string_view text) {
  std::string lower;
  for (const char c : text) {
    lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  const bool non_finite = lower.find("nan") != std::string::npos || lower.find("inf") != std::string::npos ||
                          lower.find('e') != std::string::npos;
  return fmt::format("'{}' is not a {}number", text, non_finite ? "finite " : "");
}

std::string number_text(double v) { return fmt::format("{}", v); }

}  // namespace deflex
