// How the compensated values of a program's targets go back into its text, the same for RAPID and
// KRL: a literal written in a motion is edited where it stands; a declared target is edited in
// place when every reference to it is a motion deflex resolved and all of them need the same
// values; otherwise each distinct value gets a copy declared after the original (uses that need
// the same values share one), and the original stays for the code that reads it.
#pragma once

#include <map>
#include <set>
#include <string>
#include <vector>

#include "deflex/offline/detail/program_tokens.hpp"

namespace deflex {

/// One resolved use of a target, as far as writing it back is concerned.
struct WriteBackUse {
  const void* target = nullptr;      ///< the declared target (array element) it reads; null: a literal in the motion
  std::string name;                  ///< the declaration's name, upper case (its references are counted by name)
  std::vector<std::string> numbers;  ///< the new numbers' text
};

/// What to do with one use.
struct WriteBackStep {
  enum class Kind { kLiteral, kInPlace, kCopy } kind = Kind::kLiteral;
  bool first = false;      ///< kInPlace: edit the declaration with this use's numbers; kCopy: declare the copy
  std::size_t source = 0;  ///< kCopy: the use that declares the copy this one reads (itself when first)
};

/// The steps, one a use. `references` counts every reference to a name in the program (upper case).
[[nodiscard]] std::vector<WriteBackStep> plan_write_back(const std::vector<WriteBackUse>& uses,
                                                         const std::map<std::string, int>& references);

/// Every identifier of `source`, upper case: the names a copy must not take.
void add_identifiers(const ProgramSource& source, std::set<std::string>& names);

/// `base` + `suffix` + k (k from 1 up) cut to at most `max_length` characters, the first one not in
/// `taken` (case-insensitive), which is then added to it: p1_c1, XP2_C1.
[[nodiscard]] std::string copy_name(const std::string& base, const char* suffix, std::size_t max_length,
                                    std::set<std::string>& taken);

}  // namespace deflex
