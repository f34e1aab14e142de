// A deterministic bench for deflex's controller links: the simulated cell's controller stand-ins
// (which behave as ABB's controllers do: position guidance follows deflex's absolute target after a
// dead time and reports it as "planned"; path correction applies the whole offset it is sent) talk to
// the real link classes over the in-memory network, on a clock the test advances. Forces come from a
// constant raw reading, so the expected correction is the lumped model's, computed here
// independently with a finite-difference Jacobian.
#pragma once

#include <memory>

#include "deflex/cell/egm_path_controller.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/egm/egm_joint_link.hpp"
#include "deflex/egm/egm_path_link.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/transport/memory_network.hpp"
#include "online/fd_jacobian.hpp"

namespace deflex::test {

inline const DatagramAddress kSensorAddress{0x7f000001, 6510};
inline const DatagramAddress kControllerAddress{0x7f000002, 6511};
inline const DatagramAddress kStrangerAddress{0x7f000003, 7000};

/// A constant raw sensor reading, one sample a poll (the watchdog sees a live sensor) while on.
class ConstantForce final : public ForceSource {
 public:
  bool latest(ForceSample& out) noexcept override {
    if (!on || served_) {
      served_ = false;
      return false;
    }
    served_ = true;
    out.t_s = 0.0;
    out.wrench_sensor = reading;
    out.valid = true;
    return true;
  }
  Vector6 reading = Vector6::Zero();
  bool on = true;

 private:
  bool served_ = false;
};

/// The IRB 6700 with a 350 mm tool; the sensor at the flange (so the reading is the flange wrench).
inline RobotModel bench_robot() {
  Pose tool = Pose::Identity();
  tool.translation() = Vector3(0.0, 0.0, 0.35);
  return builtin_irb6700().with_tool(tool);
}

inline SensorConfig bench_sensor() {
  SensorConfig c;
  c.components = 6;
  c.sample_rate_hz = 250.0;
  c.lowpass_cutoff_hz = 25.0;
  return c;
}

inline OnlineConfig bench_online(double period_s = 0.004) {
  OnlineConfig c;
  c.period_s = period_s;
  // A rate bound whose step a cycle fits in the 0.01 rad bound at any period up to 100 ms.
  c.max_correction_rate_rad_s = std::min(0.2, 0.009 / period_s);
  c.max_tcp_rate_m_s = 0.04;
  c.watchdog_s = 0.05;
  return c;
}

/// The reading of a 6-component sensor at the flange when force f_base acts at the TCP with the arm
/// at q (independent of the conditioning pipeline: plain frame algebra).
inline Vector6 reading_at(const RobotModel& robot, const JointVector& q, const Vector3& f_base) {
  Workspace ws(robot);
  forward_kinematics(robot, ws, q);
  const Matrix3 R = ws.base_T_flange.linear();
  Vector6 w;
  w.head<3>() = R.transpose() * f_base;
  w.tail<3>() = robot.flange_T_wap().translation().cross(Vector3(w.head<3>()));
  return w;
}

/// dtheta = K^-1 J^T W with a finite-difference Jacobian (the model's answer, computed here).
inline JointVector model_correction(const RobotModel& robot, const JointVector& q, const Vector3& f_base) {
  const Jacobian J = fd_wap_jacobian(robot, q);
  Wrench w = Wrench::Zero();
  w.head<3>() = f_base;
  return robot.compliance().cwiseProduct(J.transpose() * w);
}

/// A hold-still program at q for `seconds`, or a move from q by `delta` over `seconds`.
inline std::shared_ptr<const JointTrajectory> hold_program(const RobotModel& robot, const JointVector& q,
                                                           double seconds) {
  return std::make_shared<const JointTrajectory>(std::vector<double>{0.0, seconds}, std::vector<JointVector>{q, q},
                                                 robot, "hold");
}

inline std::shared_ptr<const JointTrajectory> sweep_program(const RobotModel& robot, const JointVector& q,
                                                            const JointVector& delta, double seconds, int points = 41) {
  std::vector<double> t;
  std::vector<JointVector> qs;
  for (int i = 0; i < points; ++i) {
    const double u = static_cast<double>(i) / (points - 1);
    t.push_back(u * seconds);
    qs.push_back(q + delta * (0.5 - 0.5 * std::cos(kPi * u)));
  }
  return std::make_shared<const JointTrajectory>(t, qs, robot, "sweep");
}

/// Controller stand-in + deflex's position-guidance link on one in-memory network.
struct JointBench {
  RobotModel robot = bench_robot();
  ManualClock clock;
  MemoryNetwork network{clock};
  MemoryTransport& sensor_port = network.add_endpoint(kSensorAddress, 0.0002);
  MemoryTransport& controller_port = network.add_endpoint(kControllerAddress, 0.0002);
  cell::ControllerConfig controller_config;
  OnlineCompensator compensator;
  OnlineStrategy strategy;
  ConstantForce force;
  std::shared_ptr<const JointTrajectory> program;
  EgmJointLink link;
  std::unique_ptr<cell::EgmPositionGuidanceController> controller;
  double t_s = 0.0;

