// ISO 9283 path accuracy and repeatability on runs whose crossing points are known by construction.
#include <algorithm>
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

// The standard's figures by a scan of every segment of every run, the crossing nearest each
// evaluation point taken from all of them (ties to the later one), in the library's arithmetic: the
// pruned search must give the same doubles.
Iso9283Path scan_every_segment(const std::vector<TrackerTrace>& runs, const TrackerTrace& ref, int points,
                               double max_offset) {
  std::vector<double> cum{0.0};
  for (std::size_t k = 1; k < ref.size(); ++k) cum.push_back(cum.back() + (ref[k].p_m - ref[k - 1].p_m).norm());
  const auto at = [&](double s) {
    s = std::clamp(s, 0.0, cum.back());
    std::size_t k = 0;
    while (k + 1 < cum.size() && cum[k + 1] <= s) ++k;
    if (k + 1 >= ref.size()) return ref.back().p_m;
    const double len = cum[k + 1] - cum[k];
    return Vector3(ref[k].p_m + (len > 0.0 ? (s - cum[k]) / len : 0.0) * (ref[k + 1].p_m - ref[k].p_m));
  };
  Iso9283Path out;
  out.runs = static_cast<int>(runs.size());
  const double length = cum.back(), n_runs = static_cast<double>(runs.size());
  double sum = 0.0;
  for (int i = 0; i < points; ++i) {
    const double s = (i + 0.5) * length / points;
    const Vector3 c = at(s), chord = at(s + 0.01 * length) - at(s - 0.01 * length);
    const Vector3 n = chord.normalized();
    std::vector<Vector3> x;
    for (const auto& run : runs) {
      Vector3 best = Vector3::Constant(std::numeric_limits<double>::quiet_NaN());
      double best_d2 = max_offset * max_offset;
      for (std::size_t k = 0; k + 1 < run.size(); ++k) {
        const double f0 = (run[k].p_m - c).dot(n), f1 = (run[k + 1].p_m - c).dot(n);
        if (!((f0 <= 0.0 && f1 >= 0.0) || (f0 >= 0.0 && f1 <= 0.0))) continue;
        const double a = f0 - f1 != 0.0 ? f0 / (f0 - f1) : 0.0;
        const Vector3 xk = run[k].p_m + a * (run[k + 1].p_m - run[k].p_m);
        if ((xk - c).squaredNorm() <= best_d2) {
          best_d2 = (xk - c).squaredNorm();
          best = xk;
        }
      }
      x.push_back(best);
    }
    if (std::any_of(x.begin(), x.end(), [](const Vector3& v) { return !v.allFinite(); })) {
      ++out.skipped_points;
      continue;
    }
    Vector3 bary = Vector3::Zero();
    for (const auto& xj : x) bary += xj;
    bary /= n_runs;
    double l_mean = 0.0, s_l = 0.0;
    for (const auto& xj : x) l_mean += (xj - bary).norm();
    l_mean /= n_runs;
    for (const auto& xj : x) s_l += ((xj - bary).norm() - l_mean) * ((xj - bary).norm() - l_mean);
    s_l = runs.size() > 1 ? std::sqrt(s_l / (n_runs - 1.0)) : 0.0;
    out.accuracy_m = std::max(out.accuracy_m, (bary - c).norm());
    out.repeatability_m = std::max(out.repeatability_m, l_mean + 3.0 * s_l);
    sum += (bary - c).norm();
    ++out.evaluation_points;
  }
  out.mean_accuracy_m = sum / out.evaluation_points;
  return out;
}

TEST(Iso9283Path, SameFiguresAsAScanOfEverySegment) {
  // Noisy laps of the study's circle (1 kHz at 10 mm/s), runs that wind across each plane many times
  // near the point (a helix about the path), runs lying in the plane of the reference circle (f = 0
  // at the crossing of a lifted-free run), a run that passes some points beyond the largest offset,
  // and all of it 1 km from the origin, where rounding is largest.
  for (const Vector3& origin : {Vector3(1.8, 0.0, 0.9), Vector3(1000.0, -700.0, 300.0)}) {
    const TrackerTrace ref = test::closed_circle(0.13, origin, 3600);
    std::vector<TrackerTrace> laps;
    for (unsigned l = 0; l < 4; ++l) {
      laps.push_back(
          test::with_noise(test::circle(0.1303, origin + Vector3(0, 0, 4e-4), 20000, 1.0, l % 2 == 1), 5e-6, l + 1));
    }
    TrackerTrace helix, partial;
    for (int i = 0; i <= 50000; ++i) {
      const double a = 2.0 * kPi * i / 50000, w = 700.0 * a;
      helix.push_back({i * 1e-3, origin + Vector3((0.13 + 2e-3 * std::cos(w)) * std::cos(a),
                                                  (0.13 + 2e-3 * std::cos(w)) * std::sin(a), 2e-3 * std::sin(w))});
      const double r = 0.13 + (a > 2.0 && a < 3.0 ? 0.02 : 0.0);  // 20 mm out over a sixth of the lap
      partial.push_back({i * 1e-3, origin + Vector3(r * std::cos(a), r * std::sin(a), 0.0)});
    }
    for (const auto& runs :
         {laps, std::vector<TrackerTrace>{helix, ref, laps[0]}, std::vector<TrackerTrace>{partial, laps[1]}}) {
      for (const int points : {81, 401}) {
        const Iso9283Path fast = iso9283_path(runs, ref, points);
        const Iso9283Path scan = scan_every_segment(runs, ref, points, 0.01);
        EXPECT_EQ(fast.accuracy_m, scan.accuracy_m);
        EXPECT_EQ(fast.repeatability_m, scan.repeatability_m);
        EXPECT_EQ(fast.mean_accuracy_m, scan.mean_accuracy_m);
        EXPECT_EQ(fast.evaluation_points, scan.evaluation_points);
        EXPECT_EQ(fast.skipped_points, scan.skipped_points);
      }
    }
  }
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
