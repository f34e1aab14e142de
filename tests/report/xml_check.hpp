// A tiny well-formedness checker for the report's XML-style output (SVG, and the HTML written as
// XHTML): every tag closed in order, quoted attributes, no stray '<' or '&' in text.
#pragma once

#include <cctype>
#include <string>
#include <vector>

namespace deflex::test {

/// Empty when well formed, else what is wrong and where (byte offset).
inline std::string xml_problem(const std::string& doc) {
  std::vector<std::string> stack;
  std::size_t i = 0;
  const auto at = [&](std::size_t pos, const std::string& msg) { return msg + " at byte " + std::to_string(pos); };
  while (i < doc.size()) {
    const char ch = doc[i];
    if (ch == '&') {
      const std::size_t semi = doc.find(';', i);
      if (semi == std::string::npos || semi - i > 8) {
        return at(i, "unterminated entity");
      }
      const std::string ent = doc.substr(i + 1, semi - i - 1);
      const bool numeric =
          ent.size() > 1 && ent[0] == '#' && ent.find_first_not_of("0123456789", 1) == std::string::npos;
      if (!numeric && ent != "amp" && ent != "lt" && ent != "gt" && ent != "quot" && ent != "apos") {
        return at(i, "unknown entity &" + ent + ";");
      }
      i = semi + 1;
      continue;
    }
    if (ch == '>') {
      return at(i, "stray '>'");
    }
    if (ch != '<') {
      ++i;
      continue;
    }
    if (doc.compare(i, 4, "<!--") == 0) {
      const std::size_t e = doc.find("-->", i);
      if (e == std::string::npos) {
        return at(i, "unterminated comment");
      }
      i = e + 3;
      continue;
    }
    if (doc.compare(i, 2, "<!") == 0 || doc.compare(i, 2, "<?") == 0) {
      const std::size_t e = doc.find('>', i);
      if (e == std::string::npos) {
        return at(i, "unterminated declaration");
      }
      i = e + 1;
      continue;
    }
    // A tag: scan to its '>' honouring quoted attribute values.
    std::size_t j = i + 1;
    const bool closing = j < doc.size() && doc[j] == '/';
    if (closing) {
      ++j;
    }
    const std::size_t name_start = j;
    while (j < doc.size() &&
           (std::isalnum(static_cast<unsigned char>(doc[j])) != 0 || doc[j] == '-' || doc[j] == ':')) {
      ++j;
    }
    const std::string name = doc.substr(name_start, j - name_start);
    if (name.empty()) {
      return at(i, "'<' not starting a tag");
    }
    char quote = 0;
    while (j < doc.size() && (quote != 0 || doc[j] != '>')) {
      if (quote != 0) {
        if (doc[j] == quote) {
          quote = 0;
        } else if (doc[j] == '<') {
          return at(j, "'<' inside an attribute value");
        }
      } else if (doc[j] == '"' || doc[j] == '\'') {
        if (doc[j - 1] != '=') {
          return at(j, "quote not after '='");
        }
        quote = doc[j];
      } else if (doc[j] == '<') {
        return at(j, "'<' inside a tag");
      }
      ++j;
    }
    if (j >= doc.size()) {
      return at(i, "unterminated tag <" + name);
    }
    const bool self_closing = doc[j - 1] == '/';
    if (closing) {
      if (stack.empty() || stack.back() != name) {
        return at(i,
                  "</" + name + "> does not close <" + (stack.empty() ? std::string("nothing") : stack.back()) + ">");
      }
      stack.pop_back();
    } else if (!self_closing) {
      stack.push_back(name);
    }
    i = j + 1;
  }
  if (!stack.empty()) {
    return "unclosed <" + stack.back() + ">";
  }
  return "";
}

/// Number of occurrences of `needle`.
inline std::size_t count_of(const std::string& hay, const std::string& needle) {
  std::size_t n = 0;
  for (std::size_t p = hay.find(needle); p != std::string::npos; p = hay.find(needle, p + needle.size())) {
    ++n;
  }
  return n;
}

}  // namespace deflex::test
