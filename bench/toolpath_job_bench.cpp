// A CAM toolpath compensated end to end, a million points streamed: G-code read, the milling force
// from a height-map stock the path cuts away, the spindle angle chosen for stiffness (or fixed), the
// arm's IK, the exact compensation with the deflection and residual predictions, and (in the _Out
// runs) the compensated G-code and the CSV written to /dev/null. The path is an outward rectangular
// spiral pocket, 5 mm step-over with a 10 mm end mill, 0.5 mm deep levels, points every 0.5 mm
// (the reader splits the long lines). Per point: the CPU time, and how the process's peak memory grew.
#include <sys/resource.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "deflex/force/force_spec.hpp"
#include "deflex/machining/milling_force_model.hpp"
#include "deflex/machining/stock_spec.hpp"
#include "deflex/offline/toolpath_job.hpp"
#include "deflex/robotfile/robot_io.hpp"

namespace {

namespace fs = std::filesystem;
using namespace deflex;

double peak_rss_mib() {
  struct rusage u {};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

/// Outward spiral rings round the pocket's centre, `levels` of them 0.5 mm apart in depth, inside a
/// 200 x 200 mm block: each level's path is about 7.6 m, 15,200 points at 0.5 mm.
std::string spiral_pocket(int levels) {
  const fs::path path = fs::temp_directory_path() / fmt::format("deflex_bench_spiral_{}.nc", levels);
  if (!fs::exists(path)) {
    std::ofstream out(path);
    out << "%\nG21 G90 G94 G17\nT1 M6\nS15000 M3\nG0 X0. Y0. Z5.\n";
    for (int level = 1; level <= levels; ++level) {
      const double z = -0.5 * level;
      out << fmt::format("G0 X0. Y0.\nG0 Z{:.3f}\nG1 Z{:.3f} F600.\nF3000.\n", z + 1.0, z);
      for (int ring = 1; ring <= 19; ++ring) {
        const double h = 5.0 * ring;
        out << fmt::format("G1 X{:.3f} Y{:.3f}\nG1 Y{:.3f}\nG1 X{:.3f}\nG1 Y{:.3f}\nG1 X{:.3f}\n", h, -h + 5.0, h, -h,
                           -h, h);
      }
      out << "G0 Z5.\n";
    }
    out << "M5\nM30\n%\n";
  }
  return path.string();
}

void run_job(benchmark::State& state, const std::string& spin, bool outputs) {
  const double cell_mm = static_cast<double>(state.range(0)) * 1e-3;
  const int levels = static_cast<int>(state.range(1));
  const RobotModel model = load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/machining/irb6700_spindle.yaml");
  const std::string file = spiral_pocket(levels);
  ForceSpecContext context;
  context.milling = milling_force_specs(parse_cutter_spec("diameter_mm=10,flutes=3,helix_deg=30"));
  const auto force =
      parse_force_spec("milling:file=" + std::string(DEFLEX_SOURCE_DIR) + "/data/machining/al7075-t6.yaml", context);
  ToolpathJobOptions o;
  o.base_T_workpiece.translation() = Vector3(2.0, 0.0, 0.75);
  o.spin = parse_tool_spin_spec(spin);
  ToolpathOptions reading;
  reading.max_linear_step_m = 0.5e-3;
  const double rss_before = peak_rss_mib();
  std::size_t points = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const std::unique_ptr<Stock> stock =
        parse_stock_spec(fmt::format("box:min_mm=-100;-100;-40,max_mm=100;100;0,cell_mm={}", cell_mm));
    const std::unique_ptr<ToolpathReader> reader = open_toolpath(file, reading);
    OutputFile gcode_file("/dev/null", "G-code"), csv_file("/dev/null", "CSV");
    std::unique_ptr<GcodeWriteBack> gcode;
    std::unique_ptr<OfflineCsvWriter> csv;
    ToolpathSinks sinks;
    if (outputs) {
      gcode = std::make_unique<GcodeWriteBack>(file, gcode_file, reading);
      csv = std::make_unique<OfflineCsvWriter>(csv_file, 6, "", "", true, toolpath_csv_columns(), "");
    }
    sinks.gcode = gcode.get();
    sinks.csv = csv.get();
    state.ResumeTiming();
    const ToolpathJobResult r =
        run_toolpath_job(model, *reader, static_cast<const MillingForceModel&>(*force), stock.get(), o, sinks);
    if (gcode) gcode->finish();
    if (csv) csv->finish();
    points = r.points;
    state.counters["mean_deflection_mm"] = r.mean_cutting_deflection_m * 1e3;
    state.counters["candidate_solves"] = static_cast<double>(r.spin.candidate_solves);
  }
  state.counters["points"] = static_cast<double>(points);
  state.counters["us_per_point"] =
      benchmark::Counter(static_cast<double>(points) * 1e-6, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["peak_rss_growth_MiB"] = peak_rss_mib() - rss_before;
  state.SetLabel(fmt::format("cell {:g} mm, {} levels, spin {}", cell_mm, levels, spin));
}

/// The parts alone, for where the time goes: the reader, and the reader with the milling force and
/// the stock (engagement query, average and peak force, the move removed).
void BM_ToolpathReadOnly(benchmark::State& state) {
  const std::string file = spiral_pocket(static_cast<int>(state.range(1)));
  ToolpathOptions reading;
  reading.max_linear_step_m = 0.5e-3;
  std::size_t points = 0;
  for (auto _ : state) {
    const std::unique_ptr<ToolpathReader> reader = open_toolpath(file, reading);
    ToolpathPoint p;
    points = 0;
    while (reader->next(p)) ++points;
  }
  state.counters["us_per_point"] =
      benchmark::Counter(static_cast<double>(points) * 1e-6, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_ToolpathForceOnly(benchmark::State& state) {
  const double cell_mm = static_cast<double>(state.range(0)) * 1e-3;
  const std::string file = spiral_pocket(static_cast<int>(state.range(1)));
  ForceSpecContext context;
  context.milling = milling_force_specs(parse_cutter_spec("diameter_mm=10,flutes=3,helix_deg=30"));
  const auto force =
      parse_force_spec("milling:file=" + std::string(DEFLEX_SOURCE_DIR) + "/data/machining/al7075-t6.yaml", context);
  ToolpathOptions reading;
  reading.max_linear_step_m = 0.5e-3;
  std::size_t points = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const std::unique_ptr<Stock> stock =
        parse_stock_spec(fmt::format("box:min_mm=-100;-100;-40,max_mm=100;100;0,cell_mm={}", cell_mm));
    const std::unique_ptr<ToolpathReader> reader = open_toolpath(file, reading);
    MillingProcess process(static_cast<const MillingForceModel&>(*force), stock.get());
    state.ResumeTiming();
    ToolpathPoint p;
    points = 0;
    while (reader->next(p)) {
      MillingPointInput in;
      in.tip_m = p.position_m;
      in.tool_axis = p.tool_axis;
      in.feed_mm_min = p.feed_m_s * 6e4;
      in.spindle_rpm = p.spindle_rpm;
      if (p.spindle != SpindleState::kOff) in.turn = SpindleTurn::kClockwise;
      in.rapid = p.motion == MotionKind::kRapid;
      in.line = p.line;
      benchmark::DoNotOptimize(process.next(in));
      ++points;
    }
  }
  state.counters["us_per_point"] =
      benchmark::Counter(static_cast<double>(points) * 1e-6, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(fmt::format("cell {:g} mm", cell_mm));
}
BENCHMARK(BM_ToolpathReadOnly)->Args({0, 6})->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_ToolpathForceOnly)
    ->Args({1000, 6})
    ->Args({500, 6})
    ->Args({250, 6})
    ->Args({100, 6})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

void BM_ToolpathJobOptimize(benchmark::State& state) { run_job(state, "optimize", false); }
void BM_ToolpathJobFixed(benchmark::State& state) { run_job(state, "fixed:0", false); }
void BM_ToolpathJobOptimizeOut(benchmark::State& state) { run_job(state, "optimize", true); }

// 6 levels: 91,000 points (quick); 66 levels: 1.0 M points.
BENCHMARK(BM_ToolpathJobOptimize)
    ->Args({500, 6})
    ->Args({1000, 66})
    ->Args({500, 66})
    ->Args({250, 66})
    ->Args({100, 66})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK(BM_ToolpathJobFixed)->Args({500, 6})->Args({500, 66})->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_ToolpathJobOptimizeOut)->Args({500, 6})->Args({500, 66})->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
