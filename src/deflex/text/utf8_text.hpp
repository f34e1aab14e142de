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

/// Windows-1252 text (what Windows programs write as "ANSI" in Western Europe and the Americas:
/// Spatial Analyzer's exports among them) as UTF-8: 0x00..0x7F as they are, 0xA0..0xFF as U+00A0..
/// U+00FF, 0x80..0x9F as the code page's table gives them (0x80 the euro sign U+20AC, 0x96 the en dash
/// U+2013 ...; the five bytes the code page leaves undefined as U+0081, U+008D, U+008F, U+0090 and
/// U+009D, as Windows maps them).
[[nodiscard]] std::string windows1252_to_utf8(std::string_view text);

/// nullopt for UTF-8 text, else "byte 0xE9 at position 7 is not UTF-8 (save the file as UTF-8)".
[[nodiscard]] std::optional<std::string> utf8_problem(std::string_view text);

}  // namespace deflex
