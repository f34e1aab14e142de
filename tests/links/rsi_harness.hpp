// A deterministic bench for deflex's KUKA RSI link: the simulated cell's RSI controller stand-in (which
// behaves as KUKA's does: a <Rob> every 4 ms, an answer carrying that IPOC expected within the cycle,
// late answers counted up to the Timeout, AXISCORR's absolute offsets clamped to its limits) runs its
// own program and talks to the real link class over the in-memory network, on a clock the test
// advances. The controller's limits are set from deflex's own bound, as `deflex controller-setup`
// writes them. Forces and the expected corrections come from link_harness.hpp (independent of the
// link: plain frame algebra and a finite-difference Jacobian).
#pragma once

#include <memory>

#include "deflex/cell/rsi_controller.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/rsi/rsi_link.hpp"
#include "links/link_harness.hpp"

namespace deflex::test {

inline cell::RsiControllerConfig rsi_controller_for(const OnlineConfig& online) {
  cell::RsiControllerConfig c;
  c.upper_limit_deg = rad_to_deg(online.max_joint_correction_rad);
  c.lower_limit_deg = -c.upper_limit_deg;
  c.max_correction_deg = 1.1 * c.upper_limit_deg;
  return c;
}

struct RsiBench {
  RobotModel robot = bench_robot();
  ManualClock clock;
  MemoryNetwork network{clock};
  MemoryTransport& sensor_port = network.add_endpoint(kSensorAddress, 0.0002);
  MemoryTransport& controller_port = network.add_endpoint(kControllerAddress, 0.0002);
  OnlineCompensator compensator;
  OnlineStrategy strategy;
  cell::RsiControllerConfig controller_config;
  ConstantForce force;
  std::shared_ptr<const JointTrajectory> program;
  RsiLink link;
  std::unique_ptr<cell::RsiController> controller;
  double t_s = 0.0;

  explicit RsiBench(std::shared_ptr<const JointTrajectory> p, StrategyKind kind = StrategyKind::kOnline,
                    const ForceModel* model = nullptr, RsiLinkConfig config = {})
      : compensator(robot, bench_sensor(), bench_online()),
        strategy(robot, kind, model),
        controller_config(rsi_controller_for(compensator.config())),
        program(std::move(p)),
        link(compensator, strategy, sensor_port, clock, config),
        controller(
            std::make_unique<cell::RsiController>(controller_config, robot, program, controller_port, kSensorAddress)) {
    link.read_force_from(&force);
  }

  /// The arm's axes now (the controller's motor side), without advancing anything.
  [[nodiscard]] const JointVector& arm() const { return arm_; }

  /// One 4 ms cycle of the controller, then deflex answers what reached it. Returns the last poll
  /// result (kIdle when nothing came).
  LinkPollResult tick(bool deflex_answers = true) {
    t_s += controller_config.cycle_s;
    clock.set(t_s);
    arm_ = controller->tick(t_s);
    clock.set(t_s + 0.0002);
    LinkPollResult last = LinkPollResult::kIdle;
    while (deflex_answers) {
      const LinkPollResult r = link.poll(0.0);
      if (r == LinkPollResult::kIdle) break;
      last = r;
    }
    return last;
  }

 private:
  JointVector arm_;
};

}  // namespace deflex::test
