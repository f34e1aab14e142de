// Per-point offline compensation.
#include "deflex/offline/compensate_path.hpp"

#include <algorithm>
#include <utility>

#include <fmt/format.h>

#include "deflex/model/compliance.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

constexpr double kDeflectionTolRad = 1e-13;  // fixed-point step at which a deflection counts as solved

const ForceModel& shared_force(const std::shared_ptr<const ForceModel>& force) {
  if (!force) throw InputError("offline compensation: no force model (a null pointer)");
  return *force;
}

}  // namespace

OfflineResult compensate_path(const RobotModel& model, const JointPath& path, const std::vector<Pose>& tcp_poses,
                              const ForceModel& force) {
  return compensate_path(model, path, tcp_poses, force, OfflineOptions{});
}

PathCompensator::PathCompensator(const RobotModel& model, std::shared_ptr<const ForceModel> force,
                                 const OfflineOptions& options)
    : PathCompensator(model, shared_force(force), options) {
  force_owner_ = std::move(force);
}

PathCompensator::PathCompensator(const RobotModel& model, const ForceModel& force, const OfflineOptions& options)
    : model_(model),
      force_(force),
      options_(options),
      ws_(model),
      q_actual_(model.dof()),
      dtheta_desired_(model.dof()),
      q_start_(model.dof()) {
  if (!model.has_stiffness()) {
    throw InputError(fmt::format("robot '{}' ({}): no joint stiffness; offline compensation needs one", model.name(),
                                 model.description().source));
  }
  result_.robot_name = model.name();
  result_.stiffness_note = model.description().stiffness_note;
  result_.force_description = force.describe();
  result_.predicted = options.predict;
}

// NOLINTNEXTLINE(readability-function-size): listed in docs/architecture.md, "Functions over 80 lines"
const OfflinePoint& PathCompensator::compensate(std::size_t i, const JointVector& q_desired, const Pose& tcp_desired) {
  const RobotModel& model = model_;
  Workspace& ws = ws_;
  OfflinePoint& pt = point_;
  OfflineResult& result = result_;
  if (const auto force_points = force_.points(); force_points && i >= *force_points) {
    throw InputError(fmt::format("offline compensation: the force model ({}) has {} points, the path more",
                                 force_.describe(), *force_points));
  }
  pt.q_desired = q_desired;
  pt.tcp_desired = tcp_desired;
  if (pt.q_desired.size() != model.dof() || !pt.q_desired.allFinite()) {
    throw InputError(fmt::format("path point {}: joint vector must hold {} finite values", i, model.dof()));
  }
  // The pose is the caller's (a force model may not look at it, and the residual is measured from
  // it): a NaN here gave NaN points whose figures the max and mean silently left out.
  if (!pt.tcp_desired.translation().allFinite()) {
    throw InputError(fmt::format("path point {}: the desired TCP pose has a non-finite position", i));
  }
  if (!pt.tcp_desired.linear().allFinite()) {
    throw InputError(fmt::format("path point {}: the desired TCP pose has a non-finite orientation", i));
  }
  const Wrench wrench_tcp = force_.wrench_at(i, pt.tcp_desired);
  if (!wrench_tcp.allFinite()) {
    throw InputError(fmt::format("path point {}: the force model gave a non-finite wrench", i));
  }
  pt.wrench_base = wrench_tcp;
  if (!model.wap_is_tcp()) {
    // The force acts at the TCP; the model takes its moment about the WAP.
    forward_kinematics(model, ws, pt.q_desired);
    pt.wrench_base = moment_moved(wrench_tcp, ws.base_T_tcp.translation(), ws.base_T_wap.translation());
  }

  compensated_configuration(model, ws, pt.q_desired, pt.wrench_base, pt.q_command, dtheta_desired_);
  const Pose tcp_at_desired = ws.base_T_tcp;  // compensated_configuration ran FK at q_desired
  if (!model.within_limits(pt.q_command)) {
    throw InputError(fmt::format("path point {}: the compensated configuration leaves the joint limits", i));
  }
  pt.tcp_command = tcp_pose(model, ws, pt.q_command);
  pt.configuration_command = arm_configuration(model, ws, pt.q_command);
  ++count_;

  result.max_correction_m =
      std::max(result.max_correction_m, (pt.tcp_command.translation() - pt.tcp_desired.translation()).norm());
  result.max_joint_correction_rad =
      std::max(result.max_joint_correction_rad, (pt.q_command - pt.q_desired).cwiseAbs().maxCoeff());
  if (!options_.predict) {
    return pt;
  }

  // Both solves start where the first fixed-point step from their command would take them, or
  // nearer: commanded to q_desired the arm first goes to q_desired + dtheta_desired (the step
  // already computed above); commanded to q_cmd it goes back to q_desired, the configuration the
  // command was computed for. The step test still certifies each fixed point to 1e-13 rad.
  q_start_ = pt.q_desired + dtheta_desired_;
  if (deflected_configuration_from(model, ws, pt.q_desired, pt.wrench_base, q_start_, q_actual_, kDeflectionTolRad) !=
      DeflectionStatus::kConverged) {
    throw InputError(
        fmt::format("path point {}: the predicted deflection does not converge (load far beyond the "
                    "model's range)",
                    i));
  }
  pt.predicted_deflection = pose_difference(tcp_at_desired, tcp_pose(model, ws, q_actual_));
  // Its first step from q_desired needs K^-1 J(q_desired)^T W, which is dtheta_desired: taken here
  // without computing it again; the step test decides as deflected_configuration's would.
  q_actual_ = pt.q_command + dtheta_desired_;
  if ((q_actual_ - pt.q_desired).cwiseAbs().maxCoeff() >= kDeflectionTolRad) {
    q_start_ = q_actual_;
    if (deflected_configuration_from(model, ws, pt.q_command, pt.wrench_base, q_start_, q_actual_, kDeflectionTolRad) !=
        DeflectionStatus::kConverged) {
      throw InputError(fmt::format("path point {}: the deflection of the compensated command does not converge", i));
    }
  }
  pt.predicted_residual = pose_difference(pt.tcp_desired, tcp_pose(model, ws, q_actual_));

  const double d = pt.predicted_deflection.head<3>().norm();
  sum_deflection_ += d;
  result.max_deflection_m = std::max(result.max_deflection_m, d);
  result.max_deflection_rad = std::max(result.max_deflection_rad, pt.predicted_deflection.tail<3>().norm());
  result.max_residual_m = std::max(result.max_residual_m, pt.predicted_residual.head<3>().norm());
  result.max_residual_rad = std::max(result.max_residual_rad, pt.predicted_residual.tail<3>().norm());
  return pt;
}

