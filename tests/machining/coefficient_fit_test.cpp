// The slot-cut fit: logs simulated from the textbook per-tooth formulas (textbook_milling.hpp) with
// sensor noise and bias, written as the force sensor's CSV in a wrist sensor's axes, fitted back; the
// true coefficients within three standard errors for one seed, and the standard errors themselves
// against the spread of the estimates over many seeds. Then what the fit refuses or warns about.
#include <cmath>
#include <fstream>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "deflex/machining/coefficient_fit.hpp"
#include "deflex/text/errors.hpp"
#include "machining/textbook_milling.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using test::TextbookCut;

constexpr double kRpm = 9000.0;
constexpr int kFlutes = 3;
const CuttingCoefficients kTrue{767e6, 168.8e6, 222e6, 27.7e3, 26.6e3, 0.7e3};

struct SimCut {
  double fz_m, ap_m;
};

/// Samples of the slot force on the tool (cut frame: feed, normal, axis) at `per_period` samples a
/// tooth period over `periods` periods, from a random spindle phase, plus white noise.
std::vector<Vector3> simulate(const SimCut& c, int periods, int per_period, double noise_n, std::mt19937& rng) {
  TextbookCut t;
  t.flutes = kFlutes;
  t.fz_m = c.fz_m;
  t.z_hi_m = c.ap_m;
  t.ktc = kTrue.ktc_n_m2;
  t.krc = kTrue.krc_n_m2;
  t.kac = kTrue.kac_n_m2;
  t.kte = kTrue.kte_n_m;
  t.kre = kTrue.kre_n_m;
  t.kae = kTrue.kae_n_m;
  std::uniform_real_distribution<double> phase(0.0, 2 * kPi);
  std::normal_distribution<double> noise(0.0, noise_n);
  const double theta0 = phase(rng);
  std::vector<Vector3> out;
  for (int i = 0; i < periods * per_period; ++i) {
    const double theta = theta0 + 2 * kPi / kFlutes * i / per_period;
    out.push_back(test::textbook_wrench(t, theta, 1).head<3>() + Vector3(noise(rng), noise(rng), noise(rng)));
  }
  return out;
}

const std::vector<SimCut> kCuts = {{0.04e-3, 4e-3}, {0.07e-3, 3e-3}, {0.10e-3, 4e-3},
                                   {0.13e-3, 3e-3}, {0.16e-3, 4e-3}, {0.19e-3, 3e-3}};

TEST(CoefficientFit, RecoversKnownCoefficientsFromSimulatedSensorLogs) {
  std::mt19937 rng(20261);
  std::vector<SlotCut> cuts;
  const double dt = 60.0 / kRpm / kFlutes / 20.0;  // 20 samples a tooth period
  const Vector3 bias(12.0, -4.0, 35.0);            // the spindle's weight and the sensor's offset
  for (std::size_t k = 0; k < kCuts.size(); ++k) {
    const auto samples = simulate(kCuts[k], 300, 20, 25.0, rng);
    // A wrist sensor mounted with its y against the feed and its x along the tool axis: the cut
    // frame's (feed, normal, axis) are (-y, -z, +x) of the sensor.
    const std::string path = ::testing::TempDir() + fmt::format("slot{}.csv", k);
    std::ofstream f(path);
    f << "# simulated slot cut\nt_s,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm\n";
    for (int i = 0; i < 500; ++i) {  // air: spindle on, not cutting
      f << fmt::format("{:.7f},{:.4f},{:.4f},{:.4f},0,0,0\n", i * dt, bias.x(), bias.y(), bias.z());
    }
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Vector3& s = samples[i];
      const Vector3 sensor = bias + Vector3(s[2], -s[0], -s[1]);
      f << fmt::format("{:.7f},{:.4f},{:.4f},{:.4f},0,0,0\n", static_cast<double>(500 + i) * dt, sensor.x(), sensor.y(),
                       sensor.z());
    }
    f.close();
    SlotLogOptions o;
    o.feed_axis = 1;
    o.feed_sign = -1.0;
    o.tool_axis = 0;
    o.window_from_s = 500 * dt;
    o.air_to_s = 499.5 * dt;
    const SlotLogMean m = read_slot_log(path, o);
    EXPECT_EQ(m.samples, 6000);
    EXPECT_EQ(m.air_samples, 500);
    cuts.push_back({kCuts[k].fz_m, kCuts[k].ap_m, kFlutes, SpindleTurn::kClockwise, m.mean_force_n, path});
  }
  const CoefficientFit fit = fit_cutting_coefficients(cuts);
  EXPECT_TRUE(fit.warnings.empty()) << fit.warnings.front();
  const double truth[6] = {kTrue.ktc_n_m2, kTrue.krc_n_m2, kTrue.kac_n_m2, kTrue.kte_n_m, kTrue.kre_n_m, kTrue.kae_n_m};
  const double got[6] = {fit.k.ktc_n_m2, fit.k.krc_n_m2, fit.k.kac_n_m2, fit.k.kte_n_m, fit.k.kre_n_m, fit.k.kae_n_m};
  const double se[6] = {fit.standard_error.ktc_n_m2, fit.standard_error.krc_n_m2, fit.standard_error.kac_n_m2,
                        fit.standard_error.kte_n_m,  fit.standard_error.kre_n_m,  fit.standard_error.kae_n_m};
  for (int i = 0; i < 6; ++i) {
    ASSERT_TRUE(std::isfinite(se[i]) && se[i] > 0.0) << kCoefficientKeys[i];
    EXPECT_LT(std::abs(got[i] - truth[i]), 3.0 * se[i]) << kCoefficientKeys[i] << " " << got[i] << " +- " << se[i];
  }
  // And not trivially so: the cutting coefficients' standard errors are a few percent of them (the
  // force's jumps at 20 samples a tooth period alias into each mean more than the noise does).
  for (int i = 0; i < 3; ++i) EXPECT_LT(se[i], 0.06 * truth[i]) << kCoefficientKeys[i];
  EXPECT_EQ(fit.distinct_feeds, 6);
}

