// deflex's FANUC Stream Motion link against a stand-in of the controller with its semantics
// (cell/fanuc_j519_controller.hpp: lock-step sequence numbers, a command queue that must never run
// dry, the velocity / acceleration / jerk check of every target, alarms that stop the stream, dead
// time and servo lag): the command converges to the model's correction (computed here with a
// finite-difference Jacobian) without the controller ever alarming, and every fault a cell has ends
// with the link stopped for a named reason and nothing beyond the bound or the step limit sent.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "deflex/cell/fanuc_j519_controller.hpp"
#include "deflex/fanuc/fanuc_j519_link.hpp"
#include "deflex/text/errors.hpp"
#include "links/link_harness.hpp"
#include "support/allocation_guard.hpp"
#include "support/poses.hpp"
#include "support/sampled_speed.hpp"

namespace deflex {
namespace {

using test::pose_deg;

OnlineConfig fanuc_online() {
  OnlineConfig c = test::bench_online(0.008);
  c.max_correction_rate_rad_s = deg_to_rad(3.0);  // deflex online's default --max-rate-deg-s
  return c;
}

struct FanucBench {
  RobotModel robot = test::bench_robot();
  ManualClock clock;
  MemoryNetwork network{clock};
  MemoryTransport& pc_port = network.add_endpoint(test::kSensorAddress, 0.0002);
  MemoryTransport& controller_port = network.add_endpoint(test::kControllerAddress, 0.0002);
  OnlineCompensator compensator;
  OnlineStrategy strategy;
  test::ConstantForce force;
  std::shared_ptr<const JointTrajectory> program;
  FanucJ519Link link;
  cell::FanucJ519Controller controller;
  double t_s = 0.0;
  bool stalled = false;
  // The wire invariants, checked on what the controller took.
  double worst_deviation_rad = 0.0;

  static FanucJ519LinkConfig link_config(std::uint32_t version) {
    FanucJ519LinkConfig c;
    c.controller = test::kControllerAddress;
    c.version = version;
    return c;
  }
  static cell::FanucJ519ControllerConfig controller_config(std::uint32_t version, double interval_s) {
    cell::FanucJ519ControllerConfig c;
    c.version = version;
    c.interval_s = interval_s;
    return c;
  }

  FanucBench(std::shared_ptr<const JointTrajectory> p, const JointVector& arm, std::uint32_t version = 1,
             std::uint32_t controller_version = 0, double controller_interval_s = 0.008)
      : FanucBench(std::move(p), arm, link_config(version),
                   controller_config(controller_version == 0 ? version : controller_version, controller_interval_s)) {}
  FanucBench(std::shared_ptr<const JointTrajectory> p, const JointVector& arm, const FanucJ519LinkConfig& link_settings,
             const cell::FanucJ519ControllerConfig& controller_settings)
      : compensator(robot, test::bench_sensor(), fanuc_online()),
        strategy(robot, StrategyKind::kOnline, nullptr),
        program(std::move(p)),
        link(compensator, strategy, program, pc_port, clock, link_settings),
        controller(controller_settings, arm, controller_port) {
    link.read_force_from(&force);
  }

  /// One 4 ms servo tick of the controller, then deflex polls until idle or stopped, each poll under an
  /// allocation guard: the allocations the polls made.
  std::size_t tick_counting_allocations() {
    t_s += 0.004;
    clock.set(t_s);
    controller.tick(t_s);
    clock.set(t_s + 0.0002);
    std::size_t allocations = 0;
    for (;;) {
      test::AllocationGuard guard;
      const LinkPollResult r = link.poll(0.0);
      allocations += guard.allocations();
      if (r == LinkPollResult::kIdle || link.state() == LinkState::kStopped) return allocations;
    }
  }

  /// One 4 ms servo tick of the controller, then deflex answers what reached it (unless stalled).
  LinkPollResult tick() { return tick(stalled ? nullptr : &link); }
  /// The same with `polled` answering (nullptr: no PC answers).
  LinkPollResult tick(FanucJ519Link* polled) {
    t_s += 0.004;
    clock.set(t_s);
    controller.tick(t_s);
    clock.set(t_s + 0.0002);
    LinkPollResult last = LinkPollResult::kIdle;
    while (polled != nullptr) {
      const LinkPollResult r = polled->poll(0.0);
      if (r == LinkPollResult::kIdle) break;
      last = r;
    }
    return last;
  }
  void run(double seconds) {
    const double end = t_s + seconds;
    while (t_s < end - 1e-9) tick();
  }
};

// What the controller took never moved by more than the per-cycle step limit computed here (the
// program's peak speed sampled every 0.5 ms, the blend's 1.5 x 0.2 deg over the 1 s ramp-in, the 3 deg/s
// rate bound, over 8 ms), and never left the program (sampled here at the program time the link
// recorded) plus its blend by more than the bound it was configured with.
void expect_wire_invariants(const FanucBench& b) {
  const JointVector limit = 0.008 * (test::sampled_peak_speed(*b.program) * 1.001).array() +
                            0.008 * (1.5 * deg_to_rad(0.2) / 1.0 + deg_to_rad(3.0)) + 1e-6;
  const std::vector<JointVector>& taken = b.controller.taken();
  for (std::size_t k = 1; k < taken.size(); ++k) {
    const JointVector step = (taken[k] - taken[k - 1]).cwiseAbs();
    for (int j = 0; j < step.size(); ++j) {
      ASSERT_LE(step[j], limit[j]) << "target " << k << " joint " << j + 1;
    }
  }
  const double bound = b.compensator.config().max_joint_correction_rad + 1e-6;
  JointVector q(6);
  const LinkHistory& h = b.link.history();  // the last 1000 cycles
  for (std::size_t k = 0; k < h.size(); ++k) {
    const LinkCycleRecord& r = h.at(k);
    if (!r.replied) continue;
    b.program->sample(r.program_time_s, q);
    ASSERT_LE((r.q_command - (q + r.q_blend)).cwiseAbs().maxCoeff(), bound) << "at " << r.t_s << " s";
  }
}

TEST(FanucJ519Link, ConstantForceHoldsTheModelsCorrectionAndTheControllerNeverAlarms) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 60.0), q0);
  const Vector3 f_base(150.0, -250.0, -300.0);
  const JointVector expected = test::model_correction(bench.robot, q0, f_base);
  ASSERT_LT(expected.cwiseAbs().maxCoeff(), bench.compensator.config().max_joint_correction_rad);
  for (int k = 0; k < 5000; ++k) {  // 20 s
    bench.force.reading = test::reading_at(bench.robot, bench.controller.position(), f_base);
    bench.tick();
    ASSERT_EQ(bench.controller.alarm(), "") << "at " << bench.t_s << " s";
  }
  ASSERT_EQ(bench.link.state(), LinkState::kRunning);
  const JointVector sent = q0 - bench.controller.taken().back();
  EXPECT_LT((sent - expected).cwiseAbs().maxCoeff(), 0.01 * expected.cwiseAbs().maxCoeff())
      << "sent " << sent.transpose() << "\nmodel " << expected.transpose();
  // The stream stayed within what the controller allows, and the smoother's bounds were the binding ones.
  const fanuc_j519::AxisLimits& peak = bench.controller.check().peak();
  EXPECT_LE(peak.jerk, 0.25 * 1240.0 + 1e-6);
  EXPECT_LE(peak.acceleration, 0.25 * 265.0 + 1e-6);
  EXPECT_GT(peak.jerk, 1.0);  // the correction did move the stream
  EXPECT_EQ(bench.link.counters().guard_trips, 0u);
  expect_wire_invariants(bench);
}

