// deflex's MotoROS2 real-time link against a stand-in of the controller with its semantics
// (cell/motoros2_rt_controller.hpp: lock-step, increments applied at the interpolation clock, the FSU's
// truncation shown a reply late, the session dropped on a sequence jump, a second sender, garbage or
// its own timeout, dead time and servo lag): the controller's command position converges to the
// model's correction (computed here with a finite-difference Jacobian), the increments it took sum to
// it, and every fault ends with the link stopped for a named reason or ridden through, with no
// increment beyond the per-cycle step limit and no absolute beyond the bound of the nominal.
#include <array>

#include <gtest/gtest.h>

#include "deflex/cell/motoros2_rt_controller.hpp"
#include "deflex/motoros2/motoros2_rt_link.hpp"
#include "deflex/text/errors.hpp"
#include "links/link_harness.hpp"
#include "support/allocation_guard.hpp"
#include "support/poses.hpp"
#include "support/sampled_speed.hpp"

namespace deflex {
namespace {

using test::pose_deg;
namespace rt = motoros2_rt;

constexpr double kPeriod = 0.004;

struct MotoBench {
  RobotModel robot = test::bench_robot();
  ManualClock clock;
  MemoryNetwork network{clock, 8192};
  MemoryTransport& pc_port = network.add_endpoint(test::kSensorAddress, 0.0002);
  MemoryTransport& controller_port = network.add_endpoint(test::kControllerAddress, 0.0002);
  // The PC's port for the controller's RobotState (rt_status_udp_port_number).
  MemoryTransport& status_port = network.add_endpoint({test::kSensorAddress.ipv4, 22001}, 0.0002);
  OnlineCompensator compensator;
  OnlineStrategy strategy;
  test::ConstantForce force;
  std::shared_ptr<const JointTrajectory> program;
  JointVector start;
  Motoros2RtLink link;
  cell::Motoros2RtController controller;
  double t_s = 0.0;
  bool stalled = false;

  static Motoros2RtLinkConfig link_config(int max_run, bool status) {
    Motoros2RtLinkConfig c;
    c.controller = test::kControllerAddress;
    c.stop.stop_silence_s = 0.5;
    c.max_truncation_run = max_run;
    c.status_port = status ? 22001 : -1;
    return c;
  }

  /// With `cc.status_port` set, the link reads the controller's RobotState.
  MotoBench(std::shared_ptr<const JointTrajectory> p, const JointVector& arm,
            const cell::Motoros2RtControllerConfig& cc = {}, int max_run = 25)
      : compensator(robot, test::bench_sensor(), test::bench_online(kPeriod)),
        strategy(robot, StrategyKind::kOnline, nullptr),
        program(std::move(p)),
        start(arm),
        link(compensator, strategy, program, pc_port, clock, link_config(max_run, cc.status_port >= 0),
             cc.status_port >= 0 ? &status_port : nullptr),
        controller(cc, arm, controller_port) {
    link.read_force_from(&force);
  }

