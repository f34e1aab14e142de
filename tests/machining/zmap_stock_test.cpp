// The height-map stock: a pocket's first slot is a full slot, a step-over pass a side cut with the
// closed-form immersion angles on the side the material is on, a pass in air touches nothing, the
// surfaces left by flat, bull-nose and ramping cutters against their geometry, and the force from the
// stock's engagement against the force from the same width and depth given directly.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/machining/milling_force.hpp"
#include "deflex/machining/zmap_stock.hpp"
#include "deflex/text/errors.hpp"
#include "support/allocation_guard.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

Cutter end_mill(double corner_mm = 0.0) {
  Cutter c;
  c.diameter_m = 10e-3;
  c.flutes = 3;
  c.helix_rad = deg_to_rad(30.0);
  c.corner_radius_m = corner_mm * 1e-3;
  return c;
}

// A 100 x 50 x 20 mm block, cell 0.1 mm.
ZMapStock block() { return ZMapStock::box(Vector3(0, 0, 0), Vector3(0.1, 0.05, 0.02), 0.1e-3); }

struct PassResult {
  Engagement last;  // the engagement at the last point inside the stock
  int in_air = 0;
  int cut = 0;
};

/// Moves the cutter in 1 mm steps from `from` to `to` (mm), querying each point before removing the
/// step that led there (stock.hpp's order), and keeps the engagement at `probe_x_mm`.
PassResult pass(ZMapStock& stock, const Cutter& cutter, Vector3 from_mm, Vector3 to_mm, double probe_x_mm,
                SpindleTurn turn = SpindleTurn::kClockwise) {
  PassResult r;
  CutFrame frame;
  EXPECT_TRUE(make_cut_frame(Vector3::UnitZ(), to_mm - from_mm, frame));
  const int steps = static_cast<int>(std::round((to_mm - from_mm).norm()));
  Vector3 prev = from_mm * 1e-3;
  for (int i = 1; i <= steps; ++i) {
    const Vector3 p = (from_mm + (to_mm - from_mm) * (static_cast<double>(i) / steps)) * 1e-3;
    Engagement e;
    const StockStatus s = stock.engagement(cutter, frame, p, turn, e);
    (s == StockStatus::kCut ? r.cut : r.in_air)++;
    if (std::abs(p.x() * 1e3 - probe_x_mm) < 1e-6) r.last = e;
    EXPECT_NE(stock.remove_swept(cutter, prev, p, Vector3::UnitZ()), StockStatus::kUnsupportedAxis);
    prev = p;
  }
  return r;
}

TEST(ZMapStock, APocketsFirstSlotIsAFullSlot) {
  ZMapStock stock = block();
  const PassResult r = pass(stock, end_mill(), {-10, 25, 15}, {110, 25, 15}, 50.0);
  ASSERT_TRUE(r.last.engaged());
  EXPECT_EQ(r.last.count, 1);
  EXPECT_NEAR(r.last.entry_rad, 0.0, 1e-9);
  EXPECT_NEAR(r.last.exit_rad, kPi, 1e-9);
  EXPECT_NEAR(r.last.ap_m, 5e-3, 1e-7);  // the box's top, 20 mm, over the tip at 15 mm (float heights)
  EXPECT_NEAR(r.last.ae_m, 10e-3, 1e-9);
  // In air while the cutter's front half is off the block: before it reaches x = 0 (tip at -9..-6 mm)
  // and once it has left x = 100 mm (tip at 101..110 mm).
  EXPECT_EQ(r.in_air, 4 + 10);
  // The slot's volume: 110 mm of travel inside plus the end's half disc... the block's 100 mm length
  // through, 10 mm wide, 5 mm deep.
  EXPECT_NEAR(stock.removed_volume_m3(), 0.1 * 0.01 * 0.005, 0.01 * 0.1 * 0.01 * 0.005);
}

