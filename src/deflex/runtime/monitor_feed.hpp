// What the live monitor page shows, collected off the loop's thread: the session's reporter (which
// already receives every cycle through the lock-free ring of record_queue.hpp) hands each cycle here,
// and the monitor's HTTP threads read snapshots. The loop never touches this: a slow or stalled
// browser can delay the reporter by one copy at most, never an answer to the controller.
// A recorded cycle log (deflex monitor --log) fills the same feed, so the page is the same.
#pragma once

#include <cstdint>
#include <deque>
#include <mutex>
#include <string>

#include "deflex/runtime/record_queue.hpp"

namespace deflex::runtime {

/// One cycle as the page draws it (units as shown: N, Nm, deg, mm, ms).
struct MonitorRow {
  double t_s = 0.0, program_t_s = 0.0;
  std::uint64_t sequence = 0;
  int status = 0;            ///< CycleStatus
  double wrench[6] = {};     ///< conditioned wrench the model used, base frame: N, Nm
  double raw_force[3] = {};  ///< the sensor's force in the base frame, N
  double dtheta_deg[kMaxJoints] = {};
  double tcp_mm[3] = {};
  double delay_ms = 0.0, answer_ms = 0.0, arrival_ms = 0.0, jitter_ms = 0.0;
  std::uint64_t missed = 0, duplicates = 0, superseded = 0, rejected = 0, restarts = 0, late = 0, controller_late = 0,
                silences = 0, guard_trips = 0;
};

struct MonitorSetup {
  std::string link;
  int joints = 6;
  double joint_bound_deg = 0.0;  ///< 0: not known (a log without it)
  double tcp_bound_mm = 0.0;
  double program_duration_s = 0.0;  ///< streaming links' program, 0 otherwise
  double window_s = 30.0;           ///< history kept (a recorded log keeps everything)
  bool recorded = false;
  std::string source;  ///< the log's path for a recorded session
};

/// The rows of the last window_s seconds, the session's state and stop reason, as JSON for the page.
/// Thread safety: add() and set_state() from one writer thread (the reporter, or a log reader)
/// while any number of threads read json() and rows_added() (under a mutex); setup() is immutable.
class MonitorFeed {
 public:
  explicit MonitorFeed(MonitorSetup setup);
  void add(const MonitorRow& row);
  void add(const SessionEntry& entry);
  /// The session's state ("waiting", "running", ...) and, once ended, why.
  void set_state(const std::string& state, const std::string& stop_reason = "");
  /// Every row with an index >= `since` still kept (all kept when `since` is older), and the index to
  /// ask from next time; the setup and the state. Columnar: {"t":[...], "fz":[...], ...}.
  [[nodiscard]] std::string json(std::uint64_t since) const;
  [[nodiscard]] std::uint64_t rows_added() const;
  [[nodiscard]] const MonitorSetup& setup() const { return setup_; }

 private:
  MonitorSetup setup_;
  mutable std::mutex mutex_;
  std::deque<MonitorRow> rows_;
  std::uint64_t first_index_ = 0;  // the index of rows_.front()
  std::string state_ = "waiting", stop_reason_;
};

/// A cycle log row (cycle_log.hpp's columns) as the page's row.
[[nodiscard]] MonitorRow monitor_row(const SessionEntry& entry);

}  // namespace deflex::runtime
