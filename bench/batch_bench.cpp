// The C++ loop the Python module's batch calls are measured against (bench/python_batch_bench.py):
// FK, Jacobian and deflection over the same 100,000 IRB6700 configurations, one Workspace, results
// stored for every configuration as a C++ user would keep them.
// Run: build/bench/batch_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_robot.hpp"
#include "deflex/model/compliance.hpp"

namespace {

using namespace deflex;

constexpr int kConfigurations = 100000;

const RobotModel& robot() { return bench::irb6700(); }

const std::vector<JointVector>& configurations() {
  static const std::vector<JointVector> qs = bench::random_configurations(kConfigurations);
  return qs;
}

void BM_Batch100k_FK(benchmark::State& state) {
  Workspace ws(robot());
  const auto& qs = configurations();
  std::vector<Pose> out(qs.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < qs.size(); ++i) {
      forward_kinematics(robot(), ws, qs[i]);
      out[i] = ws.base_T_tcp;
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kConfigurations);
}
BENCHMARK(BM_Batch100k_FK)->Unit(benchmark::kMillisecond);

void BM_Batch100k_Jacobian(benchmark::State& state) {
  Workspace ws(robot());
  const auto& qs = configurations();
  std::vector<Jacobian> out(qs.size(), Jacobian(6, 6));
  for (auto _ : state) {
    for (std::size_t i = 0; i < qs.size(); ++i) {
      jacobian(robot(), ws, qs[i], EndPoint::kTcp, out[i]);
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kConfigurations);
}
BENCHMARK(BM_Batch100k_Jacobian)->Unit(benchmark::kMillisecond);

void BM_Batch100k_Deflect(benchmark::State& state) {
  Workspace ws(robot());
  const auto& qs = configurations();
  Wrench w;
  w << 400.0, -300.0, -650.0, 0.0, 0.0, 0.0;
  std::vector<JointVector> dtheta(qs.size(), JointVector(6));
  std::vector<Displacement> dx(qs.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < qs.size(); ++i) {
      dx[i] = tcp_deflection(robot(), ws, qs[i], w, dtheta[i]);
    }
    benchmark::DoNotOptimize(dx.data());
    benchmark::DoNotOptimize(dtheta.data());
  }
  state.SetItemsProcessed(state.iterations() * kConfigurations);
}
BENCHMARK(BM_Batch100k_Deflect)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
