// The milling force: the revolution average against the full slot's closed forms, half immersion up
// and down against a plain per-angle sum of the textbook per-tooth formulas (textbook_milling.hpp),
// the instantaneous force and its peak against sliced sums, moments about the tip, corner radii, the
// feed direction turning the force, and the cut frame.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/machining/milling_force.hpp"
#include "deflex/text/errors.hpp"
#include "machining/textbook_milling.hpp"
#include "support/allocation_guard.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using test::TextbookCut;

MillingCut cut_of(const TextbookCut& t) {
  MillingCut c;
  c.cutter.diameter_m = t.diameter_m;
  c.cutter.flutes = t.flutes;
  c.cutter.helix_rad = t.helix_rad;
  c.cutter.corner_radius_m = t.corner_radius_m;
  c.k = {t.ktc, t.krc, t.kac, t.kte, t.kre, t.kae};
  c.fz_m = t.fz_m;
  c.turn = t.m3 ? SpindleTurn::kClockwise : SpindleTurn::kCounterClockwise;
  return c;
}

Engagement engagement_of(const TextbookCut& t) {
  Engagement e;
  e.add({t.entry_rad, t.exit_rad, t.z_lo_m, t.z_hi_m});
  e.summarise(0.5 * t.diameter_m);
  return e;
}

// The textbook frame: feed +x, axis +z, so normal = z x x = +y.
Wrench in_xyz(const MillingForce& f) {
  CutFrame frame;
  EXPECT_TRUE(make_cut_frame(Vector3::UnitZ(), Vector3::UnitX(), frame));
  return milling_wrench(f, frame, 0.0);
}

void expect_near_vec(const Vector6& got, const Vector6& want, double rel, const char* what) {
  const double scale = want.head<3>().norm();
  for (int i = 0; i < 6; ++i) {
    const double tol = rel * (i < 3 ? scale : scale * 10e-3) + 1e-9;
    EXPECT_NEAR(got[i], want[i], tol) << what << " component " << i;
  }
}

TEST(MillingForce, FullSlotAverageIsTheClosedForm) {
  for (double helix_deg : {0.0, 30.0}) {
    TextbookCut t;
    t.helix_rad = deg_to_rad(helix_deg);
    const MillingCut cut = cut_of(t);
    const MillingForce f = average_milling_force(cut, engagement_of(t));
    const double N = t.flutes, ap = t.z_hi_m, fz = t.fz_m;
    // Along the feed the tool is pushed back, normal to it towards +n for M3, along the axis towards
    // the tip (docs/machining.md's sign table).
    EXPECT_NEAR(f.force_n[0], -N * ap * (fz * t.krc / 4 + t.kre / kPi), 1e-9) << helix_deg;
    EXPECT_NEAR(f.force_n[1], N * ap * (fz * t.ktc / 4 + t.kte / kPi), 1e-9) << helix_deg;
    EXPECT_NEAR(f.force_n[2], -N * ap * (fz * t.kac / kPi + t.kae / 2), 1e-9) << helix_deg;
    EXPECT_NEAR(f.application_height_m, 0.5 * ap, 1e-12);
  }
}

TEST(MillingForce, FullSlotWithHelixAveragesToTheClosedFormOverARevolution) {
  // The instantaneous force, helix included, averaged over a revolution numerically: the lag must
  // not change the mean. 45 deg over 40 mm on a 10 mm cutter lags 8 rad, more than a turn.
  for (auto [helix_deg, ap_mm] : {std::pair{30.0, 12.0}, std::pair{45.0, 40.0}}) {
    TextbookCut t;
    t.helix_rad = deg_to_rad(helix_deg);
    t.z_hi_m = ap_mm * 1e-3;
    const MillingCut cut = cut_of(t);
    const Engagement e = engagement_of(t);
    Vector3 mean = Vector3::Zero();
    const int steps = 3600;
    for (int i = 0; i < steps; ++i) mean += instantaneous_milling_force(cut, e, 2 * kPi * (i + 0.5) / steps);
    mean /= steps;
    const double N = t.flutes, ap = t.z_hi_m, fz = t.fz_m;
    const Vector3 closed(-N * ap * (fz * t.krc / 4 + t.kre / kPi), N * ap * (fz * t.ktc / 4 + t.kte / kPi),
                         -N * ap * (fz * t.kac / kPi + t.kae / 2));
    EXPECT_LT((mean - closed).norm(), 1e-6 * closed.norm()) << helix_deg << " deg: " << mean.transpose();
  }
}

