// deflex's UR RTDE link against a stand-in of the controller with its semantics (cell/ur_rtde_controller.hpp:
// the RTDE handshake and recipes, one output package a 2 ms loop, the script handing the newest registers
// to servoj, servoj's lookahead as dead time and its gain as lag, the joint speed limit as a protective
// stop, the watchdog stopping the program): the arm converges to the model's correction (computed here
// with a finite-difference Jacobian), every target servoj took is within the per-cycle step limit and
// the bound of the nominal, the measured delay is servoj's lookahead (the stand-in's dead time, set
// here), and every fault ends with the link stopped for a named reason.
#include <array>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/cell/ur_rtde_controller.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/transport/memory_stream.hpp"
#include "deflex/ur/ur_rtde_link.hpp"
#include "links/link_harness.hpp"
#include "support/allocation_guard.hpp"
#include "support/poses.hpp"
#include "support/sampled_speed.hpp"

namespace deflex {
namespace {

using test::pose_deg;

constexpr double kUrPeriod = 0.002;

struct UrBench {
  RobotModel robot = test::bench_robot();
  ManualClock clock;
  MemoryStreamPair pair{clock, 0.0001};
  OnlineCompensator compensator;
  OnlineStrategy strategy;
  test::ConstantForce force;
  std::shared_ptr<const JointTrajectory> program;
  JointVector start;
  UrRtdeLink link;
  cell::UrRtdeController controller;
  double t_s = 0.0;
  bool stalled = false;

  static UrRtdeLinkConfig link_config(double lookahead_s) {
    UrRtdeLinkConfig c;
    c.stop.stop_silence_s = 0.5;
    c.lookahead_s = lookahead_s;
    return c;
  }

  UrBench(std::shared_ptr<const JointTrajectory> p, const JointVector& arm, const cell::UrRtdeControllerConfig& cc = {},
          double lookahead_s = 0.03, double period_s = kUrPeriod)
      : compensator(robot, test::bench_sensor(), test::bench_online(period_s)),
        strategy(robot, StrategyKind::kOnline, nullptr),
        program(std::move(p)),
        start(arm),
        link(compensator, strategy, program, pair.client(), clock, link_config(lookahead_s)),
        controller(cc, arm, pair.server()) {
    link.read_force_from(&force);
  }

