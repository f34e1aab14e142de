// Text deflex takes from files must be UTF-8: a name or a note goes into JSON documents, YAML files
// and messages, which all require it. A byte that is not (a robot name typed in Latin-1, a binary
// file given as a robot file) is refused naming the field, instead of failing later inside a writer.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace deflex {

/// The offset of the first byte that does not start or continue a valid UTF-8 sequence (overlong
/// forms, surrogates and code points above U+10FFFF included), or nullopt when the text is UTF-8.
[[nodiscard]] std::optional<std::size_t> invalid_utf8_at(std::string_view text);

/// nullopt for UTF-8 text, else "byte 0xE9 at position 7 is not UTF-8 (save the file as UTF-8)".
[[nodiscard]] std::optional<std::string> utf8_problem(std::string_view text);

}  // namespace deflex