TEST(FanucJ519Link, AProgramUnderAForceStepEndsWithLastDataAndNoAlarm) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(12, -6, 9, 15, -12, 25), 6.0);
  FanucBench bench(program, q0);
  for (int k = 0; k < 2500 && bench.link.state() != LinkState::kStopped; ++k) {
    // 650 N switched on at 2 s: the step the compensator's rate limit alone would pass as a ramp whose
    // start is some 47,000 deg/s^3 of jerk at 8 ms.
    const Vector3 f = bench.t_s > 2.0 ? Vector3(0.0, 0.0, -650.0) : Vector3::Zero();
    bench.force.reading = test::reading_at(bench.robot, bench.controller.position(), f);
    bench.tick();
    ASSERT_EQ(bench.controller.alarm(), "") << "at " << bench.t_s << " s";
  }
  EXPECT_EQ(bench.link.state(), LinkState::kStopped);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kEnded) << bench.link.stop_reason();
  bench.run(0.05);  // the controller takes the last-data command at its next interval
  EXPECT_TRUE(bench.controller.ended());
  EXPECT_EQ(bench.controller.alarm(), "");
  EXPECT_GT(bench.link.cycle_stats().max_program_deviation_rad, 1e-5);
  expect_wire_invariants(bench);
}

TEST(FanucJ519Link, OneLostStatusIsCaughtUpAndTheStreamGoesOn) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(5, 5, 5, 5, 5, 5), 8.0), q0);
  bench.run(1.0);
  // One status lost on its way to deflex (the controller's packets to the PC during 4 ms).
  // An 8 ms window holds exactly one of the controller's status times (and no answer, since none came).
  bench.network.add_outage(bench.t_s + 0.0005, bench.t_s + 0.0085, test::kSensorAddress);
  bench.run(2.0);
  EXPECT_EQ(bench.controller.alarm(), "");
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
  EXPECT_GE(bench.link.caught_up(), 1u);
  expect_wire_invariants(bench);
}

TEST(FanucJ519Link, FaultsStopTheLinkWithANamedReasonAndNothingUnsafeOnTheWire) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(8, -4, 6, 10, -8, 12), 20.0);
  struct Case {
    const char* name;
    LinkStopCause cause;
    const char* words;
  };
  const Case cases[] = {
      {"outage", LinkStopCause::kController, "ready bit"},  // the queue ran dry: MOTN-603
      {"stall", LinkStopCause::kController, "did not answer in time"},
      {"estop", LinkStopCause::kController, "ready bit"},
      {"planned", LinkStopCause::kRequested, "last-data"},
      {"silence", LinkStopCause::kSilent, ""},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    FanucBench bench(program, q0);
    bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
    bench.run(2.0);
    ASSERT_EQ(bench.link.state(), LinkState::kRunning);
    const std::string what = c.name;
    if (what == "outage") bench.network.add_outage(bench.t_s, bench.t_s + 0.1);
    if (what == "stall") bench.stalled = true;
    if (what == "estop") bench.controller.raise_alarm("SRVO-001 Operator panel E-stop");
    if (what == "planned") bench.link.request_planned_stop(0.5);
    if (what == "silence") bench.network.add_outage(bench.t_s, bench.t_s + 60.0, test::kSensorAddress);
    bench.run(0.1);
    bench.stalled = false;
    bench.run(5.0);
    EXPECT_EQ(bench.link.state(), LinkState::kStopped);
    EXPECT_EQ(bench.link.stop_cause(), c.cause) << bench.link.stop_reason();
    EXPECT_NE(std::string(bench.link.stop_reason()).find(c.words), std::string::npos) << bench.link.stop_reason();
    if (what == "planned") {
      EXPECT_EQ(bench.controller.alarm(), "");
      EXPECT_TRUE(bench.controller.ended());
    }
    // The controller's own check never tripped on what deflex sent (its alarms came from the fault).
    EXPECT_EQ(bench.controller.alarm().find("MOTN-61"), std::string::npos) << bench.controller.alarm();
    expect_wire_invariants(bench);
  }
}

