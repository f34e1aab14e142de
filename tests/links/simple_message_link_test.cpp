// deflex's ROS-Industrial simple message link against the simulated RAPID streaming server
// (simple_message_bench.hpp) and against controllers scripted by hand. The invariants of the EGM links:
// no point ever leaves the nominal by more than the bound, a constant force converges to the model's
// correction (computed here with a finite-difference Jacobian) with no drift over 10,000 points, zero
// force streams the program itself (each point the float32 of the program at its time). Then what a
// TCP robot program adds: the buffer kept at its depth and its lag measured; a full buffer (FAILURE)
// makes the link wait without skipping a point; FAILURE replies in a row, an emergency stop, a dropped
// connection, a silent controller, and every kind of bad frame stop the motion with STOP_TRAJECTORY
// and say why; a start away from the program is refused with nothing sent; partial writes never cut a
// point; both byte orders; the cycle does not allocate.
#include <gtest/gtest.h>

#include "support/poses.hpp"

#include <cstring>
#include <functional>
#include <limits>
#include <map>

#include "links/simple_message_bench.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

using test::ScriptedSimpleMessage;
using test::SimpleMessageBench;

using test::pose_deg;

double as_float(double v) { return static_cast<double>(static_cast<float>(v)); }

JointVector float_rounded(const JointVector& q) {
  JointVector r = q;
  for (int j = 0; j < r.size(); ++j) r[j] = as_float(q[j]);
  return r;
}

TEST(SimpleMessageLink, ConstantForceConvergesWithinTheBoundAndNeverDriftsOver10000Points) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  SimpleMessageBench bench(test::hold_program(test::bench_robot(), q0, 5000.0), q0);
  const Vector3 f_base(150.0, -250.0, -300.0);
  bench.force.reading = test::reading_at(bench.robot, q0, f_base);
  const JointVector expected = test::model_correction(bench.robot, q0, f_base);
  const double bound = bench.compensator.config().max_joint_correction_rad;
  ASSERT_LT(expected.cwiseAbs().maxCoeff(), bound);

  JointVector at_1k, at_10k;
  double worst = 0.0;
  while (bench.points < 10000) {
    // The sensor turns with the arm: its reading is the base-frame force seen at the arm's pose.
    bench.force.reading = test::reading_at(bench.robot, bench.server->motion().position(), f_base);
    const std::uint64_t before = bench.points;
    ASSERT_NE(bench.tick(), LinkPollResult::kStopped) << bench.link.stop_reason();
    if (bench.points == before) continue;
    const LinkCycleRecord& r = bench.link.last_cycle();
    worst = std::max(worst, (r.q_command - r.q_nominal).cwiseAbs().maxCoeff());
    if (bench.points == 1000) at_1k = r.q_command;
  }
  at_10k = bench.link.last_cycle().q_command;
  EXPECT_LE(worst, bound);
  // Converged to the nominal minus the model's correction (within the float32 of the wire), and still
  // there 9,000 points later, to the bit.
  EXPECT_LT((at_10k - (q0 - expected)).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((at_10k - at_1k).cwiseAbs().maxCoeff(), 3e-7);  // at most one float32 step apart
  // The controller took every point; the arm sits at the last one.
  for (int k = 0; k < 100; ++k) bench.tick();
  EXPECT_EQ(bench.server->motion().position(), bench.server->last_target());
  EXPECT_LT((bench.server->last_target() - at_10k).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(bench.link.counters().guard_trips, 0u);
  EXPECT_EQ(bench.server->counters().refused_full + bench.server->counters().refused_invalid, 0u);
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
}

// With zero force every point is the program at k cycles, to the float32 of the wire: the link's record
// of point k against the program sampled here, and what reached the controller against that record.
void expect_points_are_the_program(SimpleMessageBench& bench, const JointTrajectory& program,
                                   std::map<std::int32_t, JointVector>& sent) {
  const LinkCycleRecord& r = bench.link.last_cycle();
  const auto k = static_cast<std::int32_t>(r.sequence);
  EXPECT_NEAR(r.program_time_s, program.start_time_s() + 0.1 * k, 1e-9) << "point " << k;
  JointVector nominal(6);
  program.sample(r.program_time_s, nominal);
  // The nominal is the program, un-blended; during the 1 s ramp-in the blend takes out the float32
  // rounding of the arm's reported start (and is zero after it).
  EXPECT_LT((r.q_nominal - nominal).cwiseAbs().maxCoeff(), 1e-12) << "point " << k;
  EXPECT_LT(r.q_blend.cwiseAbs().maxCoeff(), r.program_time_s - program.start_time_s() < 1.0 ? 3e-7 : 1e-300)
      << "point " << k;
  EXPECT_EQ(r.q_command, float_rounded(r.q_nominal + r.q_blend)) << "point " << k;
  sent[k] = r.q_command;
}

TEST(SimpleMessageLink, ZeroForceStreamsTheProgramItselfOnePointACycle) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(10, -5, 8, 20, -10, 30), 8.0);
  SimpleMessageBench bench(program, q0);
  bench.force.reading = Vector6::Zero();
  std::map<std::int32_t, JointVector> sent;
  std::int32_t seen = -1;
  while (bench.link.state() != LinkState::kFinished) {
    const std::uint64_t before = bench.points;
    ASSERT_NE(bench.tick(), LinkPollResult::kStopped) << bench.link.stop_reason();
    ASSERT_LT(bench.t_s, 20.0);
    if (bench.points != before) expect_points_are_the_program(bench, *program, sent);
    if (bench.server->last_sequence() == seen) continue;
    // A new point reached the controller: the next one, exactly what the link sent.
    ASSERT_EQ(bench.server->last_sequence(), seen + 1);
    seen = bench.server->last_sequence();
    ASSERT_EQ(sent.count(seen), 1u);
    EXPECT_EQ(bench.server->last_target(), sent[seen]) << "point " << seen;
  }
  EXPECT_EQ(seen, 80);  // 8 s at 0.1 s: points 0..80, the last at the program's end
  for (int k = 0; k < 200; ++k) bench.tick();
  EXPECT_EQ(bench.server->motion().position(), bench.server->last_target());
  EXPECT_LT((bench.server->last_target() - program->points().back()).cwiseAbs().maxCoeff(), 3e-7);
  EXPECT_EQ(bench.server->counters().accepted, 81u);
}

