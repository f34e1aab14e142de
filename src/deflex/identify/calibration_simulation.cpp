// Synthetic tracker measurements of a calibration plan run on a robot of known stiffness.
#include "deflex/identify/calibration_simulation.hpp"

#include <random>

#include <fmt/format.h>

#include "deflex/model/compliance.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

std::vector<StiffnessMeasurement> simulate_calibration(const RobotModel& truth, const CalibrationPlan& plan,
                                                       double noise_m, unsigned seed) {
  if (!truth.has_stiffness()) {
    throw InputError(fmt::format("simulate_calibration: robot '{}' has no joint stiffness to simulate", truth.name()));
  }
  if (!(noise_m >= 0.0)) {
    throw InputError("simulate_calibration: the noise must be >= 0 m");
  }
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  Workspace ws(truth);
  std::vector<StiffnessMeasurement> out;
  out.reserve(plan.points.size());
  for (std::size_t i = 0; i < plan.points.size(); ++i) {
    const CalibrationPoint& p = plan.points[i];
    if (p.q.size() != truth.dof()) {
      throw InputError(fmt::format("simulate_calibration: plan point {} has {} joints, the robot {}", i + 1, p.q.size(),
                                   truth.dof()));
    }
    StiffnessMeasurement m;
    m.q = p.q;
    m.wrench_base = p.wrench_base;
    const Vector3 unloaded = tcp_pose(truth, ws, p.q).translation();
    JointVector q_actual;
    if (deflected_configuration(truth, ws, p.q, p.wrench_base, q_actual) != DeflectionStatus::kConverged) {
      throw InputError(fmt::format("simulate_calibration: plan point {}: the deflection does not converge", i + 1));
    }
    const Vector3 loaded = tcp_pose(truth, ws, q_actual).translation();
    m.dp_m = loaded - unloaded;
    for (int k = 0; k < 3; ++k) {
      m.dp_m[k] += noise_m * noise(rng);
    }
    out.push_back(m);
  }
  return out;
}

}  // namespace deflex
