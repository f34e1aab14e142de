// Inverse kinematics: the ortho-parallel closed form (opw_ik.hpp) with the configuration and turn
// the caller asks for, and damped least squares for other arms.
#include "deflex/model/inverse_kinematics.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <fmt/format.h>
#include <Eigen/SVD>

#include "deflex/model/opw_ik.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

double max_abs_diff(const JointVector& a, const JointVector& b) { return (a - b).cwiseAbs().maxCoeff(); }

void fill_errors(const RobotModel& model, Workspace& ws, const Pose& target, IkResult& r) {
  forward_kinematics(model, ws, r.q);
  const Displacement e = pose_difference(ws.base_T_tcp, target);
  r.position_error_m = e.head<3>().norm();
  r.orientation_error_rad = e.tail<3>().norm();
}

// Where damped least squares starts: the caller's seed, zero, mid-range, and a few deterministic
// spread starts (reproducible, and enough for reachable poses in practice).
std::vector<JointVector> ik_starts(const RobotModel& model, const IkRequest& req) {
  const int n = model.dof();
  std::vector<JointVector> starts;
  if (req.seed) {
    starts.push_back(*req.seed);
  }
  JointVector mid = 0.5 * (model.lower_limits() + model.upper_limits());
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(mid[i])) {
      mid[i] = 0.0;
    }
  }
  starts.push_back(JointVector::Zero(n));
  starts.push_back(mid);
  for (int k = 1; k <= 6; ++k) {
    JointVector s(n);
    for (int i = 0; i < n; ++i) {
      s[i] = std::sin(1.7 * k + 2.3 * i) * 1.5;
    }
    starts.push_back(s);
  }
  return starts;
}

// Damped least squares from `start` (Levenberg-Marquardt on the pose error, steps of at most 0.3 rad
// a joint, within the limits); returns the joints and their error norm.
JointVector descend(const RobotModel& model, Workspace& ws, const Pose& target, const IkRequest& req,
                    const JointVector& start, double& err_norm) {
  Jacobian J;
  JointVector q = start.cwiseMax(model.lower_limits()).cwiseMin(model.upper_limits());
  double lambda = 1e-3;
  err_norm = HUGE_VAL;
  for (int it = 0; it < 300; ++it) {
    forward_kinematics(model, ws, q);
    const Displacement e = pose_difference(ws.base_T_tcp, target);
    err_norm = e.norm();
    if (e.head<3>().norm() < req.tolerance && e.tail<3>().norm() < req.tolerance) {
      break;
    }
    point_jacobian(ws, ws.base_T_tcp.translation(), J);
    const Matrix6 A = J * J.transpose() + lambda * lambda * Matrix6::Identity();
    JointVector dq = J.transpose() * A.ldlt().solve(e);
    const double step = dq.cwiseAbs().maxCoeff();
    if (step > 0.3) {
      dq *= 0.3 / step;
    }
    JointVector q_new = (q + dq).cwiseMax(model.lower_limits()).cwiseMin(model.upper_limits());
    forward_kinematics(model, ws, q_new);
    const double new_err = pose_difference(ws.base_T_tcp, target).norm();
    if (new_err < err_norm) {
      q = q_new;
      lambda = std::max(1e-6, lambda * 0.5);
    } else {
      lambda = std::min(1.0, lambda * 4.0);
    }
  }
  return q;
}

IkResult numerical_ik(const RobotModel& model, Workspace& ws, const Pose& target, const IkRequest& req) {
  IkResult best;
  best.status = IkStatus::kNotConverged;
  double best_err = HUGE_VAL;
  for (const JointVector& start : ik_starts(model, req)) {
    double err_norm = HUGE_VAL;
    const JointVector q = descend(model, ws, target, req, start, err_norm);
    if (err_norm < best_err) {
      best_err = err_norm;
      best.q = q;
    }
    forward_kinematics(model, ws, q);
    const Displacement e = pose_difference(ws.base_T_tcp, target);
    if (e.head<3>().norm() < req.tolerance * 10 && e.tail<3>().norm() < req.tolerance * 10) {
      best.q = q;
      best.status = IkStatus::kOk;
      break;
    }
  }
  fill_errors(model, ws, target, best);
  best.analytic = false;
  if (best.status != IkStatus::kOk) {
    best.message = fmt::format("damped least squares did not converge: residual {:.3g} m, {:.3g} rad",
                               best.position_error_m, best.orientation_error_rad);
    return best;
  }
  best.configuration = arm_configuration(model, ws, best.q);
  best.kuka = kuka_configuration(model, ws, best.q);
  const double smin = jacobian_min_singular_value(model, ws, best.q);
  if (smin < req.near_singular_threshold) {
    best.status = IkStatus::kNearSingular;
    best.singularity = Singularity::kUnknown;
    best.message = fmt::format("near a singularity: smallest Jacobian singular value {:.3g}", smin);
  }
  return best;
}

}  // namespace