  /// One loop cycle of the controller, then deflex answers what reached it.
  LinkPollResult tick(double period_s = kUrPeriod) {
    t_s += period_s;
    clock.set(t_s);
    controller.tick(t_s);
    clock.set(t_s + 0.0003);
    LinkPollResult last = LinkPollResult::kIdle;
    while (!stalled) {
      const LinkPollResult r = link.poll(0.0);
      if (r == LinkPollResult::kIdle || link.state() == LinkState::kStopped) break;
      last = r;
    }
    return last;
  }
  void run(double seconds, double period_s = kUrPeriod) {
    const double end = t_s + seconds;
    while (t_s < end - 1e-9) tick(period_s);
  }
};

// The per-cycle step limit computed here: the program's peak speed sampled every 0.5 ms, the blend's
// 1.5 x 1 deg over the 1 s ramp-in, the rate bound, over one period.
JointVector ur_step_limit(const UrBench& b) {
  return kUrPeriod * (test::sampled_peak_speed(*b.program) * 1.001).array() +
         kUrPeriod * (1.5 * deg_to_rad(1.0) / 1.0 + b.compensator.config().max_correction_rate_rad_s) + 1e-9;
}

// Every target servoj took is within the step limit of the one before (the first: of the arm's start);
// every absolute deflex sent within the bound of the program (sampled here) plus its blend.
void expect_ur_wire_invariants(const UrBench& b) {
  const JointVector limit = ur_step_limit(b);
  JointVector prev = b.start;
  for (std::size_t k = 0; k < b.controller.targets().size(); ++k) {
    const JointVector& q = b.controller.targets()[k];
    for (int j = 0; j < 6; ++j) ASSERT_LE(std::abs(q[j] - prev[j]), limit[j]) << "target " << k << " joint " << j;
    prev = q;
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

bool ur_says(const UrRtdeLink& link, const char* what) {
  return std::string(link.stop_reason()).find(what) != std::string::npos;
}

TEST(UrRtdeLink, ConstantForceHoldsTheModelsCorrection) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  UrBench bench(test::hold_program(test::bench_robot(), q0, 60.0), q0);
  const Vector3 f_base(150.0, -250.0, -300.0);
  const JointVector expected = test::model_correction(bench.robot, q0, f_base);
  ASSERT_LT(expected.cwiseAbs().maxCoeff(), bench.compensator.config().max_joint_correction_rad);
  for (int k = 0; k < 5000; ++k) {  // 10 s
    bench.force.reading = test::reading_at(bench.robot, bench.controller.position(), f_base);
    bench.tick();
    ASSERT_EQ(bench.controller.stopped(), "") << "at " << bench.t_s << " s";
  }
  ASSERT_TRUE(bench.link.handshake_done());
  ASSERT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
  EXPECT_EQ(bench.link.controller_version().major, 5u);
  // One package answered a loop cycle: the script servoed nearly every cycle.
  EXPECT_GT(bench.controller.counters().servo_cycles, 4900u);
  const JointVector held = q0 - bench.controller.position();
  EXPECT_LT((held - expected).cwiseAbs().maxCoeff(), 0.01 * expected.cwiseAbs().maxCoeff())
      << "held " << held.transpose() << "\nmodel " << expected.transpose();
  // servoj ran with what deflex sent.
  EXPECT_DOUBLE_EQ(bench.controller.lookahead_s(), 0.03);
  EXPECT_DOUBLE_EQ(bench.controller.gain(), 2000.0);
  EXPECT_EQ(bench.link.counters().guard_trips, 0u);
  EXPECT_EQ(bench.link.counters().rejected(), 0u);
  expect_ur_wire_invariants(bench);
}

// The stand-in's dead time is the lookahead (0.1 s here), its lag 1/gain, plus up to a cycle: the
// delay the link measures on a moving program, and the lead the strategy was given, is that.
TEST(UrRtdeLink, ServojsLookaheadIsMeasuredAsTheLinksDelayAndIsTheStrategysLead) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const JointVector delta = pose_deg(12, -6, 9, 15, -12, 25);
  UrBench bench(test::sweep_program(test::bench_robot(), q0, delta, 6.0), q0, {}, 0.1);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  bench.run(4.0);
  ASSERT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
  const DelayEstimator* d = bench.link.delay_estimator();
  ASSERT_TRUE(d->measured());
  EXPECT_GE(d->delay_s(), 0.1 - 0.5 * kUrPeriod);
  EXPECT_LE(d->delay_s(), 0.1 + 1.0 / 2000.0 + 3 * kUrPeriod);
  // A measurement of its own, not the starting figure (0.1025 s) carried through.
  EXPECT_GE(d->last_measurement_s(), 0.1 - 0.5 * kUrPeriod);
  EXPECT_LE(d->last_measurement_s(), 0.1 + 1.0 / 2000.0 + 3 * kUrPeriod);
  EXPECT_NE(d->last_measurement_s(), bench.link_config(0.1).servoj_delay_s(kUrPeriod));
  EXPECT_DOUBLE_EQ(bench.link.last_cycle().delay_s, d->delay_s());
}

TEST(UrRtdeLink, AProgramRunsToItsEndAndTheScriptHoldsItsLastTarget) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const JointVector delta = pose_deg(12, -6, 9, 15, -12, 25);
  UrBench bench(test::sweep_program(test::bench_robot(), q0, delta, 6.0), q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  for (int k = 0; k < 4000 && bench.link.state() != LinkState::kStopped; ++k) bench.tick();
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kEnded) << bench.link.stop_reason();
  // The program at 0, 2 ms, ... 6 s: one target each.
  EXPECT_EQ(bench.link.counters().replies, 3001u);
  bench.run(0.2);
  EXPECT_EQ(bench.controller.stopped(), "the program ended (the stream's end)");
  const JointVector correction = (q0 + delta) - bench.controller.position();
  EXPECT_LE(correction.cwiseAbs().maxCoeff(), bench.compensator.config().max_joint_correction_rad);
  EXPECT_GT(correction.cwiseAbs().maxCoeff(), 1e-5);
  expect_ur_wire_invariants(bench);
}

TEST(UrRtdeLink, ProtectiveAndEmergencyStopsAndAStoppedProgramEndTheSessionNamingThem) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  for (int fault = 0; fault < 3; ++fault) {
    UrBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(10, 0, 0, 0, 0, 0), 6.0), q0);
    bench.run(1.0);
    ASSERT_EQ(bench.link.state(), LinkState::kRunning);
    if (fault == 0) bench.controller.protective_stop("test");
    if (fault == 1) bench.controller.emergency_stop();
    if (fault == 2) bench.controller.stop_program();
    bench.run(0.05);
    EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController) << fault;
    EXPECT_TRUE(ur_says(bench.link, fault == 0   ? "a protective stop (safety_mode 3)"
                                    : fault == 1 ? "a robot emergency stop (safety_mode 7)"
                                                 : "stopped (runtime_state 1)"))
        << bench.link.stop_reason();
    expect_ur_wire_invariants(bench);
  }
}

