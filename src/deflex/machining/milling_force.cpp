// The linear edge-force model, averaged in closed form and sampled for its peak.
//
// Every force is linear in five functions of the immersion angle, the basis
// B(phi) = [sin phi cos phi, cos phi, sin^2 phi, sin phi, 1], so a band of heights contributes
// W B(phi) per unit height with a constant 6 x 5 matrix W (three force rows, three rows of the moment
// the force has at the cutter's radius). The average over a revolution is then N / (2 pi) times
// W times the integral of B over the arc (primitive P below), times the band's height: exact, with
// two sines and cosines per arc. With a helix, a tooth whose tip is at psi reaches height z at
// phi = psi - k z (k = tan(helix) / R), so its force on a band is (1 / k) W times the integral of B
// over the part of [psi - k z_hi, psi - k z_lo] inside the arc: exact too, for any lag.
#include "deflex/machining/milling_force.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

using Basis = Eigen::Matrix<double, 5, 1>;
using Weights = Eigen::Matrix<double, 6, 5>;

constexpr double kTwoPi = 2.0 * kPi;
// Corner sub-bands for the moment's lever: the force integrals are exact whatever the split.
constexpr double kMaxCornerStepRad = kPi / 12.0;

Basis basis_at(double s, double c) { return (Basis() << s * c, c, s * s, s, 1.0).finished(); }
Basis primitive_at(double phi, double s, double c) {
  return (Basis() << 0.5 * s * s, s, 0.5 * (phi - s * c), -c, phi).finished();
}

/// A band of heights z_lo..z_hi above the tip within one patch's arc.
struct Band {
  double z_lo = 0.0;
  double z_hi = 0.0;
  double lever_m = 0.0;  // the radius at which its axial force and torque act
  Weights w = Weights::Zero();
};

/// The band's weights: the corner's edge angle kappa enters through its integrals over the band
/// (z = r (1 - cos kappa), dz = r sin kappa dkappa, edge length dS = r dkappa), exact for the force.
Band make_band(const MillingCut& cut, double z_lo, double z_hi) {
  const double rc = cut.cutter.corner_radius_m;
  const double R = cut.cutter.radius_m();
  const double az = z_hi - z_lo;
  double w_s = 1.0, w_c = 0.0, rho = 1.0, rho_s = 1.0, rho_c = 0.0;
  Band b;
  b.z_lo = z_lo;
  b.z_hi = z_hi;
  b.lever_m = R;
  if (rc > 0.0 && z_lo < rc) {
    const double k1 = std::acos(std::clamp(1.0 - z_lo / rc, -1.0, 1.0));
    const double k2 = std::acos(std::clamp(1.0 - z_hi / rc, -1.0, 1.0));
    const double s1 = std::sin(k1), c1 = std::cos(k1), s2 = std::sin(k2), c2 = std::cos(k2);
    w_s = rc * (0.5 * (k2 - k1) - 0.5 * (s2 * c2 - s1 * c1)) / az;
    w_c = rc * 0.5 * (s2 * s2 - s1 * s1) / az;
    rho = rc * (k2 - k1) / az;
    rho_s = rc * (c1 - c2) / az;
    rho_c = rc * (s2 - s1) / az;
    b.lever_m = R - rc + rc * std::sin(0.5 * (k1 + k2));
  }
  const CuttingCoefficients& k = cut.k;
  const double fz = cut.fz_m, s = turn_sign(cut.turn), L = b.lever_m;
  const double radial_c = (k.krc_n_m2 * w_s + k.kac_n_m2 * w_c) * fz;  // in-plane share of radial and axial
  const double radial_e = k.kre_n_m * rho_s + k.kae_n_m * rho_c;
  const double axial_c = (k.krc_n_m2 * w_c - k.kac_n_m2 * w_s) * fz;  // along the axis
  const double axial_e = k.kre_n_m * rho_c - k.kae_n_m * rho_s;
  // Basis order: sin cos, cos, sin^2, sin, 1.
  b.w.row(0) << -k.ktc_n_m2 * fz, -k.kte_n_m * rho, -radial_c, -radial_e, 0.0;
  b.w.row(1) << -s * radial_c, -s * radial_e, s * k.ktc_n_m2 * fz, s * k.kte_n_m * rho, 0.0;
  b.w.row(2) << 0.0, 0.0, 0.0, axial_c, axial_e;
  b.w.row(3) << s * L * axial_c, s * L * axial_e, 0.0, 0.0, 0.0;
  b.w.row(4) << 0.0, 0.0, -L * axial_c, -L * axial_e, 0.0;
  b.w.row(5) << 0.0, 0.0, 0.0, s * L * k.ktc_n_m2 * fz, s * L * k.kte_n_m * rho;
  return b;
}

