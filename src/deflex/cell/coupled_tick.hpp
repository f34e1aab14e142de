// The simulated arm a servo tick at a time under a process whose force depends on where the arm truly
// is (the LDBB's seal, a cutting force), each tick solved as one coupled problem: the TCP position p
// with p = A(F(p)), A the true arm's response to a wrench (true_robot.hpp, its drift included) and F
// the process's wrench at a position. Solving the force a tick behind the arm instead (F at the last
// tick's p) rings at half the servo rate once the process is stiffer than the arm is soft: the LDBB's
// seal holds up to a quarter of 650 N over 0.1 mm of piston travel, against about 1 um/N of arm
// compliance, a loop gain of 1.5.
#pragma once

#include <array>
#include <cstdint>

#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/process_force.hpp"
#include "deflex/cell/true_robot.hpp"

namespace deflex::cell {

/// When a tick's solve has converged, and how long it may try.
struct CoupledTickOptions {
  /// Converged when the process's wrench at the arm's solved position differs from the wrench the arm
  /// was solved under by no more than these (every force component, N; every moment, Nm). At the
  /// arm's 1-1.6 um/N, 50 mN is 50-80 nm of TCP position: some 60 times below the tracker's noise
  /// (5 um) and 40 times below what the bar's own noise (0.3 % of 650 N) moves the arm by.
  double force_tolerance_n = 5e-2;
  double moment_tolerance_nm = 1e-3;
  /// The process settles against the arm's linear response to within this (m) before the arm is
  /// solved under its force: 1 nm, a seal's 0.5 mN at its stiffest (0.25 x 650 N over 0.3 mm of
  /// pre-sliding), far below what the tolerances above ask.
  double settle_tolerance_m = 1e-9;
  /// Solves of the arm a tick at most; a tick that reaches it keeps its last iterate and is counted.
  int max_arm_solves = 8;
};

/// What the coupled solves of a run (or a calibration) did, summed over its ticks.
struct CoupledTickCounters {
  std::uint64_t ticks = 0;        ///< ticks solved with a process on the arm
  std::uint64_t arm_solves = 0;   ///< solves of the arm those took
  std::uint64_t unconverged = 0;  ///< ticks that reached the cap without converging
  int most_arm_solves = 0;        ///< the most any one tick took
  /// The largest force mismatch (N, a component) a tick was left with at the cap (0: none was).
  double worst_mismatch_n = 0.0;
  void add(const CoupledTickCounters& other);
};

/// The arm of one run and what pushes on it: the true robot with the run's workspace and state, the
/// run's drift, and the process (nullptr: nothing pushes).
struct CoupledArm {
  const TrueRobot& robot;
  Workspace& ws;
  TrueRobotState& state;
  const PathDrift& drift;
  ProcessForce* process;
};

/// Steps one run's arm tick by tick. Each tick with a process: a first guess (the arm's TCP less its
/// linear response to the force, extrapolated from the last three ticks; the process settled against
/// that response), then Newton's method on p = A(F(p)): solve the arm under the process's wrench; if
/// the process's wrench where the arm then stands differs from it by more than the tolerance, settle
/// the process against the arm's linear response about that answer (a damped Newton on the process
/// alone, cheap: its stiffness by finite differences) and solve the arm again. The arm's linear
/// response is its tangent compliance (TrueRobot::tcp_force_compliance, refreshed as the arm moves)
/// corrected by what the tick's own solves show of it (Broyden's update); once a solve fails to halve
/// the mismatch (a kink of the arm or the process between two solves), twice the tangent, whose steps
/// fall short of the answer and never overshoot it.
/// Thread safety: one thread at a time (its run's).
class CoupledTickSolver {
 public:
  explicit CoupledTickSolver(const CoupledTickOptions& options = {}) : options_(options) {}

  /// The TCP (m, base frame, drifted) with the arm standing unloaded at the command `q` (rad): where
  /// a motion starts.
  [[nodiscard]] Vector3 at_rest(CoupledArm arm, const JointVector& q);
  /// One tick of `dt_s` (> 0) to the command `q` (rad), the process's and the drift's advance() already
  /// called for it. Commits the arm's state and the process at the solution and returns the TCP (m,
  /// base frame, drifted); `wrench` is the wrench the arm was solved under (zero without a process).
  /// A tick that reaches the cap keeps its last iterate and is counted, never silently.
  [[nodiscard]] Vector3 tick(CoupledArm arm, const JointVector& q, double dt_s, Wrench& wrench);

  [[nodiscard]] const CoupledTickCounters& counters() const { return counters_; }

 private:
  // A cached (I - C K)^-1, K the process's stiffness where it was last taken.
  struct StepMatrix {
    Matrix3* matrix;
    bool* valid;
  };
  // Where the process settles against the arm's linear response `c` about (w_base, base): x with
  // x = base + c (F(x) - w_base); `w_at` = F(x). `step` is kept while its steps keep working (the
  // process's stiffness changes slowly but at a kink).
  [[nodiscard]] Vector3 settle_process(const ProcessForce& process, const Vector3& base, const Wrench& w_base,
                                       const Matrix3& c, StepMatrix& step, const Matrix3& orientation, double dt_s,
                                       Wrench& w_at) const;
  // The first guess of a tick: `w` to solve the arm under first.
  Vector3 first_guess(CoupledArm arm, double dt_s, Wrench& w);
  // Solves the arm from the first guess `w` until the process agrees (or the cap); commits the arm's
  // state and the process; returns the arm's TCP without the drift, `w` the wrench solved under.
  Vector3 solve_with_process(CoupledArm arm, const JointVector& q, double dt_s, Wrench& w);
  void refresh_tangent(CoupledArm arm, const JointVector& q_actual);

  CoupledTickOptions options_;
  CoupledTickCounters counters_;
  Vector3 last_m_ = Vector3::Zero();  // the TCP at the last tick (drifted)
  // The last tick's wrench, and the arm's TCP (without the drift) less its linear response to the
  // wrench at the last three ticks, newest first.
  Wrench w_last_ = Wrench::Zero();
  std::array<Vector3, 3> free_m_{Vector3::Zero(), Vector3::Zero(), Vector3::Zero()};
  // The arm's tangent compliance (m/N), refreshed as the arm moves, and its step matrix for the first
  // guesses.
  Matrix3 tangent_ = Matrix3::Zero();
  Matrix3 tangent_step_ = Matrix3::Identity();
  bool have_tangent_step_ = false;
  int ticks_since_refresh_ = -1;  // negative: no tangent yet
  TrueRobotState backup_;         // the arm's state before a tick's solves
};

}  // namespace deflex::cell
