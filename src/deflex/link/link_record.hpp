// What a controller link counts and records, as plain data: the counters every datagram lands in, how
// a controller message arrived, and the record of one cycle (what came in, what the compensator gave,
// what went out, how it measured against the two invariants). SI units (rad, m, N, Nm, s).
#pragma once

#include <cstdint>

#include "deflex/online/cycle_types.hpp"

namespace deflex {

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
  std::uint64_t restarts = 0;        ///< controller restarts recognised (new sessions after the first)
  std::uint64_t invalid_cycles = 0;  ///< the compensator refused the input: not answered
  std::uint64_t guard_trips = 0;     ///< the final guard found a command beyond the bound or the step limit: not sent
  std::uint64_t step_limited = 0;    ///< cycles whose command the per-cycle step limit held back
  std::uint64_t refused = 0;         ///< messages not answered because the start was refused
  std::uint64_t not_running = 0;     ///< messages while the controller reports its session not running: not consumed
  std::uint64_t send_errors = 0;
  // Sequencing and diagnostics (docs/online.md, "Link diagnostics").
  std::uint64_t far_ahead = 0;  ///< a sequence number far ahead of the running one (a stray): never answered
  std::uint64_t sequence_out_of_range = 0;  ///< wider than its field (EGM seqno > 32 bits, IPOC > 64): never answered
  std::uint64_t missing_required = 0;       ///< a field the schema requires is missing (EGM proto2): never answered
  std::uint64_t foreign_document = 0;       ///< well-formed, but not the controller's message (RSI): never answered
  std::uint64_t missed = 0;                 ///< controller cycles never received (gaps in its sequence)
  std::uint64_t late = 0;                   ///< messages received more than a period later than the quickest ones
  std::uint64_t controller_late = 0;  ///< answers the controller itself counted late (RSI <Delay>, its last value)
  std::uint64_t silences = 0;         ///< silences longer than two controller cycles that were ridden through
  std::uint64_t clock_jumps = 0;      ///< the controller's time stamp went back or jumped: the timing started again
  double max_arrival_delay_s = 0.0;   ///< the largest LinkArrival::arrival_delay_s so far
  double jitter_s = 0.0;              ///< interarrival jitter now (RFC 3550 estimator)
  double longest_silence_s = 0.0;     ///< the longest gap between two usable messages ridden through
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
  double stamp_s = 0.0;             ///< the controller's time stamp, s since the session began (its clock)
  double arrival_delay_s = 0.0;     ///< (receipt - stamp) less its minimum over the last seconds; >= 0
  double jitter_s = 0.0;            ///< RFC 3550 interarrival jitter after this message
  std::uint64_t missed_before = 0;  ///< controller cycles missing between the previous message taken and this one
};

/// One answered (or refused) cycle.
struct LinkCycleRecord {
  double t_s = 0.0;             ///< the link's clock
  double program_time_s = 0.0;  ///< streaming links: where in the program the nominal is (its own time axis)
  std::uint64_t sequence = 0;   ///< the controller's sequence number (EGM seqno, RSI IPOC, the point's number)
  /// Streaming links: the program, un-blended; links correcting the controller's program: the
  /// controller's planned or setpoint joints.
  JointVector q_nominal;
  /// Streaming links: the blend that takes the command from where the controller was at a session's
  /// start to the program (decays to zero over the ramp-in); zero otherwise. The bound holds about
  /// q_nominal + q_blend, the nominal deflex holds.
  JointVector q_blend;
  JointVector q_feedback;  ///< where the controller says the arm is
  /// What was sent, as the wire carries it: absolute joints (streaming links), or q_nominal plus the
  /// joint offset sent (RSI), or q_feedback (EGM path correction, whose command is a TCP offset).
  JointVector q_command;
  JointVector dtheta;                          ///< the bounded correction, joint space
  Vector3 tcp_correction_m = Vector3::Zero();  ///< the TCP offset the correction amounts to (base frame)
  double rotation_uncorrected_rad = 0.0;       ///< the model's TCP rotation a link could not correct
  Wrench wrench_base = Wrench::Zero();         ///< wrench the model used
  Wrench wrench_measured_base = Wrench::Zero();
  CycleStatus status = CycleStatus::kNoForceYet;
  bool replied = false;
  bool step_limited = false;   ///< the per-cycle step limit held the command back this cycle
  bool session_start = false;  ///< the first cycle of a session (the command was anchored to the controller)
  /// The largest deviation from the nominal deflex holds, this cycle: joints (rad, joint forms) and the
  /// TCP (m).
  double deviation_rad = 0.0, deviation_m = 0.0;
  /// The step from the previous command sent: the largest joint's (rad, joint forms) and the TCP
  /// offset's (m, TCP form).
  double step_rad = 0.0, step_m = 0.0;
  double step_fraction = 0.0;  ///< that step over its step limit (the largest over the joints); <= 1 when sent
  double delay_s = 0.0;        ///< the link's measured delay (command to feedback) at this cycle
  double compute_s = 0.0;      ///< from the datagram read to the answer sent
  /// From the datagram's arrival at the host (the kernel's time stamp) to the answer sent: what the
  /// controller waits, scheduling included (NaN when the transport cannot tell).
  double answer_s = 0.0;
  LinkArrival arrival;  ///< how the message arrived (diagnostics)
};

}  // namespace deflex
