// What the controller-link benchmarks share: a force source with a new sample every cycle, the arm's
// start, the measured round trips and their report (p50/p99/max, lost, the heap allocations counted by
// counting_new.hpp, which must be included first). Include it in one translation unit of a benchmark
// program (each bench/*_bench.cpp is one).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include <benchmark/benchmark.h>

#include "deflex/model/types.hpp"
#include "deflex/online/force_sample.hpp"

namespace deflex {
namespace {

// A force source with a new sample every cycle.
class FreshSampleForce final : public ForceSource {
 public:
  bool latest(ForceSample& out) noexcept override {
    served_ = !served_;
    if (!served_) return false;
    out.t_s += 0.001;
    out.wrench_sensor << 50.0, -120.0, -400.0, 2.0, 1.0, -0.5;
    return true;
  }

 private:
  bool served_ = false;
};

// The arm at rest where every benchmark's program starts, rad.
inline const JointVector& start_joints() {
  static const JointVector q = [] {
    JointVector v(6);
    v << 0.0, 0.35, 0.17, 0.0, 1.05, 0.0;
    return v;
  }();
  return q;
}

struct RoundTrips {
  std::vector<double> us;
  std::size_t lost = 0;
};

// The round trips' percentiles, the lost cycles and the allocations counted, as the benchmark's counters.
inline void report(benchmark::State& state, RoundTrips& r) {
  std::sort(r.us.begin(), r.us.end());
  const auto pct = [&](double p) { return r.us[static_cast<std::size_t>(p * static_cast<double>(r.us.size() - 1))]; };
  state.counters["cycles"] = static_cast<double>(r.us.size());
  state.counters["p50_us"] = pct(0.50);
  state.counters["p99_us"] = pct(0.99);
  state.counters["max_us"] = r.us.back();
  state.counters["lost"] = static_cast<double>(r.lost);
  state.counters["allocations"] = static_cast<double>(g_allocations.load());
}

}  // namespace
}  // namespace deflex