/// A patch's bands: the corner part (in kappa steps of at most kMaxCornerStepRad when `split`) and
/// the cylinder above it. Returns the count (at most 8).
int patch_bands(const MillingCut& cut, const EngagementPatch& p, bool split, std::array<Band, 8>& out) {
  const double rc = cut.cutter.corner_radius_m;
  int n = 0;
  if (rc > 0.0 && p.z_lo_m < rc) {
    const double top = std::min(p.z_hi_m, rc);
    int steps = 1;
    if (split) {
      const double k1 = std::acos(std::clamp(1.0 - p.z_lo_m / rc, -1.0, 1.0));
      const double k2 = std::acos(std::clamp(1.0 - top / rc, -1.0, 1.0));
      steps = std::clamp(static_cast<int>(std::ceil((k2 - k1) / kMaxCornerStepRad)), 1, 7);
      for (int i = 0; i < steps; ++i) {
        const double ka = k1 + (k2 - k1) * i / steps, kb = k1 + (k2 - k1) * (i + 1) / steps;
        const double za = i == 0 ? p.z_lo_m : rc * (1.0 - std::cos(ka));
        const double zb = i == steps - 1 ? top : rc * (1.0 - std::cos(kb));
        if (zb > za) out[static_cast<std::size_t>(n++)] = make_band(cut, za, zb);
      }
    } else if (top > p.z_lo_m) {
      out[static_cast<std::size_t>(n++)] = make_band(cut, p.z_lo_m, top);
    }
  }
  const double lo = std::max(p.z_lo_m, rc);
  if (p.z_hi_m > lo) out[static_cast<std::size_t>(n++)] = make_band(cut, lo, p.z_hi_m);
  return n;
}

double helix_rate(const Cutter& c) { return std::tan(c.helix_rad) / c.radius_m(); }

/// The force of one tooth whose tip is at psi (sin sp, cos cp) on one band of a patch, per the file
/// comment. `lag` = helix_rate; zero lag (straight teeth) is a point evaluation.
struct BandCursor {
  const Band* band;
  double entry, exit;
  double s_entry, c_entry, s_exit, c_exit;
  double lag_lo, lag_hi;  // k z_lo, k z_hi
  double sl_lo, cl_lo, sl_hi, cl_hi;
  double lag;
};

BandCursor cursor(const Band& b, const EngagementPatch& p, double lag) {
  BandCursor c{};
  c.band = &b;
  c.entry = p.entry_rad;
  c.exit = p.exit_rad;
  c.s_entry = std::sin(p.entry_rad);
  c.c_entry = std::cos(p.entry_rad);
  c.s_exit = std::sin(p.exit_rad);
  c.c_exit = std::cos(p.exit_rad);
  c.lag = lag;
  c.lag_lo = lag * b.z_lo;
  c.lag_hi = lag * b.z_hi;
  c.sl_lo = std::sin(c.lag_lo);
  c.cl_lo = std::cos(c.lag_lo);
  c.sl_hi = std::sin(c.lag_hi);
  c.cl_hi = std::cos(c.lag_hi);
  return c;
}

Vector3 tooth_on_band(const BandCursor& c, double psi, double sp, double cp) {
  const auto force_rows = c.band->w.topRows<3>();
  if (c.lag_hi - c.lag_lo < 1e-9) {
    double phi = std::fmod(psi - c.lag_lo, kTwoPi);
    if (phi < 0.0) phi += kTwoPi;
    if (phi < c.entry - 1e-9 || phi > c.exit + 1e-9) return Vector3::Zero();
    const double s = sp * c.cl_lo - cp * c.sl_lo, co = cp * c.cl_lo + sp * c.sl_lo;
    return (c.band->z_hi - c.band->z_lo) * (force_rows * basis_at(s, co));
  }
  const double lo = psi - c.lag_hi, hi = psi - c.lag_lo;
  const double s_lo = sp * c.cl_hi - cp * c.sl_hi, c_lo = cp * c.cl_hi + sp * c.sl_hi;
  const double s_hi = sp * c.cl_lo - cp * c.sl_lo, c_hi = cp * c.cl_lo + sp * c.sl_lo;
  Basis sum = Basis::Zero();
  const double m_first = std::ceil((lo - c.exit) / kTwoPi), m_last = std::floor((hi - c.entry) / kTwoPi);
  for (double m = m_first; m <= m_last; m += 1.0) {
    const double shift = kTwoPi * m;
    const bool a_is_entry = lo - shift <= c.entry, b_is_exit = hi - shift >= c.exit;
    const double a = a_is_entry ? c.entry : lo - shift, b = b_is_exit ? c.exit : hi - shift;
    if (!(b > a)) continue;
    sum += (b_is_exit ? primitive_at(b, c.s_exit, c.c_exit) : primitive_at(b, s_hi, c_hi)) -
           (a_is_entry ? primitive_at(a, c.s_entry, c.c_entry) : primitive_at(a, s_lo, c_lo));
  }
  return (force_rows * sum) / c.lag;
}

}  // namespace

