// Tokens of ABB RAPID and KUKA KRL source text, with their byte ranges and lines, so a reader can
// find numbers and names and the writer can replace exactly those bytes. Comments and blanks are
// skipped (they are never touched).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "deflex/text/parse_number.hpp"

namespace deflex {

enum class TokenKind {
  kIdentifier,  ///< RAPID: letter [letters digits _]; KRL: also $ and _ anywhere
  kNumber,      ///< unsigned: 12, 1.5, 9E+09 (a sign is a separate kPunct)
  kString,      ///< "..." with the quotes
  kBitLiteral,  ///< KRL 'B0110' or 'H1F' with the quotes
  kEnum,        ///< KRL #NAME
  kPunct,       ///< one character, or := == <> <= >=
};

struct Token {
  TokenKind kind = TokenKind::kPunct;
  std::size_t begin = 0;
  std::size_t end = 0;
  int line = 0;
};

/// A program file's text and tokens, with the file's name for messages: what the RAPID and KRL readers
/// look at.
struct ProgramSource {
  std::string file;
  const std::string& text;
  std::vector<Token> tok;

  [[nodiscard]] std::string str(std::size_t i) const;
  [[nodiscard]] bool is_ident(std::size_t i, const char* word = nullptr) const;  ///< word: case-insensitive
  [[nodiscard]] bool is_punct(std::size_t i, const char* p) const;
  /// The source text of tokens [b, e) on one line (blanks collapsed, at most 100 characters).
  [[nodiscard]] std::string span(std::size_t b, std::size_t e) const;
  /// Throws DataError "FILE:LINE: what" with the line of token i.
  [[noreturn]] void fail(std::size_t i, const std::string& what) const;
};

/// The tokens of a RAPID module. '!' starts a comment to the end of the line. Throws DataError
/// "FILE:LINE: ..." for an unterminated string or a character RAPID does not know.
[[nodiscard]] std::vector<Token> lex_rapid(const std::string& text, const std::string& file);

/// The tokens of a KRL .src or .dat file. ';' starts a comment to the end of the line (fold
/// markers included). Throws DataError "FILE:LINE: ..." for an unterminated string or literal.
[[nodiscard]] std::vector<Token> lex_krl(const std::string& text, const std::string& file);

/// The value of number token `i` of a RAPID or KRL source (anything with str(i) and fail(i, what)),
/// read locale-independently; "FILE:LINE: '1E999' is not a finite number" otherwise.
template <class Source>
[[nodiscard]] double token_number(const Source& s, std::size_t i) {
  const auto v = parse_double(s.str(i));
  if (!v) {
    s.fail(i, fmt::format("'{}' is not a finite number", s.str(i)));
  }
  return *v;
}

/// A number token used as an array size or index, truncated to int like the controller does;
/// beyond +-1e6 it is refused (no array is that large, and the cast would overflow).
template <class Source>
[[nodiscard]] int token_index(const Source& s, std::size_t i) {
  const double v = token_number(s, i);
  if (std::abs(v) > 1e6) {
    s.fail(i, fmt::format("'{}' is not an array size or index (within +-1000000)", s.str(i)));
  }
  return static_cast<int>(v);
}

}  // namespace deflex
