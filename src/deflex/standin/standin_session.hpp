// deflex's runtime session against a stand-in of the controller, in memory: one of the simulated
// cell's controllers (EGM position guidance or path correction, KUKA RSI, the RAPID simple message
// server: each with the real controller's behaviour, dead time included) on an in-memory network and
// a clock this object advances, a force sensor on the arm reading a process force given in the base
// frame, and the faults a cell has on request: a network outage, a stalled deflex, a controller
// restart, a controller that ends its session or loses its motors, RSI switched off and on, a force
// sensor that stops. What deflex sent is read off the wire on the controller's side, decoded with the
// wire's own codec. For trying a session from Python with no controller at hand, the fault-table
// tests and examples; the runtime itself never includes it (the cell is simulated hardware).
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "deflex/cell/egm_path_controller.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/cell/fanuc_j519_controller.hpp"
#include "deflex/cell/motoros2_rt_controller.hpp"
#include "deflex/cell/rsi_controller.hpp"
#include "deflex/cell/simple_message_server.hpp"
#include "deflex/cell/ur_rtde_controller.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/transport/memory_network.hpp"
#include "deflex/transport/memory_stream.hpp"

namespace deflex::standin {

/// What the controller received from deflex, in order, decoded with the wire's own codec (simple message:
/// every point the server took, as the frame carried it).
struct WireCommand {
  double t_s = 0.0;  ///< when the controller read it
  /// Absolute joints (egm-joint, simple message, fanuc-j519; ur-rtde: each target the script handed to servoj;
  /// motoros2-rt: the command position each increment taken moved the controller to) or the joint offset (rsi), rad.
  JointVector joints;
  Vector3 offset_m = Vector3::Zero();  ///< egm-path: the offset in the correction frame, m
};

struct StandInConfig {
  cell::ControllerConfig controller;       ///< EGM's period, dead time, filter, gain, timeout (path frame: tool)
  cell::SimpleMessageServerConfig server;  ///< the RAPID server's buffer, state period, read period
  /// The RSI controller; its AXISCORR limits and AXISCORRMON follow the session's bound when NaN.
  cell::RsiControllerConfig rsi;
  /// FANUC Stream Motion: its queue, dead time, lag and limits (the interval and the protocol version
  /// follow the session's).
  cell::FanucJ519ControllerConfig fanuc;
  /// MotoROS2 real-time: its dead time, lag, speed limits, sequence gap and timeout (the period follows
  /// the session's).
  cell::Motoros2RtControllerConfig motoros2;
  /// Universal Robots over RTDE: its series, speed limit and watchdog (the register layout follows the
  /// session's).
  cell::UrRtdeControllerConfig ur;
  double network_latency_s = 0.0002;       ///< one way
  Vector3 force_base_n = Vector3::Zero();  ///< the process force at the TCP, base frame (N)
  double sensor_rate_hz = 250.0;           ///< samples a second the stand-in sensor gives (one a tick at 250 Hz)
};

/// A force/torque sensor at the flange of the stand-in arm: the wrench `force_base_n` at the TCP
/// exerts, in the sensor frame, moment about the sensor origin (plain frame algebra; no noise).
/// Thread safety: one thread at a time (the stand-in's).
class ArmForceSensor final : public ForceSource {
 public:
  ArmForceSensor(const RobotModel& robot, const SensorConfig& sensor);
  /// The arm's joints now (rad) and the force at the TCP (base frame, N); one sample a call of sample().
  void set(const JointVector& q_arm, const Vector3& force_base_n);
  void sample(double t_s) noexcept;
  bool latest(ForceSample& out) noexcept override;
  bool on = true;  ///< false: the sensor stops (a stale force)

 private:
  RobotModel robot_;
  Pose flange_T_sensor_;
  Workspace ws_;
  ForceSample pending_;
  bool have_ = false;
};

/// Thread safety: one thread at a time: the stand-in runs its controller, network, clock and
/// stepped session on the caller's thread (only session().request_stop() may come from elsewhere,
/// as for any Session).
class StandInSession {
 public:
  /// Builds the stand-in of `config.link`'s controller and deflex's session on it. `program`: the
  /// nominal deflex streams (egm-joint, simple message) or the controller's own program (egm-path,
  /// rsi). Throws InputError as the session does.
  StandInSession(const runtime::SessionConfig& config, const RobotModel& robot, const SensorConfig& sensor,
                 std::shared_ptr<const JointTrajectory> program, const ForceModel* force_model,
                 const StandInConfig& standin = {});
  ~StandInSession();
  StandInSession(const StandInSession&) = delete;
  StandInSession& operator=(const StandInSession&) = delete;

