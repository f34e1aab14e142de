// The paper's mean-distance figure and its companions against closed forms, an independent
// brute-force nearest-segment search and the statistics of known noise.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/text/errors.hpp"
#include "synthetic_paths.hpp"

namespace deflex {
namespace {

// Independent of the library: the distance from p to every segment of every piece.
double brute_force_distance(const std::vector<TrackerTrace>& pieces, const Vector3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& piece : pieces) {
    if (piece.size() == 1) {
      best = std::min(best, (piece[0].p_m - p).norm());
    }
    for (std::size_t i = 0; i + 1 < piece.size(); ++i) {
      const Vector3 a = piece[i].p_m;
      const Vector3 ab = piece[i + 1].p_m - a;
      double t = ab.squaredNorm() > 0.0 ? (p - a).dot(ab) / ab.squaredNorm() : 0.0;
      t = std::max(0.0, std::min(1.0, t));
      best = std::min(best, (a + t * ab - p).norm());
    }
  }
  return best;
}

TEST(PathMetrics, CircleLiftedOutOfItsPlaneIsAtTheLiftEverywhere) {
  // Every point of a circle lifted by h along its axis is exactly h from the original circle.
  const double r = 0.1;
  const double h = 0.3e-3;
  const int n = 8000;
  const TrackerTrace ref = test::closed_circle(r, Vector3(1.2, 0.3, 0.9), n);
  const TrackerTrace loaded =
      test::shifted(test::circle(r, Vector3(1.2, 0.3, 0.9), 3001, 1.0, false, 0.123), Vector3(0, 0, h));
  // The polyline lies inside the circle by at most the sagitta r (1 - cos(pi / n)).
  const double sagitta = r * (1.0 - std::cos(kPi / n));
  const PathDeviationStats st = path_deviation(loaded, ref);
  EXPECT_NEAR(st.mean_m, h, sagitta + 1e-12);
  EXPECT_NEAR(st.max_m, h, sagitta + 1e-12);
  EXPECT_NEAR(st.rms_m, h, sagitta + 1e-12);
  EXPECT_LT(st.std_m, 1e-9);
  EXPECT_EQ(st.samples, 3001u);
  EXPECT_NEAR(mean_distance_to_path_m(loaded, ref), h, sagitta + 1e-12);
}

TEST(PathMetrics, ConcentricCircleOfLargerRadius) {
  const double r = 0.08;
  const double dr = 0.5e-3;
  const TrackerTrace ref = test::closed_circle(r, Vector3::Zero(), 8000);
  const TrackerTrace loaded = test::circle(r + dr, Vector3::Zero(), 2000, 1.0, true);
  EXPECT_NEAR(mean_distance_to_path_m(loaded, ref), dr, r * (1.0 - std::cos(kPi / 8000)) + 1e-12);
}

TEST(PathMetrics, CircleShiftedInItsPlaneMatchesTheIntegral) {
  // A circle shifted by a in its plane: the distance of its point at angle t from the original
  // circle is | |p(t)| - r |, |p(t)|^2 = r^2 + a^2 + 2 a r cos t. Its mean over t is computed here by
  // a fine midpoint rule, independently of the library.
  const double r = 0.1;
  const double a = 0.4e-3;
  const int m = 200000;
  double integral = 0.0;
  for (int i = 0; i < m; ++i) {
    const double t = 2.0 * kPi * (i + 0.5) / m;
    integral += std::abs(std::sqrt(r * r + a * a + 2.0 * a * r * std::cos(t)) - r);
  }
  integral /= m;
  const TrackerTrace ref = test::closed_circle(r, Vector3::Zero(), 10000);
  const TrackerTrace loaded = test::shifted(test::circle(r, Vector3::Zero(), 4000), Vector3(a, 0, 0));
  EXPECT_NEAR(mean_distance_to_path_m(loaded, ref), integral, 2e-8);
  EXPECT_NEAR(integral, 2.0 * a / kPi, 1e-6);  // the small-shift limit |a cos t|, a sanity check of the test
}

TEST(PathMetrics, IsotropicNoiseAboutALineGivesTheRayleighMean) {
  // Points on a line with 3D Gaussian noise sigma: the distance to the line is Rayleigh distributed
  // (two perpendicular components), mean sigma sqrt(pi/2), RMS sigma sqrt(2).
  TrackerTrace ref;
  for (int i = 0; i <= 2000; ++i) {
    ref.push_back({i * 1e-3, Vector3(-0.1 + 1.2 * i / 2000.0, 0.2, 0.5)});
  }
  TrackerTrace clean;
  for (int i = 0; i < 40000; ++i) {
    clean.push_back({i * 1e-3, Vector3(1.0 * i / 40000.0, 0.2, 0.5)});
  }
  const double sigma = 20e-6;
  const TrackerTrace loaded = test::with_noise(clean, sigma, 42);
  const PathDeviationStats st = path_deviation(loaded, ref);
  // Standard error of the mean is sigma * 0.52 / sqrt(4e4), 0.21% of the mean: 1% is ~5 standard errors.
  EXPECT_NEAR(st.mean_m, sigma * std::sqrt(kPi / 2.0), 0.01 * sigma * std::sqrt(kPi / 2.0));
  EXPECT_NEAR(st.rms_m, sigma * std::sqrt(2.0), 0.01 * sigma * std::sqrt(2.0));
  EXPECT_NEAR(st.std_m, sigma * std::sqrt(2.0 - kPi / 2.0), 0.02 * sigma * std::sqrt(2.0 - kPi / 2.0));
}

TEST(PathMetrics, StatisticsOfKnownDistances) {
  const TrackerTrace ref{{0.0, Vector3(0, 0, 0)}, {1.0, Vector3(1, 0, 0)}};
  const TrackerTrace loaded{{0.0, Vector3(0.2, 1e-3, 0)}, {0.1, Vector3(0.5, 0, 2e-3)}, {0.2, Vector3(0.7, -3e-3, 0)}};
  const PathDeviationStats st = path_deviation(loaded, ref);
  EXPECT_NEAR(st.mean_m, 2e-3, 1e-15);
  EXPECT_NEAR(st.max_m, 3e-3, 1e-15);
  EXPECT_NEAR(st.rms_m, std::sqrt(14.0 / 3.0) * 1e-3, 1e-15);
  EXPECT_NEAR(st.std_m, 1e-3, 1e-15);
  // Beyond the end of the path, the distance is to the end point.
  const TrackerTrace beyond{{0.0, Vector3(1.003, 0.004, 0)}};
  EXPECT_NEAR(mean_distance_to_path_m(beyond, ref), 5e-3, 1e-15);
}

TEST(PathMetrics, IndexAgreesWithBruteForceOnRandomPaths) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    // Pieces of random walks with mixed step sizes, repeated points (a robot standing still),
    // an occasional jump (tracker drop-out) and a single-sample piece.
    std::vector<TrackerTrace> pieces;
    const int n_pieces = 1 + trial % 3;
    for (int k = 0; k < n_pieces; ++k) {
      TrackerTrace piece;
      Vector3 p(u(rng), u(rng), u(rng));
      const double step = (trial % 4 == 0) ? 0.2 : 2e-3;
      for (int i = 0; i < 400; ++i) {
        if (i % 97 == 0) {
          piece.push_back({i * 1e-3, p});  // a repeated sample: zero-length segment
        }
        p += step * Vector3(u(rng), u(rng), u(rng));
        if (i == 200 && trial % 2 == 1) {
          p += Vector3(0.5, -0.3, 0.2);  // a jump
        }
        piece.push_back({i * 1e-3, p});
      }
      pieces.push_back(piece);
    }
    pieces.push_back({{0.0, Vector3(u(rng), u(rng), u(rng))}});
    const PolylineIndex index(pieces);
    PolylineIndex::Nearest previous;
    for (int q = 0; q < 200; ++q) {
      const double scale = (q % 3 == 0) ? 2.0 : 0.05;  // far and near queries
      const Vector3 base =
          pieces[static_cast<std::size_t>(q) % pieces.size()]
                [static_cast<std::size_t>(q * 7) % pieces[static_cast<std::size_t>(q) % pieces.size()].size()]
                    .p_m;
      const Vector3 p = base + scale * Vector3(u(rng), u(rng), u(rng));
      const auto near = index.nearest(p);
      ASSERT_NEAR(near.distance_m, brute_force_distance(pieces, p), 1e-12) << "trial " << trial << " query " << q;
      ASSERT_NEAR((near.point_m - p).norm(), near.distance_m, 1e-12);
      // Seeded with the answer for another point (a bound only): the same answer.
      if (q > 0) {
        const auto seeded = index.nearest(p, &previous);
        ASSERT_NEAR(seeded.distance_m, near.distance_m, 1e-12) << "trial " << trial << " query " << q;
        ASSERT_NEAR((seeded.point_m - p).norm(), seeded.distance_m, 1e-12);
      }
      previous = near;
    }
  }
}

