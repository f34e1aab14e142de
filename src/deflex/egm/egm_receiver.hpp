// The receiving half shared by deflex's EGM links: drains the transport every cycle, decodes the
// EgmRobot messages, and keeps only the newest usable one from the controller. Empty, oversized,
// truncated, malformed, incomplete and non-finite packets, joints beyond the robot's limits,
// duplicates and stale sequence numbers, and datagrams from another sender than the controller's are
// counted and never handed on. A controller restart (sequence numbers starting again, or a message
// after a silence) is recognised. Never allocates after construction.
#pragma once

#include <cstdint>
#include <vector>

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
  /// Throws InputError on a value out of its range.
  void validate() const;
};

class EgmReceiver {
 public:
  /// `transport`, `clock` and `counters` must outlive the receiver. Throws InputError.
  EgmReceiver(DatagramTransport& transport, const Clock& clock, const RobotModel& model, const EgmReceiverConfig& config,
              LinkCounters& counters);

  enum class Result { kNothing, kNoneUsable, kMessage };
  /// Waits up to timeout_s, drains, and leaves the newest usable message in message(). `restarted`
  /// tells whether that message starts a new session.
  Result drain(double timeout_s, bool& restarted) noexcept;
  [[nodiscard]] const EgmRobotMessage& message() const { return newest_; }
  /// Sends to the controller (the sender of the newest message).
  bool reply(const unsigned char* data, std::size_t size) noexcept;
  [[nodiscard]] EgmCodec& codec() { return codec_; }
  [[nodiscard]] bool has_controller() const { return have_sender_; }
  [[nodiscard]] const DatagramAddress& controller() const { return sender_; }
  /// Clock time of the last usable message (s).
  [[nodiscard]] double last_message_s() const { return last_accept_s_; }

 private:
  bool plausible(const EgmRobotMessage& m) const noexcept;

  DatagramTransport& transport_;
  const Clock& clock_;
  EgmReceiverConfig config_;
  LinkCounters& counters_;
  EgmCodec codec_;
  JointVector lower_, upper_;
  std::vector<unsigned char> rx_;
  EgmRobotMessage msg_, newest_;
  bool have_sender_ = false;
  DatagramAddress sender_;
  bool have_seq_ = false;
  std::uint32_t last_seq_ = 0;
  double last_accept_s_ = 0.0;
};

}  // namespace deflex