  /// One controller tick (4 ms), then deflex polls until idle (unless stalled).
  void tick();
  /// Ticks for `seconds` of the stand-in's clock, or until the session ended.
  void run_for(double seconds);

  // The faults of a cell.
  /// Every datagram in [now, now + seconds) is lost, both ways (ur-rtde: its TCP connection stalls that long).
  void outage(double seconds);
  /// The controller's next `count` messages are overtaken in the network by the one after them.
  void reorder(int count);
  /// deflex stops reading (a stalled PC, SIGSTOP) / goes on; the controller goes on either way.
  void stall(bool stalled) { stalled_ = stalled; }
  /// The controller starts a new session now: EGM (EGMRunJoint again, with its reference reset to
  /// the arm or kept), path correction (EGMActMove again), RSI (RSI_ON again after `off_s` of RSI_OFF).
  void restart(bool reset_reference = true, double off_s = 0.0);
  /// The controller ends its session now: EGM with mciState `mci_state` (2 STOPPED, 1 ERROR).
  void end_session(int mci_state = 2);
  /// The motors go off (EGM: an emergency stop); simple message: the server's emergency stop; FANUC: an
  /// e-stop alarm; MotoROS2: the controller stops answering; UR: a robot emergency stop.
  void motors_off();
  /// The force sensor stops (true) or comes back.
  void sensor_silent(bool silent) { sensor_.on = !silent; }
  /// The process force from now on (base frame, N).
  void set_force(const Vector3& force_base_n) { standin_.force_base_n = force_base_n; }

  [[nodiscard]] runtime::Session& session() { return *session_; }
  [[nodiscard]] const std::vector<WireCommand>& wire() const { return wire_; }
  [[nodiscard]] double time_s() const { return t_s_; }
  [[nodiscard]] const JointVector& arm() const { return arm_; }
  [[nodiscard]] runtime::LinkKind link() const { return kind_; }
  [[nodiscard]] const runtime::SessionConfig& config() const { return config_; }
  [[nodiscard]] const JointTrajectory& program() const { return *program_; }
  [[nodiscard]] cell::RobotController& controller() { return *controller_; }
  [[nodiscard]] cell::EgmPositionGuidanceController* egm() { return egm_; }
  [[nodiscard]] cell::EgmPathCorrectionController* path() { return path_; }
  [[nodiscard]] cell::RsiController* rsi() { return rsi_; }
  [[nodiscard]] cell::SimpleMessageServer* server() { return server_; }
  [[nodiscard]] cell::FanucJ519Controller* fanuc() { return fanuc_; }
  [[nodiscard]] cell::Motoros2RtController* motoros2() { return motoros2_; }
  [[nodiscard]] cell::UrRtdeController* ur() { return ur_; }
  [[nodiscard]] MemoryNetwork& network() { return network_; }
  [[nodiscard]] ManualClock& clock() { return clock_; }

 private:
  class Tap;
  void decode(const unsigned char* data, std::size_t size);

  runtime::LinkKind kind_;
  runtime::SessionConfig config_;
  StandInConfig standin_;
  RobotModel robot_;
  std::shared_ptr<const JointTrajectory> program_;
  ManualClock clock_;
  MemoryNetwork network_;
  MemoryTransport& deflex_port_;
  MemoryTransport& controller_port_;
  MemoryStreamPair motion_, state_;
  std::unique_ptr<Tap> tap_;
  ArmForceSensor sensor_;
  std::unique_ptr<runtime::Session> session_;
  std::unique_ptr<cell::RobotController> controller_;
  cell::EgmPositionGuidanceController* egm_ = nullptr;
  cell::EgmPathCorrectionController* path_ = nullptr;
  cell::RsiController* rsi_ = nullptr;
  cell::SimpleMessageServer* server_ = nullptr;
  cell::FanucJ519Controller* fanuc_ = nullptr;
  cell::Motoros2RtController* motoros2_ = nullptr;
  cell::UrRtdeController* ur_ = nullptr;
  std::size_t ur_seen_ = 0;  // the UR script's servo targets already in wire_
  std::vector<WireCommand> wire_;
  std::size_t motoros2_seen_ = 0;  // the MotoROS2 controller's increments already in wire_
  double t_s_ = 0.0;
  double next_sample_s_ = 0.0;
  bool stalled_ = false;
  JointVector arm_;
};

}  // namespace deflex::standin
