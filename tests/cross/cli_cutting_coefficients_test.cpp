// `deflex cutting-coefficients` end to end: slot-cut logs simulated from the textbook per-tooth
// formulas (tests/machining/textbook_milling.hpp) fitted into a coefficient file that the milling
// spec reads back; bad cuts refused with exit 2 and nothing written.
#include <filesystem>
#include <fstream>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "cross/cli_runner.hpp"
#include "deflex/machining/cutting_coefficients.hpp"
#include "machining/textbook_milling.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

/// A slot-cut log at `feed_mm_min`, 9000 rpm, 3 flutes, ap 4 mm: 2 s of cut sampled at 7 kHz (not
/// locked to the tooth frequency, as a sensor's clock is not), forces on the tool in the cut frame's
/// axes (x feed, y normal, z tool axis), with noise.
std::string write_log(const fs::path& dir, double feed_mm_min, unsigned seed) {
  test::TextbookCut t;
  t.fz_m = feed_mm_min * 1e-3 / (9000.0 * 3);
  t.z_hi_m = 4e-3;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 10.0);
  const fs::path path = dir / fmt::format("slot_{:g}.csv", feed_mm_min);
  std::ofstream f(path);
  f << "t_s,fx_N,fy_N,fz_N\n";
  const double dt = 1.0 / 7000.0;
  for (int i = 0; i < 14000; ++i) {
    const Vector3 w = test::textbook_wrench(t, 2 * kPi * 150.0 * i * dt + 0.1 * seed, 1).head<3>();
    f << fmt::format("{:.7f},{:.3f},{:.3f},{:.3f}\n", i * dt, w.x() + noise(rng), w.y() + noise(rng),
                     w.z() + noise(rng));
  }
  return path.string();
}

struct Logs {
  fs::path dir;
  std::vector<std::string> files;
  Logs() {
    dir = fs::temp_directory_path() / fmt::format("deflex_cutcoef_{}", ::getpid());
    fs::create_directories(dir);
    unsigned seed = 1;
    for (double feed : {900.0, 1800.0, 2700.0, 3600.0}) files.push_back(write_log(dir, feed, seed++));
  }
  ~Logs() { fs::remove_all(dir); }
  std::string cut(int i, const std::string& extra = "") const {
    const double feeds[] = {900.0, 1800.0, 2700.0, 3600.0};
    return fmt::format(" --cut 'log={},F_mm_min={:g},S_rpm=9000,ap_mm=4{}'", files[static_cast<std::size_t>(i)],
                       feeds[i], extra);
  }
};

TEST(CliCuttingCoefficients, FitsSlotLogsIntoAFileTheMillingSpecReads) {
  const Logs logs;
  const std::string out = (logs.dir / "al7075.yaml").string();
  const auto r =
      test::run_cli(fmt::format("cutting-coefficients {} {} {} {} --cutter 'diameter_mm=10,flutes=3' "
                                "--material Al7075-T6 -o {}",
                                logs.cut(0), logs.cut(1), logs.cut(2), logs.cut(3), out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Ktc_N_mm2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("wrote " + out), std::string::npos);
  const MillingSpec spec = parse_milling_spec("milling:file=" + out);
  EXPECT_NEAR(spec.coefficients.k.ktc_n_m2, 767e6, 0.01 * 767e6);
  EXPECT_NEAR(spec.coefficients.k.krc_n_m2, 168.8e6, 0.01 * 168.8e6);
  EXPECT_NEAR(spec.coefficients.k.kac_n_m2, 222e6, 0.01 * 222e6);
  EXPECT_NEAR(spec.coefficients.k.kte_n_m, 27.7e3, 0.01 * 27.7e3);
  EXPECT_NEAR(spec.coefficients.k.kre_n_m, 26.6e3, 0.01 * 26.6e3);
  EXPECT_EQ(spec.coefficients.material, "Al7075-T6");
  ASSERT_TRUE(spec.coefficients.standard_error.has_value());
  EXPECT_NE(spec.coefficients.source.find("slot_900.csv"), std::string::npos);
}

TEST(CliCuttingCoefficients, BadCutsExitTwoAndWriteNothing) {
  const Logs logs;
  const std::string out = (logs.dir / "out.yaml").string();
  const std::string cutter = " --cutter 'diameter_mm=10,flutes=3' -o " + out;
  struct Case {
    std::string args;
    std::string says;
  };
  const Case cases[] = {
      {logs.cut(0) + cutter, "two or more --cut"},
      {logs.cut(0) + " --cut 'log=" + logs.files[1] + ",F_mm_min=0,S_rpm=9000,ap_mm=4'" + cutter, "'F_mm_min': 0"},
      {logs.cut(0) + " --cut 'log=" + logs.files[1] + ",F_mm_min=900,S_rpm=0,ap_mm=4'" + cutter, "'S_rpm': 0 rpm"},
      {logs.cut(0) + " --cut 'log=" + logs.files[1] + ",F_mm_min=900,S_rpm=9000'" + cutter, "'ap_mm' is required"},
      {logs.cut(0) + logs.cut(1, ",feed_axis=+q") + cutter, "'+q' is not one of"},
      {logs.cut(0) + logs.cut(1, ",feed_axis=z") + cutter, "two different axes"},
      {logs.cut(0) + logs.cut(1, ",window_s=3;2") + cutter, "'window_s': 3;2 s"},
      {logs.cut(0) + logs.cut(1, ",window_s=0;0.001") + cutter, "revolutions"},
      {logs.cut(0) + " --cut 'log=" + (logs.dir / "none.csv").string() + ",F_mm_min=900,S_rpm=9000,ap_mm=4'" + cutter,
       "none.csv"},
      {logs.cut(0) + logs.cut(1) + " --cutter 'diameter_mm=10,flutes=0' -o " + out, "flutes: 0"},
      // Read as the force on the workpiece, the logs give negative coefficients far beyond their errors.
      {logs.cut(0, ",force_on=workpiece") + logs.cut(1, ",force_on=workpiece") + logs.cut(2, ",force_on=workpiece") +
           cutter,
       "do not follow the slot model"},
  };
  for (const Case& c : cases) {
    const auto r = test::run_cli("cutting-coefficients " + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}

TEST(CliCuttingCoefficients, TwoCutsFitButWarn) {
  const Logs logs;
  const std::string out = (logs.dir / "two.yaml").string();
  const auto r = test::run_cli(fmt::format("cutting-coefficients {} {} --cutter 'diameter_mm=10,flutes=3' -o {}",
                                           logs.cut(0), logs.cut(3), out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: only 2 distinct feeds per tooth"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("no standard error"), std::string::npos) << r.out;
  EXPECT_FALSE(parse_milling_spec("milling:file=" + out).coefficients.standard_error.has_value());
}

}  // namespace
}  // namespace deflex
