// The field log of the long-running subcommands (see field_log.hpp).
#include "field_log.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <vector>

#include <fmt/format.h>
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_sinks.h>

#include "deflex/text/errors.hpp"

namespace deflex::cli {

void add_log_options(CLI::App& sub, LogOptions& options) {
  sub.add_option("--log-level", options.level,
                 "Messages at this level and above: trace, debug, info, warn, error, critical or off")
      ->capture_default_str();
  sub.add_option("--log-file", options.file,
                 "Append the time-stamped messages to this file as well as printing them on stderr");
}

std::shared_ptr<spdlog::logger> make_field_logger(const std::string& name, const LogOptions& options) {
  static constexpr std::array<std::pair<const char*, spdlog::level::level_enum>, 7> kLevels = {{
      {"trace", spdlog::level::trace},
      {"debug", spdlog::level::debug},
      {"info", spdlog::level::info},
      {"warn", spdlog::level::warn},
      {"error", spdlog::level::err},
      {"critical", spdlog::level::critical},
      {"off", spdlog::level::off},
  }};
  const auto* level =
      std::find_if(kLevels.begin(), kLevels.end(), [&](const auto& l) { return options.level == l.first; });
  if (level == kLevels.end()) {
    throw InputError(fmt::format(
        "option --log-level: '{}' is not one of trace, debug, info, warn, error, critical, off", options.level));
  }
  std::vector<spdlog::sink_ptr> sinks{std::make_shared<spdlog::sinks::stderr_sink_mt>()};
  if (!options.file.empty()) {
    // Checked with the C library first: spdlog would create missing directories on its own.
    std::FILE* probe = std::fopen(options.file.c_str(), "a");
    if (probe == nullptr) throw Error(fmt::format("option --log-file: {}: cannot append the log to it", options.file));
    std::fclose(probe);
    try {
      sinks.push_back(std::make_shared<spdlog::sinks::basic_file_sink_mt>(options.file, false));
    } catch (const spdlog::spdlog_ex& e) {
      throw Error(fmt::format("{}: cannot append the log to it ({})", options.file, e.what()));
    }
  }
  auto logger = std::make_shared<spdlog::logger>(name, sinks.begin(), sinks.end());
  logger->set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%l] %v");
  logger->set_level(level->second);
  logger->flush_on(spdlog::level::trace);  // a line a second at most: every line reaches the file at once
  return logger;
}

}  // namespace deflex::cli
