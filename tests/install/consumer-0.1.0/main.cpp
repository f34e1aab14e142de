// deflex from a program of one's own (examples/consumer/CMakeLists.txt builds it against the installed
// package or the source tree): a robot from a URDF, FK, Jacobian, IK and deflection; a line
// compensated offline; the online cycle stepped in a loop of one's own; and a runtime session against
// the in-memory stand-in of an ABB EGM controller. Exits 0 when every check holds.
//   deflex_consumer ROBOT.urdf|ROBOT.yaml
#include <cmath>
#include <cstdio>
#include <memory>

#include "deflex/deflex.hpp"  // every public header; a program may include only the ones it uses

namespace {

int failures = 0;

void check(bool ok, const char* what) {
  std::printf("%s %s\n", ok ? "ok  " : "FAIL", what);
  if (!ok) ++failures;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace deflex;
  std::printf("deflex %s\n", kVersion);
  try {
    // 1. A robot file (URDF or deflex YAML) for kinematics; the stiffness of the built-in IRB 6700 when
    //    the file has none (a bare URDF).
    RobotModel robot = argc > 1 ? load_robot(argv[1]) : builtin_irb6700();
    if (!robot.has_stiffness()) {
      robot = robot.with_stiffness(std::vector<double>(static_cast<std::size_t>(robot.dof()), 1e6),
                                   "assumed 1e6 Nm/rad a joint");
    }
    Workspace ws(robot);
    JointVector q(robot.dof());
    q.setConstant(0.3);
    q[1] = -0.2;
    const Pose tcp = tcp_pose(robot, ws, q);
    Jacobian J(6, robot.dof());
    jacobian(robot, ws, q, EndPoint::kTcp, J);
    std::printf("%s: TCP at (%.4f, %.4f, %.4f) m\n", robot.name().c_str(), tcp.translation().x(), tcp.translation().y(),
                tcp.translation().z());

    // 2. IK of that pose comes back to q.
    IkRequest request;
    request.seed = q;
    const IkResult ik = inverse_kinematics(robot, ws, tcp, request);
    check(ik.ok() && (ik.q - q).cwiseAbs().maxCoeff() < 1e-6, "inverse kinematics returns the configuration");

    // 3. Deflection under 500 N down: K^-1 J^T W by hand against the library's.
    Wrench w;
    w << 0.0, 0.0, -500.0, 0.0, 0.0, 0.0;
    JointVector dtheta;
    joint_deflection(robot, ws, q, w, dtheta);
    const Eigen::VectorXd by_hand = robot.compliance().cwiseProduct(J.transpose() * w);
    check((dtheta - by_hand).norm() < 1e-12, "joint deflection = K^-1 J^T W");

    // 4. A 100 mm line towards the base (inside the reach), compensated offline for that load.
    LinePath line;
    line.start_m = tcp.translation();
    const Vector3 inward = -Vector3(tcp.translation().x(), tcp.translation().y(), 0.0).normalized();
    line.end_m = tcp.translation() + 0.1 * inward;
    line.points = 11;
    const std::vector<Pose> poses = sample_line(line, Eigen::Quaterniond(tcp.linear()));
    const JointPath path = solve_path_ik(robot, poses, request);
    const ConstantWrenchModel force(w);
    const OfflineResult offline = compensate_path(robot, path, poses, force);
    check(offline.max_residual_m < 1e-9 && offline.max_deflection_m > 1e-6,
          "offline compensation cancels the predicted deflection");

    // 5. The online cycle in a loop of one's own: a constant force sample, then steps at 4 ms.
    SensorConfig sensor;
    OnlineConfig online_config;
    OnlineCompensator online(robot, sensor, online_config);
    CycleOutput out;
    for (int k = 0; k < 250; ++k) {
      ForceSample sample;
      sample.t_s = 0.004 * k;
      sample.wrench_sensor << 0.0, 0.0, 200.0, 0.0, 0.0, 0.0;
      online.push_force(sample);
      CycleInput in;
      in.t_s = 0.004 * k;
      in.q_planned = q;
      in.q_feedback = q;
      out = online.step(in);
    }
    check(static_cast<int>(out.status) >= 0 && out.dtheta.norm() > 0.0, "the online cycle corrects under a force");

    // 6. A runtime session against the stand-in of an ABB EGM controller (egm-joint): a 2 s program
    //    holding q, a 300 N push at the TCP; every command within the session's bound of the nominal.
    auto program =
        std::make_shared<const JointTrajectory>(std::vector<double>{0.0, 2.0}, std::vector<JointVector>{q, q}, robot);
    runtime::SessionConfig config;
    config.link = runtime::LinkKind::kEgmJoint;
    config.status_interval_s = 0.0;
    standin::StandInConfig cell;
    cell.force_base_n = Vector3(0.0, 0.0, -300.0);
    standin::StandInSession session(config, robot, sensor, program, nullptr, cell);
    session.run_for(3.0);
    const runtime::SessionSummary& summary = session.session().finish();
    std::printf("session: %s, %llu cycles, largest deviation %.3g rad of %.3g rad\n", summary.reason_text.c_str(),
                static_cast<unsigned long long>(summary.cycles), summary.stats.max_deviation_rad,
                config.online.max_joint_correction_rad);
    check(summary.cycles > 400 && summary.stats.max_deviation_rad <= config.online.max_joint_correction_rad + 1e-12,
          "the session answered within its bound");
  } catch (const std::exception& e) {
    std::printf("FAIL %s\n", e.what());
    return 1;
  }
  return failures == 0 ? 0 : 1;
}
