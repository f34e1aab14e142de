// One small interface for every controller link deflex speaks (ABB EGM position guidance and path
// correction here; KUKA RSI and ROS-Industrial simple message beside them), so that the command
// line, the case study and a user's own program drive any of them alike, and a further controller is
// a new file rather than a rewrite. A link owns its protocol and its safety rules; it runs the
// compensation cycle (online/) on each controller message and never sends anything that is not
// within its stated bound of a nominal deflex itself holds.
#pragma once

#include <cstdint>
#include <string>

#include "deflex/online/online_compensator.hpp"

namespace deflex {

class LinkHistory;

enum class LinkState : int {
  kWaiting = 0,   ///< no controller message yet
  kRunning = 1,   ///< answering every controller message
  kFinished = 2,  ///< the program has ended; the last point is held (streaming links)
  kRefused = 3,   ///< the start was refused (the robot was not at the program's start): never answers
  kStopped = 4,   ///< a streaming link stopped the controller's motion (fault or stop()): sends nothing more
};
[[nodiscard]] const char* to_string(LinkState s);

/// KDL's sign convention: >= 0 nothing is wrong with the link (positive: nothing to do), < 0 a
/// message was not answered for a reason the caller should know.
enum class LinkPollResult : int {
  kAnswered = 0,     ///< a controller message was handled and answered
  kIdle = 1,         ///< nothing arrived
  kRejected = 2,     ///< datagrams arrived but none was usable (counted)
  kNotAnswered = -1, ///< a usable message was not answered (invalid cycle, guard): counted
  kRefused = -2,     ///< the start was refused: see start_distance()
  kStopped = -3,     ///< the link stopped the controller's motion for a fault: see stop_reason()
};

/// Why a streaming link stopped the controller's motion (LinkState::kStopped).
enum class LinkStopCause : int {
  kNone = 0,
  kRequested = 1,   ///< the caller's stop() (Ctrl-C, the end of a session)
  kProtocol = 2,    ///< the controller sent what the protocol does not allow (bad input: malformed, unknown ...)
  kConnection = 3,  ///< the connection was lost, or the controller went silent
  kController = 4,  ///< the controller refused points, or reports an emergency stop or an error
  kSafety = 5,      ///< deflex's own checks: the final bound check, an invalid cycle
};
[[nodiscard]] const char* to_string(LinkStopCause c);

/// What a link counts. Every datagram lands in exactly one of the reasons or is handled.
struct LinkCounters {
  std::uint64_t datagrams = 0;  ///< everything received
  std::uint64_t replies = 0;    ///< answers sent
  std::uint64_t malformed = 0, truncated = 0, oversized = 0, empty = 0;
  std::uint64_t missing_header = 0, missing_joints = 0, non_finite = 0;
  std::uint64_t duplicate = 0, out_of_order = 0;
  std::uint64_t out_of_limits = 0;   ///< joints beyond the robot's limits (plus 1 deg): never answered
  std::uint64_t foreign_sender = 0;  ///< from another address than the controller's: never answered
  std::uint64_t superseded = 0;      ///< valid but a newer one arrived in the same drain: not answered
  std::uint64_t restarts = 0;        ///< controller restarts recognised
  std::uint64_t invalid_cycles = 0;  ///< the compensator refused the input: not answered
  std::uint64_t guard_trips = 0;     ///< the final check found a command beyond the bound: not sent
  std::uint64_t refused = 0;         ///< messages not answered because the start was refused
  std::uint64_t send_errors = 0;
  // Sequencing and diagnostics (docs/online.md, "Link diagnostics").
  std::uint64_t far_ahead = 0;              ///< a sequence number far ahead of the running one (a stray): never answered
  std::uint64_t sequence_out_of_range = 0;  ///< wider than its field (EGM seqno > 32 bits, IPOC > 64): never answered
  std::uint64_t missing_required = 0;       ///< a field the schema requires is missing (EGM proto2): never answered
  std::uint64_t foreign_document = 0;       ///< well-formed, but not the controller's message (RSI): never answered
  std::uint64_t missed = 0;                 ///< controller cycles never received (gaps in its sequence)
  std::uint64_t late = 0;                   ///< messages received more than a period later than the quickest ones
  std::uint64_t controller_late = 0;        ///< answers the controller itself counted late (RSI <Delay>, its last value)
  double max_arrival_delay_s = 0.0;         ///< the largest LinkArrival::arrival_delay_s so far
  double jitter_s = 0.0;                    ///< interarrival jitter now (RFC 3550 estimator)
  [[nodiscard]] std::uint64_t rejected() const {
    return malformed + truncated + oversized + empty + missing_header + missing_joints + non_finite + duplicate +
           out_of_order + out_of_limits + foreign_sender + far_ahead + sequence_out_of_range + missing_required +
           foreign_document;
  }
};

/// How one controller message arrived, judged by the controller's own time stamp (EGM header.tm, RSI
/// IPOC: whole milliseconds of the controller's clock) against the link's clock at receipt. The two
/// clocks are not synchronised, so the absolute transit time is unknown; what is measured is how much
/// later than the quickest recent message this one came.
struct LinkArrival {
  double stamp_s = 0.0;            ///< the controller's time stamp, s since the session began (its clock)
  double arrival_delay_s = 0.0;    ///< (receipt - stamp) less its minimum over the last seconds; >= 0
  double jitter_s = 0.0;           ///< RFC 3550 interarrival jitter after this message
  std::uint64_t missed_before = 0; ///< controller cycles missing between the previous message taken and this one
};

/// One answered (or refused) cycle, SI units (rad, m, N, Nm, s).
struct LinkCycleRecord {
  double t_s = 0.0;                ///< the link's clock
  double program_time_s = 0.0;     ///< streaming links: where in the program the nominal is (its own time axis)
  std::uint64_t sequence = 0;      ///< the controller's sequence number (EGM seqno, RSI IPOC ...)
  JointVector q_nominal;           ///< what deflex holds (streaming links); the controller's planned joints otherwise
  JointVector q_feedback;          ///< where the controller says the arm is
  JointVector q_command;           ///< what was sent (streaming links: q_nominal - dtheta)
  JointVector dtheta;              ///< the bounded correction, joint space
  Vector3 tcp_correction_m = Vector3::Zero();  ///< the TCP offset the correction amounts to (base frame)
  double rotation_uncorrected_rad = 0.0;       ///< the model's TCP rotation a link could not correct
  Wrench wrench_base = Wrench::Zero();         ///< wrench the model used
  Wrench wrench_measured_base = Wrench::Zero();
  CycleStatus status = CycleStatus::kNoForceYet;
  bool replied = false;
  double delay_s = 0.0;     ///< the link's measured delay (command to feedback) at this cycle
  double compute_s = 0.0;   ///< from the datagram read to the answer sent
  LinkArrival arrival;      ///< how the message arrived (diagnostics)
};

class ControllerLink {
 public:
  virtual ~ControllerLink() = default;