TEST(ZMapStock, AStepOverPassIsASideCutOnTheMaterialsSide) {
  for (double ae_mm : {3.0, 1.23, 7.5}) {
    for (bool forward : {true, false}) {
      ZMapStock stock = block();
      (void)pass(stock, end_mill(), {-10, 25, 15}, {110, 25, 15}, 50.0);
      // The next pass ae further towards +y. Moving +x, +y is the normal n = z x f: the teeth of an M3
      // spindle come from there (immersion 0), so the cut starts thin: conventional. Moving -x it is
      // climb.
      const double y = 25.0 + ae_mm;
      const PassResult r = forward ? pass(stock, end_mill(), {-10, y, 15}, {110, y, 15}, 50.0)
                                   : pass(stock, end_mill(), {110, y, 15}, {-10, y, 15}, 50.0);
      ASSERT_TRUE(r.last.engaged()) << ae_mm;
      const double sweep = std::acos(1.0 - 2.0 * ae_mm / 10.0);
      // The wall sits within half a cell (0.05 mm) of where the first pass left it.
      const double tol_ae = 0.051e-3;
      const double tol_angle = tol_ae * 2.0 / (10e-3 * std::sin(sweep));
      EXPECT_NEAR(r.last.ae_m, ae_mm * 1e-3, tol_ae) << ae_mm << (forward ? " conventional" : " climb");
      if (forward) {
        EXPECT_NEAR(r.last.entry_rad, 0.0, 1e-12);
        EXPECT_NEAR(r.last.exit_rad, sweep, tol_angle) << ae_mm;
      } else {
        EXPECT_NEAR(r.last.entry_rad, kPi - sweep, tol_angle) << ae_mm;
        EXPECT_NEAR(r.last.exit_rad, kPi, 1e-12);
      }
      EXPECT_NEAR(r.last.ap_m, 5e-3, 1e-7);
    }
  }
}

TEST(ZMapStock, M4TurnsConventionalIntoClimb) {
  ZMapStock stock = block();
  (void)pass(stock, end_mill(), {-10, 25, 15}, {110, 25, 15}, 50.0);
  const PassResult r = pass(stock, end_mill(), {-10, 28, 15}, {110, 28, 15}, 50.0, SpindleTurn::kCounterClockwise);
  ASSERT_TRUE(r.last.engaged());
  EXPECT_NEAR(r.last.exit_rad, kPi, 1e-12);  // the teeth leave the material where the chip is thinnest
}

TEST(ZMapStock, AMoveInStepsCutsWhatTheWholeMoveCuts) {
  // Level moves that continue one another skip their start disc's flat; the surface must be the same
  // as one move's, for a flat end and a bull nose, along x and diagonally, cell-aligned or not.
  for (double corner_mm : {0.0, 2.0}) {
    for (const Vector3& to_mm : {Vector3(90.0, 25.03, 15.0), Vector3(80.0, 41.0, 12.5)}) {
      const Cutter c = end_mill(corner_mm);
      const Vector3 from_mm(3.0, 8.0, to_mm.z());
      ZMapStock whole = block(), steps = block();
      ASSERT_EQ(whole.remove_swept(c, from_mm * 1e-3, to_mm * 1e-3, Vector3::UnitZ()), StockStatus::kCut);
      Vector3 prev = from_mm * 1e-3;
      for (int i = 1; i <= 37; ++i) {
        const Vector3 p = (from_mm + (to_mm - from_mm) * (i / 37.0)) * 1e-3;
        (void)steps.remove_swept(c, prev, p, Vector3::UnitZ());
        prev = p;
      }
      double worst = 0.0;
      for (int j = 0; j <= 500; ++j) {
        for (int i = 0; i <= 1000; ++i) {
          worst = std::max(worst, std::abs(whole.height_m(i * 1e-4, j * 1e-4) - steps.height_m(i * 1e-4, j * 1e-4)));
        }
      }
      // A node's closest point on the whole move lies on one of the steps: the same surface, to the
      // float heights' rounding.
      EXPECT_LT(worst, 1e-8) << corner_mm << " " << to_mm.transpose();
      EXPECT_NEAR(whole.removed_volume_m3(), steps.removed_volume_m3(), 1e-3 * whole.removed_volume_m3());
    }
  }
}

