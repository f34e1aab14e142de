// Loopback EGM round trip: a controller-side peer sends an EgmRobot message, the sensor endpoint (its
// own thread, callback style) drains, decodes, runs the compensator on a fresh force sample and
// replies; the peer receives the EgmSensor reply. Reports p50/p99/max over 100,000 cycles and the
// heap allocations counted in steady state (both threads).
//   build-*/bench/egm_bench
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <new>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/egm/egm_robot_peer.hpp"
#include "deflex/egm/egm_sensor_endpoint.hpp"
#include "deflex/model/robot_io.hpp"

// GCC sees the replacement operator new (malloc) and delete (free) of this file inlined into the same
// translation unit and calls them mismatched; they are the standard replacement pair.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<std::size_t> g_allocations{0};
}  // namespace
void* operator new(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
  if (void* p = std::malloc(size == 0 ? 1 : size)) {
    return p;
  }
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace deflex {
namespace {

// A force source with a new sample every cycle, like a DAQ faster than the EGM cycle.
class ConstantForce final : public ForceSource {
 public:
  bool latest(ForceSample& out) noexcept override {
    served_ = !served_;
    if (!served_) {
      return false;
    }
    out.t_s += 0.001;
    out.wrench_sensor << 50.0, -120.0, -400.0, 2.0, 1.0, -0.5;
    return true;
  }

 private:
  bool served_ = false;
};

void BM_EgmLoopbackRoundTrip(benchmark::State& state) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 6;
  OnlineCompensator comp(robot, sensor, OnlineConfig{});
  EgmEndpointConfig ec;
  ec.port = 0;
  EgmSensorEndpoint endpoint(comp, ec);
  ConstantForce force;
  endpoint.set_force_source(&force);
  std::atomic<bool> stop{false};
  std::thread server([&] { endpoint.run(stop, nullptr, 0.05); });

  EgmRobotPeer controller("127.0.0.1", endpoint.port());
  EgmRobotMessage msg;
  msg.feedback_joints_deg = JointVector::Zero(6);
  msg.feedback_joints_deg << 0, 20, 10, 0, 60, 0;
  msg.planned_joints_deg = msg.feedback_joints_deg;
  EgmSensorMessage reply;
  reply.planned_joints_deg = JointVector::Zero(6);
  const std::size_t cycles = static_cast<std::size_t>(state.range(0));
  std::vector<double> rtt_us(cycles);
  std::uint32_t seq = 0;
  // Warm-up (sockets, caches, protobuf messages).
  for (int i = 0; i < 200; ++i) {
    msg.seqno = ++seq;
    controller.send(msg);
    controller.receive(reply, 1.0);
  }
  std::size_t lost = 0;
  for (auto _ : state) {
    g_allocations = 0;
    g_counting = true;
    for (std::size_t i = 0; i < cycles; ++i) {
      msg.seqno = ++seq;
      msg.tm_ms = seq * 4;
      const auto t0 = std::chrono::steady_clock::now();
      controller.send(msg);
      if (!controller.receive(reply, 1.0)) {
        ++lost;
      }
      rtt_us[i] = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    }
    g_counting = false;
  }
  stop = true;
  server.join();
  std::sort(rtt_us.begin(), rtt_us.end());
  const auto pct = [&](double p) { return rtt_us[static_cast<std::size_t>(p * static_cast<double>(cycles - 1))]; };
  state.counters["cycles"] = static_cast<double>(cycles);
  state.counters["p50_us"] = pct(0.50);
  state.counters["p99_us"] = pct(0.99);
  state.counters["max_us"] = rtt_us.back();
  state.counters["lost"] = static_cast<double>(lost);
  state.counters["allocations"] = static_cast<double>(g_allocations.load());
  state.counters["replies"] = static_cast<double>(endpoint.counters().replies);
}
BENCHMARK(BM_EgmLoopbackRoundTrip)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace deflex

BENCHMARK_MAIN();
