// The true robot of the simulated cell (see true_robot.hpp).
#include "deflex/cell/true_robot.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "deflex/robotfile/robot_io.hpp"

namespace deflex::cell {
namespace {

// Moves the workspace's end poses (flange, TCP, WAP) from its configuration by the joint step `dq`
// along the TCP Jacobian `J` taken there: the TCP moves by Jv dq and every end frame turns by
// w = Jw dq (second-order Rodrigues: its error is |w|^3). For steps of 1e-5 rad this is within
// reach x step^2 (~2e-10 m) of a forward kinematics at the new configuration, at a tenth of its cost.
// The joint frames (axis_base, origin_base) stay the old configuration's: what reads them after a
// solve (the links' and the sensor's compliance) moves by a relative 1e-5 of a displacement.
void advance_end_poses(Workspace& ws, const Jacobian& J, const JointVector& dq) {
  const Vector3 dp = J.topRows<3>() * dq;
  const Vector3 w = J.bottomRows<3>() * dq;
  Matrix3 wx;
  wx << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  const Matrix3 turn = Matrix3::Identity() + wx + 0.5 * wx * wx;
  const Vector3 p_tcp = ws.base_T_tcp.translation();
  const auto move = [&](Pose& pose) {
    const Vector3 p = pose.translation();
    pose.translation() = p + dp + w.cross(p - p_tcp);
    pose.linear() = turn * pose.linear();
  };
  move(ws.base_T_flange);
  move(ws.base_T_wap);
  move(ws.base_T_tcp);
  ws.q += dq;
}

}  // namespace

double LostMotion::update(double joint_torque_nm) {
  const double x = joint_torque_nm / torque_nm;
  state = std::clamp(state, x - 1.0, x + 1.0);
  return offset_rad();
}

double LostMotion::offset_rad() const { return half_width_rad * std::clamp(state, -1.0, 1.0); }

double GearHardening::equivalent_torque(double x) const {
  if (softening == 0.0) return x;
  const double a = std::abs(x);
  return x + std::copysign(softening * torque_nm * (1.0 - std::exp(-a / torque_nm)), x);
}

Pose setup_flange_T_tcp(const CellConfig& config, bool sensor_mounted) {
  Pose t = Pose::Identity();
  t.translation() = Vector3(0, 0, config.tool.ee_length_m + (sensor_mounted ? config.sensor.height_m : 0.0));
  return t;
}

TrueRobot::TrueRobot(const CellConfig& config, bool sensor_mounted, std::uint64_t seed)
    : config_(config), sensor_mounted_(sensor_mounted) {
  const RobotModel base = load_robot_or_builtin(config.robot_file);
  const Pose flange_T_tcp = setup_flange_T_tcp(config, sensor_mounted);
  nominal_ = std::make_shared<const RobotModel>(base.with_tool(flange_T_tcp));

  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  RobotDescription desc = base.description();
  const int n = base.dof();
  // Every draw is made whatever its size, so switching one effect off (error budget) leaves the
  // draws of the others unchanged: the same robot with one effect less.
  std::vector<DhRow> rows = desc.dh;
  for (auto& r : rows) {
    r.a_m += config.robot.dh_length_sigma_m * normal(rng);
    r.d_m += config.robot.dh_length_sigma_m * normal(rng);
    r.alpha_rad += config.robot.dh_angle_sigma_rad * normal(rng);
    r.theta_offset_rad += config.robot.dh_angle_sigma_rad * normal(rng);
  }
  if (desc.dh_convention && (config.robot.dh_length_sigma_m > 0 || config.robot.dh_angle_sigma_rad > 0)) {
    std::vector<double> lower, upper, speed;
    for (const auto& j : desc.joints) {
      lower.push_back(j.lower_rad);
      upper.push_back(j.upper_rad);
      speed.push_back(j.max_speed_rad_s);
    }
    set_dh_chain(desc, *desc.dh_convention, rows, lower, upper, speed);
  }
  std::vector<double> k_true(static_cast<std::size_t>(n));
  const auto& band_lo = config.robot.stiffness_band_min_nm_per_rad;
  const auto& band_hi = config.robot.stiffness_band_max_nm_per_rad;
  for (int i = 0; i < n; ++i) {
    const auto iu = static_cast<std::size_t>(i);
    const double mean = base.stiffness()[i] * config.robot.stiffness_scale;
    double k = mean * std::exp(config.robot.stiffness_spread * normal(rng));
    if (iu < band_lo.size() && iu < band_hi.size()) {
      // A joint of this class of arm is inside the band its identifications report: the spread
      // between arms is drawn within it (drawn again, a truncated log-normal; a scale that puts the
      // joint's mean outside the band leaves it at the band's edge).
      for (int tries = 0; (k < band_lo[iu] || k > band_hi[iu]) && tries < 100; ++tries) {
        k = mean * std::exp(config.robot.stiffness_spread * normal(rng));
      }
      k = std::clamp(k, band_lo[iu], band_hi[iu]);
    }
    k_true[iu] = k;
  }
  desc.stiffness_nm_per_rad = k_true;
  desc.stiffness_note = "true stiffness of the simulated cell";
  desc.flange_T_tcp = flange_T_tcp;
  desc.flange_T_wap.reset();
  true_ = std::make_shared<const RobotModel>(desc);
  if (!desc.dh.empty()) {
    last_d_m_ = desc.dh.back().d_m;
  }
  if (desc.dh.size() >= 2) {
    upper_arm_length_m_ = std::hypot(desc.dh[1].a_m, desc.dh[1].d_m);
  }

  JointMatrix K = JointMatrix::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    K(i, i) = k_true[static_cast<std::size_t>(i)];
  }
  if (n >= 3) {
    K(1, 2) = K(2, 1) = config.robot.coupling_23 * std::sqrt(K(1, 1) * K(2, 2));
  }
  joint_compliance_ = K.inverse();
  const auto& hs = config.robot.hardening_softening;
  const auto& ht = config.robot.hardening_torque_nm;
  for (int i = 0; i < n && static_cast<std::size_t>(i) < hs.size(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    hardening_[k].softening = hs[k];
    hardening_[k].torque_nm = k < ht.size() ? ht[k] : 1.0;
    hardening_on_ = hardening_on_ || hs[k] > 0.0;
  }
}

TrueRobotState TrueRobot::initial_state(const JointVector& q_cmd) const {
  TrueRobotState s;
  s.q_actual = q_cmd;
  s.q_cmd_last = q_cmd;
  s.q_motor = q_cmd;
  s.deflection = JointVector::Zero(true_->dof());
  s.deflection_step = JointVector::Zero(true_->dof());
  const auto& lm = config_.robot.lost_motion_rad;
  for (int i = 0; i < true_->dof(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    s.lost_motion[k].half_width_rad = k < lm.size() ? lm[k] : 0.0;
    s.lost_motion[k].torque_nm =
        k < config_.robot.lost_motion_torque_nm.size() ? config_.robot.lost_motion_torque_nm[k] : 1.0;
    s.lost_motion[k].state = 0.0;
  }
  s.gravity_torque_nm = JointVector::Zero(true_->dof());
  s.torque_lowpass_nm = JointVector::Zero(true_->dof());
  for (int i = 0; i < true_->dof(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (k < config_.robot.gravity_torque_nm.size()) s.gravity_torque_nm[i] = config_.robot.gravity_torque_nm[k];
    s.lost_motion[k].update(s.gravity_torque_nm[i]);  // the arm settled under its own weight
  }
  s.gravity_equivalent_nm = JointVector::Zero(true_->dof());
  for (int i = 0; i < true_->dof(); ++i) {
    s.gravity_equivalent_nm[i] = hardening_[static_cast<std::size_t>(i)].equivalent_torque(s.gravity_torque_nm[i]);
  }
  return s;
}

Vector3 TrueRobot::structural_displacement(const Workspace& ws, const Wrench& w) const {
  Vector3 d = Vector3::Zero();
  const Vector3 p_tcp = ws.base_T_tcp.translation();
  const Vector3 F = w.head<3>();
  const Vector3 M = w.tail<3>();
  if (config_.robot.forearm_ei_nm2 > 0.0 && ws.dof >= 6) {
    // Cantilever from the elbow to the wrist centre along the axis of joint 4.
    const Matrix3& R = ws.base_T_flange.linear();
    const Vector3 p_wc = ws.base_T_flange.translation() - last_d_m_ * R.col(2);
    const Vector3 a = ws.axis_base[3];
    const Vector3 M_wc = M + (p_tcp - p_wc).cross(F);
    const Vector3 F_perp = F - a * a.dot(F);
    const Vector3 M_perp = M_wc - a * a.dot(M_wc);
    const double L = config_.robot.forearm_length_m;
    const double ei = config_.robot.forearm_ei_nm2;
    const Vector3 delta = F_perp * (L * L * L / (3 * ei)) + M_perp.cross(a) * (L * L / (2 * ei));
    const Vector3 theta = a.cross(F_perp) * (L * L / (2 * ei)) + M_perp * (L / ei);
    d += delta + theta.cross(p_tcp - p_wc);
  }
  if (config_.robot.upper_arm_ei_nm2 > 0.0 && ws.dof >= 3 && upper_arm_length_m_ > 0.0) {
    // Cantilever from joint 2 to the elbow (joint 3's axis): the elbow moves and turns, and carries
    // everything beyond it.
    const Vector3 p2 = ws.origin_base[1];
    const Vector3 p3 = ws.origin_base[2];
    Vector3 a = p3 - p2;
    a = a - ws.axis_base[1] * ws.axis_base[1].dot(a);  // along the arm, across joint 2's axis
    if (a.norm() > 1e-6) {
      a.normalize();
      const Vector3 M_el = M + (p_tcp - p3).cross(F);
      const Vector3 F_perp = F - a * a.dot(F);
      const Vector3 M_perp = M_el - a * a.dot(M_el);
      const double L = upper_arm_length_m_;
      const double ei = config_.robot.upper_arm_ei_nm2;
      const Vector3 delta = F_perp * (L * L * L / (3 * ei)) + M_perp.cross(a) * (L * L / (2 * ei));
      const Vector3 theta = a.cross(F_perp) * (L * L / (2 * ei)) + M_perp * (L / ei);
      d += delta + theta.cross(p_tcp - p3);
    }
  }
  if (config_.robot.base_tilt_compliance_rad_per_nm > 0.0) {
    // The foundation tilts about the horizontal axes under the moment the process puts on the base
    // (its turn about z is joint 1's compliance).
    const Vector3 M_base = M + p_tcp.cross(F);
    const Vector3 tilt(M_base.x() * config_.robot.base_tilt_compliance_rad_per_nm,
                       M_base.y() * config_.robot.base_tilt_compliance_rad_per_nm, 0.0);
    d += tilt.cross(p_tcp);
  }
  if (sensor_mounted_) {
    const auto& s = config_.sensor;
    const Matrix3& R = ws.base_T_flange.linear();
    const Vector3 p_s = ws.base_T_flange.translation() + R.col(2) * s.height_m;
    const Vector3 F_s = R.transpose() * F;
    const Vector3 M_s = R.transpose() * (M + (p_tcp - p_s).cross(F));
    const Vector3 dt(s.lateral_compliance_m_per_n * F_s.x(), s.lateral_compliance_m_per_n * F_s.y(),
                     s.axial_compliance_m_per_n * F_s.z());
    const Vector3 phi = M_s * s.rotational_compliance_rad_per_nm;
    d += R * dt + (R * phi).cross(p_tcp - p_s);
  }
  return d;
}

JointVector TrueRobot::motor_position(const JointVector& q_cmd, const TrueRobotState& state, double dt_s) const {
  if (!(dt_s > 0.0)) return q_cmd;
  return q_cmd - config_.robot.servo_following_s / dt_s * (q_cmd - state.q_cmd_last);
}

Matrix3 TrueRobot::tcp_force_compliance(Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                                        const TrueRobotState& state) const {
  const int n = true_->dof();
  Jacobian J(6, n);
  jacobian(*true_, ws, q, EndPoint::kTcp, J);
  const JointVector tau = J.transpose() * wrench_base;
  // d(deflection)/d(tau): the gears' compliance at their torque along the hardening curve (its slope
  // 1 + s exp(-|x|/tau_h)), and the servo's yield to a change faster than its integral action.
  JointMatrix c = joint_compliance_;
  for (int i = 0; i < n; ++i) {
    const GearHardening& h = hardening_[static_cast<std::size_t>(i)];
    if (h.softening > 0.0) {
      c.col(i) *= 1.0 + h.softening * std::exp(-std::abs(state.gravity_torque_nm[i] + tau[i]) / h.torque_nm);
    }
    c(i, i) += config_.robot.servo_compliance_fraction * joint_compliance_(i, i);
  }
  const auto Jv = J.topRows<3>();
  Matrix3 out = Jv * c * Jv.transpose();
  for (int i = 0; i < 3; ++i) {
    Wrench unit = Wrench::Zero();
    unit[i] = 1.0;
    out.col(i) += structural_displacement(ws, unit);  // linear in the wrench at a given configuration
  }
  return out;
}

// NOLINTNEXTLINE(readability-function-size): listed in docs/architecture.md, "Functions over 80 lines"
Vector3 TrueRobot::solve(Workspace& ws, const JointVector& q_cmd_in, const Wrench& wrench_base, TrueRobotState& state,
                         double dt_s) const {
  const RobotModel& m = *true_;
  const int n = m.dof();
  const auto& rc = config_.robot;
  Jacobian J(6, n);
  // The joints' speed (from the commands) drives the motion effects; the servo's following error
  // makes the motor lag its command by servo_following_s of that speed.
  JointVector speed = JointVector::Zero(n);
  if (dt_s > 0.0) speed = (q_cmd_in - state.q_cmd_last) / dt_s;
  const JointVector q_cmd = motor_position(q_cmd_in, state, dt_s);
  // Start from the last deflection carried on by its last change: in steady motion the fixed point
  // then moves by far less than the tolerance, and one Jacobian does.
  JointVector q = q_cmd + state.deflection;
  if (dt_s > 0.0) q += state.deflection_step;
  // No process wrench (the unloaded runs): no process torque, so no Jacobian to find it with.
  const bool loaded = !wrench_base.isZero(0.0);
  JointVector tau = JointVector::Zero(n);
  if (loaded) {
    jacobian(m, ws, q, EndPoint::kTcp, J);
    tau = J.transpose() * wrench_base;
  }
  JointVector lost(n);
  JointVector tau_eff(n);
  // The gears deflect along their hardening curves from the gravity preload (linear when off).
  const auto equivalent = [&](const JointVector& t) {
    if (!hardening_on_ || !loaded) {  // unloaded: no process torque, nothing to harden
      tau_eff = t;
      return;
    }
    for (int i = 0; i < n; ++i) {
      // GearHardening::increment() with the preload's half kept from initial_state().
      tau_eff[i] = hardening_[static_cast<std::size_t>(i)].equivalent_torque(state.gravity_torque_nm[i] + t[i]) -
                   state.gravity_equivalent_nm[i];
    }
  };
  for (int i = 0; i < n; ++i) {
    lost[i] = state.lost_motion[static_cast<std::size_t>(i)].update(tau[i] + state.gravity_torque_nm[i]);
  }
  // The process deflection's scale per joint: stiffer when moving, and more yielding with the torque
  // than against it. It scales the torque each gear yields to, so a coupled joint's share of another
  // joint's deflection does not jump when its own torque changes sign.
  // Unloaded, it scales a zero torque: not computed (six tanh a tick).
  JointVector scale = JointVector::Ones(n);
  if (loaded && dt_s > 0.0 && (rc.speed_stiffening != 0.0 || rc.direction_asymmetry != 0.0)) {
    for (int i = 0; i < n; ++i) {
      const double u = std::tanh(speed[i] / rc.speed_ref_rad_s);
      scale[i] = (1.0 - rc.speed_stiffening * std::abs(u)) *
                 (1.0 + rc.direction_asymmetry * u * (tau[i] > 0.0 ? 1.0 : (tau[i] < 0.0 ? -1.0 : 0.0)));
    }
  }
  // The servo yields to the part of the process torque its integral action has not yet taken over.
  JointVector servo = JointVector::Zero(n);
  if (rc.servo_compliance_fraction > 0.0) {
    if (!state.have_torque_lowpass) {
      state.torque_lowpass_nm = tau;  // a static start: the integrator holds the present torque
      state.have_torque_lowpass = true;
    } else if (dt_s > 0.0) {
      if (dt_s != state.torque_lowpass_dt_s) {  // a run's ticks are of one length: one exp() a run
        state.torque_lowpass_dt_s = dt_s;
        state.torque_lowpass_gain = 1.0 - std::exp(-dt_s / rc.servo_integral_s);
      }
      state.torque_lowpass_nm += state.torque_lowpass_gain * (tau - state.torque_lowpass_nm);
    }
    for (int i = 0; i < n; ++i) {
      servo[i] = rc.servo_compliance_fraction * joint_compliance_(i, i) * (tau[i] - state.torque_lowpass_nm[i]);
    }
  }
  // Fixed point q = q_cmd + C tau(q). The map contracts by about |C dtau/dq| ~ C F L (1e-6 rad/Nm x
  // 650 N x 2 m ~ 1e-3), so once a step moves no joint by more than fixed_point_step_rad (1e-10 rad by
  // default) the remaining error is about a thousandth of it. The workspace then holds the kinematics
  // of the last Jacobian's configuration, within that step of q (0.3 nm at 3 m for 1e-10), so it is
  // not recomputed.
  bool ws_current = false;
  for (int it = 0; it < 30; ++it) {
    equivalent(tau);
    const JointVector q_new = q_cmd + joint_compliance_ * scale.cwiseProduct(tau_eff) + lost + servo;
    const double step = (q_new - q).cwiseAbs().maxCoeff();
    q = q_new;
    if (!loaded) break;  // tau does not depend on q
    if (step < rc.fixed_point_step_rad) {
      ws_current = true;  // the Jacobian before this step was taken at a q within the tolerance
      break;
    }
    if (it == 0 && step < rc.first_order_step_rad) {
      advance_end_poses(ws, J, q - ws.q);  // J is the TCP's, at ws.q: the first guess
      ws_current = true;
      break;
    }
    jacobian(m, ws, q, EndPoint::kTcp, J);
    tau = J.transpose() * wrench_base;
  }
  if (!ws_current) forward_kinematics(m, ws, q);
  const JointVector deflection = q - q_cmd;
  state.deflection_step = dt_s > 0.0 ? JointVector(deflection - state.deflection) : JointVector::Zero(n);
  state.deflection = deflection;
  state.q_actual = q;
  state.q_cmd_last = q_cmd_in;
  state.q_motor = q_cmd;
  if (!loaded) return ws.base_T_tcp.translation();  // no process wrench: no structural displacement
  return ws.base_T_tcp.translation() + structural_displacement(ws, wrench_base);
}

}  // namespace deflex::cell
