// Inverse kinematics along a path with one configuration kept.
#include "deflex/paths/path_ik.hpp"

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

[[noreturn]] void fail_point(std::size_t index, const IkResult& r) {
  const char* reason = "failed";
  switch (r.status) {
    case IkStatus::kUnreachable:
      reason = "unreachable";
      break;
    case IkStatus::kOutsideJointLimits:
      reason = "outside the joint limits";
      break;
    case IkStatus::kConfigurationUnavailable:
      reason = "no solution with the path's arm configuration";
      break;
    case IkStatus::kNearSingular:
      reason = "singular";
      break;
    case IkStatus::kNotConverged:
      reason = "inverse kinematics did not converge";
      break;
    case IkStatus::kInvalidInput:
      reason = "invalid pose";
      break;
    case IkStatus::kOk:
      break;
  }
  throw InputError(fmt::format("path point {}: {} ({})", index, reason, r.message));
}

}  // namespace

JointPath solve_path_ik(const RobotModel& model, const std::vector<Pose>& poses, const IkRequest& first) {
  return solve_path_ik(model, poses, first, PathIkOptions{});
}

PathIkSolver::PathIkSolver(const RobotModel& model, const IkRequest& first, const PathIkOptions& options)
    : model_(model), options_(options), ws_(model), request_(first), q_(model.dof()) {
  // Checked once here: next() compares every joint step with it, and a NaN bound would pass any jump.
  if (!(options.max_joint_step_rad > 0.0)) {
    throw InputError(fmt::format("path inverse kinematics: max_joint_step_rad must be > 0 rad (got {})",
                                 options.max_joint_step_rad));
  }
}

const JointVector& PathIkSolver::next(const Pose& base_T_tcp) {
  const std::size_t i = index_;
  const IkResult r = inverse_kinematics(model_, ws_, base_T_tcp, request_);
  if (!r.ok() || (r.status == IkStatus::kNearSingular && !options_.allow_near_singular)) {
    fail_point(i, r);
  }
  if (i == 0) {
    configuration_ = r.configuration;
    // From here on the branch (cfx) is fixed and the nearest solution wins: the quadrants follow
    // the joints continuously instead of being forced.
    request_.configuration = r.configuration;
    request_.match_quadrants = false;
  } else {
    for (int j = 0; j < model_.dof(); ++j) {
      const double step = std::abs(r.q[j] - q_[j]);
      if (step > options_.max_joint_step_rad) {
        throw InputError(
            fmt::format("path point {}: joint {} moves {:.2f} deg from point {} (limit {:.2f} deg): the path passes a "
                        "singularity or a joint limit with this configuration, or it is sampled too coarsely",
                        i, j + 1, rad_to_deg(step), i - 1, rad_to_deg(options_.max_joint_step_rad)));
      }
    }
  }
  q_ = r.q;
  request_.seed = r.q;
  ++index_;
  return q_;
}

JointPath solve_path_ik(const RobotModel& model, const std::vector<Pose>& poses, const IkRequest& first,
                        const PathIkOptions& options) {
  if (poses.empty()) {
    throw InputError("path: no points");
  }
  PathIkSolver solver(model, first, options);
  JointPath path;
  path.q.reserve(poses.size());
  for (const Pose& pose : poses) {
    path.q.push_back(solver.next(pose));
  }
  path.configuration = solver.configuration();
  return path;
}

}  // namespace deflex
