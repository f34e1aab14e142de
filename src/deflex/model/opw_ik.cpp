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

/// Nearest whole number of x (|x| < 2^51, halves to even) with two additions and no branch: adding
/// 1.5 * 2^52 leaves no bits below the units, so the addition itself rounds (to nearest, the
/// default mode, which deflex never changes).
inline double nearest_whole(double x) {
  constexpr double kShift = 6755399441055744.0;  // 1.5 * 2^52
  return (x + kShift) - kShift;
}

/// Smallest whole number >= x for 0 <= x < 2^51, without a call into libm.
inline double ceil_whole_nonnegative(double x) {
  const double r = nearest_whole(x);
  return r < x ? r + 1.0 : r;
}

/// The 2*pi turn of q nearest `ref` inside [lo, hi]; false when no turn fits. The turn nearest
/// `ref` is taken without a branch: whether it differs from q depends on the branch and the seed
/// (the other wrist's joints 4 and 6 are half a turn from this one's), a guess no predictor makes
/// well, and a wrong one waits for the angle before it. A turn outside the limits, rarer and
/// predictable, takes the slow way. (A seed exactly half a turn away rounds to even.)
[[gnu::always_inline]] inline bool fit_turn(double q, double ref, double lo, double hi, double& out) {
  double t = q + kTwoPi * nearest_whole((ref - q) * (1.0 / kTwoPi));
  if (t > hi || t < lo) [[unlikely]] {
    if (t > hi + kLimitSlack) {
      t -= kTwoPi * ceil_whole_nonnegative((t - hi - kLimitSlack) * (1.0 / kTwoPi));
    }
    if (t < lo - kLimitSlack) {
      t += kTwoPi * ceil_whole_nonnegative((lo - kLimitSlack - t) * (1.0 / kTwoPi));
    }
    if (t > hi + kLimitSlack || t < lo - kLimitSlack) {
      return false;
    }
    t = t < lo ? lo : (t > hi ? hi : t);
  }
  out = t;
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

/// The limits and seed of an OpwJointFit as plain arrays, so the per-joint test reads no Eigen
/// object (JointVector stores its values contiguously).
struct OpwFitLimits {
  const double* lo = nullptr;  // null: no fit, the joints are not computed
  const double* hi = nullptr;
  const double* ref = nullptr;
};

/// `fit`'s limits and seed (zero without a seed); without `fit`, an empty OpwFitLimits.
inline OpwFitLimits opw_fit_limits(const OpwJointFit* fit) {
  static constexpr std::array<double, kMaxJoints> kZero{};
  if (fit == nullptr) {
    return {};
  }
  return {fit->lower.data(), fit->upper.data(), fit->reference != nullptr ? fit->reference->data() : kZero.data()};
}

/// What every branch of one target shares.
struct OpwTarget {
  const OpwGeometry& g;
  const Matrix3& Re;  // the target's rotation
  Vector3 w;          // the wrist centre
  double theta4_when_singular;
  double near_singular_threshold;
  OpwFitLimits fit;
};

/// Joint i of the model for canonical angle theta at the turn the fit asks for; false when no turn fits.
[[gnu::always_inline]] inline bool opw_fit_joint(const OpwTarget& t, std::size_t i, double theta, double& q) {
  return t.fit.lo == nullptr ||
         fit_turn(t.g.sign[i] * (theta - t.g.offset[i]), t.fit.ref[i], t.fit.lo[i], t.fit.hi[i], q);
}

/// One shoulder: theta1 as (cos, sin) and the planar two-link problem from axis 2 to the wrist centre.
struct OpwShoulder {
  double X, c1, s1;   // the wrist centre is at (X, b, z) in the A1 frame
  double dx, dz, d2;  // from axis 2 to the wrist centre in the arm's plane, and its length squared
  double cg, sg_abs;  // cos and |sin| of the elbow's gamma
  double t1;          // set by the caller
};

/// Shoulder 0 (front) or 1 (back) of the wrist centre, all but theta1; false when the elbow cannot reach it.
inline bool opw_shoulder(const OpwTarget& t, double rho2, double x_abs, int shoulder, OpwShoulder& s) {
  const OpwGeometry& g = t.g;
  const Vector3& w = t.w;
  // In the A1 frame the wrist centre is at (X, b, z); theta1 turns (X, b) onto (w.x, w.y).
  s.X = shoulder == 0 ? x_abs : -x_abs;
  s.c1 = shoulder == 0 ? 1.0 : -1.0;
  s.s1 = 0.0;
  if (rho2 > 1e-24) {
    const double inv = 1.0 / rho2;
    s.c1 = (s.X * w.x() + g.b * w.y()) * inv;
    s.s1 = (s.X * w.y() - g.b * w.x()) * inv;
  }
  // Planar two-link problem from axis 2 to the wrist centre: d = c2 u(theta2) + k u(theta2 + gamma).
  s.dx = s.X - g.a1;
  s.dz = w.z() - g.c1;
  s.d2 = s.dx * s.dx + s.dz * s.dz;
  const double C = (s.d2 - g.c2 * g.c2 - g.k * g.k) * g.inv_2_c2_k;
  if (!(std::abs(C) <= 1.0 + 1e-12)) {
    return false;
  }
  s.cg = std::clamp(C, -1.0, 1.0);
  s.sg_abs = std::sqrt(1.0 - s.cg * s.cg);
  return true;
}

/// One elbow: theta2, theta3 and phi = theta2 + theta3, each as (cos, sin), and the angles theta2, theta3.
struct OpwElbow {
  double sg, c2, s2, c3, s3, t2, t3;
  double cp, sp;  // set by the caller once joints 2 and 3 fit
};

/// Elbow 0 or 1 (the sign of sin gamma) of shoulder s, all but phi; false when the wrist centre is on axis 2.
inline bool opw_elbow(const OpwGeometry& g, const OpwShoulder& s, double gamma, int elbow, OpwElbow& e) {
  e.sg = elbow == 0 ? s.sg_abs : -s.sg_abs;
  const double ex = g.c2 + g.k * s.cg;
  const double ey = g.k * e.sg;
  const double nrm2 = s.d2 * (ex * ex + ey * ey);
  if (!(nrm2 > 0.0)) {
    return false;  // wrist centre on axis 2: theta2 undefined
  }
  // theta2 = angle(d) - angle(ex, ey); theta3 = gamma - psi; phi = theta2 + theta3.
  const double inv_nrm = 1.0 / std::sqrt(nrm2);
  e.c2 = (s.dz * ex + s.dx * ey) * inv_nrm;
  e.s2 = (s.dx * ex - s.dz * ey) * inv_nrm;
  e.c3 = s.cg * g.psi_cos + e.sg * g.psi_sin;
  e.s3 = e.sg * g.psi_cos - s.cg * g.psi_sin;
  e.t2 = unit_vector_angle(e.s2, e.c2);
  e.t3 = (elbow == 0 ? gamma : -gamma) - g.psi;
  return true;
}

/// m = (Rz(theta1) Ry(phi))^T Re = Rz(theta4) Ry(theta5) Rz(theta6), row by row.
inline Matrix3 opw_wrist_rotation(const OpwShoulder& s, const OpwElbow& e, const Matrix3& Re) {
  const Vector3 rc0(s.c1 * e.cp, s.s1 * e.cp, -e.sp);
  const Vector3 rc1(-s.s1, s.c1, 0.0);
  const Vector3 rc2(s.c1 * e.sp, s.s1 * e.sp, e.cp);
  Matrix3 m;
  m.row(0) = rc0.transpose() * Re;
  m.row(1) = rc1.transpose() * Re;
  m.row(2) = rc2.transpose() * Re;
  return m;
}

/// Distance from the wrist centre w of the one the canonical FK puts there, for the check.
inline double opw_wrist_centre_error(const OpwGeometry& g, const Vector3& w, const OpwShoulder& s, const OpwElbow& e) {
  const double xa = g.a1 + g.c2 * e.s2 + g.a2 * e.cp + g.c3 * e.sp;
  const double za = g.c1 + g.c2 * e.c2 - g.a2 * e.sp + g.c3 * e.cp;
  const double ex0 = s.c1 * xa - s.s1 * g.b - w.x();
  const double ex1 = s.s1 * xa + s.c1 * g.b - w.y();
  const double ex2 = za - w.z();
  return std::sqrt(ex0 * ex0 + ex1 * ex1 + ex2 * ex2);
}

/// The singularity a branch is near: the wrist centre's X, the elbow's sin gamma, h = |sin theta5|.
inline Singularity opw_singularity(double X, double sg, double h, double threshold) {
  if (std::abs(X) < threshold) {
    return Singularity::kShoulder;
  }
  if (std::abs(sg) < threshold) {
    return Singularity::kElbow;
  }
  if (h < threshold) {
    return Singularity::kWrist;
  }
  return Singularity::kNone;
}

/// One wrist: theta4, theta5 and theta6 as (cos, sin) pairs and as angles.
struct OpwWrist {
  double c4, s4, c5, s5, c6, s6;
  double t4, t5, t6;
};

/// The first wrist of m, h = |sin theta5|; when exactly singular, theta4 is `theta4_when_singular`.
inline OpwWrist opw_wrist_angles(const Matrix3& m, double h, bool singular, double theta4_when_singular) {
  OpwWrist r;
  if (singular) {
    r.c4 = std::cos(theta4_when_singular);
    r.s4 = std::sin(theta4_when_singular);
    r.c5 = m(2, 2) >= 0.0 ? 1.0 : -1.0;
    r.s5 = 0.0;
  } else {
    // (m22, h) and, below, (c6, s6) are unit pairs up to rounding because m is a rotation, so they
    // need no normalising: atan2 takes any scale and the FK check would see an error.
    const double inv_h = 1.0 / h;
    r.c4 = m(0, 2) * inv_h;
    r.s4 = m(1, 2) * inv_h;
    r.c5 = m(2, 2);
    r.s5 = h;
  }
  // theta6 from what remains once theta4 and theta5 are taken out: exact near the wrist
  // singularity, where theta4 alone is ill-conditioned.
  const double r00 = r.c4 * m(0, 0) + r.s4 * m(1, 0);
  const double r10 = -r.s4 * m(0, 0) + r.c4 * m(1, 0);
  r.c6 = r.c5 * r00 - r.s5 * m(2, 0);
  r.s6 = r10;
  r.t4 = unit_vector_angle(r.s4, r.c4);
  r.t5 = unit_vector_angle(r.s5, r.c5);
  r.t6 = unit_vector_angle(r.s6, r.c6);
  return r;
}

/// Turns a wrist into the other one: Rz(t4 + pi) Ry(-t5) Rz(t6 + pi) is the same rotation.
inline void opw_flip_wrist(OpwWrist& r) {
  r.c4 = -r.c4, r.s4 = -r.s4, r.s5 = -r.s5, r.c6 = -r.c6, r.s6 = -r.s6;
  r.t4 = flip(r.t4), r.t5 = -r.t5, r.t6 = flip(r.t6);
}

/// Frobenius norm of Rz(theta4) Ry(theta5) Rz(theta6) - m, for the check.
inline double opw_rotation_error(const OpwWrist& r, const Matrix3& m) {
  const double e00 = r.c4 * r.c5 * r.c6 - r.s4 * r.s6 - m(0, 0);
  const double e01 = -r.c4 * r.c5 * r.s6 - r.s4 * r.c6 - m(0, 1);
  const double e02 = r.c4 * r.s5 - m(0, 2);
  const double e10 = r.s4 * r.c5 * r.c6 + r.c4 * r.s6 - m(1, 0);
  const double e11 = -r.s4 * r.c5 * r.s6 + r.c4 * r.c6 - m(1, 1);
  const double e12 = r.s4 * r.s5 - m(1, 2);
  const double e20 = -r.s5 * r.c6 - m(2, 0);
  const double e21 = r.s5 * r.s6 - m(2, 1);
  const double e22 = r.c5 - m(2, 2);
  return std::sqrt(e00 * e00 + e01 * e01 + e02 * e02 + e10 * e10 + e11 * e11 + e12 * e12 + e20 * e20 + e21 * e21 +
                   e22 * e22);
}

/// Appends one branch that passed its fit and the FK check to `out`.
inline void opw_emit_branch(const OpwShoulder& s, const OpwElbow& e, const OpwWrist& r, int bits, Singularity sing,
                            double pos_err, double rot_err, const std::array<double, 6>& q, OpwBranches& out) {
  OpwBranch& b = out.branch[static_cast<std::size_t>(out.count++)];
  b.theta = {s.t1, e.t2, e.t3, r.t4, r.t5, r.t6};
  b.wrist_x_a1 = s.X;
  b.lower_arm_cross = e.c2 * s.dx - e.s2 * s.dz;
  b.branch = static_cast<std::uint8_t>(bits);
  b.singularity = sing;
  b.position_error_m = pos_err;
  b.orientation_error = rot_err;
  b.q = q;
}

/// Both wrists of one shoulder and elbow (one when exactly singular): joints 4 to 6 fitted, the FK
/// check, and each branch that passes appended to `out`. `arm_bits` are the branch's shoulder and
/// elbow bits. Both wrists are fitted before either is kept, so the only branches taken on the
/// fits are the two that keep a wrist.
inline void opw_wrist_branches(const OpwTarget& t, const OpwShoulder& s, const OpwElbow& e, const Matrix3& m,
                               int arm_bits, const std::array<double, 6>& q_arm, OpwBranches& out) {
  const double pos_err = opw_wrist_centre_error(t.g, t.w, s, e);
  const double h = std::sqrt(m(0, 2) * m(0, 2) + m(1, 2) * m(1, 2));  // |sin theta5|
  const Singularity sing = opw_singularity(s.X, e.sg, h, t.near_singular_threshold);
  const bool wrist_singular = h < 1e-12;
  const OpwWrist first = opw_wrist_angles(m, h, wrist_singular, t.theta4_when_singular);
  // Only signs flip between the two wrists, so the check's products are bit for bit the same:
  // computed once, for both wrists.
  const double rot_err = opw_rotation_error(first, m);
  if (!(pos_err < kFkCheck && rot_err < kFkCheck)) {
    return;  // the FK is the judge: a branch that does not reproduce the target is dropped
  }
  OpwWrist second = first;
  opw_flip_wrist(second);
  std::array<double, 6> q_first = q_arm;
  std::array<double, 6> q_second = q_arm;
  const bool f4 = opw_fit_joint(t, 3, first.t4, q_first[3]);
  const bool f5 = opw_fit_joint(t, 4, first.t5, q_first[4]);
  const bool f6 = opw_fit_joint(t, 5, first.t6, q_first[5]);
  const bool g4 = opw_fit_joint(t, 3, second.t4, q_second[3]);
  const bool g5 = opw_fit_joint(t, 4, second.t5, q_second[4]);
  const bool g6 = opw_fit_joint(t, 5, second.t6, q_second[5]);
  if (f4 && f5 && f6) {
    opw_emit_branch(s, e, first, arm_bits, sing, pos_err, rot_err, q_first, out);
  }
  if (!wrist_singular && g4 && g5 && g6) {
    opw_emit_branch(s, e, second, arm_bits | 1, sing, pos_err, rot_err, q_second, out);
  }
}

/// Both elbows of shoulder s (whose theta1 fits) that `arms` asks for: joints 2 and 3 of both
/// fitted, then the wrists of each that fits.
inline void opw_elbow_branches(const OpwTarget& t, const OpwShoulder& s, int shoulder, unsigned arms,
                               const std::array<double, 6>& q_shoulder, OpwBranches& out) {
  const double gamma = unit_vector_angle(s.sg_abs, s.cg);
  std::array<OpwElbow, 2> e{};
  std::array<std::array<double, 6>, 2> q{q_shoulder, q_shoulder};
  std::array<bool, 2> fits{false, false};
  for (std::size_t elbow = 0; elbow < 2; ++elbow) {
    const int bit = 2 * shoulder + static_cast<int>(elbow);
    if (((arms >> bit) & 1U) != 0 && opw_elbow(t.g, s, gamma, static_cast<int>(elbow), e[elbow])) {
      const bool f2 = opw_fit_joint(t, 1, e[elbow].t2, q[elbow][1]);
      const bool f3 = opw_fit_joint(t, 2, e[elbow].t3, q[elbow][2]);
      fits[elbow] = f2 && f3;
    }
  }
  for (std::size_t elbow = 0; elbow < 2; ++elbow) {
    if (!fits[elbow]) {
      continue;
    }
    OpwElbow& el = e[elbow];
    el.cp = el.c2 * el.c3 - el.s2 * el.s3;
    el.sp = el.s2 * el.c3 + el.c2 * el.s3;
    opw_wrist_branches(t, s, el, opw_wrist_rotation(s, el, t.Re), (shoulder << 2) | (static_cast<int>(elbow) << 1),
                       q[elbow], out);
  }
}

}  // namespace

