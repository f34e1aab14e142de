// Deriving the OPW lengths, signs and offsets from a chain's axes at its zero pose.
#include "deflex/model/opw_geometry.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/model/folded_chain.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/model/robot_model.hpp"

namespace deflex {
namespace {

// Geometric tolerance, m and rad. Datasheet geometry is exact to far better than this; a URDF whose
// axes are off by more (rpy written with 3.14) is treated as not ortho-parallel and gets the
// numerical solver rather than an analytic one that misses by that much.
constexpr double kTol = 1e-9;

Matrix3 rot_y(double a) { return Eigen::AngleAxisd(a, Vector3::UnitY()).toRotationMatrix(); }
Matrix3 rot_z(double a) { return Eigen::AngleAxisd(a, Vector3::UnitZ()).toRotationMatrix(); }

/// Points on the two lines closest to each other; false when the lines are parallel.
bool closest_points(const Vector3& p, const Vector3& u, const Vector3& q, const Vector3& v, Vector3& on_first,
                    Vector3& on_second) {
  const double uv = u.dot(v);
  const double den = 1.0 - uv * uv;
  if (den < 1e-12) {
    return false;
  }
  const Vector3 w = p - q;
  const double s = (uv * v.dot(w) - u.dot(w)) / den;
  const double t = (v.dot(w) - uv * u.dot(w)) / den;
  on_first = p + s * u;
  on_second = q + t * v;
  return true;
}

double distance_to_line(const Vector3& x, const Vector3& p, const Vector3& u) { return (x - p).cross(u).norm(); }

}  // namespace

Pose opw_forward(const OpwGeometry& g, const std::array<double, 6>& th) {
  const double phi = th[1] + th[2];
  const Vector3 w_a1 = opw_wrist_centre_a1(g, th[1], phi);
  const Matrix3 Rz1 = rot_z(th[0]);
  const Matrix3 R = Rz1 * rot_y(phi) * rot_z(th[3]) * rot_y(th[4]) * rot_z(th[5]);
  Pose E = Pose::Identity();
  E.linear() = R;
  E.translation() = Rz1 * w_a1 + g.c4 * R.col(2);
  return E;
}

namespace {

// The chain at q = 0 in its own frame: the joint axes, a point on each, the flange.
struct ChainAtZero {
  std::array<Vector3, 6> axis;
  std::array<Vector3, 6> point;
  Pose flange = Pose::Identity();
};

ChainAtZero chain_at_zero(const RobotDescription& d) {
  ChainAtZero c;
  Matrix3 R = Matrix3::Identity();
  Vector3 p = Vector3::Zero();
  for (int i = 0; i < 6; ++i) {
    const JointSpec& j = d.joints[static_cast<std::size_t>(i)];
    p += R * j.parent_T_joint.translation();
    R = R * j.parent_T_joint.linear();
    c.axis[static_cast<std::size_t>(i)] = (R * j.axis).normalized();
    c.point[static_cast<std::size_t>(i)] = p;
    R = R * Eigen::AngleAxisd(j.offset_rad, j.axis).toRotationMatrix();
  }
  c.flange.linear() = R * d.last_T_flange.linear();
  c.flange.translation() = p + R * d.last_T_flange.translation();
  return c;
}

// The arm's plane: axis 1 as z, axis 2 as y, the shoulder (a1, c1) and the upper arm (c2), and where
// axis 3 stands in that frame. Empty, with why_not, when axes 1-3 are not ortho-parallel.
struct ArmPlane {
  Vector3 x, y, z, origin;
  double x3 = 0.0, z3 = 0.0;  // axis 3's point in the plane
};

std::optional<ArmPlane> arm_plane(const ChainAtZero& c, OpwGeometry& g, std::string& why_not) {
  ArmPlane a;
  // Axis 1: canonical z, pointing up the chain's z where it can.
  a.z = c.axis[0];
  g.sign[0] = 1.0;
  if (a.z.z() < -kTol) {
    a.z = -a.z;
    g.sign[0] = -1.0;
  }
  a.origin = c.point[0] + (Vector3::Zero() - c.point[0]).dot(a.z) * a.z;  // the chain origin's foot on axis 1
  if (std::abs(c.axis[1].dot(a.z)) > kTol) {
    why_not = "axis 2 is not perpendicular to axis 1";
    return std::nullopt;
  }
  if (c.axis[2].cross(c.axis[1]).norm() > kTol) {
    why_not = "axes 2 and 3 are not parallel";
    return std::nullopt;
  }
  a.y = c.axis[1];
  a.x = a.y.cross(a.z);
  g.a1 = (c.point[1] - a.origin).dot(a.x);
  if (g.a1 < -kTol || (std::abs(g.a1) <= kTol && a.y.y() < -kTol)) {
    a.y = -a.y;
    a.x = -a.x;
    g.a1 = -g.a1;
  }
  g.a1 = std::abs(g.a1) <= kTol ? 0.0 : g.a1;
  g.sign[1] = c.axis[1].dot(a.y) > 0.0 ? 1.0 : -1.0;
  g.sign[2] = c.axis[2].dot(a.y) > 0.0 ? 1.0 : -1.0;
  g.c1 = (c.point[1] - a.origin).dot(a.z);
  a.x3 = (c.point[2] - a.origin).dot(a.x);
  a.z3 = (c.point[2] - a.origin).dot(a.z);
  g.c2 = std::hypot(a.x3 - g.a1, a.z3 - g.c1);
  if (g.c2 <= kTol) {
    why_not = "axes 2 and 3 coincide (no upper arm)";
    return std::nullopt;
  }
  g.offset[1] = std::atan2(a.x3 - g.a1, a.z3 - g.c1);
  return a;
}

// Spherical wrist: axes 4 and 5 meet, axis 6 passes through the same point; the forearm (a2, b, c3),
// the hand (c4), the wrist's signs and offsets, and the frames between the chain's and the canonical
// arm's. False, with why_not, when the wrist is not spherical or there is no forearm.
bool wrist(const ChainAtZero& c, const ArmPlane& a, OpwGeometry& g, std::string& why_not) {
  if (std::abs(c.axis[3].dot(a.y)) > kTol) {
    why_not = "axis 4 is not perpendicular to axes 2 and 3";
    return false;
  }
  if (std::abs(c.axis[4].dot(c.axis[3])) > kTol || std::abs(c.axis[5].dot(c.axis[4])) > kTol) {
    why_not = "wrist axes 4-5 or 5-6 are not perpendicular";
    return false;
  }
  Vector3 wc;
  Vector3 on5;
  if (!closest_points(c.point[3], c.axis[3], c.point[4], c.axis[4], wc, on5) || (wc - on5).norm() > kTol ||
      distance_to_line(wc, c.point[5], c.axis[5]) > kTol) {
    why_not = "axes 4, 5 and 6 do not meet in one point (no spherical wrist)";
    return false;
  }
  g.b = (wc - a.origin).dot(a.y);
  const double vx = (wc - a.origin).dot(a.x) - a.x3;
  const double vz = (wc - a.origin).dot(a.z) - a.z3;
  // Axis 4 points from axis 3 towards the wrist centre.
  Vector3 z4 = c.axis[3];
  g.sign[3] = 1.0;
  if (vx * z4.dot(a.x) + vz * z4.dot(a.z) < 0.0) {
    z4 = -z4;
    g.sign[3] = -1.0;
  }
  const double phi0 = std::atan2(z4.dot(a.x), z4.dot(a.z));
  g.c3 = vx * std::sin(phi0) + vz * std::cos(phi0);
  g.a2 = vx * std::cos(phi0) - vz * std::sin(phi0);
  g.offset[2] = phi0 - g.offset[1];

  Matrix3 basis;
  basis.col(0) = a.x;
  basis.col(1) = a.y;
  basis.col(2) = a.z;
  const Matrix3 Rc0 = basis * rot_y(phi0);
  // Axis 5 and 6 directions in the forearm frame; signs chosen so the offsets stay within +-90 deg.
  const Vector3 y5 = Rc0.transpose() * c.axis[4];
  g.sign[4] = y5.y() >= 0.0 ? 1.0 : -1.0;
  g.offset[3] = std::atan2(-g.sign[4] * y5.x(), g.sign[4] * y5.y());
  const Matrix3 G = Rc0 * rot_z(g.offset[3]);
  const Vector3 z6 = G.transpose() * c.axis[5];
  g.sign[5] = z6.z() >= 0.0 ? 1.0 : -1.0;
  g.offset[4] = std::atan2(g.sign[5] * z6.x(), g.sign[5] * z6.z());
  g.offset[5] = 0.0;
  const Matrix3 E0 = G * rot_y(g.offset[4]);
  g.c4 = (c.flange.translation() - wc).dot(E0.col(2));

  g.chain_T_opw = Pose::Identity();
  g.chain_T_opw.linear() = basis;
  g.chain_T_opw.translation() = a.origin;
  Pose end0 = Pose::Identity();
  end0.linear() = E0;
  end0.translation() = wc + g.c4 * E0.col(2);
  g.end_T_flange = end0.inverse() * c.flange;

  g.k = std::hypot(g.a2, g.c3);
  if (g.k <= kTol) {
    why_not = "the wrist centre lies on axis 3 (no forearm)";
    return false;
  }
  return true;
}

// The judge: the canonical arm must reproduce the model's flange, joint signs and offsets included.
bool reproduces_chain(const RobotModel& model, const OpwGeometry& g) {
  const RobotDescription& d = model.description();
  Workspace ws(model);
  for (int s = 0; s < 8; ++s) {
    JointVector q(6);
    std::array<double, 6> th{};
    for (int i = 0; i < 6; ++i) {
      q[i] = s == 0 ? 0.0 : 1.7 * std::sin(1.3 * s + 2.1 * i);
      th[static_cast<std::size_t>(i)] = g.theta(i, q[i]);
    }
    forward_kinematics(model, ws, q);
    const Pose want = ws.base_T_flange;
    const Pose got = d.base_T_chain * g.chain_T_opw * opw_forward(g, th) * g.end_T_flange;
    if ((want.translation() - got.translation()).norm() > kTol || (want.linear() - got.linear()).norm() > kTol) {
      return false;
    }
  }
  return true;
}

}  // namespace

std::optional<OpwGeometry> derive_opw_geometry(const RobotModel& model, std::string& why_not) {
  const RobotDescription& d = model.description();
  if (model.dof() != 6) {
    why_not = fmt::format("{} joints (the ortho-parallel solver needs 6)", model.dof());
    return std::nullopt;
  }
  const ChainAtZero chain = chain_at_zero(d);
  OpwGeometry g;
  const std::optional<ArmPlane> plane = arm_plane(chain, g, why_not);
  if (!plane || !wrist(chain, *plane, g, why_not)) return std::nullopt;
  // The constants the solver uses every call.
  g.psi_cos = g.c3 / g.k;
  g.psi_sin = g.a2 / g.k;
  g.psi = std::atan2(g.a2, g.c3);
  g.inv_2_c2_k = 1.0 / (2.0 * g.c2 * g.k);
  g.q3_stretched = g.joint(2, -std::atan2(g.a2, g.c3));
  g.opw_T_base = (d.base_T_chain * g.chain_T_opw).inverse();
  g.tcp_T_end = (g.end_T_flange * d.flange_T_tcp).inverse();
  g.frames_unrotated = fold_step(g.opw_T_base).turn == FoldedStep::Turn::kIdentity &&
                       fold_step(g.tcp_T_end).turn == FoldedStep::Turn::kIdentity;
  if (!reproduces_chain(model, g)) {
    why_not = "the derived ortho-parallel parameters do not reproduce the chain";
    return std::nullopt;
  }
  return g;
}

}  // namespace deflex
