// The field log of the long-running subcommands (see field_log.hpp).
#include "field_log.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <optional>

#include <fmt/format.h>
#include <spdlog/sinks/base_sink.h>
#include <spdlog/sinks/stdout_sinks.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::cli {

namespace {

// The field log's file: every line appended with one checked write(2). spdlog's own file sink writes
// through a C stream and does not check its flush, so a full disk lost lines with no error at all
// (measured: `--log-file /dev/full` ran 4 s with exit 0); here a failed write throws, spdlog hands
// the failure to the logger's error handler, and the program names the file.
class CheckedFileSink final : public spdlog::sinks::base_sink<std::mutex> {
 public:
  explicit CheckedFileSink(std::string path) : path_(std::move(path)) {
    fd_ = ::open(path_.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw Error(fmt::format("{}: cannot append the log to it ({})", path_, std::strerror(errno)));
  }
  ~CheckedFileSink() override {
    if (fd_ >= 0) ::close(fd_);
  }
  CheckedFileSink(const CheckedFileSink&) = delete;
  CheckedFileSink& operator=(const CheckedFileSink&) = delete;

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    spdlog::memory_buf_t line;
    formatter_->format(msg, line);
    const char* at = line.data();
    std::size_t left = line.size();
    while (left > 0) {
      const ssize_t n = ::write(fd_, at, left);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw spdlog::spdlog_ex(fmt::format("writing to {} failed: {}", path_, std::strerror(errno)));
      at += n;
      left -= static_cast<std::size_t>(n);
    }
  }
  void flush_() override {}

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace

void add_log_options(CLI::App& sub, LogOptions& options) {
  sub.add_option("--log-level", options.level,
                 "Messages at this level and above: trace, debug, info, warn, error, critical or off")
      ->capture_default_str();
  sub.add_option("--log-file", options.file,
                 "Append the time-stamped messages to this file as well as printing them on stderr");
}

void FieldLogHealth::on_failure(const std::function<void(const std::string&)>& f) {
  std::string already;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    on_failure_ = f;
    already = error_;
  }
  if (!already.empty() && f) f(already);  // a line before the callback came failed already
}

std::string FieldLogHealth::error() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

void FieldLogHealth::failure(const std::string& what) {
  std::function<void(const std::string&)> tell;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!error_.empty()) return;
    error_ = what;
    tell = on_failure_;
  }
  failed_.store(true);
  if (tell) tell(what);
}

std::shared_ptr<spdlog::logger> make_field_logger(const std::string& name, const LogOptions& options,
                                                  const std::shared_ptr<FieldLogHealth>& health) {
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
    // A missing folder is made, as for every output of deflex (and kept: the log is appended at once).
    std::optional<OutputFolder> folder;
    const std::string parent = std::filesystem::path(options.file).parent_path().string();
    if (!parent.empty()) folder.emplace(parent, "option --log-file");
    std::FILE* probe = std::fopen(options.file.c_str(), "a");
    if (probe == nullptr) throw Error(fmt::format("option --log-file: {}: cannot append the log to it", options.file));
    std::fclose(probe);
    sinks.push_back(std::make_shared<CheckedFileSink>(options.file));
    if (folder) folder->keep();
  }
  auto logger = std::make_shared<spdlog::logger>(name, sinks.begin(), sinks.end());
  logger->set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%l] %v");
  logger->set_level(level->second);
  logger->flush_on(spdlog::level::trace);  // a line a second at most: every line reaches the file at once
  if (health && !options.file.empty()) {
    // spdlog catches a sink's failure and, by default, prints it on stderr and goes on: the file would
    // lose lines silently. The failure is kept instead (the other sinks still get the line).
    logger->set_error_handler([health, file = options.file](const std::string& message) {
      health->failure(fmt::format("the field log {} could not be written ({})", file, message));
    });
  }
  return logger;
}

}  // namespace deflex::cli
