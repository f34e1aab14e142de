// The write-back plan shared by the RAPID and KRL writers.
#include "deflex/offline/detail/program_write_back.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "deflex/offline/detail/program_text.hpp"

namespace deflex {

std::vector<WriteBackStep> plan_write_back(const std::vector<WriteBackUse>& uses,
                                           const std::map<std::string, int>& references) {
  std::map<std::string, int> resolved;  // resolved references per declaration name
  for (const WriteBackUse& u : uses) {
    if (u.target != nullptr) {
      ++resolved[u.name];
    }
  }
  std::vector<WriteBackStep> steps(uses.size());
  std::vector<char> done(uses.size(), 0);
  for (std::size_t a = 0; a < uses.size(); ++a) {
    if (uses[a].target == nullptr || done[a] != 0) {
      continue;  // a literal (the default step), or planned with its group
    }
    std::vector<std::size_t> group;
    for (std::size_t b = a; b < uses.size(); ++b) {
      if (uses[b].target == uses[a].target) {
        group.push_back(b);
        done[b] = 1;
      }
    }
    const auto it = references.find(uses[a].name);
    const bool only_resolved = it != references.end() && it->second == resolved[uses[a].name];
    const bool agree =
        std::all_of(group.begin(), group.end(), [&](std::size_t b) { return uses[b].numbers == uses[a].numbers; });
    std::vector<std::size_t> copies;  // the uses that declare a copy, one per distinct value
    for (const std::size_t b : group) {
      WriteBackStep& s = steps[b];
      if (only_resolved && agree) {
        s = {WriteBackStep::Kind::kInPlace, b == a, a};
        continue;
      }
      const auto same =
          std::find_if(copies.begin(), copies.end(), [&](std::size_t c) { return uses[c].numbers == uses[b].numbers; });
      s = {WriteBackStep::Kind::kCopy, same == copies.end(), same == copies.end() ? b : *same};
      if (s.first) {
        copies.push_back(b);
      }
    }
  }
  return steps;
}

void add_identifiers(const ProgramSource& source, std::set<std::string>& names) {
  for (std::size_t i = 0; i < source.tok.size(); ++i) {
    if (source.tok[i].kind == TokenKind::kIdentifier) {
      names.insert(to_upper(source.str(i)));
    }
  }
}

std::string copy_name(const std::string& base, const char* suffix, std::size_t max_length,
                      std::set<std::string>& taken) {
  for (int k = 1;; ++k) {
    const std::string tail = fmt::format("{}{}", suffix, k);
    std::string name = base.substr(0, std::min(base.size(), max_length - tail.size())) + tail;
    if (taken.insert(to_upper(name)).second) {
      return name;
    }
  }
}

}  // namespace deflex
