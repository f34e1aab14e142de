// The milling force and the stock per toolpath point: the revolution average from a given
// engagement (the per-point budget is about 1 us), its peak, the height map's engagement query and
// the move that follows it, at three cell sizes. A 10 mm, 3-flute end mill, 30 deg helix, Al7075-T6.
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "deflex/machining/dexel_stock.hpp"
#include "deflex/machining/milling_force.hpp"
#include "deflex/machining/zmap_stock.hpp"

namespace {

using namespace deflex;

MillingCut cut(double corner_mm = 0.0) {
  MillingCut c;
  c.cutter.diameter_m = 10e-3;
  c.cutter.flutes = 3;
  c.cutter.helix_rad = deg_to_rad(30.0);
  c.cutter.corner_radius_m = corner_mm * 1e-3;
  c.k = {767e6, 168.8e6, 222e6, 27.7e3, 26.6e3, 0.7e3};
  c.fz_m = 0.1e-3;
  return c;
}

void BM_AverageForceSideCut(benchmark::State& state) {
  const MillingCut c = cut();
  const Engagement e = uniform_engagement(3e-3, 5e-3, 10e-3, CutSide::kClimb);
  for (auto _ : state) benchmark::DoNotOptimize(average_milling_force(c, e));
}
BENCHMARK(BM_AverageForceSideCut);

void BM_AverageForceBullNoseSlot(benchmark::State& state) {
  const MillingCut c = cut(2.0);  // the corner in six bands, the side above it
  const Engagement e = uniform_engagement(10e-3, 5e-3, 10e-3, CutSide::kClimb);
  for (auto _ : state) benchmark::DoNotOptimize(average_milling_force(c, e));
}
BENCHMARK(BM_AverageForceBullNoseSlot);

void BM_PeakForce(benchmark::State& state) {
  const MillingCut c = cut();
  const Engagement e = uniform_engagement(3e-3, 5e-3, 10e-3, CutSide::kClimb);
  for (auto _ : state) benchmark::DoNotOptimize(peak_milling_force(c, e, static_cast<int>(state.range(0))));
}
BENCHMARK(BM_PeakForce)->Arg(16)->Arg(32);

/// A 200 x 100 x 30 mm block with a slot along x at y = 50 mm, 5 mm deep, cut already; the point
/// under test is a 3 mm step-over side cut beside it.
struct SlottedBlock {
  ZMapStock stock;
  explicit SlottedBlock(double cell_m) : stock(ZMapStock::box(Vector3(0, 0, 0), Vector3(0.2, 0.1, 0.03), cell_m)) {
    const Cutter c = cut().cutter;
    (void)stock.remove_swept(c, Vector3(-0.01, 0.05, 0.025), Vector3(0.21, 0.05, 0.025), Vector3::UnitZ());
  }
};

void BM_EngagementQuery(benchmark::State& state) {
  const double cell_m = static_cast<double>(state.range(0)) * 1e-6;
  const SlottedBlock block(cell_m);
  const Cutter c = cut().cutter;
  CutFrame frame;
  (void)make_cut_frame(Vector3::UnitZ(), Vector3::UnitX(), frame);
  Engagement e;
  double x = 0.02;
  for (auto _ : state) {
    benchmark::DoNotOptimize(block.stock.engagement(c, frame, Vector3(x, 0.053, 0.025), SpindleTurn::kClockwise, e));
    x = x < 0.18 ? x + 1e-4 : 0.02;
  }
  state.SetLabel(fmt::format("cell {:g} mm", cell_m * 1e3));
}
BENCHMARK(BM_EngagementQuery)->Arg(500)->Arg(100)->Arg(50);

/// Per toolpath point of a side-cut pass: the query, the force from it, and the move (`step` um long)
/// into the point; the pass restarts on a fresh copy of the block when it reaches the end.
void BM_SideCutPoint(benchmark::State& state) {
  const double cell_m = static_cast<double>(state.range(0)) * 1e-6, step_m = static_cast<double>(state.range(1)) * 1e-6;
  const SlottedBlock fresh(cell_m);
  ZMapStock stock = fresh.stock;
  const MillingCut c = cut();
  CutFrame frame;
  (void)make_cut_frame(Vector3::UnitZ(), Vector3::UnitX(), frame);
  Engagement e;
  Vector3 at(0.02, 0.053, 0.025);
  for (auto _ : state) {
    const Vector3 next = at + Vector3(step_m, 0, 0);
    (void)stock.engagement(c.cutter, frame, next, SpindleTurn::kClockwise, e);
    benchmark::DoNotOptimize(average_milling_force(c, e));
    (void)stock.remove_swept(c.cutter, at, next, Vector3::UnitZ());
    at = next;
    if (at.x() > 0.18) {
      state.PauseTiming();
      stock = fresh.stock;
      at = Vector3(0.02, 0.053, 0.025);
      state.ResumeTiming();
    }
  }
  state.SetLabel(fmt::format("cell {:g} mm, step {:g} mm", cell_m * 1e3, step_m * 1e3));
}
BENCHMARK(BM_SideCutPoint)->Args({500, 1000})->Args({100, 1000})->Args({50, 1000})->Args({100, 100});

/// The same pass on the dexel stock: cell and layer spacing from the first argument (um).
void BM_DexelSideCutPoint(benchmark::State& state) {
  const double cell_m = static_cast<double>(state.range(0)) * 1e-6, step_m = 1e-3;
  DexelStock fresh = DexelStock::box(Vector3(0, 0, 0), Vector3(0.2, 0.1, 0.03), cell_m, cell_m);
  const MillingCut c = cut();
  (void)fresh.remove_swept(c.cutter, Vector3(-0.01, 0.05, 0.025), Vector3(0.21, 0.05, 0.025), Vector3::UnitZ());
  DexelStock stock = fresh;
  CutFrame frame;
  (void)make_cut_frame(Vector3::UnitZ(), Vector3::UnitX(), frame);
  Engagement e;
  Vector3 at(0.02, 0.053, 0.025);
  for (auto _ : state) {
    const Vector3 next = at + Vector3(step_m, 0, 0);
    (void)stock.engagement(c.cutter, frame, next, SpindleTurn::kClockwise, e);
    benchmark::DoNotOptimize(average_milling_force(c, e));
    (void)stock.remove_swept(c.cutter, at, next, Vector3::UnitZ());
    at = next;
    if (at.x() > 0.18) {
      state.PauseTiming();
      stock = fresh;
      at = Vector3(0.02, 0.053, 0.025);
      state.ResumeTiming();
    }
  }
  state.SetLabel(fmt::format("cell and layer {:g} mm, step 1 mm", cell_m * 1e3));
}
BENCHMARK(BM_DexelSideCutPoint)->Arg(500)->Arg(250)->Arg(100);

}  // namespace

BENCHMARK_MAIN();