OfflineResult PathCompensator::summary() const {
  if (count_ == 0) {
    throw InputError("offline compensation: the path has no points");
  }
  if (const auto force_points = force_.points(); force_points && *force_points != count_) {
    throw InputError(fmt::format("offline compensation: the force model ({}) has {} points, the path {}",
                                 force_.describe(), *force_points, count_));
  }
  OfflineResult r = result_;
  r.point_count = count_;
  r.mean_deflection_m = sum_deflection_ / static_cast<double>(count_);
  return r;
}

OfflineResult compensate_path(const RobotModel& model, const JointPath& path, const std::vector<Pose>& tcp_poses,
                              const ForceModel& force, const OfflineOptions& options) {
  OfflineResult result;
  compensate_path(model, path, tcp_poses, force, options, result);
  return result;
}

void compensate_path(const RobotModel& model, const JointPath& path, const std::vector<Pose>& tcp_poses,
                     const ForceModel& force, const OfflineOptions& options, OfflineResult& out) {
  std::vector<OfflinePoint> points = std::move(out.points);
  points.clear();  // keeps its capacity
  out = OfflineResult();
  out.points = std::move(points);
  PathCompensator compensator(model, force, options);
  const std::size_t n = path.q.size();
  if (n == 0) {
    throw InputError("offline compensation: the path has no points");
  }
  if (tcp_poses.size() != n) {
    throw InputError(
        fmt::format("offline compensation: {} joint configurations but {} TCP poses", n, tcp_poses.size()));
  }
  if (const auto force_points = force.points(); force_points && *force_points != n) {
    throw InputError(fmt::format("offline compensation: the force model ({}) has {} points, the path {}",
                                 force.describe(), *force_points, n));
  }
  out.points.resize(n);  // within the capacity of a path as long before: no allocation
  for (std::size_t i = 0; i < n; ++i) {
    out.points[i] = compensator.compensate(i, path.q[i], tcp_poses[i]);
  }
  std::vector<OfflinePoint> filled = std::move(out.points);
  out = compensator.summary();
  out.points = std::move(filled);
}

}  // namespace deflex
