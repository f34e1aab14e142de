// The tick's coupled solve of the arm and a process whose force depends on where the arm is, against
// a stiff spring on the lumped arm: the explicit scheme (the force from the last tick's position)
// rings and grows; the coupled solve lands where the arm and the spring agree, as an independent
// solve of the arm under its wrench confirms and as the first-order closed form of the lumped model
// (the core's tcp_deflection, not the cell's code) predicts; a tick that reaches the cap is counted.
#include <gtest/gtest.h>

#include <cmath>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/coupled_tick.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/true_robot.hpp"
#include "deflex/model/compliance.hpp"

namespace deflex::cell {
namespace {

// A spring along `n` on the TCP: F = (f0 - k n.(p - anchor)) n. Memoryless, so commit() does nothing.
class Spring final : public ProcessForce {
 public:
  Spring(const Vector3& n, const Vector3& anchor, double f0, double k)
      : n_(n.normalized()), a_(anchor), f0_(f0), k_(k) {}
  void advance(double /*dt_s*/) override {}
  [[nodiscard]] Wrench wrench_at(const TcpMotion& m) const override {
    Wrench w;
    w << (f0_ - k_ * n_.dot(m.position_m - a_)) * n_, Vector3::Zero();
    return w;
  }
  void commit(const TcpMotion& /*motion*/) override {}
  [[nodiscard]] const Vector3& n() const { return n_; }

