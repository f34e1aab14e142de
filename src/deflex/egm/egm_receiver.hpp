// The receiving half shared by deflex's EGM links: drains the transport every cycle, decodes the
// EgmRobot messages, and keeps only the newest usable one from the controller. Empty, oversized,
// truncated, malformed, incomplete and non-finite packets, joints beyond the robot's limits,
// duplicates and stale sequence numbers, sequence numbers far ahead of the running one or wider than
// 32 bits, and datagrams from another sender than the controller's are counted and never handed on.
// A controller restart (sequence numbers starting again, a jump confirmed by the packets after it, or
// a message after a silence, measured from the last datagram the controller sent) is recognised.
// It also measures how the messages arrive (link_timing.hpp). Never allocates after construction.
#pragma once

#include <cstdint>
#include <vector>

#include "deflex/link/controller_gate.hpp"
#include "deflex/link/controller_link.hpp"
#include "deflex/model/robot_model.hpp"
#include "deflex/transport/clock.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/egm_codec.hpp"

namespace deflex {

struct EgmReceiverConfig {
  std::size_t max_packet_bytes = 1400;  ///< larger datagrams are "oversized" and ignored
  /// Silence after which any sequence number starts a new session (the controller restarted), and
  /// after which another sender may take the link over (a controller that came back on a new port).
  double restart_silence_s = 0.5;
  /// A backwards jump to a sequence number at most this is a restart, not a stale packet.
  std::uint32_t restart_seqno_max = 16;
  /// A sequence number more than this ahead of the running one is a stray (far_ahead) unless
  /// `confirm_jump` packets in a row continue it. The default is 1 s of 4 ms cycles: twice the
  /// restart silence, so no genuine gap without a silence is that long.
  std::uint32_t max_seqno_ahead = 250;
  int confirm_jump = 3;
  /// The controller's cycle, for the arrival diagnostics (a message later than this is "late"). The
  /// EGM links set it to their compensator's period (deflex online --period-ms).
  double period_s = 0.004;
  /// Throws InputError on a value out of its range.
  void validate() const;
};

/// `config` with the controller's period set to `period_s` (what the EGM links pass their receiver).
[[nodiscard]] inline EgmReceiverConfig with_period(EgmReceiverConfig config, double period_s) {
  config.period_s = period_s;
  return config;
}

/// Thread safety: one thread at a time (the link's).
class EgmReceiver {
 public:
  /// `transport`, `clock` and `counters` must outlive the receiver. Throws InputError.
  EgmReceiver(DatagramTransport& transport, const Clock& clock, const RobotModel& model,
              const EgmReceiverConfig& config, LinkCounters& counters);
  /// A temporary clock would dangle: it does not compile (docs/architecture.md, "Ownership").
  EgmReceiver(DatagramTransport& transport, const Clock&& clock, const RobotModel& model,
              const EgmReceiverConfig& config, LinkCounters& counters) = delete;

  enum class Result { kNothing, kNoneUsable, kMessage };
  /// Waits up to timeout_s, drains, and leaves the newest usable message in message(). `restarted`
  /// tells whether that message starts a new session.
  Result drain(double timeout_s, bool& restarted) noexcept;
  [[nodiscard]] const EgmRobotMessage& message() const { return newest_; }
  /// Sends to the controller (the sender of the newest message).
  bool reply(const unsigned char* data, std::size_t size) noexcept;
  [[nodiscard]] EgmCodec& codec() { return codec_; }
  [[nodiscard]] bool has_controller() const { return gate_.has_controller(); }
  [[nodiscard]] const DatagramAddress& controller() const { return gate_.controller(); }
  /// Clock time of the last usable message (s).
  [[nodiscard]] double last_message_s() const { return last_accept_s_; }
  /// From the newest message's arrival at the host to `now_s` (the link's clock), s; NaN when the
  /// transport cannot tell.
  [[nodiscard]] double answer_time_s(double now_s) const noexcept { return receipt_age_s_ + (now_s - taken_at_s_); }
  /// How the newest message arrived (diagnostics; also counted in the counters).
  [[nodiscard]] const LinkArrival& arrival() const { return arrival_; }

 private:
  bool decoded(std::size_t size) noexcept;
  bool plausible(const EgmRobotMessage& m) const noexcept;

  DatagramTransport& transport_;
  const Clock& clock_;
  EgmReceiverConfig config_;
  LinkCounters& counters_;
  EgmCodec codec_;
  JointVector lower_, upper_;
  std::vector<unsigned char> rx_;
  EgmRobotMessage msg_, newest_;
  ControllerGate gate_;
  double last_accept_s_ = 0.0;
  double receipt_age_s_ = 0.0, taken_at_s_ = 0.0;  // the taken message's age when it was read, and when
  LinkArrival arrival_, msg_arrival_;
};

}  // namespace deflex