// A restart of the TP program (after an alarm was reset, say) starts with the ready bit clear: to
// deflex the stream it ran has stopped, and a new session needs a new `deflex online`.
TEST(FanucJ519Link, AControllerRestartEndsTheSessionItRan) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  bench.run(2.0);
  bench.controller.restart(bench.t_s);
  const std::uint64_t taken = bench.controller.counters().taken;
  bench.run(2.0);
  EXPECT_EQ(bench.link.state(), LinkState::kStopped);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.counters().taken, taken) << "nothing moved the arm after the restart";
  expect_wire_invariants(bench);
}

TEST(FanucJ519Link, GarbageIsCountedAndNeverAnswered) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0);
  bench.run(1.0);
  const std::uint64_t replies = bench.link.counters().replies;
  MemoryTransport& stranger = bench.network.add_endpoint(test::kStrangerAddress, 0.0002);
  std::vector<unsigned char> junk(132, 0xAB);
  // Garbage from the controller's own address (truncated, wrong type) and a stranger's valid-looking status.
  for (int k = 0; k < 50; ++k) {
    bench.controller_port.send_to(junk.data(), 60 + static_cast<std::size_t>(k), test::kSensorAddress);
    stranger.send_to(junk.data(), junk.size(), test::kSensorAddress);
  }
  bench.clock.set(bench.t_s + 0.001);  // delivered, and no status of the controller's among them
  while (bench.link.poll(0.0) != LinkPollResult::kIdle) {
  }
  EXPECT_EQ(bench.link.counters().replies, replies);
  EXPECT_GE(bench.link.counters().foreign_sender, 50u);
  EXPECT_GE(bench.link.counters().malformed + bench.link.counters().truncated, 50u);
  bench.run(1.0);
  EXPECT_EQ(bench.controller.alarm(), "");
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
}

TEST(FanucJ519Link, AVersionMismatchStopsTheLinkNamingBoth) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0, 1, 3);
  bench.run(1.0);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kProtocol);
  EXPECT_NE(std::string(bench.link.stop_reason()).find("version 3"), std::string::npos) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.counters().taken, 0u);
  // The controller alarms on the start packet of another version, as the reference's MOTN-607 names both.
  EXPECT_EQ(bench.controller.alarm(), "MOTN-607 ST: Protocol version mismatch PC 1, Rob 3");
}

TEST(FanucJ519Link, ProtocolThreeCarriesDoublesAndRunsTheSame) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 60.0), q0, 3);
  const Vector3 f_base(0.0, 200.0, -300.0);
  const JointVector expected = test::model_correction(bench.robot, q0, f_base);
  for (int k = 0; k < 4000; ++k) {
    bench.force.reading = test::reading_at(bench.robot, bench.controller.position(), f_base);
    bench.tick();
  }
  EXPECT_EQ(bench.controller.alarm(), "");
  EXPECT_LT(((q0 - bench.controller.taken().back()) - expected).cwiseAbs().maxCoeff(),
            0.01 * expected.cwiseAbs().maxCoeff());
}

TEST(FanucJ519Link, AProgramTooFastForTheControllerIsRefusedBeforeAnythingIsSent) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  // 30 deg on joint 1 in 0.5 s: a peak acceleration of 30 (pi/0.5)^2 / 2 = 592 deg/s^2, over 265.
  const auto fast = test::sweep_program(test::bench_robot(), q0, pose_deg(30, 0, 0, 0, 0, 0), 0.5);
  try {
    FanucBench bench(fast, q0);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("joint 1"), std::string::npos) << e.what();
  }
}

// A planned stop while the program moves at 12 deg/s: its speed falls along a smoothstep, so the
// controller's jerk check holds (a linear ramp over 0.5 s would add 12 / (0.5 x 0.008) = 3000 deg/s^3).
TEST(FanucJ519Link, APlannedStopOfAFastProgramStaysWithinTheJerkLimit) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(30, 0, 0, 30, 0, 0), 4.0, 161), q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  bench.run(2.0);  // the peak speed: 30 pi / 8 = 11.8 deg/s
  bench.link.request_planned_stop(0.5);
  bench.run(2.0);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kRequested) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.alarm(), "");
  EXPECT_TRUE(bench.controller.ended());
  EXPECT_GT(bench.controller.check().peak().velocity, 10.0);
  EXPECT_LE(bench.controller.check().peak().jerk, 1240.0);
}

// A force that jumps as the program ends: the correction settles before the last-data command.
TEST(FanucJ519Link, TheLastDataCommandFreezesAStreamAtRest) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(5, 5, 5, 5, 5, 5), 3.0), q0);
  for (int k = 0; k < 2000 && bench.link.state() != LinkState::kStopped; ++k) {
    const Vector3 f = bench.t_s > 3.9 ? Vector3(0.0, 300.0, -650.0) : Vector3::Zero();
    bench.force.reading = test::reading_at(bench.robot, bench.controller.position(), f);
    bench.tick();
  }
  bench.run(0.1);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kEnded) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.alarm(), "");
  EXPECT_TRUE(bench.controller.ended());
  // The last targets taken are equal: the stream was at rest when it was frozen.
  const auto& taken = bench.controller.taken();
  ASSERT_GT(taken.size(), 3u);
  EXPECT_EQ(taken[taken.size() - 1], taken[taken.size() - 3]);
}

// The controller begins a new session with the ready bit set at once: not resumed.
TEST(FanucJ519Link, ANewSessionWhileTheStreamRunsIsNotResumed) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0);
  bench.run(2.0);
  bench.controller.restart(bench.t_s - 1.0);  // statuses from 1 again, ready already
  const std::uint64_t taken = bench.controller.counters().taken;
  bench.run(1.0);
  // Stopped, whichever the link saw first: the new numbering, or the controller's alarm at a command
  // of the old one still on its way (MOTN-601); nothing moved the arm after the restart.
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.counters().taken, taken);
}