  JointBench(std::shared_ptr<const JointTrajectory> p, const JointVector& arm_start,
             StrategyKind kind = StrategyKind::kOnline, const ForceModel* model = nullptr,
             EgmJointLinkConfig config = {})
      : compensator(robot, bench_sensor(), bench_online()),
        strategy(robot, kind, model),
        program(std::move(p)),
        link(compensator, strategy, program, sensor_port, clock, config),
        controller(std::make_unique<cell::EgmPositionGuidanceController>(controller_config, arm_start, controller_port,
                                                                         kSensorAddress)) {
    link.read_force_from(&force);
  }

  /// One 4 ms servo tick of the controller, then deflex answers what reached it. Returns the last
  /// poll result of the tick (kIdle when nothing came).
  LinkPollResult tick() {
    t_s += controller_config.servo_period_s;
    clock.set(t_s);
    controller->tick(t_s);
    clock.set(t_s + 0.0002);
    LinkPollResult last = LinkPollResult::kIdle;
    for (;;) {
      const LinkPollResult r = link.poll(0.0);
      if (r == LinkPollResult::kIdle) break;
      last = r;
    }
    return last;
  }
};

}  // namespace deflex::test

namespace deflex::test {

/// Controller stand-in running its own program + deflex's path-correction link.
struct PathBench {
  RobotModel robot = bench_robot();
  ManualClock clock;
  MemoryNetwork network{clock};
  MemoryTransport& sensor_port = network.add_endpoint(kSensorAddress, 0.0002);
  MemoryTransport& controller_port = network.add_endpoint(kControllerAddress, 0.0002);
  cell::ControllerConfig controller_config;
  OnlineCompensator compensator;
  OnlineStrategy strategy;
  ConstantForce force;
  std::shared_ptr<const JointTrajectory> program;
  EgmPathLink link;
  std::unique_ptr<cell::EgmPathCorrectionController> controller;
  double t_s = 0.0;

  static cell::ControllerConfig with_frame(cell::ControllerConfig c, const std::string& frame, double period_s) {
    c.path_corr_frame = frame;
    c.path_corr_period_s = period_s;
    return c;
  }
  static EgmPathLinkConfig link_config(const std::string& frame) {
    EgmPathLinkConfig c;
    c.frame = parse_path_corr_frame(frame);
    return c;
  }

  PathBench(std::shared_ptr<const JointTrajectory> p, const std::string& frame = "tool", double period_s = 0.048,
            StrategyKind kind = StrategyKind::kOnline, const ForceModel* model = nullptr)
      : controller_config(with_frame({}, frame, period_s)),
        compensator(robot, bench_sensor(), bench_online(period_s)),
        strategy(robot, kind, model),
        program(std::move(p)),
        link(compensator, strategy, sensor_port, clock, link_config(frame)),
        controller(std::make_unique<cell::EgmPathCorrectionController>(controller_config, robot, program,
                                                                       controller_port, kSensorAddress)) {
    link.read_force_from(&force);
  }

  /// One servo tick of the controller, then deflex answers what reached it.
  LinkPollResult tick() {
    t_s += controller_config.servo_period_s;
    clock.set(t_s);
    controller->tick(t_s);
    clock.set(t_s + 0.0002);
    LinkPollResult last = LinkPollResult::kIdle;
    for (;;) {
      const LinkPollResult r = link.poll(0.0);
      if (r == LinkPollResult::kIdle) break;
      last = r;
    }
    return last;
  }
};

}  // namespace deflex::test