TEST(MillingForce, HalfImmersionUpAndDownAgainstAPerAngleSum) {
  for (bool m3 : {true, false}) {
    for (bool up : {true, false}) {
      for (double helix_deg : {0.0, 30.0}) {
        TextbookCut t;
        t.m3 = m3;
        t.helix_rad = deg_to_rad(helix_deg);
        t.entry_rad = up ? 0.0 : 0.5 * kPi;
        t.exit_rad = up ? 0.5 * kPi : kPi;
        const Vector6 want = helix_deg > 0 ? test::textbook_average(t, 3600, 60) : test::textbook_average(t, 36000, 1);
        const Vector6 got = in_xyz(average_milling_force(cut_of(t), engagement_of(t)));
        expect_near_vec(got, want, 2e-4, up ? "up" : "down");
      }
    }
  }
}

TEST(MillingForce, UpAndDownHalfImmersionDirections) {
  // Without edge forces up and down milling at half immersion share the in-plane magnitude (the
  // cutting terms' integrals over 0..pi/2 and pi/2..pi differ only in sign); the edge forces break that.
  TextbookCut up, down;
  up.exit_rad = 0.5 * kPi;
  down.entry_rad = 0.5 * kPi;
  for (TextbookCut* t : {&up, &down}) t->kte = t->kre = t->kae = 0.0;
  const MillingForce fu = average_milling_force(cut_of(up), engagement_of(up));
  const MillingForce fd = average_milling_force(cut_of(down), engagement_of(down));
  EXPECT_NEAR(fu.force_n.head<2>().norm(), fd.force_n.head<2>().norm(), 1e-9 * fu.force_n.norm());
  // Conventional (M3, material on +n): the tool is pushed back against the feed and drawn towards the
  // material; climb (material on -n): pulled forward along the feed and pushed away from the material.
  EXPECT_LT(fu.force_n[0], 0.0);
  EXPECT_GT(fu.force_n[1], 0.0);
  EXPECT_GT(fd.force_n[0], 0.0);
  EXPECT_GT(fd.force_n[1], 0.0);
  EXPECT_GT((fu.force_n - fd.force_n).head<2>().norm(), 0.5 * fu.force_n.head<2>().norm());
}

TEST(MillingForce, TurningTheFeedTurnsTheForce) {
  TextbookCut t;
  t.exit_rad = 0.6;  // a conventional side cut: a force with every component
  const MillingForce f = average_milling_force(cut_of(t), engagement_of(t));
  CutFrame along_x, along_y;
  ASSERT_TRUE(make_cut_frame(Vector3::UnitZ(), Vector3(2.0, 0.0, 0.0), along_x));
  ASSERT_TRUE(make_cut_frame(Vector3::UnitZ(), Vector3(0.0, 0.5, 0.0), along_y));
  const Wrench wx = milling_wrench(f, along_x, 0.02), wy = milling_wrench(f, along_y, 0.02);
  const Matrix3 quarter = Eigen::AngleAxisd(0.5 * kPi, Vector3::UnitZ()).toRotationMatrix();
  EXPECT_LT((wy.head<3>() - quarter * wx.head<3>()).norm(), 1e-9 * wx.norm());
  EXPECT_LT((wy.tail<3>() - quarter * wx.tail<3>()).norm(), 1e-9 * wx.norm());
  // The x feed's force along -x (pushed back) becomes a force along -y.
  EXPECT_LT(wx[0], 0.0);
  EXPECT_LT(wy[1], 0.0);
}