MillingForce average_milling_force(const MillingCut& cut, const Engagement& engagement) noexcept {
  MillingForce out;
  Vector6 wrench = Vector6::Zero();
  Eigen::Vector2d height_weighted = Eigen::Vector2d::Zero();  // sum of z times in-plane force
  double z_min = 1e300, z_max = -1e300;
  std::array<Band, 8> bands;
  for (int i = 0; i < engagement.count; ++i) {
    const EngagementPatch& p = engagement.patches[static_cast<std::size_t>(i)];
    const Basis integral = primitive_at(p.exit_rad, std::sin(p.exit_rad), std::cos(p.exit_rad)) -
                           primitive_at(p.entry_rad, std::sin(p.entry_rad), std::cos(p.entry_rad));
    const int n = patch_bands(cut, p, true, bands);
    for (int b = 0; b < n; ++b) {
      const Band& band = bands[static_cast<std::size_t>(b)];
      Vector6 w = (band.z_hi - band.z_lo) * (band.w * integral);
      const double z_mid = 0.5 * (band.z_lo + band.z_hi);
      w[3] -= z_mid * w[1];  // the in-plane force's lever along the axis: z a x F
      w[4] += z_mid * w[0];
      wrench += w;
      height_weighted += z_mid * w.head<2>();
    }
    z_min = std::min(z_min, p.z_lo_m);
    z_max = std::max(z_max, p.z_hi_m);
  }
  if (engagement.count == 0) return out;
  wrench *= cut.cutter.flutes / kTwoPi;
  out.force_n = wrench.head<3>();
  out.moment_tip_nm = wrench.tail<3>();
  // The height whose lever best reproduces the in-plane force's moment about the tip (least squares
  // over the bands' levers): sum z_b F_b . F / |F|^2, in-plane components.
  const double f2 = out.force_n.head<2>().squaredNorm();
  if (f2 > 1e-18) {
    out.application_height_m = (cut.cutter.flutes / kTwoPi) * height_weighted.dot(out.force_n.head<2>()) / f2;
  } else {
    out.application_height_m = 0.5 * (z_min + z_max);
  }
  return out;
}

Vector3 instantaneous_milling_force(const MillingCut& cut, const Engagement& engagement, double rotation_rad) noexcept {
  Vector3 f = Vector3::Zero();
  const double lag = helix_rate(cut.cutter);
  const int teeth = cut.cutter.flutes;
  std::array<Band, 8> bands;
  for (int i = 0; i < engagement.count; ++i) {
    const EngagementPatch& p = engagement.patches[static_cast<std::size_t>(i)];
    const int n = patch_bands(cut, p, false, bands);
    for (int b = 0; b < n; ++b) {
      const BandCursor c = cursor(bands[static_cast<std::size_t>(b)], p, lag);
      for (int j = 0; j < teeth; ++j) {
        const double psi = rotation_rad + kTwoPi * j / teeth;
        f += tooth_on_band(c, psi, std::sin(psi), std::cos(psi));
      }
    }
  }
  return f;
}

