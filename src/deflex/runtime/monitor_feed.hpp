// What the live monitor page shows, collected off the loop's thread: the session's reporter (which
// already receives every cycle through the lock-free ring of record_queue.hpp) hands each cycle here,
// and the monitor's HTTP threads read published snapshots. The loop never touches this. The writer
// never waits for a reader either: rows go into fixed blocks that readers only read below the
// published row count, and a new snapshot (a few pointers) is published with a try-lock, so a reader
// holding the lock (a starved low-priority server thread) only makes the writer publish later.
// A recorded cycle log (deflex monitor --log) fills the same feed, so the page is the same.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "deflex/runtime/record_queue.hpp"
#include "deflex/runtime/shown_setting.hpp"

namespace deflex::runtime {

/// One cycle as the page draws it (units as shown: N, Nm, deg, mm, ms).
struct MonitorRow {
  double t_s = 0.0, program_t_s = 0.0;
  std::uint64_t sequence = 0;
  int status = 0;            ///< CycleStatus
  bool replied = true;       ///< the cycle was answered (answer_ms is its answer time)
  double wrench[6] = {};     ///< conditioned wrench the model used, base frame: N, Nm
  double raw_force[3] = {};  ///< the sensor's force in the base frame, N
  double dtheta_deg[kMaxJoints] = {};
  double tcp_mm[3] = {};
  double delay_ms = 0.0, answer_ms = 0.0, arrival_ms = 0.0, jitter_ms = 0.0;
  /// The link's counts since the session began. `late` is the link's count of messages that arrived
  /// more than a cycle after the quickest recent one (the cycle log's `late` column): the page calls
  /// them delayed messages, keeping "late" for answers.
  std::uint64_t missed = 0, duplicates = 0, superseded = 0, rejected = 0, restarts = 0, late = 0, controller_late = 0,
                silences = 0, guard_trips = 0;
  /// Answers since the session began, and those later than the controller's cycle (the summary's
  /// "N of M answers later than the 4 ms cycle"). Counted by MonitorFeed::add.
  std::uint64_t answers = 0, late_answers = 0;
};

/// A mark on the page's status timeline. Events of one kind and text less than kMergeS apart are one
/// event with a count (a fault that flickers is one mark, not thousands).
struct MonitorEvent {
  static constexpr double kMergeS = 1.0;
  double t_s = 0.0;       ///< the first
  double last_t_s = 0.0;  ///< the last merged into it
  std::string kind;       ///< "force fault", "stale force", "held", "invalid input", "guard trip", "restart",
                          ///< "silence", "rejected", "state", "stop"
  std::string text;
  std::uint64_t count = 1;
};

struct MonitorSetup {
  std::string link;
  int joints = 6;
  int force_components = 6;      ///< 3: the sensor measures forces only (no moment panel); 0: not known
  double period_s = 0.0;         ///< the controller's cycle: an answer later than this is late (0: not known)
  double joint_bound_deg = 0.0;  ///< 0: not known (a log without it)
  double tcp_bound_mm = 0.0;
  double force_fault_n = 0.0;       ///< |F| above this is a force fault (0: not known)
  double program_duration_s = 0.0;  ///< streaming links' program, 0 otherwise
  double window_s = 30.0;           ///< history kept (a recorded log keeps everything)
  bool recorded = false;
  std::string source;  ///< the log's path for a recorded session
  /// The settings the session ran with; the page shows each with its unit and help from the settings
  /// table (session_settings.hpp). Empty for a log written before they were recorded.
  std::vector<ShownSetting> settings;
};

/// The rows of the last window_s seconds, the session's state, events and stop reason, as JSON for the
/// page. Thread safety: add(), set_state() and flush() from one writer thread (the reporter, or a log
/// reader), never waiting for a reader; json() and rows_added() from any number of threads. Rows
/// reach readers when published: every 50 ms of the rows' time or 64 rows, at a heartbeat (the
/// controller silent) and at every state change (a recorded log: at set_state() or flush()).
class MonitorFeed {
 public:
  static constexpr std::size_t kMaxRowsPerAnswer = 5000;  ///< a reader asks again for the rest
  static constexpr std::size_t kMaxEvents = 500;          ///< the newest kept

  explicit MonitorFeed(MonitorSetup setup);
  ~MonitorFeed();
  MonitorFeed(const MonitorFeed&) = delete;
  MonitorFeed& operator=(const MonitorFeed&) = delete;

  void add(MonitorRow row);
  void add(const SessionEntry& entry);
  /// The session's state ("waiting", "running", ...) and, once ended, why. Publishes (the end waits
  /// for the lock: nothing is left to delay then).
  void set_state(const std::string& state, const std::string& stop_reason = "");
  /// Publishes every row added so far, waiting for the lock if a reader holds it.
  void flush();
  /// The rows from index `since` (the oldest kept when `since` is older) up to `max_rows` of them,
  /// the index to ask from next time and whether more are there already; the setup, the state and
  /// the events. Columnar: {"t":[...], "fz":[...], ...}.
  [[nodiscard]] std::string json(std::uint64_t since, std::size_t max_rows = kMaxRowsPerAnswer) const;
  /// Rows published so far.
  [[nodiscard]] std::uint64_t rows_added() const;
  [[nodiscard]] const MonitorSetup& setup() const { return setup_; }

  struct Block;
  struct Snapshot;

 private:
  void note_events(const MonitorRow& row);
  void add_event(double t_s, const char* kind, std::string text);
  void publish(bool wait);

  MonitorSetup setup_;
  std::string settings_json_;  // the setup's settings as the page reads them (they never change)
  // The writer's own (never read by readers).
  std::vector<std::shared_ptr<Block>> blocks_;
  std::uint64_t first_ = 0, next_ = 0;
  std::uint64_t answers_ = 0, late_answers_ = 0;
  MonitorRow last_{};
  bool have_last_ = false;
  std::string state_ = "waiting", stop_reason_;
  std::vector<MonitorEvent> events_;
  bool events_changed_ = true;
  std::shared_ptr<const std::vector<MonitorEvent>> events_published_;
  double published_t_s_ = -1e300;
  std::uint64_t published_next_ = 0;
  bool dirty_ = true;
  // Shared with readers.
  mutable std::mutex mutex_;
  std::shared_ptr<const Snapshot> published_;
};

/// A cycle log row (cycle_log.hpp's columns) as the page's row (answers and late answers are counted
/// by the feed).
[[nodiscard]] MonitorRow monitor_row(const SessionEntry& entry);

/// The compensator's status (CycleStatus as an int) as the page names it.
[[nodiscard]] const char* monitor_status_name(int status);

}  // namespace deflex::runtime
