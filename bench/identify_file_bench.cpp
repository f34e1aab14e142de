// Identification from a file of a million rows (issue 28, item 4: under 2 s of CPU and 50 MB), beside its
// anchor in the same run: a one-pass streamed least squares over the same file, through the same reader and the
// same regressor, that sums the normal equations and solves them once (no robust re-weighting, no c >= 0, no
// identifiability checks, no standard errors). The anchor is what the file and the model cost at the least; the
// difference is what the estimator costs.
//
// Data: DEFLEX_IDENTIFY_DATA, else /tmp/deflex_scale_identify_1000000.csv (the shipped KR 210 measurements
// repeated, as bench/scale_bench.py writes it; written here when missing). Whole-program CPU time and peak memory
// of both: bench/scale_bench.py --identify-only.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <benchmark/benchmark.h>
#include <Eigen/Cholesky>

#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/robotfile/robot_io.hpp"

namespace {

using namespace deflex;

constexpr int kRows = 1000000;

std::string source_path(const std::string& relative) { return std::string(DEFLEX_SOURCE_DIR) + "/" + relative; }

// The shipped measurements repeated to kRows data rows, as bench/scale_bench.py writes them.
std::string data_file() {
  if (const char* env = std::getenv("DEFLEX_IDENTIFY_DATA")) {
    return env;
  }
  std::string path = "/tmp/deflex_scale_identify_" + std::to_string(kRows) + ".csv";
  if (!std::filesystem::exists(path)) {
    std::ifstream in(source_path("examples/identify/kr210_synthetic_measurements.csv"));
    std::string header, line;
    std::vector<std::string> rows;
    while (std::getline(in, line)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') {
        continue;
      }
      (header.empty() ? header : rows.emplace_back()) = line;
    }
    const std::string tmp = path + ".part";
    {
      std::ofstream out(tmp);
      out << header << '\n';
      for (int i = 0; i < kRows; ++i) {
        out << rows[static_cast<std::size_t>(i) % rows.size()] << '\n';
      }
    }
    std::filesystem::rename(tmp, path);
  }
  return path;
}

const RobotModel& robot() {
  static const RobotModel model = load_robot(source_path("examples/identify/kr210_true_stiffness.yaml"));
  return model;
}

// What `deflex identify --robot examples/identify/kr210_true_stiffness.yaml --data FILE` computes.
void BM_IdentifyFile(benchmark::State& state) {
  const std::string path = data_file();
  for (auto _ : state) {
    StiffnessMeasurementReader reader(path);
    StiffnessIdentifier identifier(robot(), IdentificationOptions{});
    for (StiffnessMeasurement m; reader.next(m);) {
      identifier.add(m);
    }
    const StiffnessEstimate est = identifier.solve();
    benchmark::DoNotOptimize(est.stiffness_nm_per_rad.data());
    state.counters["irls_iterations"] = est.iterations;
    state.counters["measurements"] = est.measurements;
  }
}
BENCHMARK(BM_IdentifyFile)->Unit(benchmark::kMillisecond)->Iterations(1);

// The anchor: one pass, sum A_i^T A_i and A_i^T b_i, one Cholesky solve.
void BM_OnePassLeastSquaresAnchor(benchmark::State& state) {
  const std::string path = data_file();
  const RobotModel& model = robot();
  const int n = model.dof();
  for (auto _ : state) {
    StiffnessMeasurementReader reader(path);
    Workspace ws(model);
    Jacobian block(6, n);
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd h = Eigen::VectorXd::Zero(n);
    int count = 0;
    for (StiffnessMeasurement m; reader.next(m);) {
      stiffness_regressor(model, ws, m.q, m.wrench_base, block);
      const auto A = block.topRows<3>();
      G.noalias() += m.weight * (A.transpose() * A);
      h.noalias() += m.weight * (A.transpose() * m.dp_m);
      ++count;
    }
    const Eigen::VectorXd c = G.ldlt().solve(h);
    benchmark::DoNotOptimize(c.data());
    state.counters["measurements"] = count;
  }
}
BENCHMARK(BM_OnePassLeastSquaresAnchor)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
