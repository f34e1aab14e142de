// The simulated cell's arm as every simulated motion moves it, a servo tick at a time: the protocol's
// runs (simulated_run.cpp) and the calibration's passes (cell_calibration.cpp) step the bar, the drift
// and the true arm in one way, so the two see the same cell.
#pragma once

#include "deflex/cell/ldbb_device.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/true_robot.hpp"

namespace deflex::study {

/// The parts of the cell that put the TCP where the tracker sees it: the true arm (with the run's
/// workspace and state), the LDBB pushing on the TCP's ball and the path drift, all of one run.
/// Thread safety: one thread at a time (the run's), as the parts it refers to.
struct CellArm {
  const cell::TrueRobot& robot;
  Workspace& ws;
  cell::TrueRobotState& state;
  cell::LdbbDevice& bar;
  cell::PathDrift& drift;

  /// The TCP (m, base frame, drifted) with the arm standing unloaded at the command `q` (rad): where
  /// a motion starts.
  [[nodiscard]] Vector3 at_rest(const JointVector& q) { return drift.apply(robot.solve(ws, q, Wrench::Zero(), state)); }

  /// One servo tick of `dt_s` to the command `q` (rad). When `loaded`, the bar's force moves on and
  /// the bar pushes at the TCP's last position `p_prev` and velocity `v_prev` (m, m/s); `w` is its
  /// wrench (zero unloaded). The drift moves on and the arm settles under the wrench. Returns the TCP
  /// (m, base frame), drifted: the drift moves the whole arm (thermal growth, repeatability), so the
  /// bar sees it too.
  [[nodiscard]] Vector3 tick(const JointVector& q, bool loaded, const Vector3& p_prev, const Vector3& v_prev,
                             double dt_s, Wrench& w) {
    w = Wrench::Zero();
    if (loaded) {
      bar.advance(dt_s);
      w = bar.wrench(p_prev, v_prev);
    }
    drift.advance(dt_s);
    return drift.apply(robot.solve(ws, q, w, state, dt_s));
  }
};

}  // namespace deflex::study