TEST(CoefficientFit, StandardErrorsMatchTheSpreadOverManySeeds) {
  const int seeds = 200;
  std::vector<std::array<double, 6>> estimates, errors;
  std::mt19937 rng(7);
  for (int s = 0; s < seeds; ++s) {
    std::vector<SlotCut> cuts;
    for (const SimCut& c : kCuts) {
      Vector3 mean = Vector3::Zero();
      const auto samples = simulate(c, 100, 20, 60.0, rng);
      for (const Vector3& v : samples) mean += v;
      cuts.push_back({c.fz_m, c.ap_m, kFlutes, SpindleTurn::kClockwise, mean / samples.size(), ""});
    }
    const CoefficientFit fit = fit_cutting_coefficients(cuts);
    estimates.push_back({fit.k.ktc_n_m2, fit.k.krc_n_m2, fit.k.kac_n_m2, fit.k.kte_n_m, fit.k.kre_n_m, fit.k.kae_n_m});
    errors.push_back({fit.standard_error.ktc_n_m2, fit.standard_error.krc_n_m2, fit.standard_error.kac_n_m2,
                      fit.standard_error.kte_n_m, fit.standard_error.kre_n_m, fit.standard_error.kae_n_m});
  }
  const double truth[6] = {kTrue.ktc_n_m2, kTrue.krc_n_m2, kTrue.kac_n_m2, kTrue.kte_n_m, kTrue.kre_n_m, kTrue.kae_n_m};
  for (int i = 0; i < 6; ++i) {
    if (i == 5) continue;  // Kae (0.7 N/mm) sits at zero within its error: the fit clips it, see below
    double sum = 0.0, sq = 0.0, se2 = 0.0;
    for (int s = 0; s < seeds; ++s) {
      sum += estimates[s][i];
      sq += (estimates[s][i] - truth[i]) * (estimates[s][i] - truth[i]);
      se2 += errors[s][i] * errors[s][i];
    }
    const double spread = std::sqrt(sq / seeds), stated = std::sqrt(se2 / seeds);
    // The stated standard error is the spread's estimate: within a factor 1.3 over 200 seeds.
    EXPECT_GT(stated / spread, 1.0 / 1.3) << kCoefficientKeys[i];
    EXPECT_LT(stated / spread, 1.3) << kCoefficientKeys[i];
    // Unbiased: the mean estimate within 3 standard errors of the mean.
    EXPECT_LT(std::abs(sum / seeds - truth[i]), 3.0 * spread / std::sqrt(seeds)) << kCoefficientKeys[i];
  }
}

