// Closed-form branches of an ortho-parallel arm. Angles are carried as (cos, sin) pairs from the
// target to the FK check, so atan2 runs once per output angle and no other trigonometry runs.
#include "deflex/model/opw_ik.hpp"

#include <algorithm>
#include <cmath>

#include "deflex/model/detail/fast_atan2.hpp"
#include "deflex/model/robot_model.hpp"

namespace deflex {
namespace {

constexpr double kTwoPi = 2.0 * kPi;
constexpr double kFkCheck = 1e-8;     // m, and rotation-matrix difference
constexpr double kLimitSlack = 1e-9;  // rad: a solution this close to a limit counts as inside (and is clamped)

double flip(double angle) { return angle > 0.0 ? angle - kPi : angle + kPi; }

/// Nearest whole number of x (|x| < 2^52), without a call into libm: this runs for every joint of
/// every solution.
double round_whole(double x) {
  const double r = static_cast<double>(static_cast<long long>(x));  // truncates towards zero
  const double f = x - r;
  return f >= 0.5 ? r + 1.0 : (f <= -0.5 ? r - 1.0 : r);
}

/// Smallest whole number >= x (|x| < 2^52).
double ceil_whole(double x) {
  const double r = static_cast<double>(static_cast<long long>(x));
  return r < x ? r + 1.0 : r;
}

/// The 2*pi turn of q nearest `ref` inside [lo, hi]; false when no turn fits. Rounds only when the
/// turn differs from q (the common case along a path is no rounding at all).
inline bool fit_turn(double q, double ref, double lo, double hi, double& out) {
  double t = q;
  const double d = ref - t;
  if (d > kPi || d < -kPi) {
    t += kTwoPi * round_whole(d * (1.0 / kTwoPi));
  }
  if (t > hi + kLimitSlack) {
    t -= kTwoPi * ceil_whole((t - hi - kLimitSlack) * (1.0 / kTwoPi));
  }
  if (t < lo - kLimitSlack) {
    t += kTwoPi * ceil_whole((lo - kLimitSlack - t) * (1.0 / kTwoPi));
  }
  if (t > hi + kLimitSlack || t < lo - kLimitSlack) {
    return false;
  }
  out = t < lo ? lo : (t > hi ? hi : t);
  return true;
}

/// floor(q / 90 deg) without a call into libm (this runs three times per solution).
int quadrant(double q) {
  const double x = q * (2.0 / kPi) + 1e-12;
  const int i = static_cast<int>(x);
  return x < static_cast<double>(i) ? i - 1 : i;
}

int kuka_status(const OpwGeometry& g, double wrist_x_a1, double q3, double q5) {
  double d = q3 - g.q3_stretched;
  d -= kTwoPi * round_whole(d * (1.0 / kTwoPi));
  return (wrist_x_a1 < 0.0 ? 1 : 0) | (d >= 0.0 ? 2 : 0) | (negative_joint(q5) ? 4 : 0);
}

int abb_cfx(const OpwGeometry& g, double wrist_x_a1, double lower_arm_cross, double q5) {
  return (wrist_x_a1 < 0.0 ? 4 : 0) + (g.sign[1] * lower_arm_cross < 0.0 ? 2 : 0) + (negative_joint(q5) ? 1 : 0);
}

}  // namespace

void opw_branches(const OpwGeometry& g, const Pose& opw_T_end, double theta4_when_singular,
                  double near_singular_threshold, const OpwJointFit* fit, OpwBranches& out) {
  // Joint i of the model for canonical angle theta at the turn `fit` asks for; false when no turn
  // fits. Limits and references copied once, so the per-joint test reads no pointers.
  std::array<double, 6> lo{}, hi{}, ref{};
  if (fit != nullptr) {
    for (int i = 0; i < 6; ++i) {
      lo[static_cast<std::size_t>(i)] = fit->lower[i];
      hi[static_cast<std::size_t>(i)] = fit->upper[i];
      ref[static_cast<std::size_t>(i)] = fit->reference != nullptr ? (*fit->reference)[i] : 0.0;
    }
  }
  const auto fit_joint = [&](std::size_t i, double theta, double& q) {
    return fit == nullptr || fit_turn(g.sign[i] * (theta - g.offset[i]), ref[i], lo[i], hi[i], q);
  };
  std::array<double, 6> q{};
  out.count = 0;
  out.reachable = false;
  const Matrix3& Re = opw_T_end.linear();
  const Vector3 w = opw_T_end.translation() - g.c4 * Re.col(2);
  const double rho2 = w.x() * w.x() + w.y() * w.y();
  const double x2 = rho2 - g.b * g.b;
  if (x2 < -1e-12) {
    return;  // the wrist centre is inside the cylinder the lateral offset b sweeps about axis 1
  }
  const double x_abs = std::sqrt(std::max(0.0, x2));
  double t1_front = 0.0;
  bool front_done = false;
  for (int shoulder = 0; shoulder < 2; ++shoulder) {
    // In the A1 frame the wrist centre is at (X, b, z); theta1 turns (X, b) onto (w.x, w.y).
    const double X = shoulder == 0 ? x_abs : -x_abs;
    double c1 = shoulder == 0 ? 1.0 : -1.0;
    double s1 = 0.0;
    if (rho2 > 1e-24) {
      const double inv = 1.0 / rho2;
      c1 = (X * w.x() + g.b * w.y()) * inv;
      s1 = (X * w.y() - g.b * w.x()) * inv;
    }
    // Planar two-link problem from axis 2 to the wrist centre: d = c2 u(theta2) + k u(theta2 + gamma).
    const double dx = X - g.a1;
    const double dz = w.z() - g.c1;
    const double d2 = dx * dx + dz * dz;
    const double C = (d2 - g.c2 * g.c2 - g.k * g.k) * g.inv_2_c2_k;
    if (!(std::abs(C) <= 1.0 + 1e-12)) {
      continue;
    }
    out.reachable = true;
    const double cg = std::clamp(C, -1.0, 1.0);
    const double sg_abs = std::sqrt(1.0 - cg * cg);
    // Without a lateral offset the back shoulder is the front one turned by pi.
    const double t1 = shoulder == 1 && front_done && g.b == 0.0 && rho2 > 1e-24 ? flip(t1_front) : fast_atan2(s1, c1);
    t1_front = t1;
    front_done = true;
    if (!fit_joint(0, t1, q[0])) {
      continue;
    }
    const double gamma = fast_atan2(sg_abs, cg);
    for (int elbow = 0; elbow < 2; ++elbow) {
      const double sg = elbow == 0 ? sg_abs : -sg_abs;
      const double ex = g.c2 + g.k * cg;
      const double ey = g.k * sg;
      const double nrm2 = d2 * (ex * ex + ey * ey);
      if (!(nrm2 > 0.0)) {
        continue;  // wrist centre on axis 2: theta2 undefined
      }
      // theta2 = angle(d) - angle(ex, ey); theta3 = gamma - psi; phi = theta2 + theta3.
      const double inv_nrm = 1.0 / std::sqrt(nrm2);
      const double c2 = (dz * ex + dx * ey) * inv_nrm;
      const double s2 = (dx * ex - dz * ey) * inv_nrm;
      const double c3 = cg * g.psi_cos + sg * g.psi_sin;
      const double s3 = sg * g.psi_cos - cg * g.psi_sin;
      const double t2 = fast_atan2(s2, c2);
      const double t3 = (elbow == 0 ? gamma : -gamma) - g.psi;
      if (!fit_joint(1, t2, q[1]) || !fit_joint(2, t3, q[2])) {
        continue;
      }
      const double cp = c2 * c3 - s2 * s3;
      const double sp = s2 * c3 + c2 * s3;
      // m = (Rz(theta1) Ry(phi))^T Re = Rz(theta4) Ry(theta5) Rz(theta6), row by row.
      const Vector3 rc0(c1 * cp, s1 * cp, -sp);
      const Vector3 rc1(-s1, c1, 0.0);
      const Vector3 rc2(c1 * sp, s1 * sp, cp);
      Matrix3 m;
      m.row(0) = rc0.transpose() * Re;
      m.row(1) = rc1.transpose() * Re;
      m.row(2) = rc2.transpose() * Re;

      // The wrist centre the canonical FK puts there, for the check.
      const double xa = g.a1 + g.c2 * s2 + g.a2 * cp + g.c3 * sp;
      const double za = g.c1 + g.c2 * c2 - g.a2 * sp + g.c3 * cp;
      const double ex0 = c1 * xa - s1 * g.b - w.x();
      const double ex1 = s1 * xa + c1 * g.b - w.y();
      const double ex2 = za - w.z();
      const double pos_err = std::sqrt(ex0 * ex0 + ex1 * ex1 + ex2 * ex2);
      const double h = std::sqrt(m(0, 2) * m(0, 2) + m(1, 2) * m(1, 2));  // |sin theta5|
      Singularity sing = Singularity::kNone;
      if (std::abs(X) < near_singular_threshold) {
        sing = Singularity::kShoulder;
      } else if (std::abs(sg) < near_singular_threshold) {
        sing = Singularity::kElbow;
      } else if (h < near_singular_threshold) {
        sing = Singularity::kWrist;
      }
      const bool wrist_singular = h < 1e-12;
      double c4, s4, c5, s5;
      if (wrist_singular) {
        c4 = std::cos(theta4_when_singular);
        s4 = std::sin(theta4_when_singular);
        c5 = m(2, 2) >= 0.0 ? 1.0 : -1.0;
        s5 = 0.0;
      } else {
        // (m22, h) and, below, (c6, s6) are unit pairs up to rounding because m is a rotation, so they
        // need no normalising: atan2 takes any scale and the FK check would see an error.
        const double inv_h = 1.0 / h;
        c4 = m(0, 2) * inv_h;
        s4 = m(1, 2) * inv_h;
        c5 = m(2, 2);
        s5 = h;
      }
      // theta6 from what remains once theta4 and theta5 are taken out: exact near the wrist
      // singularity, where theta4 alone is ill-conditioned.
      const double r00 = c4 * m(0, 0) + s4 * m(1, 0);
      const double r10 = -s4 * m(0, 0) + c4 * m(1, 0);
      double c6 = c5 * r00 - s5 * m(2, 0);
      double s6 = r10;
      double t4 = fast_atan2(s4, c4);
      double t5 = fast_atan2(s5, c5);
      double t6 = fast_atan2(s6, c6);
      double rot_err = 0.0;
      for (int wrist = 0; wrist < (wrist_singular ? 1 : 2); ++wrist) {
        if (wrist == 1) {  // Rz(t4 + pi) Ry(-t5) Rz(t6 + pi) is the same rotation
          c4 = -c4, s4 = -s4, s5 = -s5, c6 = -c6, s6 = -s6;
          t4 = flip(t4), t5 = -t5, t6 = flip(t6);
        }
        if (!fit_joint(3, t4, q[3]) || !fit_joint(4, t5, q[4]) || !fit_joint(5, t6, q[5])) {
          continue;
        }
        // Only signs flip between the two wrists, so the check's products are bit for bit the same:
        // computed once.
        if (wrist == 0) {
          const double e00 = c4 * c5 * c6 - s4 * s6 - m(0, 0);
          const double e01 = -c4 * c5 * s6 - s4 * c6 - m(0, 1);
          const double e02 = c4 * s5 - m(0, 2);
          const double e10 = s4 * c5 * c6 + c4 * s6 - m(1, 0);
          const double e11 = -s4 * c5 * s6 + c4 * c6 - m(1, 1);
          const double e12 = s4 * s5 - m(1, 2);
          const double e20 = -s5 * c6 - m(2, 0);
          const double e21 = s5 * s6 - m(2, 1);
          const double e22 = c5 - m(2, 2);
          rot_err = std::sqrt(e00 * e00 + e01 * e01 + e02 * e02 + e10 * e10 + e11 * e11 + e12 * e12 + e20 * e20 +
                              e21 * e21 + e22 * e22);
        }
        if (!(pos_err < kFkCheck && rot_err < kFkCheck)) {
          continue;  // the FK is the judge: a branch that does not reproduce the target is dropped
        }
        OpwBranch& b = out.branch[static_cast<std::size_t>(out.count++)];
        b.theta = {t1, t2, t3, t4, t5, t6};
        b.wrist_x_a1 = X;
        b.lower_arm_cross = c2 * dx - s2 * dz;
        b.branch = static_cast<std::uint8_t>((shoulder << 2) | (elbow << 1) | wrist);
        b.singularity = sing;
        b.position_error_m = pos_err;
        b.orientation_error = rot_err;
        b.q = q;
      }
    }
  }
}

void opw_solutions(const RobotModel& model, const Pose& base_T_tcp, const JointVector* seed, OpwSolutions& out,
                   double near_singular_threshold) {
  out.count = 0;
  const OpwGeometry* g = model.opw();
  if (g == nullptr || (seed != nullptr && seed->size() != 6)) {
    out.status = IkStatus::kInvalidInput;
    return;
  }
  const Pose target = g->opw_T_base * base_T_tcp * g->tcp_T_end;
  OpwBranches branches;
  const OpwJointFit fit{model.lower_limits(), model.upper_limits(), seed};
  opw_branches(*g, target, g->theta(3, seed != nullptr ? (*seed)[3] : 0.0), near_singular_threshold, &fit, branches);
  if (!branches.reachable) {
    out.status = IkStatus::kUnreachable;
    return;
  }
  bool near_singular = false;
  for (int k = 0; k < branches.count; ++k) {
    const OpwBranch& b = branches.branch[static_cast<std::size_t>(k)];
    OpwSolution& s = out.solution[static_cast<std::size_t>(out.count++)];
    int turn = 0;
    for (int i = 0; i < 6; ++i) {
      s.q[i] = b.q[static_cast<std::size_t>(i)];
      turn |= negative_joint(s.q[i]) ? (1 << i) : 0;
    }
    s.configuration = {quadrant(s.q[0]), quadrant(s.q[3]), quadrant(s.q[5]),
                       abb_cfx(*g, b.wrist_x_a1, b.lower_arm_cross, s.q[4])};
    s.kuka.status = kuka_status(*g, b.wrist_x_a1, s.q[2], s.q[4]);
    s.kuka.turn = turn;
    s.branch = b.branch;
    s.singularity = b.singularity;
    s.position_error_m = b.position_error_m;
    s.orientation_error = b.orientation_error;
    near_singular = near_singular || b.singularity != Singularity::kNone;
  }
  if (out.count == 0) {
    out.status = IkStatus::kOutsideJointLimits;
  } else {
    out.status = near_singular ? IkStatus::kNearSingular : IkStatus::kOk;
  }
}

void opw_configuration(const OpwGeometry& g, const JointVector& q, ArmConfiguration& abb, KukaConfiguration& kuka) {
  const double t2 = g.theta(1, q[1]);
  const double phi = t2 + g.theta(2, q[2]);
  const Vector3 wc = opw_wrist_centre_a1(g, t2, phi);
  const double cross = std::cos(t2) * (wc.x() - g.a1) - std::sin(t2) * (wc.z() - g.c1);
  abb = {abb_quadrant(q[0]), abb_quadrant(q[3]), abb_quadrant(q[5]), abb_cfx(g, wc.x(), cross, q[4])};
  kuka.status = kuka_status(g, wc.x(), q[2], q[4]);
  kuka.turn = kuka_turn(q);
}

}  // namespace deflex
