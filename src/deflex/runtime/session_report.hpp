// What an online session tells about itself, all of it off the loop's thread: the cycle log (every
// cycle, CSV), the fault dump (the last cycles, once per fault episode and at a stop for a fault), the
// status line every interval (every field with one meaning: "now" the last cycle's, "in the last N s"
// maxima or counts over that interval), the log lines that name a silence, a restart or a fault, and
// the summary (text and JSON): counts, the command against its two invariants, the answer time and
// late answers, the stop reason. Fed with the loop's entries (record_queue.hpp); the distributions are
// fixed histograms, so a long run does not grow memory.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>  // the declarations below; the caller includes <nlohmann/json.hpp> to use them

#include "deflex/runtime/cycle_log.hpp"
#include "deflex/runtime/monitor_feed.hpp"
#include "deflex/runtime/stop_reason.hpp"

namespace deflex::runtime {

enum class LogLevel { kInfo, kWarn, kError };
/// Where a session's messages go (the CLI: its spdlog field log; Python: the logging module or none).
using LogSink = std::function<void(LogLevel, const std::string&)>;

/// Quantiles from a fixed histogram of `bins` bins of width `bin` (values beyond fall in the last).
/// Thread safety: one thread at a time.
class Histogram {
 public:
  Histogram(double bin, std::size_t bins) : bin_(bin), counts_(bins, 0) {}
  void add(double v);
  /// The value below which a fraction q of the samples lie (to a bin); NaN when empty.
  [[nodiscard]] double quantile(double q) const;
  [[nodiscard]] double max() const { return max_; }
  [[nodiscard]] std::uint64_t count() const { return n_; }

 private:
  double bin_;
  std::vector<std::uint64_t> counts_;
  std::uint64_t n_ = 0;
  double max_ = 0.0;
};

struct ReportSetup {
  const char* link_name = "";
  int joints = 6;
  double period_s = 0.004;
  int force_components = 6;            ///< what the sensor measures (the cycle log's first line says it)
  double force_fault_n = 0.0;          ///< the sensor's fault threshold (the same)
  std::vector<ShownSetting> settings;  ///< what the session runs with (the log's "# setting: " lines)
  CommandLimits limits;
  bool streams_program = false;
  double program_start_s = 0.0, program_duration_s = 0.0;
  std::string log_path;   ///< "" no cycle log
  std::string dump_path;  ///< "" no fault dump file (episodes are still counted and named)
  std::size_t dump_cycles = 1000;
  double fault_quiet_s = 1.0;  ///< an episode ends after this long without a fault
  double status_interval_s = 1.0;
  bool collect = false;  ///< keep every cycle's record (Python's cycle log)
  LogSink sink;
  std::shared_ptr<MonitorFeed> monitor;  ///< the live page's data (null: no monitor)
  /// Called (on the reporter's thread) when an output of the session fails while it runs: the cycle
  /// log or a fault dump could not be written. The sentence names the file and why.
  std::function<void(const std::string&)> on_output_failure;
};

/// Thread safety: one thread at a time (the session's reporter thread, or the caller's service()
/// when stepped).
class SessionReporter {
 public:
  /// Opens the cycle log and checks the dump path (an unwritable one is an error now, not at the
  /// first fault). Throws Error naming the path.
  explicit SessionReporter(ReportSetup setup);

  void consume(const SessionEntry& e);
  /// A status line when one is due by `now_s` (the session's clock).
  void status_if_due(double now_s);
  /// The session ended: closes an open episode, writes the dump when the end was a fault, closes the
  /// cycle log (an Error from a failed write is logged and kept in log_error()).
  void end(double now_s, StopReason reason, const std::string& reason_text);