TEST(SimpleMessageLink, MovingUnderForceStaysWithinTheBoundAndMeasuresTheBufferLag) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(12, -6, 9, 15, -12, 25), 20.0);
  SimpleMessageBench bench(program, q0);
  const Vector3 f_base(0.0, 0.0, -650.0);
  double worst = 0.0;
  while (bench.points < 150) {
    bench.force.reading = test::reading_at(bench.robot, bench.server->motion().position(), f_base);
    const std::uint64_t before = bench.points;
    ASSERT_NE(bench.tick(), LinkPollResult::kStopped) << bench.link.stop_reason();
    if (bench.points == before) continue;
    const LinkCycleRecord& r = bench.link.last_cycle();
    worst = std::max(worst, (r.q_command - r.q_nominal).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, bench.compensator.config().max_joint_correction_rad);
  EXPECT_GT(worst, 1e-5);
  EXPECT_DOUBLE_EQ(bench.link.buffer_lag_s(), 0.2);
  // Points 0 and 1 go at once, point k one cycle after point k-1; the arm reaches point k at the end of
  // its move k, which began from rest 50 ms (the planner's latency) plus 50 ms (half the ramp) after point
  // 0: so it reaches point k 0.2 + 0.1 s after it was sent. The buffer's two cycles, plus that start.
  ASSERT_TRUE(bench.link.delay().measured());
  EXPECT_GT(bench.link.delay().delay_s(), 0.2 + 0.1 - 0.005);
  EXPECT_LT(bench.link.delay().delay_s(), 0.2 + 0.1 + 0.01);
  // The buffer stayed at its depth: never a FAILURE, never a corner without its next point.
  EXPECT_EQ(bench.server->counters().refused_full, 0u);
  EXPECT_EQ(bench.server->motion().counters().corner_failures, 0u);
  EXPECT_GE(bench.server->motion().queued(), 1u);
}

