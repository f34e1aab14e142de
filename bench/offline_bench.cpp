// Offline compensation of a 100,000-point path on the built-in IRB6700: the compensation step alone
// (target: under 100 ms), with the deflection and residual prediction, and the path IK before it.
#include <benchmark/benchmark.h>

#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/path_spec.hpp"

namespace {

using namespace deflex;

constexpr int kPoints = 100000;

struct LongPath {
  RobotModel model = builtin_irb6700();
  std::vector<Pose> poses;
  JointPath path;
  LdbbForceModel force{Vector3(1.5, 0.0, 0.9), 625.0, true};
  LongPath() {
    CirclePath c = default_circle();
    c.points = kPoints;
    poses = sample_circle(c, Eigen::Quaterniond(0, 0, 1, 0));
    path = solve_path_ik(model, poses, IkRequest{});
  }
};

const LongPath& long_path() {
  static const LongPath p;
  return p;
}

void BM_PathIk100k(benchmark::State& state) {
  const LongPath& p = long_path();
  for (auto _ : state) {
    benchmark::DoNotOptimize(solve_path_ik(p.model, p.poses, IkRequest{}));
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}

void BM_Compensate100k(benchmark::State& state) {
  const LongPath& p = long_path();
  OfflineOptions options;
  options.predict = state.range(0) != 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(compensate_path(p.model, p.path, p.poses, p.force, options));
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
  state.SetLabel(options.predict ? "with deflection + residual prediction" : "compensation step only");
}

}  // namespace

BENCHMARK(BM_PathIk100k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Compensate100k)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
