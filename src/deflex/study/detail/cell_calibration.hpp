// The compliance calibration of one setup, an experiment on the simulated cell in the operating
// space of the task (the paper's local calibration): loaded arcs around the circle measured by the
// tracker while moving, deflex's identification, and for a joint it calls unusable a second look at
// poses identify's planner adds. The compensators only ever get its result.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "deflex/cell/coupled_tick.hpp"
#include "deflex/cell/true_robot.hpp"
#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/study/case_config.hpp"

namespace deflex::study {

struct CellCalibration {
  RobotModel identified;  ///< nominal kinematics and tool, identified joint stiffness
  StiffnessEstimate estimate;
  int measurements = 0;
  /// Mean magnitude of the forces the identification was given (N): what the bar reported or the
  /// sensor read, never the force the cell applied.
  double mean_force_n = 0.0;
  std::vector<std::string> notes;     ///< joints measured again or kept at the assumed value, warnings
  cell::CoupledTickCounters coupled;  ///< what the loaded passes' coupled solves of the arm and the bar did
  /// Joints (1-based) the arcs left unusable that were measured again at the planner's poses.
  std::vector<int> remeasured_joints;
  /// Joints (1-based) the compensators get at the assumed stiffness: the final estimate could not
  /// give them a usable value (not identified, or flagged: a relative standard error over the limit,
  /// at the c >= 0 bound, collinear).
  std::vector<int> kept_joints;
};

/// Measures along the arcs and identifies; a joint the identification calls unusable is measured
/// again at poses identify's planner adds (those its poses can turn), and whatever is still unusable
/// keeps the assumed stiffness, with a note: the compensators never get a value the identification
/// says not to use. With config.exact_model the true diagonal stiffness is given instead (the
/// model-consistent test cell). Throws InputError when no plan can be made.
[[nodiscard]] CellCalibration calibrate_setup(const CaseConfig& config, const cell::TrueRobot& robot,
                                              std::uint64_t seed);

}  // namespace deflex::study