// A target faster than the safety configuration's joint speed limit: the controller's protective
// stop, and the link names it.
TEST(UrRtdeLink, ATargetBeyondTheControllersSpeedLimitIsAProtectiveStopTheLinkNames) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(20, 0, 0, 0, 0, 0), 2.0);
  cell::UrRtdeControllerConfig cc;
  cc.max_speed_rad_s = 0.5 * test::sampled_peak_speed(*program).maxCoeff();
  UrBench bench(program, q0, cc);
  bench.run(3.0);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController) << bench.link.stop_reason();
  EXPECT_TRUE(ur_says(bench.link, "protective stop")) << bench.link.stop_reason();
  EXPECT_EQ(bench.controller.stopped(), "protective stop: a joint's speed limit was exceeded");
}

// A stalled PC: the counter stops changing, the script's watchdog stops the program after 0.1 s, and
// the link, once it runs again, stops naming the program's state.
TEST(UrRtdeLink, AStalledPcTripsTheScriptsWatchdogAndTheLinkStopsNamingIt) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  UrBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(10, 0, 0, 0, 0, 0), 6.0), q0);
  bench.run(1.0);
  bench.stalled = true;
  bench.run(0.05);
  EXPECT_EQ(bench.controller.stopped(), "");  // a stall shorter than the watchdog is ridden through
  bench.run(0.1);
  EXPECT_EQ(bench.controller.stopped(), "the RTDE watchdog: input_int_register_24 did not change");
  const JointVector where = bench.controller.position();
  bench.stalled = false;
  bench.run(0.05);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController);
  EXPECT_TRUE(ur_says(bench.link, "runtime_state 1")) << bench.link.stop_reason();
  EXPECT_LT((bench.controller.position() - where).cwiseAbs().maxCoeff(), 1e-12) << "the arm moved after the stop";
  expect_ur_wire_invariants(bench);
}

TEST(UrRtdeLink, AnErrorTextMessageEndsTheSessionNamingIt) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  UrBench bench(test::hold_program(test::bench_robot(), q0, 10.0), q0);
  bench.run(0.5);
  bench.controller.error_message("servoj: invalid setpoints");
  bench.run(0.01);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController);
  EXPECT_TRUE(ur_says(bench.link, "RTDE error message: servoj: invalid setpoints")) << bench.link.stop_reason();
  EXPECT_EQ(bench.link.text_messages()[1], 1u);
}

