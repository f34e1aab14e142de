// The controller side of FANUC Stream Motion (J519), as the real controller behaves, never more
// kindly (../shared/reference/fanuc_j519.md; what FANUC's text leaves open is taken the strict way and
// said so):
//   - it streams nothing until a start packet comes; then a status every interval (8 ms by default)
//     to the sender, numbered from 1, with the arm's joints (degrees), the ready bit once the TP
//     program waits in IBGN (`ready_after_s`), the in-motion bit;
//   - each command must carry the next sequence number in turn, starting from a status already sent
//     (else MOTN-601, sequence error); a command of another protocol version is MOTN-607;
//   - commands queue ($STMO.$PKT_STACK deep); motion starts once `start_buffer` are queued, and from
//     then on one is taken every interval: an empty queue then is MOTN-603 (receiving interval over);
//   - every target taken is checked as the controller does (fanuc_j519::MotionCheck: velocity,
//     acceleration and jerk of each axis from the finite differences at the interval): one over a
//     limit is MOTN-609/610/611, and it is not applied;
//   - an alarm stops the stream: the arm decelerates to rest where it is (dead time, then the servo's
//     lag), the ready bit clears (and, in protocol 3 and 4, the in-error bit sets); statuses go on
//     until a stop packet (unconfirmed in FANUC's text: the strict reading keeps reporting);
//   - a command flagged last-data ends the session as planned once it is taken (the TP program leaves
//     IBGN: the ready bit clears, no alarm; FANUC's text does not say when the bit clears);
//   - the arm follows the targets taken after a dead time, through a first-order servo lag;
//   - a threshold request (axis, kind) is answered with the table of the limits it enforces, while no
//     stream runs (before the start packet or after a stop packet: FANUC's own driver asks before the
//     start; whether the controller answers during a stream is not published, so it does not);
//     `answer_thresholds` off is older system software, which answers none. FANUC publishes no table, so
//     its 20 speed columns are a made-up profile whose strictest value is the enforced limit: full payload
//     at 100 % of the maximum Cartesian speed is the limit, each 5 % slower allows limit / 19 more (twice
//     the limit at 5 %), and no payload allows 1.25 times full payload's;
//   - of protocol 3 or 4, a capability get (type 7, id as asked) is answered, while no stream runs (as the
//     tables), with its version as available_version, its interval as sampling_rate and start_buffer as
//     start_move (status at the faceplate); of protocol 1 it is not answered (version 1 documents no
//     capability packet);
//   - a start packet or a command of another protocol version than its own is MOTN-607 "ST: Protocol version
//     mismatch PC n, Rob m" (the reference's v3 client on a v1 controller); the statuses it then sends are
//     of its own version, the ready bit clear.
// Faults on request (tests): an alarm now (an e-stop), a restart of the TP program (a new session,
// numbered from 1 again). A network outage is the network's. It knows nothing of deflex.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "deflex/cell/robot_controller.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/fanuc_j519.hpp"

namespace deflex::cell {

struct FanucJ519ControllerConfig {
  double interval_s = 0.008;  ///< $STMO.$COM_INT: 8 ms, 4 ms, or 1 ms with S647
  std::uint32_t version = 1;
  std::size_t packet_stack = 10;  ///< $STMO.$PKT_STACK: commands the controller queues at most
  /// Commands queued before motion starts (protocol 3's start_move): one spare against a lost status.
  std::size_t start_buffer = 2;
  double ready_after_s = 0.05;  ///< from the start packet to the TP program waiting in IBGN
  /// From a target taken to the drives following it: the controller's interpolation and servo delay,
  /// assumed 3 intervals (not published by FANUC; users report tens of milliseconds).
  double dead_time_s = 0.024;
  double servo_lag_s = 0.01;  ///< first-order lag of the drives following the delayed target
  /// The limits it holds the stream to (deg/s, deg/s^2, deg/s^3): a CRX-10iA/L's strictest.
  std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> limits = strict_crx();
  bool answer_thresholds = true;                  ///< false: older system software, threshold requests go unanswered
  std::uint32_t max_cartesian_speed_mm_s = 2000;  ///< $STMO_GRP's $MAX_SPD, the tables' 100 % column

