// "Did you mean ...?" for every place that refuses an unknown name: command-line options, YAML
// keys, CSV columns, spec keys.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace deflex {

/// The candidate closest to `name` by edit distance (case-insensitive), if it is close enough to be
/// a likely typo (at most a third of the name's length, at least 2 edits allowed, and any
/// candidate equal but for case); else "".
[[nodiscard]] std::string nearest_name(std::string_view name, const std::vector<std::string>& candidates);

/// " (did you mean 'X'?)" or "" when nothing is near.
[[nodiscard]] std::string did_you_mean(std::string_view name, const std::vector<std::string>& candidates);

}  // namespace deflex
