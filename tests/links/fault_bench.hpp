// A bench for the fault table (docs/online.md, "Faults and exit codes"): deflex's runtime session runs
// a link against the simulated cell's stand-in of the real controller (EGM position guidance or path
// correction, KUKA RSI, the RAPID simple message server), on the in-memory network and a clock the
// test advances, and the test injects the faults a cell has: a network outage (MemoryNetwork), a
// stalled deflex (the controller goes on, deflex does not poll), a controller restart, a controller
// that stops, a stale force, a slow consumer. What deflex sends is read off the wire on the
// controller's side (WireTap decodes every datagram it is handed, with the wire's own codec), and the
// two invariants are checked there, against limits the test computes itself from the program it made
// (its peak speed by sampling, not the library's figure) and the settings it gave.
#pragma once

#include <cmath>
#include <memory>
#include <vector>

#include "deflex/cell/egm_path_controller.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/cell/rsi_controller.hpp"
#include "deflex/cell/simple_message_server.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/transport/memory_stream.hpp"
#include "deflex/wire/egm_codec.hpp"
#include "deflex/wire/rsi_xml.hpp"
#include "links/link_harness.hpp"

namespace deflex::test {

/// What the controller received from deflex, in order, decoded with the wire's own codec.
struct WireCommand {
  double t_s = 0.0;                         ///< when the controller read it
  JointVector joints;                       ///< absolute joints (EGM joint, SM) or the joint offset (RSI), rad
  Vector3 offset_m = Vector3::Zero();       ///< EGM path correction: the offset in the correction frame, m
};

/// The controller's transport, decoding every datagram from deflex on the way in.
class WireTap final : public DatagramTransport {
 public:
  WireTap(DatagramTransport& inner, runtime::LinkKind kind, const ManualClock& clock, int joints)
      : inner_(inner), kind_(kind), clock_(clock), codec_(joints), joints_(joints) {}
  bool wait_readable(double timeout_s) noexcept override { return inner_.wait_readable(timeout_s); }
  long receive(unsigned char* buffer, std::size_t capacity, DatagramAddress& from) noexcept override {
    const long n = inner_.receive(buffer, capacity, from);
    if (n > 0 && static_cast<std::size_t>(n) <= capacity) decode(buffer, static_cast<std::size_t>(n));
    return n;
  }
  bool send_to(const unsigned char* data, std::size_t size, const DatagramAddress& to) noexcept override {
    return inner_.send_to(data, size, to);
  }
  [[nodiscard]] DatagramAddress local_address() const noexcept override { return inner_.local_address(); }

  std::vector<WireCommand> commands;

 private:
  void decode(const unsigned char* data, std::size_t size) {
    WireCommand c;
    c.t_s = clock_.now_s();
    if (kind_ == runtime::LinkKind::kEgmJoint) {
      EgmSensorMessage m;
      if (!codec_.decode_sensor(data, size, m)) return;
      c.joints = m.planned_joints_deg * (kPi / 180.0);
    } else if (kind_ == runtime::LinkKind::kEgmPath) {
      EgmPathCorrMessage m;
      if (!codec_.decode_path_corr(data, size, m)) return;
      c.offset_m = m.pos_mm * 1e-3;
    } else {
      RsiSensorMessage m;
      if (decode_rsi_sensor(data, size, "ImFree", joints_, m) != RsiDecodeStatus::kOk) return;
      c.joints = m.correction_deg * (kPi / 180.0);
    }
    commands.push_back(c);
  }

