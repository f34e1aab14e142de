// Yaskawa MotoROS2's real-time motion interface, deflex as the motion source. Once the ROS 2 service
// start_rt_mode has put the controller in the mode (joint increments), deflex sends one command to the
// controller (UDP 22000) and waits for its reply before the next: strict lock-step, paced by the
// controller's interpolation clock (4 ms for one arm). A command carries INCREMENTS for one cycle;
// deflex holds the absolute target
//     target = program(p) + blend - dtheta,   |target_i - (program_i(p) + blend_i)| <= bound,
// and sends target - c, where c is the command position the controller's last reply reported (the sum
// of every increment it accepted), never the sum of what deflex sent: an increment the Functional
// Safety Unit truncated, or one lost on the way, is folded into the next (the per-cycle step limit
// bounds that increment, so the catch-up is spread over cycles) and the absolute stays within the bound
// of the nominal. The per-cycle step limit holds on every increment on the wire.
//
// The program's clock is the controller's: it moves on one cycle per reply. A reply that does not come
// within `resend_after_s` has its command sent again with the same number (the controller answers a
// number it has taken with its previous reply and does not apply it twice; one it never got it applies),
// so deflex never skips a number and never makes the controller's sequence check drop the session. A
// reply is taken only from the controller's address, of the reply's exact size, finite, echoing the
// number outstanding; anything else is counted and never answered. The truncation flag is counted; a
// run of more than `max_truncation_run` flagged replies in a row stops the link (kController): the
// stream is faster than the safety unit's speed limit lets the arm go.
//
// A session starts with command 0 of zero increments (the protocol's keep-alive): its reply's command
// position is the anchor (the offset to the program is blended out). It ends once the reply to the
// program's last increment (or, on a planned stop, the last of the ramp to rest on the path) came back:
// the controller then holds the arm and ends its real-time session itself after its timeout_for_rt_msg
// (or at once on stop_traj_mode). stop() sends nothing more: the arm stops where its last increment took
// it. A silence longer than the stop silence is a controller that dropped the session (a sequence jump,
// a second sender, an increment beyond its per-cycle maximum, its own timeout) or stopped (kSilent).
// Given the status side channel (the RobotState datagram the controller sends every 10 ms to the PC's
// port 22001), a status from the controller's address reporting an e-stop, an error, the drives off or
// motion not possible stops the link at once (kController), naming it; a status that does not decode
// is counted and ignored.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "deflex/link/controller_link.hpp"
#include "deflex/link/joint_stream.hpp"
#include "deflex/online/delay_estimator.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/motoros2_rt.hpp"

namespace deflex {

struct Motoros2RtLinkConfig {
  DatagramAddress controller;  ///< where the controller listens (rt_listener_udp_port_number, 22000)
  int group = 0;               ///< the control group deflex streams (0..7; 0: the first robot)
  int tool = 0;                ///< the tool number sent with every command (0..63)
  JointStreamConfig stream;
  LinkStopRules stop;
  std::size_t history_cycles = 1000;
  double initial_delay_s = 0.03;
  /// A command whose reply has not come this long is sent again, with the same number.
  double resend_after_s = 0.012;
  /// Replies in a row with the safety unit's truncation flag before the link stops (0: the first).
  int max_truncation_run = 25;
  std::size_t max_packet_bytes = 4096;
  /// The PC's UDP port the controller's RobotState comes to (rt_status_udp_port_number, 22001); -1: not
  /// read. The session opens it; a link built directly is given its transport.
  int status_port = -1;
  /// Throws InputError naming the setting.
  void validate() const;
};

/// Thread safety: one thread at a time (the loop's), as every ControllerLink.
class Motoros2RtLink final : public ControllerLink {
 public:
  /// Every reference must outlive the link. The controller's interpolation period is the compensator's
  /// period_s; `status` (may be null) receives the controller's RobotState. Throws InputError on a bad
  /// setting or a program for another number of joints.
  Motoros2RtLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                 std::shared_ptr<const JointTrajectory> nominal, DatagramTransport& transport, const Clock& clock,
                 const Motoros2RtLinkConfig& config, DatagramTransport* status = nullptr);
  Motoros2RtLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                 std::shared_ptr<const JointTrajectory> nominal, DatagramTransport& transport, const Clock&& clock,
                 const Motoros2RtLinkConfig& config, DatagramTransport* status = nullptr) = delete;

  LinkPollResult poll(double timeout_s) noexcept override;
  void stop() noexcept override;
  [[nodiscard]] const char* name() const override { return "motoros2-rt"; }
  [[nodiscard]] const DelayEstimator* delay_estimator() const override { return &delay_; }
  [[nodiscard]] std::string protocol_summary() const override;

  [[nodiscard]] const JointStream& stream() const { return stream_; }
  /// Replies that carried the safety unit's truncation flag.
  [[nodiscard]] std::uint64_t truncations() const { return truncations_; }
  /// Replies whose command position was not what deflex's increment should have made it (an increment
  /// lost, purged or truncated): the difference went into the next increment.
  [[nodiscard]] std::uint64_t shortfalls() const { return shortfalls_; }
  /// Commands sent again because their reply did not come in time.
  [[nodiscard]] std::uint64_t resent() const { return resent_; }
  /// RobotState datagrams taken from the status side channel, and those refused (another address, not
  /// the struct's size, a boolean neither 0 nor 1).
  [[nodiscard]] std::uint64_t statuses() const { return statuses_; }
  [[nodiscard]] std::uint64_t statuses_refused() const { return statuses_refused_; }

 private:
  bool receive_reply(double timeout_s) noexcept;
  bool read_status() noexcept;
  bool take(const unsigned char* data, long n, const DatagramAddress& from) noexcept;
  bool read_reply() noexcept;
  bool send(std::uint32_t sequence, const JointVector& increment) noexcept;
  void resend_if_due(double now) noexcept;
  LinkPollResult start_session() noexcept;
  LinkPollResult answer(double now) noexcept;
  LinkPollResult finish() noexcept;

  Motoros2RtLinkConfig config_;
  DatagramTransport& transport_;
  DatagramTransport* status_;
  JointStream stream_;
  DelayEstimator delay_;
  double period_s_;
  std::uint32_t outstanding_ = 0;  // the number of the command whose reply deflex waits for
  bool sent_any_ = false;
  double last_send_s_ = -1e300;
  std::uint64_t truncations_ = 0, shortfalls_ = 0, resent_ = 0, statuses_ = 0, statuses_refused_ = 0;
  int truncation_run_ = 0;
  std::size_t tx_size_ = 0;

  // Preallocated per-cycle buffers.
  std::vector<unsigned char> rx_, tx_, encoded_;  // tx_: the last command sent (what a resend repeats)
  motoros2_rt::Reply reply_, scratch_;
  motoros2_rt::Command command_;
  JointVector feedback_, reported_, expected_, increment_, program_, program_velocity_, blend_, blend_velocity_,
      nominal_;
  double receipt_age_s_ = 0.0, taken_at_s_ = 0.0;
};

}  // namespace deflex