TEST(ZMapStock, APassInAirTouchesNothingAndSaysSo) {
  ZMapStock stock = block();
  const PassResult above = pass(stock, end_mill(), {-10, 25, 21}, {110, 25, 21}, 50.0);
  const PassResult beside = pass(stock, end_mill(), {-10, -6, 5}, {110, -6, 5}, 50.0);
  EXPECT_EQ(above.cut + beside.cut, 0);
  EXPECT_EQ(stock.removed_volume_m3(), 0.0);
  // Riding on the top exactly cuts nothing either (the end face's cutting is not modelled).
  const PassResult riding = pass(stock, end_mill(), {-10, 25, 20}, {110, 25, 20}, 50.0);
  EXPECT_EQ(riding.cut, 0);
}

TEST(ZMapStock, ATiltedAxisIsRefusedNotApproximated) {
  ZMapStock stock = block();
  const Vector3 tilted = Vector3(std::sin(deg_to_rad(5.0)), 0.0, std::cos(deg_to_rad(5.0)));
  CutFrame frame;
  ASSERT_TRUE(make_cut_frame(tilted, Vector3::UnitY(), frame));
  Engagement e;
  EXPECT_EQ(stock.engagement(end_mill(), frame, Vector3(0.05, 0.025, 0.015), SpindleTurn::kClockwise, e),
            StockStatus::kUnsupportedAxis);
  EXPECT_EQ(stock.remove_swept(end_mill(), Vector3(0, 0.025, 0.015), Vector3(0.05, 0.025, 0.015), tilted),
            StockStatus::kUnsupportedAxis);
  EXPECT_EQ(stock.removed_volume_m3(), 0.0);
}

TEST(ZMapStock, CuttingThroughTheBottomEngagesFromTheBottomUp) {
  ZMapStock stock = block();
  const PassResult r = pass(stock, end_mill(), {-10, 25, -3}, {110, 25, -3}, 50.0);
  ASSERT_EQ(r.last.count, 1);
  EXPECT_NEAR(r.last.patches[0].z_lo_m, 3e-3, 1e-9);
  EXPECT_NEAR(r.last.patches[0].z_hi_m, 23e-3, 1e-7);
  EXPECT_NEAR(stock.height_m(0.05, 0.025), 0.0, 1e-12);  // through: nothing left
}

TEST(ZMapStock, ABullNoseLeavesItsCornerOnTheFloor) {
  ZMapStock stock = block();
  const Cutter bull = end_mill(2.0);
  (void)pass(stock, bull, {-10, 25, 15}, {110, 25, 15}, 50.0);
  // Across the slot: flat within R - rc = 3 mm of the path, the corner's arc from 3 to 5 mm.
  for (double d_mm : {0.0, 2.9, 3.5, 4.0, 4.5, 4.9}) {
    const double u = std::max(0.0, d_mm - 3.0);
    const double want = 15.0 + 2.0 - std::sqrt(4.0 - u * u);
    const double got = stock.height_m(0.05, (25.0 + d_mm) * 1e-3) * 1e3;
    EXPECT_NEAR(got, want, 0.01 + (d_mm > 4.5 ? 0.05 : 0.0)) << d_mm;  // bilinear over 0.1 mm cells
  }
  EXPECT_NEAR(stock.height_m(0.05, 0.0305), 0.02, 1e-7);  // beyond the cutter: the top
}