  DatagramTransport& inner_;
  runtime::LinkKind kind_;
  const ManualClock& clock_;
  EgmCodec codec_;
  int joints_;
};

/// The program's largest speed on each joint, by sampling it every 0.5 ms (rad/s): the test's own
/// figure for the step limit, not the library's analytic one.
inline JointVector sampled_peak_speed(const JointTrajectory& p) {
  JointVector peak = JointVector::Zero(p.dof()), a(p.dof()), b(p.dof());
  const double h = 0.0005;
  p.sample(p.start_time_s(), a);
  for (double t = p.start_time_s() + h; t <= p.end_time_s() + h; t += h) {
    p.sample(t, b);
    peak = peak.cwiseMax((b - a).cwiseAbs() / h);
    a = b;
  }
  return peak;
}

struct FaultBench {
  runtime::LinkKind kind;
  RobotModel robot = bench_robot();
  ManualClock clock;
  MemoryNetwork network{clock};
  MemoryTransport& deflex_port = network.add_endpoint(kSensorAddress, 0.0002);
  MemoryTransport& controller_port = network.add_endpoint(kControllerAddress, 0.0002);
  MemoryStreamPair motion{clock, 0.0002};
  MemoryStreamPair state{clock, 0.0002};
  WireTap tap;
  std::shared_ptr<const JointTrajectory> program;
  ConstantForce force;
  runtime::SessionConfig config;
  std::unique_ptr<runtime::Session> session;
  std::unique_ptr<cell::RobotController> controller;
  cell::EgmPositionGuidanceController* egm = nullptr;
  cell::EgmPathCorrectionController* path = nullptr;
  cell::RsiController* rsi = nullptr;
  cell::SimpleMessageServer* server = nullptr;
  std::vector<JointVector> sm_points;  // simple message: every point the server took, in order
  double t_s = 0.0, tick_s = 0.004;
  bool deflex_running = true;  // false: a stalled deflex (scheduler, swap, SIGSTOP): the controller goes on
  JointVector arm;

  /// `program`: the nominal deflex streams (egm-joint, simple message) or the controller's own program
  /// (egm-path, rsi). `tune` changes the session's settings before it is built.
  FaultBench(runtime::LinkKind k, std::shared_ptr<const JointTrajectory> p,
             const std::function<void(runtime::SessionConfig&, cell::SimpleMessageServerConfig&)>& tune = {})
      : kind(k), tap(controller_port, k, clock, 6), program(std::move(p)) {
    const bool sm = kind == runtime::LinkKind::kSimpleMessage;
    const double period = kind == runtime::LinkKind::kEgmPath ? 0.048 : sm ? 0.1 : 0.004;
    config.link = kind;
    config.online = bench_online(period);
    config.online.watchdog_s = std::max(0.05, 2.5 * period);
    config.collect_cycles = true;
    config.egm_path.frame = PathCorrFrame::kTool;
    cell::SimpleMessageServerConfig server_config;
    if (tune) tune(config, server_config);
    runtime::SessionEndpoints ends{&deflex_port, &motion.client(), &state.client()};
    const bool streams = kind == runtime::LinkKind::kEgmJoint || sm;
    session = std::make_unique<runtime::Session>(config, robot, bench_sensor(), streams ? program : nullptr, nullptr,
                                                 &force, clock, ends);
    cell::ControllerConfig cc;
    cc.path_corr_frame = "tool";
    switch (kind) {
      case runtime::LinkKind::kEgmJoint: {
        auto c = std::make_unique<cell::EgmPositionGuidanceController>(cc, program->points().front(), tap, kSensorAddress);
        egm = c.get();
        controller = std::move(c);
        break;
      }
      case runtime::LinkKind::kEgmPath: {
        auto c = std::make_unique<cell::EgmPathCorrectionController>(cc, robot, program, tap, kSensorAddress);
        path = c.get();
        controller = std::move(c);
        break;
      }
      case runtime::LinkKind::kRsi: {
        auto c = std::make_unique<cell::RsiController>(rsi_controller_config(), robot, program, tap, kSensorAddress);
        rsi = c.get();
        controller = std::move(c);
        break;
      }
      case runtime::LinkKind::kSimpleMessage: {
        auto c = std::make_unique<cell::SimpleMessageServer>(server_config, robot, program->points().front(),
                                                            motion.server(), state.server());
        server = c.get();
        controller = std::move(c);
        break;
      }
    }
    arm = program->points().front();
  }

  [[nodiscard]] cell::RsiControllerConfig rsi_controller_config() const {
    cell::RsiControllerConfig c;
    c.upper_limit_deg = rad_to_deg(config.online.max_joint_correction_rad);
    c.lower_limit_deg = -c.upper_limit_deg;
    c.max_correction_deg = 1.1 * c.upper_limit_deg;
    return c;
  }