SlotCut exact_slot(double fz_m, double ap_m, const CuttingCoefficients& k, SpindleTurn turn) {
  const double N = kFlutes, s = turn_sign(turn);
  return {fz_m,
          ap_m,
          kFlutes,
          turn,
          Vector3(-N * ap_m * (fz_m * k.krc_n_m2 / 4 + k.kre_n_m / kPi),
                  s * N * ap_m * (fz_m * k.ktc_n_m2 / 4 + k.kte_n_m / kPi),
                  -N * ap_m * (fz_m * k.kac_n_m2 / kPi + k.kae_n_m / 2)),
          "exact"};
}

TEST(CoefficientFit, ExactSlotsGiveExactCoefficientsEitherWayOfTurning) {
  for (SpindleTurn turn : {SpindleTurn::kClockwise, SpindleTurn::kCounterClockwise}) {
    const std::vector<SlotCut> cuts = {exact_slot(0.05e-3, 4e-3, kTrue, turn), exact_slot(0.1e-3, 2e-3, kTrue, turn),
                                       exact_slot(0.15e-3, 5e-3, kTrue, turn)};
    const CoefficientFit fit = fit_cutting_coefficients(cuts);
    EXPECT_NEAR(fit.k.ktc_n_m2, kTrue.ktc_n_m2, 1e-6 * kTrue.ktc_n_m2);
    EXPECT_NEAR(fit.k.kte_n_m, kTrue.kte_n_m, 1e-6 * kTrue.kte_n_m);
    EXPECT_NEAR(fit.k.kac_n_m2, kTrue.kac_n_m2, 1e-6 * kTrue.kac_n_m2);
    EXPECT_NEAR(fit.k.kae_n_m, kTrue.kae_n_m, 1e-6 * kTrue.kte_n_m);
    EXPECT_NEAR(fit.residual_rms_n.norm(), 0.0, 1e-6);
  }
}

TEST(CoefficientFit, WarnsWhenTheFeedsDoNotSpanEnough) {
  const CoefficientFit two =
      fit_cutting_coefficients({exact_slot(0.05e-3, 4e-3, kTrue, {}), exact_slot(0.15e-3, 4e-3, kTrue, {})});
  ASSERT_EQ(two.warnings.size(), 1u);
  EXPECT_NE(two.warnings[0].find("only 2 distinct feeds"), std::string::npos);
  EXPECT_TRUE(std::isnan(two.standard_error.ktc_n_m2));
  const CoefficientFit close =
      fit_cutting_coefficients({exact_slot(0.10e-3, 4e-3, kTrue, {}), exact_slot(0.12e-3, 4e-3, kTrue, {}),
                                exact_slot(0.14e-3, 4e-3, kTrue, {})});
  ASSERT_EQ(close.warnings.size(), 1u);
  EXPECT_NE(close.warnings[0].find("a ratio of 1.40"), std::string::npos);
}

TEST(CoefficientFit, RefusesWhatCannotBeFitted) {
  EXPECT_NE(test::error_of([] {
              (void)fit_cutting_coefficients({exact_slot(0.05e-3, 4e-3, kTrue, {})});
            }).find("at least two"),
            std::string::npos);
  EXPECT_NE(
      test::error_of([] {
        (void)fit_cutting_coefficients({exact_slot(0.05e-3, 4e-3, kTrue, {}), exact_slot(0.05e-3, 2e-3, kTrue, {})});
      }).find("at least two different feeds"),
      std::string::npos);
  SlotCut zero_feed = exact_slot(0.05e-3, 4e-3, kTrue, {});
  zero_feed.fz_m = 0.0;
  zero_feed.label = "cut3.csv";
  EXPECT_NE(test::error_of([&] {
              (void)fit_cutting_coefficients({zero_feed, exact_slot(0.1e-3, 4e-3, kTrue, {})});
            }).find("cut3.csv: feed per tooth 0 mm"),
            std::string::npos);
  // A log read as the force on the workpiece when it was the force on the tool: every coefficient
  // comes out negative, far beyond its error.
  std::vector<SlotCut> flipped = {exact_slot(0.05e-3, 4e-3, kTrue, {}), exact_slot(0.1e-3, 4e-3, kTrue, {}),
                                  exact_slot(0.15e-3, 4e-3, kTrue, {})};
  for (SlotCut& c : flipped) c.mean_force_n = -c.mean_force_n;
  flipped[1].mean_force_n *= 1.01;  // some scatter, so the standard errors are finite
  EXPECT_NE(test::error_of([&] { (void)fit_cutting_coefficients(flipped); }).find("do not follow the slot model"),
            std::string::npos);
  // A unit slip (ap in m read as mm: forces 1000 times too large) is refused by the coefficient ranges.
  std::vector<SlotCut> slip = {exact_slot(0.05e-3, 4e-3, kTrue, {}), exact_slot(0.1e-3, 4e-3, kTrue, {})};
  for (SlotCut& c : slip) c.ap_m *= 1e-3;
  EXPECT_NE(test::error_of([&] { (void)fit_cutting_coefficients(slip); }).find("the fitted coefficients: Ktc_N_mm2"),
            std::string::npos);
}