  /// One 4 ms interpolation clock of the controller, then deflex answers what reached it.
  LinkPollResult tick() {
    t_s += kPeriod;
    clock.set(t_s);
    controller.tick(t_s);
    clock.set(t_s + 0.0005);
    LinkPollResult last = LinkPollResult::kIdle;
    while (!stalled) {
      const LinkPollResult r = link.poll(0.0);
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

// The per-cycle step limit computed here: the program's peak speed sampled every 0.5 ms, the blend's
// 1.5 x 1 deg over the 1 s ramp-in, the rate bound, over one period.
JointVector step_limit(const MotoBench& b) {
  return kPeriod * (test::sampled_peak_speed(*b.program) * 1.001).array() +
         kPeriod * (1.5 * deg_to_rad(1.0) / 1.0 + b.compensator.config().max_correction_rate_rad_s) + 1e-9;
}

// Every increment the controller received within the step limit; the increments it took (with no FSU
// truncation and no new session) sum to its command position; every absolute deflex sent within the bound of the
// program (sampled here at the recorded program time) plus its blend.
void expect_wire_invariants(const MotoBench& b, bool sums = true) {
  const JointVector limit = step_limit(b);
  JointVector sum = b.start;
  for (std::size_t k = 0; k < b.controller.increments().size(); ++k) {
    const JointVector& inc = b.controller.increments()[k];
    for (int j = 0; j < inc.size(); ++j) ASSERT_LE(std::abs(inc[j]), limit[j]) << "increment " << k << " joint " << j;
    sum += inc;
  }
  if (sums) {
    EXPECT_LT((sum - b.controller.command_position()).cwiseAbs().maxCoeff(), 1e-12);
  }
  const double bound = b.compensator.config().max_joint_correction_rad * (1 + 1e-9) + 1e-12;
  JointVector q(6);
  const LinkHistory& h = b.link.history();
  for (std::size_t k = 0; k < h.size(); ++k) {
    const LinkCycleRecord& r = h.at(k);
    if (!r.replied) continue;
    b.program->sample(r.program_time_s, q);
    ASSERT_LE((r.q_command - (q + r.q_blend)).cwiseAbs().maxCoeff(), bound) << "at " << r.t_s << " s";
  }
}

TEST(Motoros2RtLink, ConstantForceHoldsTheModelsCorrectionAndTheIncrementsSumToIt) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  MotoBench bench(test::hold_program(test::bench_robot(), q0, 60.0), q0);
  const Vector3 f_base(150.0, -250.0, -300.0);
  const JointVector expected = test::model_correction(bench.robot, q0, f_base);
  ASSERT_LT(expected.cwiseAbs().maxCoeff(), bench.compensator.config().max_joint_correction_rad);
  for (int k = 0; k < 2500; ++k) {  // 10 s
    bench.force.reading = test::reading_at(bench.robot, bench.controller.position(), f_base);
    bench.tick();
    ASSERT_EQ(bench.controller.dropped(), "") << "at " << bench.t_s << " s";
  }
  ASSERT_EQ(bench.link.state(), LinkState::kRunning);
  // Lock-step: one command taken a clock.
  EXPECT_GT(bench.controller.counters().taken, 2400u);
  const JointVector held = q0 - bench.controller.command_position();
  EXPECT_LT((held - expected).cwiseAbs().maxCoeff(), 0.01 * expected.cwiseAbs().maxCoeff())
      << "held " << held.transpose() << "\nmodel " << expected.transpose();
  // The arm follows the command position through the dead time and lag.
  EXPECT_LT((bench.controller.position() - bench.controller.command_position()).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(bench.link.truncations(), 0u);
  EXPECT_EQ(bench.link.shortfalls(), 0u);
  EXPECT_EQ(bench.link.counters().guard_trips, 0u);
  expect_wire_invariants(bench);
}

TEST(Motoros2RtLink, AProgramRunsToItsEndAndTheControllerHoldsItsLastPoint) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const JointVector delta = pose_deg(12, -6, 9, 15, -12, 25);
  MotoBench bench(test::sweep_program(test::bench_robot(), q0, delta, 6.0), q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  for (int k = 0; k < 2500 && bench.link.state() != LinkState::kStopped; ++k) bench.tick();
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kEnded) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.dropped(), "");
  // The session's first command (no motion), then the program at 0, 4 ms, ... 6 s: one increment each.
  EXPECT_EQ(bench.controller.counters().taken, 1u + 1501u);
  const JointVector correction = (q0 + delta) - bench.controller.command_position();
  EXPECT_LE(correction.cwiseAbs().maxCoeff(), bench.compensator.config().max_joint_correction_rad);
  EXPECT_GT(correction.cwiseAbs().maxCoeff(), 1e-5);
  expect_wire_invariants(bench);
}

// The FSU holds the fastest joint to 90 % of the program's peak: the increments it truncated are
// counted, and the lost motion is made up once the program slows, so the program still ends where the
// model's correction puts it.
TEST(Motoros2RtLink, TruncatedIncrementsAreCountedAndTheLostMotionMadeUp) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const JointVector delta = pose_deg(10, 0, 0, 0, 0, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, delta, 4.0);
  cell::Motoros2RtControllerConfig cc;
  cc.fsu_speed_rad_s = 0.9 * test::sampled_peak_speed(*program).maxCoeff();
  MotoBench bench(program, q0, cc, 10000);
  for (int k = 0; k < 2000 && bench.link.state() != LinkState::kStopped; ++k) bench.tick();
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kEnded) << bench.link.stop_reason();
  EXPECT_GT(bench.controller.counters().truncated, 10u);
  // Each truncation is flagged one reply later: all but none at the program's very end are counted.
  EXPECT_GE(bench.link.truncations() + 1, bench.controller.counters().truncated);
  EXPECT_GT(bench.link.shortfalls(), 10u);
  EXPECT_EQ(bench.controller.dropped(), "");
  // No force: the program's last point, exactly where it is (what was truncated came back).
  EXPECT_LT((bench.controller.command_position() - (q0 + delta)).cwiseAbs().maxCoeff(), 1e-9);
  expect_wire_invariants(bench, false);
}

TEST(Motoros2RtLink, ARunOfTruncationsBeyondTheLimitStopsTheLinkNamingTheSafetyUnit) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(10, 0, 0, 0, 0, 0), 4.0);
  cell::Motoros2RtControllerConfig cc;
  cc.fsu_speed_rad_s = 0.5 * test::sampled_peak_speed(*program).maxCoeff();
  MotoBench bench(program, q0, cc);
  bench.run(5.0);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController) << bench.link.stop_reason();
  EXPECT_NE(std::string(bench.link.stop_reason()).find("Functional Safety Unit truncated 26 increments"),
            std::string::npos)
      << bench.link.stop_reason();
  const std::size_t taken = bench.controller.counters().taken;
  bench.run(0.5);
  EXPECT_EQ(bench.controller.counters().taken, taken) << "an increment after the link stopped";
  expect_wire_invariants(bench, false);
}

