// The dexel stock: walls where they were cut, to a micrometre, on a 0.5 mm grid (where the height map
// alone is within a quarter millimetre): side cuts along x, along y and on a slant, the walls a bull
// nose's corner and a ramp leave, a pocket's first slot, air, a tilted axis, a line cut into more
// pieces than it holds.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/machining/dexel_stock.hpp"
#include "deflex/machining/milling_force.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

Cutter dexel_end_mill(double corner_mm = 0.0) {
  Cutter c;
  c.diameter_m = 10e-3;
  c.flutes = 3;
  c.helix_rad = deg_to_rad(30.0);
  c.corner_radius_m = corner_mm * 1e-3;
  return c;
}

// A 100 x 60 x 20 mm block, 0.5 mm grid and layers.
DexelStock dexel_block() { return DexelStock::box(Vector3(0, 0, 0), Vector3(0.1, 0.06, 0.02), 0.5e-3, 0.5e-3); }

/// Moves in 1 mm steps from `from` to `to` (mm), querying each point before its move; returns the
/// engagement at the step nearest the middle.
Engagement pass(DexelStock& stock, const Cutter& cutter, const Vector3& from_mm, const Vector3& to_mm,
                SpindleTurn turn = SpindleTurn::kClockwise) {
  CutFrame frame;
  EXPECT_TRUE(make_cut_frame(Vector3::UnitZ(), to_mm - from_mm, frame));
  const int steps = static_cast<int>(std::round((to_mm - from_mm).norm()));
  Vector3 prev = from_mm * 1e-3;
  Engagement middle;
  for (int i = 1; i <= steps; ++i) {
    const Vector3 p = (from_mm + (to_mm - from_mm) * (static_cast<double>(i) / steps)) * 1e-3;
    Engagement e;
    (void)stock.engagement(cutter, frame, p, turn, e);
    if (i == steps / 2) middle = e;
    EXPECT_NE(stock.remove_swept(cutter, prev, p, Vector3::UnitZ()), StockStatus::kUnsupportedAxis);
    prev = p;
  }
  return middle;
}

TEST(DexelStock, APocketsFirstSlotIsAFullSlot) {
  DexelStock stock = dexel_block();
  const Engagement e = pass(stock, dexel_end_mill(), {-10, 30, 15}, {110, 30, 15});
  ASSERT_EQ(e.count, 1);
  EXPECT_NEAR(e.entry_rad, 0.0, 1e-12);
  EXPECT_NEAR(e.exit_rad, kPi, 1e-12);
  EXPECT_NEAR(e.ap_m, 5e-3, 1e-7);
}

TEST(DexelStock, SideCutsAreExactOnACoarseGrid) {
  // Passes along x, along y and at 30 degrees, ae off the grid's spacing, conventional and climb.
  for (double heading_deg : {0.0, 90.0, 30.0}) {
    for (double ae_mm : {3.0, 1.27, 6.4}) {
      for (bool forward : {true, false}) {
        DexelStock stock = dexel_block();
        const double h = deg_to_rad(heading_deg);
        const Vector3 u(std::cos(h), std::sin(h), 0.0), left(-std::sin(h), std::cos(h), 0.0);
        const Vector3 centre(50, 30, 15);
        (void)pass(stock, dexel_end_mill(), centre - 80 * u, centre + 80 * u);
        // The next pass ae to the left of the first (seen along u): conventional when it runs along u
        // with M3 (the material on +n), climb when it runs back.
        const Vector3 next = centre + ae_mm * left;
        const Engagement e = forward ? pass(stock, dexel_end_mill(), next - 80 * u, next + 80 * u)
                                     : pass(stock, dexel_end_mill(), next + 80 * u, next - 80 * u);
        ASSERT_TRUE(e.engaged());
        const double sweep = std::acos(1.0 - 2.0 * ae_mm / 10.0);
        EXPECT_NEAR(e.ae_m, ae_mm * 1e-3, 1e-6)
            << heading_deg << " deg, ae " << ae_mm << (forward ? " conv" : " climb");
        EXPECT_NEAR(forward ? e.exit_rad : kPi - e.entry_rad, sweep, 1e-3) << heading_deg << " " << ae_mm;
        EXPECT_NEAR(forward ? e.entry_rad : e.exit_rad, forward ? 0.0 : kPi, 1e-12);
      }
    }
  }
}