TEST(SimpleMessageLink, RefusesAStartMoreThanOneDegreeFromTheProgramAndSendsNothing) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  JointVector arm = q0;
  arm[1] += deg_to_rad(1.5);
  SimpleMessageBench bench(test::hold_program(test::bench_robot(), q0, 10.0), arm);
  EXPECT_EQ(bench.tick(), LinkPollResult::kRefused);
  EXPECT_EQ(bench.link.state(), LinkState::kRefused);
  EXPECT_NEAR(bench.link.start_distance()[1], deg_to_rad(1.5), 1e-6);  // from float32 feedback
  for (int k = 0; k < 500; ++k) EXPECT_EQ(bench.tick(), LinkPollResult::kIdle);
  EXPECT_EQ(bench.server->counters().requests, 0u);  // not a point, not even a STOP
  EXPECT_EQ(bench.link.protocol_counters().points_sent, 0u);
  EXPECT_EQ(bench.server->motion().position(), arm);
}

TEST(SimpleMessageLink, StartsWhereTheArmIsAndBlendsTheOffsetOut) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  JointVector arm = q0;
  arm[2] -= deg_to_rad(0.8);
  SimpleMessageLinkConfig config;
  config.stream.ramp_in_s = 0.5;
  SimpleMessageBench bench(test::hold_program(test::bench_robot(), q0, 10.0), arm, StrategyKind::kOnline, nullptr,
                           config);
  bench.force.reading = Vector6::Zero();
  ASSERT_TRUE(bench.run_points(1));
  // The first point is where the controller says the arm is (its float32 JOINT_POSITION).
  EXPECT_EQ(bench.link.last_cycle().q_command, float_rounded(arm));
  ASSERT_TRUE(bench.run_points(10));
  EXPECT_EQ(bench.link.last_cycle().q_command, float_rounded(q0));  // after 0.5 s of program: the program
}

TEST(SimpleMessageLink, AFullBufferMakesTheLinkWaitACycleAndNoPointIsSkipped) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(8, -4, 6, 10, -8, 12), 15.0);
  SimpleMessageLinkConfig config;
  config.buffer_depth = 4;
  cell::SimpleMessageServerConfig server;
  server.buffer_points = 1;  // the controller holds fewer points than deflex wants queued
  SimpleMessageBench bench(program, q0, StrategyKind::kOnline, nullptr, config, server);
  bench.force.reading = Vector6::Zero();
  std::map<std::int32_t, JointVector> sent;
  std::int32_t seen = -1;
  for (int k = 0; k < 20000 && seen < 100; ++k) {
    const std::uint64_t before = bench.points;
    ASSERT_NE(bench.tick(), LinkPollResult::kStopped) << bench.link.stop_reason();
    if (bench.points != before) expect_points_are_the_program(bench, *program, sent);
    if (bench.server->last_sequence() == seen) continue;
    // Every point the controller takes is the next one: none skipped, none out of order.
    ASSERT_EQ(bench.server->last_sequence(), seen + 1);
    seen = bench.server->last_sequence();
    EXPECT_EQ(bench.server->last_target(), sent[seen]);
  }
  EXPECT_EQ(seen, 100);
  EXPECT_GT(bench.server->counters().refused_full, 0u);
  EXPECT_EQ(bench.link.protocol_counters().failures, bench.server->counters().refused_full);
  EXPECT_EQ(bench.link.state(), LinkState::kRunning);
}

TEST(SimpleMessageLink, FailureRepliesInARowStopTheMotionWithStopTrajectory) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  ScriptedSimpleMessage s(test::hold_program(test::bench_robot(), q0, 10.0));
  s.joint_position(q0);
  int failures = 0, stops = 0;
  LinkPollResult last = LinkPollResult::kIdle;
  for (int k = 0; k < 200 && last != LinkPollResult::kStopped; ++k) {
    if (k % 25 == 0) s.joint_position(q0);
    last = s.step();
    for (const auto& f : s.sent()) {
      if (f.i32(false, 0) >= 0) {
        ++failures;
        s.to_motion(test::hand_header(false, 11, 3, 2));  // FAILURE, header only (as ABB's server)
      } else {
        EXPECT_EQ(f.i32(false, 0), -4);
        ++stops;
      }
    }
  }
  ASSERT_EQ(last, LinkPollResult::kStopped);
  EXPECT_EQ(failures, 3);
  EXPECT_EQ(s.link.stop_cause(), LinkStopCause::kController);
  EXPECT_NE(std::string(s.link.stop_reason()).find("refused point 0 3 times"), std::string::npos)
      << s.link.stop_reason();
  EXPECT_EQ(s.link.protocol_counters().stops_sent, 1u);
  EXPECT_EQ(s.link.protocol_counters().points_sent, 3u);  // point 0, twice more after a cycle each
  s.step();
  const auto rest = s.sent();
  ASSERT_EQ(rest.size() + static_cast<std::size_t>(stops), 1u);  // and one STOP_TRAJECTORY on the wire
}