// A command or its reply lost: the command goes again with the same number; the controller answers a
// number it took without applying it twice. The stream goes on, the program waiting meanwhile.
TEST(Motoros2RtLink, LostCommandsAndRepliesAreSentAgainAndTheStreamGoesOn) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  MotoBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(5, 5, 5, 5, 5, 5), 8.0), q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  bench.run(1.0);
  bench.network.add_outage(bench.t_s, bench.t_s + 0.03, test::kControllerAddress);  // commands lost
  bench.run(1.0);
  bench.network.add_outage(bench.t_s, bench.t_s + 0.03, test::kSensorAddress);  // replies lost
  bench.run(1.0);
  EXPECT_EQ(bench.controller.dropped(), "");
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
  EXPECT_GE(bench.link.resent(), 2u);
  EXPECT_GE(bench.controller.counters().duplicates, 1u);  // a command whose reply was lost, again
  EXPECT_EQ(bench.controller.counters().skipped, 0u);     // deflex never skips a number
  EXPECT_EQ(bench.link.shortfalls(), 0u);
  expect_wire_invariants(bench);
}

TEST(Motoros2RtLink, GarbageStraysAndForeignRepliesAreCountedAndNeverAnswered) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  MotoBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0);
  bench.run(1.0);
  const std::uint64_t sent = bench.link.counters().replies;
  MemoryTransport& stranger = bench.network.add_endpoint(test::kStrangerAddress, 0.0002);
  // A valid reply but for a number never sent (far ahead), an old one (already answered), one with a
  // NaN, truncated and oversized datagrams, garbage flag bytes; and a valid reply from a stranger.
  rt::Reply r;
  std::vector<unsigned char> good(rt::kReplyBytes);
  const auto reply_bytes = [&](std::uint32_t echo) {
    r.sequence_echo = echo;
    EXPECT_EQ(rt::encode(r, good.data(), good.size()), rt::kReplyBytes);
    return good;
  };
  const std::uint32_t outstanding = static_cast<std::uint32_t>(bench.controller.counters().taken);
  const std::vector<unsigned char> ahead = reply_bytes(outstanding + 5);
  const std::vector<unsigned char> old = reply_bytes(outstanding - 3);
  std::vector<unsigned char> nan = reply_bytes(outstanding);
  std::vector<unsigned char> flag = nan;
  const double bad = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(nan.data() + 1028, &bad, 8);
  flag[2052] = 7;
  std::vector<unsigned char> big(5000, 0);
  for (int k = 0; k < 10; ++k) {
    bench.controller_port.send_to(ahead.data(), ahead.size(), test::kSensorAddress);
    bench.controller_port.send_to(old.data(), old.size(), test::kSensorAddress);
    bench.controller_port.send_to(nan.data(), nan.size(), test::kSensorAddress);
    bench.controller_port.send_to(flag.data(), flag.size(), test::kSensorAddress);
    bench.controller_port.send_to(nan.data(), 100, test::kSensorAddress);
    bench.controller_port.send_to(big.data(), 2100, test::kSensorAddress);
    bench.controller_port.send_to(big.data(), big.size(), test::kSensorAddress);
    stranger.send_to(reply_bytes(outstanding).data(), rt::kReplyBytes, test::kSensorAddress);
  }
  bench.clock.set(bench.t_s + 0.001);  // delivered; the controller's own reply was taken already
  while (bench.link.poll(0.0) != LinkPollResult::kIdle) {
  }
  const LinkCounters& c = bench.link.counters();
  EXPECT_EQ(c.replies, sent) << "a command sent in answer to garbage";
  EXPECT_EQ(c.far_ahead, 10u);
  EXPECT_EQ(c.duplicate, 10u);
  EXPECT_EQ(c.non_finite, 10u);
  EXPECT_EQ(c.malformed, 10u);
  EXPECT_EQ(c.truncated, 10u);
  EXPECT_EQ(c.oversized, 20u);
  EXPECT_EQ(c.foreign_sender, 10u);
  bench.run(1.0);
  EXPECT_EQ(bench.controller.dropped(), "");
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
  EXPECT_GT(bench.link.counters().replies, sent + 200);
}

