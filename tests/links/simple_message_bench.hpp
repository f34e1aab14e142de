// A deterministic bench for deflex's simple message link: the simulated cell's RAPID streaming server
// (a small buffer, SUCCESS/FAILURE replies, each point a joint move with a zone, JOINT_POSITION every
// 0.1 s) talks to the real link class over two in-memory TCP-like connections, on a clock the test
// advances in 4 ms servo ticks. A scripted controller (the test writes every frame by hand) stands in
// where a test needs a controller that misbehaves. Forces as in link_harness.hpp: a constant raw
// reading, the expected correction computed independently with a finite-difference Jacobian.
#pragma once

#include <memory>

#include "deflex/cell/simple_message_server.hpp"
#include "deflex/simple_message/simple_message_link.hpp"
#include "deflex/transport/memory_stream.hpp"
#include "links/link_harness.hpp"
#include "support/simple_message_frames.hpp"

namespace deflex::test {

inline OnlineConfig bench_online_100ms() {
  OnlineConfig c = bench_online(0.1);
  c.watchdog_s = 0.25;  // a 100 ms cycle drains the sensor once a cycle
  return c;
}

/// The RAPID streaming server stand-in + deflex's simple message link.
struct SimpleMessageBench {
  RobotModel robot = bench_robot();
  ManualClock clock;
  MemoryStreamPair motion;
  MemoryStreamPair state{clock, 0.0002};
  cell::SimpleMessageServerConfig server_config;
  OnlineCompensator compensator;
  OnlineStrategy strategy;
  ConstantForce force;
  std::shared_ptr<const JointTrajectory> program;
  SimpleMessageLink link;
  std::unique_ptr<cell::SimpleMessageServer> server;
  double t_s = 0.0;
  std::uint64_t points = 0;  ///< kAnswered polls so far

  SimpleMessageBench(std::shared_ptr<const JointTrajectory> p, const JointVector& arm_start,
                     StrategyKind kind = StrategyKind::kOnline, const ForceModel* model = nullptr,
                     SimpleMessageLinkConfig config = {}, cell::SimpleMessageServerConfig server_cfg = {},
                     std::size_t motion_window_bytes = 65536, ForceSource* force_source = nullptr)
      : motion(clock, 0.0002, motion_window_bytes),
        server_config(server_cfg),
        compensator(robot, bench_sensor(), bench_online_100ms()),
        strategy(robot, kind, model),
        program(std::move(p)),
        link(compensator, strategy, program, motion.client(), state.client(), clock, config),
        server(std::make_unique<cell::SimpleMessageServer>(server_config, robot, arm_start, motion.server(),
                                                           state.server())) {
    link.read_force_from(force_source != nullptr ? force_source : &force);
  }

  /// One 4 ms servo tick of the controller, then deflex polls until it has nothing to do. Returns the
  /// last poll result that was not kIdle (kIdle when all were).
  LinkPollResult tick() {
    t_s += 0.004;
    clock.set(t_s);
    server->tick(t_s);
    clock.set(t_s + 0.0002);
    LinkPollResult last = LinkPollResult::kIdle;
    for (int guard = 0; guard < 100; ++guard) {
      const LinkPollResult r = link.poll(0.0);
      if (r == LinkPollResult::kIdle) break;
      last = r;
      if (r == LinkPollResult::kAnswered) ++points;
      if (r == LinkPollResult::kStopped || r == LinkPollResult::kRefused) break;
    }
    return last;
  }
  /// Ticks until `n` more points were sent (or the link stopped); false when it stopped first.
  bool run_points(std::uint64_t n, int max_ticks = 10'000'000) {
    const std::uint64_t goal = points + n;
    for (int k = 0; k < max_ticks && points < goal; ++k) {
      const LinkPollResult r = tick();
      if (r == LinkPollResult::kStopped || r == LinkPollResult::kRefused) return false;
    }
    return points >= goal;
  }
};

/// deflex's link against a controller the test scripts by hand: the test reads what the link sent
/// (hand_split) and writes the frames it wants the link to see.
struct ScriptedSimpleMessage {
  RobotModel robot = bench_robot();
  ManualClock clock;
  MemoryStreamPair motion{clock, 0.0002};
  MemoryStreamPair state{clock, 0.0002};
  OnlineCompensator compensator;
  OnlineStrategy strategy;
  ConstantForce force;
  std::shared_ptr<const JointTrajectory> program;
  SimpleMessageLink link;
  bool big;
  double t_s = 0.0;
  Bytes from_link;

  ScriptedSimpleMessage(std::shared_ptr<const JointTrajectory> p, bool big_endian = false,
                        SimpleMessageLinkConfig config = {})
      : compensator(robot, bench_sensor(), bench_online_100ms()),
        strategy(robot, StrategyKind::kOnline, nullptr),
        program(std::move(p)),
        link(compensator, strategy, program, motion.client(), state.client(), clock,
             [&] {
               config.byte_order = big_endian ? simple_message::ByteOrder::kBig : simple_message::ByteOrder::kLittle;
               return config;
             }()),
        big(big_endian) {
    link.read_force_from(&force);
  }

  void to_state(const Bytes& b) { state.server().write(b.data(), b.size()); }
  void to_motion(const Bytes& b) { motion.server().write(b.data(), b.size()); }
  void joint_position(const JointVector& q) {
    std::vector<float> f;
    for (int j = 0; j < q.size(); ++j) f.push_back(static_cast<float>(q[j]));
    to_state(hand_joint_position(big, f));
  }
  /// Advances the clock by dt, lets the link poll until idle; returns the last non-idle result.
  LinkPollResult step(double dt = 0.004) {
    t_s += dt;
    clock.set(t_s);
    LinkPollResult last = LinkPollResult::kIdle;
    for (int guard = 0; guard < 100; ++guard) {
      const LinkPollResult r = link.poll(0.0);
      if (r == LinkPollResult::kIdle) break;
      last = r;
      if (r == LinkPollResult::kStopped || r == LinkPollResult::kRefused) break;
    }
    // What the link wrote reaches the scripted controller after the latency.
    clock.set(t_s + 0.0003);
    unsigned char buf[4096];
    for (long n = motion.server().read(buf, sizeof(buf)); n > 0; n = motion.server().read(buf, sizeof(buf))) {
      from_link.insert(from_link.end(), buf, buf + n);
    }
    return last;
  }
  std::vector<HandParsed> sent() { return hand_split(big, from_link); }
};

}  // namespace deflex::test