MillingPeak peak_milling_force(const MillingCut& cut, const Engagement& engagement, int samples_per_tooth) noexcept {
  MillingPeak out;
  if (engagement.count == 0) return out;
  constexpr int kMaxSamples = 256, kMaxEvents = 64;
  const int m_count = std::clamp(samples_per_tooth, 4, kMaxSamples);
  const int teeth = std::clamp(cut.cutter.flutes, 1, cutter_limits::kMaxFlutes);
  const double period = kTwoPi / teeth, step = period / m_count, lag = helix_rate(cut.cutter);
  std::array<Vector3, kMaxSamples> sampled;
  std::array<double, kMaxEvents> event_angle{};
  std::array<Vector3, kMaxEvents> event_force;
  std::array<double, cutter_limits::kMaxFlutes> s_tooth{}, c_tooth{};
  for (int j = 0; j < teeth; ++j) {
    s_tooth[static_cast<std::size_t>(j)] = std::sin(period * j);
    c_tooth[static_cast<std::size_t>(j)] = std::cos(period * j);
  }
  std::fill(sampled.begin(), sampled.begin() + m_count, Vector3::Zero());
  // The angles where an arc's end meets a band's end: a force without helix jumps there.
  int events = 0;
  for (int i = 0; i < engagement.count && events + 4 <= kMaxEvents; ++i) {
    const EngagementPatch& p = engagement.patches[static_cast<std::size_t>(i)];
    for (double e : {p.entry_rad, p.exit_rad}) {
      for (double z : {p.z_lo_m, p.z_hi_m}) event_angle[static_cast<std::size_t>(events++)] = e + lag * z;
    }
  }
  std::fill(event_force.begin(), event_force.begin() + events, Vector3::Zero());
  const double s_step = std::sin(step), c_step = std::cos(step);
  std::array<Band, 8> bands;
  for (int i = 0; i < engagement.count; ++i) {
    const EngagementPatch& p = engagement.patches[static_cast<std::size_t>(i)];
    const int n = patch_bands(cut, p, false, bands);
    for (int b = 0; b < n; ++b) {
      const BandCursor c = cursor(bands[static_cast<std::size_t>(b)], p, lag);
      double s_m = 0.0, c_m = 1.0;  // sin, cos of m step, by rotation
      for (int m = 0; m < m_count; ++m) {
        for (int j = 0; j < teeth; ++j) {
          const double sj = s_tooth[static_cast<std::size_t>(j)], cj = c_tooth[static_cast<std::size_t>(j)];
          sampled[static_cast<std::size_t>(m)] +=
              tooth_on_band(c, m * step + period * j, s_m * cj + c_m * sj, c_m * cj - s_m * sj);
        }
        const double s_next = s_m * c_step + c_m * s_step;
        c_m = c_m * c_step - s_m * s_step;
        s_m = s_next;
      }
      for (int e = 0; e < events; ++e) {
        for (int j = 0; j < teeth; ++j) {
          const double psi = event_angle[static_cast<std::size_t>(e)] + period * j;
          event_force[static_cast<std::size_t>(e)] += tooth_on_band(c, psi, std::sin(psi), std::cos(psi));
        }
      }
    }
  }
  for (int m = 0; m < m_count; ++m) {
    const double mag = sampled[static_cast<std::size_t>(m)].norm();
    if (mag > out.peak_force_n) {
      out = {mag, sampled[static_cast<std::size_t>(m)], m * step};
    }
  }
  for (int e = 0; e < events; ++e) {
    const double mag = event_force[static_cast<std::size_t>(e)].norm();
    if (mag > out.peak_force_n) {
      out = {mag, event_force[static_cast<std::size_t>(e)], event_angle[static_cast<std::size_t>(e)]};
    }
  }
  return out;
}

double feed_per_tooth_m(double feed_mm_min, double spindle_rpm, int flutes) {
  if (!std::isfinite(feed_mm_min) || !(feed_mm_min > 0.0)) {
    throw InputError(fmt::format("feed: {} mm/min: the tool cuts here, so the feed must be positive", feed_mm_min));
  }
  if (!std::isfinite(spindle_rpm) || !(spindle_rpm > 0.0)) {
    throw InputError(
        fmt::format("spindle speed: {} rpm: the tool cuts here, so the spindle must turn (S > 0)", spindle_rpm));
  }
  if (flutes < 1) {
    throw InputError(fmt::format("cutter: flutes: {}: a cutter without flutes does not cut", flutes));
  }
  return feed_mm_min * 1e-3 / (spindle_rpm * flutes);
}

double tooth_passing_frequency_hz(double spindle_rpm, int flutes) noexcept { return spindle_rpm * flutes / 60.0; }

bool make_cut_frame(const Vector3& axis, const Vector3& velocity, CutFrame& out) noexcept {
  const double an = axis.norm(), vn = velocity.norm();
  if (!axis.allFinite() || !velocity.allFinite() || !(an > 1e-12) || !(vn > 0.0)) return false;
  const Vector3 a = axis / an;
  const Vector3 in_plane = velocity - a.dot(velocity) * a;
  const double pn = in_plane.norm();
  if (!(pn > 1e-9 * vn)) return false;
  out.axis = a;
  out.feed = in_plane / pn;
  out.normal = a.cross(out.feed);
  out.in_plane_fraction = pn / vn;
  return true;
}

Wrench milling_wrench(const MillingForce& force, const CutFrame& frame, double point_height_m) noexcept {
  Matrix3 r;
  r.col(0) = frame.feed;
  r.col(1) = frame.normal;
  r.col(2) = frame.axis;
  const Vector3 f = r * force.force_n;
  const Vector3 m_tip = r * force.moment_tip_nm;
  Wrench w;
  w.head<3>() = f;
  w.tail<3>() = m_tip - (point_height_m * frame.axis).cross(f);
  return w;
}

}  // namespace deflex
