// Joint stiffness identification speed: the issue asks for 10,000 measurements in under 50 ms.
// Data: the built-in IRB6700 with a tool whose TCP is off the flange axis, random poses and loads, the core's exact
// deflection plus 10 um tracker noise and 1% gross outliers (so the robust loop really iterates).
#include <random>

#include <benchmark/benchmark.h>

#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"

namespace {

using namespace deflex;

const RobotModel& robot() {
  static const RobotModel model = [] {
    Pose tool = Pose::Identity();
    tool.translation() = Vector3(0.06, 0.0, 0.25);
    return builtin_irb6700().with_tool(tool);
  }();
  return model;
}

std::vector<StiffnessMeasurement> make_data(int count) {
  const RobotModel& model = robot();
  std::mt19937 rng(1);
  std::normal_distribution<double> n01;
  Workspace ws(model);
  std::vector<StiffnessMeasurement> data;
  while (static_cast<int>(data.size()) < count) {
    StiffnessMeasurement m;
    m.q.resize(6);
    for (int j = 0; j < 6; ++j) {
      m.q[j] = std::uniform_real_distribution<double>(std::max(model.lower_limits()[j], -2.6),
                                                      std::min(model.upper_limits()[j], 2.6))(rng);
    }
    if (jacobian_min_singular_value(model, ws, m.q) < 0.05) {
      continue;
    }
    m.wrench_base << 800 * n01(rng), 800 * n01(rng), 800 * n01(rng), 100 * n01(rng), 100 * n01(rng), 100 * n01(rng);
    const Vector3 p0 = tcp_pose(model, ws, m.q).translation();
    JointVector qa;
    (void)deflected_configuration(model, ws, m.q, m.wrench_base, qa);
    m.dp_m = tcp_pose(model, ws, qa).translation() - p0 + 10e-6 * Vector3(n01(rng), n01(rng), n01(rng));
    if (data.size() % 100 == 7) {
      m.dp_m.x() += 1e-3;  // gross outlier
    }
    data.push_back(m);
  }
  return data;
}

void BM_IdentifyStiffness(benchmark::State& state) {
  const auto data = make_data(static_cast<int>(state.range(0)));
  IdentificationOptions opt;
  opt.robust = state.range(1) != 0;
  int iterations = 0;
  for (auto _ : state) {
    const StiffnessEstimate est = identify_stiffness(robot(), data, opt);
    iterations = est.iterations;
    benchmark::DoNotOptimize(est.stiffness_nm_per_rad.data());
  }
  state.counters["irls_iterations"] = iterations;
  state.counters["measurements"] = static_cast<double>(data.size());
}
BENCHMARK(BM_IdentifyStiffness)->Args({10000, 1})->Args({10000, 0})->Args({1000, 1})->Unit(benchmark::kMillisecond);

void BM_StiffnessRegressor(benchmark::State& state) {
  const auto data = make_data(64);
  Workspace ws(robot());
  Jacobian block(6, 6);
  std::size_t i = 0;
  for (auto _ : state) {
    stiffness_regressor(robot(), ws, data[i % data.size()].q, data[i % data.size()].wrench_base, block);
    benchmark::DoNotOptimize(block.data());
    ++i;
  }
}
BENCHMARK(BM_StiffnessRegressor);

}  // namespace

BENCHMARK_MAIN();
