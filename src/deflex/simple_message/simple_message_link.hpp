// The paper's own kind of link, for cells without a real-time controller option: deflex streams
// compensated joint targets over TCP to a robot program speaking the ROS-Industrial simple message
// protocol (the RAPID, KAREL ... server programs; wire/simple_message.hpp). deflex is the motion
// source. It holds the nominal program itself (JointStream) and, once a cycle, sends the next point
//     target_k = nominal(k T) - dtheta_k,    |target_k,i - nominal_i(k T)| <= max_joint_correction_rad,
// as a JOINT_TRAJ_PT service request on the motion connection, with the cycle T as its duration; the
// controller queues it and runs it as a joint move with a zone. JOINT_POSITION messages on the state
// connection are the feedback.
//   - Buffer: points go out one at a time (each waits for its reply, so a refused point is sent again
//     before the next: the controller never skips one) and are paced so that `buffer_depth` points
//     wait on the controller ahead of the one it executes. The buffer adds about buffer_depth x T of
//     lag between a correction and the arm; buffer_lag_s() reports it, the delay estimator measures
//     the whole command-to-feedback delay, and the predictive strategy leads by it.
//   - FAILURE reply: the point was not taken (the controller's buffer was full: it is behind deflex's
//     clock), so the pacing waits a cycle and the same point goes again; max_failures in a row stop.
//   - Start: the first JOINT_POSITION must find the arm within the tolerance (1 deg) of the program's
//     start, or the link refuses and sends nothing, ever.
//   - Faults (a malformed, truncated, oversized or unknown frame, a reply with the wrong sequence or
//     none expected, a lost connection, a silent controller, a controller reporting an emergency stop
//     or an error, a final check that fails): counted, and the link stops the controller's motion with
//     STOP_TRAJECTORY (carrying the last target sent, never a new one) and sends nothing more;
//     stop_reason() says why. stop() does the same on request (Ctrl-C).
//   - A force fault is not a link fault: the compensator ramps the correction to zero and the nominal
//     keeps streaming, as on the EGM links.
//   - A slow controller (one that takes a point less often than once a cycle) makes the program run
//     late: the link reports how far behind its schedule the program is, and stops the motion once
//     that exceeds max_behind_s (kTooSlow).
// Each point is the one link cycle's command (link_cycle.hpp): within the bound of the nominal and the
// step limit of the previous point, checked on the float32 values actually sent. The program moves on
// one cycle a point taken (SUCCESS), never by the wall clock. poll() never allocates, locks or throws.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>

#include "deflex/link/controller_link.hpp"
#include "deflex/link/joint_stream.hpp"
#include "deflex/online/delay_estimator.hpp"
#include "deflex/transport/clock.hpp"
#include "deflex/transport/stream_transport.hpp"
#include "deflex/wire/simple_message_stream.hpp"

