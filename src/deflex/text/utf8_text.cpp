// UTF-8 validation (RFC 3629: at most four bytes, no overlong forms, no surrogates).
#include "deflex/text/utf8_text.hpp"

#include <fmt/format.h>

namespace deflex {

std::optional<std::size_t> invalid_utf8_at(std::string_view text) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  std::size_t i = 0;
  while (i < text.size()) {
    const unsigned char c = byte(i);
    if (c < 0x80) {
      ++i;
      continue;
    }
    std::size_t n = 0;
    unsigned char lo = 0x80;  // the bounds of the second byte, which rule out overlong forms and surrogates
    unsigned char hi = 0xBF;
    if (c >= 0xC2 && c <= 0xDF) {
      n = 1;
    } else if (c >= 0xE0 && c <= 0xEF) {
      n = 2;
      lo = c == 0xE0 ? 0xA0 : 0x80;
      hi = c == 0xED ? 0x9F : 0xBF;
    } else if (c >= 0xF0 && c <= 0xF4) {
      n = 3;
      lo = c == 0xF0 ? 0x90 : 0x80;
      hi = c == 0xF4 ? 0x8F : 0xBF;
    } else {
      return i;
    }
    if (i + n >= text.size()) {
      return i;  // cut short at the end
    }
    if (byte(i + 1) < lo || byte(i + 1) > hi) {
      return i;
    }
    for (std::size_t k = 2; k <= n; ++k) {
      if ((byte(i + k) & 0xC0) != 0x80) {
        return i;
      }
    }
    i += n + 1;
  }
  return std::nullopt;
}

std::string windows1252_to_utf8(std::string_view text) {
  // Code page 1252's 0x80..0x9F (Microsoft's table, bestfit1252.txt); 0 where the code page defines
  // no character and the byte maps to the C1 control of the same value.
  static constexpr char16_t kHigh[32] = {0x20AC, 0,      0x201A, 0x0192, 0x201E, 0x2026, 0x2020, 0x2021,
                                         0x02C6, 0x2030, 0x0160, 0x2039, 0x0152, 0,      0x017D, 0,
                                         0,      0x2018, 0x2019, 0x201C, 0x201D, 0x2022, 0x2013, 0x2014,
                                         0x02DC, 0x2122, 0x0161, 0x203A, 0x0153, 0,      0x017E, 0x0178};
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    unsigned cp = c;
    if (c >= 0x80 && c <= 0x9F && kHigh[c - 0x80] != 0) {
      cp = kHigh[c - 0x80];
    }
    if (cp < 0x80) {
      out += static_cast<char>(cp);
    } else if (cp < 0x800) {
      out += static_cast<char>(0xC0 | (cp >> 6));
      out += static_cast<char>(0x80 | (cp & 0x3F));
    } else {
      out += static_cast<char>(0xE0 | (cp >> 12));
      out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (cp & 0x3F));
    }
  }
  return out;
}

std::optional<std::string> utf8_problem(std::string_view text) {
  const auto at = invalid_utf8_at(text);
  if (!at) {
    return std::nullopt;
  }
  return fmt::format("byte 0x{:02X} at position {} is not UTF-8 text (save the file as UTF-8)",
                     static_cast<unsigned char>(text[*at]), *at + 1);
}

}  // namespace deflex
