// Loopback round trips of deflex's KUKA RSI link: a controller-side sender encodes a <Rob> document (RIst,
// RSol, AIPos, ASPos, Delay, IPOC, 4 decimals, as a KR C4 sends it), the link (its own thread) drains,
// scans the XML, runs the strategy and the compensator on a fresh force sample and answers with a
// <Sen>; the sender receives the answer. Beside it the floor: the same datagrams bounced by a plain UDP
// echo (no parsing, no compute), so the link's own cost is the difference. Reports p50/p99/max over
// 100,000 cycles and the heap allocations counted in steady state; and the document scan and answer
// alone, without sockets.
//   build/bench/rsi_bench
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <new>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/rsi/rsi_link.hpp"
#include "deflex/transport/udp_transport.hpp"

#include "counting_new.hpp"

namespace deflex {
namespace {

// A force source with a new sample every cycle, like a DAQ faster than the RSI cycle.
class ConstantForce final : public ForceSource {
 public:
  bool latest(ForceSample& out) noexcept override {
    served_ = !served_;
    if (!served_) return false;
    out.t_s += 0.001;
    out.wrench_sensor << 50.0, -120.0, -400.0, 2.0, 1.0, -0.5;
    return true;
  }

 private:
  bool served_ = false;
};

RsiRobotMessage robot_message() {
  RsiRobotMessage m;
  m.actual_deg.resize(6);
  m.actual_deg << 0.1234, 20.5678, 10.9012, -0.3456, 60.7890, 0.1234;
  m.setpoint_deg = m.actual_deg;
  m.has_setpoint = true;
  m.rist = {1949.8861, 0.0, 895.4281, 0.0, 90.0, 0.0};
  m.rsol = m.rist;
  m.has_rist = m.has_rsol = true;
  return m;
}

struct RoundTrips {
  std::vector<double> us;
  std::size_t lost = 0;
  std::size_t bytes = 0;
};

// Sends `cycles` <Rob> documents from a fresh socket to `to` and times each answer.
RoundTrips exchange(const DatagramAddress& to, std::size_t cycles) {
  UdpTransport controller("127.0.0.1", 0);
  RsiRobotMessage msg = robot_message();
  std::vector<unsigned char> out(kRsiMaxEncodedBytes), in(4096);
  RoundTrips r;
  r.us.resize(cycles);
  std::uint64_t ipoc = 4208163628ULL;
  const auto one = [&](double& us) {
    msg.ipoc = (ipoc += 4);
    const std::size_t n = encode_rsi_robot(msg, 4, out.data(), out.size());
    r.bytes = n;
    const auto t0 = std::chrono::steady_clock::now();
    controller.send_to(out.data(), n, to);
    DatagramAddress from;
    if (!controller.wait_readable(1.0) || controller.receive(in.data(), in.size(), from) < 0) ++r.lost;
    us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  };
  double warm = 0.0;
  for (int i = 0; i < 200; ++i) one(warm);  // sockets, caches
  g_allocations = 0;
  g_counting = true;
  for (std::size_t i = 0; i < cycles; ++i) one(r.us[i]);
  g_counting = false;
  return r;
}

void report(benchmark::State& state, RoundTrips& r) {
  std::sort(r.us.begin(), r.us.end());
  const auto pct = [&](double p) { return r.us[static_cast<std::size_t>(p * static_cast<double>(r.us.size() - 1))]; };
  state.counters["cycles"] = static_cast<double>(r.us.size());
  state.counters["p50_us"] = pct(0.50);
  state.counters["p99_us"] = pct(0.99);
  state.counters["max_us"] = r.us.back();
  state.counters["lost"] = static_cast<double>(r.lost);
  state.counters["allocations"] = static_cast<double>(g_allocations.load());
  state.counters["rob_bytes"] = static_cast<double>(r.bytes);
}

// The floor: the same datagrams bounced by a plain UDP echo.
void BM_RsiUdpLoopbackFloor(benchmark::State& state) {
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
    RoundTrips r = exchange(echo.local_address(), static_cast<std::size_t>(state.range(0)));
    report(state, r);
  }
  stop = true;
  server.join();
}
BENCHMARK(BM_RsiUdpLoopbackFloor)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_RsiLinkRoundTrip(benchmark::State& state) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 6;
  OnlineCompensator comp(robot, sensor, OnlineConfig{});
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  ConstantForce force;
  UdpTransport transport("127.0.0.1", 0);
  SteadyClock clock;
  RsiLink link(comp, strategy, transport, clock);
  link.read_force_from(&force);
  std::atomic<bool> stop{false};
  std::thread server([&] {
    while (!stop.load()) (void)link.poll(0.05);
  });
  for (auto _ : state) {
    RoundTrips r = exchange(transport.local_address(), static_cast<std::size_t>(state.range(0)));
    report(state, r);
    state.counters["replies"] = static_cast<double>(link.counters().replies);
    state.counters["rejected"] = static_cast<double>(link.counters().rejected());
  }
  stop = true;
  server.join();
}
BENCHMARK(BM_RsiLinkRoundTrip)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

// The document work alone: scan a <Rob>, write the <Sen>.
void BM_RsiScanAndAnswer(benchmark::State& state) {
  RsiRobotMessage msg = robot_message();
  msg.ipoc = 4208163628ULL;
  std::vector<unsigned char> doc(kRsiMaxEncodedBytes), out(kRsiMaxEncodedBytes);
  const std::size_t n = encode_rsi_robot(msg, 4, doc.data(), doc.size());
  RsiRobotMessage in = msg;
  RsiSensorMessage answer;
  answer.correction_deg = JointVector::Constant(6, -0.0123456);
  g_allocations = 0;
  g_counting = true;
  for (auto _ : state) {
    benchmark::DoNotOptimize(decode_rsi_robot(doc.data(), n, 6, in));
    answer.ipoc = in.ipoc;
    benchmark::DoNotOptimize(encode_rsi_sensor("ImFree", answer, out.data(), out.size()));
  }
  g_counting = false;
  state.counters["allocations"] = static_cast<double>(g_allocations.load());
  state.counters["rob_bytes"] = static_cast<double>(n);
}
BENCHMARK(BM_RsiScanAndAnswer);

}  // namespace
}  // namespace deflex

BENCHMARK_MAIN();