// The sensor falls silent: the correction ramps out at the rate bound, the stream goes on.
TEST(Motoros2RtLink, AStaleForceRampsTheCorrectionOutAtTheRateBound) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  MotoBench bench(test::hold_program(test::bench_robot(), q0, 30.0), q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -650));
  bench.run(3.0);
  const double held = (q0 - bench.controller.command_position()).cwiseAbs().maxCoeff();
  ASSERT_GT(held, 1e-4);
  bench.force.on = false;
  bench.run(3.0);
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
  EXPECT_LT((q0 - bench.controller.command_position()).cwiseAbs().maxCoeff(), 1e-9);
  expect_wire_invariants(bench);
}

TEST(Motoros2RtLink, AStoppedOrRestartedControllerEndsTheSessionAndNothingMovesTheArm) {
  for (const bool restart : {false, true}) {
    SCOPED_TRACE(restart ? "restart" : "stopped");
    const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
    MotoBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(8, -4, 6, 10, -8, 12), 20.0), q0);
    bench.run(2.0);
    if (restart) {
      bench.controller.restart(bench.t_s);  // a new session waits for command 0: deflex's next is not
    } else {
      bench.controller.stop("e-stop");
    }
    const std::uint64_t taken = bench.controller.counters().taken;
    bench.run(2.0);
    EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kSilent) << bench.link.stop_reason();
    EXPECT_EQ(bench.controller.counters().taken, taken);
    if (restart) {
      EXPECT_NE(bench.controller.dropped().find("not number 0"), std::string::npos);
    }
    expect_wire_invariants(bench, !restart);  // a new session starts its command position afresh
  }
}

