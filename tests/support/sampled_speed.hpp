// A program's joint speeds as the tests measure them: by sampling, not by the library's own figure.
#pragma once

#include "deflex/paths/joint_trajectory.hpp"

namespace deflex::test {

/// The program's largest speed on each joint, by sampling it every 0.5 ms (rad/s): the test's own
/// figure for the step limit, not the library's analytic one.
inline JointVector sampled_peak_speed(const JointTrajectory& p) {
  JointVector peak = JointVector::Zero(p.dof()), a(p.dof()), b(p.dof());
  const double h = 0.0005;
  p.sample(p.start_time_s(), a);
  for (double t = p.start_time_s() + h; t <= p.end_time_s() + h; t += h) {
    p.sample(t, b);
    peak = peak.cwiseMax((b - a).cwiseAbs() / h);
    a = b;
  }
  return peak;
}

}  // namespace deflex::test