TEST(PathMetrics, TrackerOrderQueriesSeededByTheLastAnswerAgreeWithBruteForce) {
  // The study's use: a closed, slightly noisy reference of a few thousand segments (its start and end
  // meet, far apart along the path), and a run's samples in time order, each seeded with the answer
  // for the one before. The offsets sweep from far below a segment's length (the answer certified
  // from a few neighbours) to many segments' lengths (the tree searched), and the run crosses the
  // reference's seam; a second reference is a figure eight, whose two loops cross, a third two laps of
  // a spiral side by side.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 2e-6);
  TrackerTrace ring = test::with_noise(test::closed_circle(0.13, Vector3(1.8, 0.0, 0.9), 3600), 1e-6, 5);
  ring.push_back(ring.front());  // closed exactly: the seam's two segments share a vertex
  TrackerTrace eight;
  for (int i = 0; i <= 2000; ++i) {
    const double a = 2.0 * kPi * i / 2000;
    eight.push_back({i * 1e-3, Vector3(1.0 + 0.1 * std::sin(a), 0.05 * std::sin(2.0 * a), 0.5)});
  }
  TrackerTrace spiral;  // two laps 0.6 mm apart: the other lap is nearer than the path's next few metres
  for (int i = 0; i <= 6000; ++i) {
    const double a = 2.0 * kPi * i / 3000;
    const double r = 0.13 + 0.6e-3 * a / (2.0 * kPi);
    spiral.push_back({i * 1e-3, Vector3(1.8 + r * std::cos(a), r * std::sin(a), 0.9)});
  }
  for (const TrackerTrace& reference : {ring, eight, spiral}) {
    const std::vector<TrackerTrace> pieces{reference};
    const PolylineIndex index(reference);
    PolylineIndex::Nearest previous;
    const int n = 4000;
    for (int i = 0; i < n; ++i) {
      // Along the reference from just before its seam, a little faster than it was sampled, the
      // offset from the path growing from 1 um to 5 mm and back.
      const double u = std::fmod(0.97 + 1.3 * i / n, 1.0) * static_cast<double>(reference.size() - 1);
      const auto j = static_cast<std::size_t>(u);
      const Vector3 on = reference[j].p_m + (u - static_cast<double>(j)) * (reference[j + 1].p_m - reference[j].p_m);
      const double offset = 1e-6 * std::pow(5000.0, std::sin(kPi * i / n));
      const Vector3 p = on + Vector3(offset * std::cos(0.001 * i), 0.3 * offset, offset * std::sin(0.001 * i)) +
                        Vector3(noise(rng), noise(rng), noise(rng));
      const auto seeded = index.nearest(p, i > 0 ? &previous : nullptr);
      ASSERT_NEAR(seeded.distance_m, brute_force_distance(pieces, p), 1e-15) << "sample " << i;
      ASSERT_EQ(seeded.distance_m, index.nearest(p).distance_m) << "sample " << i;
      ASSERT_NEAR((seeded.point_m - p).norm(), seeded.distance_m, 1e-15);
      previous = seeded;
    }
  }
}