namespace deflex {

struct SimpleMessageLinkConfig {
  simple_message::ByteOrder byte_order = simple_message::ByteOrder::kLittle;  ///< ABB RAPID: little
  int buffer_depth = 2;          ///< points kept queued on the controller (>= 1)
  double reply_timeout_s = 1.0;  ///< a point unanswered this long: the controller is not listening
  double state_timeout_s = 1.0;  ///< no JOINT_POSITION this long while streaming (ABB publishes every 0.1 s)
  int max_failures = 3;          ///< FAILURE replies in a row before the link stops
  /// The program may fall this far behind its schedule (a controller slower than one point a cycle)
  /// before the link stops the motion (kTooSlow), s.
  double max_behind_s = 2.0;
  LinkStopRules stop;  ///< end_silence_s: after the program's last point is taken, the session ends
  std::size_t max_frame_bytes = simple_message::kDefaultMaxFrameBytes;  ///< a longer LENGTH is out of step
  JointStreamConfig stream;
  std::size_t history_cycles = 1000;  ///< ring of the last cycles (100 s at 100 ms)
  /// The delay assumed until it is measured (s); NaN: the buffer's lag, buffer_depth x the cycle.
  double initial_delay_s = std::numeric_limits<double>::quiet_NaN();
  /// Throws InputError naming the setting.
  void validate() const;
};

/// What the simple message link counts beyond LinkCounters.
struct SimpleMessageCounters {
  std::uint64_t state_frames = 0, motion_frames = 0;  ///< frames received on each connection
  std::uint64_t joint_positions = 0, robot_statuses = 0;
  std::uint64_t points_sent = 0;      ///< JOINT_TRAJ_PT requests, repeats included
  std::uint64_t points_accepted = 0;  ///< SUCCESS replies
  std::uint64_t failures = 0;         ///< FAILURE replies (the point was not taken)
  std::uint64_t unknown_type = 0;     ///< frames of a message type the link does not speak
  std::uint64_t unexpected = 0;       ///< a reply nothing was waiting for, a request or topic on the motion port
  std::uint64_t wrong_sequence = 0;   ///< a reply naming another point than the one waiting
  std::uint64_t partial_writes = 0;   ///< writes the stream took only part of (the rest went later)
  std::uint64_t stops_sent = 0;       ///< STOP_TRAJECTORY requests
  double behind_s = 0.0;              ///< how far behind its schedule the program is now (s)
  double max_behind_s = 0.0;          ///< the most it was
};

/// Thread safety: one thread at a time (the loop's), as every ControllerLink.
class SimpleMessageLink final : public ControllerLink {
 public:
  /// Every reference must outlive the link; `motion` and `state` are connected streams (the
  /// controller's motion and state servers). The cycle (the points' duration and the pacing) is the
  /// compensator's period_s. Throws InputError on a configuration that cannot work.
  SimpleMessageLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                    std::shared_ptr<const JointTrajectory> nominal, StreamTransport& motion, StreamTransport& state,
                    const Clock& clock, const SimpleMessageLinkConfig& config = {});
  /// A temporary clock would dangle: it does not compile (docs/architecture.md, "Ownership").
  SimpleMessageLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                    std::shared_ptr<const JointTrajectory> nominal, StreamTransport& motion, StreamTransport& state,
                    const Clock&& clock, const SimpleMessageLinkConfig& config = {}) = delete;

  /// Waits up to timeout_s (no longer than until the next point is due) for either connection, reads
  /// what came, and sends the next point when it is due. kAnswered: a point was sent (one cycle);
  /// kIdle: nothing to send yet; kRefused / kStopped once, when the link refuses the start or stops.
  LinkPollResult poll(double timeout_s) noexcept override;
  [[nodiscard]] const char* name() const override { return "simple-message"; }
  /// Stops the motion with STOP_TRAJECTORY (the last target sent) and sends nothing more.
  void stop() noexcept override;
  [[nodiscard]] std::string protocol_summary() const override;
  [[nodiscard]] bool winding_down() const override;

  [[nodiscard]] const SimpleMessageCounters& protocol_counters() const { return sm_; }
  [[nodiscard]] const JointStream& stream() const { return stream_; }
  [[nodiscard]] const DelayEstimator& delay() const { return delay_; }
  [[nodiscard]] const DelayEstimator* delay_estimator() const override { return &delay_; }
  /// The lag the controller's buffer adds between a point sent and the arm reaching it (s).
  [[nodiscard]] double buffer_lag_s() const { return config_.buffer_depth * period_s_; }
  /// The last feedback (rad); false before the first.
  [[nodiscard]] bool has_feedback() const { return have_feedback_; }
  [[nodiscard]] const JointVector& feedback() const { return feedback_; }
  /// True when the link has sent the program's last point and it was taken.
  [[nodiscard]] bool program_done() const { return state_ == LinkState::kFinished; }
  /// Bytes written to the motion connection's outbox that the stream has not taken yet.
  [[nodiscard]] std::size_t unsent_bytes() const { return outbox_.pending_bytes(); }
  [[nodiscard]] const SimpleMessageLinkConfig& config() const { return config_; }

 private:
  enum class Port { kMotion, kState };
  bool read_port(Port port, double now) noexcept;
  void discard_input() noexcept;
  bool handle_state_frame(const simple_message::FrameView& f, double now) noexcept;
  void count_bad_decode(simple_message::DecodeStatus s) noexcept;
  bool take_joint_position(const simple_message::FrameView& f, double now) noexcept;
  bool take_robot_status(const simple_message::FrameView& f) noexcept;
  bool handle_motion_frame(const simple_message::FrameView& f, double now) noexcept;
  bool reply_in_step(const simple_message::FrameView& f) noexcept;
  bool take_reply(int reply_code, double now) noexcept;
  bool within_deadlines(double now) noexcept;
  bool begin_session(double now) noexcept;
  LinkPollResult send_point(double now) noexcept;
  bool too_far_behind(double now) noexcept;
  LinkCycle::Verdict plan_point(double now, bool& last) noexcept;
  void fill_point(const JointVector& command) noexcept;
  bool flush() noexcept;
  void fault(LinkStopCause cause, const char* format, ...) noexcept __attribute__((format(printf, 3, 4)));
  void send_stop() noexcept;
  [[nodiscard]] double next_due_s() const noexcept;

  StreamTransport& motion_;
  StreamTransport& state_port_;
  SimpleMessageLinkConfig config_;
  double period_s_;
  SimpleMessageCounters sm_;
  JointStream stream_;
  DelayEstimator delay_;

  simple_message::FrameReader motion_reader_, state_reader_;
  simple_message::FrameOutbox outbox_;
  bool motion_closed_ = false, state_closed_ = false;
  bool stop_reply_due_ = false;  // STOP_TRAJECTORY sent, its reply not read yet

  // Pacing: points accepted, the one waiting for its reply, the schedule's origin (moved by each
  // FAILURE) and the original one (how far behind the program runs).
  std::int32_t next_sequence_ = 0;
  std::uint64_t accepted_ = 0;
  bool waiting_reply_ = false;
  std::int32_t waiting_sequence_ = 0;
  double waiting_since_s_ = 0.0;
  bool waiting_is_last_ = false;
  double schedule_origin_s_ = 0.0, first_origin_s_ = 0.0;
  double finished_at_s_ = 0.0;
  int failures_in_row_ = 0;
  bool sent_any_ = false;

  // Feedback.
  bool have_feedback_ = false;
  double last_state_s_ = 0.0;
  JointVector feedback_, lower_, upper_;

  // Preallocated per-cycle buffers.
  JointVector program_, program_velocity_, blend_, blend_velocity_, nominal_, last_sent_;
  simple_message::JointTrajPt point_;
  simple_message::JointPosition position_;
  simple_message::RobotStatus status_;
};

}  // namespace deflex