TEST(ZMapStock, ARampCutsDownToItsLowestReach) {
  ZMapStock stock = block();
  const Cutter flat = end_mill();
  ASSERT_EQ(stock.remove_swept(flat, Vector3(0.0, 0.025, 0.020), Vector3(0.04, 0.025, 0.015), Vector3::UnitZ()),
            StockStatus::kCut);
  // A node at x on the path is under the cutter while the tip is within 5 mm of it: lowest at the
  // later end, x + 5 mm (or the ramp's end).
  for (double x_mm : {0.0, 10.0, 20.0, 34.0, 40.0}) {
    const double xt = std::min(x_mm + 5.0, 40.0);
    EXPECT_NEAR(stock.height_m(x_mm * 1e-3, 0.025) * 1e3, 20.0 - 5.0 * xt / 40.0, 1e-4) << x_mm;
  }
  // The same with a ball: the lowest point over the path's line is the tip itself where it passes.
  ZMapStock balls = block();
  ASSERT_EQ(
      balls.remove_swept(end_mill(5.0), Vector3(0.0, 0.025, 0.020), Vector3(0.04, 0.025, 0.015), Vector3::UnitZ()),
      StockStatus::kCut);
  // Directly on the path at x the ball's surface is 5 - sqrt(25 - (x - xt)^2) above a tip at xt,
  // minimised over xt in 0..40 with z(xt) = 20 - xt / 8.
  for (double x_mm : {10.0, 20.0}) {
    double best = 1e9;
    for (int i = 0; i <= 400000; ++i) {
      const double xt = 40.0 * i / 400000.0, d = std::abs(x_mm - xt);
      if (d <= 5.0) best = std::min(best, 20.0 - xt / 8.0 + 5.0 - std::sqrt(25.0 - d * d));
    }
    EXPECT_NEAR(balls.height_m(x_mm * 1e-3, 0.025) * 1e3, best, 1e-4) << x_mm;
  }
}

TEST(ZMapStock, TheStocksForceIsTheForceOfItsWidthAndDepth) {
  ZMapStock stock = block();
  MillingCut cut;
  cut.cutter = end_mill();
  cut.k = {767e6, 168.8e6, 222e6, 27.7e3, 26.6e3, 0.7e3};
  cut.fz_m = 1e-4;
  (void)pass(stock, cut.cutter, {-10, 25, 15}, {110, 25, 15}, 50.0);
  const PassResult r = pass(stock, cut.cutter, {110, 27.5, 15}, {-10, 27.5, 15}, 50.0);  // climb, ae 2.5 mm
  const MillingForce from_stock = average_milling_force(cut, r.last);
  const MillingForce direct = average_milling_force(cut, uniform_engagement(2.5e-3, 5e-3, 10e-3, CutSide::kClimb));
  EXPECT_LT((from_stock.force_n - direct.force_n).norm(), 0.02 * direct.force_n.norm());
}

TEST(ZMapStock, QueriesAndMovesDoNotAllocate) {
  ZMapStock stock = block();
  CutFrame frame;
  ASSERT_TRUE(make_cut_frame(Vector3::UnitZ(), Vector3::UnitX(), frame));
  Engagement e;
  test::AllocationGuard guard;
  (void)stock.remove_swept(end_mill(), Vector3(-0.01, 0.025, 0.015), Vector3(0.05, 0.025, 0.015), Vector3::UnitZ());
  (void)stock.engagement(end_mill(), frame, Vector3(0.051, 0.025, 0.015), SpindleTurn::kClockwise, e);
  EXPECT_EQ(guard.allocations(), 0u);
  EXPECT_TRUE(e.engaged());
}

TEST(ZMapStock, BadBoxesAndGridsAreRefusedNamingTheValue) {
  EXPECT_NE(
      test::error_of([] { (void)ZMapStock::box(Vector3(0, 0, 0), Vector3(0.1, 0, 0.02), 1e-3); }).find("is not a box"),
      std::string::npos);
  EXPECT_NE(test::error_of([] { (void)ZMapStock::box(Vector3(0, 0, 0), Vector3(1, 1, 1), 0.0); }).find("cell_mm"),
            std::string::npos);
  EXPECT_NE(
      test::error_of([] { (void)ZMapStock::box(Vector3(0, 0, 0), Vector3(10, 10, 1), 1e-4); }).find("use cell_mm="),
      std::string::npos);
  EXPECT_NE(test::error_of([] { (void)ZMapStock(0, 0, 1e-3, 3, 3, 0, std::vector<float>(8, 1.0f)); }).find("8 heights"),
            std::string::npos);
}

}  // namespace
}  // namespace deflex
