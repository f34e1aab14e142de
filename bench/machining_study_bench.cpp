// Where the machining study's time goes (`deflex machining-study`): the quick study on one seed and
// one thread, its phases as counters (the seed's cell and calibration, the slot cuts and the fit, the
// parts by strategy, seconds), and the stock's engagement query the coupled solve asks at every trial
// position of every tick, with the study's sampling against the dexel stock's default.
#include <benchmark/benchmark.h>

#include "deflex/machining/dexel_stock.hpp"
#include "deflex/machining/milling_force.hpp"
#include "deflex/study/machining_study.hpp"

namespace {

using namespace deflex;

void BM_QuickMachiningStudyOneSeed(benchmark::State& state) {
  study::MachiningStudyOptions o;
  o.quick = true;
  o.seeds = 1;
  o.threads = 1;
  for (auto _ : state) {
    const study::MachiningStudyOutput out = study::run_machining_study(o);
    state.counters["calibration_s"] = out.times.calibration_s;
    state.counters["slot_cuts_s"] = out.times.slot_cuts_s;
    for (study::MachiningStrategy s : study::kMachiningStrategies) {
      state.counters[std::string(study::to_string(s)) + "_s"] = out.times.parts_s[static_cast<int>(s)];
    }
    state.counters["cut_ticks"] = static_cast<double>(out.coupled.ticks);
    state.counters["arm_solves_per_tick"] = static_cast<double>(out.coupled.arm_solves) /
                                            static_cast<double>(std::max<std::uint64_t>(out.coupled.ticks, 1));
  }
}
BENCHMARK(BM_QuickMachiningStudyOneSeed)->Unit(benchmark::kSecond)->Iterations(1);

// One engagement query of a 2 mm climb side cut 4 mm deep beside a 10 mm slot, on the study's 0.1 mm
// grid: argument 0 the stock's default sampling (65 angles, arc ends bisected 20 times), 1 the
// study's (33 angles, 12 bisections).
void BM_StudyEngagementQuery(benchmark::State& state) {
  DexelStock stock = DexelStock::box(Vector3(0.0, -0.02, -0.008), Vector3(0.04, 0.02, 0.0), 0.1e-3, 0.5e-3);
  if (state.range(0) == 1) stock.set_sampling(EngagementSampling{32, 12, 10e-6, 1e-6});
  Cutter c;
  c.diameter_m = 10e-3;
  c.flutes = 3;
  c.helix_rad = deg_to_rad(30.0);
  (void)stock.remove_swept(c, Vector3(-0.006, 0.0, -0.004), Vector3(0.046, 0.0, -0.004), Vector3::UnitZ());
  CutFrame frame;
  (void)make_cut_frame(Vector3::UnitZ(), Vector3(1.0, 0.0, 0.0), frame);
  const Vector3 tip(0.02, -0.002, -0.004);
  Engagement e;
  for (auto _ : state) {
    benchmark::DoNotOptimize(stock.engagement(c, frame, tip, SpindleTurn::kClockwise, e));
  }
  state.SetLabel(state.range(0) == 1 ? "the study's sampling" : "the stock's default");
}
BENCHMARK(BM_StudyEngagementQuery)->Arg(0)->Arg(1);

}  // namespace
BENCHMARK_MAIN();
