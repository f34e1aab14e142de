// Compliance calibration on the simulated cell (see cell_calibration.hpp).
#include "deflex/study/cell_calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "deflex/identify/calibration_planner.hpp"

namespace deflex::study {

CellCalibration calibrate_setup(const CaseConfig& c, const cell::TrueRobot& robot, std::uint64_t seed) {
  const RobotModel& nominal = robot.nominal_model();
  if (c.exact_model) {
    const auto& k = robot.true_model().stiffness();
    std::vector<double> kv(k.data(), k.data() + k.size());
    return CellCalibration{nominal.with_stiffness(kv, "exact true stiffness (model-consistent cell)"),
                           {},
                           0,
                           {"exact stiffness given: model-consistent cell"}};
  }
  CalibrationPlanOptions plan_options;
  const double r = c.radius_m();
  plan_options.region_min_m = c.circle.center_m - Vector3(r, r, 0.1);
  plan_options.region_max_m = c.circle.center_m + Vector3(r, r, 0.1);
  plan_options.load_n = c.calibration.load_n;
  plan_options.poses = c.calibration.poses;
  plan_options.orientation = Eigen::Quaterniond(c.circle.tcp_orientation.linear());
  // The planner predicts standard errors from the noise; a noiseless cell still needs a positive one.
  plan_options.noise_m = std::max(1e-9, c.cell.tracker.noise_m / std::sqrt(static_cast<double>(c.calibration.samples)));
  const CalibrationPlan plan = plan_calibration(nominal, plan_options);

  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Workspace ws(robot.true_model());
  const double tracker_sigma = c.cell.tracker.noise_m / std::sqrt(static_cast<double>(c.calibration.samples));
  std::vector<StiffnessMeasurement> data;
  for (const CalibrationPoint& pt : plan.points) {
    // Unloaded, then loaded, from the same lost-motion state: what a tracker sees as the load goes on.
    cell::TrueRobotState state = robot.initial_state(pt.q);
    const Vector3 p0 = robot.solve(ws, pt.q, Wrench::Zero(), state);
    const Vector3 p1 = robot.solve(ws, pt.q, pt.wrench_base, state);
    StiffnessMeasurement m;
    m.q = pt.q;
    // The load cell reading of the calibration rig carries its own error.
    m.wrench_base = pt.wrench_base * (1.0 + c.calibration.load_error * normal(rng));
    m.dp_m = p1 - p0 + tracker_sigma * Vector3(normal(rng), normal(rng), normal(rng)) * std::sqrt(2.0);
    data.push_back(m);
  }
  // Plain least squares: the cell's misfit is systematic (sensor compliance, lost motion), not
  // gross outliers, and a robust re-weighting would throw good measurements away for it.
  IdentificationOptions id_options;
  id_options.robust = false;
  CellCalibration out{nominal, identify_stiffness(nominal, data, id_options), static_cast<int>(data.size()), {}};
  std::vector<double> k(static_cast<std::size_t>(nominal.dof()));
  for (int j = 0; j < nominal.dof(); ++j) {
    const double kj = out.estimate.stiffness_nm_per_rad[static_cast<std::size_t>(j)];
    if (std::isfinite(kj) && kj > 0.0) {
      k[static_cast<std::size_t>(j)] = kj;
    } else {
      k[static_cast<std::size_t>(j)] = nominal.stiffness()[j];
      out.notes.push_back(fmt::format("joint {} not identifiable: kept the assumed stiffness", j + 1));
    }
  }
  for (const auto& w : out.estimate.warnings) {
    out.notes.push_back(w);
  }
  out.identified = nominal.with_stiffness(
      k, fmt::format("identified on the simulated cell ({} measurements, residual {:.1f} um RMS)", data.size(),
                     out.estimate.residual_rms_m * 1e6));
  return out;
}

}  // namespace deflex::study
