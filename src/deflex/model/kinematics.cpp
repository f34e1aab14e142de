// Forward kinematics and geometric Jacobian: one pass over the chain, rotation-about-z fast path.
#include "deflex/model/kinematics.hpp"

#include <cmath>

#include <fmt/format.h>

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

void forward_kinematics(const RobotModel& model, Workspace& ws, const JointVector& q) {
  if (q.size() != model.dof() || ws.dof != model.dof()) [[unlikely]] {
    wrong_size(model, ws, q);
  }
  const RobotDescription& d = model.description();
  const int n = model.dof();
  ws.q = q;
  // Running pose as rotation R and translation p (cheaper than general 4x4 products).
  Matrix3 R = d.base_T_chain.linear();
  Vector3 p = d.base_T_chain.translation();
  const bool z_only = model.z_axes_only();
  for (int i = 0; i < n; ++i) {
    const JointSpec& j = d.joints[static_cast<std::size_t>(i)];
    p += R * j.parent_T_joint.translation();
    R = R * j.parent_T_joint.linear();
    const double angle = q[i] + j.offset_rad;
    const double c = std::cos(angle);
    const double s = std::sin(angle);
    if (z_only) {
      ws.axis_base[static_cast<std::size_t>(i)] = R.col(2);
      // R * Rz(angle): only the first two columns change.
      const Vector3 c0 = R.col(0);
      const Vector3 c1 = R.col(1);
      R.col(0) = c * c0 + s * c1;
      R.col(1) = -s * c0 + c * c1;
    } else {
      ws.axis_base[static_cast<std::size_t>(i)] = R * j.axis;
      R = R * Eigen::AngleAxisd(angle, j.axis).toRotationMatrix();
    }
    ws.origin_base[static_cast<std::size_t>(i)] = p;
  }
  ws.base_T_flange.linear() = R * d.last_T_flange.linear();
  ws.base_T_flange.translation() = p + R * d.last_T_flange.translation();
  ws.base_T_tcp = ws.base_T_flange * d.flange_T_tcp;
  ws.base_T_wap = ws.base_T_flange * model.flange_T_wap();
}

void point_jacobian(const Workspace& ws, const Vector3& point_base, Jacobian& J) {
  J.resize(6, ws.dof);
  for (int i = 0; i < ws.dof; ++i) {
    const Vector3& z = ws.axis_base[static_cast<std::size_t>(i)];
    J.col(i).head<3>() = z.cross(point_base - ws.origin_base[static_cast<std::size_t>(i)]);
    J.col(i).tail<3>() = z;
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