void opw_branches(const OpwGeometry& g, const Pose& opw_T_end, double theta4_when_singular,
                  double near_singular_threshold, const OpwJointFit* fit, OpwBranches& out, unsigned arms) {
  std::array<double, 6> q{};
  out.count = 0;
  out.reachable = false;
  const Matrix3& Re = opw_T_end.linear();
  const OpwTarget t{g,
                    Re,
                    opw_T_end.translation() - g.c4 * Re.col(2),
                    theta4_when_singular,
                    near_singular_threshold,
                    opw_fit_limits(fit)};
  const Vector3& w = t.w;
  const double rho2 = w.x() * w.x() + w.y() * w.y();
  const double x2 = rho2 - g.b * g.b;
  if (x2 < -1e-12) {
    return;  // the wrist centre is inside the cylinder the lateral offset b sweeps about axis 1
  }
  const double x_abs = std::sqrt(std::max(0.0, x2));
  double t1_front = 0.0;
  bool front_done = false;
  for (int shoulder = 0; shoulder < 2; ++shoulder) {
    const unsigned shoulder_arms = (arms >> (2 * shoulder)) & 3U;
    // A front shoulder not asked for is still solved when the back one takes its theta1 from it,
    // so the back shoulder's answer is the same whichever arms are asked for.
    const bool feeds_back = shoulder == 0 && g.b == 0.0 && ((arms >> 2U) & 3U) != 0;
    OpwShoulder s;
    if ((shoulder_arms == 0 && !feeds_back) || !opw_shoulder(t, rho2, x_abs, shoulder, s)) {
      continue;
    }
    // Without a lateral offset the back shoulder is the front one turned by pi.
    s.t1 = shoulder == 1 && front_done && g.b == 0.0 && rho2 > 1e-24 ? flip(t1_front) : unit_vector_angle(s.s1, s.c1);
    t1_front = s.t1;
    front_done = true;
    if (shoulder_arms == 0) {
      continue;
    }
    out.reachable = true;
    if (opw_fit_joint(t, 0, s.t1, q[0])) {
      opw_elbow_branches(t, s, shoulder, arms, q, out);
    }
  }
}

