// Loopback round trips of deflex's FANUC Stream Motion link: a controller-side peer sends a status
// (protocol 1, 132 bytes, the ready bit set, numbered in turn, stamped 8 ms apart), the link (its own
// thread) drains, decodes, runs the strategy, the compensator and the smoother on a fresh force sample
// and answers with a 64-byte command; the peer receives it. Beside it the floor: the same status
// bounced by a plain UDP echo (no decoding, no compute), so the link's own cost is the difference.
// Reports p50/p99/max over 100,000 cycles and the heap allocations counted in steady state.
//   build/bench/fanuc_bench
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <new>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/fanuc/fanuc_j519_link.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/transport/udp_transport.hpp"

#include "counting_new.hpp"
#include "link_round_trips.hpp"

namespace deflex {
namespace {

namespace j519 = fanuc_j519;

// The controller's side: waits for the start packet (when `wait_start`), then sends `cycles` statuses
// to `to` (or to the start packet's sender) and times each answer.
RoundTrips exchange(UdpTransport& controller, DatagramAddress to, std::size_t cycles, bool wait_start) {
  std::vector<unsigned char> out(j519::kMaxDatagramBytes), in(2048);
  DatagramAddress from;
  if (wait_start) {
    while (!controller.wait_readable(1.0) || controller.receive(in.data(), in.size(), from) != 8) {
    }
    to = from;
  }
  j519::Status s;
  s.status_bits = j519::kStatusReady | j519::kStatusSysReady;
  for (int j = 0; j < 6; ++j)
    s.joints_deg[static_cast<std::size_t>(j)] = static_cast<float>(rad_to_deg(start_joints()[j]));
  RoundTrips r;
  r.us.resize(cycles);
  const auto one = [&](double& us, double timeout_s) {
    ++s.sequence;
    s.time_stamp_ms += 8;
    const std::size_t n = j519::encode(1, s, out.data(), out.size());
    const auto t0 = std::chrono::steady_clock::now();
    controller.send_to(out.data(), n, to);
    if (!controller.wait_readable(timeout_s) || controller.receive(in.data(), in.size(), from) < 0) ++r.lost;
    us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  };
  double warm = 0.0;
  one(warm, 0.02);  // the first status only times the interval: no answer
  for (int i = 0; i < 200; ++i) one(warm, 1.0);
  r.lost = 0;
  g_allocations = 0;
  g_counting = true;
  for (std::size_t i = 0; i < cycles; ++i) one(r.us[i], 1.0);
  g_counting = false;
  return r;
}

// The floor: the same statuses bounced by a plain UDP echo.
void BM_FanucUdpLoopbackFloor(benchmark::State& state) {
  UdpTransport echo("127.0.0.1", 0);
  std::atomic<bool> stop{false};
  std::thread server([&] {
    std::vector<unsigned char> buf(2048);
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
BENCHMARK(BM_FanucUdpLoopbackFloor)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_FanucLinkRoundTrip(benchmark::State& state) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 6;
  OnlineConfig online;
  online.period_s = 0.008;
  OnlineCompensator comp(robot, sensor, online);
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  FreshSampleForce force;
  UdpTransport transport("127.0.0.1", 0);
  UdpTransport controller("127.0.0.1", 0);
  SteadyClock clock;
  // Held at its start for longer than the cycles take.
  const auto program = std::make_shared<const JointTrajectory>(
      std::vector<double>{0.0, 2000.0}, std::vector<JointVector>{start_joints(), start_joints()}, robot, "hold");
  FanucJ519LinkConfig config;
  config.controller = controller.local_address();
  config.stop.stop_silence_s = 30.0;
  FanucJ519Link link(comp, strategy, program, transport, clock, config);
  link.read_force_from(&force);
  std::atomic<bool> stop{false};
  std::thread client([&] {
    while (!stop.load()) (void)link.poll(0.05);
  });
  for (auto _ : state) {
    RoundTrips r = exchange(controller, {}, static_cast<std::size_t>(state.range(0)), true);
    report(state, r);
    state.counters["replies"] = static_cast<double>(link.counters().replies);
    state.counters["smoother_taps"] = static_cast<double>(link.smoother().taps());
  }
  stop = true;
  client.join();
}
BENCHMARK(BM_FanucLinkRoundTrip)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace deflex

BENCHMARK_MAIN();
