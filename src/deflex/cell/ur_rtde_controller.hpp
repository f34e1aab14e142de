// The controller side of a Universal Robots arm streamed over RTDE, as the real one behaves, never
// more kindly (../shared/reference/ur_rtde.md):
//   - the RTDE server on one stream connection: protocol version 2 only; the URControl version of the
//     configured series (5.x e-Series, 500 Hz; 3.x CB3, 125 Hz); an output recipe at a frequency above
//     the series' loop is refused (the start is not accepted), an unknown field is NOT_FOUND, an input
//     register in `in_use_registers` is IN_USE; after the start one output package every loop cycle;
//   - the URScript program deflex's controller setup writes, playing from construction: every cycle it
//     takes the newest input registers, and while the mode register says servo hands the six targets
//     to servoj with the lookahead and gain the registers carry (0.03..0.2 s, 100..2000; outside them
//     the program stops with an error, as servoj raises one); the end mode holds the last target and
//     ends the program after twice the lookahead (at most half the watchdog's period); it echoes the counter taken in
//     its output register;
//   - servoj's lookahead is a dead time of the lookahead and its gain a first-order lag of 1/gain s;
//   - a servo target moving any joint faster than `max_speed_rad_s` (the safety configuration's joint
//     speed limit) is a protective stop: the arm halts where it is, safety_mode 3, the program paused;
//   - the watchdog (rtde_set_watchdog on the counter register, action stop): the counter unchanged for
//     `watchdog_s` once the first target came stops the program and the arm halts;
//   - a connection closed by the client ends the RTDE session; the program's watchdog then stops it.
// Faults on request (tests): protective_stop(), emergency_stop(), stop_program() (the pendant's stop),
// error_message() (an error text message), stall_network() (TCP stalls both ways: nothing is read,
// what is written arrives once it ends, the script runs on with the registers it has). It knows nothing of deflex.
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "deflex/cell/robot_controller.hpp"
#include "deflex/transport/stream_transport.hpp"
#include "deflex/wire/rtde.hpp"

namespace deflex::cell {

struct UrRtdeControllerConfig {
  bool e_series = true;           ///< URControl 5.x (500 Hz loop) or CB3's 3.x (125 Hz)
  int register_offset = 24;       ///< the layout deflex's script uses (controller setup's --ur-register-offset)
  double max_speed_rad_s = 3.14;  ///< the safety configuration's joint speed limit (UR5e: 180 deg/s)
  double watchdog_s = 0.1;        ///< rtde_set_watchdog's 10 Hz minimum
  /// Input registers another writer holds (a fieldbus, another RTDE client): IN_USE.
  std::vector<int> in_use_registers;
  [[nodiscard]] double period_s() const { return e_series ? 0.002 : 0.008; }
};

struct UrRtdeControllerCounters {
  std::uint64_t outputs = 0;   ///< output data packages sent
  std::uint64_t inputs = 0;    ///< input data packages taken
  std::uint64_t rejected = 0;  ///< packages from the client that did not decode
  std::uint64_t servo_cycles = 0;
};

/// Thread safety: one thread at a time (the simulation's), with its stream.
class UrRtdeController final : public RobotController {
 public:
  /// The arm starts at rest at `q_start` (rad); the program is playing, waiting for targets.
  UrRtdeController(const UrRtdeControllerConfig& config, const JointVector& q_start, StreamTransport& stream);

  const JointVector& tick(double t_s) override;
  void encoders(const JointVector& q_motor_rad) override;
  [[nodiscard]] const char* name() const override { return "UR RTDE"; }

  [[nodiscard]] const UrRtdeControllerCounters& counters() const { return counters_; }
  /// "" while the program plays; otherwise why it stopped.
  [[nodiscard]] const std::string& stopped() const { return stopped_; }
  [[nodiscard]] std::int32_t safety_mode() const { return safety_mode_; }
  [[nodiscard]] const JointVector& position() const { return position_; }
  /// Every servo target the program handed to servoj (one a cycle, the newest registers), in order.
  [[nodiscard]] const std::vector<JointVector>& targets() const { return targets_; }
  /// The lookahead and gain servoj ran with last.
  [[nodiscard]] double lookahead_s() const { return lookahead_s_; }
  [[nodiscard]] double gain() const { return gain_; }

  void protective_stop(const std::string& why);
  void emergency_stop();
  void stop_program();
  /// Sends a text message of error level (1) naming `text`.
  void error_message(const std::string& text);
  /// The connection stalls until `until_s`: outputs are held back and sent together at its end, inputs
  /// wait unread in the stream.
  void stall_network(double until_s) { stall_until_s_ = until_s; }

 private:
  void read_client();
  void handle(const unsigned char* p, std::size_t size, std::uint8_t type);
  void setup(const unsigned char* p, std::size_t size, rtde::PackageType type);
  void servo_cycle(double t_s);
  void send_outputs(double t_s);
  void send(std::size_t n, double t_s = -1.0);
  void halt(const std::string& why, std::uint32_t runtime_state);

  UrRtdeControllerConfig config_;
  StreamTransport& stream_;
  std::vector<unsigned char> rx_, tx_;
  std::size_t rx_size_ = 0;
  bool started_ = false, closed_ = false, have_inputs_ = false;
  rtde::Recipe out_recipe_, in_recipe_;
  std::vector<std::string> out_fields_, in_fields_;
  double stall_until_s_ = -1.0;
  std::vector<unsigned char> held_;  // outputs written during a stall
  double next_cycle_s_ = 0.0, last_counter_change_s_ = 0.0, end_at_s_ = -1.0;
  std::vector<unsigned char> inputs_;  // the newest input package (registers keep their last value)
  std::int32_t counter_ = 0, echo_ = 0, safety_mode_ = 1;
  std::uint32_t runtime_state_ = 2;
  std::string stopped_;
  double lookahead_s_ = 0.0, gain_ = 0.0;
  JointVector target_, position_, previous_, encoders_;
  bool have_encoders_ = false;
  std::deque<std::pair<double, JointVector>> delay_;
  std::vector<JointVector> targets_;
  UrRtdeControllerCounters counters_;
};

}  // namespace deflex::cell
