// The tracker-file options `evaluate` and `register` share (format, units, columns, frame name).
#pragma once

#include <CLI/CLI.hpp>

#include "deflex/evaluate/tracker_files.hpp"

namespace deflex::cli {

void add_tracker_format_options(CLI::App& sub, TrackerReadOptions& options);

}  // namespace deflex::cli
