// One G-code line split into its words, with where each word stands in the line (the write-back
// replaces numbers in place). Comments "( )" and ";", '%' lines and blanks between a letter and its
// number ("X 10.5") are understood here; what a word means is the interpreter's business.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace deflex::detail {

struct GcodeWord {
  char letter = 0;         ///< 'A'..'Z' (upper case)
  std::uint8_t index = 0;  ///< 0 for a plain word; 3 for Siemens' A3=, B3=, C3=
  double value = 0.0;
  std::uint32_t begin = 0;         ///< first byte of the word in the line (its letter)
  std::uint32_t end = 0;           ///< one past its number's last byte
  std::uint32_t number_begin = 0;  ///< first byte of its number
  std::int16_t decimals = -1;      ///< digits after the decimal point; -1 without one
  /// The word as written ("G01", "X 10.5", "A3=0.5"), for messages.
  [[nodiscard]] std::string_view text(std::string_view line) const { return line.substr(begin, end - begin); }
};

/// A run of letters that is not a word ("TRAORI", "ORIWKS").
struct GcodeKeyword {
  std::string_view name;  ///< as written (points into the line)
  std::uint32_t begin = 0;
  std::uint32_t end = 0;
};

struct GcodeLine {
  std::vector<GcodeWord> words;
  std::vector<GcodeKeyword> keywords;
  bool delimiter = false;  ///< a '%' line (program start or end marker): nothing else on it counts
  bool compact = false;    ///< two of its words touch ("G1X10Y5"): words the write-back adds touch too
  void clear() {
    words.clear();
    keywords.clear();
    delimiter = false;
    compact = false;
  }
};

/// Splits `text` into `out` (cleared first; its vectors keep their capacity). Throws DataError
/// "SOURCE:LINE: ..." naming the text that is not a word: an unclosed '(' comment, a block-delete
/// '/', a parameter or expression ('#', '['), a letter without a number.
void split_gcode_line(std::string_view text, const std::string& source, std::size_t line, GcodeLine& out);

}  // namespace deflex::detail