// deflex's PC went away mid-stream (a crash, a pulled cable): the controller alarms for the missing
// commands but keeps sending statuses to the old address, and while it does it answers no capability
// request and takes no start. A new protocol-3 session's first packet is a stop, as FANUC's own driver
// begins, so it starts where it would otherwise have stopped for an unanswered capability request.
TEST(FanucJ519Link, ANewSessionClearsTheStreamAnEarlierPcLeftRunning) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 60.0), q0, 3);
  bench.run(2.0);
  ASSERT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
  bench.stalled = true;  // the first PC answers no more
  bench.run(0.5);
  ASSERT_NE(bench.controller.alarm(), "");
  const std::uint64_t old_statuses = bench.pc_port.queued();
  ASSERT_GT(old_statuses, 0u);  // its statuses still reach the old address

  // The second `deflex online` on another port of the same PC, its own compensator and settings.
  MemoryTransport& second_port = bench.network.add_endpoint(make_datagram_address("127.0.0.1", 50999), 0.0002);
  OnlineCompensator compensator(bench.robot, test::bench_sensor(), fanuc_online());
  OnlineStrategy strategy(bench.robot, StrategyKind::kOnline, nullptr);
  FanucJ519Link second(compensator, strategy, bench.program, second_port, bench.clock, FanucBench::link_config(3));
  second.read_force_from(&bench.force);
  const std::uint64_t taken = bench.controller.counters().taken;
  for (int k = 0; k < 750; ++k) bench.tick(&second);  // 3 s
  ASSERT_EQ(second.state(), LinkState::kRunning) << second.stop_reason();
  EXPECT_TRUE(second.capability_counters().cleared);
  EXPECT_TRUE(second.capability_counters().read);
  EXPECT_EQ(bench.controller.alarm(), "");
  EXPECT_GT(bench.controller.counters().taken, taken + 300);
  EXPECT_EQ(bench.pc_port.queued(), old_statuses);  // nothing more went to the PC that left
}

// deflex runs 8 ms, the controller 4 ms: its time stamps say so before anything is sent.
TEST(FanucJ519Link, AControllerAtAnotherIntervalIsRefusedBeforeAnyCommand) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0, 1, 0, 0.004);
  bench.run(1.0);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kProtocol) << bench.link.stop_reason();
  EXPECT_NE(std::string(bench.link.stop_reason()).find("every 4.0 ms"), std::string::npos) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.counters().commands, 0u);
}

// Every poll of a whole session: the start (timing the interval, the anchor), a caught-up status, the
// settling at the end, last-data and the stop packet.
TEST(FanucJ519Link, NoPollFromStartToEndAllocates) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(5, 5, 5, 5, 5, 5), 2.0), q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  bench.network.add_outage(1.0005, 1.0085, test::kSensorAddress);  // one status lost: caught up
  std::size_t allocations = 0;
  for (int k = 0; k < 2000 && bench.link.state() != LinkState::kStopped; ++k) {
    allocations += bench.tick_counting_allocations();
  }
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kEnded) << bench.link.stop_reason();
  EXPECT_GE(bench.link.caught_up(), 1u);
  EXPECT_EQ(allocations, 0u);
}

TEST(FanucJ519Link, PollDoesNotAllocate) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(5, 5, 5, 5, 5, 5), 8.0), q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  bench.run(1.0);
  for (int k = 0; k < 200; ++k) {
    bench.t_s += 0.004;
    bench.clock.set(bench.t_s);
    bench.controller.tick(bench.t_s);
    bench.clock.set(bench.t_s + 0.0002);
    test::AllocationGuard guard;
    bench.link.poll(0.0);
    ASSERT_EQ(guard.allocations(), 0u) << k;
  }
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
}

// ---- The controller's threshold tables, read before the start packet ---------------------------------

using Limits = std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes>;

void expect_limits(const Limits& got, const Limits& want, int joints) {
  for (int j = 0; j < joints; ++j) {
    const auto i = static_cast<std::size_t>(j);
    EXPECT_DOUBLE_EQ(got[i].velocity, want[i].velocity) << "joint " << j + 1;
    EXPECT_DOUBLE_EQ(got[i].acceleration, want[i].acceleration) << "joint " << j + 1;
    EXPECT_DOUBLE_EQ(got[i].jerk, want[i].jerk) << "joint " << j + 1;
  }
}

// A controller far stricter than the limits given (50 deg/s^3 of jerk, where a CRX-10iA/L allows 1240),
// so that one force step shows the difference, with the correction given half of each limit. Its
// smoother, sized from the limits given (half of 1240 deg/s^3), averages over
// N = ceil(sqrt(4 s / (620 deg/s^3 x T^3))) = 18 intervals (s = 3 deg/s x 8 ms = 0.024 deg, T = 8 ms)
// and lets a force step through with more jerk than 50; sized from the tables (half of 50 deg/s^3) it
// needs N = ceil(sqrt(4 s / (25 deg/s^3 x T^3))) = 87 and never exceeds 4 s / (N^2 T^3) = 24.8.
// Protocol 3 (float64 targets: float32 rounding alone is worth ~60 deg/s^3 at 8 ms) and a 4 s ramp-in
// (the blend's budget, 6 d / (R^2 T) = 9.4 deg/s^3) leave the program room under such limits.
struct StrictController {
  Limits standin{};
  Limits expected{};  // the stricter of the given (120, 265, 1240) and the stand-in's, per joint and kind
  StrictController() {
    standin.fill({60.0, 40.0, 50.0});
    standin[1] = {150.0, 45.0, 55.0};    // joint 2's velocity is laxer than the one given: that one holds
    standin[4] = {90.0, 300.0, 1500.0};  // joint 5's acceleration and jerk laxer than given
    expected.fill({60.0, 40.0, 50.0});
    expected[1] = {120.0, 45.0, 55.0};
    expected[4] = {90.0, 265.0, 1240.0};
  }
  FanucJ519LinkConfig link(bool read) const {
    FanucJ519LinkConfig c = FanucBench::link_config(3);
    c.stream.ramp_in_s = 4.0;
    c.correction_share = 0.5;
    c.read_thresholds = read;
    return c;
  }
  cell::FanucJ519ControllerConfig controller() const {
    cell::FanucJ519ControllerConfig c = FanucBench::controller_config(3, 0.008);
    c.limits = standin;
    return c;
  }
};