TEST(MillingForce, MomentAboutTheTipAgainstThePerAngleSum) {
  for (double helix_deg : {0.0, 30.0}) {
    TextbookCut t;
    t.helix_rad = deg_to_rad(helix_deg);
    t.z_lo_m = 2e-3;
    t.z_hi_m = 9e-3;
    t.entry_rad = 0.3;
    t.exit_rad = 2.2;
    const Vector6 want = test::textbook_average(t, 7200, 120);
    const MillingForce f = average_milling_force(cut_of(t), engagement_of(t));
    const Vector6 got = in_xyz(f);
    expect_near_vec(got, want, 1e-3, "moment");
    // The torque about the axis is the tangential force times the radius: M3 drives the tool about -z,
    // the cut holds it back, so +z.
    EXPECT_GT(got[5], 0.0);
    // The full slot's torque in closed form: R N ap (2 Ktc fz + pi Kte) / (2 pi).
    TextbookCut slot;
    const Vector6 ws = in_xyz(average_milling_force(cut_of(slot), engagement_of(slot)));
    EXPECT_NEAR(ws[5], 5e-3 * 3 * 5e-3 * (2 * slot.ktc * slot.fz_m + kPi * slot.kte) / (2 * kPi), 1e-9);
  }
}

TEST(MillingForce, MomentMovesToAnotherPointOnTheAxis) {
  TextbookCut t;
  const MillingForce f = average_milling_force(cut_of(t), engagement_of(t));
  CutFrame frame;
  ASSERT_TRUE(make_cut_frame(Vector3::UnitZ(), Vector3::UnitX(), frame));
  const Wrench tip = milling_wrench(f, frame, 0.0);
  const Wrench tcp = milling_wrench(f, frame, 0.1);  // 100 mm up the axis
  // M_tcp = M_tip + (tip - tcp) x F = M_tip - (0.1 z) x F.
  EXPECT_LT((tcp.tail<3>() - (tip.tail<3>() - Vector3(0, 0, 0.1).cross(tip.head<3>()))).norm(), 1e-12);
}

TEST(MillingForce, CornerRadiusAgainstTheSlicedEdge) {
  // A ball nose engaged in its corner only, and a bull nose engaged above and in its corner.
  for (auto [rc_mm, lo_mm, hi_mm] : {std::tuple{5.0, 0.0, 2.5}, std::tuple{2.0, 0.0, 6.0}, std::tuple{2.0, 1.0, 6.0}}) {
    TextbookCut t;
    t.corner_radius_m = rc_mm * 1e-3;
    t.z_lo_m = lo_mm * 1e-3;
    t.z_hi_m = hi_mm * 1e-3;
    t.entry_rad = 0.4;
    t.exit_rad = kPi;
    const Vector6 want = test::textbook_average(t, 3600, 150);
    const Vector6 got = in_xyz(average_milling_force(cut_of(t), engagement_of(t)));
    // The force exactly (the corner's integrals are closed forms); the moment's lever in the corner
    // from each 15 degree band's middle.
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(got[i], want[i], 2e-4 * want.head<3>().norm()) << rc_mm << " " << i;
    for (int i = 3; i < 6; ++i) EXPECT_NEAR(got[i], want[i], 1e-2 * want.tail<3>().norm()) << rc_mm << " " << i;
  }
}

TEST(MillingForce, InstantaneousForceAgainstTheSlicedSum) {
  TextbookCut t;
  t.helix_rad = deg_to_rad(35.0);
  t.z_hi_m = 15e-3;
  t.entry_rad = 0.9;
  t.exit_rad = kPi;
  t.m3 = false;
  const MillingCut cut = cut_of(t);
  const Engagement e = engagement_of(t);
  for (double theta : {0.0, 0.37, 1.9, 4.4}) {
    const Vector3 want = test::textbook_wrench(t, theta, 4000).head<3>();
    const Vector3 got = instantaneous_milling_force(cut, e, theta);
    EXPECT_LT((got - want).norm(), 2e-3 * want.norm() + 1e-6) << theta;
  }
}

double sampled_peak(const TextbookCut& t, int steps, int slices) {
  double peak = 0.0;
  for (int i = 0; i < steps; ++i) {
    peak = std::max(peak, test::textbook_wrench(t, 2 * kPi * i / steps, slices).head<3>().norm());
  }
  return peak;
}

