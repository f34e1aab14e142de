// FANUC Stream Motion (option J519), deflex as the motion source. deflex sends the start packet to
// the controller (UDP 60015); the controller then sends a status every communication interval (8, 4
// or 1 ms) and takes, in answer to each, one command: the absolute joint target (degrees) carrying the
// status's sequence number,
//     target = program(p) + blend - dtheta_smoothed,   |target_i - (program_i(p) + blend_i)| <= bound.
// The controller checks every joint's velocity, acceleration and jerk from successive commands and
// stops the stream at the first over its limits (MOTN-609..611 / 720..722), so the correction passes
// through a smoother with closed-form bounds (link/correction_smoother.hpp) sized from the controller's
// limits and the share of them the correction may take, and the program is checked against the rest of
// them before the session starts. Those limits are, per joint and kind, the stricter of the ones the
// user gives and the controller's own threshold table, read before the start packet (a controller that
// does not answer: the user's, and the summary says so). In protocol 3 and 4 the controller's capability
// is asked first, as FANUC's own driver does: a controller offering an older version than deflex was told
// to speak, reporting another interval than --period-ms, or not answering at all stops the link before
// the start packet (version 1 has no capability packet, so nothing is asked).
//
// The program's clock is the controller's: it moves on one interval per command, and a status whose
// number skips some (a status lost on the way) is answered with one command for each number missed,
// in order (as FANUC's own driver catches up), so no interval of the program is dropped and no velocity
// dip enters the stream; more than `max_catch_up` missed is a PC too slow for the controller's buffer
// (kTooSlow). A session starts at the first status with the ready bit set: its joints are the anchor
// (the first command is where the arm is; the offset to the program is blended out). The ready bit
// cleared after that (an alarm, the TP program leaving IBGN) or, in protocol 3 and 4, the in-error or
// e-stop bits, stop the link (kController). The session ends with a command flagged last-data
// (holding the last target) and the stop packet: at the program's end (kEnded), after a planned stop
// has brought the program to rest on its path (kRequested); at either the correction is first held and
// the smoother settled, so the last command adds no acceleration or jerk. A stop for any other reason,
// or stop(), sends the stop packet alone (the controller then stops the stream itself, MOTN-603). A
// controller that begins a new session while the stream runs (its statuses numbered afresh) stops the
// link: a stream is not resumed. The first statuses time the controller's interval by their time
// stamps; one that is not --period-ms stops the link before any command (kProtocol).
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "deflex/link/controller_gate.hpp"
#include "deflex/link/controller_link.hpp"
#include "deflex/link/correction_smoother.hpp"
#include "deflex/link/joint_stream.hpp"
#include "deflex/online/delay_estimator.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/fanuc_j519.hpp"

namespace deflex {

struct FanucJ519LinkConfig {
  DatagramAddress controller;  ///< where the controller listens (port 60015 by default)
  std::uint32_t version = 1;   ///< the protocol version (1: float32 targets; 3, 4: float64)
  /// The controller's limits on the stream per joint (deg/s, deg/s^2, deg/s^3): the threshold tables'
  /// strictest values, or the $STMO_GRP limits read on the pendant. Default: a CRX-10iA/L's
  /// strictest (120 deg/s, 265 deg/s^2, 1240 deg/s^3).
  std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> limits = default_limits();
  /// The share of the acceleration and jerk limits the correction may use; the program keeps the rest.
  double correction_share = 0.25;
  /// The blend from where the arm is to the program: a start tolerance of 0.2 deg (the TP program
  /// moves the arm to the program's start first), so the blend's jerk stays small at every interval.
  JointStreamConfig stream = fanuc_stream();
  LinkStopRules stop;
  std::size_t history_cycles = 1000;
  double initial_delay_s = 0.04;
  double start_resend_s = 0.5;  ///< the start packet again while no status comes
  int max_catch_up = 8;         ///< statuses missed in a row that are caught up (0..9); more: kTooSlow
  std::size_t max_packet_bytes = 1400;
  /// Ask the controller for its threshold tables before the start packet (joints 1..dof: velocity,
  /// acceleration, jerk): one request at a time, each answered within `threshold_timeout_s` or sent
  /// again, at most `threshold_retries` times; a request still unanswered then ends the reading (older
  /// system software does not answer) and the limits above are used as given.
  bool read_thresholds = true;
  double threshold_timeout_s = 0.1;
  int threshold_retries = 2;
  /// Protocol 3 and 4: the capability request before the threshold tables, answered within
  /// `capability_timeout_s` or sent again, at most `capability_retries` times; still unanswered, the
  /// link stops (a controller without protocol 3 does not answer it, and raises MOTN-607 on a v3 start).
  double capability_timeout_s = 0.1;
  int capability_retries = 2;