void run_with_force_step(FanucBench& bench, double seconds) {
  for (int k = 0; k < static_cast<int>(seconds / 0.004); ++k) {
    const Vector3 f = bench.t_s > 1.0 ? Vector3(0.0, 0.0, -650.0) : Vector3::Zero();
    bench.force.reading = test::reading_at(bench.robot, bench.controller.position(), f);
    bench.tick();
    if (!bench.controller.alarm().empty()) return;
  }
}

TEST(FanucJ519Link, TheControllersStricterThresholdTablesHoldTheStreamWhereTheLimitsGivenWouldNot) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  const StrictController strict;
  const Limits given = FanucJ519LinkConfig::default_limits();
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 60.0), q0, strict.link(true), strict.controller());
  run_with_force_step(bench, 12.0);
  EXPECT_EQ(bench.controller.alarm(), "");
  ASSERT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
  EXPECT_EQ(bench.link.thresholds().asked, 18u);
  EXPECT_EQ(bench.link.thresholds().read, 18u);
  EXPECT_EQ(bench.link.thresholds().rejected, 0u);
  EXPECT_FALSE(bench.link.thresholds().unanswered);
  EXPECT_EQ(bench.controller.counters().threshold_replies, 18u);
  expect_limits(bench.link.effective_limits(), strict.expected, 6);
  EXPECT_EQ(bench.link.smoother().taps(), 87u);
  // What the controller took stayed within its own strictest limits, and the correction did move it.
  const fanuc_j519::AxisLimits& peak = bench.controller.check().peak();
  EXPECT_LE(peak.jerk, 50.0);
  EXPECT_LE(peak.acceleration, 40.0);
  EXPECT_GT(peak.jerk, 1.0);
  EXPECT_EQ(bench.link.counters().guard_trips, 0u);
  EXPECT_NE(bench.link.protocol_summary().find("18 threshold tables were read"), std::string::npos)
      << bench.link.protocol_summary();
  expect_wire_invariants(bench);

  // The control: the same run held to the limits given alone (the tables not asked for) makes the
  // controller stop the stream on a joint's jerk or acceleration.
  FanucBench control(test::hold_program(test::bench_robot(), q0, 60.0), q0, strict.link(false), strict.controller());
  run_with_force_step(control, 12.0);
  EXPECT_NE(control.controller.alarm().find("MOTN-61"), std::string::npos)
      << control.controller.alarm() << " peak " << control.controller.check().peak().jerk << " "
      << control.controller.check().peak().acceleration << " taken " << control.controller.taken().size() << " "
      << (q0 - control.controller.taken().back()).transpose();
  EXPECT_EQ(control.controller.counters().threshold_requests, 0u);
  expect_limits(control.link.effective_limits(), given, 6);
  EXPECT_EQ(control.link.smoother().taps(), 18u);
  EXPECT_DOUBLE_EQ(bench.link.effective_limits()[0].jerk / control.link.effective_limits()[0].jerk, 50.0 / 1240.0);
}

// Older system software answers no threshold request: after one request and its two retries, 0.1 s
// each, the link starts with the limits given and says so.
TEST(FanucJ519Link, AControllerThatDoesNotAnswerThresholdRequestsGetsTheLimitsGivenAfterTheTimeout) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  cell::FanucJ519ControllerConfig old_software = FanucBench::controller_config(1, 0.008);
  old_software.answer_thresholds = false;
  FanucBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(5, 5, 5, 5, 5, 5), 8.0), q0,
                   FanucBench::link_config(1), old_software);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  double started_s = -1.0;
  double done_s = -1.0;
  while (bench.t_s < 1.0) {
    bench.tick();
    if (done_s < 0.0 && bench.link.thresholds_done()) done_s = bench.t_s;
    if (bench.controller.counters().starts == 0) {
      EXPECT_EQ(bench.controller.counters().commands, 0u);
    } else if (started_s < 0.0) {
      started_s = bench.t_s;  // the controller read the start packet at this tick
    }
  }
  EXPECT_GE(done_s, 0.3);
  EXPECT_LE(done_s, 0.3 + 0.008);
  // The first request at 4.2 ms, again at 104.2 and 204.2 ms, given up at 304.2 ms with the start packet.
  EXPECT_GE(started_s, 0.3);
  EXPECT_LE(started_s, 0.3 + 0.012);
  EXPECT_EQ(bench.controller.counters().threshold_requests, 3u);
  EXPECT_EQ(bench.controller.counters().threshold_replies, 0u);
  EXPECT_TRUE(bench.link.thresholds().unanswered);
  EXPECT_EQ(bench.link.thresholds().resent, 2u);
  EXPECT_EQ(bench.link.thresholds().read, 0u);
  Limits given{};
  given.fill({120.0, 265.0, 1240.0});
  expect_limits(bench.link.effective_limits(), given, 6);
  bench.run(3.0);
  EXPECT_EQ(bench.controller.alarm(), "");
  EXPECT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
  EXPECT_GT(bench.controller.counters().taken, 300u);
  EXPECT_NE(bench.link.protocol_summary().find("answered no threshold request (3 tries of 0.1 s"), std::string::npos)
      << bench.link.protocol_summary();
  expect_wire_invariants(bench);
}

