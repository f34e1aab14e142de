// ISO 9283 path accuracy and repeatability on runs whose crossing points are known by construction.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/text/errors.hpp"
#include "synthetic_paths.hpp"

namespace deflex {
namespace {

const Vector3 kCentre(1.5, -0.2, 1.1);
constexpr double kR = 0.1;

TEST(Iso9283Path, RunsOnTheReferenceHaveZeroAccuracyAndRepeatability) {
  const TrackerTrace ref = test::closed_circle(kR, kCentre, 2000);
  const std::vector<TrackerTrace> runs{ref, ref, ref};
  const Iso9283Path iso = iso9283_path(runs, ref);
  EXPECT_LT(iso.accuracy_m, 1e-12);
  EXPECT_LT(iso.repeatability_m, 1e-15);  // identical runs: every crossing is the barycentre (to rounding)
  EXPECT_EQ(iso.evaluation_points, 81);
  EXPECT_EQ(iso.skipped_points, 0);
  EXPECT_EQ(iso.runs, 3);
}

TEST(Iso9283Path, RunsLiftedAlongTheAxisGiveTheIsoFormulas) {
  // Runs lifted by 0.1, 0.2 and 0.3 mm out of the circle's plane cross each normal plane exactly at
  // c_i + (0, 0, h_j). Barycentre at 0.2 mm: AT_p = 0.2 mm. l_j = 0.1, 0, 0.1 mm; l_bar = 0.2/3 mm;
  // S_l = sqrt(((0.1 - l_bar)^2 * 2 + l_bar^2) / 2); RT_p = l_bar + 3 S_l.
  const TrackerTrace ref = test::closed_circle(kR, kCentre, 3000);
  std::vector<TrackerTrace> runs;
  for (const double h : {0.1e-3, 0.2e-3, 0.3e-3}) {
    runs.push_back(test::shifted(test::circle(kR, kCentre, 2500, 1.0, h > 0.15e-3, 0.05), Vector3(0, 0, h)));
  }
  const double l_bar = 0.2e-3 / 3.0;
  const double s_l = std::sqrt((2.0 * (0.1e-3 - l_bar) * (0.1e-3 - l_bar) + l_bar * l_bar) / 2.0);
  const Iso9283Path iso = iso9283_path(runs, ref, 40);
  EXPECT_NEAR(iso.accuracy_m, 0.2e-3, 1e-9);
  EXPECT_NEAR(iso.mean_accuracy_m, 0.2e-3, 1e-9);
  EXPECT_NEAR(iso.repeatability_m, l_bar + 3.0 * s_l, 1e-9);
  EXPECT_EQ(iso.evaluation_points, 40);
}

TEST(Iso9283Path, LargerRadiusGivesTheRadialError) {
  // The normal plane at c_i contains the radial direction, so a concentric run of radius r + dr
  // crosses it dr from c_i (up to the chord error of the sampled run).
  const double dr = 0.25e-3;
  const TrackerTrace commanded = test::closed_circle(kR, kCentre, 81);  // sparse, like the paper's 81 points
  const std::vector<TrackerTrace> runs{test::closed_circle(kR + dr, kCentre, 20000, true)};
  const Iso9283Path iso = iso9283_path(runs, commanded);
  // The commanded polyline of 81 chords lies inside the circle by up to r (1 - cos(pi/81)) = 75 um:
  // the accuracy measured against it is dr plus that sagitta at the chord's middle.
  const double sagitta = kR * (1.0 - std::cos(kPi / 81));
  EXPECT_GE(iso.accuracy_m, dr - 1e-7);
  EXPECT_LE(iso.accuracy_m, dr + sagitta + 1e-7);
  EXPECT_EQ(iso.repeatability_m, 0.0);
}

TEST(Iso9283Path, OpenPathAndFarRuns) {
  // A straight reference; runs that are 5 mm away are not "the same path" at a 1 mm limit.
  TrackerTrace ref;
  for (int i = 0; i <= 100; ++i) {
    ref.push_back({i * 1e-3, Vector3(i * 1e-3, 0, 0)});
  }
  const std::vector<TrackerTrace> near{test::shifted(ref, Vector3(0, 0.3e-3, 0.4e-3))};
  const Iso9283Path iso = iso9283_path(near, ref, 10, 1e-3);
  EXPECT_NEAR(iso.accuracy_m, 0.5e-3, 1e-12);
  const std::vector<TrackerTrace> far{test::shifted(ref, Vector3(0, 5e-3, 0))};
  EXPECT_THROW(iso9283_path(far, ref, 10, 1e-3), InputError);
}

TEST(Iso9283Path, BadInput) {
  const TrackerTrace ref = test::closed_circle(kR, kCentre, 100);
  EXPECT_THROW(iso9283_path({}, ref), InputError);
  EXPECT_THROW(iso9283_path({ref}, TrackerTrace{ref[0]}), InputError);
  EXPECT_THROW(iso9283_path({TrackerTrace{ref[0]}}, ref), InputError);
  EXPECT_THROW(iso9283_path({ref}, ref, 0), InputError);
}

std::string error_of(const std::vector<TrackerTrace>& runs, const TrackerTrace& ref) {
  try {
    (void)iso9283_path(runs, ref);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Iso9283Path, NonFiniteSamplesAreNamedNotSkipped) {
  const TrackerTrace ref = test::closed_circle(kR, kCentre, 400);
  TrackerTrace bad_run = ref;
  bad_run[123].p_m.y() = std::nan("");
  // Before: the planes that sample should cross were counted as "not crossed" and the figures came
  // from the others, with no word about the NaN.
  EXPECT_NE(error_of({ref, bad_run, ref}, ref).find("run 2 sample 123"), std::string::npos)
      << error_of({ref, bad_run, ref}, ref);
  TrackerTrace bad_ref = ref;
  bad_ref[0].p_m.x() = std::numeric_limits<double>::infinity();
  // Before: the first sample was not checked, so the length was NaN and the error said "zero length".
  EXPECT_NE(error_of({ref}, bad_ref).find("reference sample 0 is not finite"), std::string::npos)
      << error_of({ref}, bad_ref);
}

}  // namespace
}  // namespace deflex
