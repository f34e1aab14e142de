// An online compensation session: what `deflex online`, the Python module and the case study all run
// a controller link through. It owns the compensator, the strategy, the link (chosen by kind from the
// table in link_table.hpp, configured by plain structs) and the sockets a real cell needs; it runs the
// loop and its stop rules, and sends every cycle off the loop's thread to the reporter (the cycle log,
// the fault dump, the status lines, the summary: session_report.hpp).
//
// Two ways to drive it:
//   - real time: run() is the whole loop (optionally SCHED_FIFO, memory locked, pinned: realtime.hpp);
//     the reporter works on a thread of its own, so nothing on the loop's thread writes a file;
//   - stepped: the caller owns time (a simulated cell on an in-memory network, tests, Python's
//     stand-ins) and calls poll() whenever its controller has spoken, and service() between polls
//     for the reporter's work.
// Either way the session ends with a StopReason (stop_reason.hpp: the exit code), and finish() gives
// the summary. Options are validated once, at construction (the bounds, the per-cycle step limits
// the link's command is held to, the stop rules): the loop only computes and reports.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "deflex/online/online_strategy.hpp"
#include "deflex/runtime/session_config.hpp"
#include "deflex/runtime/session_report.hpp"
#include "deflex/transport/stream_transport.hpp"

namespace deflex::runtime {

/// Transports the caller gives (a simulated cell's in-memory network, tests). Null: the session opens
/// real sockets from NetworkConfig.
struct SessionEndpoints {
  DatagramTransport* datagram = nullptr;  ///< EGM, RSI, fanuc-j519, motoros2-rt
  StreamTransport* motion = nullptr;      ///< simple message; ur-rtde: its RTDE connection
  StreamTransport* state = nullptr;
  DatagramTransport* status = nullptr;  ///< motoros2-rt: the controller's RobotState (with status_port >= 0)
};

/// How a session ended and what it did.
struct SessionSummary {
  StopReason reason = StopReason::kRunning;
  int exit_code = 0;
  std::string reason_text;  ///< a sentence naming what stopped it
  std::string link;         ///< "egm-joint" ...
  double duration_s = 0.0;
  std::uint64_t cycles = 0, answers = 0;
  LinkCounters counters;
  CycleStats stats;  ///< the command against its invariants, on the wire values
  CommandLimits limits;
  CompensatorCounters compensator;
  ForceSourceStats force_source;  ///< the force source's counts (zero when the caller pushed the samples)
  double measured_delay_s = 0.0;  ///< the mean of the link's delay measurements (NaN before one)
  std::uint64_t log_dropped = 0;  ///< entries the reporter never saw (a full ring: the log has gaps)
  std::uint64_t fault_episodes = 0, faulted_cycles = 0;
  std::uint64_t late_answers = 0;
  double program_time_s = 0.0;    ///< streaming links: where the program was at the end (its own axis)
  double program_behind_s = 0.0;  ///< how far behind real time the program ran
  std::string output_error;       ///< the cycle log could not be written ("" when it was, or none was asked)
  std::string text;               ///< the summary as lines for a person
  std::string json_text;          ///< the same for a program: one JSON document (`deflex online --json`)
};

/// Thread safety: one thread drives it (poll(), service(), run(), finish() and the accessors; while
/// run() runs, the reporter works on a thread of its own); request_stop() is safe from any thread
/// or a signal handler, and the feed of monitor_feed() from any thread.
class Session {
 public:
  /// Builds everything and validates every option (InputError naming it): the link's options, the
  /// per-cycle step limit against the bound, a program for a streaming link, the log paths (Error
  /// naming the path). The robot is copied; `clock`, `force` (may be null: push samples into
  /// compensator()), `force_model` (hybrid and predictive) and the endpoints' transports must outlive
  /// the session, so a temporary clock does not compile (docs/architecture.md, "Ownership").
  Session(const SessionConfig& config, const RobotModel& robot, const SensorConfig& sensor,
          std::shared_ptr<const JointTrajectory> program, const ForceModel* force_model, ForceSource* force,
          const Clock& clock, const SessionEndpoints& endpoints = {}, LogSink sink = {});
  Session(const SessionConfig& config, const RobotModel& robot, const SensorConfig& sensor,
          std::shared_ptr<const JointTrajectory> program, const ForceModel* force_model, ForceSource* force,
          const Clock&& clock, const SessionEndpoints& endpoints = {}, LogSink sink = {}) = delete;
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  /// Stepped: one poll of the link (waits up to timeout_s on real sockets), then the stop rules.
  /// Returns the link's result. Never allocates, locks or throws.
  LinkPollResult poll(double timeout_s) noexcept;
  /// Stepped: the reporter's work (log rows, status lines, dumps) for what the loop has handed over.
  void service();
  /// Real time: the loop, until the session ends or `max_s` of the session's clock has passed (then
  /// it returns kRunning and can be called again). The first call makes its thread real-time when
  /// asked (InputError naming the missing permission when refused) and starts the reporter's thread.
  StopReason run(double max_s = std::numeric_limits<double>::infinity());
  /// Asks the loop to end the session (planned: a user stop): the link ramps down first (stop_ramp_s;
  /// ControllerLink::request_planned_stop), then the session ends. A second request ends it at once.
  /// Safe from another thread or a signal handler (an atomic counter).
  void request_stop() noexcept { stop_requests_.fetch_add(1); }
  /// An output of the session (its cycle log, the field log of the program around it, a fault dump)
  /// could not be written: the loop ramps down and ends the session (StopReason::kOutputFailed, exit 1)
  /// with `text` as its reason (the first such text is kept). Safe from any thread but the loop's.
  void report_output_failure(const std::string& text);
  /// Ends the session (a running link is stopped: simple message sends STOP_TRAJECTORY), drains the
  /// reporter, writes the fault dump when the end was a fault, closes the cycle log, and builds the
  /// summary. Idempotent.
  const SessionSummary& finish();