TEST(DexelStock, ACoarserSamplingFindsTheSameSideCut) {
  // The machining study's sampling (33 angles, the arcs' ends bisected 12 times: pi / 32 / 2^12 =
  // 2.4e-5 rad, 0.12 um along the edge) against the closed form of a 2 mm climb side cut's arc: its
  // end to that step, the width to 50 nm (the step times the edge's slope across the feed there).
  DexelStock stock = dexel_block();
  stock.set_sampling(EngagementSampling{32, 12, 10e-6, 1e-6});
  (void)pass(stock, dexel_end_mill(), {-10, 30, 15}, {110, 30, 15});
  const Engagement e = pass(stock, dexel_end_mill(), {110, 32, 15}, {-10, 32, 15});  // climb, back along x
  ASSERT_TRUE(e.engaged());
  EXPECT_NEAR(e.ae_m, 2e-3, 50e-9);
  EXPECT_NEAR(kPi - e.entry_rad, std::acos(1.0 - 2.0 * 2.0 / 10.0), 2.5e-5);
  EXPECT_NEAR(e.exit_rad, kPi, 1e-12);
}

TEST(DexelStock, WallsAreWhereTheyWereCut) {
  DexelStock stock = dexel_block();
  (void)pass(stock, dexel_end_mill(), {-10, 25, 15}, {110, 25, 15});
  (void)pass(stock, dexel_end_mill(), {-10, 28.3, 15}, {110, 28.3, 15});
  // Along y at x = 50 mm, 2.25 mm above the floor: material below 20 and above 33.3 mm.
  const auto lines = stock.along_y(0.05, 0.01725);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NEAR(lines[0].second, 0.020, 1e-8);
  EXPECT_NEAR(lines[1].first, 0.0333, 1e-8);
  // Below the floor nothing was cut.
  const auto below = stock.along_y(0.05, 0.01475);
  ASSERT_EQ(below.size(), 1u);
  EXPECT_NEAR(below[0].second - below[0].first, 0.06, 1e-8);
  // A slanted pass: along x at y = 40 mm its wall lies where the line meets the band 5 mm from it.
  DexelStock slant = dexel_block();
  const double h = deg_to_rad(20.0);
  const Vector3 u(std::cos(h), std::sin(h), 0.0);
  (void)pass(slant, dexel_end_mill(), Vector3(50, 30, 15) - 80 * u, Vector3(50, 30, 15) + 80 * u);
  // The band |(p - c) x u| <= 5: on the row y = 40, x - 50 = (10 cos h -+ 5) / sin h.
  const auto row = slant.along_x(0.040, 0.01725);
  ASSERT_EQ(row.size(), 2u);
  EXPECT_NEAR(row[0].second, (50 + (10 * std::cos(h) - 5) / std::sin(h)) * 1e-3, 1e-8);
  EXPECT_NEAR(row[1].first, (50 + (10 * std::cos(h) + 5) / std::sin(h)) * 1e-3, 1e-8);
}

TEST(DexelStock, ABullNosesWallFollowsItsCorner) {
  DexelStock stock = dexel_block();
  (void)pass(stock, dexel_end_mill(2.0), {-10, 30, 15}, {110, 30, 15});
  // A layer h above the tip, within the 2 mm corner: the wall at R - rc + sqrt(rc^2 - (rc - h)^2).
  for (double z_mm : {15.25, 15.75, 16.25, 17.25}) {
    const double hz = z_mm - 15.0, u = std::max(0.0, 2.0 - hz);
    const double half = 3.0 + std::sqrt(4.0 - u * u);
    const auto lines = stock.along_y(0.05, z_mm * 1e-3);
    ASSERT_EQ(lines.size(), 2u) << z_mm;
    EXPECT_NEAR(lines[0].second, (30.0 - half) * 1e-3, 1e-8) << z_mm;
    EXPECT_NEAR(lines[1].first, (30.0 + half) * 1e-3, 1e-8) << z_mm;
  }
}

