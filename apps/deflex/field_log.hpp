// The field log of the long-running subcommands (`deflex online`): leveled, time-stamped lines on
// stderr and, with --log-file, appended to a file as well, through spdlog (Debian's libspdlog). It is
// for everything outside a link's cycle (start-up, status lines, faults, the summary); nothing inside
// poll() ever logs, so a flood of bad packets shows as counters, not as lines.
#pragma once

#include <memory>
#include <string>

#include <spdlog/logger.h>
#include <CLI/CLI.hpp>

namespace deflex::cli {

struct LogOptions {
  std::string level = "info";
  std::string file;
};

/// Adds --log-level and --log-file to `sub`.
void add_log_options(CLI::App& sub, LogOptions& options);

/// The logger for `name`: "[2026-11-23 07:23:18.312] [info] ..." on stderr and in the file. Throws
/// InputError naming --log-level for an unknown level, Error naming the file when it cannot be opened
/// for appending (checked now, not at the first line).
std::shared_ptr<spdlog::logger> make_field_logger(const std::string& name, const LogOptions& options);

}  // namespace deflex::cli
