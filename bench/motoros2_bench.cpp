// Loopback round trips of deflex's MotoROS2 real-time link: a controller-side peer answers each command
// with a 2053-byte reply (the command position: the sum of the increments it took), the link (its own
// thread) drains, decodes, runs the strategy and the compensator on a fresh force sample and sends the
// next 620-byte command of increments; the peer times from its reply to that command. Beside it the
// floor: the same reply bounced by a plain UDP echo (no decoding, no compute), so the link's own cost
// is the difference. Reports p50/p99/max over 100,000 cycles and the heap allocations counted in
// steady state.
//   build/bench/motoros2_bench
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <new>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/motoros2/motoros2_rt_link.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/transport/udp_transport.hpp"

#include "counting_new.hpp"
#include "link_round_trips.hpp"

namespace deflex {
namespace {

namespace rt = motoros2_rt;

// The controller's side: `link` true waits for the link's command 0 and answers every command with
// its reply (the command position moved by its increments); false bounces replies off an echo at `to`.
RoundTrips exchange(UdpTransport& controller, DatagramAddress to, std::size_t cycles, bool link) {
  std::vector<unsigned char> out(rt::kReplyBytes), in(4096);
  DatagramAddress from;
  rt::Reply reply;
  for (int j = 0; j < 6; ++j) reply.command_joints[0][static_cast<std::size_t>(j)] = start_joints()[j];
  rt::Command command;
  const auto take = [&](double timeout_s) {
    if (!controller.wait_readable(timeout_s)) return false;
    const long n = controller.receive(in.data(), in.size(), from);
    if (!link) return n > 0;
    if (n < 0 || rt::decode(in.data(), static_cast<std::size_t>(n), command) != rt::DecodeStatus::kOk) return false;
    to = from;
    reply.sequence_echo = command.sequence;
    for (std::size_t j = 0; j < 6; ++j) reply.command_joints[0][j] += command.delta[0][j];
    reply.feedback_joints = reply.command_joints;
    return true;
  };
  if (link) {
    while (!take(1.0)) {
    }
  }
  RoundTrips r;
  r.us.resize(cycles);
  const auto one = [&](double& us) {
    const std::size_t n = rt::encode(reply, out.data(), out.size());
    const auto t0 = std::chrono::steady_clock::now();
    controller.send_to(out.data(), n, to);
    if (!take(1.0)) ++r.lost;
    us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  };
  double warm = 0.0;
  for (int i = 0; i < 200; ++i) one(warm);
  r.lost = 0;
  g_allocations = 0;
  g_counting = true;
  for (std::size_t i = 0; i < cycles; ++i) one(r.us[i]);
  g_counting = false;
  return r;
}

// The floor: the same replies bounced by a plain UDP echo.
void BM_Motoros2UdpLoopbackFloor(benchmark::State& state) {
  UdpTransport echo("127.0.0.1", 0);
  std::atomic<bool> stop{false};
  std::thread server([&] {
    std::vector<unsigned char> buf(4096);
    while (!stop.load()) {
      if (!echo.wait_readable(0.05)) continue;
      DatagramAddress from;
      const long n = echo.receive(buf.data(), buf.size(), from);
      if (n > 0) echo.send_to(buf.data(), static_cast<std::size_t>(n), from);
    }
  });
  for (auto _ : state) {
    UdpTransport controller("127.0.0.1", 0);
    RoundTrips r = exchange(controller, echo.local_address(), static_cast<std::size_t>(state.range(0)), false);
    report(state, r);
  }
  stop = true;
  server.join();
}
BENCHMARK(BM_Motoros2UdpLoopbackFloor)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_Motoros2LinkRoundTrip(benchmark::State& state) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 6;
  OnlineConfig online;
  online.period_s = 0.004;
  OnlineCompensator comp(robot, sensor, online);
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  FreshSampleForce force;
  UdpTransport transport("127.0.0.1", 0);
  UdpTransport controller("127.0.0.1", 0);
  SteadyClock clock;
  // Held at its start for longer than the cycles take.
  const auto program = std::make_shared<const JointTrajectory>(
      std::vector<double>{0.0, 2000.0}, std::vector<JointVector>{start_joints(), start_joints()}, robot, "hold");
  Motoros2RtLinkConfig config;
  config.controller = controller.local_address();
  config.stop.stop_silence_s = 30.0;
  config.resend_after_s = 1.0;  // the peer answers at once; a resend would be counted as lost
  Motoros2RtLink link(comp, strategy, program, transport, clock, config);
  link.read_force_from(&force);
  std::atomic<bool> stop{false};
  std::thread client([&] {
    while (!stop.load()) (void)link.poll(0.05);
  });
  for (auto _ : state) {
    RoundTrips r = exchange(controller, {}, static_cast<std::size_t>(state.range(0)), true);
    report(state, r);
    state.counters["commands"] = static_cast<double>(link.counters().replies);
    state.counters["resent"] = static_cast<double>(link.resent());
  }
  stop = true;
  client.join();
}
BENCHMARK(BM_Motoros2LinkRoundTrip)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace deflex

BENCHMARK_MAIN();