// A run's samples along a reference, in time order: `steps` samples, each `step_m` on from the last
// along the reference (wrapping at its end), at an offset that wanders from 0 to `offset_m` in all
// three directions, with 2 um of noise.
std::vector<Vector3> samples_along(const TrackerTrace& reference, int steps, double step_m, double offset_m,
                                   unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 2e-6);
  std::vector<double> cum{0.0};
  for (std::size_t k = 1; k < reference.size(); ++k) {
    cum.push_back(cum.back() + (reference[k].p_m - reference[k - 1].p_m).norm());
  }
  std::vector<Vector3> out;
  for (int i = 0; i < steps; ++i) {
    const double s = std::fmod(0.9 * cum.back() + i * step_m, cum.back());
    const auto k = static_cast<std::size_t>(std::upper_bound(cum.begin(), cum.end(), s) - cum.begin()) - 1;
    const double f = cum[k + 1] > cum[k] ? (s - cum[k]) / (cum[k + 1] - cum[k]) : 0.0;
    const Vector3 on = reference[k].p_m + f * (reference[k + 1].p_m - reference[k].p_m);
    const double o = offset_m * 0.5 * (1.0 - std::cos(0.01 * i));
    out.push_back(on + o * Vector3(std::cos(0.003 * i), std::sin(0.007 * i), 0.5) +
                  Vector3(noise(rng), noise(rng), noise(rng)));
  }
  return out;
}