  /// Waits up to timeout_s for controller messages, drains them, handles the newest usable one and
  /// answers it. Never allocates, locks or throws.
  virtual LinkPollResult poll(double timeout_s) noexcept = 0;

  [[nodiscard]] virtual const char* name() const = 0;  ///< "egm-joint", "egm-path", ...
  [[nodiscard]] virtual LinkState state() const = 0;
  [[nodiscard]] virtual const LinkCounters& counters() const = 0;
  [[nodiscard]] virtual const LinkCycleRecord& last_cycle() const = 0;
  /// When the start was refused: each joint's distance from the program's start (rad).
  [[nodiscard]] virtual const JointVector& start_distance() const = 0;
  /// True after a cycle with a force fault or an invalid input, until clear_fault().
  [[nodiscard]] virtual bool fault_pending() const = 0;
  virtual void clear_fault() = 0;
  /// The last cycles, oldest first, as CSV (set-up time I/O: allocates; throws Error).
  virtual void write_history_csv(const std::string& path) const = 0;
  /// The ring of the last cycles, so a caller can copy it between polls and write it elsewhere (a
  /// fault dump on another thread); null when the link keeps none.
  [[nodiscard]] virtual const LinkHistory* history() const { return nullptr; }

  /// Stops the controller's motion as soon as possible (streaming links over a connection: the
  /// simple message link sends STOP_TRAJECTORY) and sends nothing more. Links whose controller stops on
  /// its own when answers stop (EGM) have nothing to do. Never allocates or throws.
  virtual void stop() noexcept {}
  /// Why the link stopped (kNone while it has not).
  [[nodiscard]] virtual LinkStopCause stop_cause() const { return LinkStopCause::kNone; }
  /// A sentence saying why, naming the frame or field at fault ("" while the link has not stopped).
  [[nodiscard]] virtual const char* stop_reason() const { return ""; }

 protected:
  ControllerLink() = default;
  ControllerLink(const ControllerLink&) = default;
  ControllerLink& operator=(const ControllerLink&) = default;
};

}  // namespace deflex
