// The machining study, quick, end to end: the coefficients the cell fitted from its own slot-cut logs
// against the truth it drew; the uncompensated contour wall against an independent closed form (the
// true arm's static solve under the revolution-average force of a per-tooth sum, textbook_milling.hpp,
// with the chip's feedback as a fixed point here); and every strategy's walls against the
// uncompensated ones. The test reads the cell's truth; the strategies never do.
#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <memory>

#include "deflex/cell/true_robot.hpp"
#include "deflex/study/detail/machining_run.hpp"
#include "deflex/study/machining_study.hpp"
#include "deflex/text/errors.hpp"
#include "machining/textbook_milling.hpp"

namespace deflex::study {
namespace {

// The quick study takes 17 s of CPU, and ctest runs every test in a process of its own: the checks
// below share one run, in the one test at the end of the file, each under its own name.
std::unique_ptr<MachiningStudyOutput> out_;
const MachiningRun& run(MachiningStrategy s, double feed, int seed) {
  for (const MachiningRun& r : out_->runs) {
    if (r.strategy == s && r.feed_mm_min == feed && r.seed_index == seed) return r;
  }
  throw Error("no such run");
}

void the_table_has_every_strategy_feed_and_seed() {
  ASSERT_EQ(out_->seeds, 2);
  EXPECT_EQ(out_->runs.size(), 2u * 2u * 4u);
  EXPECT_EQ(out_->rows.size(), 2u * 4u);
  for (const MachiningRow& r : out_->rows) {
    EXPECT_EQ(r.climb_mean.n, 2);
  }
  const std::string table = machining_table_text(*out_);
  EXPECT_NE(table.find("climb wall um"), std::string::npos);
  EXPECT_NE(machining_table_csv(*out_).find("climb_wall_mean_um"), std::string::npos);
}

// Slot cuts at three feeds per tooth, 3 mm deep, logged by the sensor (noise, crosstalk, the tare,
// the arm's yield in the chip) and fitted by the library. The tangential and axial sets and the edge
// terms follow the truth closely; the radial cutting coefficient, from the feed-direction force (a
// quarter of the normal one, so whatever leaks the normal force into the feed axis weighs four times
// as much in it), comes out 9-17 % high on every seed: within 20 %. Most of that is the sensor's
// calibration errors the user never learns (its turn about the tool axis, its sensitivities): with them
// switched off the same cuts fit Krc 3 % high, against 12 % with them.
void the_fitted_coefficients_follow_the_cells_drawn_truth() {
  ASSERT_EQ(out_->fits.size(), 2u);
  for (const MachiningFit& f : out_->fits) {
    const CuttingCoefficients& k = f.fit.k;
    const CuttingCoefficients& t = f.truth;
    EXPECT_NEAR(k.ktc_n_m2, t.ktc_n_m2, 0.05 * t.ktc_n_m2) << "seed " << f.seed_index;
    EXPECT_NEAR(k.kac_n_m2, t.kac_n_m2, 0.10 * t.kac_n_m2) << "seed " << f.seed_index;
    EXPECT_NEAR(k.krc_n_m2, t.krc_n_m2, 0.20 * t.krc_n_m2) << "seed " << f.seed_index;
    EXPECT_NEAR(k.kte_n_m, t.kte_n_m, 0.10 * t.kte_n_m) << "seed " << f.seed_index;
    EXPECT_NEAR(k.kre_n_m, t.kre_n_m, 0.15 * t.kre_n_m) << "seed " << f.seed_index;
    // The truth is not the published set (15 % spread): a fit that returned the published set fails.
    EXPECT_GT(std::abs(t.ktc_n_m2 / out_->published.ktc_n_m2 - 1.0), 0.01);
  }
}

// The revolution-average wrench (stock frame: feed x, axis z, M3, the material on -y: down milling)
// of the independent per-tooth sum at a radial width and depth.
Vector6 textbook_side_cut(const CuttingCoefficients& k, double ae, double ap, double fz) {
  const Cutter cutter = study_cutter();
  test::TextbookCut c;
  c.diameter_m = cutter.diameter_m;
  c.flutes = cutter.flutes;
  c.helix_rad = 0.0;  // a revolution's average is the same for any helix on a uniform engagement
  c.fz_m = fz;
  c.m3 = true;
  const double sweep = std::acos(1.0 - 2.0 * ae / cutter.diameter_m);
  c.entry_rad = kPi - sweep;
  c.exit_rad = kPi;
  c.z_lo_m = 0.0;
  c.z_hi_m = ap;
  c.ktc = k.ktc_n_m2;
  c.krc = k.krc_n_m2;
  c.kac = k.kac_n_m2;
  c.kte = k.kte_n_m;
  c.kre = k.kre_n_m;
  c.kae = k.kae_n_m;
  return test::textbook_average(c, 36000, 1);
}

// The contour's first leg takes 2 mm off the block's untouched face y = 20 mm, 4 mm deep, in down
// milling: the wall it leaves stands off by the tool's deflection along y less the runout (the
// outermost tooth cuts it). The deflection: the true arm's static solve (all its elastic effects) at
// the program's joints under the per-tooth sum's force at the width and depth the deflection itself
// leaves (a fixed point).
void the_uncompensated_contour_wall_is_where_the_closed_form_puts_it() {
  const MillCell mc = build_mill_cell(1);  // seed index 0's cell, rebuilt: the same draws
  const MillPart part = make_mill_part(true);
  const MillPass& contour = part.passes.back();
  const double feed = out_->feeds_mm_min.front();
  const double fz = feed / 60.0 * 1e-3 * 60.0 / (kStudySpindleRpm * study_cutter().flutes);
  const std::vector<PassProgram> programs =
      plan_passes(mc, {contour}, part.stock, MachiningStrategy::kUncompensated, feed, nullptr);
  // The station x = 4.5 mm: the whole arc in the material, the block's end 7.5 mm ahead.
  constexpr double kStation = 4.5e-3;
  std::size_t i = 0;
  while (programs[0].tips_workpiece_m[i].x() < kStation) ++i;
  const JointVector& q = programs[0].q[i];
  const cell::TrueRobot& robot = *mc.setup.robot;
  Workspace ws(robot.true_model());
  cell::TrueRobotState state = robot.initial_state(q);
  const Vector3 unloaded = robot.solve(ws, q, Wrench::Zero(), state);
  const Matrix3 r = mc.base_T_workpiece.linear();
  const MachiningFit& fit = out_->fits.front();
  Vector3 d = Vector3::Zero();
  for (int it = 0; it < 60; ++it) {
    const Vector6 w = textbook_side_cut(fit.truth, 2e-3 - d.y(), 4e-3 - d.z(), fz);
    Wrench wb;
    wb << r * w.head<3>(), r * w.tail<3>();
    d = r.transpose() * (robot.solve(ws, q, wb, state) - unloaded);
  }
  const double expected = d.y() - fit.truth_runout_m;
  ASSERT_GT(expected, 50e-6) << "a cut that hardly moves the tool tests nothing";
  // The study's probed wall (seed 1, the mid-depth row) about the station.
  const MachiningRun& uc = run(MachiningStrategy::kUncompensated, feed, 0);
  const WallTrace* wall = nullptr;
  for (const WallTrace& w : uc.walls) {
    if (w.name == "contour wall") wall = &w;
  }
  ASSERT_NE(wall, nullptr);
  double sum = 0.0;
  int n = 0;
  for (std::size_t j = 0; j < wall->along_m.size(); ++j) {
    if (std::abs(wall->along_m[j] - kStation) < 1.0e-3) {
      sum += wall->deviation_m[j];
      ++n;
    }
  }
  ASSERT_GT(n, 0);
  // The cell's drift over the pass, the probe's 1 um and the arm solved at its deflected pose while
  // the closed form's force is the nominal path's: 5 % and 5 um.
  EXPECT_NEAR(sum / n, expected, 0.05 * expected + 5e-6) << "closed form " << expected * 1e6 << " um";
}

// Each strategy leaves the down-milled walls (the pocket's and the contour's) and the pocket's width
// within 35 % of the uncompensated error, at both feeds, on every seed.
void every_strategy_reduces_the_wall_errors_by_a_stated_margin() {
  for (int seed = 0; seed < out_->seeds; ++seed) {
    for (double feed : out_->feeds_mm_min) {
      const PartErrors& uc = run(MachiningStrategy::kUncompensated, feed, seed).errors;
      ASSERT_GT(uc.climb_wall_mean_m, 100e-6);  // down milling pushes the tool off the wall: material left
      ASSERT_GT(uc.contour_wall_mean_m, 100e-6);
      EXPECT_LT(uc.conventional_wall_mean_m, 0.5 * uc.climb_wall_mean_m);  // up milling pushes less across
      for (MachiningStrategy s :
           {MachiningStrategy::kOffline, MachiningStrategy::kOnline, MachiningStrategy::kHybrid}) {
        const PartErrors& e = run(s, feed, seed).errors;
        EXPECT_LT(std::abs(e.climb_wall_mean_m), 0.35 * uc.climb_wall_mean_m) << to_string(s) << " " << feed;
        EXPECT_LT(std::abs(e.contour_wall_mean_m), 0.35 * uc.contour_wall_mean_m) << to_string(s) << " " << feed;
        EXPECT_LT(std::abs(e.pocket_width_error_m), 0.35 * std::abs(uc.pocket_width_error_m)) << to_string(s);
      }
    }
  }
}

// Every size the study gives the cell and the cuts lies inside the range data/cases/effect-ranges.yaml
// documents for it, with its source.
void every_size_is_inside_its_documented_range() {
  const YAML::Node ranges =
      YAML::LoadFile((std::filesystem::path(DEFLEX_SOURCE_DIR) / "data/cases/effect-ranges.yaml").string());
  const YAML::Node milling = ranges["milling"];
  ASSERT_TRUE(milling);
  const MachiningSizes& z = out_->sizes;
  auto check = [&](const char* key, double value) {
    const YAML::Node r = milling[key];
    ASSERT_TRUE(r && r["range"] && r["source"]) << key;
    EXPECT_FALSE(r["source"].as<std::string>().empty()) << key;
    EXPECT_GE(value, r["range"][0].as<double>()) << key;
    EXPECT_LE(value, r["range"][1].as<double>()) << key;
  };
  check("coefficient_spread_pct", z.coefficient_spread * 100.0);
  check("runout_um", z.runout_lo_m * 1e6);
  check("runout_um", z.runout_hi_m * 1e6);
  check("stock_cell_mm", z.stock_cell_m * 1e3);
  check("probe_noise_um", z.probe_noise_m * 1e6);
  ASSERT_FALSE(z.fz_m.empty());
  for (double fz : z.fz_m) check("feed_per_tooth_mm", fz * 1e3);
  ASSERT_FALSE(z.ap_m.empty());
  for (double ap : z.ap_m) check("axial_depth_mm", ap * 1e3);
}

TEST(MachiningStudyQuick, TheQuickStudyChecks) {
  MachiningStudyOptions o;
  o.quick = true;
  out_ = std::make_unique<MachiningStudyOutput>(run_machining_study(o));
  {
    SCOPED_TRACE("TheTableHasEveryStrategyFeedAndSeed");
    the_table_has_every_strategy_feed_and_seed();
  }
  {
    SCOPED_TRACE("TheFittedCoefficientsFollowTheCellsDrawnTruth");
    the_fitted_coefficients_follow_the_cells_drawn_truth();
  }
  {
    SCOPED_TRACE("TheUncompensatedContourWallIsWhereTheClosedFormPutsIt");
    the_uncompensated_contour_wall_is_where_the_closed_form_puts_it();
  }
  {
    SCOPED_TRACE("EveryStrategyReducesTheWallErrorsByAStatedMargin");
    every_strategy_reduces_the_wall_errors_by_a_stated_margin();
  }
  {
    SCOPED_TRACE("EverySizeIsInsideItsDocumentedRange");
    every_size_is_inside_its_documented_range();
  }
  out_.reset();
}

TEST(MachiningStudy, BadOptionsAreRefused) {
  MachiningStudyOptions o;
  o.seeds = -1;
  EXPECT_THROW((void)run_machining_study(o), InputError);
  o.seeds = 21;
  EXPECT_THROW((void)run_machining_study(o), InputError);
}

}  // namespace
}  // namespace deflex::study