TEST(PathMetrics, FollowerAgreesWithBruteForceAtEverySpeedAndOffset) {
  // The follower answers most samples from the few segments about an earlier sample's: checked
  // against the brute force on the study's closed noisy circle, a figure eight whose loops cross, two
  // laps of a spiral 0.6 mm apart, a hairpin whose two legs run 20 um apart, a path with repeated
  // samples (segments of no length) and a reference of two pieces, at steps from 1 um (many samples
  // a segment) to 2 mm (many segments a sample) and offsets from 0 to 5 mm.
  TrackerTrace ring = test::with_noise(test::closed_circle(0.13, Vector3(1.8, 0.0, 0.9), 3600), 1e-6, 5);
  ring.push_back(ring.front());
  TrackerTrace eight, spiral, hairpin, repeated;
  for (int i = 0; i <= 2000; ++i) {
    const double a = 2.0 * kPi * i / 2000;
    eight.push_back({i * 1e-3, Vector3(1.0 + 0.1 * std::sin(a), 0.05 * std::sin(2.0 * a), 0.5)});
  }
  for (int i = 0; i <= 6000; ++i) {
    const double a = 2.0 * kPi * i / 3000;
    const double r = 0.13 + 0.6e-3 * a / (2.0 * kPi);
    spiral.push_back({i * 1e-3, Vector3(1.8 + r * std::cos(a), r * std::sin(a), 0.9)});
  }
  for (int i = 0; i <= 400; ++i) {  // out along x in 10 um steps, back 20 um to the side
    const double x = i <= 200 ? i * 1e-5 : (400 - i) * 1e-5;
    hairpin.push_back({i * 1e-3, Vector3(x, i <= 200 ? 0.0 : 2e-5, 0.0)});
  }
  for (int i = 0; i <= 3000; ++i) {  // each sample three times over, on a wavy line
    const double x = (i / 3) * 1e-4;
    repeated.push_back({i * 1e-3, Vector3(x, 1e-3 * std::sin(50.0 * x), 0.0)});
  }
  const std::vector<std::vector<TrackerTrace>> references{
      {ring},     {eight},
      {spiral},   {hairpin},
      {repeated}, {TrackerTrace(ring.begin(), ring.begin() + 1800), TrackerTrace(ring.begin() + 1800, ring.end())}};
  unsigned seed = 1;
  for (const auto& pieces : references) {
    const PolylineIndex index(pieces);
    for (const double step : {1e-6, 1e-5, 2e-4, 2e-3}) {
      for (const double offset : {0.0, 5e-4, 5e-3}) {
        PolylineIndex::Follower follower(index);
        std::size_t i = 0;
        for (const Vector3& p : samples_along(pieces.front(), 800, step, offset, ++seed)) {
          const double d = follower.next(p).distance_m;
          ASSERT_NEAR(d, brute_force_distance(pieces, p), 1e-15)
              << "step " << step << " offset " << offset << " sample " << i;
          ASSERT_EQ(d, index.nearest(p).distance_m) << "step " << step << " offset " << offset << " sample " << i;
          ++i;
        }
      }
    }
  }
}