TEST(SimpleMessageLink, StopTrajectoryFrameCarriesTheLastTargetNeverANewOne) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  ScriptedSimpleMessage s(test::hold_program(test::bench_robot(), q0, 10.0));
  s.joint_position(q0);
  std::vector<test::HandParsed> frames;
  for (int k = 0; k < 20; ++k) {
    s.step();
    for (auto& f : s.sent()) {
      if (f.i32(false, 0) >= 0) s.to_motion(test::hand_header(false, 11, 3, 1));
      frames.push_back(std::move(f));
    }
  }
  ASSERT_GE(frames.size(), 2u);
  s.link.stop();
  s.step();
  for (auto& f : s.sent()) frames.push_back(std::move(f));
  const test::HandParsed& stop = frames.back();
  EXPECT_EQ(stop.type, 11);
  EXPECT_EQ(stop.comm, 2);
  EXPECT_EQ(stop.i32(false, 0), -4);
  const test::HandParsed& before = frames[frames.size() - 2];
  for (std::size_t j = 1; j <= 10; ++j) EXPECT_EQ(stop.f32(false, j), before.f32(false, j));
  EXPECT_EQ(s.link.state(), LinkState::kStopped);
  EXPECT_EQ(s.link.stop_cause(), LinkStopCause::kRequested);
  EXPECT_EQ(s.step(), LinkPollResult::kIdle);  // and nothing more, ever
  EXPECT_TRUE(s.sent().empty());
}

TEST(SimpleMessageLink, AnEmergencyStopOnTheStatePortStopsTheLink) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  SimpleMessageBench bench(test::hold_program(test::bench_robot(), q0, 100.0), q0);
  ASSERT_TRUE(bench.run_points(20));
  bench.server->emergency_stop(bench.t_s);
  LinkPollResult r = LinkPollResult::kIdle;
  for (int k = 0; k < 100 && r != LinkPollResult::kStopped; ++k) r = bench.tick();
  ASSERT_EQ(r, LinkPollResult::kStopped);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kController);
  EXPECT_NE(std::string(bench.link.stop_reason()).find("emergency stop"), std::string::npos);
  for (int k = 0; k < 10; ++k) bench.tick();
  EXPECT_EQ(bench.server->counters().stops, 1u);  // STOP_TRAJECTORY reached it
}

TEST(SimpleMessageLink, ADroppedStateConnectionStopsTheArmWithStopTrajectory) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(20, 0, 0, 0, 0, 0), 10.0);
  SimpleMessageBench bench(program, q0);
  ASSERT_TRUE(bench.run_points(30));
  bench.state.server().close();  // the state server's connection goes
  LinkPollResult r = LinkPollResult::kIdle;
  for (int k = 0; k < 100 && r != LinkPollResult::kStopped; ++k) r = bench.tick();
  ASSERT_EQ(r, LinkPollResult::kStopped);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kConnection);
  EXPECT_NE(std::string(bench.link.stop_reason()).find("state connection"), std::string::npos);
  for (int k = 0; k < 100; ++k) bench.tick();
  EXPECT_EQ(bench.server->counters().stops, 1u);
  EXPECT_TRUE(bench.server->motion().at_rest());
  EXPECT_EQ(bench.server->motion().queued(), 0u);
}

TEST(SimpleMessageLink, ADroppedMotionConnectionStopsTheLinkAndTheArmRunsOutItsQueue) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(20, 0, 0, 0, 0, 0), 10.0);
  SimpleMessageBench bench(program, q0);
  ASSERT_TRUE(bench.run_points(30));
  const std::uint64_t sent = bench.link.protocol_counters().points_sent;
  bench.motion.server().close();
  LinkPollResult r = LinkPollResult::kIdle;
  for (int k = 0; k < 100 && r != LinkPollResult::kStopped; ++k) r = bench.tick();
  ASSERT_EQ(r, LinkPollResult::kStopped);
  EXPECT_EQ(bench.link.stop_cause(), LinkStopCause::kConnection);
  EXPECT_NE(std::string(bench.link.stop_reason()).find("motion connection"), std::string::npos)
      << bench.link.stop_reason();
  for (int k = 0; k < 300; ++k) bench.tick();
  EXPECT_LE(bench.link.protocol_counters().points_sent, sent + 1);
  EXPECT_TRUE(bench.server->motion().at_rest());  // it ran the points it had, then stopped
  EXPECT_EQ(bench.server->motion().position(), bench.server->last_target());
}

