// Loopback round trips of deflex's ABB EGM links: a controller-side sender encodes an EgmRobot
// message, the link (its own thread) drains, decodes, runs the strategy and the compensator on a
// fresh force sample and answers; the sender receives the answer. Beside them, the floor: the same
// exchange with a plain UDP echo (no decode, no compute), so the link's own cost is the difference.
// Reports p50/p99/max over 100,000 cycles and the heap allocations counted in steady state. And each
// of the codec's four messages alone (encode and decode, robot's and sensor's side), as a cycle of
// the case study pays them: BM_EgmCodec/0..3.
//   build-*/bench/egm_bench
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <new>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/egm/egm_joint_link.hpp"
#include "deflex/egm/egm_path_link.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/transport/udp_transport.hpp"
#include "deflex/wire/egm_codec.hpp"

#include "counting_new.hpp"
#include "link_round_trips.hpp"

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

// Sends `cycles` EgmRobot messages from a fresh socket to `to` and times each answer.
RoundTrips exchange(const DatagramAddress& to, std::size_t cycles, const JointVector& q_deg) {
  UdpTransport controller("127.0.0.1", 0);
  EgmCodec codec(6);
  EgmRobotMessage msg;
  msg.feedback_joints_deg = msg.planned_joints_deg = q_deg;
  msg.has_planned = true;
  std::vector<unsigned char> out(1024), in(2048);
  RoundTrips r;
  r.us.resize(cycles);
  std::uint32_t seq = 0;
  const auto one = [&](double& us) {
    msg.seqno = ++seq;
    msg.tm_ms = seq * 4;
    const std::size_t n = codec.encode_robot(msg, out.data(), out.size());
    const auto t0 = std::chrono::steady_clock::now();
    controller.send_to(out.data(), n, to);
    DatagramAddress from;
    if (!controller.wait_readable(1.0) || controller.receive(in.data(), in.size(), from) < 0) ++r.lost;
    us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  };
  double warm = 0.0;
  for (int i = 0; i < 200; ++i) one(warm);  // sockets, caches, protobuf messages
  g_allocations = 0;
  g_counting = true;
  for (std::size_t i = 0; i < cycles; ++i) one(r.us[i]);
  g_counting = false;
  return r;
}

JointVector start_deg() {
  JointVector q(6);
  q << 0, 20, 10, 0, 60, 0;
  return q;
}

// The floor: the same datagrams bounced by a plain UDP echo.
void BM_UdpLoopbackFloor(benchmark::State& state) {
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
    RoundTrips r = exchange(echo.local_address(), static_cast<std::size_t>(state.range(0)), start_deg());
    report(state, r);
  }
  stop = true;
  server.join();
}
BENCHMARK(BM_UdpLoopbackFloor)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

template <class Link>
void run_link(benchmark::State& state, Link& link, UdpTransport& transport) {
  std::atomic<bool> stop{false};
  std::thread server([&] {
    while (!stop.load()) (void)link.poll(0.05);
  });
  for (auto _ : state) {
    RoundTrips r = exchange(transport.local_address(), static_cast<std::size_t>(state.range(0)), start_deg());
    report(state, r);
    state.counters["replies"] = static_cast<double>(link.counters().replies);
  }
  stop = true;
  server.join();
}

void BM_EgmJointLinkRoundTrip(benchmark::State& state) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 6;
  OnlineCompensator comp(robot, sensor, OnlineConfig{});
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  const JointVector q = start_deg() * (kPi / 180.0);
  auto program = std::make_shared<const JointTrajectory>(std::vector<double>{0.0, 1e6}, std::vector<JointVector>{q, q},
                                                         robot, "hold");
  ConstantForce force;
  UdpTransport transport("127.0.0.1", 0);
  SteadyClock clock;
  EgmJointLink link(comp, strategy, program, transport, clock);
  link.read_force_from(&force);
  run_link(state, link, transport);
}
BENCHMARK(BM_EgmJointLinkRoundTrip)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_EgmPathLinkRoundTrip(benchmark::State& state) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 6;
  OnlineCompensator comp(robot, sensor, OnlineConfig{});
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  ConstantForce force;
  UdpTransport transport("127.0.0.1", 0);
  SteadyClock clock;
  EgmPathLink link(comp, strategy, transport, clock);
  link.read_force_from(&force);
  run_link(state, link, transport);
}
BENCHMARK(BM_EgmPathLinkRoundTrip)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

// One EGM message of a 6-joint cycle coded alone: 0 the controller encodes EgmRobot, 1 deflex
// decodes it, 2 deflex encodes its EgmSensor answer, 3 the controller decodes that.
void BM_EgmCodec(benchmark::State& state) {
  EgmCodec codec(6);
  EgmRobotMessage robot;
  robot.feedback_joints_deg = JointVector::LinSpaced(6, -12.5, 47.25);
  robot.planned_joints_deg = JointVector::LinSpaced(6, -12.0, 47.0);
  robot.has_planned = true;
  robot.motor_state = 1;
  robot.mci_state = 3;
  robot.rapid_exec_state = 2;
  EgmSensorMessage sensor;
  sensor.planned_joints_deg = JointVector::LinSpaced(6, -11.9, 46.9);
  sensor.speed_ref_joints_deg_s = JointVector::Zero(6);
  unsigned char robot_bytes[512], sensor_bytes[512];
  const std::size_t robot_n = codec.encode_robot(robot, robot_bytes, sizeof(robot_bytes));
  const std::size_t sensor_n = codec.encode_sensor(sensor, sensor_bytes, sizeof(sensor_bytes));
  EgmRobotMessage robot_back;
  EgmSensorMessage sensor_back;
  unsigned char out[512];
  std::uint32_t seq = 0;
  for (auto _ : state) {
    switch (state.range(0)) {
      case 0:
        robot.seqno = ++seq;
        benchmark::DoNotOptimize(codec.encode_robot(robot, out, sizeof(out)));
        break;
      case 1:
        benchmark::DoNotOptimize(codec.decode_robot(robot_bytes, robot_n, robot_back));
        break;
      case 2:
        sensor.seqno = ++seq;
        benchmark::DoNotOptimize(codec.encode_sensor(sensor, out, sizeof(out)));
        break;
      default:
        benchmark::DoNotOptimize(codec.decode_sensor(sensor_bytes, sensor_n, sensor_back));
        break;
    }
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_EgmCodec)->DenseRange(0, 3);

}  // namespace
}  // namespace deflex

BENCHMARK_MAIN();