TEST(PathMetrics, FollowerAgreesWithBruteForceOnRandomJumps) {
  // Samples that jump about at random between runs of nearby ones (a drop-out, a new lap), on random
  // polylines: each answer the brute force's, the anchor of a far sample never trusted.
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    TrackerTrace path;
    Vector3 p = Vector3::Zero();
    for (int i = 0; i < 500; ++i) {
      p += 1e-3 * Vector3(u(rng), u(rng), 0.2 * u(rng));
      path.push_back({i * 1e-3, p});
    }
    const std::vector<TrackerTrace> pieces{path};
    const PolylineIndex index(path);
    PolylineIndex::Follower follower(index);
    Vector3 q = path[0].p_m;
    for (int i = 0; i < 3000; ++i) {
      q = i % 50 == 0 ? path[static_cast<std::size_t>(250 + 250 * u(rng))].p_m
                      : q + 2e-4 * Vector3(u(rng), u(rng), u(rng));
      ASSERT_NEAR(follower.next(q).distance_m, brute_force_distance(pieces, q), 1e-15)
          << "trial " << trial << " sample " << i;
    }
    EXPECT_TRUE(std::isnan(follower.next(Vector3::Constant(std::nan(""))).distance_m));
    ASSERT_NEAR(follower.next(q).distance_m, brute_force_distance(pieces, q), 1e-15);
  }
}

TEST(PathMetrics, PiecesAreNotJoined) {
  // Two parallel lines as separate pieces: a point between their ends is far from both, though it
  // would lie on a segment joining the end of one to the start of the other.
  const TrackerTrace a{{0.0, Vector3(0, 0, 0)}, {1.0, Vector3(1, 0, 0)}};
  const TrackerTrace b{{0.0, Vector3(1, 1, 0)}, {1.0, Vector3(0, 1, 0)}};
  const PolylineIndex index(std::vector<TrackerTrace>{a, b});
  EXPECT_NEAR(index.nearest(Vector3(1.0, 0.5, 0)).distance_m, 0.5, 1e-15);
}

TEST(PathMetrics, CompensationRatio) {
  EXPECT_NEAR(compensation_ratio(0.12, 0.04), 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(compensation_ratio(1.10, 0.22), 0.8, 1e-15);
  EXPECT_NEAR(compensation_ratio(0.2, 0.3), -0.5, 1e-15);  // worse than uncompensated: negative
  EXPECT_TRUE(std::isnan(compensation_ratio(0.0, 0.01)));
  EXPECT_TRUE(std::isnan(compensation_ratio(std::numeric_limits<double>::quiet_NaN(), 0.01)));
}

TEST(PathMetrics, BadInputIsAnError) {
  const TrackerTrace ok{{0.0, Vector3(0, 0, 0)}, {1.0, Vector3(1, 0, 0)}};
  EXPECT_THROW(mean_distance_to_path_m(ok, TrackerTrace{}), InputError);
  EXPECT_THROW(mean_distance_to_path_m(TrackerTrace{}, ok), InputError);
  TrackerTrace bad = ok;
  bad[1].p_m.x() = std::numeric_limits<double>::quiet_NaN();
  try {
    mean_distance_to_path_m(ok, bad);
    FAIL() << "no error for a NaN reference sample";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sample 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(mean_distance_to_path_m(bad, ok), InputError);
}

}  // namespace
}  // namespace deflex