// The controller's texts are bytes (UR's own client takes them as sent: UniversalRobots/
// RTDE_Python_Client_Library, rtde/serialize.py, Message): an error with a byte beyond ASCII, written
// into the stream by hand, still ends the session, the byte shown as '?'.
TEST(UrRtdeLink, AnErrorTextWithBytesThatDoNotPrintStillEndsTheSession) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  UrBench bench(test::hold_program(test::bench_robot(), q0, 10.0), q0);
  bench.run(0.5);
  ASSERT_EQ(bench.link.state(), LinkState::kRunning);
  // 22 bytes: the size, 'M', "J3 71\xB0C" (7), source "URControl" (9), level 1 (error).
  const unsigned char text[22] = {0, 22,  'M', 7,   'J', '3', ' ', '7', '1', 0xB0, 'C',
                                  9, 'U', 'R', 'C', 'o', 'n', 't', 'r', 'o', 'l',  1};
  ASSERT_EQ(bench.pair.server().write(text, sizeof text), 22);
  bench.run(0.01);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController);
  EXPECT_TRUE(ur_says(bench.link, "RTDE error message: J3 71?C")) << bench.link.stop_reason();
}

// The handshake read as UR's own client reads it (UniversalRobots/RTDE_Python_Client_Library,
// rtde/rtde.py and rtde/serialize.py): the version reply's byte is a truth value, and until the
// controller accepted protocol 2 its text messages are protocol 1's (the level, then the text).
TEST(UrRtdeLink, TheHandshakeTakesAnyNonZeroAcceptAndProtocol1TextsBeforeVersion2) {
  const RobotModel robot = test::bench_robot();
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  UrRtdeLinkConfig config;
  config.stop.stop_silence_s = 0.5;
  // A link from its first byte, and one exchange: the controller's reply (if any) written, five cycles
  // polled, what the link sent back read.
  struct Handshake {
    ManualClock clock;
    MemoryStreamPair pair{clock, 0.0001};
    OnlineCompensator compensator;
    OnlineStrategy strategy;
    UrRtdeLink link;
    double t = 0.0;
    Handshake(const RobotModel& robot, const JointVector& q0, const UrRtdeLinkConfig& config)
        : compensator(robot, test::bench_sensor(), test::bench_online(kUrPeriod)),
          strategy(robot, StrategyKind::kOnline, nullptr),
          link(compensator, strategy, test::hold_program(robot, q0, 10.0), pair.client(), clock, config) {}
    std::vector<unsigned char> exchange(const std::vector<unsigned char>& reply) {
      if (!reply.empty()) {
        EXPECT_EQ(pair.server().write(reply.data(), reply.size()), static_cast<long>(reply.size()));
      }
      for (int k = 0; k < 5; ++k) {
        clock.set(t += kUrPeriod);
        (void)link.poll(0.0);
      }
      std::array<unsigned char, 64> got{};
      const long n = pair.server().read(got.data(), got.size());
      return std::vector<unsigned char>(got.begin(), got.begin() + std::max(n, 0L));
    }
  };
  {
    Handshake h(robot, q0, config);
    EXPECT_EQ(h.exchange({}), (std::vector<unsigned char>{0, 5, 'V', 0, 2}));
    EXPECT_EQ(h.exchange({0, 4, 'V', 2}), (std::vector<unsigned char>{0, 3, 'v'}))
        << "the version reply's byte 2 is accepted: the next request is the controller's version";
    EXPECT_NE(h.link.state(), LinkState::kStopped) << h.link.stop_reason();
  }
  {
    Handshake h(robot, q0, config);
    (void)h.exchange({});
    (void)h.exchange({0, 10, 'M', 1, 'C', '2', '0', '4', 'A', '3'});
    EXPECT_EQ(h.link.stop_cause(), LinkStopCause::kController);
    EXPECT_TRUE(ur_says(h.link, "RTDE error message: C204A3")) << h.link.stop_reason();
  }
}

