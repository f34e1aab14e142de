// Inverse kinematics along a path with one configuration kept.
#include "deflex/paths/path_ik.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/model/opw_ik.hpp"
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

/// The one-arm shortcut needs the path's arm to be told apart from the others by cfx: the shoulder
/// by the sign of the wrist centre's x in the A1 frame, the elbow by the sign of sin(gamma), both at
/// least the near-singular threshold away from zero in a solution that is not near a singularity.
/// Below this threshold (a caller asking to hear of no singularity) the shortcut is not taken.
constexpr double kArmMarginThreshold = 1e-6;

double max_abs_diff(const Eigen::Matrix<double, 6, 1>& a, const JointVector& b) {
  double m = 0.0;
  for (int j = 0; j < 6; ++j) {
    m = std::max(m, std::abs(a[j] - b[j]));
  }
  return m;
}

}  // namespace

unsigned opw_arm_of_configuration(const OpwGeometry& g, int cfx) {
  // cfx bit 2 is the back shoulder; bit 1 is set for the first elbow (sin gamma > 0) exactly when
  // axis 2 turns against the canonical y axis (opw_ik.cpp, abb_cfx: the lower arm cross product has
  // the sign of sin gamma).
  const unsigned shoulder = (static_cast<unsigned>(cfx) >> 2U) & 1U;
  const unsigned bit1 = (static_cast<unsigned>(cfx) >> 1U) & 1U;
  const unsigned elbow = bit1 ^ (g.sign[1] < 0.0 ? 1U : 0U);
  return 1U << (2U * shoulder + elbow);
}

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

bool PathIkSolver::next_on_path_arm(const Pose& base_T_tcp) {
  // The full solve refuses these with its message.
  if (!base_T_tcp.matrix().allFinite() ||
      (base_T_tcp.linear().transpose() * base_T_tcp.linear() - Matrix3::Identity()).norm() > 1e-6) {
    return false;
  }
  OpwSolutions solutions;
  opw_solutions(model_, base_T_tcp, &q_, solutions, request_.near_singular_threshold, arm_);
  // As inverse_kinematics() chooses among the branches of the path's cfx: the nearest to the
  // previous point (largest joint difference), the first of equals.
  int best = -1;
  double best_step = HUGE_VAL;
  for (int k = 0; k < solutions.count; ++k) {
    const OpwSolution& s = solutions.solution[static_cast<std::size_t>(k)];
    if (s.configuration.cfx != configuration_.cfx) {
      continue;
    }
    const double step = max_abs_diff(s.q, q_);
    if (step < best_step) {
      best_step = step;
      best = k;
    }
  }
  // Near a singularity another arm may share the cfx, and the point may stop the path: the full solve decides.
  if (best < 0 || solutions.solution[static_cast<std::size_t>(best)].singularity != Singularity::kNone ||
      !(best_step <= options_.max_joint_step_rad)) {
    return false;
  }
  q_ = solutions.solution[static_cast<std::size_t>(best)].q;
  request_.seed = q_;
  return true;
}

const JointVector& PathIkSolver::next(const Pose& base_T_tcp) {
  const std::size_t i = index_;
  if (arm_ != 0 && next_on_path_arm(base_T_tcp)) {
    ++index_;
    return q_;
  }
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
    if (const OpwGeometry* g = model_.opw();
        g != nullptr && !request_.kuka_configuration && request_.near_singular_threshold >= kArmMarginThreshold) {
      arm_ = opw_arm_of_configuration(*g, r.configuration.cfx);
    }
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