TEST(SimpleMessageLink, ASilentControllerStopsTheLink) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  {  // no JOINT_POSITION for longer than the state timeout
    ScriptedSimpleMessage s(test::hold_program(test::bench_robot(), q0, 10.0));
    s.joint_position(q0);
    LinkPollResult r = LinkPollResult::kIdle;
    for (int k = 0; k < 400 && r != LinkPollResult::kStopped; ++k) {
      r = s.step();
      for (const auto& f : s.sent()) {
        if (f.i32(false, 0) >= 0) s.to_motion(test::hand_header(false, 11, 3, 1));
      }
    }
    ASSERT_EQ(r, LinkPollResult::kStopped);
    EXPECT_EQ(s.link.stop_cause(), LinkStopCause::kSilent);
    EXPECT_NE(std::string(s.link.stop_reason()).find("no JOINT_POSITION"), std::string::npos);
    EXPECT_NEAR(s.t_s, 1.0, 0.01);
  }
  {  // no reply to a point
    ScriptedSimpleMessage s(test::hold_program(test::bench_robot(), q0, 10.0));
    LinkPollResult r = LinkPollResult::kIdle;
    for (int k = 0; k < 400 && r != LinkPollResult::kStopped; ++k) {
      if (k % 25 == 0) s.joint_position(q0);
      r = s.step();
    }
    ASSERT_EQ(r, LinkPollResult::kStopped);
    EXPECT_NE(std::string(s.link.stop_reason()).find("no reply to point 0"), std::string::npos) << s.link.stop_reason();
  }
}

// One bad frame after a clean start: the link must stop, say why (naming the field), count it, and send
// STOP_TRAJECTORY; everything it sent before was within the bound.
struct BadFrameCase {
  const char* name;
  bool to_motion;
  std::function<test::Bytes(bool big)> frame;
  const char* reason;
};

