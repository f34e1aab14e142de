// One small interface for every controller link deflex speaks (ABB EGM position guidance and path
// correction, KUKA RSI, ROS-Industrial simple message), so that the runtime, the case study and a
// user's own program drive any of them alike, and a further controller is a new folder rather than a
// rewrite. A link owns its protocol: it receives and decodes the controller's messages, runs the one
// link cycle (link_cycle.hpp: strategy, compensation, the bound, the per-cycle step limit, the final
// guard, the record) and encodes and sends the answer. What every link shares (its state, counters,
// the stop rules and the stop reason) lives here, once.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "deflex/link/link_cycle.hpp"
#include "deflex/online/delay_estimator.hpp"
#include "deflex/transport/clock.hpp"

namespace deflex {

enum class LinkState : int {
  kWaiting = 0,   ///< no controller message yet
  kRunning = 1,   ///< answering every controller message
  kFinished = 2,  ///< the program has ended; the last point is held (streaming links)
  kRefused = 3,   ///< the start was refused (the arm was not where the program is): never answers
  kStopped = 4,   ///< the link stopped (stop_cause() says why): sends nothing more
};
[[nodiscard]] const char* to_string(LinkState s);

/// KDL's sign convention: >= 0 nothing is wrong with the link (positive: nothing to do), < 0 a
/// message was not answered for a reason the caller should know.
enum class LinkPollResult : int {
  kAnswered = 0,      ///< a controller message was handled and answered
  kIdle = 1,          ///< nothing arrived
  kRejected = 2,      ///< datagrams arrived but none was usable (counted)
  kNotAnswered = -1,  ///< a usable message was not answered (invalid cycle): counted
  kRefused = -2,      ///< the start was refused: see start_distance() (returned once)
  kStopped = -3,      ///< the link stopped: see stop_cause(), stop_reason() (returned once)
};

/// Why a link stopped (LinkState::kStopped). The runtime maps each to a stop reason and an exit code
/// (runtime/stop_reason.hpp, docs/online.md "Faults and exit codes").
enum class LinkStopCause : int {
  kNone = 0,
  kRequested = 1,   ///< the caller's stop() (Ctrl-C, the end of a session)
  kEnded = 2,       ///< the controller ended the session as planned (after the program's end, EGM stopped)
  kProtocol = 3,    ///< the controller sent what the protocol does not allow (bad input: malformed, unknown ...)
  kSilent = 4,      ///< the controller went silent for longer than the link's stop silence
  kConnection = 5,  ///< the connection was closed or broke
  kController = 6,  ///< the controller stopped or faulted: RSI's Timeout, EGM ended early, motors off, e-stop,
                    ///< an error, refused points
  kSafety = 7,      ///< deflex's own final guard: a command beyond the bound or the step limit, an invalid cycle
  kTooSlow = 8,     ///< the controller falls behind the program by more than the link allows
};
[[nodiscard]] const char* to_string(LinkStopCause c);

/// Settings every link shares: when a silent controller counts as gone.
struct LinkStopRules {
  /// The controller silent (no usable message) this long while the session runs: the link stops
  /// (kSilent). Shorter silences are ridden through (the program waits, nothing steps).
  double stop_silence_s = 3.0;
  /// Streaming links, after the program's end: a silence this long is the session's planned end.
  double end_silence_s = 2.0;
  /// Links that correct the controller's own program (egm-path, rsi): a silence longer than
  /// stop_silence_s after a healthy session is the planned end (the program's RSI_OFF or EGMStop),
  /// not a fault. Off: such a silence stops the link as kSilent.
  bool end_on_silence = false;
  /// Throws InputError naming the setting.
  void validate() const;
};

/// Thread safety: one thread at a time (the loop's), together with the compensator, strategy and
/// force source it drives, for every link.
class ControllerLink {
 public:
  virtual ~ControllerLink() = default;
  ControllerLink(const ControllerLink&) = delete;
  ControllerLink& operator=(const ControllerLink&) = delete;

  /// Waits up to timeout_s for controller messages, drains them, handles the newest usable one and
  /// answers it; applies the stop rules when nothing comes. Never allocates, locks or throws.
  virtual LinkPollResult poll(double timeout_s) noexcept = 0;
  [[nodiscard]] virtual const char* name() const = 0;  ///< "egm-joint", "egm-path", ...

  /// Stops the link: it sends nothing more (streaming links over a connection stop the controller's
  /// motion first: simple message sends STOP_TRAJECTORY). Links whose controller stops on its own when
  /// answers stop (EGM, RSI) have nothing else to do. Never allocates or throws.
  virtual void stop() noexcept { stop_link(LinkStopCause::kRequested, "stop requested"); }
  /// A planned stop while the arm may be moving (SIGINT, SIGTERM, a session's time limit): a streaming
  /// link brings its program to a standstill on its own path over `ramp_s` (the correction kept), a link
  /// that corrects the controller's own program ramps its correction to zero at the rate bound; then
  /// the link stops (kRequested) with a sentence saying so. A link that has nothing to ramp (not
  /// started, the program ended) stops at once; so does stop() at any time. Never allocates or throws.
  virtual void request_planned_stop(double ramp_s) noexcept;
  /// True from request_planned_stop() until the link stopped.
  [[nodiscard]] bool ramping_down() const { return ramping_down_ && state_ != LinkState::kStopped; }