void opw_solutions(const RobotModel& model, const Pose& base_T_tcp, const JointVector* seed, OpwSolutions& out,
                   double near_singular_threshold, unsigned arms) {
  out.count = 0;
  const OpwGeometry* g = model.opw();
  if (g == nullptr || (seed != nullptr && seed->size() != 6)) {
    out.status = IkStatus::kInvalidInput;
    return;
  }
  // opw_T_base * base_T_tcp * tcp_T_end as plain 3x3 products, inlined (Eigen's product of two
  // isometries is a call and a tenth of this function's instructions).
  Pose target;
  if (g->frames_unrotated) {
    target.linear() = base_T_tcp.linear();
    target.translation() =
        base_T_tcp.linear() * g->tcp_T_end.translation() + base_T_tcp.translation() + g->opw_T_base.translation();
  } else {
    const Matrix3 opw_R_tcp = g->opw_T_base.linear() * base_T_tcp.linear();
    target.linear() = opw_R_tcp * g->tcp_T_end.linear();
    target.translation() = opw_R_tcp * g->tcp_T_end.translation() + g->opw_T_base.linear() * base_T_tcp.translation() +
                           g->opw_T_base.translation();
  }
  OpwBranches branches;
  const OpwJointFit fit{model.lower_limits(), model.upper_limits(), seed};
  opw_branches(*g, target, g->theta(3, seed != nullptr ? (*seed)[3] : 0.0), near_singular_threshold, &fit, branches,
               arms);
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