const char* to_string(IkStatus s) {
  switch (s) {
    case IkStatus::kOk:
      return "ok";
    case IkStatus::kNearSingular:
      return "near_singular";
    case IkStatus::kUnreachable:
      return "unreachable";
    case IkStatus::kOutsideJointLimits:
      return "outside_joint_limits";
    case IkStatus::kConfigurationUnavailable:
      return "configuration_unavailable";
    case IkStatus::kNotConverged:
      return "not_converged";
    case IkStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

const char* to_string(Singularity s) {
  switch (s) {
    case Singularity::kNone:
      return "none";
    case Singularity::kWrist:
      return "wrist";
    case Singularity::kElbow:
      return "elbow";
    case Singularity::kShoulder:
      return "shoulder";
    case Singularity::kUnknown:
      return "unknown";
  }
  return "unknown";
}

bool has_analytic_ik(const RobotModel& model) { return model.opw() != nullptr; }

namespace {

/// Joints 4 and 5 of the model's first frames give the generic configuration of non-OPW arms.
void generic_configuration(const RobotModel& model, Workspace& ws, const JointVector& q, ArmConfiguration& abb,
                           KukaConfiguration& kuka) {
  const int n = model.dof();
  abb = ArmConfiguration{};
  abb.cf1 = abb_quadrant(q[0]);
  abb.cf4 = n > 3 ? abb_quadrant(q[3]) : 0;
  abb.cf6 = n > 5 ? abb_quadrant(q[5]) : 0;
  kuka = KukaConfiguration{0, kuka_turn(q)};
  if (n < 5) {
    return;
  }
  forward_kinematics(model, ws, q);
  const RobotDescription& d = model.description();
  const JointSpec& j1 = d.joints[0];
  const Matrix3 R1 = d.base_T_chain.linear() * j1.parent_T_joint.linear() *
                     Eigen::AngleAxisd(q[0] + j1.offset_rad, j1.axis).toRotationMatrix();
  const Vector3 x1 = R1.col(0);
  const Vector3 wc = ws.origin_base[4];
  const bool behind_axis1 = (wc - ws.origin_base[0]).dot(x1) < 0.0;
  const Vector3 lower_arm = ws.origin_base[2] - ws.origin_base[1];
  const Vector3 to_wc = wc - ws.origin_base[1];
  const bool behind_lower_arm = ws.axis_base[1].dot(lower_arm.cross(to_wc)) < 0.0;
  const bool q5_negative = negative_joint(q[4]);
  abb.cfx = (behind_axis1 ? 4 : 0) + (behind_lower_arm ? 2 : 0) + (q5_negative ? 1 : 0);
  kuka.status = (behind_axis1 ? 1 : 0) + (behind_lower_arm ? 0 : 2) + (q5_negative ? 4 : 0);
}

/// Every 2*pi turn of `q` inside [lo, hi] (at most `capacity`), ascending; only the one nearest
/// `ref` when a limit is infinite.
int turns_within(double q, double ref, double lo, double hi, std::array<double, 8>& out) {
  constexpr double kTwoPi = 2.0 * kPi;
  constexpr double kSlack = 1e-9;
  if (!std::isfinite(lo) || !std::isfinite(hi)) {
    out[0] = q + kTwoPi * std::nearbyint((ref - q) / kTwoPi);
    return 1;
  }
  int n = 0;
  for (double t = q - kTwoPi * std::floor((q - lo + kSlack) / kTwoPi); t <= hi + kSlack && n < 8; t += kTwoPi) {
    if (t >= lo - kSlack) {
      out[static_cast<std::size_t>(n++)] = std::clamp(t, lo, hi);
    }
  }
  return n;
}

std::string configuration_text(const ArmConfiguration& c, const KukaConfiguration& k) {
  return fmt::format("[{},{},{},{}] (S {} T {})", c.cf1, c.cf4, c.cf6, c.cfx, k.status, k.turn);
}

}  // namespace

ArmConfiguration arm_configuration(const RobotModel& model, Workspace& ws, const JointVector& q) {
  ArmConfiguration abb;
  KukaConfiguration kuka;
  if (const OpwGeometry* g = model.opw()) {
    opw_configuration(*g, q, abb, kuka);
  } else {
    generic_configuration(model, ws, q, abb, kuka);
  }
  return abb;
}

KukaConfiguration kuka_configuration(const RobotModel& model, Workspace& ws, const JointVector& q) {
  ArmConfiguration abb;
  KukaConfiguration kuka;
  if (const OpwGeometry* g = model.opw()) {
    opw_configuration(*g, q, abb, kuka);
  } else {
    generic_configuration(model, ws, q, abb, kuka);
  }
  return kuka;
}

double jacobian_min_singular_value(const RobotModel& model, Workspace& ws, const JointVector& q) {
  Jacobian J;
  jacobian(model, ws, q, EndPoint::kTcp, J);
  // The 6 x n Jacobian padded with zeros to a square matrix has J's singular values and max(6, n) - min(6, n)
  // zeros, so Jacobi's SVD needs no QR preconditioner (which made up most of this file's compile time) and,
  // with fixed capacities, allocates nothing. The smallest of J's own is the min(6, n)-th largest.
  constexpr int kSide = std::max(6, kMaxJoints);
  using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kSide, kSide>;
  const Eigen::Index side = std::max<Eigen::Index>(6, J.cols());
  Square padded = Square::Zero(side, side);
  padded.topLeftCorner(6, J.cols()) = J;
  const Eigen::JacobiSVD<Square, Eigen::NoQRPreconditioner> svd(padded);
  return svd.singularValues()[std::min<Eigen::Index>(6, J.cols()) - 1];
}

namespace {

/// The analytic branches of a target, with the message when there are none.
bool branches_of(const RobotModel& model, const Pose& base_T_tcp, const IkRequest& request, OpwBranches& out,
                 std::string& message) {
  const OpwGeometry& g = *model.opw();
  const double theta4 = g.theta(3, request.seed ? (*request.seed)[3] : 0.0);
  // No early limit check: the caller tells "outside the joint limits" from "no such configuration".
  opw_branches(g, g.opw_T_base * base_T_tcp * g.tcp_T_end, theta4, request.near_singular_threshold, nullptr, out);
  if (!out.reachable) {
    const Pose end = base_T_tcp * g.tcp_T_end;
    const Vector3 wc = end.translation() - g.c4 * end.linear().col(2);
    message = fmt::format("wrist centre ({:.4f}, {:.4f}, {:.4f}) m (base frame) is out of the arm's reach", wc.x(),
                          wc.y(), wc.z());
    return false;
  }
  return true;
}

/// The model's joint values of a branch with the turn of each joint chosen: among the turns inside
/// the limits (and, when asked, in the wanted quadrant or of the wanted sign) the one nearest the
/// seed (or zero). False when some joint has no such turn; `fits_limits` says whether the limits
/// alone left a turn for every joint.
bool choose_turns(const RobotModel& model, const OpwBranch& b, const IkRequest& request, bool apply_request,
                  JointVector& q, bool& fits_limits) {
  const OpwGeometry& g = *model.opw();
  q.resize(6);
  fits_limits = true;
  bool ok = true;
  for (int i = 0; i < 6; ++i) {
    const double ref = request.seed ? (*request.seed)[i] : 0.0;
    std::array<double, 8> turns{};
    const int n = turns_within(g.joint(i, b.theta[static_cast<std::size_t>(i)]), ref, model.lower_limits()[i],
                               model.upper_limits()[i], turns);
    if (n == 0) {
      fits_limits = false;
      return false;
    }
    double best = HUGE_VAL;
    bool found = false;
    for (int k = 0; k < n; ++k) {
      const double t = turns[static_cast<std::size_t>(k)];
      // A joint within kBoundary of a quadrant boundary or of zero matches either side: a program
      // taught at A4 = 0 may come back as -1e-16, which must not send the joint a turn away.
      constexpr double kBoundary = 1e-6;
      if (apply_request && request.configuration && request.match_quadrants && (i == 0 || i == 3 || i == 5)) {
        const ArmConfiguration& want = *request.configuration;
        const int wanted = i == 0 ? want.cf1 : i == 3 ? want.cf4 : want.cf6;
        if (abb_quadrant(t - kBoundary) != wanted && abb_quadrant(t + kBoundary) != wanted) {
          continue;
        }
      }
      if (apply_request && request.kuka_configuration && std::abs(t) > kBoundary &&
          ((request.kuka_configuration->turn >> i) & 1) != (t < 0.0)) {
        continue;
      }
      if (std::abs(t - ref) < std::abs(best - ref)) {
        best = t;
        found = true;
      }
    }
    ok = ok && found;
    q[i] = found ? best : turns[0];
  }
  return ok;
}

void fill_configuration(const RobotModel& model, IkResult& r) {
  opw_configuration(*model.opw(), r.q, r.configuration, r.kuka);
}

// The message when no solution has the configuration asked for: what was asked, what is on offer.
std::string unavailable_configuration(const IkRequest& request,
                                      const std::pair<ArmConfiguration, KukaConfiguration>* available, int count) {
  std::string wanted;
  if (request.configuration) {
    const ArmConfiguration& w = *request.configuration;
    wanted += fmt::format(" configuration [{},{},{},{}]", w.cf1, w.cf4, w.cf6, w.cfx);
  }
  if (request.kuka_configuration) {
    wanted += fmt::format(" Status {} Turn {}", request.kuka_configuration->status, request.kuka_configuration->turn);
  }
  std::string offered;
  for (int k = 0; k < count; ++k) {
    offered += ' ';
    offered += configuration_text(available[k].first, available[k].second);
  }
  return fmt::format("no solution with{}; available [cf1,cf4,cf6,cfx] (S T):{}", wanted, offered);
}

}  // namespace

std::vector<IkResult> all_ik_solutions(const RobotModel& model, Workspace& ws, const Pose& base_T_tcp,
                                       const IkRequest& request) {
  std::vector<IkResult> out;
  if (request.seed && (request.seed->size() != model.dof() || !request.seed->allFinite())) {
    throw InputError(fmt::format("all_ik_solutions: the seed has {} joint value(s), not {} finite ones for {}",
                                 request.seed->size(), model.dof(), model.name()));
  }
  OpwBranches branches;
  std::string message;
  if (!has_analytic_ik(model) || !branches_of(model, base_T_tcp, request, branches, message)) {
    return out;
  }
  const OpwGeometry& g = *model.opw();
  for (int k = 0; k < branches.count; ++k) {
    const OpwBranch& b = branches.branch[static_cast<std::size_t>(k)];
    std::array<std::array<double, 8>, 6> turns{};
    std::array<int, 6> n{};
    bool empty = false;
    for (int i = 0; i < 6; ++i) {
      n[static_cast<std::size_t>(i)] =
          turns_within(g.joint(i, b.theta[static_cast<std::size_t>(i)]), 0.0, model.lower_limits()[i],
                       model.upper_limits()[i], turns[static_cast<std::size_t>(i)]);
      empty = empty || n[static_cast<std::size_t>(i)] == 0;
    }
    if (empty) {
      continue;
    }
    std::array<int, 6> idx{};
    while (true) {
      IkResult r;
      r.q.resize(6);
      for (std::size_t i = 0; i < 6; ++i) {
        r.q[static_cast<int>(i)] = turns[i][static_cast<std::size_t>(idx[i])];
      }
      r.analytic = true;
      r.singularity = b.singularity;
      fill_errors(model, ws, base_T_tcp, r);
      fill_configuration(model, r);
      r.status = b.singularity == Singularity::kNone ? IkStatus::kOk : IkStatus::kNearSingular;
      if (b.singularity != Singularity::kNone) {
        r.message = fmt::format("near a {} singularity", to_string(b.singularity));
      }
      out.push_back(r);
      std::size_t i = 0;
      for (; i < 6; ++i) {
        if (++idx[i] < n[i]) {
          break;
        }
        idx[i] = 0;
      }
      if (i == 6) {
        break;
      }
    }
  }
  if (request.seed) {
    // The nearest the seed first (the largest joint difference), as the seed picks one solution in
    // inverse_kinematics(): [0] is each joint at the turn nearest the seed.
    const JointVector& seed = *request.seed;
    std::stable_sort(out.begin(), out.end(), [&](const IkResult& a, const IkResult& b) {
      return (a.q - seed).cwiseAbs().maxCoeff() < (b.q - seed).cwiseAbs().maxCoeff();
    });
  }
  return out;
}

IkResult inverse_kinematics(const RobotModel& model, Workspace& ws, const Pose& base_T_tcp, const IkRequest& request) {
  IkResult fail;
  if (!base_T_tcp.matrix().allFinite() ||
      (base_T_tcp.linear().transpose() * base_T_tcp.linear() - Matrix3::Identity()).norm() > 1e-6) {
    fail.status = IkStatus::kInvalidInput;
    fail.message = "target pose is not finite or its orientation is not a rotation";
    return fail;
  }
  if (request.seed && (request.seed->size() != model.dof() || !request.seed->allFinite())) {
    fail.status = IkStatus::kInvalidInput;
    fail.message = fmt::format("seed must hold {} finite joint values", model.dof());
    return fail;
  }
  if (!has_analytic_ik(model)) {
    return numerical_ik(model, ws, base_T_tcp, request);
  }
  OpwBranches branches;
  if (!branches_of(model, base_T_tcp, request, branches, fail.message)) {
    fail.status = IkStatus::kUnreachable;
    return fail;
  }
  IkResult best;
  double best_score = HUGE_VAL;
  bool any_fits = false;
  // The configurations on offer, for the message when none is the one asked for; kept as numbers
  // and written only then, so a path of a million poses formats no text.
  std::array<std::pair<ArmConfiguration, KukaConfiguration>, 8> available;
  int available_count = 0;
  for (int k = 0; k < branches.count; ++k) {
    const OpwBranch& b = branches.branch[static_cast<std::size_t>(k)];
    IkResult r;
    bool fits = false;
    if (choose_turns(model, b, request, false, r.q, fits)) {
      fill_configuration(model, r);
      available[static_cast<std::size_t>(available_count++)] = {r.configuration, r.kuka};
    }
    any_fits = any_fits || fits;
    if (!fits || !choose_turns(model, b, request, true, r.q, fits)) {
      continue;
    }
    fill_configuration(model, r);
    if ((request.configuration && r.configuration.cfx != request.configuration->cfx) ||
        (request.kuka_configuration && r.kuka.status != request.kuka_configuration->status)) {
      continue;
    }
    const double score = request.seed ? max_abs_diff(r.q, *request.seed) : r.q.norm();
    if (score < best_score) {
      best_score = score;
      best = r;
      best.singularity = b.singularity;
    }
  }
  if (!any_fits) {
    fail.status = IkStatus::kOutsideJointLimits;
    fail.message = "the pose is reachable, but every solution violates a joint limit";
    return fail;
  }
  if (!std::isfinite(best_score)) {
    fail.status = IkStatus::kConfigurationUnavailable;
    fail.message = unavailable_configuration(request, available.data(), available_count);
    return fail;
  }
  best.analytic = true;
  fill_errors(model, ws, base_T_tcp, best);
  best.status = best.singularity == Singularity::kNone ? IkStatus::kOk : IkStatus::kNearSingular;
  if (best.singularity != Singularity::kNone) {
    best.message = fmt::format("near a {} singularity", to_string(best.singularity));
  }
  return best;
}

}  // namespace deflex
