// Reading CAM toolpaths: a generated G-code raster of a million G1 blocks, a program whose arcs
// become a million chords, the same raster as APT/CL data, and the G-code write-back of a million
// points (to /dev/null). Reports points per second and how much the process's peak resident memory
// grew while reading: the readers stream, so it stays at their buffers whatever the file's length.
#include <sys/resource.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "deflex/toolpath/gcode_write_back.hpp"
#include "deflex/toolpath/toolpath_reader.hpp"

namespace {

namespace fs = std::filesystem;

double peak_rss_mib() {
  struct rusage u {};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // Linux: kB
}

/// A raster of `blocks` G1 moves over a 200 x 200 mm face, as a 3-axis post writes it.
std::string raster_gcode(std::size_t blocks) {
  const fs::path path = fs::temp_directory_path() / fmt::format("deflex_bench_raster_{}.nc", blocks);
  if (!fs::exists(path)) {
    std::ofstream out(path);
    out << "%\nO1000 (RASTER)\nG21 G90 G94 G17\nT1 M6\nS12000 M3\nG0 X0. Y0.\nG43 Z5. H1\nG1 Z-1. F2000.\n";
    for (std::size_t i = 0; i < blocks; ++i) {
      const double x = static_cast<double>(i % 1000) * 0.2, y = static_cast<double>(i / 1000) * 0.2;
      out << fmt::format("N{} X{:.3f} Y{:.3f}\n", i + 10, (i / 1000) % 2 == 0 ? x : 200.0 - x, y);
    }
    out << "G0 Z5.\nM30\n%\n";
  }
  return path.string();
}

/// Full circles of r = 10 mm at the default 0.01 mm chord tolerance: 71 chords each.
std::string arcs_gcode(std::size_t circles) {
  const fs::path path = fs::temp_directory_path() / fmt::format("deflex_bench_arcs_{}.nc", circles);
  if (!fs::exists(path)) {
    std::ofstream out(path);
    out << "G21 G90 G17\nS12000 M3\nG0 X0. Y0. Z0.\nF1500.\n";
    for (std::size_t i = 0; i < circles; ++i) {
      out << (i % 2 == 0 ? "G2 I10. J0.\n" : "G3 I-10. J0.\n");
    }
  }
  return path.string();
}

std::string raster_apt(std::size_t records) {
  const fs::path path = fs::temp_directory_path() / fmt::format("deflex_bench_raster_{}.apt", records);
  if (!fs::exists(path)) {
    std::ofstream out(path);
    out << "PARTNO RASTER\nUNITS/MM\nMULTAX/ON\nCUTTER/10,0\nLOADTL/1\nSPINDL/RPM,12000,CLW\nFEDRAT/MMPM,2000\n";
    for (std::size_t i = 0; i < records; ++i) {
      const double x = static_cast<double>(i % 1000) * 0.2, y = static_cast<double>(i / 1000) * 0.2;
      out << fmt::format("GOTO/{:.4f},{:.4f},-1.0000,0.000000,0.000000,1.000000\n", x, y);
    }
    out << "FINI\n";
  }
  return path.string();
}

void read_all(benchmark::State& state, const std::string& path) {
  std::size_t points = 0;
  const double rss_before = peak_rss_mib();
  for (auto _ : state) {
    const auto reader = deflex::open_toolpath(path);
    deflex::ToolpathPoint p;
    std::size_t n = 0;
    while (reader->next(p)) ++n;
    benchmark::DoNotOptimize(p);
    points = n;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(points) * state.iterations());
  state.counters["points"] = static_cast<double>(points);
  state.counters["file_MiB"] = static_cast<double>(fs::file_size(path)) / (1024.0 * 1024.0);
  state.counters["peak_rss_growth_MiB"] = peak_rss_mib() - rss_before;
}

void BM_ReadGcodeRaster(benchmark::State& state) {
  read_all(state, raster_gcode(static_cast<std::size_t>(state.range(0))));
}
BENCHMARK(BM_ReadGcodeRaster)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_ReadGcodeArcs(benchmark::State& state) {
  read_all(state, arcs_gcode(static_cast<std::size_t>(state.range(0))));
}
BENCHMARK(BM_ReadGcodeArcs)->Arg(14'085)->Unit(benchmark::kMillisecond)->Iterations(3);  // 1.0 M chords

void BM_ReadAptRaster(benchmark::State& state) {
  read_all(state, raster_apt(static_cast<std::size_t>(state.range(0))));
}
BENCHMARK(BM_ReadAptRaster)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_GcodeWriteBack(benchmark::State& state) {
  const std::string path = raster_gcode(static_cast<std::size_t>(state.range(0)));
  std::size_t points = 0;
  const double rss_before = peak_rss_mib();
  for (auto _ : state) {
    const auto reader = deflex::open_toolpath(path);
    deflex::GcodeWriteBack out(path, "/dev/null");
    deflex::ToolpathPoint p;
    std::size_t n = 0;
    while (reader->next(p)) {
      out.add(p, p.position_m + deflex::Vector3(1e-4, -1e-4, 0.0));
      ++n;
    }
    out.finish();
    points = n;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(points) * state.iterations());
  state.counters["points"] = static_cast<double>(points);
  state.counters["peak_rss_growth_MiB"] = peak_rss_mib() - rss_before;
}
BENCHMARK(BM_GcodeWriteBack)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