// A threshold reply built byte by byte (big-endian, the layout of the reference notes): type 3, version 1,
// axis, kind, 2000 mm/s, 8 ms, then 20 no-load and 20 full-load float32 all `value`.
std::vector<unsigned char> threshold_reply(std::uint32_t axis, std::uint32_t kind, float value) {
  std::vector<unsigned char> b(184, 0);
  const auto put = [&](std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<unsigned char>(v >> (24 - 8 * i));
  };
  put(0, 3);
  put(4, 1);
  put(8, axis);
  put(12, kind);
  put(16, 2000);
  put(20, 8);
  for (std::size_t i = 0; i < 40; ++i) put(24 + 4 * i, std::bit_cast<std::uint32_t>(value));
  return b;
}

void set_column(std::vector<unsigned char>& b, std::size_t column, float value) {
  const auto v = std::bit_cast<std::uint32_t>(value);
  for (int i = 0; i < 4; ++i)
    b[24 + 4 * column + static_cast<std::size_t>(i)] = static_cast<unsigned char>(v >> (24 - 8 * i));
}

TEST(FanucJ519Link, BadThresholdRepliesAreRejectedCountedAndNeverUsed) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  cell::FanucJ519ControllerConfig silent = FanucBench::controller_config(1, 0.008);
  silent.answer_thresholds = false;  // every reply comes from the test
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0, FanucBench::link_config(1), silent);
  bench.tick();  // the link asks for joint 1's velocity table
  ASSERT_EQ(bench.controller.counters().threshold_requests, 0u);
  bench.tick();
  ASSERT_EQ(bench.controller.counters().threshold_requests, 1u);
  // Every bad reply says 10 deg/s: had one been used, joint 1's velocity limit would be 10.
  std::vector<std::vector<unsigned char>> bad = {
      threshold_reply(2, 0, 10.0f),  // another axis
      threshold_reply(1, 1, 10.0f),  // another kind
      threshold_reply(1, 0, 10.0f), threshold_reply(1, 0, 10.0f), threshold_reply(1, 0, 10.0f),
      threshold_reply(1, 0, 10.0f), threshold_reply(1, 0, 10.0f), threshold_reply(1, 0, 10.0f),
  };
  set_column(bad[2], 7, std::numeric_limits<float>::quiet_NaN());
  set_column(bad[3], 25, 0.0f);
  set_column(bad[4], 39, -5.0f);
  set_column(bad[5], 0, std::numeric_limits<float>::infinity());
  bad[6].resize(183);   // truncated
  bad[7].push_back(0);  // one byte too many
  for (const auto& b : bad) bench.controller_port.send_to(b.data(), b.size(), test::kSensorAddress);
  bench.clock.set(bench.t_s + 0.001);
  while (bench.link.poll(0.0) != LinkPollResult::kIdle) {
  }
  EXPECT_EQ(bench.link.thresholds().rejected, 8u);
  EXPECT_EQ(bench.link.thresholds().read, 0u);
  EXPECT_EQ(bench.link.tables()[0].velocity, 0.0);
  // The right reply (hand-built the same way) is taken: the builder makes valid bytes.
  const auto good = threshold_reply(1, 0, 100.0f);
  bench.controller_port.send_to(good.data(), good.size(), test::kSensorAddress);
  bench.clock.set(bench.t_s + 0.002);
  while (bench.link.poll(0.0) != LinkPollResult::kIdle) {
  }
  EXPECT_EQ(bench.link.thresholds().read, 1u);
  EXPECT_EQ(bench.link.tables()[0].velocity, 100.0);
  // No one answers joint 1's acceleration: the reading ends and the session runs.
  bench.run(2.0);
  EXPECT_TRUE(bench.link.thresholds().unanswered);
  EXPECT_EQ(bench.link.thresholds().rejected, 8u);
  Limits want{};
  want.fill({120.0, 265.0, 1240.0});
  want[0].velocity = 100.0;
  expect_limits(bench.link.effective_limits(), want, 6);
  EXPECT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.alarm(), "");
  EXPECT_NE(bench.link.protocol_summary().find("1 of the controller's 18 threshold tables"), std::string::npos)
      << bench.link.protocol_summary();
  EXPECT_NE(bench.link.protocol_summary().find("8 threshold replies rejected"), std::string::npos)
      << bench.link.protocol_summary();
}

// A table stricter than the program can follow: the link stops before the start packet, naming the
// joint, the limit and the value.
TEST(FanucJ519Link, AThresholdTableTheProgramExceedsStopsTheLinkBeforeAnythingIsSent) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  // 10 deg on joint 1 in 4 s (a half-cosine sweep): a peak acceleration of 10 (pi/4)^2 / 2 = 3.1 deg/s^2,
  // well under the 265 given, over what a table's 3 deg/s^2 leaves the program (75 % of it, less the
  // ramp-in blend's 6 x 0.2 deg / (1 s)^2 and float32 rounding: under 1.1).
  cell::FanucJ519ControllerConfig strict = FanucBench::controller_config(1, 0.008);
  strict.limits[0] = {120.0, 3.0, 1240.0};
  FanucBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(10, 0, 0, 0, 0, 0), 4.0, 161), q0,
                   FanucBench::link_config(1), strict);
  bench.run(1.0);
  EXPECT_EQ(bench.link.state(), LinkState::kStopped);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController) << bench.link.stop_reason();
  const std::string why = bench.link.stop_reason();
  EXPECT_NE(why.find("threshold tables"), std::string::npos) << why;
  EXPECT_NE(why.find("joint acceleration"), std::string::npos) << why;
  EXPECT_NE(why.find("joint 1"), std::string::npos) << why;
  EXPECT_EQ(bench.controller.counters().starts, 0u);
  EXPECT_EQ(bench.controller.counters().commands, 0u);
}

// The threshold phase runs in poll(): reading stricter tables, checking the program again and sizing
// the smoother again allocate nothing either.
TEST(FanucJ519Link, ReadingStricterThresholdTablesDoesNotAllocate) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  const StrictController strict;
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 60.0), q0, strict.link(true), strict.controller());
  std::size_t allocations = 0;
  while (bench.t_s < 2.0) {
    allocations += bench.tick_counting_allocations();
  }
  EXPECT_TRUE(bench.link.capability_counters().read);  // the capability exchange ran in poll() too
  EXPECT_EQ(bench.link.thresholds().read, 18u);
  EXPECT_EQ(bench.link.smoother().taps(), 87u);
  EXPECT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
  EXPECT_EQ(allocations, 0u);
}