  /// One servo tick of the controller, then (unless deflex is stalled) deflex polls until idle.
  void tick() {
    t_s += tick_s;
    clock.set(t_s);
    arm = controller->tick(t_s);
    if (server != nullptr && server->last_sequence() >= static_cast<std::int32_t>(sm_points.size())) {
      sm_points.push_back(server->last_target());
    }
    force.reading = reading_at(robot, arm, applied_force);
    clock.set(t_s + 0.0002);
    if (!deflex_running) return;
    while (!session->ended() && session->poll(0.0) != LinkPollResult::kIdle) {
    }
  }
  void run_for(double seconds) {
    const double until = t_s + seconds;
    while (t_s < until - 1e-9 && !session->ended()) tick();
  }

  /// The per-cycle step limit the test expects, per joint (rad): the program's own speed, the ramp-in
  /// blend's (1.5 x the start tolerance over the ramp) and the correction's rate, over one period.
  [[nodiscard]] JointVector joint_step_limit() const {
    const double period = config.online.period_s;
    const JointStreamConfig& s = kind == runtime::LinkKind::kSimpleMessage ? config.simple_message.stream
                                                                             : config.egm_joint.stream;
    const bool streams = kind == runtime::LinkKind::kEgmJoint || kind == runtime::LinkKind::kSimpleMessage;
    JointVector limit = JointVector::Constant(6, period * config.online.max_correction_rate_rad_s);
    if (streams) {
      limit += period * (sampled_peak_speed(*program) * 1.001 +
                         JointVector::Constant(6, s.ramp_in_s > 0 ? 1.5 * s.start_tolerance_rad / s.ramp_in_s : 0.0));
    }
    return limit.array() + 1e-7;  // the float32 and decimal rounding of the wire
  }

  /// The largest step between consecutive commands on the wire over its limit (<= 1 holds the
  /// invariant), from `first` on.
  [[nodiscard]] double worst_step_fraction(std::size_t first = 0) const {
    double worst = 0.0;
    if (kind == runtime::LinkKind::kEgmPath) {
      const double limit = config.online.max_tcp_rate_m_s * config.online.period_s;
      for (std::size_t k = std::max<std::size_t>(first, 1); k < tap.commands.size(); ++k) {
        // The tool frame turns a little between answers: allow its share (offset x angle, < 1 um here).
        worst = std::max(worst, (tap.commands[k].offset_m - tap.commands[k - 1].offset_m).norm() / (limit + 1e-6));
      }
      return worst;
    }
    const JointVector limit = joint_step_limit();
    const auto step = [&](const JointVector& a, const JointVector& b) {
      return ((a - b).cwiseAbs().array() / limit.array()).maxCoeff();
    };
    if (server != nullptr) {
      for (std::size_t k = std::max<std::size_t>(first, 1); k < sm_points.size(); ++k) {
        worst = std::max(worst, step(sm_points[k], sm_points[k - 1]));
      }
      return worst;
    }
    for (std::size_t k = std::max<std::size_t>(first, 1); k < tap.commands.size(); ++k) {
      worst = std::max(worst, step(tap.commands[k].joints, tap.commands[k - 1].joints));
    }
    return worst;
  }

  /// The largest deviation of what was sent from the nominal deflex held (the program at the cycle's
  /// program time, sampled here, plus the blend recorded), over the bound (<= 1 holds).
  [[nodiscard]] double worst_bound_fraction() {
    session->service();
    double worst = 0.0;
    const double bound = config.online.max_joint_correction_rad * (1 + 1e-9) + 1e-7;
    JointVector q(6);
    for (const LinkCycleRecord& r : session->collected()) {
      if (!r.replied) continue;
      if (kind == runtime::LinkKind::kEgmPath) {
        worst = std::max(worst, r.tcp_correction_m.norm() / config.online.max_tcp_correction_m);
        continue;
      }
      if (kind == runtime::LinkKind::kRsi) {
        worst = std::max(worst, (r.q_command - r.q_nominal).cwiseAbs().maxCoeff() / bound);
        continue;
      }
      program->sample(r.program_time_s, q);
      EXPECT_LT((r.q_nominal - q).cwiseAbs().maxCoeff(), 1e-12) << "the nominal recorded is not the program";
      worst = std::max(worst, (r.q_command - (q + r.q_blend)).cwiseAbs().maxCoeff() / bound);
    }
    return worst;
  }

  Vector3 applied_force = Vector3(0.0, 0.0, -650.0);  ///< the process force at the TCP (base frame)
};

}  // namespace deflex::test