 private:
  Vector3 n_, a_;
  double f0_, k_;
};

CellConfig lumped_cell() {
  CellConfig c;  // the built-in robot, lumped joints only
  c.robot.gravity_torque_nm = {0, 9000, 3500, 0, 60, 0};
  return c;
}

JointVector pose() {
  JointVector q(6);
  q << 0.1, deg_to_rad(25.0), deg_to_rad(5.0), 0.2, deg_to_rad(55.0), -0.3;
  return q;
}

struct Rig {
  explicit Rig(const CellConfig& c = lumped_cell())
      : robot(c, false, 7), ws(robot.true_model()), state(robot.initial_state(pose())), drift({}, 1) {
    forward_kinematics(robot.true_model(), ws, pose());
    p0 = ws.base_T_tcp.translation();
    // The first-order compliance along n of the lumped model (the core's code, the true stiffness).
    Wrench unit;
    unit << n, Vector3::Zero();
    Workspace w2(robot.true_model());
    c_nn = n.dot(tcp_deflection(robot.true_model(), w2, pose(), unit).head<3>());
  }
  TrueRobot robot;
  Workspace ws;
  TrueRobotState state;
  PathDrift drift;
  Vector3 n = Vector3(0.3, -0.5, 0.8).normalized();
  Vector3 p0;
  double c_nn = 0.0;
};

TEST(CoupledTick, AStiffSpringRingsWhenLaggedAndSettlesWhenSolvedTogether) {
  Rig rig;
  // Three times stiffer than the arm is soft along n: the lagged loop's gain is -3.
  const double k = 3.0 / rig.c_nn;
  const double f0 = 400.0;
  const Spring spring(rig.n, rig.p0, f0, k);
  ASSERT_GT(rig.c_nn, 1e-7);
  ASSERT_LT(rig.c_nn, 1e-5);

  // Lagged: each tick the force from where the arm stood the tick before.
  {
    TrueRobotState s = rig.state;
    Workspace ws(rig.robot.true_model());
    Vector3 p = rig.p0;
    double last_swing = 0.0, previous_force = f0;
    for (int tick = 0; tick < 6; ++tick) {
      TcpMotion m;
      m.position_m = p;
      const Wrench w = spring.wrench_at(m);
      p = rig.robot.solve(ws, pose(), w, s, 0.004);
      const double force = rig.n.dot(w.head<3>());
      last_swing = std::abs(force - previous_force);
      previous_force = force;
    }
    EXPECT_GT(last_swing, 10.0 * f0) << "the lagged spring should ring and grow";
  }

  // Coupled: where the arm under the spring's force is where the spring gives that force.
  CoupledTickSolver solver;
  Spring process(rig.n, rig.p0, f0, k);
  const CoupledArm arm{rig.robot, rig.ws, rig.state, rig.drift, &process};
  (void)solver.at_rest(CoupledArm{rig.robot, rig.ws, rig.state, rig.drift, nullptr}, pose());
  Wrench w;
  Vector3 p = Vector3::Zero();
  for (int tick = 0; tick < 5; ++tick) p = solver.tick(arm, pose(), 0.004, w);
  EXPECT_EQ(solver.counters().unconverged, 0u);
  EXPECT_EQ(solver.counters().ticks, 5u);
  // The arm solved afresh under the wrench the tick settled on stands where the spring gives it.
  TrueRobotState fresh = rig.robot.initial_state(pose());
  Workspace ws(rig.robot.true_model());
  const Vector3 p_check = rig.robot.solve(ws, pose(), w, fresh, 0.0);
  EXPECT_NEAR((p_check - p).norm(), 0.0, 1e-9);
  TcpMotion m;
  m.position_m = p_check;
  EXPECT_LE((process.wrench_at(m) - w).cwiseAbs().maxCoeff(), CoupledTickOptions{}.force_tolerance_n);
  // The first-order closed form along n: s = c f0 / (1 + k c); the deflected configuration's
  // second-order part is below a per cent of it.
  const double s = rig.n.dot(p - rig.p0);
  const double s_closed = rig.c_nn * f0 / (1.0 + k * rig.c_nn);
  EXPECT_NEAR(s / s_closed, 1.0, 0.01) << s << " against " << s_closed;
}

TEST(CoupledTick, ATickThatReachesTheCapIsCountedNotHidden) {
  // The wrist's lost motion (60 urad each way, taken up past 30-60 Nm), which the arm's tangent leaves
  // out: the first solve yields more than the guess expected, and a stiff spring turns that into
  // newtons; one solve a tick cannot settle it.
  CellConfig c = lumped_cell();
  c.robot.lost_motion_rad = {0.0, 0.0, 0.0, 60e-6, 60e-6, 60e-6};
  c.robot.lost_motion_torque_nm = {300, 300, 300, 60, 60, 30};
  Rig rig(c);
  CoupledTickOptions one;
  one.max_arm_solves = 1;
  CoupledTickSolver solver(one);
  Spring process(rig.n, rig.p0, 2000.0, 3.0 / rig.c_nn);  // 500 N where they agree
  (void)solver.at_rest(CoupledArm{rig.robot, rig.ws, rig.state, rig.drift, nullptr}, pose());
  Wrench w;
  (void)solver.tick(CoupledArm{rig.robot, rig.ws, rig.state, rig.drift, &process}, pose(), 0.004, w);
  EXPECT_EQ(solver.counters().ticks, 1u);
  EXPECT_EQ(solver.counters().arm_solves, 1u);
  EXPECT_EQ(solver.counters().unconverged, 1u);
  EXPECT_GT(solver.counters().worst_mismatch_n, one.force_tolerance_n);
  // The same tick with the default cap settles, in more than one solve.
  Rig again(c);
  CoupledTickSolver patient;
  (void)patient.at_rest(CoupledArm{again.robot, again.ws, again.state, again.drift, nullptr}, pose());
  (void)patient.tick(CoupledArm{again.robot, again.ws, again.state, again.drift, &process}, pose(), 0.004, w);
  EXPECT_EQ(patient.counters().unconverged, 0u);
  EXPECT_GT(patient.counters().arm_solves, 1u);
  CoupledTickCounters sum;
  sum.add(solver.counters());
  sum.add(solver.counters());
  EXPECT_EQ(sum.unconverged, 2u);
  EXPECT_EQ(sum.most_arm_solves, 1);
}

TEST(CoupledTick, WithoutAProcessATickIsThePlainSolve) {
  Rig rig;
  CoupledTickSolver solver;
  TrueRobotState plain = rig.state;
  Workspace ws(rig.robot.true_model());
  (void)solver.at_rest(CoupledArm{rig.robot, rig.ws, rig.state, rig.drift, nullptr}, pose());
  (void)rig.robot.solve(ws, pose(), Wrench::Zero(), plain);
  Wrench w;
  const Vector3 p = solver.tick(CoupledArm{rig.robot, rig.ws, rig.state, rig.drift, nullptr}, pose(), 0.004, w);
  EXPECT_TRUE(w.isZero(0.0));
  EXPECT_EQ(p, rig.robot.solve(ws, pose(), Wrench::Zero(), plain, 0.004));
  EXPECT_EQ(solver.counters().ticks, 0u);
}

}  // namespace
}  // namespace deflex::cell
