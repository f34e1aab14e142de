// The arm and its process solved together a tick at a time (see coupled_tick.hpp).
#include "deflex/cell/coupled_tick.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace deflex::cell {
namespace {

// The process's tangent is taken by forward differences of this step (m): far below the seal's 0.1 mm
// of pre-sliding, far above rounding.
constexpr double kDifferenceStep = 1e-7;
constexpr int kSettleIterations = 40;
// The tangent compliance is recomputed every this many ticks (0.26 s at 4 ms: the arm turns the
// circle's 81 points in 16-80 s); the solves' corrections carry on across.
constexpr int kRefreshTicks = 64;

// The TCP moving to `p_m` over the tick, as the process sees it.
TcpMotion motion_at(const Vector3& p_m, const Matrix3& orientation, const Vector3& p_prev_m, double dt_s) {
  TcpMotion m;
  m.position_m = p_m;
  m.orientation = orientation;
  m.velocity_m_s = (p_m - p_prev_m) / dt_s;
  return m;
}

}  // namespace

void CoupledTickCounters::add(const CoupledTickCounters& other) {
  ticks += other.ticks;
  arm_solves += other.arm_solves;
  unconverged += other.unconverged;
  most_arm_solves = std::max(most_arm_solves, other.most_arm_solves);
  worst_mismatch_n = std::max(worst_mismatch_n, other.worst_mismatch_n);
}

Vector3 CoupledTickSolver::at_rest(CoupledArm arm, const JointVector& q) {
  const Vector3 arm_m = arm.robot.solve(arm.ws, q, Wrench::Zero(), arm.state);
  last_m_ = arm.drift.apply(arm_m);
  w_last_ = Wrench::Zero();
  free_m_[0] = free_m_[1] = free_m_[2] = arm_m;
  return last_m_;
}

void CoupledTickSolver::refresh_tangent(CoupledArm arm, const JointVector& q_actual) {
  tangent_ = arm.robot.tcp_force_compliance(arm.ws, q_actual, w_last_, arm.state);
  ticks_since_refresh_ = 0;
  have_tangent_step_ = false;
}

Vector3 CoupledTickSolver::settle_process(const ProcessForce& process, const Vector3& base, const Wrench& w_base,
                                          const Matrix3& c, StepMatrix& step, const Matrix3& orientation, double dt_s,
                                          Wrench& w_at) const {
  TcpMotion motion = motion_at(base, orientation, last_m_, dt_s);
  const auto at = [&](const Vector3& x) -> const TcpMotion& {
    motion.position_m = x;
    motion.velocity_m_s = (x - last_m_) / dt_s;
    return motion;
  };
  auto residual = [&](const Vector3& x, Wrench& w) {
    w = process.wrench_at(at(x));
    return Vector3(x - base - c * (w - w_base).head<3>());
  };
  Vector3 x = base;
  Vector3 r = residual(x, w_at);
  for (int it = 0; it < kSettleIterations && r.cwiseAbs().maxCoeff() > options_.settle_tolerance_m; ++it) {
    if (!*step.valid) {
      Matrix3 k;
      for (int i = 0; i < 3; ++i) {
        Vector3 xi = x;
        xi[i] += kDifferenceStep;
        k.col(i) = (process.wrench_at(at(xi)) - w_at).head<3>() / kDifferenceStep;
      }
      *step.matrix = (Matrix3::Identity() - c * k).inverse();
      *step.valid = true;
    }
    const Vector3 d = -*step.matrix * r;
    // The process may be piecewise linear (a seal sticks, then slides): a full Newton step across a
    // kink can overshoot and cycle, so the step is halved until the residual falls, and the stiffness
    // taken afresh where it lands.
    const double r_norm = r.cwiseAbs().maxCoeff();
    double lambda = 1.0;
    for (;;) {
      Wrench w_try;
      const Vector3 r_try = residual(x + lambda * d, w_try);
      const double r_try_norm = r_try.cwiseAbs().maxCoeff();
      if (r_try_norm <= (1.0 - 1e-4 * lambda) * r_norm || lambda < 1.0 / 1024.0) {
        x += lambda * d;
        r = r_try;
        w_at = w_try;
        // A step that had to be halved, or that left much of the residual, met a change of the
        // process's stiffness: take it afresh.
        *step.valid = lambda == 1.0 && r_try_norm < 0.1 * r_norm;
        break;
      }
      lambda *= 0.5;
    }
  }
  return x;
}

