// The bias of the paper's mean-deformation figure when the unloaded reference is a dense, noisy
// tracker file (issue 16: 0.0418 mm reported for a 0.050 mm offset), and how much of it
// `deflex evaluate --mean-reference` removes. Measured through the program, on synthetic tracker
// files whose truth is known: a circle, the loaded laps 0.050 mm outside the unloaded ones, both
// with the same isotropic tracker noise.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cross/cli_runner.hpp"

namespace deflex::test {
namespace {

namespace fs = std::filesystem;

constexpr double kRadiusMm = 100.0;
constexpr double kOffsetMm = 0.050;
constexpr double kNoiseMm = 0.020;  // per axis, 1 sigma: a noisy tracker, to make the bias plain

// `laps` laps of the circle at 50 mm/s sampled at 1000 Hz, radius + offset, with noise (0: none).
void write_laps(const fs::path& p, double offset_mm, double noise_mm, int laps, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::ofstream out(p);
  out << "t_s,x_mm,y_mm,z_mm\n";
  const double omega = 50.0 / kRadiusMm;  // rad/s
  const int samples = static_cast<int>(laps * 2.0 * M_PI / omega * 1000.0);
  for (int i = 0; i <= samples; ++i) {
    const double t = i * 1e-3;
    const double r = kRadiusMm + offset_mm;
    out << fmt::format("{:.3f},{:.6f},{:.6f},{:.6f}\n", t, 1500.0 + r * std::cos(omega * t) + noise_mm * n(rng),
                       r * std::sin(omega * t) + noise_mm * n(rng), 1000.0 + noise_mm * n(rng));
  }
}

double mean_mm(const std::string& args) {
  const CliRun r = run_cli("evaluate --split-laps --json " + args);
  EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out)["mean_deformation_mm"].get<double>() : NAN;
}

TEST(EvaluateReferenceBias, MeanReferenceRemovesTheNoisyDenseReferencesBias) {
  const fs::path d = fs::temp_directory_path() / ("deflex_bias_" + std::to_string(::getpid()));
  fs::create_directories(d);
  write_laps(d / "unloaded.csv", 0.0, kNoiseMm, 3, 1);
  write_laps(d / "exact.csv", 0.0, 0.0, 1, 2);
  write_laps(d / "loaded.csv", kOffsetMm, kNoiseMm, 3, 3);
  const std::string loaded = " --loaded " + (d / "loaded.csv").string();
  // The loaded noise's own share, against the noise-free reference: the figure both methods aim at.
  const double truth = mean_mm("--unloaded " + (d / "exact.csv").string() + loaded);
  const double nearest = mean_mm("--unloaded " + (d / "unloaded.csv").string() + loaded);
  const double averaged = mean_mm("--mean-reference --unloaded " + (d / "unloaded.csv").string() + loaded);
  std::cout << fmt::format(
      "offset {:.4f} mm, noise {:.3f} mm: against the exact path {:.4f} mm, nearest noisy "
      "sample {:.4f} mm ({:+.1f}%), mean of the unloaded laps {:.4f} mm ({:+.1f}%)\n",
      kOffsetMm, kNoiseMm, truth, nearest, 100.0 * (nearest / truth - 1.0), averaged, 100.0 * (averaged / truth - 1.0));
  // The figure the paper's metric aims at: |offset + loaded noise| across the path, a bit over 0.05.
  EXPECT_GT(truth, kOffsetMm);
  EXPECT_LT(truth, kOffsetMm + kNoiseMm);
  // The documented bias: the nearest of many noisy samples lies closer than the path does.
  EXPECT_LT(nearest, 0.9 * truth);
  // What remains with --mean-reference (docs/evaluation.md quotes it): within 3 % of the truth.
  EXPECT_NEAR(averaged, truth, 0.03 * truth);
  fs::remove_all(d);
}

}  // namespace
}  // namespace deflex::test
