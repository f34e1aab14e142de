// Loopback round trips of deflex's UR RTDE link: a controller-side peer (the bench's own RTDE server on a
// TCP connection: the handshake, then one output package a cycle) sends an output package, the link (its
// own thread) reads, decodes, runs the strategy and the compensator on a fresh force sample and writes
// its input package; the peer times from its package to the answer. Beside it the floor: the same
// package bounced by a plain TCP echo (no decoding, no compute), so the link's own cost is the
// difference. Reports p50/p99/max over 100,000 cycles and the heap allocations counted in steady state.
//   build/bench/ur_rtde_bench
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <memory>
#include <string_view>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/transport/tcp_stream.hpp"
#include "deflex/ur/ur_rtde_link.hpp"

#include "counting_new.hpp"
#include "link_round_trips.hpp"

namespace deflex {
namespace {

// Reads one whole package into `in` (waiting up to `timeout_s` in all); its size, or 0.
std::size_t read_package(StreamTransport& s, std::vector<unsigned char>& in, std::size_t& have, double timeout_s) {
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    std::size_t bytes = 0;
    std::uint8_t type = 0;
    if (rtde::peek_package(in.data(), have, in.size(), bytes, type) == rtde::FrameStatus::kComplete) return bytes;
    const double left = timeout_s - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (left <= 0.0 || !s.wait_readable(left)) return 0;
    const long n = s.read(in.data() + have, in.size() - have);
    if (n <= 0) return 0;
    have += static_cast<std::size_t>(n);
  }
}

void consume(std::vector<unsigned char>& in, std::size_t& have, std::size_t bytes) {
  std::copy(in.begin() + static_cast<long>(bytes), in.begin() + static_cast<long>(have), in.begin());
  have -= bytes;
}

void write_all(StreamTransport& s, const unsigned char* data, std::size_t n) {
  for (std::size_t at = 0; at < n;) {
    const long w = s.write(data + at, n - at);
    if (w < 0) return;
    at += static_cast<std::size_t>(w);
  }
}

// The controller's side of the handshake: protocol 2 accepted, URControl 5.11, the recipes' types.
rtde::Recipe serve_handshake(StreamTransport& s, std::vector<unsigned char>& in, std::size_t& have) {
  std::array<unsigned char, 512> out{};
  using T = rtde::PackageType;
  const std::array<rtde::FieldType, UrRtdeLink::kOutputs> types{
      rtde::FieldType::kDouble, rtde::FieldType::kVector6d, rtde::FieldType::kVector6d, rtde::FieldType::kInt32,
      rtde::FieldType::kInt32,  rtde::FieldType::kUint32,   rtde::FieldType::kInt32};
  rtde::Recipe recipe;
  (void)rtde::make_recipe(1, types.data(), types.size(), recipe);
  for (bool started = false; !started;) {
    const std::size_t n = read_package(s, in, have, 5.0);
    if (n == 0) return recipe;
    const auto t = static_cast<T>(in[2]);
    std::size_t m = 0;
    if (t == T::kRequestProtocolVersion || t == T::kStart) m = rtde::encode_accepted(t, true, out.data(), out.size());
    if (t == T::kGetUrControlVersion) m = rtde::encode(rtde::UrControlVersion{5, 11, 0, 0}, out.data(), out.size());
    if (t == T::kSetupOutputs) {
      m = rtde::encode_setup_reply(t, 1, "DOUBLE,VECTOR6D,VECTOR6D,INT32,INT32,UINT32,INT32", out.data(), out.size());
    }
    if (t == T::kSetupInputs) {
      m = rtde::encode_setup_reply(t, 2, "INT32,INT32,DOUBLE,DOUBLE,DOUBLE,DOUBLE,DOUBLE,DOUBLE,DOUBLE,DOUBLE",
                                   out.data(), out.size());
    }
    started = t == T::kStart;
    consume(in, have, n);
    write_all(s, out.data(), m);
  }
  return recipe;
}

// `link` true: the link's handshake is served first and every output package waits for its input
// package; false: the same package is bounced off an echo.
RoundTrips exchange(StreamTransport& s, std::size_t cycles, bool link) {
  std::vector<unsigned char> in(1 << 16), out(1024);
  std::size_t have = 0;
  rtde::Recipe recipe;
  if (link) {
    recipe = serve_handshake(s, in, have);
  } else {
    const std::array<rtde::FieldType, 7> types{
        rtde::FieldType::kDouble, rtde::FieldType::kVector6d, rtde::FieldType::kVector6d, rtde::FieldType::kInt32,
        rtde::FieldType::kInt32,  rtde::FieldType::kUint32,   rtde::FieldType::kInt32};
    (void)rtde::make_recipe(1, types.data(), types.size(), recipe);
  }
  std::array<double, 6> q{};
  for (int j = 0; j < 6; ++j) q[static_cast<std::size_t>(j)] = start_joints()[j];
  RoundTrips r;
  r.us.resize(cycles);
  double t_s = 0.0;
  const auto one = [&](double& us) {
    t_s += 0.002;
    rtde::DataBuilder b(recipe, out.data(), out.size());
    b.set(UrRtdeLink::kTimestamp, t_s);
    b.set(UrRtdeLink::kActualQ, q);
    b.set(UrRtdeLink::kTargetQ, q);
    b.set(UrRtdeLink::kRobotMode, std::int32_t{7});
    b.set(UrRtdeLink::kSafetyMode, std::int32_t{1});
    b.set(UrRtdeLink::kRuntimeState, std::uint32_t{2});
    const std::size_t n = b.finish();
    const auto t0 = std::chrono::steady_clock::now();
    write_all(s, out.data(), n);
    const std::size_t got = read_package(s, in, have, 1.0);
    if (got == 0) {
      ++r.lost;
    } else {
      consume(in, have, got);
    }
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

// The floor: the same packages bounced by a plain TCP echo.
void BM_UrRtdeTcpLoopbackFloor(benchmark::State& state) {
  TcpListener listener("127.0.0.1", 0);
  std::atomic<bool> stop{false};
  std::unique_ptr<TcpStream> client = TcpStream::connect("127.0.0.1", listener.port(), 5.0);
  std::unique_ptr<TcpStream> server = listener.accept(5.0);
  std::thread echo([&] {
    std::vector<unsigned char> buf(1 << 16);
    while (!stop.load()) {
      if (!server->wait_readable(0.05)) continue;
      const long n = server->read(buf.data(), buf.size());
      if (n < 0) break;
      write_all(*server, buf.data(), static_cast<std::size_t>(n));
    }
  });
  for (auto _ : state) {
    RoundTrips r = exchange(*client, static_cast<std::size_t>(state.range(0)), false);
    report(state, r);
  }
  stop = true;
  echo.join();
}
BENCHMARK(BM_UrRtdeTcpLoopbackFloor)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_UrRtdeLinkRoundTrip(benchmark::State& state) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 6;
  OnlineConfig online;
  online.period_s = 0.002;
  OnlineCompensator comp(robot, sensor, online);
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  FreshSampleForce force;
  TcpListener listener("127.0.0.1", 0);
  std::unique_ptr<TcpStream> client = TcpStream::connect("127.0.0.1", listener.port(), 5.0);
  std::unique_ptr<TcpStream> controller = listener.accept(5.0);
  SteadyClock clock;
  // Held at its start for longer than the cycles take.
  const auto program = std::make_shared<const JointTrajectory>(
      std::vector<double>{0.0, 2000.0}, std::vector<JointVector>{start_joints(), start_joints()}, robot, "hold");
  UrRtdeLinkConfig config;
  config.stop.stop_silence_s = 30.0;
  UrRtdeLink link(comp, strategy, program, *client, clock, config);
  link.read_force_from(&force);
  std::atomic<bool> stop{false};
  std::thread loop([&] {
    while (!stop.load()) (void)link.poll(0.05);
  });
  for (auto _ : state) {
    RoundTrips r = exchange(*controller, static_cast<std::size_t>(state.range(0)), true);
    report(state, r);
    state.counters["answered"] = static_cast<double>(link.counters().replies);
  }
  stop = true;
  loop.join();
}
BENCHMARK(BM_UrRtdeLinkRoundTrip)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace deflex

BENCHMARK_MAIN();