// ---- The capability exchange (protocol 3 and 4) ------------------------------------------------------

// A capability packet built byte by byte (big-endian uint32s, the layout of the reference notes): type,
// version 3, id, sampling rate ms, start_move, available_version, rob_status_use_tcp 0; `size` bytes
// (28 is the packet's, the rest zero or cut off).
std::vector<unsigned char> capability_bytes(std::uint32_t type, std::uint32_t id, std::uint32_t rate_ms,
                                            std::uint32_t start_move, std::uint32_t available, std::size_t size = 28) {
  std::vector<unsigned char> b(std::max<std::size_t>(size, 28), 0);
  const auto put = [&](std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<unsigned char>(v >> (24 - 8 * i));
  };
  put(0, type);
  put(4, 3);
  put(8, id);
  put(12, rate_ms);
  put(16, start_move);
  put(20, available);
  b.resize(size);
  return b;
}

// Delivers `bytes` from the controller's address to the link and lets it read them.
void from_controller(FanucBench& bench, const std::vector<unsigned char>& bytes) {
  bench.controller_port.send_to(bytes.data(), bytes.size(), test::kSensorAddress);
  bench.clock.set(bench.clock.now_s() + 0.001);
  while (bench.link.poll(0.0) != LinkPollResult::kIdle && bench.link.state() != LinkState::kStopped) {
  }
}

// A protocol 3 (and 4) controller answers the capability request before the threshold tables are asked;
// the link records what it reported (the stand-in's 8 ms interval, its 2 buffered commands, its version)
// and runs as before.
TEST(FanucJ519Link, ProtocolThreeAndFourAskTheCapabilityFirstAndRecordTheControllers) {
  for (const std::uint32_t version : {3U, 4U}) {
    SCOPED_TRACE(version);
    const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
    FanucBench bench(test::hold_program(test::bench_robot(), q0, 60.0), q0, version);
    const Vector3 f_base(0.0, 200.0, -300.0);
    for (int k = 0; k < 750; ++k) {  // 3 s
      bench.force.reading = test::reading_at(bench.robot, bench.controller.position(), f_base);
      bench.tick();
      // No threshold request before the capability's reply, no start packet before the tables.
      if (bench.controller.counters().threshold_requests > 0) {
        ASSERT_EQ(bench.controller.counters().capability_replies, 1u);
      }
      if (bench.controller.counters().starts > 0) {
        ASSERT_EQ(bench.controller.counters().threshold_replies, 18u);
      }
    }
    EXPECT_EQ(bench.controller.alarm(), "");
    ASSERT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
    EXPECT_GT(bench.controller.counters().taken, 300u);
    EXPECT_EQ(bench.controller.counters().capability_requests, 1u);
    const FanucCapabilityCounters& k = bench.link.capability_counters();
    EXPECT_TRUE(k.asked);
    EXPECT_TRUE(k.read);
    EXPECT_FALSE(k.unanswered);
    EXPECT_EQ(k.rejected, 0u);
    EXPECT_EQ(k.resent, 0u);
    const fanuc_j519::Capability& c = bench.link.capability();
    EXPECT_EQ(c.type, 7u);
    EXPECT_EQ(c.id, 1u);
    EXPECT_EQ(c.available_version, version);
    EXPECT_EQ(c.sampling_rate_ms, 8u);
    EXPECT_EQ(c.start_move, 2u);
    EXPECT_EQ(c.status_uses_tcp, 0u);
    EXPECT_NE(
        bench.link.protocol_summary().find(fmt::format(
            "capability: protocol {} available, sampling rate 8 ms, start_move 2, status at the faceplate", version)),
        std::string::npos)
        << bench.link.protocol_summary();
  }
}

// Version 1 has no capability packet: a version 1 link asks nothing.
TEST(FanucJ519Link, ProtocolOneAsksNoCapability) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0, 1);
  bench.run(1.0);
  EXPECT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.counters().capability_requests, 0u);
  EXPECT_FALSE(bench.link.capability_counters().asked);
  EXPECT_NE(bench.link.protocol_summary().find("protocol 1 has no capability exchange"), std::string::npos);
}

// The reference's MOTN-607 case: a version 3 client on a version 1 controller, which does not answer the
// capability request. After the request and its two retries (0.1 s each) the link stops; nothing but the
// stop packet a protocol-3 client begins with and the requests was sent.
TEST(FanucJ519Link, AProtocolThreeLinkOnAVersionOneControllerStopsBeforeAnyStartPacket) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0, 3, 1);
  double stopped_s = -1.0;
  while (bench.t_s < 1.0) {
    bench.tick();
    if (stopped_s < 0.0 && bench.link.state() == LinkState::kStopped) stopped_s = bench.t_s;
  }
  EXPECT_GE(stopped_s, 0.3);
  EXPECT_LE(stopped_s, 0.3 + 0.008);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController);
  const std::string why = bench.link.stop_reason();
  EXPECT_NE(why.find("MOTN-607"), std::string::npos) << why;
  EXPECT_NE(why.find("PC 3, Rob 1"), std::string::npos) << why;
  EXPECT_NE(why.find("--fanuc-version 1"), std::string::npos) << why;
  EXPECT_TRUE(bench.link.capability_counters().unanswered);
  EXPECT_EQ(bench.link.capability_counters().resent, 2u);
  EXPECT_EQ(bench.controller.counters().capability_requests, 3u);
  EXPECT_EQ(bench.controller.counters().capability_replies, 0u);
  EXPECT_EQ(bench.controller.counters().threshold_requests, 0u);
  EXPECT_EQ(bench.controller.counters().starts, 0u);
  EXPECT_EQ(bench.controller.counters().stops, 1u);  // the one a protocol-3 client sends first
  EXPECT_EQ(bench.controller.counters().commands, 0u);
  EXPECT_EQ(bench.controller.counters().statuses, 0u);
  EXPECT_EQ(bench.controller.alarm(), "");
}