  [[nodiscard]] LinkState state() const { return state_; }
  [[nodiscard]] const LinkCounters& counters() const { return counters_; }
  [[nodiscard]] const LinkCycleRecord& last_cycle() const { return cycle_.record(); }
  [[nodiscard]] const LinkHistory& history() const { return cycle_.history(); }
  [[nodiscard]] const CycleStats& cycle_stats() const { return cycle_.stats(); }
  [[nodiscard]] const CommandLimits& limits() const { return cycle_.limits(); }
  /// When the start was refused: each joint's distance from where the program is (rad); empty otherwise.
  [[nodiscard]] const JointVector& start_distance() const { return start_distance_; }
  /// True after a cycle with a force fault, an invalid input or a guard trip, until clear_fault().
  [[nodiscard]] bool fault_pending() const { return cycle_.fault_pending(); }
  void clear_fault() { cycle_.clear_fault(); }
  /// Why the link stopped (kNone while it has not), and a sentence naming the frame or field at fault.
  [[nodiscard]] LinkStopCause stop_cause() const { return stop_cause_; }
  [[nodiscard]] const char* stop_reason() const { return stop_reason_.data(); }
  /// The link's clock when the last usable controller message was taken (s; NaN before the first).
  [[nodiscard]] double last_message_s() const { return last_message_s_; }
  /// The link's clock (what poll() measures time by).
  [[nodiscard]] const Clock& clock() const { return clock_; }
  [[nodiscard]] const LinkStopRules& stop_rules() const { return rules_; }
  /// True while a stopped link still owes the controller something (simple message: the
  /// STOP_TRAJECTORY's bytes, or the controller's reply to it, which must be read before the
  /// connection closes, or the controller sees a reset). A session polls it a little longer.
  [[nodiscard]] virtual bool winding_down() const { return false; }
  /// What the link's protocol adds to a session's summary ("simple message: 812 points sent ..."), or
  /// "" (outside the cycle: allocates).
  [[nodiscard]] virtual std::string protocol_summary() const { return {}; }
  /// The link's measurement of its delay (command to feedback); null for a link that keeps none.
  [[nodiscard]] virtual const DelayEstimator* delay_estimator() const { return nullptr; }
  /// The force source the cycle reads, handed over by whoever owns it (the session) before the first
  /// poll(); null (the default): samples are pushed into the compensator directly. It must outlive the
  /// link. No link's own code sees it.
  void read_force_from(ForceSource* force) noexcept { cycle_.read_force_from(force); }
  /// The strategy's and the compensator's (read-only).
  [[nodiscard]] const OnlineCompensator& compensator() const { return cycle_.compensator(); }

 protected:
  /// Every reference must outlive the link. Throws InputError on bad limits or rules.
  ControllerLink(OnlineCompensator& compensator, OnlineStrategy& strategy, const Clock& clock,
                 const CommandLimits& limits, const LinkStopRules& rules, std::size_t history_cycles);
  ControllerLink(OnlineCompensator& compensator, OnlineStrategy& strategy, const Clock&& clock,
                 const CommandLimits& limits, const LinkStopRules& rules, std::size_t history_cycles) = delete;

  /// Stops the link once (later calls keep the first reason): state kStopped, the cause and a
  /// printf-style sentence. Never allocates.
  void stop_link(LinkStopCause cause, const char* format, ...) noexcept __attribute__((format(printf, 3, 4)));
  /// The start was refused: state kRefused, the distance kept, a fault pending.
  void refuse_start(const JointVector& distance) noexcept;
  /// A usable controller message was taken at `now`.
  void heard(double now) noexcept;
  /// Whether the controller was silent (more than two of its cycles) before the message just heard, or
  /// nothing was heard before it: a session it starts then follows the end of its previous one.
  [[nodiscard]] bool after_silence() const { return after_silence_; }
  /// A session start without a silence whose anchor is more than two step limits from the last command
  /// sent (reanchor_gap()): no command can step from both, so the link stops (kController) naming it.
  /// True when it stopped.
  bool stop_if_anchor_unreachable(double gap, const char* what) noexcept;
  /// The stop rules when nothing usable came: a silence longer than the link allows stops it (kSilent,
  /// or kEnded when the silence is the planned end). True when the link stopped now.
  bool apply_silence_rules(double now) noexcept;
  /// The terminal states: kRefused / kStopped returned once, then kIdle.
  LinkPollResult announce_terminal() noexcept;
  /// A cycle whose command did not pass (`verdict` not kSend): recorded as not sent; kInvalid (the
  /// compensator refused the input) is left unanswered, kGuard (the final guard refused the command)
  /// stops the link for safety. Returns the poll's result.
  LinkPollResult cycle_not_passed(LinkCycle::Verdict verdict, double compute_s) noexcept;
  /// Whether the session so far ended healthy enough for a silence to be its planned end (links that
  /// correct the controller's program; RSI: its late count below the Timeout).
  [[nodiscard]] virtual bool silence_is_planned_end() const { return rules_.end_on_silence; }

  /// Links that correct the controller's program: during a planned stop the correction ramps to zero;
  /// once a sent command carries none, the link stops. Call after a command was sent.
  void stop_when_correction_gone() noexcept;

  LinkCycle cycle_;
  const Clock& clock_;
  bool ramping_down_ = false;
  double ramp_down_s_ = 0.0;       // the stop ramp asked for (streaming links)
  std::uint64_t ramp_cycles_ = 0;  // cycles answered during the ramp
  LinkCounters counters_;
  LinkState state_ = LinkState::kWaiting;
  LinkStopRules rules_;
  JointVector start_distance_;

 private:
  LinkStopCause stop_cause_ = LinkStopCause::kNone;
  std::array<char, 320> stop_reason_{};
  double last_message_s_;
  bool after_silence_ = true;
  bool announced_ = false;
};

}  // namespace deflex