TEST(SimpleMessageLink, EveryKindOfBadFrameStopsTheMotionAndSaysWhy) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  std::vector<float> q0f;
  for (int j = 0; j < 6; ++j) q0f.push_back(static_cast<float>(q0[j]));
  const std::vector<BadFrameCase> cases = {
      {"truncated JOINT_POSITION", false,
       [](bool big) {
         test::HandFrame f{big, {}};
         f.i32(12 + 40).i32(10).i32(1).i32(0);
         for (int k = 0; k < 10; ++k) f.i32(0);
         return f.bytes;
       },
       "JOINT_POSITION truncated (40 data bytes, 44 expected)"},
      {"non-finite joint", false,
       [&](bool big) {
         std::vector<float> q = q0f;
         q[3] = std::numeric_limits<float>::quiet_NaN();
         return test::hand_joint_position(big, q);
       },
       "JOINT_POSITION non-finite"},
      {"joint beyond the limits", false,
       [&](bool big) {
         std::vector<float> q = q0f;
         q[2] = 10.0f;
         return test::hand_joint_position(big, q);
       },
       "joint 3 at 572.958 deg is beyond the robot's limits"},
      {"oversized LENGTH on the state port", false,
       [](bool big) {
         test::HandFrame f{big, {}};
         f.i32(5000).i32(10);
         return f.bytes;
       },
       "state connection: frame LENGTH 5000"},
      {"LENGTH below the header on the motion port", true,
       [](bool big) {
         test::HandFrame f{big, {}};
         f.i32(4).i32(11);
         return f.bytes;
       },
       "motion connection: frame LENGTH 4"},
      {"unknown message type on the state port", false, [](bool big) { return test::hand_header(big, 2017, 1, 0); },
       "message type 2017 is not one the link speaks"},
      {"a request on the state port", false, [&](bool big) { return test::hand_joint_position(big, q0f, 0, 2); },
       "COMM_TYPE 2, TOPIC (1) expected"},
      {"a reply when no point waits", true, [](bool big) { return test::hand_header(big, 11, 3, 1); },
       "no point was waiting"},
      {"a reply of an unknown type", true, [](bool big) { return test::hand_header(big, 1, 3, 1); },
       "message type 1 is not a reply"},
  };
  for (bool big : {false, true}) {
    for (const BadFrameCase& c : cases) {
      SCOPED_TRACE(std::string(c.name) + (big ? " (big-endian)" : " (little-endian)"));
      ScriptedSimpleMessage s(test::hold_program(test::bench_robot(), q0, 10.0), big);
      std::vector<test::HandParsed> frames;
      // A clean start: five points taken, their replies all in (none waiting).
      for (int k = 0; k < 200 && s.link.protocol_counters().points_accepted < 5; ++k) {
        if (k % 25 == 0) s.joint_position(q0);
        s.step();
        for (auto& f : s.sent()) {
          s.to_motion(test::hand_header(big, 11, 3, 1));
          frames.push_back(std::move(f));
        }
      }
      ASSERT_EQ(s.link.protocol_counters().points_accepted, 5u);
      s.step();
      for (auto& f : s.sent()) frames.push_back(std::move(f));
      ASSERT_EQ(frames.size(), 5u);  // the sixth is not due for a cycle
      if (c.to_motion) {
        s.to_motion(c.frame(big));
      } else {
        s.to_state(c.frame(big));
      }
      // The poll that meets the bad frame: it stops the motion, formats the reason, queues the STOP, all
      // without allocating.
      s.t_s += 0.004;
      s.clock.set(s.t_s);
      {
        test::AllocationGuard guard;
        EXPECT_EQ(s.link.poll(0.0), LinkPollResult::kStopped);
        EXPECT_EQ(guard.allocations(), 0u);
      }
      s.step();
      EXPECT_EQ(s.link.state(), LinkState::kStopped);
      EXPECT_EQ(s.link.stop_cause(), LinkStopCause::kProtocol);
      EXPECT_NE(std::string(s.link.stop_reason()).find(c.reason), std::string::npos) << s.link.stop_reason();
      EXPECT_GT(s.link.counters().datagrams, 0u);
      for (auto& f : s.sent()) frames.push_back(std::move(f));
      ASSERT_EQ(frames.size(), 6u);
      EXPECT_EQ(frames.back().i32(big, 0), -4);  // STOP_TRAJECTORY
      for (const auto& f : frames) {
        for (std::size_t j = 0; j < 6; ++j) {
          EXPECT_LE(std::abs(f.f32(big, 1 + j) - q0f[j]), s.compensator.config().max_joint_correction_rad + 1e-6);
        }
      }
      for (int k = 0; k < 50; ++k) EXPECT_NE(s.step(), LinkPollResult::kAnswered);
      EXPECT_TRUE(s.sent().empty());
    }
  }
}

TEST(SimpleMessageLink, RepliesNamingAnotherPointOrWithABadCodeStopTheMotion) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  struct Case {
    std::function<test::Bytes(std::int32_t waiting)> reply;
    const char* reason;
  };
  const std::vector<Case> cases = {
      {[](std::int32_t w) { return test::hand_traj_pt(false, 3, 1, w + 99, {}, 0.0f, 0.1f); },
       "the reply names point 99, but point 0 was waiting"},
      {[](std::int32_t w) { return test::hand_joint_position(false, {}, w + 5, 3, 1); },
       "the reply names point 5, but point 0 was waiting"},
      {[](std::int32_t) { return test::hand_header(false, 11, 3, 0); }, "reply code 0"},
      {[](std::int32_t) { return test::hand_header(false, 11, 2, 1); }, "COMM_TYPE 2, SERVICE_REPLY (3) expected"},
      {[](std::int32_t) {
         test::HandFrame f{false, {}};
         f.i32(12 + 20).i32(11).i32(3).i32(1);
         for (int k = 0; k < 5; ++k) f.i32(0);
         return f.bytes;
       },
       "reply with 20 data bytes (0 or 52 expected)"},
  };
  for (const Case& c : cases) {
    ScriptedSimpleMessage s(test::hold_program(test::bench_robot(), q0, 10.0));
    s.joint_position(q0);
    LinkPollResult r = LinkPollResult::kIdle;
    bool replied = false;
    for (int k = 0; k < 50 && r != LinkPollResult::kStopped; ++k) {
      r = s.step();
      for (const auto& f : s.sent()) {
        if (!replied && f.i32(false, 0) >= 0) {
          s.to_motion(c.reply(f.i32(false, 0)));
          replied = true;
        }
      }
    }
    ASSERT_EQ(r, LinkPollResult::kStopped) << c.reason;
    EXPECT_EQ(s.link.stop_cause(), LinkStopCause::kProtocol);
    EXPECT_NE(std::string(s.link.stop_reason()).find(c.reason), std::string::npos) << s.link.stop_reason();
  }
}