namespace deflex {
namespace {

TEST(MeanClosedPath, RemovesTheLowBiasOfANoisyDenseReference) {
  // Six laps of a 130 mm circle at 1 kHz with 5 um tracker noise as the unloaded reference, and a
  // loaded run 50 um outside it (also noisy): the nearest-point distance to the raw reference finds a
  // noise sample closer than the true path; to the mean of the laps it finds the 50 um.
  const Vector3 c(1.8, 0.0, 0.9);
  const TrackerTrace reference = test::with_noise(test::circle(0.13, c, 6 * 16000, 6.0), 5e-6, 1);
  const TrackerTrace loaded = test::with_noise(test::circle(0.13005, c, 16000, 1.0, false, 0.3), 5e-6, 2);
  const double raw = mean_distance_to_path_m(loaded, reference);
  const TrackerTrace mean = mean_closed_path(reference);
  const double to_mean = mean_distance_to_path_m(loaded, mean);
  EXPECT_LT(raw, 0.047e-3);                   // biased low by the reference's noise
  EXPECT_NEAR(to_mean, 0.050e-3, 0.0015e-3);  // the offset, within a few percent
  // The mean path lies on the circle to within the noise averaged over ~27 samples a bin: a radial
  // error of about 5 um / sqrt(27) = 1 um a bin, none beyond 5 sigma, and no bias.
  double worst = 0.0, sum = 0.0;
  for (const auto& s : mean) {
    const double e = std::hypot(s.p_m.x() - c.x(), s.p_m.y() - c.y()) - 0.13;
    worst = std::max(worst, std::abs(e));
    sum += e;
  }
  EXPECT_LT(worst, 5e-6);
  EXPECT_LT(std::abs(sum / static_cast<double>(mean.size())), 1e-7);
  EXPECT_EQ(mean.front().p_m, mean.back().p_m);  // closed
  // A path that does not go round its centre is refused.
  TrackerTrace line;
  for (int i = 0; i < 1000; ++i) line.push_back({i * 1e-3, Vector3(1e-4 * i, 0, 0)});
  EXPECT_THROW((void)mean_closed_path(line), InputError);
}

TEST(TimeSynchronousDeviation, SeesTheLagTheNearestPointDistanceDoesNot) {
  // The same circle, the loaded run 20 ms late: at 50 mm/s it trails by 1 mm along the path. The
  // nearest-point distance is ~0, the time-synchronous error the chord 2 r sin(w dt / 2).
  const Vector3 c(1.8, 0.0, 0.9);
  const double r = 0.13, v = 0.05, lag = 0.02;
  const double w = v / r;
  TrackerTrace ref, late;
  for (int i = 0; i < 20000; ++i) {
    const double t = i * 1e-3;
    ref.push_back({t, c + r * Vector3(std::cos(w * t), std::sin(w * t), 0)});
    late.push_back({t, c + r * Vector3(std::cos(w * (t - lag)), std::sin(w * (t - lag)), 0)});
  }
  EXPECT_LT(mean_distance_to_path_m(late, ref), 1e-7);
  const PathDeviationStats s = time_synchronous_deviation(late, ref);
  EXPECT_NEAR(s.mean_m, 2.0 * r * std::sin(w * lag / 2.0), 1e-9);
  EXPECT_EQ(s.samples, 20000u);
  TrackerTrace outside{{100.0, c}};
  EXPECT_THROW((void)time_synchronous_deviation(outside, ref), InputError);
}

}  // namespace
}  // namespace deflex
