// Where the case study's CPU time goes, per phase (the seeds' calibrations, the unloaded reference
// runs, the loaded runs, their evaluation, the error budget, the assembly of the tables, and the
// report written from them), in the exact mode (the reference computation) and the default fast one.
// One iteration each: a study is seconds to minutes. The phases are thread CPU time summed over the
// study's threads; beside them what it simulated (servo ticks, loaded ticks and the arm's solves in
// them, tracker samples, link cycles) and its CPU per servo tick. By default one seed of the paper's
// case, quick (a clockwise and an anticlockwise lap a run); DEFLEX_BENCH_FULL=1 runs the whole
// default study (four seeds, 3 + 3 laps: minutes).
// Run: build/bench/case_study_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <time.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "deflex/report/case_report.hpp"
#include "deflex/report/html_report.hpp"
#include "deflex/study/case_config.hpp"
#include "deflex/study/case_study.hpp"

namespace {

using namespace deflex;

double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

void BM_CaseStudy(benchmark::State& state) {
  const bool full = std::getenv("DEFLEX_BENCH_FULL") != nullptr;
  const study::CaseConfig config = study::paper_case();
  study::CaseStudyOptions options;
  options.exact = state.range(0) != 0;
  options.quick = !full;
  options.seeds = full ? 0 : 1;
  const std::string out_dir =
      (std::filesystem::temp_directory_path() / ("deflex-case-study-bench-" + std::to_string(state.range(0)))).string();
  for (auto _ : state) {
    const double start = process_cpu_s();
    const study::CaseStudyOutput out = study::run_case_study(config, options);
    const double study_end = process_cpu_s();
    write_report(study::case_report(config, out, study::paper_case_yaml()), out_dir);
    const double end = process_cpu_s();
    const study::StudyPhaseTimes& p = out.phases;
    state.counters["calibration_s"] = p.calibration_s;
    state.counters["unloaded_s"] = p.unloaded_s;
    state.counters["loaded_s"] = p.loaded_s;
    state.counters["evaluation_s"] = p.evaluation_s;
    state.counters["budget_s"] = p.budget_s;
    state.counters["assembly_s"] = p.assembly_s;
    state.counters["report_s"] = end - study_end;
    state.counters["study_cpu_s"] = study_end - start;
    state.counters["runs"] = out.runs;
    state.counters["calibrations"] = out.calibrations;
    // What the study simulated, to set beside cell_tick_bench's cost of each (the floor).
    const double servo_ticks = out.simulated_s / config.cell.controller.servo_period_s;
    double cycles = 0.0;
    for (const auto& link : out.links) cycles += static_cast<double>(link.cycles);
    state.counters["servo_ticks"] = servo_ticks;
    state.counters["loaded_ticks"] = static_cast<double>(out.coupled.ticks);
    state.counters["arm_solves"] = static_cast<double>(out.coupled.arm_solves);
    state.counters["tracker_samples"] = out.simulated_s * config.cell.tracker.rate_hz;
    state.counters["link_cycles"] = cycles;
    state.counters["us_per_tick"] = (study_end - start) / servo_ticks * 1e6;
  }
  std::filesystem::remove_all(out_dir);
}
BENCHMARK(BM_CaseStudy)->ArgName("exact")->Arg(1)->Arg(0)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