TEST(SimpleMessageLink, AControllerOfTheOtherByteOrderIsCaughtAtItsFirstFrameAndNothingIsSent) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  ScriptedSimpleMessage s(test::hold_program(test::bench_robot(), q0, 10.0), false);
  std::vector<float> q0f;
  for (int j = 0; j < 6; ++j) q0f.push_back(static_cast<float>(q0[j]));
  s.to_state(test::hand_joint_position(true, q0f));  // a big-endian server, a little-endian link
  EXPECT_EQ(s.step(), LinkPollResult::kStopped);
  EXPECT_NE(std::string(s.link.stop_reason()).find("frame LENGTH 939524096"), std::string::npos)
      << s.link.stop_reason();
  EXPECT_TRUE(s.sent().empty());  // no point and no STOP: nothing was ever sent
}

TEST(SimpleMessageLink, BigEndianLinkAndServerConvergeLikeLittleEndianOnes) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  SimpleMessageLinkConfig config;
  config.byte_order = simple_message::ByteOrder::kBig;
  cell::SimpleMessageServerConfig server;
  server.byte_order = simple_message::ByteOrder::kBig;
  SimpleMessageBench bench(test::hold_program(test::bench_robot(), q0, 500.0), q0, StrategyKind::kOnline, nullptr,
                           config, server);
  const Vector3 f_base(0.0, 0.0, -400.0);
  while (bench.points < 1000) {
    bench.force.reading = test::reading_at(bench.robot, bench.server->motion().position(), f_base);
    ASSERT_NE(bench.tick(), LinkPollResult::kStopped) << bench.link.stop_reason();
  }
  const JointVector expected = test::model_correction(bench.robot, q0, f_base);
  EXPECT_LT((bench.link.last_cycle().q_command - (q0 - expected)).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(SimpleMessageLink, PartialWritesNeverCutAPoint) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(5, 0, 0, 0, 0, 5), 10.0);
  // The motion connection's window holds 30 bytes: every 68-byte point goes out in three writes.
  SimpleMessageBench bench(program, q0, StrategyKind::kOnline, nullptr, {}, {}, 30);
  bench.force.reading = Vector6::Zero();
  std::map<std::int32_t, JointVector> sent;
  std::int32_t seen = -1;
  for (int k = 0; k < 5000 && seen < 50; ++k) {
    const std::uint64_t before = bench.points;
    ASSERT_NE(bench.tick(), LinkPollResult::kStopped) << bench.link.stop_reason();
    if (bench.points != before) expect_points_are_the_program(bench, *program, sent);
    if (bench.server->last_sequence() == seen) continue;
    ASSERT_EQ(bench.server->last_sequence(), seen + 1);
    seen = bench.server->last_sequence();
    EXPECT_EQ(bench.server->last_target(), sent[seen]);
  }
  EXPECT_EQ(seen, 50);
  EXPECT_GT(bench.link.protocol_counters().partial_writes, 0u);
  EXPECT_EQ(bench.server->counters().skipped, 0u);
}

// A sensor that measures the LDBB-like force at the arm's true pose, at 250 Hz.
class PoseForce final : public ForceSource {
 public:
  PoseForce(const RobotModel& robot, const ForceModel& field, const ManualClock& clock,
            const cell::SimpleMessageServer& server)
      : robot_(robot), field_(field), clock_(clock), server_(server), ws_(robot) {}
  bool latest(ForceSample& out) noexcept override {
    if (next_s_ > clock_.now_s()) return false;
    const JointVector& q = server_.motion().position();
    forward_kinematics(robot_, ws_, q);
    Wrench w;
    if (!field_.wrench_at_pose(ws_.base_T_tcp, w)) return false;
    out.t_s = next_s_;
    out.wrench_sensor = test::reading_at(robot_, q, w.head<3>());
    out.valid = true;
    next_s_ += 0.004;  // the bench sensor's 250 Hz
    return true;
  }

 private:
  const RobotModel& robot_;
  const ForceModel& field_;
  const ManualClock& clock_;
  const cell::SimpleMessageServer& server_;
  Workspace ws_;
  double next_s_ = 0.0;
};

