// CSV reading and writing per row: the streaming reader over a 100,000-row file of the offline
// output's width, and the writer's %.10g row into its buffer (to /dev/null, so the disk is left out).
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/format_number.hpp"

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

// The numbers of an offline row as they come: joint angles (deg), positions (mm), quaternion parts,
// configuration integers, forces (N), small deflections (mm, mrad), zeros and rounding noise.
std::vector<double> offline_like_numbers() {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> deg(-180.0, 180.0), mm(-2500.0, 2500.0), unit(-1.0, 1.0), force(-650.0, 650.0),
      small(-0.6, 0.6), noise(1e-13, 1e-11);
  std::vector<double> v;
  for (int r = 0; r < 1000; ++r) {
    v.push_back(r);
    for (int k = 0; k < 12; ++k) v.push_back(deg(rng));
    for (int k = 0; k < 6; ++k) v.push_back(mm(rng));
    for (int k = 0; k < 8; ++k) v.push_back(unit(rng));
    for (int k = 0; k < 4; ++k) v.push_back(static_cast<double>(static_cast<int>(unit(rng) * 3)));
    for (int k = 0; k < 3; ++k) v.push_back(force(rng));
    for (int k = 0; k < 3; ++k) v.push_back(0.0);
    for (int k = 0; k < 7; ++k) v.push_back(small(rng));
    for (int k = 0; k < 2; ++k) v.push_back(noise(rng));
  }
  return v;
}

// One number of that mix as "%.10g": deflex's formatter against std::to_chars (general, 10).
void BM_FormatG10(benchmark::State& state) {
  const std::vector<double> v = offline_like_numbers();
  char buf[64];
  std::size_t i = 0, bytes = 0;
  for (auto _ : state) {
    bytes += static_cast<std::size_t>(deflex::format_g10(buf, v[i]) - buf);
    i = i + 1 == v.size() ? 0 : i + 1;
  }
  benchmark::DoNotOptimize(bytes);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FormatG10);

void BM_ToCharsG10(benchmark::State& state) {
  const std::vector<double> v = offline_like_numbers();
  char buf[64];
  std::size_t i = 0, bytes = 0;
  for (auto _ : state) {
    bytes +=
        static_cast<std::size_t>(std::to_chars(buf, buf + sizeof buf, v[i], std::chars_format::general, 10).ptr - buf);
    i = i + 1 == v.size() ? 0 : i + 1;
  }
  benchmark::DoNotOptimize(bytes);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ToCharsG10);

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
