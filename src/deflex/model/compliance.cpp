// Lumped joint-compliance model: joint and Cartesian deflection, compliance, compensation.
#include "deflex/model/compliance.hpp"

#include <Eigen/LU>

namespace deflex {

void joint_deflection(const RobotModel& model, Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                      JointVector& dtheta, const ComplianceOptions& options) {
  if (!model.has_stiffness()) [[unlikely]] {
    (void)model.stiffness();  // throws ModelError naming the robot file that gives none
  }
  const JointVector& c = model.compliance();
  jacobian(model, ws, q, EndPoint::kWap, ws.jacobian);
  const JointVector tau = ws.jacobian.transpose() * wrench_base;  // joint torques, Nm
  if (!options.complementary_stiffness) {
    dtheta = c.cwiseProduct(tau);
    return;
  }
  JointMatrix Kc;
  complementary_stiffness(model, ws, q, wrench_base, Kc);
  JointMatrix K_eff = -Kc;
  K_eff.diagonal() += model.stiffness();
  dtheta = K_eff.partialPivLu().solve(tau);
}

Displacement tcp_deflection(const RobotModel& model, Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                            const ComplianceOptions& options) {
  JointVector dtheta;
  return tcp_deflection(model, ws, q, wrench_base, dtheta, options);
}

Displacement tcp_deflection(const RobotModel& model, Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                            JointVector& dtheta, const ComplianceOptions& options) {
  joint_deflection(model, ws, q, wrench_base, dtheta, options);
  // joint_deflection left the FK of q in ws; the TCP Jacobian reuses it.
  point_jacobian(ws, ws.base_T_tcp.translation(), ws.jacobian);
  return ws.jacobian * dtheta;
}

Matrix6 cartesian_compliance(const RobotModel& model, Workspace& ws, const JointVector& q) {
  if (!model.has_stiffness()) [[unlikely]] {
    (void)model.stiffness();  // throws ModelError naming the robot file that gives none
  }
  jacobian(model, ws, q, EndPoint::kWap, ws.jacobian);
  const JointVector& c = model.compliance();
  return ws.jacobian * c.asDiagonal() * ws.jacobian.transpose();
}

void complementary_stiffness(const RobotModel& model, Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                             JointMatrix& Kc) {
  forward_kinematics(model, ws, q);
  const int n = model.dof();
  const Vector3 p = ws.base_T_wap.translation();
  const Vector3 f = wrench_base.head<3>();
  const Vector3 m = wrench_base.tail<3>();
  Kc.setZero(n, n);
  // tau_i = (z_i x (p - o_i)) . f + z_i . m. For a rotation about joint k (axis z_k through o_k),
  // every vector of the moving part turns: d/dq_k z_i = z_k x z_i for k < i (0 otherwise);
  // d/dq_k (p - o_i) = z_k x (p - o_i) for k < i, and z_k x (p - o_k) for k >= i.
  for (int i = 0; i < n; ++i) {
    const Vector3& zi = ws.axis_base[static_cast<std::size_t>(i)];
    const Vector3 ri = p - ws.origin_base[static_cast<std::size_t>(i)];
    for (int k = 0; k < n; ++k) {
      const Vector3& zk = ws.axis_base[static_cast<std::size_t>(k)];
      Vector3 dz = Vector3::Zero();
      Vector3 dr;
      if (k < i) {
        dz = zk.cross(zi);
        dr = zk.cross(ri);
      } else {
        dr = zk.cross(p - ws.origin_base[static_cast<std::size_t>(k)]);
      }
      Kc(i, k) = (dz.cross(ri) + zi.cross(dr)).dot(f) + dz.dot(m);
    }
  }
}

void compensated_configuration(const RobotModel& model, Workspace& ws, const JointVector& q_desired,
                               const Wrench& wrench_base, JointVector& q_cmd) {
  JointVector dtheta;
  compensated_configuration(model, ws, q_desired, wrench_base, q_cmd, dtheta);
}

void compensated_configuration(const RobotModel& model, Workspace& ws, const JointVector& q_desired,
                               const Wrench& wrench_base, JointVector& q_cmd, JointVector& dtheta) {
  joint_deflection(model, ws, q_desired, wrench_base, dtheta);
  q_cmd = q_desired - dtheta;
}

DeflectionStatus deflected_configuration(const RobotModel& model, Workspace& ws, const JointVector& q_cmd,
                                         const Wrench& wrench_base, JointVector& q_actual, double tol_rad,
                                         int max_iterations) {
  return deflected_configuration_from(model, ws, q_cmd, wrench_base, q_cmd, q_actual, tol_rad, max_iterations);
}

DeflectionStatus deflected_configuration_from(const RobotModel& model, Workspace& ws, const JointVector& q_cmd,
                                              const Wrench& wrench_base, const JointVector& q_start,
                                              JointVector& q_actual, double tol_rad, int max_iterations) {
  q_actual = q_start;
  JointVector dtheta;
  for (int it = 0; it < max_iterations; ++it) {
    joint_deflection(model, ws, q_actual, wrench_base, dtheta);
    const JointVector next = q_cmd + dtheta;
    const double step = (next - q_actual).cwiseAbs().maxCoeff();
    q_actual = next;
    if (step < tol_rad) {
      return DeflectionStatus::kConverged;
    }
  }
  return DeflectionStatus::kNotConverged;
}

}  // namespace deflex