  [[nodiscard]] bool ended() const { return reason_ != StopReason::kRunning; }
  [[nodiscard]] StopReason stop_reason() const { return reason_; }
  [[nodiscard]] ControllerLink& link() { return *link_; }
  [[nodiscard]] const ControllerLink& link() const { return *link_; }
  [[nodiscard]] OnlineCompensator& compensator() { return *compensator_; }
  [[nodiscard]] const SessionConfig& config() const { return config_; }
  [[nodiscard]] const LinkKindInfo& kind() const { return link_kind(config_.link); }
  /// "EGM on 127.0.0.1:6510" (where the controller reaches deflex).
  [[nodiscard]] const std::string& where() const { return where_; }
  /// The start-up line: link, strategy, bounds and limits, where, program.
  [[nodiscard]] std::string describe() const;
  /// What run() got of real time ("SCHED_FIFO priority 80 on CPU 1, memory locked").
  [[nodiscard]] const std::string& realtime_text() const { return realtime_.text; }
  /// The cycles kept (collect_cycles), oldest first; read after finish() or between service() calls.
  [[nodiscard]] const std::vector<LinkCycleRecord>& collected() const;
  [[nodiscard]] const SessionReporter* reporter() const { return reporter_.get(); }
  /// The live monitor's data (null unless config.monitor): filled by the reporter, read by a server.
  [[nodiscard]] std::shared_ptr<MonitorFeed> monitor_feed() const { return monitor_; }

 private:
  void open_link(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program);
  void open_fanuc_j519(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program,
                       const LinkStopRules& rules);
  void open_motoros2_rt(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program,
                        const LinkStopRules& rules);
  void open_simple_message(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program,
                           const LinkStopRules& rules);
  void open_ur_rtde(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program,
                    const LinkStopRules& rules);
  void push(SessionEntry::Kind kind, double now) noexcept;
  void end(StopReason reason) noexcept;
  void reporter_loop();
  void drain_reporter(double now);
  void build_summary();
  void gather_summary();
  [[nodiscard]] std::string summary_text() const;
  [[nodiscard]] std::string summary_json() const;

  SessionConfig config_;
  const Clock& clock_;
  LogSink sink_;
  std::unique_ptr<OnlineCompensator> compensator_;
  std::unique_ptr<OnlineStrategy> strategy_;
  std::unique_ptr<DatagramTransport> own_datagram_;
  std::unique_ptr<DatagramTransport> own_status_;  // motoros2-rt: the controller's RobotState, when read
  std::unique_ptr<StreamTransport> own_motion_, own_state_;
  std::unique_ptr<ControllerLink> link_;
  ForceSource* force_ = nullptr;
  std::shared_ptr<const JointTrajectory> program_;
  std::string where_;
  StopReason reason_ = StopReason::kRunning;
  std::string reason_text_;
  double start_s_ = 0.0, last_push_s_ = -1.0;
  std::uint64_t pushed_cycles_ = 0;  // the link's cycle count at the last cycle entry
  std::atomic<int> stop_requests_{0};
  std::atomic<bool> output_failed_{false};
  std::mutex output_failure_mutex_;  // never taken on the loop's thread
  std::string output_failure_;
  StopReason planned_stop_ = StopReason::kRunning;  // a planned stop under way: its reason
  void planned_stop(StopReason why, double now) noexcept;
  [[nodiscard]] std::string ramp_text() const;
  // Loop -> reporter.
  bool reporting_ = false;  // anything consumes the entries (a log, a dump, a sink, collection)
  std::unique_ptr<SpscRing<SessionEntry>> queue_;
  SessionEntry entry_;
  std::atomic<std::uint64_t> dropped_{0};
  std::unique_ptr<SessionReporter> reporter_;
  std::shared_ptr<MonitorFeed> monitor_;
  std::thread reporter_thread_;
  std::atomic<bool> reporter_stop_{false};
  bool started_ = false, finished_ = false;
  RealtimeGrant realtime_;
  SessionSummary summary_;
};

}  // namespace deflex::runtime
