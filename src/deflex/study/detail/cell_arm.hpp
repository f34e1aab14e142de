// The simulated cell's arm as every simulated motion moves it, a servo tick at a time: the protocol's
// runs (simulated_run.cpp) and the calibration's passes (cell_calibration.cpp) step the bar, the drift
// and the true arm in one way, so the two see the same cell.
#pragma once

#include "deflex/cell/coupled_tick.hpp"
#include "deflex/cell/ldbb_device.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/true_robot.hpp"

namespace deflex::study {

/// The parts of the cell that put the TCP where the tracker sees it: the true arm (with the run's
/// workspace and state), the LDBB pushing on the TCP's ball and the path drift, all of one run; and
/// the solver that settles the arm and the bar together each tick.
/// Thread safety: one thread at a time (the run's), as the parts it refers to.
struct CellArm {
  const cell::TrueRobot& robot;
  Workspace& ws;
  cell::TrueRobotState& state;
  cell::LdbbDevice& bar;
  cell::PathDrift& drift;
  cell::CoupledTickSolver solver;

  /// The TCP (m, base frame, drifted) with the arm standing unloaded at the command `q` (rad): where
  /// a motion starts.
  [[nodiscard]] Vector3 at_rest(const JointVector& q) { return solver.at_rest(parts(false), q); }

  /// One servo tick of `dt_s` to the command `q` (rad). The drift moves on; when `loaded`, the bar's
  /// force moves on and the arm and the bar are solved together (coupled_tick.hpp), `w` the bar's
  /// wrench (zero unloaded). Returns the TCP (m, base frame), drifted: the drift moves the whole arm
  /// (thermal growth, repeatability), so the bar sees it too.
  [[nodiscard]] Vector3 tick(const JointVector& q, bool loaded, double dt_s, Wrench& w) {
    drift.advance(dt_s);
    if (loaded) bar.advance(dt_s);
    return solver.tick(parts(loaded), q, dt_s, w);
  }

  [[nodiscard]] const cell::CoupledTickCounters& counters() const { return solver.counters(); }

 private:
  cell::CoupledArm parts(bool loaded) { return cell::CoupledArm{robot, ws, state, drift, loaded ? &bar : nullptr}; }
};

}  // namespace deflex::study