TEST(DexelStock, ARampCutsEachLayerWhereTheTipPassedBelowIt) {
  DexelStock stock = dexel_block();
  ASSERT_EQ(
      stock.remove_swept(dexel_end_mill(), Vector3(0.0, 0.03, 0.020), Vector3(0.04, 0.03, 0.010), Vector3::UnitZ()),
      StockStatus::kCut);
  // The layer at 15.25 mm: the tip is below it past x = 19 mm (z = 20 - x / 4); the cut reaches 5 mm
  // further each way: x from 14 mm to 45 mm on the ramp's own row.
  const auto row = stock.along_x(0.03, 0.01525);
  ASSERT_EQ(row.size(), 2u);
  EXPECT_NEAR(row[0].second, 0.014, 1e-8);
  EXPECT_NEAR(row[1].first, 0.045, 1e-8);
}

TEST(DexelStock, AirAndTiltedAxesAreSaid) {
  DexelStock stock = dexel_block();
  CutFrame frame;
  ASSERT_TRUE(make_cut_frame(Vector3::UnitZ(), Vector3::UnitX(), frame));
  Engagement e;
  EXPECT_EQ(stock.engagement(dexel_end_mill(), frame, Vector3(0.05, 0.03, 0.021), SpindleTurn::kClockwise, e),
            StockStatus::kInAir);
  EXPECT_EQ(stock.remove_swept(dexel_end_mill(), Vector3(0, 0.03, 0.021), Vector3(0.1, 0.03, 0.021), Vector3::UnitZ()),
            StockStatus::kInAir);
  const Vector3 tilted(0.1, 0.0, 1.0);
  EXPECT_EQ(stock.remove_swept(dexel_end_mill(), Vector3(0, 0.03, 0.015), Vector3(0.1, 0.03, 0.015), tilted),
            StockStatus::kUnsupportedAxis);
  EXPECT_EQ(stock.along_x(0.03, 0.017).size(), 1u);  // nothing changed
  EXPECT_EQ(stock.removed_volume_m3(), 0.0);
}

TEST(DexelStock, ALineCutIntoTooManyPiecesKeepsMaterialNotLosesIt) {
  DexelStock stock = dexel_block();
  // Eight slots across the line y = 30: nine pieces of material on it, six kept.
  for (int s = 0; s < 8; ++s) {
    const double x = 0.008 + s * 0.012;
    (void)stock.remove_swept(dexel_end_mill(), Vector3(x, -0.01, 0.015), Vector3(x, 0.07, 0.015), Vector3::UnitZ());
  }
  const auto row = stock.along_x(0.03, 0.017);
  EXPECT_EQ(row.size(), 6u);
  EXPECT_GT(stock.overflows(), 0u);
  double material = 0.0;
  for (const auto& [lo, hi] : row) material += hi - lo;
  EXPECT_GE(material, 0.1 - 8 * 0.010 - 1e-9);  // at least what is really there
}

TEST(DexelStock, QueriesAndMovesDoNotAllocate) {
  DexelStock stock = dexel_block();
  CutFrame frame;
  ASSERT_TRUE(make_cut_frame(Vector3::UnitZ(), Vector3::UnitX(), frame));
  (void)stock.remove_swept(dexel_end_mill(), Vector3(-0.01, 0.03, 0.015), Vector3(0.05, 0.03, 0.015), Vector3::UnitZ());
  Engagement e;
  test::AllocationGuard guard;
  (void)stock.remove_swept(dexel_end_mill(), Vector3(-0.01, 0.033, 0.015), Vector3(0.05, 0.033, 0.015),
                           Vector3::UnitZ());
  (void)stock.engagement(dexel_end_mill(), frame, Vector3(0.051, 0.036, 0.015), SpindleTurn::kClockwise, e);
  EXPECT_EQ(guard.allocations(), 0u);
  EXPECT_TRUE(e.engaged());
}

}  // namespace
}  // namespace deflex
