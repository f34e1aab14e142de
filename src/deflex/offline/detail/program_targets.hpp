// The targets a robot program moves to, once a program reader has resolved them statically (pose or
// joints, tool, configuration), and their compensation for a force model: the language-independent
// middle of compensating an existing RAPID or KRL program.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "deflex/force/force_model.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/offline/program_compensation.hpp"

namespace deflex {

/// One use of a target by a motion instruction.
struct ProgramTargetUse {
  std::string file;                      ///< for messages
  int line = 0;                          ///< of the motion instruction
  std::string instruction;               ///< MoveL, MoveAbsJ, PTP, CIRC, ...
  std::string target;                    ///< as written: p10, path{3}, Offs(p10,0,0,50), a literal
  bool joint = false;                    ///< a joint target (jointtarget, E6AXIS): `q` given, no IK
  Pose base_T_tcp = Pose::Identity();    ///< Cartesian target: the TCP pose it reaches, robot base frame
  JointVector q;                         ///< joint target: the joint values, rad
  Pose flange_T_tcp = Pose::Identity();  ///< the tool the instruction moves
  /// Cartesian target: the configuration it names (ABB confdata, KUKA Status/Turn); with neither
  /// (`continue_from_previous`), the solution nearest the previous use, on the previous use's branch.
  IkRequest ik;
  bool continue_from_previous = false;
  /// RAPID's ConfJ\Off / ConfL\Off: the solution nearest the previous use's joints, whatever its
  /// configuration (the controller takes the one closest to where the arm is). `ik` is used for the
  /// first use, which has no previous one.
  bool nearest_previous = false;
  /// The rule that chose the configuration, for a refusal: "ConfJ\\Off (line 40)" ("" for its own).
  std::string configuration_rule;
  std::size_t force_index = 0;  ///< the force model's point index of this use
};

/// What compensating a use gives. Joint values rad, poses base frame with the use's tool.
struct ProgramTargetResult {
  JointVector q_desired;
  JointVector q_command;  ///< q_desired - K^-1 J(q_desired)^T W, as compensate_path computes it
  Pose tcp_desired = Pose::Identity();
  Pose tcp_command = Pose::Identity();
  ArmConfiguration configuration;  ///< ABB confdata of q_command
  KukaConfiguration kuka;          ///< KUKA Status and Turn of q_command
  Wrench wrench_base = Wrench::Zero();
  Displacement deflection = Displacement::Zero();  ///< predicted without compensation [m; rad]
  double residual_m = 0.0;                         ///< model-consistent check after compensation
};

/// Compensates every use in order. `start_q` (ProgramOptions::start_q) stands for the previous use of
/// the first one. Throws InputError "FILE:LINE: INSTRUCTION TARGET: REASON" when a target is out of
/// reach, at or near a singularity, has no solution with its configuration, compensates out of the
/// joint limits, or the force model has no data for its index.
[[nodiscard]] std::vector<ProgramTargetResult> compensate_program_targets(
    const RobotModel& model, const std::vector<ProgramTargetUse>& uses, const ForceModel& force,
    const std::optional<JointVector>& start_q = std::nullopt);

/// The report line of one compensated use: where it is and what was done to it (`action`), with
/// the deflection, correction and wrench of its result. Shared by the RAPID and KRL readers.
[[nodiscard]] ProgramTargetReport target_report(const ProgramTargetResult& result, const std::string& file, int line,
                                                const std::string& instruction, const std::string& target,
                                                const std::string& action);

}  // namespace deflex
