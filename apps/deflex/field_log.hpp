// The field log of the long-running subcommands (`deflex online`): leveled, time-stamped lines on
// stderr and, with --log-file, appended to a file as well, through spdlog (Debian's libspdlog). It is
// for everything outside a link's cycle (start-up, status lines, faults, the summary); nothing inside
// poll() ever logs, so a flood of bad packets shows as counters, not as lines.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
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

/// What became of the --log-file: a line that could not be written to it (a full disk) is kept here,
/// never lost silently. Thread safety: any thread (the logger's lines come from the reporter's too).
class FieldLogHealth {
 public:
  /// Called once, with a sentence naming the file, when the first write fails (on the logging thread), or
  /// at once when one failed before.
  void on_failure(const std::function<void(const std::string&)>& f);
  [[nodiscard]] bool failed() const { return failed_.load(); }
  [[nodiscard]] std::string error() const;
  void failure(const std::string& what);

 private:
  std::atomic<bool> failed_{false};
  mutable std::mutex mutex_;
  std::string error_;
  std::function<void(const std::string&)> on_failure_;
};

/// The logger for `name`: "[2026-11-23 07:23:18.312] [info] ..." on stderr and in the file. Throws
/// InputError naming --log-level for an unknown level, Error naming the file when it cannot be opened
/// for appending (checked now, not at the first line). A write to the file that fails later goes to
/// `health` (when given) naming the file; the line still reaches stderr.
std::shared_ptr<spdlog::logger> make_field_logger(const std::string& name, const LogOptions& options,
                                                  const std::shared_ptr<FieldLogHealth>& health = nullptr);

}  // namespace deflex::cli
