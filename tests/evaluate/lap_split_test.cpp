// Laps of a closed path: full turns, reversals, partial pieces; and the plane of best fit.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/text/errors.hpp"
#include "synthetic_paths.hpp"

namespace deflex {
namespace {

const Vector3 kLapCentre(1.6, -0.1, 0.8);

TrackerTrace concat(const std::vector<TrackerTrace>& parts) {
  TrackerTrace out;
  for (const auto& p : parts) {
    for (const auto& s : p) {
      out.push_back({static_cast<double>(out.size()) * 1e-3, s.p_m});
    }
  }
  return out;
}

TEST(LapSplit, ThreeAnticlockwiseThenThreeClockwise) {
  // 3 laps anticlockwise without stopping, then 3 clockwise: 6 laps of n samples each (the last
  // one gets the closing sample).
  const int n = 2000;
  const TrackerTrace t = test::with_noise(
      concat({test::circle(0.1, kLapCentre, 3 * n, 3.0, false), test::closed_circle(0.1, kLapCentre, n, true),
              test::circle(0.1, kLapCentre, 2 * n, 2.0, true, 2.0 * kPi / n * 0.0)}),
      5e-6, 3);
  const LapSplit s = split_laps(t);
  ASSERT_EQ(s.laps.size(), 6u);
  EXPECT_EQ(s.dropped_partial, 0);
  std::size_t total = 0;
  for (const auto& lap : s.laps) {
    EXPECT_NEAR(static_cast<double>(lap.size()), n, 3.0);
    total += lap.size();
  }
  EXPECT_NEAR(static_cast<double>(total), static_cast<double>(t.size()), 8.0);  // laps share their end samples
}

TEST(LapSplit, AlternatingDirectionsAndAPartialPiece) {
  // CW, CCW, CW laps, then a quarter turn: 3 laps and one dropped piece.
  const int n = 1000;
  const TrackerTrace t =
      concat({test::closed_circle(0.1, kLapCentre, n, true), test::closed_circle(0.1, kLapCentre, n, false),
              test::closed_circle(0.1, kLapCentre, n, true), test::circle(0.1, kLapCentre, n / 4, 0.25)});
  const LapSplit s = split_laps(t);
  EXPECT_EQ(s.laps.size(), 3u);
  EXPECT_EQ(s.dropped_partial, 1);
}

TEST(LapSplit, SplitLapsGiveIsoRepeatability) {
  // Three laps lifted by 0.1, 0.2, 0.3 mm in one file: once split, ISO 9283 sees three runs
  // (the same construction as in the ISO test, where RT_p = l_bar + 3 S_l).
  const int n = 1500;
  std::vector<TrackerTrace> parts;
  for (const double h : {0.1e-3, 0.2e-3, 0.3e-3}) {
    parts.push_back(test::shifted(test::closed_circle(0.1, kLapCentre, n, h > 0.15e-3), Vector3(0, 0, h)));
  }
  const LapSplit s = split_laps(concat(parts));
  ASSERT_EQ(s.laps.size(), 3u);
  const Iso9283Path iso = iso9283_path(s.laps, test::closed_circle(0.1, kLapCentre, 4000));
  const double l_bar = 0.2e-3 / 3.0;
  const double s_l = std::sqrt((2.0 * (0.1e-3 - l_bar) * (0.1e-3 - l_bar) + l_bar * l_bar) / 2.0);
  EXPECT_NEAR(iso.repeatability_m, l_bar + 3.0 * s_l, 2e-6);  // lap ends carry the neighbour's lift
  EXPECT_NEAR(iso.accuracy_m, 0.2e-3, 1e-6);
}

TEST(LapSplit, PlaneOfATiltedCircle) {
  const Eigen::AngleAxisd tilt(0.3, Vector3::UnitY());
  TrackerTrace t = test::circle(0.1, Vector3::Zero(), 500);  // uniform samples: the centroid is the centre
  for (auto& s : t) {
    s.p_m = kLapCentre + tilt * s.p_m;
  }
  const PathPlane pl = best_fit_plane(t);
  EXPECT_NEAR(std::abs(pl.normal.dot(tilt * Vector3::UnitZ())), 1.0, 1e-12);
  EXPECT_GE(pl.normal.z(), 0.0);
  EXPECT_NEAR((pl.centroid_m - kLapCentre).norm(), 0.0, 1e-12);
  EXPECT_NEAR(pl.u.dot(pl.normal), 0.0, 1e-12);
  EXPECT_NEAR(pl.u.cross(pl.v).dot(pl.normal), 1.0, 1e-12);
  EXPECT_GT(pl.u.x(), 0.9);  // follows the base x
  EXPECT_THROW(best_fit_plane(TrackerTrace{t[0]}), InputError);
}

}  // namespace
}  // namespace deflex
