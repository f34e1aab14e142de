// The library-timed loop: it feeds the state callback's joints and the source's samples to the
// compensator and hands over the same outputs a hand-driven step() gives; no allocation per cycle.
#include <optional>

#include <gtest/gtest.h>

#include "deflex/model/robot_io.hpp"
#include "deflex/online/detail/periodic_loop.hpp"
#include "deflex/text/errors.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

class OneSamplePerCall final : public ForceSource {
 public:
  bool latest(ForceSample& out) noexcept override {
    served_ = !served_;
    if (served_) {
      out.wrench_sensor << 0.0, 150.0, -400.0, 0.0, 0.0, 0.0;
    }
    return served_;
  }

 private:
  bool served_ = false;
};

TEST(PeriodicLoop, RunsTheCompensatorWithTheCallbacksState) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  OnlineConfig cfg;
  cfg.max_correction_rate_rad_s = 100.0;
  cfg.max_tcp_rate_m_s = 100.0;  // no ramp: the loop's and the hand's clocks may differ by microseconds
  cfg.watchdog_s = 10.0;
  OnlineCompensator looped(robot, sensor, cfg);
  OnlineCompensator by_hand(robot, sensor, cfg);
  OneSamplePerCall source, source2;
  JointVector q(6);
  q << 0.2, 0.3, 0.1, -0.4, 0.5, 0.6;
  std::atomic<bool> stop{false};
  int calls = 0;
  CycleOutput last;
  std::size_t allocations = 0;
  std::optional<test::AllocationGuard> guard;
  const LoopStats stats = run_periodic(
      looped, &source, 0.001, stop,
      [&](CycleInput& in) {
        if (calls == 2) {
          guard.emplace();  // steady state from the third cycle on
        }
        in.q_planned = q;
        in.q_feedback = q;
        return ++calls <= 30;
      },
      [&](const CycleOutput& out) { last = out; });
  ASSERT_TRUE(guard.has_value());
  allocations = guard->allocations();
  guard.reset();
  EXPECT_EQ(stats.cycles, 30u);
  EXPECT_EQ(allocations, 0u);
  CycleOutput expected;
  for (int k = 0; k < 30; ++k) {
    expected = by_hand.step({0.001 * k, q, q}, source2);
  }
  EXPECT_EQ(last.status, CycleStatus::kOk);
  EXPECT_LT((last.q_command - expected.q_command).norm(), 1e-15);
  EXPECT_GT(last.dtheta.norm(), 1e-6);
  EXPECT_THROW((void)run_periodic(looped, nullptr, 0.0, stop, nullptr, nullptr), InputError);
}

}  // namespace
}  // namespace deflex
