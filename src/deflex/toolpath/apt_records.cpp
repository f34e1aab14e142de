// Joining APT/CL source lines into records.
#include <cctype>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/toolpath/detail/apt_interpreter.hpp"

namespace deflex::detail {
namespace {

constexpr std::size_t kMaxRecordBytes = 65536;

std::string_view ar_trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

/// ASCII upper case (the C library's toupper, a call per character, was a quarter of the reading).
char ar_up(char c) { return c >= 'a' && c <= 'z' ? static_cast<char>(c - 'a' + 'A') : c; }

std::string ar_upper(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = ar_up(c);
  return out;
}

/// The line without its "$$" comment.
std::string_view ar_code(std::string_view text) {
  const auto c = text.find("$$");
  return c == std::string_view::npos ? text : text.substr(0, c);
}

/// The major word of a record: its text up to '/' (or the whole record), blanks collapsed.
std::string ar_major(std::string_view head) {
  std::string out;
  bool blank = false;
  for (const char c : ar_trim(head)) {
    if (c == ' ' || c == '\t') {
      blank = true;
      continue;
    }
    if (blank && !out.empty()) out += ' ';
    blank = false;
    out += ar_up(c);
  }
  return out;
}

bool ar_text_record(const std::string& first_word) {
  return first_word == "PARTNO" || first_word == "PPRINT" || first_word == "INSERT" || first_word == "REMARK";
}

}  // namespace

bool AptRecordReader::next(AptRecord& out) {
  SourceLine line;
  while (lines_.next(line)) {
    // Text records keep their text whole ("PPRINT/'100 $ per part'").
    const std::string_view t = ar_trim(line.text);
    std::size_t word_end = 0;
    while (word_end < t.size() && std::isalpha(static_cast<unsigned char>(t[word_end])) != 0) ++word_end;
    const std::string first = ar_upper(t.substr(0, word_end));
    // Cleared, not replaced: the argument strings keep their storage from record to record.
    out.major.clear();
    out.args.clear();
    out.text.clear();
    out.line = line.number;
    if (ar_text_record(first)) {
      out.major = first;
      std::string_view rest = ar_trim(t.substr(word_end));
      if (!rest.empty() && rest.front() == '/') rest = ar_trim(rest.substr(1));
      out.text = std::string(rest);
      return true;
    }
    joined_.clear();
    std::string_view code = ar_trim(ar_code(line.text));
    while (!code.empty() && code.back() == '$') {
      joined_.append(code.substr(0, code.size() - 1));
      if (joined_.size() > kMaxRecordBytes) {
        throw DataError(
            fmt::format("{}:{}: a record longer than {} bytes", lines_.source(), out.line, kMaxRecordBytes));
      }
      if (!lines_.next(line)) {
        throw DataError(
            fmt::format("{}:{}: the record continues ('$') past the end of the file", lines_.source(), out.line));
      }
      code = ar_trim(ar_code(line.text));
    }
    joined_.append(code);
    const std::string_view record = ar_trim(joined_);
    if (record.empty()) continue;
    const auto slash = record.find('/');
    out.major = ar_major(record.substr(0, slash));
    if (slash != std::string_view::npos) {
      std::string_view rest = record.substr(slash + 1);
      while (true) {
        const auto comma = rest.find(',');
        const std::string_view arg = ar_trim(rest.substr(0, comma));
        if (arg.empty()) {
          throw DataError(fmt::format("{}:{}: record '{}': an empty argument", lines_.source(), out.line, out.major));
        }
        out.args.push_back(ar_upper(arg));
        if (comma == std::string_view::npos) break;
        rest = rest.substr(comma + 1);
      }
    }
    return true;
  }
  return false;
}

}  // namespace deflex::detail