// With the status side channel an e-stop ends the session at once, named, instead of after the stop
// silence; a status from another address, or one that does not decode, is counted and changes nothing.
TEST(Motoros2RtLink, AnEStopTheStatusReportsStopsTheLinkAtOnce) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  cell::Motoros2RtControllerConfig cc;
  cc.status_port = 22001;
  MotoBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(8, -4, 6, 10, -8, 12), 20.0), q0, cc);
  bench.run(1.0);
  EXPECT_GT(bench.link.statuses(), 80u);  // one every 10 ms
  MemoryTransport& stranger = bench.network.add_endpoint(test::kStrangerAddress, 0.0002);
  rt::RobotState bad;
  bad.e_stopped = true;
  std::array<unsigned char, rt::kRobotStateBytes> b{};
  ASSERT_EQ(rt::encode(bad, b.data(), b.size()), rt::kRobotStateBytes);
  stranger.send_to(b.data(), b.size(), {test::kSensorAddress.ipv4, 22001});  // not the controller's
  b[0] = 2;                                                                  // a boolean that is not 0 or 1
  bench.controller_port.send_to(b.data(), b.size(), {test::kSensorAddress.ipv4, 22001});
  bench.controller_port.send_to(b.data(), 20, {test::kSensorAddress.ipv4, 22001});
  bench.run(0.2);
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
  EXPECT_EQ(bench.link.statuses_refused(), 3u);
  bench.controller.stop("e-stop");
  bench.run(0.03);  // three status periods
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController) << bench.link.stop_reason();
  EXPECT_NE(std::string(bench.link.stop_reason()).find("an emergency stop"), std::string::npos)
      << bench.link.stop_reason();
  expect_wire_invariants(bench);
}

// A stalled PC: the controller applies nothing meanwhile (lock-step) and the stream resumes; a stall
// beyond the controller's timeout ends its session, and deflex names the silence.
TEST(Motoros2RtLink, AStalledPcIsRiddenThroughUntilTheControllersTimeout) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  cell::Motoros2RtControllerConfig cc;
  cc.timeout_s = 0.3;
  for (const double stall : {0.1, 0.5}) {
    SCOPED_TRACE(stall);
    MotoBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(8, -4, 6, 10, -8, 12), 20.0), q0, cc);
    bench.run(2.0);
    bench.stalled = true;
    bench.run(stall);
    bench.stalled = false;
    bench.run(1.0);
    if (stall < cc.timeout_s) {
      EXPECT_EQ(bench.link.state(), LinkState::kRunning);
      EXPECT_EQ(bench.controller.dropped(), "");
    } else {
      EXPECT_EQ(bench.controller.dropped(), "no command for timeout_for_rt_msg");
      EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kSilent) << bench.link.stop_reason();
    }
    expect_wire_invariants(bench);
  }
}

TEST(Motoros2RtLink, APlannedStopBringsTheProgramToRestOnItsPath) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  MotoBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(30, 0, 0, 30, 0, 0), 4.0, 161), q0);
  bench.run(2.0);
  bench.link.request_planned_stop(0.5);
  bench.run(2.0);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kRequested) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.dropped(), "");
  // The last increment next to nothing: the program at rest (no force, so no correction moving).
  const auto& inc = bench.controller.increments();
  ASSERT_GT(inc.size(), 3u);
  double largest = 0.0;
  for (const JointVector& i : inc) largest = std::max(largest, i.cwiseAbs().maxCoeff());
  EXPECT_LT(inc.back().cwiseAbs().maxCoeff(), 1e-3 * largest);
  // Stopped on its path, short of the program's end.
  JointVector q(6);
  bench.program->sample(bench.link.stream().program_time_s(), q);
  EXPECT_LT((bench.controller.command_position() - q).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(bench.link.stream().program_time_s(), 3.0);
  expect_wire_invariants(bench);
}

TEST(Motoros2RtLink, AnArmAwayFromTheProgramIsRefusedAndNeverMoved) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  MotoBench bench(test::hold_program(test::bench_robot(), q0, 30.0), pose_deg(3, 20, 10, 0, 60, 0));
  bench.run(0.5);
  EXPECT_EQ(bench.link.state(), LinkState::kRefused);
  EXPECT_NEAR(bench.link.start_distance()[0], deg_to_rad(3.0), 1e-9);
  // Only the session's first command (no motion) was ever taken.
  EXPECT_EQ(bench.controller.counters().taken, 1u);
  EXPECT_LT(bench.controller.increments().front().cwiseAbs().maxCoeff(), 1e-15);
}

