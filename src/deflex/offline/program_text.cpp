// Byte-exact program edits and the small text helpers the program readers share.
#include "deflex/offline/program_text.hpp"

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
  return 1 + static_cast<int>(std::count(
                 text.begin(), text.begin() + static_cast<std::ptrdiff_t>(std::min(offset, text.size())), '\n'));
}

std::size_t end_of_line(const std::string& text, std::size_t offset) {
  const std::size_t nl = text.find('\n', offset);
  return nl == std::string::npos ? text.size() : nl + 1;
}

std::string indentation_of(const std::string& text, std::size_t offset) {
  std::size_t begin = std::min(offset, text.size());
  while (begin > 0 && text[begin - 1] != '\n') {
    --begin;
  }
  std::size_t end = begin;
  while (end < text.size() && (text[end] == ' ' || text[end] == '\t')) {
    ++end;
  }
  return text.substr(begin, end - begin);
}

std::string line_terminator(const std::string& text) {
  const std::size_t nl = text.find('\n');
  return nl != std::string::npos && nl > 0 && text[nl - 1] == '\r' ? "\r\n" : "\n";
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