// A controller that answers with an older available_version than the link speaks: stopped before the
// tables and the start packet, naming both and the option that fits.
TEST(FanucJ519Link, ACapabilityOfferingAnOlderVersionStopsNamingBoth) {
  struct Case {
    std::uint32_t link, available;
    const char* option;
  };
  for (const Case& c :
       {Case{3, 1, "--fanuc-version 1"}, Case{4, 3, "--fanuc-version 3"}, Case{3, 2, "--fanuc-version 1"}}) {
    SCOPED_TRACE(c.option);
    const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
    // A version 1 stand-in does not answer: the reply comes from the test.
    FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0, c.link, 1);
    bench.tick();
    from_controller(bench, capability_bytes(7, 1, 8, 2, c.available));
    ASSERT_EQ(bench.link.state(), LinkState::kStopped);
    EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController);
    const std::string why = bench.link.stop_reason();
    EXPECT_NE(
        why.find(fmt::format("offers J519 protocol version {}, deflex was set to version {}", c.available, c.link)),
        std::string::npos)
        << why;
    EXPECT_NE(why.find(c.option), std::string::npos) << why;
    EXPECT_EQ(bench.link.capability().available_version, c.available);
    bench.run(0.5);
    EXPECT_EQ(bench.controller.counters().threshold_requests, 0u);
    EXPECT_EQ(bench.controller.counters().starts, 0u);
  }
}

// A sampling rate that is not the compensator's period: stopped naming both (a 4 ms controller, 8 ms deflex).
TEST(FanucJ519Link, ACapabilitySamplingRateOtherThanThePeriodStopsNamingBoth) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0, 3, 3, 0.004);
  bench.run(0.5);
  ASSERT_EQ(bench.link.state(), LinkState::kStopped);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kProtocol);
  const std::string why = bench.link.stop_reason();
  EXPECT_NE(why.find("sampling rate of 4 ms, deflex runs at 8 ms (--period-ms)"), std::string::npos) << why;
  EXPECT_EQ(bench.link.capability().sampling_rate_ms, 4u);
  EXPECT_EQ(bench.controller.counters().capability_replies, 1u);
  EXPECT_EQ(bench.controller.counters().threshold_requests, 0u);
  EXPECT_EQ(bench.controller.counters().starts, 0u);
}

// The stop packet and the request on the wire, byte for byte; then replies that are not a valid one are rejected,
// counted and never used (each says version 1 at 4 ms: had one been taken, the link would have stopped).
TEST(FanucJ519Link, TheCapabilityRequestsBytesAndBadRepliesRejectedAndCounted) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  FanucBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0, 3, 1);
  bench.clock.set(0.001);
  ASSERT_EQ(bench.link.poll(0.0), LinkPollResult::kIdle);
  bench.clock.set(0.002);
  std::vector<unsigned char> got(64, 0);
  DatagramAddress from;
  // First the stop packet that clears a session an earlier PC left running (type 2, version 3).
  ASSERT_EQ(bench.controller_port.receive(got.data(), got.size(), from), 8);
  EXPECT_EQ(std::vector<unsigned char>(got.begin(), got.begin() + 8),
            std::vector<unsigned char>({0, 0, 0, 2, 0, 0, 0, 3}));
  const long n = bench.controller_port.receive(got.data(), got.size(), from);
  ASSERT_EQ(n, 28);
  got.resize(28);
  const std::vector<unsigned char> want = {0, 0, 0, 7, 0, 0, 0, 3, 0, 0, 0, 1, 0, 0,
                                           0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(got, want);

  std::vector<std::vector<unsigned char>> bad = {
      capability_bytes(7, 1, 4, 2, 1, 27),       // truncated
      capability_bytes(7, 1, 4, 2, 1, 29),       // one byte too many
      capability_bytes(8, 1, 4, 2, 1),           // a capability set, not the get's reply
      capability_bytes(3, 1, 4, 2, 1),           // a threshold type
      capability_bytes(7, 0, 4, 2, 1),           // id 0
      capability_bytes(7, 2, 4, 2, 1),           // another id
      capability_bytes(7, 1, 4, 12, 1),          // start_move over 9
      capability_bytes(7, 1, 0, 2, 1),           // no sampling rate
      capability_bytes(7, 1, 4, 2, 0),           // no available version
      capability_bytes(7, 1, 0xDEADBEEF, 2, 1),  // garbage rate
      capability_bytes(7, 1, 4, 2, 0x5A17C0DE),  // garbage version
  };
  for (const auto& b : bad) from_controller(bench, b);
  EXPECT_EQ(bench.link.capability_counters().rejected, bad.size());
  EXPECT_FALSE(bench.link.capability_counters().read);
  EXPECT_EQ(bench.link.state(), LinkState::kWaiting) << bench.link.stop_reason();
  // The right reply (hand-built the same way) is taken: the builder makes valid bytes.
  from_controller(bench, capability_bytes(7, 1, 8, 3, 4));
  EXPECT_TRUE(bench.link.capability_counters().read);
  EXPECT_EQ(bench.link.capability().available_version, 4u);
  EXPECT_EQ(bench.link.capability().sampling_rate_ms, 8u);
  EXPECT_EQ(bench.link.capability().start_move, 3u);
  EXPECT_NE(bench.link.state(), LinkState::kStopped) << bench.link.stop_reason();
  EXPECT_NE(bench.link.protocol_summary().find("11 capability replies rejected"), std::string::npos)
      << bench.link.protocol_summary();
}

}  // namespace
}  // namespace deflex
