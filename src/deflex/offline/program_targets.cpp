// Compensation of resolved program targets, one compensate_path() call per use so the program path
// computes exactly what the path path computes.
#include "deflex/offline/detail/program_targets.hpp"

#include <map>
#include <memory>

#include <fmt/format.h>

#include "deflex/offline/compensate_path.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

/// The program's force model seen from a one-point path: point 0 is the use's own index.
class ShiftedForce final : public ForceModel {
 public:
  ShiftedForce(const ForceModel& force, std::size_t index) : force_(force), index_(index) {}
  [[nodiscard]] Wrench wrench_at(std::size_t /*index*/, const Pose& base_T_tcp) const override {
    return force_.wrench_at(index_, base_T_tcp);
  }
  [[nodiscard]] std::string describe() const override { return force_.describe(); }

 private:
  const ForceModel& force_;
  std::size_t index_;
};

/// The robot with a program's tool, built once per distinct tool.
const RobotModel& model_with_tool(const RobotModel& model, const Pose& tool,
                                  std::vector<std::pair<Pose, std::unique_ptr<RobotModel>>>& cache) {
  for (const auto& [pose, m] : cache) {
    if ((pose.matrix() - tool.matrix()).cwiseAbs().maxCoeff() < 1e-12) {
      return *m;
    }
  }
  cache.emplace_back(tool, std::make_unique<RobotModel>(model.with_tool(tool)));
  return *cache.back().second;
}

}  // namespace

// NOLINTNEXTLINE(readability-function-size): listed in docs/architecture.md, "Functions over 80 lines"
std::vector<ProgramTargetResult> compensate_program_targets(const RobotModel& model,
                                                            const std::vector<ProgramTargetUse>& uses,
                                                            const ForceModel& force,
                                                            const std::optional<JointVector>& start_q) {
  if (const auto n = force.points(); n && !uses.empty()) {
    std::size_t needed = 0;
    for (const ProgramTargetUse& u : uses) {
      needed = std::max(needed, u.force_index + 1);
    }
    if (*n < needed) {
      throw InputError(fmt::format("the force model ({}) has {} points, the program's motion targets need {}",
                                   force.describe(), *n, needed));
    }
  }
  std::vector<std::pair<Pose, std::unique_ptr<RobotModel>>> tools;
  std::vector<ProgramTargetResult> out;
  out.reserve(uses.size());
  const ProgramTargetResult* previous = nullptr;
  for (const ProgramTargetUse& u : uses) {
    const std::string where = fmt::format("{}:{}: {} {}", u.file, u.line, u.instruction, u.target);
    const RobotModel& m = model_with_tool(model, u.flange_T_tcp, tools);
    Workspace ws(m);
    ProgramTargetResult r;
    if (u.joint) {
      if (u.q.size() != m.dof()) {
        throw InputError(fmt::format("{}: {} joint values for a robot of {} joints", where, u.q.size(), m.dof()));
      }
      if (!m.within_limits(u.q)) {
        throw InputError(fmt::format("{}: the joint target lies outside the robot's joint limits", where));
      }
      r.q_desired = u.q;
      r.tcp_desired = tcp_pose(m, ws, u.q);
    } else {
      // The joints the controller starts from: the previous use's, or the arm's at the start.
      const std::optional<JointVector> before =
          previous != nullptr ? std::optional<JointVector>(previous->q_desired) : start_q;
      IkRequest req = u.ik;
      if (u.nearest_previous && before) {
        req.seed = *before;
        req.configuration.reset();
        req.kuka_configuration.reset();
      } else if (u.continue_from_previous) {
        if (!before) {
          throw InputError(fmt::format("{}: no configuration given and no earlier target to continue from", where));
        }
        req.seed = *before;
        req.configuration = arm_configuration(m, ws, *before);
        req.match_quadrants = false;
      }
      const IkResult ik = inverse_kinematics(m, ws, u.base_T_tcp, req);
      if (!ik.ok()) {
        // Under ConfJ\Off the controller would take the configuration nearest the arm, which only
        // the arm's joints at the start can say for the first target.
        const std::string hint =
            u.nearest_previous && !before
                ? fmt::format(
                      "; under {} the controller takes the configuration nearest the arm: give the arm's "
                      "joints at the start with --seed-deg",
                      u.configuration_rule)
                : "";
        throw InputError(fmt::format("{}: {} ({}){}", where, to_string(ik.status), ik.message, hint));
      }
      if (ik.status == IkStatus::kNearSingular) {
        throw InputError(
            fmt::format("{}: {}: the compensation would move joints by large amounts there", where, ik.message));
      }
      r.q_desired = ik.q;
      r.tcp_desired = u.base_T_tcp;
    }
    JointPath path;
    path.q = {r.q_desired};
    path.configuration = arm_configuration(m, ws, r.q_desired);
    OfflineResult c;
    try {
      c = compensate_path(m, path, {r.tcp_desired}, ShiftedForce(force, u.force_index));
    } catch (const Error& e) {
      throw InputError(fmt::format("{}: {}", where, e.what()));
    }
    const OfflinePoint& p = c.points.front();
    r.q_command = p.q_command;
    r.tcp_command = p.tcp_command;
    r.configuration = p.configuration_command;
    r.kuka = kuka_configuration(m, ws, p.q_command);
    r.wrench_base = p.wrench_base;
    r.deflection = p.predicted_deflection;
    r.residual_m = p.predicted_residual.head<3>().norm();
    out.push_back(r);
    previous = &out.back();
  }
  return out;
}

ProgramTargetReport target_report(const ProgramTargetResult& result, const std::string& file, int line,
                                  const std::string& instruction, const std::string& target,
                                  const std::string& action) {
  ProgramTargetReport rep;
  rep.file = file;
  rep.line = line;
  rep.instruction = instruction;
  rep.target = target;
  rep.action = action;
  rep.deflection_m = result.deflection.head<3>().norm();
  rep.deflection_rad = result.deflection.tail<3>().norm();
  rep.correction_m = (result.tcp_command.translation() - result.tcp_desired.translation()).norm();
  rep.joint_correction_rad = (result.q_command - result.q_desired).cwiseAbs().maxCoeff();
  rep.wrench_base = result.wrench_base;
  return rep;
}

}  // namespace deflex