TEST(SimpleMessageLink, ThePredictiveStrategyCompensatesTheBuffersLag) {
  // A force that turns with the pose (the LDBB's bar from a pivot to the TCP), measured where the arm
  // is; the ideal point is the nominal minus the model's correction for the force at the nominal's own
  // pose. The online strategy corrects with the force the arm felt some 0.3 s earlier (the
  // buffer and the planner); the predictive one leads by it: it must come much closer to the ideal.
  const JointVector q0 = pose_deg(0, 25, 5, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(25, 0, 0, 0, 0, 0), 6.0, 81);
  const RobotModel robot = test::bench_robot();
  Workspace ws(robot);
  forward_kinematics(robot, ws, q0);
  const Vector3 pivot = ws.base_T_tcp.translation() + Vector3(0.0, 0.0, -0.15);
  const LdbbForceModel ldbb(pivot, 600.0, true);
  double error[2] = {0.0, 0.0};
  for (int which = 0; which < 2; ++which) {
    const StrategyKind kind = which == 0 ? StrategyKind::kOnline : StrategyKind::kPredictive;
    // The source needs the bench's clock and server, so the bench gets a forwarder filled in after.
    struct Forward final : public ForceSource {
      ForceSource* inner = nullptr;
      bool latest(ForceSample& out) noexcept override { return inner != nullptr && inner->latest(out); }
    } forward;
    SimpleMessageBench bench(program, q0, kind, &ldbb, {}, {}, 65536, &forward);
    PoseForce source(bench.robot, ldbb, bench.clock, *bench.server);
    forward.inner = &source;
    int counted = 0;
    while (bench.link.state() != LinkState::kFinished) {
      const std::uint64_t before = bench.points;
      ASSERT_NE(bench.tick(), LinkPollResult::kStopped) << bench.link.stop_reason();
      ASSERT_LT(bench.t_s, 30.0);
      if (bench.points == before) continue;
      const LinkCycleRecord& r = bench.link.last_cycle();
      if (r.program_time_s < 1.5 || r.program_time_s > 4.5) continue;  // the middle of the sweep: moving fast
      forward_kinematics(robot, ws, r.q_nominal);
      Wrench w;
      ASSERT_TRUE(ldbb.wrench_at_pose(ws.base_T_tcp, w));
      const JointVector ideal = test::model_correction(robot, r.q_nominal, w.head<3>());
      error[which] += (r.dtheta - ideal).norm();
      ++counted;
    }
    ASSERT_GT(counted, 20);
    error[which] /= counted;
  }
  EXPECT_LT(error[1], 0.5 * error[0]) << "online " << error[0] << " rad, predictive " << error[1] << " rad";
}

TEST(SimpleMessageLink, SteadyStateCycleDoesNotAllocate) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(8, -3, 4, 10, -5, 12), 30.0);
  const LdbbForceModel ldbb(Vector3(1.5, 0.0, 0.5), 400.0, true);
  for (StrategyKind kind : {StrategyKind::kOnline, StrategyKind::kHybrid, StrategyKind::kPredictive}) {
    SimpleMessageBench bench(program, q0, kind, &ldbb);
    bench.force.reading = test::reading_at(bench.robot, q0, Vector3(50, 0, -400));
    ASSERT_TRUE(bench.run_points(20));  // warm: every buffer at its size
    std::size_t allocations = 0;
    std::uint64_t sent = 0;
    for (int k = 0; k < 1000; ++k) {
      bench.t_s += 0.004;
      bench.clock.set(bench.t_s);
      bench.server->tick(bench.t_s);
      bench.clock.set(bench.t_s + 0.0002);
      test::AllocationGuard guard;
      for (int i = 0; i < 4; ++i) {
        const LinkPollResult r = bench.link.poll(0.0);
        if (r == LinkPollResult::kAnswered) ++sent;
        if (r == LinkPollResult::kIdle) break;
      }
      allocations += guard.allocations();
    }
    EXPECT_EQ(allocations, 0u) << to_string(kind);
    EXPECT_GE(sent, 35u) << to_string(kind);  // 4 s of points
    // And stopping (a fault's path) does not allocate either.
    test::AllocationGuard guard;
    bench.link.stop();
    bench.link.poll(0.0);
    EXPECT_EQ(guard.allocations(), 0u);
  }
}

}  // namespace
}  // namespace deflex