// The stand-in's own rules, as the sources state them: a gap up to max_sequence_diff_for_rt_msg is
// taken (its increments lost), one beyond drops the session; a second sender drops it too.
TEST(Motoros2RtController, DropsTheSessionOnASequenceJumpBeyondItsMaximumOrASecondSender) {
  ManualClock clock;
  MemoryNetwork network{clock, 8192};
  MemoryTransport& pc = network.add_endpoint(test::kSensorAddress, 0.0);
  MemoryTransport& port = network.add_endpoint(test::kControllerAddress, 0.0);
  MemoryTransport& other = network.add_endpoint(test::kStrangerAddress, 0.0);
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  cell::Motoros2RtController controller({}, q0, port);
  double t = 0.0;
  const auto send = [&](MemoryTransport& from, std::uint32_t seq, double inc) {
    rt::Command c;
    c.sequence = seq;
    c.delta[0][0] = inc;
    std::vector<unsigned char> b(rt::kCommandBytes);
    ASSERT_EQ(rt::encode(c, b.data(), b.size()), rt::kCommandBytes);
    from.send_to(b.data(), b.size(), test::kControllerAddress);
    t += 0.004;
    clock.set(t);
    controller.tick(t);
  };
  send(pc, 0, 0.001);
  send(pc, 1, 0.001);
  send(pc, 4, 0.001);  // 2 and 3 lost: a gap of 3 is taken
  EXPECT_EQ(controller.dropped(), "");
  EXPECT_EQ(controller.counters().skipped, 2u);
  EXPECT_NEAR(controller.command_position()[0], q0[0] + 0.003, 1e-15);
  send(pc, 4, 0.001);  // a duplicate: answered, not applied
  EXPECT_EQ(controller.counters().duplicates, 1u);
  EXPECT_NEAR(controller.command_position()[0], q0[0] + 0.003, 1e-15);
  send(other, 5, 0.0);
  EXPECT_EQ(controller.dropped(), "a command from a second sender");
  controller.restart(t);
  send(pc, 0, 0.0);
  send(pc, 1, 0.0);
  send(pc, 5, 0.0);  // a gap of 4
  EXPECT_EQ(controller.dropped(), "Missed too many command packets");
  const std::uint64_t replies = controller.counters().replies;
  send(pc, 6, 0.0);
  EXPECT_EQ(controller.counters().replies, replies) << "a dropped session answers nothing";
}

// Every poll of a whole session: the start, resends after lost commands, truncations, the statuses,
// the end.
TEST(Motoros2RtLink, NoPollFromStartToEndAllocates) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(5, 5, 5, 5, 5, 5), 2.0);
  cell::Motoros2RtControllerConfig cc;
  cc.status_port = 22001;
  cc.fsu_speed_rad_s = 0.95 * test::sampled_peak_speed(*program).maxCoeff();
  MotoBench bench(program, q0, cc, 10000);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  bench.network.add_outage(1.0005, 1.03, test::kControllerAddress);
  std::size_t allocations = 0;
  for (int k = 0; k < 2000 && bench.link.state() != LinkState::kStopped; ++k) {
    bench.t_s += kPeriod;
    bench.clock.set(bench.t_s);
    bench.controller.tick(bench.t_s);
    bench.clock.set(bench.t_s + 0.0005);
    for (;;) {
      test::AllocationGuard guard;
      const LinkPollResult r = bench.link.poll(0.0);
      allocations += guard.allocations();
      if (r == LinkPollResult::kIdle || bench.link.state() == LinkState::kStopped) break;
    }
  }
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kEnded) << bench.link.stop_reason();
  EXPECT_GE(bench.link.resent(), 1u);
  EXPECT_GE(bench.link.truncations(), 1u);
  EXPECT_GT(bench.link.statuses(), 100u);
  EXPECT_EQ(allocations, 0u);
}

TEST(Motoros2RtLink, BadSettingsAreRefusedNamingThem) {
  Motoros2RtLinkConfig c;
  c.group = 8;
  EXPECT_THROW(c.validate(), InputError);
  c.group = 0;
  c.tool = 64;
  try {
    c.validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--motoros2-tool"), std::string::npos) << e.what();
  }
  c.tool = 0;
  c.resend_after_s = 0.0;
  EXPECT_THROW(c.validate(), InputError);
  c.resend_after_s = 0.012;
  c.max_truncation_run = -1;
  EXPECT_THROW(c.validate(), InputError);
}

}  // namespace
}  // namespace deflex
