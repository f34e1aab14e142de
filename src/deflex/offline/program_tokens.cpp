// RAPID and KRL lexers.
#include "deflex/offline/detail/program_tokens.hpp"

#include <algorithm>
#include <cctype>

#include <fmt/format.h>

#include "deflex/offline/detail/program_text.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

bool is_digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }
bool is_alpha(char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0; }

/// A number at `i`: digits [. digits] [E [+-] digits]; returns its end.
std::size_t scan_number(const std::string& t, std::size_t i) {
  while (i < t.size() && is_digit(t[i])) {
    ++i;
  }
  if (i < t.size() && t[i] == '.') {
    ++i;
    while (i < t.size() && is_digit(t[i])) {
      ++i;
    }
  }
  if (i < t.size() && (t[i] == 'E' || t[i] == 'e')) {
    std::size_t j = i + 1;
    if (j < t.size() && (t[j] == '+' || t[j] == '-')) {
      ++j;
    }
    if (j < t.size() && is_digit(t[j])) {
      i = j;
      while (i < t.size() && is_digit(t[i])) {
        ++i;
      }
    }
  }
  return i;
}

struct Lexer {
  const std::string& text;
  const std::string& file;
  std::vector<Token> out;
  int line = 1;

  void push(TokenKind kind, std::size_t b, std::size_t e) { out.push_back({kind, b, e, line}); }

  [[noreturn]] void fail(const std::string& what) const { throw DataError(fmt::format("{}:{}: {}", file, line, what)); }

  /// Blanks, newlines, comments, strings, numbers and operators common to both languages; false
  /// when the character at `i` is none of them.
  bool common(std::size_t& i, char comment) {
    const char c = text[i];
    // A line ends with LF, CR LF or a lone CR (old Mac editors, some controllers' exports).
    if (c == '\n' || (c == '\r' && (i + 1 >= text.size() || text[i + 1] != '\n'))) {
      ++line;
      ++i;
      return true;
    }
    if (c == ' ' || c == '\t' || c == '\r' || c == '\f') {
      ++i;
      return true;
    }
    if (c == comment) {
      while (i < text.size() && text[i] != '\n' && text[i] != '\r') {
        ++i;
      }
      return true;
    }
    if (c == '"') {
      std::size_t j = i + 1;
      while (j < text.size() && text[j] != '"' && text[j] != '\n' && text[j] != '\r') {
        ++j;
      }
      if (j >= text.size() || text[j] != '"') {
        fail("string not closed on its line");
      }
      push(TokenKind::kString, i, j + 1);
      i = j + 1;
      return true;
    }
    if (is_digit(c) || (c == '.' && i + 1 < text.size() && is_digit(text[i + 1]))) {
      const std::size_t e = scan_number(text, i);
      push(TokenKind::kNumber, i, e);
      i = e;
      return true;
    }
    if (i + 1 < text.size()) {
      const std::string two = text.substr(i, 2);
      if (two == ":=" || two == "==" || two == "<>" || two == "<=" || two == ">=") {
        push(TokenKind::kPunct, i, i + 2);
        i += 2;
        return true;
      }
    }
    return false;
  }
};

}  // namespace

std::string ProgramSource::str(std::size_t i) const {
  return i < tok.size() ? text.substr(tok[i].begin, tok[i].end - tok[i].begin) : std::string();
}

bool ProgramSource::is_ident(std::size_t i, const char* word) const {
  return i < tok.size() && tok[i].kind == TokenKind::kIdentifier && (word == nullptr || iequals(str(i), word));
}

bool ProgramSource::is_punct(std::size_t i, const char* p) const {
  return i < tok.size() && tok[i].kind == TokenKind::kPunct && str(i) == p;
}

std::string ProgramSource::span(std::size_t b, std::size_t e) const {
  if (b >= e || b >= tok.size()) {
    return {};
  }
  const std::string s = text.substr(tok[b].begin, tok[std::min(e, tok.size()) - 1].end - tok[b].begin);
  std::string out;
  bool blank = false;
  for (const char c : s) {
    if (c == '\n' || c == '\r' || c == '\t' || c == ' ') {
      blank = true;
      continue;
    }
    if (blank && !out.empty()) {
      out += ' ';
    }
    blank = false;
    out += c;
  }
  return out.size() > 100 ? out.substr(0, 97) + "..." : out;
}

void ProgramSource::fail(std::size_t i, const std::string& what) const {
  throw DataError(fmt::format("{}:{}: {}", file, i < tok.size() ? tok[i].line : 0, what));
}

std::vector<Token> lex_rapid(const std::string& text, const std::string& file) {
  Lexer lx{text, file, {}};
  for (std::size_t i = 0; i < text.size();) {
    if (lx.common(i, '!')) {
      continue;
    }
    const char c = text[i];
    if (is_alpha(c)) {
      std::size_t j = i + 1;
      while (j < text.size() && (std::isalnum(static_cast<unsigned char>(text[j])) != 0 || text[j] == '_')) {
        ++j;
      }
      lx.push(TokenKind::kIdentifier, i, j);
      i = j;
      continue;
    }
    if (std::string("[](){},;:\\+-*/=<>.%").find(c) != std::string::npos || static_cast<unsigned char>(c) >= 0x80) {
      lx.push(TokenKind::kPunct, i, i + 1);
      ++i;
      continue;
    }
    lx.fail(fmt::format("unexpected character '{}'", c));
  }
  return lx.out;
}

std::vector<Token> lex_krl(const std::string& text, const std::string& file) {
  Lexer lx{text, file, {}};
  for (std::size_t i = 0; i < text.size();) {
    if (lx.common(i, ';')) {
      continue;
    }
    const char c = text[i];
    if (is_alpha(c) || c == '_' || c == '$') {
      std::size_t j = i + 1;
      while (j < text.size() &&
             (std::isalnum(static_cast<unsigned char>(text[j])) != 0 || text[j] == '_' || text[j] == '$')) {
        ++j;
      }
      lx.push(TokenKind::kIdentifier, i, j);
      i = j;
      continue;
    }
    if (c == '\'') {
      std::size_t j = i + 1;
      while (j < text.size() && text[j] != '\'' && text[j] != '\n' && text[j] != '\r') {
        ++j;
      }
      if (j >= text.size() || text[j] != '\'') {
        lx.fail("literal '...' not closed on its line");
      }
      lx.push(TokenKind::kBitLiteral, i, j + 1);
      i = j + 1;
      continue;
    }
    if (c == '#') {
      std::size_t j = i + 1;
      while (j < text.size() && (std::isalnum(static_cast<unsigned char>(text[j])) != 0 || text[j] == '_')) {
        ++j;
      }
      lx.push(TokenKind::kEnum, i, j);
      i = j;
      continue;
    }
    // Everything else is one punctuation character (KRL's &ACCESS lines, operators, brackets).
    lx.push(TokenKind::kPunct, i, i + 1);
    ++i;
  }
  return lx.out;
}

}  // namespace deflex