Vector3 CoupledTickSolver::first_guess(CoupledArm arm, double dt_s, Wrench& w) {
  if (ticks_since_refresh_ < 0 || ++ticks_since_refresh_ >= kRefreshTicks) refresh_tangent(arm, arm.state.q_actual);
  // The arm's TCP less its linear response to the wrench over the last three ticks, extrapolated (the
  // motion and the deflection the force does not explain move smoothly; the bar's own changes from
  // tick to tick do not carry on), and the process settled against the arm's linear response there.
  const Vector3 free_now = 3.0 * free_m_[0] - 3.0 * free_m_[1] + free_m_[2];
  StepMatrix step{&tangent_step_, &have_tangent_step_};
  return settle_process(*arm.process, arm.drift.apply(free_now + tangent_ * w_last_.head<3>()), w_last_, tangent_, step,
                        arm.ws.base_T_tcp.linear(), dt_s, w);
}

Vector3 CoupledTickSolver::tick(CoupledArm arm, const JointVector& q, double dt_s, Wrench& wrench) {
  Vector3 arm_m;
  Wrench w = Wrench::Zero();
  if (arm.process == nullptr) {
    arm_m = arm.robot.solve(arm.ws, q, w, arm.state, dt_s);
  } else {
    (void)first_guess(arm, dt_s, w);
    arm_m = solve_with_process(arm, q, dt_s, w);
  }
  free_m_[2] = free_m_[1];
  free_m_[1] = free_m_[0];
  free_m_[0] = arm_m - tangent_ * w.head<3>();
  w_last_ = w;
  last_m_ = arm.drift.apply(arm_m);
  wrench = w;
  return last_m_;
}

Vector3 CoupledTickSolver::solve_with_process(CoupledArm arm, const JointVector& q, double dt_s, Wrench& w) {
  const ProcessForce& process = *arm.process;
  Matrix3 c = tangent_;  // this tick's view of the arm's response, corrected by its solves
  Matrix3 c_step = tangent_step_;
  bool c_step_valid = have_tangent_step_;
  backup_ = arm.state;  // each solve starts from the last tick's state: a trial that misses is undone
  Vector3 arm_m, p_arm;
  Vector3 previous_arm_m = Vector3::Zero();
  Wrench previous_w = Wrench::Zero();
  double miss = 0.0, previous_miss = 0.0;
  bool cautious = false;
  int solves = 0;
  for (;;) {
    if (solves > 0) arm.state = backup_;
    arm_m = arm.robot.solve(arm.ws, q, w, arm.state, dt_s);
    p_arm = arm.drift.apply(arm_m);
    ++solves;
    // g: what the process would push with where the arm now stands, less what the arm was solved under.
    const Wrench g = process.wrench_at(motion_at(p_arm, arm.ws.base_T_tcp.linear(), last_m_, dt_s)) - w;
    miss = std::max(g.head<3>().cwiseAbs().maxCoeff() / options_.force_tolerance_n,
                    g.tail<3>().cwiseAbs().maxCoeff() / options_.moment_tolerance_nm);
    if (miss <= 1.0 || solves >= std::max(1, options_.max_arm_solves)) {
      if (miss > 1.0) {
        ++counters_.unconverged;
        counters_.worst_mismatch_n = std::max(counters_.worst_mismatch_n, g.head<3>().cwiseAbs().maxCoeff());
      }
      break;
    }
    const Wrench solved_w = w;
    if (solves > 1 && (cautious || miss > 0.5 * previous_miss)) {
      // Not contracting: a kink of the arm's response (a joint's lost motion taken up) or of the
      // process's lies between the last two solves, where Newton can overshoot. From here on, the arm
      // taken for twice as compliant as its tangent: each step then falls short of the answer, by
      // less than half the way for a process up to several times stiffer than the arm is soft, and
      // never overshoots it.
      if (!cautious) {
        cautious = true;
        c = 2.0 * tangent_;
        c_step_valid = false;
      }
    } else if (solves > 1) {
      // Broyden's update: the arm's response as this tick's two solves show it along their wrenches'
      // difference (what the tangent misses: the gears' hardening, the servo's yield ...).
      const Vector3 dw = (w - previous_w).head<3>();
      if (dw.squaredNorm() > 1e-4) {
        c += (arm_m - previous_arm_m - c * dw) * dw.transpose() / dw.squaredNorm();
        c_step_valid = false;
      }
    }
    StepMatrix step{&c_step, &c_step_valid};
    (void)settle_process(process, p_arm, solved_w, c, step, arm.ws.base_T_tcp.linear(), dt_s, w);
    previous_arm_m = arm_m;
    previous_w = solved_w;
    previous_miss = miss;
  }
  // The arm's state and the workspace's kinematics are the last solve's.
  arm.process->commit(motion_at(p_arm, arm.ws.base_T_tcp.linear(), last_m_, dt_s));
  ++counters_.ticks;
  counters_.arm_solves += static_cast<std::uint64_t>(solves);
  counters_.most_arm_solves = std::max(counters_.most_arm_solves, solves);
  return arm_m;
}

}  // namespace deflex::cell