  static std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> strict_crx() {
    std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> l{};
    l.fill({120.0, 265.0, 1240.0});
    return l;
  }
};

struct FanucJ519ControllerCounters {
  std::uint64_t statuses = 0;  ///< status packets sent
  std::uint64_t commands = 0;  ///< commands queued
  std::uint64_t taken = 0;     ///< targets taken (one an interval once moving)
  std::uint64_t ignored = 0;   ///< datagrams that were not a packet it takes
  std::uint64_t starts = 0, stops = 0;
  std::uint64_t threshold_requests = 0;   ///< threshold requests received (answered or not)
  std::uint64_t threshold_replies = 0;    ///< threshold tables sent
  std::uint64_t capability_requests = 0;  ///< capability gets received (answered or not)
  std::uint64_t capability_replies = 0;   ///< capability replies sent
};

/// Thread safety: one thread at a time (the simulation's), with its transport.
class FanucJ519Controller final : public RobotController {
 public:
  /// The arm starts at rest at `q_start` (rad); the controller listens on `transport`.
  FanucJ519Controller(const FanucJ519ControllerConfig& config, const JointVector& q_start,
                      DatagramTransport& transport);

  const JointVector& tick(double t_s) override;
  void encoders(const JointVector& q_motor_rad) override;
  [[nodiscard]] const char* name() const override { return "FANUC Stream Motion"; }

  [[nodiscard]] const FanucJ519ControllerCounters& counters() const { return counters_; }
  /// "" while none; otherwise the alarm that stopped the stream ("MOTN-603 ...").
  [[nodiscard]] const std::string& alarm() const { return alarm_; }
  /// Where the arm is (rad).
  [[nodiscard]] const JointVector& position() const { return position_; }
  /// The session ended as planned (a last-data command taken).
  [[nodiscard]] bool ended() const { return ended_; }
  /// The controller's own check of every target taken (its peaks: what deflex's stream reached).
  [[nodiscard]] const fanuc_j519::MotionCheck& check() const { return check_; }
  /// Every target taken (rad), in order: what deflex's stream moved the arm to.
  [[nodiscard]] const std::vector<JointVector>& taken() const { return taken_; }

  /// An alarm now (an e-stop, a servo fault): the stream stops as for any alarm.
  void raise_alarm(const std::string& code);
  /// The TP program restarted at t_s: a new session, statuses numbered from 1, the queue empty, the
  /// ready bit after ready_after_s; the alarm cleared.
  void restart(double t_s);

 private:
  void read_packets(double t_s);
  void answer_threshold(std::size_t size, const DatagramAddress& from);
  void answer_capability(std::size_t size, const DatagramAddress& from);
  void version_mismatch(std::uint32_t pc_version);
  void take_command(double t_s);
  void send_status(double t_s, double stamp_s);
  void stop_stream(const std::string& alarm);

  FanucJ519ControllerConfig config_;
  DatagramTransport& transport_;
  std::vector<unsigned char> buffer_;
  fanuc_j519::MotionCheck check_;
  bool streaming_ = false;  // a start packet came (and no stop since)
  DatagramAddress pc_;
  double ready_at_s_ = 0.0;
  double next_status_s_ = 0.0;
  double last_t_s_ = 0.0;
  std::uint32_t status_seq_ = 0;
  std::uint32_t expected_seq_ = 0;  // the next command's number (0: none taken yet)
  std::deque<fanuc_j519::Command> queue_;
  bool moving_ = false;
  bool ended_ = false;
  std::string alarm_;
  JointVector target_, position_, encoders_;
  bool have_encoders_ = false;
  std::deque<std::pair<double, JointVector>> delay_;  // targets taken and when, for the dead time
  JointVector following_;                             // the target the drives follow now
  std::vector<JointVector> taken_;
  FanucJ519ControllerCounters counters_;
};

}  // namespace deflex::cell
