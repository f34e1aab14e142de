// Splitting a G-code line into words.
#include "deflex/toolpath/detail/gcode_words.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <system_error>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex::detail {
namespace {

bool words_is_letter(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }
bool words_is_digit(char c) { return c >= '0' && c <= '9'; }
bool words_is_blank(char c) { return c == ' ' || c == '\t'; }

/// A printable excerpt of the line from `at` for a message (at most 24 bytes).
std::string words_excerpt(std::string_view text, std::size_t at) {
  std::string out;
  for (std::size_t i = at; i < text.size() && out.size() < 24; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += std::isprint(c) != 0 ? static_cast<char>(c) : '?';
  }
  return out;
}

class LineSplitter {
 public:
  LineSplitter(std::string_view text, const std::string& source, std::size_t line, GcodeLine& out)
      : text_(text), source_(source), line_(line), out_(out) {}

  void run() {
    std::size_t i = skip_blanks(0);
    if (i < text_.size() && text_[i] == '%') {
      out_.delimiter = true;
      return;
    }
    if (i < text_.size() && text_[i] == '/') {
      fail(i,
           "a block-delete '/' (an optional block): deflex cannot know whether the control skips it; remove "
           "the '/' or the block");
    }
    std::size_t previous_end = std::string_view::npos;
    while ((i = skip_blanks(i)) < text_.size()) {
      const char c = text_[i];
      if (c == ';') {
        return;
      }
      if (c == '(') {
        const std::size_t close = text_.find(')', i);
        if (close == std::string_view::npos) {
          fail(i, "a comment '(' without its ')'");
        }
        i = close + 1;
        continue;
      }
      if (!words_is_letter(c)) {
        const bool expression = c == '#' || c == '[' || c == '=' || c == '@';
        fail(i, expression ? "a parameter or an expression: deflex reads programs with plain numbers only"
                           : "not a G-code word (a letter and a number)");
      }
      if (previous_end == i) {
        out_.compact = true;
      }
      i = read_word(i);
      previous_end = i;
    }
  }

 private:
  [[noreturn]] void fail(std::size_t at, const std::string& what) const {
    throw DataError(fmt::format("{}:{}: '{}': {}", source_, line_, words_excerpt(text_, at), what));
  }

  std::size_t skip_blanks(std::size_t i) const {
    while (i < text_.size() && words_is_blank(text_[i])) {
      ++i;
    }
    return i;
  }

  // A letter at `begin`: a word (letter, blanks, number), an indexed word (A3=number) or a keyword.
  std::size_t read_word(std::size_t begin) {
    std::size_t i = begin + 1;
    if (i < text_.size() && (words_is_letter(text_[i]) || text_[i] == '_')) {
      while (i < text_.size() && (words_is_letter(text_[i]) || words_is_digit(text_[i]) || text_[i] == '_')) {
        ++i;
      }
      out_.keywords.push_back(
          {text_.substr(begin, i - begin), static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(i)});
      return i;
    }
    GcodeWord w;
    w.letter = static_cast<char>(std::toupper(static_cast<unsigned char>(text_[begin])));
    w.begin = static_cast<std::uint32_t>(begin);
    // "A3=0.5": digits, then '=' (blanks allowed before it).
    std::size_t d = i;
    while (d < text_.size() && words_is_digit(text_[d])) {
      ++d;
    }
    if (d > i && skip_blanks(d) < text_.size() && text_[skip_blanks(d)] == '=') {
      const std::string_view index = text_.substr(i, d - i);
      if (index != "3") {
        fail(begin, "an address with an index other than 3 (deflex reads A3=, B3=, C3= tool-axis vectors only)");
      }
      w.index = 3;
      i = skip_blanks(skip_blanks(d) + 1);
    } else {
      i = skip_blanks(i);
      if (i < text_.size() && text_[i] == '=') {
        fail(begin, fmt::format("'{}=' assigns a value: write it as {}10.5 (letter and number)", w.letter, w.letter));
      }
    }
    return read_number(w, begin, i);
  }

  std::size_t read_number(GcodeWord& w, std::size_t begin, std::size_t i) {
    w.number_begin = static_cast<std::uint32_t>(i);
    if (i < text_.size() && (text_[i] == '+' || text_[i] == '-')) {
      ++i;
    }
    std::size_t digits = 0;
    while (i < text_.size() && words_is_digit(text_[i])) {
      ++i;
      ++digits;
    }
    if (i < text_.size() && text_[i] == '.') {
      ++i;
      std::size_t after = 0;
      while (i < text_.size() && words_is_digit(text_[i])) {
        ++i;
        ++after;
      }
      digits += after;
      w.decimals = static_cast<std::int16_t>(after > 100 ? 100 : after);
    }
    if (digits == 0) {
      fail(begin, fmt::format("the letter '{}' without a number", text_[begin]));
    }
    // The text is a sign, digits and a point, which std::from_chars reads (without the '+') as a
    // finite number unless it has hundreds of digits.
    std::string_view number = text_.substr(w.number_begin, i - w.number_begin);
    if (number.front() == '+') number.remove_prefix(1);
    const auto r = std::from_chars(number.data(), number.data() + number.size(), w.value);
    if (r.ec != std::errc() || r.ptr != number.data() + number.size() || !std::isfinite(w.value)) {
      fail(begin, not_a_number(number));
    }
    w.end = static_cast<std::uint32_t>(i);
    out_.words.push_back(w);
    return i;
  }

  std::string_view text_;
  const std::string& source_;
  std::size_t line_;
  GcodeLine& out_;
};

}  // namespace

void split_gcode_line(std::string_view text, const std::string& source, std::size_t line, GcodeLine& out) {
  out.clear();
  LineSplitter(text, source, line, out).run();
}

}  // namespace deflex::detail
