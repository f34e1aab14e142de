// The robot description (plain, editable data) and the validated, immutable RobotModel built from
// it. Kinematics and compliance algorithms take a `const RobotModel&` and a `Workspace&`
// (kinematics.hpp): the model never changes once built, so one model serves many threads.
#pragma once

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "deflex/model/folded_chain.hpp"
#include "deflex/model/opw_geometry.hpp"
#include "deflex/model/types.hpp"

namespace deflex {

enum class DhConvention {
  kStandard,  ///< T_i = Rz(q_i + offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i)
  kModified,  ///< T_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(q_i + offset_i) Tz(d_i); row i holds alpha_{i-1}, a_{i-1}
};

/// One row of a Denavit-Hartenberg table (revolute joints only), SI units.
struct DhRow {
  double a_m = 0.0;
  double alpha_rad = 0.0;
  double d_m = 0.0;
  double theta_offset_rad = 0.0;
};

/// One revolute joint of a general serial chain: a fixed transform from the previous joint's moving
/// frame (the base frame for the first joint) to this joint's frame, then a rotation by
/// (q + offset) about `axis` (a unit vector in this joint's frame).
struct JointSpec {
  std::string name;
  Pose parent_T_joint = Pose::Identity();
  Vector3 axis = Vector3::UnitZ();
  double offset_rad = 0.0;
  double lower_rad = -kPi;
  double upper_rad = kPi;
  /// Largest joint speed the controller allows, rad/s; infinity when the file does not say.
  double max_speed_rad_s = HUGE_VAL;
};

/// Everything a robot file says. Plain data: fill it, then build a RobotModel (which validates it).
struct RobotDescription {
  std::string name;
  std::string source = "<memory>";  ///< where it came from (file path), used in error messages

  std::vector<JointSpec> joints;          ///< the chain; for DH robots made by joints_from_dh()
  Pose last_T_flange = Pose::Identity();  ///< last joint's moving frame to the flange

  /// Kept when the chain came from a DH table: the analytic inverse kinematics uses it.
  std::optional<DhConvention> dh_convention;
  std::vector<DhRow> dh;
  /// Kept when the chain came from a URDF: the file (absolute) and the chain's end links.
  std::string urdf_file, urdf_base_link, urdf_tip_link;
  /// How the file was read when that is worth telling the user (which URDF chain was chosen and
  /// which joints were left out); the command-line program prints them as notes.
  std::vector<std::string> notes;

  /// Diagonal joint stiffness K, Nm/rad, one value a joint. Empty when the file gives none.
  std::vector<double> stiffness_nm_per_rad;
  std::string stiffness_note;  ///< where the stiffness comes from (identified, assumed, ...)

  Pose base_T_chain = Pose::Identity();  ///< robot base frame to the chain's first frame (mounting)
  Pose flange_T_tcp = Pose::Identity();  ///< tool frame: flange to tool centre point
  std::optional<Pose> flange_T_wap;      ///< wrench application point; the TCP when absent
};

/// Builds the joints and the flange transform of a DH chain. Lengths in m, angles in rad.
/// `max_speed_rad_s` may be empty (speeds unknown: infinity).
void set_dh_chain(RobotDescription& desc, DhConvention convention, const std::vector<DhRow>& rows,
                  const std::vector<double>& lower_rad, const std::vector<double>& upper_rad,
                  const std::vector<double>& max_speed_rad_s = {});

/// A validated robot description with quantities derived once. Immutable.
/// Thread safety: immutable once built: any number of threads may share one, each with its own
/// Workspace.
class RobotModel {
 public:
  /// Validates the description (sizes, finite numbers, unit axes, limits, positive stiffness).
  /// Throws ModelError naming `desc.source` and the field at fault.
  explicit RobotModel(RobotDescription desc);

  [[nodiscard]] int dof() const { return dof_; }
  [[nodiscard]] const RobotDescription& description() const { return desc_; }
  [[nodiscard]] const std::string& name() const { return desc_.name; }
  [[nodiscard]] const JointSpec& joint(int i) const { return desc_.joints[static_cast<std::size_t>(i)]; }

  [[nodiscard]] bool has_stiffness() const { return !desc_.stiffness_nm_per_rad.empty(); }
  /// Joint stiffness, Nm/rad. Throws ModelError when the robot file gives none.
  [[nodiscard]] const JointVector& stiffness() const;
  /// 1/k per joint, rad/Nm (the stiffness is held to its range at load, so this is finite). Throws
  /// ModelError, as stiffness() does, when the robot file gives none.
  [[nodiscard]] const JointVector& compliance() const {
    if (!has_stiffness()) throw_no_stiffness();
    return compliance_;
  }

  [[nodiscard]] const JointVector& lower_limits() const { return lower_; }
  [[nodiscard]] const JointVector& upper_limits() const { return upper_; }
  /// Largest joint speeds, rad/s (infinity where the robot file gives none).
  [[nodiscard]] const JointVector& max_speed() const { return max_speed_; }
  [[nodiscard]] bool has_max_speed() const { return max_speed_.allFinite(); }
  /// True when every joint of q is inside its limits, within `tolerance_rad`.
  [[nodiscard]] bool within_limits(const JointVector& q, double tolerance_rad = 1e-9) const;

  /// Flange to wrench application point (the TCP unless the file says otherwise).
  [[nodiscard]] const Pose& flange_T_wap() const { return flange_T_wap_; }
  [[nodiscard]] bool wap_is_tcp() const { return !desc_.flange_T_wap.has_value(); }

  /// The chain as forward kinematics walks it, folded once here (folded_chain.hpp).
  [[nodiscard]] const FoldedChain& folded_chain() const { return chain_; }

  /// The ortho-parallel (OPW) geometry the analytic inverse kinematics uses, derived once from the
  /// chain (DH or URDF) and checked against its FK; null for arms outside that family.
  [[nodiscard]] const OpwGeometry* opw() const { return opw_ ? &*opw_ : nullptr; }
  /// Why the chain has no OPW geometry (empty when it has one).
  [[nodiscard]] const std::string& opw_note() const { return opw_note_; }

  /// Returns a copy with a different stiffness (e.g. after identification). Validated again: a value
  /// outside the robot file's range (input_ranges.hpp, kJointStiffness) is a ModelError.
  [[nodiscard]] RobotModel with_stiffness(const std::vector<double>& stiffness_nm_per_rad,
                                          const std::string& note) const;
  /// Returns a copy with a different tool (flange to TCP) and, optionally, WAP.
  [[nodiscard]] RobotModel with_tool(const Pose& flange_T_tcp, std::optional<Pose> flange_T_wap = std::nullopt) const;

 private:
  [[noreturn]] void throw_no_stiffness() const;

  RobotDescription desc_;
  int dof_ = 0;
  JointVector stiffness_;
  JointVector compliance_;
  JointVector lower_;
  JointVector upper_;
  JointVector max_speed_;
  Pose flange_T_wap_ = Pose::Identity();
  FoldedChain chain_;
  std::optional<OpwGeometry> opw_;
  std::string opw_note_;
};

using RobotModelPtr = std::shared_ptr<const RobotModel>;

}  // namespace deflex