  static JointStreamConfig fanuc_stream() {
    JointStreamConfig s;
    s.start_tolerance_rad = 0.2 * kPi / 180.0;
    return s;
  }
  static std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> default_limits() {
    std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> l{};
    l.fill({120.0, 265.0, 1240.0});
    return l;
  }
  /// Throws InputError naming the setting.
  void validate() const;
};

/// "VEL,ACC,JERK" (deg/s, deg/s^2, deg/s^3) for every joint, or one triple a joint separated by ';' (as
/// deflex online --fanuc-limits takes them). Throws InputError naming `option` and the triple.
[[nodiscard]] std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> parse_fanuc_limits(const std::string& text,
                                                                                       const char* option);

/// How the reading of the controller's threshold tables went.
struct FanucThresholdCounters {
  std::size_t asked = 0;       ///< tables to read (3 a joint); 0 when reading is off
  std::size_t read = 0;        ///< tables read and used
  std::uint64_t rejected = 0;  ///< replies that were not the table asked for, or not a valid one: never used
  std::uint64_t resent = 0;    ///< requests sent again after their timeout
  bool unanswered = false;     ///< a request went unanswered after every retry: the rest were not asked
};

/// How the capability exchange went (protocol 3 and 4 only).
struct FanucCapabilityCounters {
  bool asked = false;          ///< the link speaks protocol 3 or 4 (version 1 has no capability packet)
  bool cleared = false;        ///< a stop packet went first, to end a session a PC left running
  bool read = false;           ///< a valid reply was taken (FanucJ519Link::capability())
  std::uint64_t rejected = 0;  ///< datagrams in the phase that were not a valid reply: never used
  std::uint64_t resent = 0;    ///< requests sent again after their timeout
  bool unanswered = false;     ///< no valid reply after every retry: the link stopped
};

/// Thread safety: one thread at a time (the loop's), as every ControllerLink.
class FanucJ519Link final : public ControllerLink {
 public:
  /// Every reference must outlive the link. The controller's interval is the compensator's period_s.
  /// Throws InputError on a configuration that cannot work: a bad setting, a program for another
  /// number of joints or one that alone exceeds the controller's limits (naming the joint, the time
  /// and the limit), limits the smoother cannot meet.
  FanucJ519Link(OnlineCompensator& compensator, OnlineStrategy& strategy,
                std::shared_ptr<const JointTrajectory> nominal, DatagramTransport& transport, const Clock& clock,
                const FanucJ519LinkConfig& config);
  FanucJ519Link(OnlineCompensator& compensator, OnlineStrategy& strategy,
                std::shared_ptr<const JointTrajectory> nominal, DatagramTransport& transport, const Clock&& clock,
                const FanucJ519LinkConfig& config) = delete;

  LinkPollResult poll(double timeout_s) noexcept override;
  void stop() noexcept override;
  [[nodiscard]] const char* name() const override { return "fanuc-j519"; }
  [[nodiscard]] const DelayEstimator* delay_estimator() const override { return &delay_; }
  [[nodiscard]] std::string protocol_summary() const override;

  [[nodiscard]] const JointStream& stream() const { return stream_; }
  [[nodiscard]] const CorrectionSmoother& smoother() const { return smoother_; }
  /// Commands sent as catch-up for statuses that never arrived.
  [[nodiscard]] std::uint64_t caught_up() const { return caught_up_; }
  /// The limits the stream is held to (deg/s, deg/s^2, deg/s^3): the configured ones until the
  /// threshold tables are read, then per joint and kind the stricter of the two.
  [[nodiscard]] const std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes>& effective_limits() const {
    return limits_;
  }
  /// The strictest value of each table read (0 where none was read).
  [[nodiscard]] const std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes>& tables() const { return tables_; }
  [[nodiscard]] const FanucThresholdCounters& thresholds() const { return thresholds_; }
  /// What the controller reported in its capability reply (valid when capability_counters().read).
  [[nodiscard]] const fanuc_j519::Capability& capability() const { return capability_; }
  [[nodiscard]] const FanucCapabilityCounters& capability_counters() const { return capability_counters_; }
  /// True once the threshold phase is over (read, unanswered or off): the start packet may go out.
  [[nodiscard]] bool thresholds_done() const { return tables_done_; }