  [[nodiscard]] std::uint64_t cycles() const { return cycles_; }
  [[nodiscard]] std::uint64_t answers() const { return answers_; }
  [[nodiscard]] std::uint64_t late_answers() const { return late_answers_; }
  [[nodiscard]] std::uint64_t episodes() const { return episodes_; }
  [[nodiscard]] std::uint64_t faulted_cycles() const { return faulted_total_; }
  [[nodiscard]] std::uint64_t log_rows() const { return log_ ? log_->rows() : 0; }
  [[nodiscard]] const std::string& log_error() const { return log_error_; }
  [[nodiscard]] const Histogram& compute_us() const { return compute_us_; }
  [[nodiscard]] const Histogram& answer_ms() const { return answer_ms_; }
  [[nodiscard]] const Histogram& arrival_ms() const { return arrival_ms_; }
  [[nodiscard]] double largest_gap_s() const { return max_gap_s_; }
  /// How far behind real time the program ran at the end (streaming links), s.
  [[nodiscard]] double program_behind_s() const { return behind_s_; }
  [[nodiscard]] const std::vector<LinkCycleRecord>& collected() const { return collected_; }
  /// The timing of the summary as a sentence.
  [[nodiscard]] std::string timing_text() const;
  [[nodiscard]] nlohmann::json timing_json() const;

 private:
  void log(LogLevel level, const std::string& text) const;
  [[nodiscard]] CycleLogBounds bounds() const {
    return {rad_to_deg(setup_.limits.joint_bound_rad), setup_.limits.tcp_bound_m * 1e3};
  }
  [[nodiscard]] CycleLogInfo info() const {
    return {setup_.link_name, setup_.period_s, setup_.force_components, setup_.force_fault_n, setup_.settings};
  }
  void on_cycle(const SessionEntry& e);
  void keep(const SessionEntry& e);
  void tally(const LinkCycleRecord& r);
  void note_silence_and_restart(const SessionEntry& e);
  void track_faults(const SessionEntry& e);
  void begin_episode(const SessionEntry& e);
  void write_dump(const std::string& why);
  std::string status_line(double now_s);

  ReportSetup setup_;
  std::unique_ptr<CycleLogFile> log_;
  std::string log_error_;
  void output_failed(const std::string& text);
  // The last cycles, for the fault dump (a ring of entries).
  std::vector<SessionEntry> ring_;
  std::size_t ring_head_ = 0, ring_count_ = 0;
  // Totals.
  std::uint64_t cycles_ = 0, answers_ = 0, late_answers_ = 0;
  Histogram compute_us_{1.0, 20000};   // 1 us bins to 20 ms
  Histogram answer_ms_{0.01, 20000};   // 10 us bins to 200 ms
  Histogram arrival_ms_{0.01, 20000};  // 10 us bins to 200 ms
  double max_gap_s_ = 0.0, last_t_s_ = -1.0;
  double first_t_s_ = -1.0, first_program_s_ = 0.0, behind_s_ = 0.0;
  std::uint64_t last_restarts_ = 0, last_guard_trips_ = 0;
  // Fault episodes.
  bool in_episode_ = false;
  double episode_began_s_ = 0.0, last_fault_s_ = 0.0;
  std::uint64_t episodes_ = 0, faulted_ = 0, faulted_total_ = 0;
  // The interval since the last status line.
  double interval_start_s_ = -1.0, next_status_s_ = -1.0;
  std::uint64_t window_cycles_ = 0, window_answers_ = 0, window_late_ = 0;
  double window_compute_s_ = 0.0, window_gap_s_ = 0.0, window_dev_rad_ = 0.0, window_dev_m_ = 0.0,
         window_program_dev_rad_ = 0.0, window_step_fraction_ = 0.0, window_answer_s_ = 0.0;
  double window_program_start_s_ = 0.0, window_t_start_s_ = 0.0;
  LinkCounters at_window_start_;
  SessionEntry last_;
  void on_force_source(const SessionEntry& e);
  ForceSourceStats force_logged_;  // the counts last named in the log
  double faulty_logged_s_ = -1e300, re_request_logged_s_ = -1e300;
  bool have_last_ = false, have_cycle_ = false;
  std::vector<LinkCycleRecord> collected_;
};

/// Every counter of `c` by name, for JSON.
[[nodiscard]] nlohmann::json counters_json(const LinkCounters& c);

}  // namespace deflex::runtime
