// The controller side of Yaskawa MotoROS2's real-time motion interface (joint increments), as the real
// one behaves, never more kindly (../shared/reference/motoros2_rt.md; where its sources leave a point
// open the strict reading is taken and said so):
//   - the session is open from construction (start_rt_mode called); the first command's sender is the
//     only commander, and its first command must carry number 0 (strict: the sources say the PC sends
//     0 first, not what the controller does otherwise);
//   - one command is taken an interpolation period: its increment is applied at the clock and answered
//     with one reply (to the command's source), and every other datagram queued by then is discarded;
//   - a command whose number is not ahead of the last taken is answered with the previous reply and not
//     applied; one more than `max_sequence_gap` ahead drops the session ("Missed too many command
//     packets"); a smaller gap is accepted and the missing increments are simply never applied;
//   - a datagram of another size, another version or increment kind, a second sender, a non-finite
//     increment, or an increment above the axis' maximum per interpolation period drops the session;
//   - no command for `timeout_s` drops the session; a dropped session answers nothing more;
//   - the Functional Safety Unit's speed limit truncates an increment beyond it; the reply to that
//     command still reports the command position as if the whole increment were taken (strict: the
//     sources do not say when the truncation shows), the next one reports the truncated position and
//     sets the truncation flag;
//   - the arm follows the command position after a dead time, through a first-order servo lag;
//   - with a status port, a RobotState every `status_period_s` to the first commander's IP at that port,
//     healthy while the session runs and after it was dropped (strict: the sources do not say a
//     dropped session shows there), reporting the e-stop after stop().
// Faults on request (tests): stop() (an e-stop, an alarm, stop_traj_mode: it stops answering, the arm
// comes to rest where it is), restart() (a new session: stop_traj_mode, start_rt_mode). It knows
// nothing of deflex.
#pragma once

#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "deflex/cell/robot_controller.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/motoros2_rt.hpp"

namespace deflex::cell {

struct Motoros2RtControllerConfig {
  double period_s = 0.004;  ///< the interpolation period (start_rt_mode's `period`)
  int group = 0;            ///< the control group the arm is
  std::int32_t max_sequence_gap = motoros2_rt::kDefaultMaxSequenceGap;  ///< max_sequence_diff_for_rt_msg
  double timeout_s = 5.0;                                               ///< timeout_for_rt_msg (< 0: never)
  /// From an increment taken to the drives following it: the controller's interpolation and servo
  /// delay, assumed 3 periods (not published by Yaskawa).
  double dead_time_s = 0.012;
  double servo_lag_s = 0.01;  ///< first-order lag of the drives following the delayed command
  /// Every axis' maximum speed (rad/s): an increment above it times the period drops the session.
  double max_speed_rad_s = 3.0;
  /// The FSU's speed limit per axis (rad/s): larger increments are truncated to it. Infinite: none set.
  double fsu_speed_rad_s = std::numeric_limits<double>::infinity();
  int status_port = -1;           ///< rt_status_udp_port_number (22001); -1: no status sent
  double status_period_s = 0.01;  ///< rt_status_sleep_period
};

struct Motoros2RtControllerCounters {
  std::uint64_t replies = 0;     ///< reply datagrams sent
  std::uint64_t taken = 0;       ///< commands applied
  std::uint64_t duplicates = 0;  ///< commands answered with the previous reply, not applied
  std::uint64_t skipped = 0;     ///< numbers never received within an accepted gap (their increments lost)
  std::uint64_t purged = 0;      ///< datagrams discarded after a command was taken
  std::uint64_t truncated = 0;   ///< increments the FSU truncated
  std::uint64_t statuses = 0;    ///< RobotState datagrams sent
};

/// Thread safety: one thread at a time (the simulation's), with its transport.
class Motoros2RtController final : public RobotController {
 public:
  /// The arm starts at rest at `q_start` (rad), the command position there; the session is open.
  Motoros2RtController(const Motoros2RtControllerConfig& config, const JointVector& q_start,
                       DatagramTransport& transport);

  const JointVector& tick(double t_s) override;
  void encoders(const JointVector& q_motor_rad) override;
  [[nodiscard]] const char* name() const override { return "MotoROS2 real-time"; }

  [[nodiscard]] const Motoros2RtControllerCounters& counters() const { return counters_; }
  /// "" while the session runs; otherwise why it ended ("Missed too many command packets", ...).
  [[nodiscard]] const std::string& dropped() const { return dropped_; }
  [[nodiscard]] const JointVector& position() const { return position_; }
  /// The command position: the sum of every increment applied (rad).
  [[nodiscard]] const JointVector& command_position() const { return command_; }
  /// The command position after every increment applied, in order (what deflex's stream commanded).
  [[nodiscard]] const std::vector<JointVector>& taken() const { return taken_; }
  /// Every increment applied as received (before the FSU), in order.
  [[nodiscard]] const std::vector<JointVector>& increments() const { return increments_; }

  /// An e-stop: the controller stops answering, the arm comes to rest, the status (if sent) reports it.
  void stop(const std::string& why);
  /// A new session (stop_traj_mode, start_rt_mode) at t_s: from the command position where the arm is,
  /// waiting for a first command numbered 0 from any sender.
  void restart(double t_s);

 private:
  void read_commands(double t_s);
  bool handle(const unsigned char* data, std::size_t size, const DatagramAddress& from, double t_s);
  void apply(const motoros2_rt::Command& c, const DatagramAddress& from, double t_s);
  void drop(const std::string& why);
  void send_status(double t_s);

  Motoros2RtControllerConfig config_;
  DatagramTransport& transport_;
  std::vector<unsigned char> buffer_, last_reply_;
  std::size_t last_reply_size_ = 0;
  bool have_pc_ = false, have_last_ = false;
  DatagramAddress pc_;
  std::uint32_t last_sequence_ = 0;
  double last_command_s_ = 0.0;
  double last_t_s_ = 0.0;
  std::string dropped_;
  JointVector command_, shortfall_, position_, encoders_, following_;
  bool have_encoders_ = false, truncated_last_ = false, estop_ = false;
  double next_status_s_ = 0.0;
  std::deque<std::pair<double, JointVector>> delay_;
  std::vector<JointVector> taken_, increments_;
  Motoros2RtControllerCounters counters_;
};

}  // namespace deflex::cell
