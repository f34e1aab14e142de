// Validation of robot descriptions and the DH-to-chain conversion.
#include "deflex/model/robot_model.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/input_ranges.hpp"

namespace deflex {
namespace {

Pose rot_x(double a) { return Pose(Eigen::AngleAxisd(a, Vector3::UnitX())); }
Pose trans(double x, double y, double z) { return Pose(Eigen::Translation3d(x, y, z)); }

bool finite_pose(const Pose& p) { return p.matrix().allFinite(); }

bool is_rotation(const Matrix3& r) {
  return (r.transpose() * r - Matrix3::Identity()).norm() < 1e-6 && std::abs(r.determinant() - 1.0) < 1e-6;
}

[[noreturn]] void fail(const RobotDescription& d, const std::string& field, const std::string& what) {
  throw ModelError(fmt::format("{}: field '{}': {}", d.source, field, what));
}

}  // namespace

void set_dh_chain(RobotDescription& desc, DhConvention convention, const std::vector<DhRow>& rows,
                  const std::vector<double>& lower_rad, const std::vector<double>& upper_rad,
                  const std::vector<double>& max_speed_rad_s) {
  desc.dh_convention = convention;
  desc.dh = rows;
  desc.joints.clear();
  const std::size_t n = rows.size();
  // Each joint's rotation is about z of its own frame; what lies between two rotations is fixed.
  Pose pending = Pose::Identity();  // fixed transform accumulated since the previous rotation
  for (std::size_t i = 0; i < n; ++i) {
    const DhRow& r = rows[i];
    JointSpec j;
    j.name = fmt::format("joint_{}", i + 1);
    j.axis = Vector3::UnitZ();
    j.offset_rad = r.theta_offset_rad;
    j.lower_rad = i < lower_rad.size() ? lower_rad[i] : -kPi;
    j.upper_rad = i < upper_rad.size() ? upper_rad[i] : kPi;
    j.max_speed_rad_s = i < max_speed_rad_s.size() ? max_speed_rad_s[i] : HUGE_VAL;
    if (convention == DhConvention::kStandard) {
      j.parent_T_joint = pending;
      pending = trans(0, 0, r.d_m) * trans(r.a_m, 0, 0) * rot_x(r.alpha_rad);
    } else {
      j.parent_T_joint = pending * rot_x(r.alpha_rad) * trans(r.a_m, 0, 0);
      pending = trans(0, 0, r.d_m);
    }
    desc.joints.push_back(j);
  }
  desc.last_T_flange = pending;
}

RobotModel::RobotModel(RobotDescription desc) : desc_(std::move(desc)) {
  const auto& d = desc_;
  const std::size_t n = d.joints.size();
  if (n == 0) {
    fail(d, "joints", "the chain has no joints");
  }
  if (n > static_cast<std::size_t>(kMaxJoints)) {
    fail(d, "joints", fmt::format("{} joints, at most {} are supported", n, kMaxJoints));
  }
  dof_ = static_cast<int>(n);
  lower_.resize(dof_);
  upper_.resize(dof_);
  max_speed_.resize(dof_);
  for (std::size_t i = 0; i < n; ++i) {
    const JointSpec& j = d.joints[i];
    const std::string where = fmt::format("joints[{}]", i + 1);
    if (!finite_pose(j.parent_T_joint) || !is_rotation(j.parent_T_joint.linear())) {
      fail(d, where, "joint frame is not a finite rigid transform");
    }
    if (!j.axis.allFinite() || std::abs(j.axis.norm() - 1.0) > 1e-6) {
      fail(d, where + ".axis", "joint axis must be a finite unit vector");
    }
    if (!std::isfinite(j.offset_rad)) {
      fail(d, where + ".offset", "not a finite number");
    }
    if (std::isnan(j.lower_rad) || std::isnan(j.upper_rad) || !(j.lower_rad < j.upper_rad)) {
      fail(d, where + ".limits",
           fmt::format("lower limit ({} rad) must be below upper limit ({} rad)", j.lower_rad, j.upper_rad));
    }
    if (std::isnan(j.max_speed_rad_s) || !(j.max_speed_rad_s > 0.0)) {
      fail(d, where + ".max_speed",
           fmt::format("joint speed limit must be positive (got {} rad/s)", j.max_speed_rad_s));
    }
    max_speed_[static_cast<int>(i)] = j.max_speed_rad_s;
    lower_[static_cast<int>(i)] = j.lower_rad;
    upper_[static_cast<int>(i)] = j.upper_rad;
  }
  if (!finite_pose(d.last_T_flange) || !finite_pose(d.base_T_chain) || !finite_pose(d.flange_T_tcp)) {
    fail(d, "base_frame/tool_frame", "not a finite rigid transform");
  }
  if (!is_rotation(d.base_T_chain.linear())) {
    fail(d, "base_frame", "orientation is not a rotation");
  }
  if (!is_rotation(d.flange_T_tcp.linear())) {
    fail(d, "tool_frame", "orientation is not a rotation");
  }
  if (d.flange_T_wap) {
    if (!finite_pose(*d.flange_T_wap) || !is_rotation(d.flange_T_wap->linear())) {
      fail(d, "wap_frame", "not a finite rigid transform");
    }
    flange_T_wap_ = *d.flange_T_wap;
  } else {
    flange_T_wap_ = d.flange_T_tcp;
  }
  if (!d.stiffness_nm_per_rad.empty()) {
    if (d.stiffness_nm_per_rad.size() != n) {
      fail(d, "joint_stiffness_Nm_per_rad",
           fmt::format("{} values for a chain of {} joints", d.stiffness_nm_per_rad.size(), n));
    }
    stiffness_.resize(dof_);
    compliance_.resize(dof_);
    for (std::size_t i = 0; i < n; ++i) {
      const double k = d.stiffness_nm_per_rad[i];
      // The robot file's range, whichever way the stiffness came (a file, with_stiffness, an
      // identification): 1e-300 Nm/rad would deflect by 1e302 rad.
      if (const auto why = range_violation(k, range::kJointStiffness)) {
        fail(d, fmt::format("joint_stiffness_Nm_per_rad[{}]", i + 1), *why);
      }
      stiffness_[static_cast<int>(i)] = k;
      compliance_[static_cast<int>(i)] = 1.0 / k;
    }
  }
  chain_ = fold_chain(d, flange_T_wap_);
  // Last: the derivation runs FK on this (otherwise complete) model to check itself.
  opw_ = derive_opw_geometry(*this, opw_note_);
}

void RobotModel::throw_no_stiffness() const {
  throw ModelError(
      fmt::format("{}: field 'joint_stiffness_Nm_per_rad': the robot '{}' has no joint stiffness; "
                  "add it to the robot file or identify it (deflex identify)",
                  desc_.source, desc_.name));
}

const JointVector& RobotModel::stiffness() const {
  if (!has_stiffness()) throw_no_stiffness();
  return stiffness_;
}

bool RobotModel::within_limits(const JointVector& q, double tolerance_rad) const {
  if (q.size() != dof_) {
    return false;
  }
  for (int i = 0; i < dof_; ++i) {
    if (!(q[i] >= lower_[i] - tolerance_rad && q[i] <= upper_[i] + tolerance_rad)) {
      return false;
    }
  }
  return true;
}

RobotModel RobotModel::with_stiffness(const std::vector<double>& stiffness_nm_per_rad, const std::string& note) const {
  RobotDescription d = desc_;
  d.stiffness_nm_per_rad = stiffness_nm_per_rad;
  d.stiffness_note = note;
  return RobotModel(std::move(d));
}

RobotModel RobotModel::with_tool(const Pose& flange_T_tcp, std::optional<Pose> flange_T_wap) const {
  RobotDescription d = desc_;
  d.flange_T_tcp = flange_T_tcp;
  d.flange_T_wap = std::move(flange_T_wap);
  return RobotModel(std::move(d));
}

}  // namespace deflex
