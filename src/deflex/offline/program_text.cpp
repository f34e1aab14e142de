// Byte-exact program edits and the small text helpers the program readers share.
#include "deflex/offline/detail/program_text.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace deflex {

std::string apply_edits(const std::string& text, std::vector<TextEdit> edits) {
  std::stable_sort(edits.begin(), edits.end(),
                   [](const TextEdit& a, const TextEdit& b) { return a.offset < b.offset; });
  std::string out;
  out.reserve(text.size() + 256);
  std::size_t at = 0;
  for (const TextEdit& e : edits) {
    if (e.offset < at || e.offset + e.length > text.size()) {
      throw std::logic_error(
          fmt::format("apply_edits: edit at {} (+{}) overlaps another or leaves the text", e.offset, e.length));
    }
    out.append(text, at, e.offset - at);
    out += e.replacement;
    at = e.offset + e.length;
  }
  out.append(text, at, std::string::npos);
  return out;
}

int line_of(const std::string& text, std::size_t offset) {
  int line = 1;
  const std::size_t end = std::min(offset, text.size());
  for (std::size_t i = 0; i < end; ++i) {
    // LF, CR LF (counted at its LF) and a lone CR each end a line.
    line += text[i] == '\n' || (text[i] == '\r' && (i + 1 >= text.size() || text[i + 1] != '\n')) ? 1 : 0;
  }
  return line;
}

std::size_t end_of_line(const std::string& text, std::size_t offset) {
  const std::size_t at = text.find_first_of("\r\n", offset);
  if (at == std::string::npos) {
    return text.size();
  }
  return text[at] == '\r' && at + 1 < text.size() && text[at + 1] == '\n' ? at + 2 : at + 1;
}

std::string indentation_of(const std::string& text, std::size_t offset) {
  std::size_t begin = std::min(offset, text.size());
  while (begin > 0 && text[begin - 1] != '\n' && text[begin - 1] != '\r') {
    --begin;
  }
  std::size_t end = begin;
  while (end < text.size() && (text[end] == ' ' || text[end] == '\t')) {
    ++end;
  }
  return text.substr(begin, end - begin);
}

std::string line_terminator(const std::string& text) {
  const std::size_t at = text.find_first_of("\r\n");
  if (at == std::string::npos || text[at] == '\n') {
    return "\n";
  }
  return at + 1 < text.size() && text[at + 1] == '\n' ? "\r\n" : "\r";
}

std::string program_number(double value, int decimals) {
  const double resolution = std::pow(10.0, -decimals);
  if (std::abs(value) < 0.5 * resolution) {
    value = 0.0;
  }
  std::string s = fmt::format("{:.{}f}", value, decimals);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') {
      s.pop_back();
    }
    if (s.back() == '.') {
      s.pop_back();
    }
  }
  return s == "-0" ? "0" : s;
}

bool iequals(const std::string& a, const std::string& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::toupper(static_cast<unsigned char>(x)) == std::toupper(static_cast<unsigned char>(y));
         });
}

std::string to_upper(std::string s) {
  for (char& c : s) {
    c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  return s;
}

}  // namespace deflex