TEST(UrRtdeLink, ARefusedRecipeOrARateTheControllerCannotGiveStopsTheHandshake) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  {
    cell::UrRtdeControllerConfig cc;
    cc.in_use_registers = {27};
    UrBench bench(test::hold_program(test::bench_robot(), q0, 10.0), q0, cc);
    bench.run(0.1);
    EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController);
    EXPECT_TRUE(ur_says(bench.link, "input field 6")) << bench.link.stop_reason();
    EXPECT_TRUE(ur_says(bench.link, "IN_USE")) << bench.link.stop_reason();
    EXPECT_EQ(bench.controller.counters().servo_cycles, 0u);
  }
  {
    cell::UrRtdeControllerConfig cc;
    cc.e_series = false;  // CB3: 125 Hz
    UrBench bench(test::hold_program(test::bench_robot(), q0, 10.0), q0, cc);
    bench.run(0.1, 0.008);
    EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController);
    EXPECT_TRUE(ur_says(bench.link, "runs at most 125 Hz")) << bench.link.stop_reason();
  }
  {  // CB3 at its own rate runs.
    cell::UrRtdeControllerConfig cc;
    cc.e_series = false;
    UrBench bench(test::hold_program(test::bench_robot(), q0, 10.0), q0, cc, 0.03, 0.008);
    bench.run(1.0, 0.008);
    EXPECT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
    EXPECT_GT(bench.controller.counters().servo_cycles, 110u);
  }
}

// Packages the controller's stream should not hold, written into it by hand: each counted, none
// answered, an oversized one dropped by its size; a header whose size is below the header's own stops
// the link (the stream cannot be re-framed).
TEST(UrRtdeLink, GarbageOutOfOrderAndTruncatedPackagesAreCountedAndNeverAnswered) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  UrBench bench(test::hold_program(test::bench_robot(), q0, 10.0), q0);
  bench.run(0.5);
  ASSERT_EQ(bench.link.state(), LinkState::kRunning);
  const std::uint64_t replies = bench.link.counters().replies;
  // A data package of another recipe id (7), of the right size for deflex's recipe: 3 + 1 + 8 + 2*48 + 3*4 + 4 + 4.
  std::array<unsigned char, 128> p{};
  const std::size_t n = 3 + 1 + 8 + 96 + 4 + 4 + 4 + 4;
  p[0] = 0;
  p[1] = static_cast<unsigned char>(n);
  p[2] = 'U';
  p[3] = 7;
  ASSERT_EQ(bench.pair.server().write(p.data(), n), static_cast<long>(n));
  // A data package of deflex's recipe with timestamp 0: older than the controller's last.
  p[3] = 1;
  ASSERT_EQ(bench.pair.server().write(p.data(), n), static_cast<long>(n));
  // A package of a type RTDE does not have.
  const unsigned char unknown[4] = {0, 4, 'Z', 0};
  ASSERT_EQ(bench.pair.server().write(unknown, 4), 4);
  bench.clock.set(bench.t_s + 0.001);
  while (bench.link.poll(0.0) != LinkPollResult::kIdle) {
  }
  EXPECT_EQ(bench.link.counters().replies, replies) << "a garbage package was answered";
  EXPECT_GE(bench.link.counters().malformed, 2u);
  EXPECT_EQ(bench.link.counters().out_of_order, 1u);
  bench.run(0.1);
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
  // A package larger than the link takes (5000 bytes, over its 4096): dropped by its size, counted, and
  // the stream framed again after it.
  std::vector<unsigned char> big(5000, 0xAB);
  big[0] = 5000 >> 8;
  big[1] = 5000 & 0xFF;
  big[2] = 'U';
  ASSERT_EQ(bench.pair.server().write(big.data(), big.size()), static_cast<long>(big.size()));
  const std::uint64_t before = bench.link.counters().replies;
  bench.run(0.1);
  EXPECT_EQ(bench.link.state(), LinkState::kRunning) << bench.link.stop_reason();
  EXPECT_EQ(bench.link.counters().oversized, 1u);
  EXPECT_GT(bench.link.counters().replies, before + 40);
  const unsigned char short_header[3] = {0, 2, 'U'};
  ASSERT_EQ(bench.pair.server().write(short_header, 3), 3);
  bench.run(0.01);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kProtocol);
  EXPECT_TRUE(ur_says(bench.link, "out of step")) << bench.link.stop_reason();
  expect_ur_wire_invariants(bench);
}

