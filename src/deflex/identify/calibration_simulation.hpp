// Synthetic calibration measurements: what a laser tracker would record if a plan were run on a
// robot whose true stiffness is known. For examples, tests and the simulated cell.
#pragma once

#include <vector>

#include "deflex/identify/calibration_planner.hpp"
#include "deflex/identify/stiffness_measurements.hpp"

namespace deflex {

/// Runs each plan point on `truth`: the arm commanded to q under the wrench settles at
/// q + K^-1 J_wap(q_actual)^T W (the core's deflected_configuration, the exact fixed point, not
/// the identification's first-order model); the displacement is FK(q_actual) - FK(q) of the TCP
/// plus Gaussian noise of `noise_m` per axis from a generator seeded with `seed`. Throws InputError
/// when `truth` has no stiffness or a deflection does not converge.
[[nodiscard]] std::vector<StiffnessMeasurement> simulate_calibration(const RobotModel& truth,
                                                                     const CalibrationPlan& plan, double noise_m,
                                                                     unsigned seed);

}  // namespace deflex
