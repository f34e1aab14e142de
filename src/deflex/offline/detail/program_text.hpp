// A robot program's text and the byte-exact edits made to it: compensating a program replaces some
// numbers and names and inserts some lines; every other byte must come out as it went in.
#pragma once

#include <string>
#include <vector>

namespace deflex {

/// Replace `length` bytes at `offset` by `replacement` (length 0: insert).
struct TextEdit {
  std::size_t offset = 0;
  std::size_t length = 0;
  std::string replacement;
};

/// The text with the edits applied. Edits may come in any order; overlapping edits are a
/// programming error (std::logic_error), two inserts at one offset keep their given order.
[[nodiscard]] std::string apply_edits(const std::string& text, std::vector<TextEdit> edits);

/// 1-based line number of a byte offset (lines end with LF, CR LF or a lone CR).
[[nodiscard]] int line_of(const std::string& text, std::size_t offset);

/// Offset just past the end of the line holding `offset` (past its LF, CR LF or CR, or the text's end).
[[nodiscard]] std::size_t end_of_line(const std::string& text, std::size_t offset);

/// The line's leading blanks (spaces and tabs) for the line holding `offset`.
[[nodiscard]] std::string indentation_of(const std::string& text, std::size_t offset);

/// The line terminator the text uses: its first line's ("\r\n", "\r" or "\n"; "\n" for one line).
[[nodiscard]] std::string line_terminator(const std::string& text);

/// A number as robot programs write it: fixed `decimals`, trailing zeros and a bare '.' dropped,
/// never "-0".
[[nodiscard]] std::string program_number(double value, int decimals);

/// Case-insensitive ASCII comparison (RAPID and KRL identifiers are case-insensitive).
[[nodiscard]] bool iequals(const std::string& a, const std::string& b);

/// ASCII upper case.
[[nodiscard]] std::string to_upper(std::string s);

}  // namespace deflex