TEST(UrRtdeLink, AClosedConnectionEndsTheSessionAndTheWatchdogStopsTheArm) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  UrBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(10, 0, 0, 0, 0, 0), 6.0), q0);
  bench.run(1.0);
  bench.pair.server().close();
  bench.run(0.2);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kConnection);
  EXPECT_NE(bench.controller.stopped(), "");
}

// A server that never answers (another service on the port, a controller without RTDE): the link gives
// up on the handshake after 2 s, naming what it waited for, and sent no target.
TEST(UrRtdeLink, AControllerThatNeverAnswersTheHandshakeEndsTheSessionNamingIt) {
  const RobotModel robot = test::bench_robot();
  ManualClock clock;
  MemoryStreamPair pair(clock, 0.0001);
  OnlineCompensator compensator(robot, test::bench_sensor(), test::bench_online(kUrPeriod));
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  UrRtdeLinkConfig config;
  config.stop.stop_silence_s = 0.5;  // the session's default for ur-rtde: the handshake still gets 2 s
  UrRtdeLink link(compensator, strategy, test::hold_program(robot, q0, 10.0), pair.client(), clock, config);
  for (int k = 0; k < 1100 && link.state() != LinkState::kStopped; ++k) {
    clock.set(k * kUrPeriod);
    (void)link.poll(0.0);
  }
  EXPECT_EQ(link.stop_cause(), LinkStopCause::kSilent);
  EXPECT_TRUE(ur_says(link, "no answer to deflex's protocol version request")) << link.stop_reason();
  EXPECT_GT(clock.now_s(), 2.0);
  EXPECT_EQ(link.counters().replies, 0u);
}

TEST(UrRtdeLink, PollNeverAllocates) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  UrBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(10, -5, 5, 0, 0, 0), 3.0), q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -300));
  bench.run(0.1);  // the handshake (its recipe text is parsed once) and the first cycles
  ASSERT_TRUE(bench.link.handshake_done());
  std::size_t allocations = 0;
  for (int k = 0; k < 3000 && bench.link.state() != LinkState::kStopped; ++k) {
    bench.t_s += kUrPeriod;
    bench.clock.set(bench.t_s);
    bench.controller.tick(bench.t_s);
    bench.clock.set(bench.t_s + 0.0003);
    for (;;) {
      test::AllocationGuard guard;
      const LinkPollResult r = bench.link.poll(0.0);
      allocations += guard.allocations();
      if (r == LinkPollResult::kIdle || bench.link.state() == LinkState::kStopped) break;
    }
  }
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kEnded) << bench.link.stop_reason();
  EXPECT_EQ(allocations, 0u);
}

TEST(UrRtdeLink, BadSettingsAreRefusedNamingThem) {
  UrRtdeLinkConfig c;
  c.lookahead_s = 0.02;
  EXPECT_THROW(c.validate(), InputError);
  c.lookahead_s = 0.03;
  c.gain = 2500;
  EXPECT_THROW(c.validate(), InputError);
  c.gain = 300;
  c.register_offset = 12;
  EXPECT_THROW(c.validate(), InputError);
  c.register_offset = 0;
  EXPECT_NO_THROW(c.validate());
  // servoj's delay: the lookahead, 1/gain, one cycle.
  EXPECT_DOUBLE_EQ(c.servoj_delay_s(0.002), 0.03 + 1.0 / 300.0 + 0.002);
}

}  // namespace
}  // namespace deflex
