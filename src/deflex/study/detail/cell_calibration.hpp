// The compliance calibration of one setup, an experiment on the simulated cell in the operating
// space of the task (the paper's local calibration): a plan of poses and loads around the circle
// (identify's planner), the cell's static response to each load measured by its tracker, and
// deflex's identification. The compensators only ever get its result.
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
  std::vector<std::string> notes;     ///< joints kept at the assumed value, warnings
  cell::CoupledTickCounters coupled;  ///< what the loaded passes' coupled solves of the arm and the bar did
};

/// Plans, measures and identifies. With config.exact_model the true diagonal stiffness is given
/// instead (the model-consistent test cell). Throws InputError when no plan can be made.
[[nodiscard]] CellCalibration calibrate_setup(const CaseConfig& config, const cell::TrueRobot& robot,
                                              std::uint64_t seed);

}  // namespace deflex::study
