// Subcommands of the model layer: fk, ik, deflect, robot.
#include <cmath>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::cli {
namespace {

nlohmann::json pose_json(const Pose& p) {
  const Eigen::Quaterniond q(p.linear());
  return {{"position_m", vector_to_json(p.translation())},
          {"rotation_matrix", to_json(p.linear())},
          {"quaternion_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
}

void setup_fk(CLI::App& sub, int& exit_code) {
  struct Opts {
    std::string robot, joints;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--joints-deg", o->joints, "Joint values in degrees, comma-separated: \"j1,...,j6\"")->required();
  sub.add_flag("--json", o->json, "Print one JSON document on stdout");
  sub.callback([o, &exit_code] {
    const RobotModel model = load_cli_robot("fk", o->robot);
    const JointVector q = parse_joints_deg(o->joints, model, "--joints-deg");
    Workspace ws(model);
    const Pose tcp = tcp_pose(model, ws, q);
    if (!model.within_limits(q)) {
      std::cerr << "deflex fk: warning: the configuration is outside the joint limits\n";
    }
    if (o->json) {
      nlohmann::json doc = pose_json(tcp);
      doc["robot"] = model.name();
      doc["within_joint_limits"] = model.within_limits(q);
      print_json(doc);
    } else {
      const Eigen::Quaterniond qt(tcp.linear());
      const Vector3 p = tcp.translation() * 1e3;
      std::cout << fmt::format("robot: {}\nTCP position (mm, base frame): {:.3f} {:.3f} {:.3f}\n", model.name(), p.x(),
                               p.y(), p.z())
                << fmt::format("TCP orientation (quaternion w x y z): {:.6f} {:.6f} {:.6f} {:.6f}\n", qt.w(), qt.x(),
                               qt.y(), qt.z());
    }
    exit_code = 0;
  });
}

void setup_ik(CLI::App& sub, int& exit_code) {
  struct Opts {
    std::string robot, position, quaternion, config, seed;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--position-mm", o->position, "TCP position in mm, base frame: \"x,y,z\"")->required();
  sub.add_option("--quaternion-wxyz", o->quaternion, "TCP orientation as a unit quaternion \"w,x,y,z\"")->required();
  sub.add_option("--config", o->config,
                 "ABB confdata \"cf1,cf4,cf6,cfx\" (quadrants of joints 1, 4, 6; cfx 0-7); default: the solution "
                 "closest to the seed, or to all joints zero");
  sub.add_option("--seed-deg", o->seed, "Preferred joint values in degrees \"j1,...,j6\"");
  sub.add_flag("--json", o->json, "Print one JSON document on stdout");
  sub.callback([o, &exit_code] {
    const RobotModel model = load_cli_robot("ik", o->robot);
    const auto p = parse_numbers(o->position, "--position-mm", 3, range::kLengthMm);
    const auto qv = parse_numbers(o->quaternion, "--quaternion-wxyz", 4, range::kUnitQuaternion);
    Eigen::Quaterniond quat(qv[0], qv[1], qv[2], qv[3]);
    if (std::abs(quat.norm() - 1.0) > 1e-3) {
      throw InputError(fmt::format("option --quaternion-wxyz: not a unit quaternion (norm {:.6f})", quat.norm()));
    }
    Pose target = Pose::Identity();
    target.linear() = quat.normalized().toRotationMatrix();
    target.translation() = Vector3(p[0], p[1], p[2]) * 1e-3;
    IkRequest req;
    if (!o->config.empty()) {
      const auto c = parse_numbers(o->config, "--config", 4);
      req.configuration = ArmConfiguration{static_cast<int>(c[0]), static_cast<int>(c[1]), static_cast<int>(c[2]),
                                           static_cast<int>(c[3])};
      if (c[3] < 0 || c[3] > 7) {
        throw InputError("option --config: cfx must be 0..7");
      }
    }
    if (!o->seed.empty()) {
      req.seed = parse_joints_deg(o->seed, model, "--seed-deg");
    }
    Workspace ws(model);
    const IkResult r = inverse_kinematics(model, ws, target, req);
    if (o->json) {
      nlohmann::json doc{{"status", to_string(r.status)},
                         {"ok", r.ok()},
                         {"message", r.message},
                         {"analytic", r.analytic},
                         {"singularity", to_string(r.singularity)}};
      if (r.ok()) {
        JointVector deg = r.q * (180.0 / kPi);
        doc["joints_deg"] = vector_to_json(deg);
        doc["config"] = {r.configuration.cf1, r.configuration.cf4, r.configuration.cf6, r.configuration.cfx};
        doc["kuka_status"] = r.kuka.status;
        doc["kuka_turn"] = r.kuka.turn;
        doc["position_error_m"] = r.position_error_m;
        doc["orientation_error_rad"] = r.orientation_error_rad;
      }
      print_json(doc);
    } else if (r.ok()) {
      std::cout << "joints (deg):";
      for (int i = 0; i < r.q.size(); ++i) {
        std::cout << fmt::format(" {:.4f}", rad_to_deg(r.q[i]));
      }
      std::cout << fmt::format(
          "\nconfig [cf1,cf4,cf6,cfx]: [{},{},{},{}]  (KUKA S {} T {})\n"
          "solver: {}, residual {:.2e} m, {:.2e} rad\n",
          r.configuration.cf1, r.configuration.cf4, r.configuration.cf6, r.configuration.cfx, r.kuka.status,
          r.kuka.turn, r.analytic ? "analytic (ortho-parallel)" : "damped least squares", r.position_error_m,
          r.orientation_error_rad);
    }
    if (!r.message.empty()) {
      std::cerr << fmt::format("deflex ik: {}: {}\n", r.ok() ? "warning" : "error", r.message);
    }
    exit_code = r.ok() ? 0 : 1;
  });
}

void setup_deflect(CLI::App& sub, int& exit_code) {
  struct Opts {
    std::string robot, stiffness, joints, wrench;
    bool json = false, complementary = false;
  };
  auto o = std::make_shared<Opts>();
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--stiffness-Nm-per-rad", o->stiffness, kStiffnessHelp);
  sub.add_option("--joints-deg", o->joints, "Joint values in degrees \"j1,...,j6\"")->required();
  sub.add_option("--wrench", o->wrench,
                 "Wrench at the WAP \"Fx,Fy,Fz,Mx,My,Mz\" in N and Nm, robot base frame, moment about the WAP")
      ->required();
  sub.add_flag("--complementary-stiffness", o->complementary,
               "Include the complementary stiffness d(J^T W)/dtheta (large loads)");
  sub.add_flag("--json", o->json, "Print one JSON document on stdout");
  sub.callback([o, &exit_code] {
    const RobotModel model = load_cli_robot("deflect", o->robot, o->stiffness);
    // Without stiffness the deflection would print as zero: refuse, as offline and online do.
    require_stiffness(model);
    const JointVector q = parse_joints_deg(o->joints, model, "--joints-deg");
    const Wrench wrench = parse_wrench(o->wrench, "--wrench");
    Workspace ws(model);
    ComplianceOptions opt;
    opt.complementary_stiffness = o->complementary;
    JointVector dtheta;
    joint_deflection(model, ws, q, wrench, dtheta, opt);
    const Displacement dx = tcp_deflection(model, ws, q, wrench, opt);
    const Matrix6 C = cartesian_compliance(model, ws, q);
    if (o->json) {
      print_json(
          {{"robot", model.name()},
           {"dtheta_rad", vector_to_json(dtheta)},
           {"tcp_deflection_m", vector_to_json(dx)},
           {"tcp_deflection_units", "m, m, m, rad, rad, rad (base frame)"},
           {"cartesian_compliance", to_json(C)},
           {"cartesian_compliance_units", "rows/cols [m, m, m, rad, rad, rad] per [N, N, N, Nm, Nm, Nm] at the WAP"},
           {"complementary_stiffness", o->complementary}});
    } else {
      std::cout << fmt::format("robot: {}\njoint deflection (mrad):", model.name());
      for (int i = 0; i < dtheta.size(); ++i) {
        std::cout << fmt::format(" {:.5f}", dtheta[i] * 1e3);
      }
      std::cout << fmt::format("\nTCP deflection (mm, base frame): {:.4f} {:.4f} {:.4f}  |dp| = {:.4f} mm\n",
                               dx[0] * 1e3, dx[1] * 1e3, dx[2] * 1e3, dx.head<3>().norm() * 1e3)
                << fmt::format("TCP rotation (mrad): {:.5f} {:.5f} {:.5f}\n", dx[3] * 1e3, dx[4] * 1e3, dx[5] * 1e3);
    }
    exit_code = 0;
  });
}

void setup_robot(CLI::App& sub, int& exit_code) {
  struct Opts {
    std::string robot, stiffness;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--stiffness-Nm-per-rad", o->stiffness, kStiffnessHelp);
  sub.add_flag("--json", o->json,
               "Print one JSON document on stdout: name, source, dof, joint limits (deg), stiffness (Nm/rad), the "
               "tool and the robot file text (yaml)");
  sub.callback([o, &exit_code] {
    const RobotModel model = load_cli_robot("robot", o->robot, o->stiffness);
    const std::string yaml = robot_to_yaml(model);
    if (!o->json) {
      std::cout << yaml;
      exit_code = 0;
      return;
    }
    nlohmann::json joints = nlohmann::json::array();
    for (const JointSpec& j : model.description().joints) {
      joints.push_back({{"name", j.name},
                        {"min_deg", std::isfinite(j.lower_rad) ? nlohmann::json(rad_to_deg(j.lower_rad)) : nullptr},
                        {"max_deg", std::isfinite(j.upper_rad) ? nlohmann::json(rad_to_deg(j.upper_rad)) : nullptr}});
    }
    print_json(
        {{"name", model.name()},
         {"source", model.description().source},
         {"dof", model.dof()},
         {"joints", joints},
         {"stiffness_Nm_per_rad", model.has_stiffness() ? vector_to_json(model.stiffness()) : nlohmann::json(nullptr)},
         {"flange_T_tcp", pose_json(model.description().flange_T_tcp)},
         {"yaml", yaml}});
    exit_code = 0;
  });
}

}  // namespace

DEFLEX_COMMAND("fk", "Forward kinematics: TCP pose from joint values (deg)", setup_fk, 10);
DEFLEX_COMMAND("ik", "Inverse kinematics: joint values from a TCP pose (mm, quaternion)", setup_ik, 11);
DEFLEX_COMMAND("deflect", "Joint and TCP deflection under a wrench (N, Nm) by the lumped joint-compliance model",
               setup_deflect, 12);
DEFLEX_COMMAND("robot", "Print a robot description as deflex YAML (e.g. the built-in IRB6700)", setup_robot, 13);

}  // namespace deflex::cli
