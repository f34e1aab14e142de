// CSV reading and writing per row: the streaming reader over a 100,000-row file of the offline
// output's width, and the writer's %.10g row into its buffer (to /dev/null, so the disk is left out).
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "deflex/model/csv_table.hpp"

namespace {

constexpr std::size_t kColumns = 42;  // deflex offline's CSV for a 6-joint arm

std::vector<std::string> header() {
  std::vector<std::string> h;
  for (std::size_t i = 0; i < kColumns; ++i) {
    h.push_back(fmt::format("c{}_mm", i));
  }
  return h;
}

std::vector<double> random_row(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-2000.0, 2000.0);
  std::vector<double> row(kColumns);
  for (double& v : row) {
    v = u(rng);
  }
  return row;
}

void BM_CsvWriteRow(benchmark::State& state) {
  std::mt19937_64 rng(1);
  const std::vector<double> row = random_row(rng);
  deflex::CsvWriter w("/dev/null", header());
  for (auto _ : state) {
    w.row(row);
  }
  w.finish();
  state.SetItemsProcessed(state.iterations());
  state.counters["cells_per_row"] = static_cast<double>(kColumns);
}
BENCHMARK(BM_CsvWriteRow);

void BM_CsvReadRows(benchmark::State& state) {
  const auto path = std::filesystem::temp_directory_path() / "deflex_io_bench.csv";
  const std::size_t rows = 100000;
  {
    std::mt19937_64 rng(2);
    deflex::CsvWriter w(path.string(), header());
    for (std::size_t r = 0; r < rows; ++r) {
      w.row(random_row(rng));
    }
    w.finish();
  }
  double sum = 0.0;
  for (auto _ : state) {
    deflex::CsvReader reader(path.string());
    while (reader.next()) {
      sum += reader[0];
    }
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(rows));
  state.counters["file_MB"] = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
  std::filesystem::remove(path);
}
BENCHMARK(BM_CsvReadRows)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