 private:
  bool read_capability(double timeout_s) noexcept;
  void send_capability_request(double now) noexcept;
  bool take_capability_reply(std::size_t size) noexcept;
  void judge_capability() noexcept;
  bool read_thresholds(double timeout_s) noexcept;
  void send_threshold_request(double now) noexcept;
  /// A request before the stream: what it has been sent so far, and when last.
  struct PendingRequest {
    int attempts = 0;
    double sent_s = 0.0;
  };
  /// Sends the `n` bytes in tx_ to the controller (n == 0: encoding failed, counted as a send error),
  /// counting a repeat in `resent`, and notes the attempt in `request`.
  void send_request(std::size_t n, PendingRequest& request, std::uint64_t& resent, double now) noexcept;
  void take_threshold_reply(std::size_t size) noexcept;
  void apply_tables() noexcept;
  /// The controller's datagrams before the stream (the capability, the tables): waits up to `wait_s`,
  /// then hands each from the controller within max_packet_bytes to `take` (its size; rx_ holds it)
  /// until `take` returns false; foreign and oversized ones are counted.
  template <typename Take>
  void receive_before_stream(double wait_s, Take&& take) noexcept;
  LinkPollResult poll_once(double timeout_s) noexcept;
  void send_stop_packet() noexcept;  // the session's end: at most once after its start packet
  void transmit_stop() noexcept;     // a stop packet on the wire, nothing recorded
  bool interval_agrees(const fanuc_j519::Status& s) noexcept;
  bool drain(double timeout_s, fanuc_j519::Status& newest, bool& session_start) noexcept;
  bool controller_state(const fanuc_j519::Status& s) noexcept;
  bool start_session(const fanuc_j519::Status& s) noexcept;
  LinkPollResult answer(std::uint32_t sequence, double now, bool session_start) noexcept;
  LinkPollResult finish(const fanuc_j519::Status& s, double now) noexcept;
  bool send_command(std::uint32_t sequence, const JointVector& target_rad, bool last) noexcept;

  FanucJ519LinkConfig config_;
  DatagramTransport& transport_;
  ControllerGate gate_;
  JointStream stream_;
  CorrectionSmoother smoother_;
  DelayEstimator delay_;
  double period_s_;
  double last_start_s_ = -1e300;
  bool ready_seen_ = false;          // a status with the ready bit set arrived this session
  std::uint32_t next_sequence_ = 0;  // the sequence number the next command carries
  std::uint64_t caught_up_ = 0;
  bool last_data_sent_ = false;
  bool start_sent_ = false, stop_sent_ = false;
  bool have_previous_status_ = false;  // the status before the first ready one answered (its interval)
  std::uint32_t previous_sequence_ = 0, previous_stamp_ms_ = 0;
  double last_data_s_ = 0.0;

  // The capability phase (protocol 3 and 4), before the threshold phase.
  fanuc_j519::Capability capability_;
  FanucCapabilityCounters capability_counters_;
  bool capability_done_ = false;
  PendingRequest capability_request_;

  // The threshold phase, before the start packet.
  std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> limits_;  // what the stream is held to
  std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> tables_{};
  FanucThresholdCounters thresholds_;
  bool tables_done_ = false;
  std::size_t table_next_ = 0;    // the table asked for: joint * 3 + kind
  PendingRequest table_request_;  // for the table asked for

  // Preallocated per-cycle buffers.
  std::vector<unsigned char> rx_, tx_;
  fanuc_j519::Status status_;
  fanuc_j519::Command command_;
  JointVector feedback_, program_, program_velocity_, blend_, blend_velocity_, nominal_;
  LinkArrival arrival_;
  std::array<double, fanuc_j519::kAxes> aux_deg_{};  // the anchor status's joints: the axes beyond the arm's
  double receipt_age_s_ = 0.0;  // the newest status's age when it was read (the transport's time stamp)
  double taken_at_s_ = 0.0;
};

}  // namespace deflex
