// A bench for the fault table (docs/online.md, "Faults and exit codes"): deflex's runtime session
// against the simulated cell's stand-in of the real controller, in memory (standin/standin_session.hpp:
// EGM position guidance or path correction, KUKA RSI, the RAPID simple message server, FANUC Stream
// Motion, MotoROS2 real-time), with the
// faults a cell has injected by the test. What deflex sent is read off the wire on the controller's
// side, and the two invariants are checked there, against limits the test computes itself from the
// program it made (its peak speed by sampling, not the library's figure) and the settings it gave.
#pragma once

#include <cmath>
#include <functional>
#include <memory>
#include <vector>

#include "deflex/online/online_strategy.hpp"
#include "deflex/standin/standin_session.hpp"
#include "links/link_harness.hpp"
#include "support/sampled_speed.hpp"

namespace deflex::test {

inline runtime::SessionConfig bench_session(runtime::LinkKind kind) {
  runtime::SessionConfig c;
  const bool sm = kind == runtime::LinkKind::kSimpleMessage;
  const double period = kind == runtime::LinkKind::kEgmPath     ? 0.048
                        : sm                                    ? 0.1
                        : kind == runtime::LinkKind::kFanucJ519 ? 0.008
                        : kind == runtime::LinkKind::kUrRtde    ? 0.002
                                                                : 0.004;
  c.link = kind;
  c.online = bench_online(period);
  c.online.watchdog_s = std::max(0.05, 2.5 * period);
  c.collect_cycles = true;
  c.status_interval_s = 0.0;
  return c;
}

struct FaultBench {
  runtime::LinkKind kind;
  RobotModel robot = bench_robot();
  std::shared_ptr<const JointTrajectory> program;
  runtime::SessionConfig config;
  std::unique_ptr<standin::StandInSession> standin;
  runtime::Session* session = nullptr;

  /// `program`: the nominal deflex streams (egm-joint, simple message) or the controller's own program
  /// (egm-path, rsi). `tune` changes the settings before anything is built. The process force: 650 N
  /// down at the TCP.
  FaultBench(runtime::LinkKind k, std::shared_ptr<const JointTrajectory> p,
             const std::function<void(runtime::SessionConfig&, standin::StandInConfig&)>& tune = {})
      : kind(k), program(std::move(p)), config(bench_session(k)) {
    standin::StandInConfig sc;
    sc.force_base_n = Vector3(0.0, 0.0, -650.0);
    if (tune) tune(config, sc);
    standin = std::make_unique<standin::StandInSession>(config, robot, bench_sensor(), program, nullptr, sc);
    session = &standin->session();
  }

  void run_for(double seconds) { standin->run_for(seconds); }
  [[nodiscard]] double t_s() const { return standin->time_s(); }
  [[nodiscard]] const std::vector<standin::WireCommand>& wire() const { return standin->wire(); }

  /// The per-cycle step limit the test expects, per joint (rad): the program's own speed, the ramp-in
  /// blend's (1.5 x the start tolerance over the ramp) and the correction's rate, over one period.
  [[nodiscard]] JointVector joint_step_limit() const {
    const double period = config.online.period_s;
    const JointStreamConfig& s = kind == runtime::LinkKind::kSimpleMessage ? config.simple_message.stream
                                 : kind == runtime::LinkKind::kFanucJ519   ? config.fanuc_j519.stream
                                 : kind == runtime::LinkKind::kMotoros2Rt  ? config.motoros2_rt.stream
                                 : kind == runtime::LinkKind::kUrRtde      ? config.ur_rtde.stream
                                                                           : config.egm_joint.stream;
    const bool streams = runtime::link_kind(kind).streams_program;
    JointVector limit = JointVector::Constant(6, period * config.online.max_correction_rate_rad_s);
    if (streams) {
      limit += period * (sampled_peak_speed(*program) * 1.001 +
                         JointVector::Constant(6, s.ramp_in_s > 0 ? 1.5 * s.start_tolerance_rad / s.ramp_in_s : 0.0));
    }
    return limit.array() + 1e-7;  // the float32 and decimal rounding of the wire
  }

  /// The largest step between consecutive commands on the wire over its limit (<= 1 holds the
  /// invariant), from the `first`-th command on.
  [[nodiscard]] double worst_step_fraction(std::size_t first = 0) const {
    double worst = 0.0;
    if (kind == runtime::LinkKind::kEgmPath) {
      const double limit = config.online.max_tcp_rate_m_s * config.online.period_s;
      const auto& w = wire();
      for (std::size_t k = std::max<std::size_t>(first, 1); k < w.size(); ++k) {
        // The tool frame turns a little between answers: allow its share (offset x angle, < 1 um here).
        worst = std::max(worst, (w[k].offset_m - w[k - 1].offset_m).norm() / (limit + 1e-6));
      }
      return worst;
    }
    const JointVector limit = joint_step_limit();
    const auto step = [&](const JointVector& a, const JointVector& b) {
      return ((a - b).cwiseAbs().array() / limit.array()).maxCoeff();
    };
    std::vector<JointVector> commands;
    for (const auto& c : wire()) commands.push_back(c.joints);
    for (std::size_t k = std::max<std::size_t>(first, 1); k < commands.size(); ++k) {
      worst = std::max(worst, step(commands[k], commands[k - 1]));
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
};

}  // namespace deflex::test
