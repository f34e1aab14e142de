// Evaluation hot paths on tracker-sized data: the paper's mean distance of 6 noisy loaded laps
// (10 mm/s on a 100 mm circle at 1000 Hz: 377k points) from 6 unloaded laps (377k points), and
// ISO 9283 over 6 laps at 81 planes, and the laps of one 377k-point run split by angle; and the case
// study's own query: every 1 kHz sample of a run against the mean of its unloaded laps (3600 angle
// bins on the 130 mm circle), the cost a tracker sample adds to the study's evaluation.
// Run: build/bench/evaluate_bench --benchmark_min_time=1
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/path_metrics.hpp"

namespace {

using namespace deflex;

constexpr int kPerLap = 62832;  // 2 pi 100 mm / (10 mm/s) at 1 kHz
constexpr int kLaps = 6;

// 3 anticlockwise and 3 clockwise laps, radius r, lifted by dz, with 10 um tracker noise per axis.
std::vector<TrackerTrace> laps(double r, double dz, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 10e-6);
  std::vector<TrackerTrace> out;
  for (int l = 0; l < kLaps; ++l) {
    TrackerTrace t;
    t.reserve(kPerLap);
    for (int i = 0; i < kPerLap; ++i) {
      const double a = (l % 2 == 0 ? 1.0 : -1.0) * 2.0 * kPi * i / kPerLap;
      t.push_back({(l * kPerLap + i) * 1e-3, Vector3(1.8 + r * std::cos(a), r * std::sin(a), 1.0 + dz) +
                                                 Vector3(noise(rng), noise(rng), noise(rng))});
    }
    out.push_back(std::move(t));
  }
  return out;
}

const std::vector<TrackerTrace>& unloaded() {
  static const std::vector<TrackerTrace> t = laps(0.1, 0.0, 1);
  return t;
}

const std::vector<TrackerTrace>& loaded() {
  static const std::vector<TrackerTrace> t = laps(0.1003, 0.0004, 2);
  return t;
}

void BM_MeanDistance377kx377k(benchmark::State& state) {
  for (auto _ : state) {
    benchmark::DoNotOptimize(path_deviation(loaded(), unloaded()).mean_m);
  }
  state.SetItemsProcessed(state.iterations() * kPerLap * kLaps);
}
BENCHMARK(BM_MeanDistance377kx377k)->Unit(benchmark::kMillisecond);

// The case study's nearest-point metric: a loaded run (3 + 3 laps at 10 mm/s on the 130 mm circle,
// 1 kHz, 0.3 mm outward and 0.4 mm up, 5 um of tracker noise) against the mean of an unloaded run's
// laps (3600 angle bins), indexed once as the study does. The argument is the speed (mm/s): the
// study's tables run 10 to 50, its sweep up to 200 (a sample every 0.2 mm, about a segment).
void BM_StudyNearest(benchmark::State& state) {
  const double speed_m_s = static_cast<double>(state.range(0)) * 1e-3;
  const auto run = [&](double r, double dz, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, 5e-6);
    const int per_lap = static_cast<int>(2.0 * kPi * r / speed_m_s * 1000.0);
    TrackerTrace t;
    for (int l = 0; l < kLaps; ++l) {
      for (int i = 0; i < per_lap; ++i) {
        const double a = (l < kLaps / 2 ? 1.0 : -1.0) * 2.0 * kPi * i / per_lap;
        t.push_back({static_cast<double>(t.size()) * 1e-3, Vector3(1.8 + r * std::cos(a), r * std::sin(a), 0.9 + dz) +
                                                               Vector3(noise(rng), noise(rng), noise(rng))});
      }
    }
    return t;
  };
  const TrackerTrace reference = mean_closed_path(run(0.13, 0.0, 3));
  const TrackerTrace loaded = run(0.1303, 0.0004, 4);
  const PolylineIndex index(reference);
  for (auto _ : state) {
    benchmark::DoNotOptimize(path_deviation(loaded, index).mean_m);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(loaded.size()));
}
BENCHMARK(BM_StudyNearest)->Arg(10)->Arg(50)->Arg(200)->Unit(benchmark::kMillisecond);

void BM_BuildIndex377k(benchmark::State& state) {
  for (auto _ : state) {
    const PolylineIndex index(unloaded());
    benchmark::DoNotOptimize(index.vertices().data());
  }
}
BENCHMARK(BM_BuildIndex377k)->Unit(benchmark::kMillisecond);

void BM_Iso9283SixLaps81Planes(benchmark::State& state) {
  for (auto _ : state) {
    benchmark::DoNotOptimize(iso9283_path(loaded(), unloaded().front()).accuracy_m);
  }
}
BENCHMARK(BM_Iso9283SixLaps81Planes)->Unit(benchmark::kMillisecond);

// The case study splits every run's trace into laps (a plane fit, then an angle a sample).
void BM_SplitLaps377k(benchmark::State& state) {
  TrackerTrace run;
  for (const auto& lap : loaded()) run.insert(run.end(), lap.begin(), lap.end());
  for (auto _ : state) {
    benchmark::DoNotOptimize(split_laps(run).laps.size());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(run.size()));
}
BENCHMARK(BM_SplitLaps377k)->Unit(benchmark::kMillisecond);

void BM_PlaneFit377k(benchmark::State& state) {
  TrackerTrace run;
  for (const auto& lap : loaded()) run.insert(run.end(), lap.begin(), lap.end());
  for (auto _ : state) {
    benchmark::DoNotOptimize(best_fit_plane(run).normal);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(run.size()));
}
BENCHMARK(BM_PlaneFit377k)->Unit(benchmark::kMillisecond);

}  // namespace
BENCHMARK_MAIN();