TEST(CoefficientFit, ANegativeCoefficientWithinItsErrorIsWrittenAsZero) {
  CuttingCoefficients k = kTrue;
  k.kae_n_m = 0.0;
  std::vector<SlotCut> cuts = {exact_slot(0.05e-3, 4e-3, k, {}), exact_slot(0.1e-3, 4e-3, k, {}),
                               exact_slot(0.15e-3, 4e-3, k, {}), exact_slot(0.2e-3, 4e-3, k, {})};
  // Scatter on the axial force that pulls the intercept below zero.
  cuts[0].mean_force_n[2] += 2.0;
  cuts[1].mean_force_n[2] -= 1.0;
  cuts[3].mean_force_n[2] += 0.5;
  const CoefficientFit fit = fit_cutting_coefficients(cuts);
  EXPECT_EQ(fit.k.kae_n_m, 0.0);
  ASSERT_FALSE(fit.warnings.empty());
  EXPECT_NE(fit.warnings.back().find("Kae_N_mm fitted -"), std::string::npos);
}

TEST(SlotLog, TheWindowIsShortenedToWholeRevolutions) {
  // 1 + sin(revolution angle) at 600 rpm (10 Hz), sampled at 1 kHz over 0.2349 s: 2.349 revolutions,
  // whose mean is 1.05; over the 2 whole ones it is 1.
  const std::string path = ::testing::TempDir() + "rev.csv";
  {
    std::ofstream f(path);
    f << "t_s,fx_N,fy_N,fz_N\n";
    for (int i = 0; i <= 234; ++i) {
      const double t = i * 1e-3;
      f << fmt::format("{:.4f},{:.12f},0,0\n", t, 1.0 + std::sin(2 * kPi * 10.0 * t));
    }
  }
  SlotLogOptions o;
  const SlotLogMean all = read_slot_log(path, o);
  EXPECT_GT(std::abs(all.mean_force_n.x() - 1.0), 0.02);
  o.spindle_rpm = 600.0;
  const SlotLogMean whole = read_slot_log(path, o);
  EXPECT_EQ(whole.revolutions, 2.0);
  EXPECT_EQ(whole.samples, 200);
  EXPECT_NEAR(whole.mean_force_n.x(), 1.0, 1e-9);
}

TEST(SlotLog, BadLogsAreRefusedNamingTheFileAndLine) {
  const std::string dir = ::testing::TempDir();
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + name) << text;
    return dir + name;
  };
  SlotLogOptions o;
  const std::string back = write("back.csv", "t_s,fx_N,fy_N,fz_N\n0,1,2,3\n0.002,1,2,3\n0.001,1,2,3\n");
  EXPECT_NE(test::error_of([&] { (void)read_slot_log(back, o); }).find("back.csv:4: column 't_s'"), std::string::npos);
  const std::string ok = write("ok.csv", "t_s,fx_N,fy_N,fz_N\n0,1,2,3\n0.001,1,2,3\n0.002,1,2,3\n");
  o.window_from_s = 5.0;
  EXPECT_NE(test::error_of([&] { (void)read_slot_log(ok, o); }).find("ok.csv: the cut window 5..end s holds 0 samples"),
            std::string::npos);
  o = SlotLogOptions();
  o.tool_axis = 0;
  EXPECT_NE(test::error_of([&] { (void)read_slot_log(ok, o); }).find("two different axes"), std::string::npos);
  const std::string extra = write("extra.csv", "t_s,fx_N,fy_N,fz_N,speed\n0,1,2,3,4\n0.001,1,2,3,4\n");
  EXPECT_NE(test::error_of([&] { (void)read_slot_log(extra, SlotLogOptions()); }).find("speed"), std::string::npos);
  const std::string nan = write("nan.csv", "t_s,fx_N,fy_N,fz_N\n0,1,nan,3\n0.001,1,2,3\n");
  EXPECT_NE(test::error_of([&] { (void)read_slot_log(nan, SlotLogOptions()); }).find("nan.csv:2"), std::string::npos);
}

}  // namespace
}  // namespace deflex
