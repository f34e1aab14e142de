// The controller side of ABB EGM position guidance in joint mode (EGMActJoint + EGMRunJoint), as the
// real controller behaves, never more kindly:
//   - every egm_period_s it sends an EgmRobot with the motor-side joints as feedback and, as
//     "planned", the reference it is following: the sensor's own last target;
//   - it takes each EgmSensor's joints as the absolute target (and its speed reference, when sent),
//     filters them (\LpFilter), and its servo follows them after a dead time with
//       speed = k (target - position) + speed reference
//     (k the position gain: PosCorrGain x the configured proportional position gain);
//   - with no answer for egm_comm_timeout_s EGM stops and the arm holds where it is;
//   - the faults of a real cell on request (tests): a new EGM session (EGMRunJoint called again: the
//     sequence starts again, and the reference starts from where the arm is or stays the one
//     followed), EGM ended by the program (mciState STOPPED) or an error (ERROR) while it goes on
//     streaming its state, the motors off (an emergency stop). A network outage is the network's
//     (MemoryNetwork::add_outage).
// It knows nothing of deflex: only the wire format, over a datagram transport.
#pragma once

#include <cstdint>
#include <vector>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/robot_controller.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/egm_codec.hpp"

namespace deflex::cell {

struct EgmControllerCounters {
  std::uint64_t sent = 0;     ///< EgmRobot messages
  std::uint64_t targets = 0;  ///< EgmSensor messages taken
  std::uint64_t ignored = 0;  ///< datagrams that were not a usable answer
  bool timed_out = false;     ///< EGM stopped for lack of answers
};

/// Thread safety: one thread at a time (the simulation's), with its transport.
class EgmPositionGuidanceController final : public RobotController {
 public:
  /// The arm starts at rest at `q_start` (rad). `transport` must outlive the controller; the sensor
  /// (deflex) listens at `sensor`.
  EgmPositionGuidanceController(const ControllerConfig& config, const JointVector& q_start,
                                DatagramTransport& transport, const DatagramAddress& sensor);

  const JointVector& tick(double t_s) override;
  void encoders(const JointVector& q_motor_rad) override;
  [[nodiscard]] const char* name() const override { return "EGM position guidance"; }
  [[nodiscard]] const EgmControllerCounters& counters() const { return counters_; }
  /// The target the controller follows now (rad): the sensor's last one.
  [[nodiscard]] const JointVector& target() const { return target_; }

  /// A new EGM session at t_s (EGMRunJoint called again, after a timeout too): the sequence number
  /// starts again at 1; with `reset_reference` the reference is where the arm is now, else the one it
  /// followed stays.
  void restart(double t_s, bool reset_reference);
  /// EGM ends with `mci_state` (2 STOPPED, 1 ERROR): targets are no longer taken, the arm holds, the
  /// controller keeps streaming its state.
  void end_session(int mci_state);
  /// The motors go off (an emergency stop): the arm stops where it is, motorState OFF is reported.
  void motors_off();

 private:
  void reset_reference();
  ControllerConfig config_;
  DatagramTransport& transport_;
  DatagramAddress sensor_;
  EgmCodec codec_;
  std::vector<unsigned char> buffer_;
  EgmRobotMessage robot_;
  EgmSensorMessage answer_;
  JointVector encoders_;  ///< the last encoder reading: the feedback it reports
  bool have_encoders_ = false;
  JointVector target_, speed_ref_, filtered_target_, filtered_speed_, position_;
  // Delay line of the filtered references, one entry a servo tick.
  std::vector<JointVector> delay_target_, delay_speed_;
  std::size_t delay_head_ = 0;
  double last_t_s_ = 0.0, next_send_s_ = 0.0, last_answer_s_ = 0.0;
  std::uint32_t seqno_ = 0;
  bool stopped_ = false;
  bool streaming_after_stop_ = false;  // EGM ended by the program: the state goes on being sent
  bool reset_pending_ = false;         // a restart's reference reset, after the answers already in flight
  EgmControllerCounters counters_;
};

}  // namespace deflex::cell
