// The ROS-Industrial simple message link's costs: encoding a JOINT_TRAJ_PT and parsing a JOINT_POSITION
// frame; one point cycle of the link (strategy, compensator, final check, encode, write) against the
// simulated RAPID server on the in-memory streams; and the loopback TCP round trip of a point (the link
// sends it, the server takes it and replies SUCCESS, the link reads the reply), single-threaded. Reports
// medians (Google Benchmark) or p50/p99/max over 10,000 points, with heap allocations counted.
//   build-*/bench/simple_message_bench
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/cell/simple_message_server.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/simple_message/simple_message_link.hpp"
#include "deflex/transport/memory_stream.hpp"
#include "deflex/transport/tcp_stream.hpp"

#include "counting_new.hpp"

namespace deflex {
namespace {

namespace sm = simple_message;

class ConstantForce final : public ForceSource {
 public:
  bool latest(ForceSample& out) noexcept override {
    served_ = !served_;
    if (!served_) return false;
    out.t_s += 0.001;
    out.wrench_sensor << 50.0, -120.0, -400.0, 2.0, 1.0, -0.5;
    out.valid = true;
    return true;
  }

 private:
  bool served_ = false;
};

JointVector start_pose() {
  JointVector q(6);
  q << 0.0, 0.35, 0.17, 0.0, 1.05, 0.0;
  return q;
}

void BM_EncodeJointTrajPt(benchmark::State& state) {
  sm::JointTrajPt p;
  p.sequence = 7;
  for (std::size_t j = 0; j < 6; ++j) p.joints_rad[j] = 0.1f * static_cast<float>(j);
  p.duration_s = 0.1f;
  unsigned char out[68];
  for (auto _ : state) {
    benchmark::DoNotOptimize(sm::encode(sm::ByteOrder::kBig, {sm::kJointTrajPt, sm::kServiceRequest, 0}, p, out, 68));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_EncodeJointTrajPt);

void BM_ParseJointPosition(benchmark::State& state) {
  sm::JointPosition jp;
  for (std::size_t j = 0; j < 6; ++j) jp.joints_rad[j] = 0.2f * static_cast<float>(j);
  unsigned char frame[60];
  const std::size_t n = sm::encode(sm::ByteOrder::kLittle, {sm::kJointPosition, sm::kTopic, 0}, jp, frame, 60);
  sm::FrameReader reader(sm::ByteOrder::kLittle);
  sm::JointPosition out;
  for (auto _ : state) {
    std::copy_n(frame, n, reader.space());
    reader.commit(n);
    sm::FrameView v;
    reader.next(v);
    benchmark::DoNotOptimize(sm::decode(sm::ByteOrder::kLittle, v.data, v.data_bytes, out));
  }
}
BENCHMARK(BM_ParseJointPosition);

struct Spread {
  double p50 = 0, p99 = 0, max = 0;
};
Spread spread(std::vector<double> us) {
  std::sort(us.begin(), us.end());
  if (us.empty()) return {};
  return {us[us.size() / 2], us[us.size() * 99 / 100], us.back()};
}

// The link's point cycle on the in-memory streams, timed around the poll that sends a point.
void BM_LinkPointCycleInMemory(benchmark::State& state) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 6;
  OnlineConfig oc;
  oc.period_s = 0.1;
  oc.watchdog_s = 0.25;
  for (auto _ : state) {
    ManualClock clock;
    MemoryStreamPair motion(clock, 0.0002), state_pair(clock, 0.0002);
    OnlineCompensator comp(robot, sensor, oc);
    OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
    ConstantForce force;
    auto program = std::make_shared<const JointTrajectory>(std::vector<double>{0.0, 2000.0},
                                                           std::vector<JointVector>{start_pose(), start_pose()}, robot);
    SimpleMessageLink link(comp, strategy, program, motion.client(), state_pair.client(), clock);
    link.read_force_from(&force);
    cell::SimpleMessageServer server({}, robot, start_pose(), motion.server(), state_pair.server());
    std::vector<double> us;
    us.reserve(10000);
    std::size_t allocations = 0;
    double t = 0.0;
    while (us.size() < 10000) {
      t += 0.004;
      clock.set(t);
      server.tick(t);
      clock.set(t + 0.0002);
      g_allocations = 0;
      g_counting = us.size() > 100;
      const auto t0 = std::chrono::steady_clock::now();
      const LinkPollResult r = link.poll(0.0);
      const auto t1 = std::chrono::steady_clock::now();
      g_counting = false;
      allocations += g_allocations.load();
      if (r == LinkPollResult::kAnswered) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    }
    const Spread s = spread(us);
    state.counters["p50_us"] = s.p50;
    state.counters["p99_us"] = s.p99;
    state.counters["max_us"] = s.max;
    state.counters["allocations"] = static_cast<double>(allocations);
  }
}
BENCHMARK(BM_LinkPointCycleInMemory)->Iterations(1)->Unit(benchmark::kMillisecond);

// A point's loopback TCP round trip: the link sends it, the server reads it and replies, the link reads
// the reply (single-threaded, so no scheduler hand-over is measured: the sockets' and the code's cost).
void BM_LinkPointRoundTripLoopbackTcp(benchmark::State& state) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 6;
  OnlineConfig oc;
  oc.period_s = 0.1;
  oc.watchdog_s = 1e9;
  for (auto _ : state) {
    TcpListener ml("127.0.0.1", 0), sl("127.0.0.1", 0);
    auto motion = TcpStream::connect("127.0.0.1", ml.port(), 2.0);
    auto state_stream = TcpStream::connect("127.0.0.1", sl.port(), 2.0);
    auto motion_server = ml.accept(2.0);
    auto state_server = sl.accept(2.0);
    ManualClock clock;
    OnlineCompensator comp(robot, sensor, oc);
    OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
    ConstantForce force;
    auto program = std::make_shared<const JointTrajectory>(std::vector<double>{0.0, 5000.0},
                                                           std::vector<JointVector>{start_pose(), start_pose()}, robot);
    SimpleMessageLinkConfig lc;
    lc.buffer_depth = 1;
    lc.reply_timeout_s = lc.state_timeout_s = 1e9;  // the simulated clock jumps a cycle a round trip
    SimpleMessageLink link(comp, strategy, program, *motion, *state_stream, clock, lc);
    link.read_force_from(&force);
    cell::SimpleMessageServerConfig sc;
    sc.buffer_points = 16;
    cell::SimpleMessageServer server(sc, robot, start_pose(), *motion_server, *state_server);
    server.tick(0.0);  // the first JOINT_POSITION
    std::vector<double> us;
    us.reserve(10000);
    std::size_t allocations = 0;
    double t = 0.0;
    while (us.size() < 10000) {
      t += 0.1;  // one cycle: the next point is due
      clock.set(t);
      g_allocations = 0;
      g_counting = us.size() > 100;
      const auto t0 = std::chrono::steady_clock::now();
      LinkPollResult r = link.poll(0.05);  // reads the state, sends the point
      if (r != LinkPollResult::kAnswered) {
        g_counting = false;
        continue;
      }
      while (server.counters().accepted < link.protocol_counters().points_sent) {
        motion_server->wait_readable(0.05);
        server.tick(t);
      }
      while (link.protocol_counters().points_accepted < link.protocol_counters().points_sent) {
        r = link.poll(0.05);
        if (r == LinkPollResult::kStopped) break;
      }
      const auto t1 = std::chrono::steady_clock::now();
      g_counting = false;
      allocations += g_allocations.load();
      us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    }
    const Spread s = spread(us);
    state.counters["p50_us"] = s.p50;
    state.counters["p99_us"] = s.p99;
    state.counters["max_us"] = s.max;
    state.counters["allocations"] = static_cast<double>(allocations);
  }
}
BENCHMARK(BM_LinkPointRoundTripLoopbackTcp)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace deflex

BENCHMARK_MAIN();
