// Forward kinematics and geometric Jacobian: one pass over the chain folded at load (folded_chain.hpp).
#include "deflex/model/kinematics.hpp"

#include <array>
#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "deflex/model/detail/joint_sincos.hpp"
#include "deflex/model/detail/kinematics_count.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

[[noreturn, gnu::cold]] void wrong_size(const RobotModel& model, const Workspace& ws, const JointVector& q) {
  if (ws.dof != model.dof()) {
    throw InputError(fmt::format("forward_kinematics: the workspace was made for a robot of {} joints, {} has {}",
                                 ws.dof, model.name(), model.dof()));
  }
  throw InputError(fmt::format("forward_kinematics: {} joint values for {}, which has {} joints", q.size(),
                               model.name(), model.dof()));
}

}  // namespace

Workspace::Workspace(const RobotModel& model) : dof(model.dof()) {
  q = JointVector::Zero(dof);
  jacobian = Jacobian::Zero(6, dof);
}

namespace {

// A frame as forward kinematics carries it: the columns of its rotation and its origin, base frame.
struct Frame {
  Vector3 x, y, z, p;
};

// frame <- frame * step: the translation first (in the frame before the step's turn), then the turn.
[[gnu::always_inline]] inline void apply(const FoldedStep& step, Frame& f) {
  const std::uint8_t mask = step.translation_mask;
  if ((mask & 1U) != 0) f.p += step.translation[0] * f.x;
  if ((mask & 2U) != 0) f.p += step.translation[1] * f.y;
  if ((mask & 4U) != 0) f.p += step.translation[2] * f.z;
  switch (step.turn) {
    case FoldedStep::Turn::kIdentity:
      break;
    case FoldedStep::Turn::kAboutX: {
      const Vector3 y = f.y;
      f.y = step.c * y + step.s * f.z;
      f.z = step.c * f.z - step.s * y;
      break;
    }
    case FoldedStep::Turn::kQuarterX: {
      // The permutation's products by +-1 are exact, so this is the same as its general form.
      const Vector3 y = f.y;
      f.y = step.s * f.z;
      f.z = -step.s * y;
      break;
    }
    case FoldedStep::Turn::kPermutation: {
      const std::array<Vector3, 3> cols{f.x, f.y, f.z};
      f.x = step.sign[0] * cols[step.perm[0]];
      f.y = step.sign[1] * cols[step.perm[1]];
      f.z = step.sign[2] * cols[step.perm[2]];
      break;
    }
    case FoldedStep::Turn::kGeneral: {
      Matrix3 r;
      r << f.x, f.y, f.z;
      const Matrix3 turned = r * step.rotation;
      f.x = turned.col(0);
      f.y = turned.col(1);
      f.z = turned.col(2);
      break;
    }
  }
}

// The pose of a frame.
inline void store(const Frame& f, Pose& out) {
  out.linear().col(0) = f.x;
  out.linear().col(1) = f.y;
  out.linear().col(2) = f.z;
  out.translation() = f.p;
}

}  // namespace

void forward_kinematics(const RobotModel& model, Workspace& ws, const JointVector& q) {
  if (q.size() != model.dof() || ws.dof != model.dof()) [[unlikely]] {
    wrong_size(model, ws, q);
  }
  if (&model == detail::kinematics_count.model) [[unlikely]]
    ++detail::kinematics_count.calls;
  const FoldedChain& chain = model.folded_chain();
  const int n = chain.dof;
  ws.q = q;
  // One sin/cos pass over the joints first, then the walk: every joint turns about its frame's z.
  std::array<double, kMaxJoints> angle{};
  for (int i = 0; i < n; ++i) {
    angle[static_cast<std::size_t>(i)] = q[i] + chain.offset_rad[static_cast<std::size_t>(i)];
  }
  std::array<double, kMaxJoints> c{};
  std::array<double, kMaxJoints> s{};
  detail::joint_sincos(angle, n, c, s);
  Frame f{chain.first_rotation.col(0), chain.first_rotation.col(1), chain.first_rotation.col(2), chain.first_origin};
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (i > 0) apply(chain.steps[k], f);
    ws.axis_base[k] = f.z;
    ws.origin_base[k] = f.p;
    // frame * Rz(angle): only the first two columns change.
    const Vector3 x = f.x;
    f.x = c[k] * x + s[k] * f.y;
    f.y = c[k] * f.y - s[k] * x;
  }
  apply(chain.last_to_flange, f);
  store(f, ws.base_T_flange);
  Frame end = f;
  apply(chain.flange_to_tcp, end);
  store(end, ws.base_T_tcp);
  if (model.wap_is_tcp()) {
    ws.base_T_wap = ws.base_T_tcp;
  } else {
    apply(chain.flange_to_wap, f);
    store(f, ws.base_T_wap);
  }
}

void point_jacobian(const Workspace& ws, const Vector3& point_base, Jacobian& J) {
  J.resize(6, ws.dof);
  double* col = J.data();  // column-major, 6 rows: a column is 6 doubles in a row
  const double px = point_base.x(), py = point_base.y(), pz = point_base.z();
  for (int i = 0; i < ws.dof; ++i, col += 6) {
    const Vector3& z = ws.axis_base[static_cast<std::size_t>(i)];
    const Vector3& o = ws.origin_base[static_cast<std::size_t>(i)];
    const double rx = px - o.x(), ry = py - o.y(), rz = pz - o.z();
    col[0] = z.y() * rz - z.z() * ry;
    col[1] = z.z() * rx - z.x() * rz;
    col[2] = z.x() * ry - z.y() * rx;
    col[3] = z.x();
    col[4] = z.y();
    col[5] = z.z();
  }
}

const Pose& end_pose(const Workspace& ws, EndPoint point) {
  switch (point) {
    case EndPoint::kFlange:
      return ws.base_T_flange;
    case EndPoint::kTcp:
      return ws.base_T_tcp;
    case EndPoint::kWap:
      break;
  }
  return ws.base_T_wap;
}

void jacobian(const RobotModel& model, Workspace& ws, const JointVector& q, EndPoint point, Jacobian& J) {
  forward_kinematics(model, ws, q);
  point_jacobian(ws, end_pose(ws, point).translation(), J);
}

Pose tcp_pose(const RobotModel& model, Workspace& ws, const JointVector& q) {
  forward_kinematics(model, ws, q);
  return ws.base_T_tcp;
}

Displacement pose_difference(const Pose& a, const Pose& b) {
  Displacement d;
  d.head<3>() = b.translation() - a.translation();
  const Eigen::AngleAxisd aa(b.linear() * a.linear().transpose());
  d.tail<3>() = aa.angle() * aa.axis();
  return d;
}

Pose apply_displacement(const Pose& pose, const Displacement& d) {
  Pose out = pose;
  out.translation() += d.head<3>();
  const double angle = d.tail<3>().norm();
  if (angle > 0.0) {
    out.linear() = Eigen::AngleAxisd(angle, d.tail<3>() / angle).toRotationMatrix() * pose.linear();
  }
  return out;
}

}  // namespace deflex
