// Time alignment on the study's own data: an unloaded run of the simulated cell, its tracker stamps
// moved onto a clock of their own, aligned with the commanded TCP path the program gives (the
// identified model's forward kinematics of the joint program, on the program's clock). The known
// offset (the clock shift plus the drives' documented following lag) comes back within one tracker
// sample.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/evaluate/time_alignment.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/study/detail/simulated_run.hpp"

namespace deflex::study {
namespace {

TEST(TrackerTimeAlignment, StudyRunOnItsOwnClockComesBackWithinOneSample) {
  CaseConfig c = paper_case();
  c.cell.ldbb.settle_s = 1.0;
  // This test sets the tracker's clock itself (an offset below): the cell's own trigger jitter and
  // rate error would add an offset it cannot know.
  c.cell.tracker.trigger_jitter_s = 0.0;
  c.cell.tracker.clock_rate_error = 0.0;
  const SetupCell cell = build_setup_cell(c, false);
  RunSpec spec;
  spec.kind = RunKind::kUnloaded;
  spec.speed_m_s = 0.05;
  spec.laps_cw = 1;
  spec.laps_ccw = 1;
  spec.seed = 5;
  const RunOutput run = simulate_run(c, cell, spec);
  ASSERT_GT(run.trace.size(), 1000u);
  const double sample_s = (run.trace.back().t_s - run.trace.front().t_s) / static_cast<double>(run.trace.size() - 1);

  // The command as deflex's log or a program file would give it: program time from the program's start.
  const RobotModel& model = cell.calibration.identified;
  const JointTrajectory program = protocol_program(cell.circle_poses, cell.nominal_path.q, spec.speed_m_s,
                                                   c.cell.ldbb.settle_s, spec.laps_cw, spec.laps_ccw, model);
  Workspace ws(model);
  JointVector q(model.dof());
  TrackerTrace commanded;
  for (double t = program.start_time_s(); t <= program.end_time_s(); t += 0.004) {
    program.sample(t, q);
    commanded.push_back({t, tcp_pose(model, ws, q).translation()});
  }
  // The tracker's clock: the run's trace starts at the laps (program time settle_s), stamped 7321.4567 s.
  const double tracker_start = 7321.4567;
  TrackerTrace tracker = run.trace;
  for (auto& s : tracker) s.t_s += tracker_start;
  const double clock_offset = c.cell.ldbb.settle_s + program.start_time_s() - tracker_start;
  // The cell's drives follow their command servo_following_s late (8 ms in the paper's case, a
  // documented size of the simulated robot): the tracker sees the arm where the program was that long
  // ago, and a constant lag cannot be told from a clock offset, so the alignment finds both together.
  const double true_offset = clock_offset - c.cell.robot.servo_following_s;
  ASSERT_GT(c.cell.robot.servo_following_s, 0.0);

  const TimeAlignment a = align_time(tracker, commanded);
  EXPECT_NEAR(a.offset_s, true_offset, sample_s)
      << "found " << a.offset_s << " s, set " << true_offset << " s, +- " << a.offset_std_s << " s";
  // The stated uncertainty (from the spread over the run's blocks: drift and wander are correlated
  // along the path) is a few samples, and covers the error found.
  EXPECT_LT(a.offset_std_s, 5 * sample_s);
  EXPECT_LT(std::abs(a.offset_s - true_offset), 3 * a.offset_std_s + 0.5 * sample_s);
}

}  // namespace
}  // namespace deflex::study