TEST(MillingForce, PeakAgainstFineSampling) {
  struct Case {
    double helix_deg, entry, exit;
    int flutes;
  };
  // Small radial width in climb without helix: the force jumps at entry, where the peak is.
  const Case cases[] = {{0.0, kPi - std::acos(1 - 2 * 0.1), kPi, 2},
                        {0.0, 0.0, 0.5 * kPi, 3},
                        {30.0, 0.5 * kPi, kPi, 3},
                        {30.0, 0.0, kPi, 4}};
  for (const Case& c : cases) {
    TextbookCut t;
    t.helix_rad = deg_to_rad(c.helix_deg);
    t.entry_rad = c.entry;
    t.exit_rad = c.exit;
    t.flutes = c.flutes;
    const double want = c.helix_deg > 0 ? sampled_peak(t, 7200, 100) : sampled_peak(t, 20000, 1);
    const MillingPeak p = peak_milling_force(cut_of(t), engagement_of(t));
    EXPECT_NEAR(p.peak_force_n, want, 0.01 * want) << c.helix_deg << " " << c.entry;
  }
  EXPECT_DOUBLE_EQ(tooth_passing_frequency_hz(12000.0, 3), 600.0);
}

TEST(MillingForce, AnEmptyEngagementHasNoForce) {
  TextbookCut t;
  const Engagement none;
  EXPECT_EQ(average_milling_force(cut_of(t), none).force_n, Vector3::Zero());
  EXPECT_EQ(peak_milling_force(cut_of(t), none).peak_force_n, 0.0);
}

TEST(MillingForce, TheHotCallsDoNotAllocate) {
  TextbookCut t;
  t.corner_radius_m = 1e-3;
  t.helix_rad = 0.5;
  const MillingCut cut = cut_of(t);
  const Engagement e = engagement_of(t);
  test::AllocationGuard guard;
  const MillingForce f = average_milling_force(cut, e);
  const MillingPeak p = peak_milling_force(cut, e);
  EXPECT_EQ(guard.allocations(), 0u);
  EXPECT_GT(f.force_n.norm(), 0.0);
  EXPECT_GT(p.peak_force_n, 0.0);
}

TEST(CutFrame, FeedNormalAndAxisFromTheMotion) {
  CutFrame f;
  // A 45 degree ramp: the feed is the in-plane part, fz scales with cos 45.
  ASSERT_TRUE(make_cut_frame(Vector3(0, 0, 2), Vector3(1, 0, 1), f));
  EXPECT_LT((f.feed - Vector3::UnitX()).norm(), 1e-12);
  EXPECT_LT((f.normal - Vector3::UnitY()).norm(), 1e-12);
  EXPECT_LT((f.axis - Vector3::UnitZ()).norm(), 1e-12);
  EXPECT_NEAR(f.in_plane_fraction, std::sqrt(0.5), 1e-12);
  EXPECT_FALSE(make_cut_frame(Vector3::UnitZ(), Vector3(0, 0, -1), f));  // a plunge
  EXPECT_FALSE(make_cut_frame(Vector3::Zero(), Vector3::UnitX(), f));
  EXPECT_FALSE(make_cut_frame(Vector3::UnitZ(), Vector3::Zero(), f));
  EXPECT_FALSE(make_cut_frame(Vector3(kNaN, 0, 1), Vector3::UnitX(), f));
}

TEST(FeedPerTooth, FromFeedSpindleAndFlutesAndRefusedWhereTheToolCannotCut) {
  EXPECT_NEAR(feed_per_tooth_m(1200.0, 10000.0, 3), 1200e-3 / 30000.0, 1e-18);
  EXPECT_NE(test::error_of([] { (void)feed_per_tooth_m(0.0, 10000.0, 3); }).find("feed: 0 mm/min"), std::string::npos);
  EXPECT_NE(test::error_of([] { (void)feed_per_tooth_m(1200.0, 0.0, 3); }).find("spindle speed: 0 rpm"),
            std::string::npos);
  EXPECT_NE(test::error_of([] { (void)feed_per_tooth_m(1200.0, kNaN, 3); }).find("spindle speed"), std::string::npos);
  EXPECT_NE(test::error_of([] { (void)feed_per_tooth_m(1200.0, 1000.0, 0); }).find("flutes"), std::string::npos);
}

}  // namespace
}  // namespace deflex
