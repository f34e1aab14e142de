// Benchmarks of the online strategy's hot path: one conditioning step, one compensation cycle, and
// both together (the target: under 1 microsecond median), and a link's delay measurement of a cycle,
// with heap allocations counted.
//   build-*/bench/online_bench --benchmark_repetitions=10 --benchmark_report_aggregates_only=true
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/online/delay_estimator.hpp"
#include "deflex/online/online_compensator.hpp"
#include "deflex/robotfile/robot_io.hpp"

// GCC sees the replacement operator new (malloc) and delete (free) of this file inlined into the same
// translation unit and calls them mismatched; they are the standard replacement pair.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

// Global allocation counter for this program: every operator new bumps it, so a benchmark can report
// the allocations its loop made.
namespace {
std::atomic<std::size_t> g_allocations{0};
}
void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) {
    return p;
  }
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace deflex {
namespace {

struct Setup {
  RobotModel robot = [] {
    Pose tool = Pose::Identity();
    tool.translation() = Vector3(0.0, 0.0, 0.3);
    return builtin_irb6700().with_tool(tool);
  }();
  SensorConfig sensor = [] {
    SensorConfig c;
    c.components = 6;
    c.sample_rate_hz = 1000.0;
    c.lowpass_order = 2;
    c.payload_mass_kg = 10.0;
    c.payload_cog_sensor_m = Vector3(0, 0, 0.1);
    c.dead_band_N = 2.0;
    return c;
  }();
  JointVector q = [] {
    JointVector v(6);
    v << 0.1, 0.4, -0.2, 0.5, 0.7, -0.3;
    return v;
  }();
  ForceSample sample = [] {
    ForceSample s;
    s.wrench_sensor << 120.0, -80.0, -450.0, 4.0, -6.0, 1.0;
    return s;
  }();
};

void BM_ConditioningStep(benchmark::State& state) {
  Setup s;
  ForcePipeline pipeline(s.sensor);
  const Matrix3 R = Eigen::AngleAxisd(0.3, Vector3(1, 2, 3).normalized()).toRotationMatrix();
  const std::size_t before = g_allocations.load();
  for (auto _ : state) {
    s.sample.wrench_sensor[0] += 1e-9;
    benchmark::DoNotOptimize(pipeline.step(s.sample, R));
  }
  state.counters["allocations"] = static_cast<double>(g_allocations.load() - before);
}
BENCHMARK(BM_ConditioningStep);

void BM_CompensationCycle(benchmark::State& state) {
  Setup s;
  OnlineConfig cfg;
  cfg.watchdog_s = 1e12;  // one sample stays fresh: every cycle takes the full path (FK, J^T W, bounds)
  OnlineCompensator comp(s.robot, s.sensor, cfg);
  CycleInput in{0.0, s.q, s.q};
  comp.push_force(s.sample);
  (void)comp.step(in);
  const std::size_t before = g_allocations.load();
  for (auto _ : state) {
    in.t_s += 0.004;
    benchmark::DoNotOptimize(comp.step(in));
  }
  state.counters["allocations"] = static_cast<double>(g_allocations.load() - before);
}
BENCHMARK(BM_CompensationCycle);

// The figure: one sample conditioned plus one cycle computed.
void BM_ConditioningPlusCycle(benchmark::State& state) {
  Setup s;
  OnlineCompensator comp(s.robot, s.sensor, OnlineConfig{});
  CycleInput in{0.0, s.q, s.q};
  comp.push_force(s.sample);
  (void)comp.step(in);
  const std::size_t before = g_allocations.load();
  for (auto _ : state) {
    in.t_s += 0.004;
    s.sample.wrench_sensor[2] += 1e-9;
    comp.push_force(s.sample);
    const CycleOutput out = comp.step(in);
    benchmark::DoNotOptimize(out);
  }
  state.counters["allocations"] = static_cast<double>(g_allocations.load() - before);
  state.counters["status_ok"] = static_cast<double>(comp.step(in).status == CycleStatus::kOk);
}
BENCHMARK(BM_ConditioningPlusCycle);

// The link's delay measurement for one cycle: a reference recorded, and a feedback sample 24 ms
// behind it matched against the last 0.5 s of references (six joints on a smooth path at the 4 ms of
// EGM), as every cycle of a link measures it.
void BM_DelayEstimatorCycle(benchmark::State& state) {
  DelayEstimator est(0.05, 0.5);
  // A path of period 10 s sampled every 4 ms, taken round and round; the feedback 6 cycles behind.
  constexpr double kPeriod = 0.004;
  constexpr int kSamples = 2500, kBehind = 6;
  std::vector<JointVector> path(kSamples, JointVector(6));
  for (int k = 0; k < kSamples; ++k) {
    for (int j = 0; j < 6; ++j) path[k][j] = 0.1 * j + 0.3 * std::sin(2.0 * kPi * k / kSamples + 0.5 * j);
  }
  long k = kSamples;
  const auto cycle = [&] {
    const double t = static_cast<double>(k) * kPeriod;
    est.record_reference(t, path[k % kSamples]);
    est.observe_feedback(t, path[(k - kBehind) % kSamples]);
    ++k;
  };
  for (int i = 0; i < 200; ++i) cycle();
  const std::size_t before = g_allocations.load();
  for (auto _ : state) cycle();
  state.counters["allocations"] = static_cast<double>(g_allocations.load() - before);
  state.counters["delay_ms"] = est.delay_s() * 1e3;
}
BENCHMARK(BM_DelayEstimatorCycle);

}  // namespace
}  // namespace deflex

BENCHMARK_MAIN();
