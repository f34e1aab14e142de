// Analytic IK for ortho-parallel arms with a spherical wrist, and damped least squares otherwise.
#include "deflex/model/inverse_kinematics.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/SVD>
#include <fmt/format.h>

namespace deflex {
namespace {

constexpr double kHalfPi = kPi / 2.0;

bool near(double a, double b, double tol = 1e-9) { return std::abs(a - b) < tol; }
bool is_quarter_turn(double alpha) { return near(std::abs(alpha), kHalfPi); }

int quadrant(double q) { return static_cast<int>(std::floor(q / kHalfPi + 1e-12)); }

Matrix3 rot_z(double a) { return Eigen::AngleAxisd(a, Vector3::UnitZ()).toRotationMatrix(); }
Matrix3 rot_x(double a) { return Eigen::AngleAxisd(a, Vector3::UnitX()).toRotationMatrix(); }

double wrap_pi(double a) {
  a = std::remainder(a, 2.0 * kPi);
  return a;
}

/// Target flange pose in the chain's own frame (base frame and tool removed).
Pose chain_T_flange(const RobotModel& model, const Pose& base_T_tcp) {
  const RobotDescription& d = model.description();
  return d.base_T_chain.inverse() * base_T_tcp * d.flange_T_tcp.inverse();
}

/// One analytic branch before joint limits and 2*pi turns.
struct Branch {
  std::array<double, 6> q{};  // joint values (offsets removed), wrapped to (-pi, pi]
  Singularity singularity = Singularity::kNone;
};

/// Solves the analytic branches. Returns false when the target is out of reach (message set).
bool analytic_branches(const RobotModel& model, const Pose& base_T_tcp, const JointVector* seed, double near_tol,
                       std::vector<Branch>& out, std::string& message) {
  const auto& dh = model.description().dh;
  const Pose target = chain_T_flange(model, base_T_tcp);
  const Matrix3 R06 = target.linear();
  const double d6 = dh[5].d_m;
  const double a6 = dh[5].alpha_rad;
  const Vector3 wc = target.translation() - d6 * (R06 * Vector3(0.0, std::sin(a6), std::cos(a6)));

  const double s1 = std::sin(dh[0].alpha_rad) > 0 ? 1.0 : -1.0;
  const double lateral = -s1 * (dh[1].d_m + dh[2].d_m);
  const double rho2 = wc.x() * wc.x() + wc.y() * wc.y();
  if (rho2 < lateral * lateral - 1e-15) {
    message = fmt::format("wrist centre ({:.4f}, {:.4f}, {:.4f}) m is inside the shoulder offset cylinder", wc.x(),
                          wc.y(), wc.z());
    return false;
  }
  const double h_abs = std::sqrt(std::max(0.0, rho2 - lateral * lateral));
  const double L2 = dh[1].a_m;
  const Eigen::Vector2d v3(dh[2].a_m, -std::sin(dh[2].alpha_rad) * dh[3].d_m);
  const double L3 = v3.norm();
  const double phi3 = std::atan2(v3.y(), v3.x());
  const double s4 = std::sin(dh[3].alpha_rad) > 0 ? 1.0 : -1.0;
  const double s5 = std::sin(dh[4].alpha_rad) > 0 ? 1.0 : -1.0;
  bool any_reach = false;
  for (const double shoulder : {1.0, -1.0}) {
    const double h = shoulder * h_abs;
    const double q1p = std::atan2(wc.y(), wc.x()) - std::atan2(lateral, h);
    const double X1 = h - dh[0].a_m;
    const double Y1 = s1 * (wc.z() - dh[0].d_m);
    const double P2 = X1 * X1 + Y1 * Y1;
    const double cb = (P2 - L2 * L2 - L3 * L3) / (2.0 * L2 * L3);
    if (std::abs(cb) > 1.0 + 1e-12) {
      continue;
    }
    any_reach = true;
    const double cbc = std::clamp(cb, -1.0, 1.0);
    for (const double elbow : {1.0, -1.0}) {
      const double beta = elbow * std::acos(cbc);
      const double q3p = beta - phi3;
      const double q2p = std::atan2(Y1, X1) - std::atan2(L3 * std::sin(beta), L2 + L3 * std::cos(beta));
      const Matrix3 R03 = rot_z(q1p) * rot_x(dh[0].alpha_rad) * rot_z(q2p) * rot_x(dh[1].alpha_rad) * rot_z(q3p) *
                          rot_x(dh[2].alpha_rad);
      const Matrix3 M = R03.transpose() * R06 * rot_x(-a6);
      // |sin q5| from the third column (M(0,2), M(1,2) = s5 sin q5 [cos q4, sin q4]) and cos q5 from
      // M(2,2): atan2 keeps full precision near q5 = 0, where acos(cos q5) would lose half the digits.
      const double c5 = -s4 * s5 * M(2, 2);
      const double sin5_abs = std::hypot(M(0, 2), M(1, 2));
      Singularity sing = Singularity::kNone;
      if (h_abs < near_tol) {
        sing = Singularity::kShoulder;
      } else if (std::abs(std::sin(beta)) < near_tol) {
        sing = Singularity::kElbow;
      } else if (sin5_abs < near_tol) {
        sing = Singularity::kWrist;
      }
      const bool wrist_singular = sin5_abs < 1e-12;
      for (const double wrist : {1.0, -1.0}) {
        const double q5p = wrist * std::atan2(sin5_abs, c5);
        // q4 from the third column; at the singularity only q4 + q6 is fixed: keep q4 at the seed
        // (or zero) and give the rest to q6.
        const double q4p = wrist_singular ? (seed ? (*seed)[3] + dh[3].theta_offset_rad : 0.0)
                                          : std::atan2(wrist * s5 * M(1, 2), wrist * s5 * M(0, 2));
        // q6 from what remains of the rotation once q4 and q5 are taken out: exact whatever the
        // precision of q4 near the singularity.
        const Matrix3 A = rot_z(q4p) * rot_x(dh[3].alpha_rad) * rot_z(q5p) * rot_x(dh[4].alpha_rad);
        const Matrix3 Rz6 = A.transpose() * M;
        const double q6p = std::atan2(Rz6(1, 0), Rz6(0, 0));
        Branch b;
        const std::array<double, 6> qp{q1p, q2p, q3p, q4p, q5p, q6p};
        for (std::size_t i = 0; i < 6; ++i) {
          b.q[i] = wrap_pi(qp[i] - dh[i].theta_offset_rad);
        }
        b.singularity = sing;
        out.push_back(b);
        if (wrist_singular) {
          break;  // both wrist signs give the same pose family
        }
      }
    }
  }
  if (!any_reach) {
    message = fmt::format("wrist centre ({:.4f}, {:.4f}, {:.4f}) m is out of the arm's reach", wc.x(), wc.y(), wc.z());
    return false;
  }
  return true;
}

double max_abs_diff(const JointVector& a, const JointVector& b) { return (a - b).cwiseAbs().maxCoeff(); }

void fill_errors(const RobotModel& model, Workspace& ws, const Pose& target, IkResult& r) {
  forward_kinematics(model, ws, r.q);
  const Displacement e = pose_difference(ws.base_T_tcp, target);
  r.position_error_m = e.head<3>().norm();
  r.orientation_error_rad = e.tail<3>().norm();
}

bool matches(const ArmConfiguration& have, const IkRequest& req) {
  if (!req.configuration) {
    return true;
  }
  const ArmConfiguration& want = *req.configuration;
  if (have.cfx != want.cfx) {
    return false;
  }
  return !req.match_quadrants || (have.cf1 == want.cf1 && have.cf4 == want.cf4 && have.cf6 == want.cf6);
}

IkResult numerical_ik(const RobotModel& model, Workspace& ws, const Pose& target, const IkRequest& req) {
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
  // A few deterministic spread starts: reproducible, and enough for reachable poses in practice.
  for (int k = 1; k <= 6; ++k) {
    JointVector s(n);
    for (int i = 0; i < n; ++i) {
      s[i] = std::sin(1.7 * k + 2.3 * i) * 1.5;
    }
    starts.push_back(s);
  }
  IkResult best;
  best.status = IkStatus::kNotConverged;
  double best_err = HUGE_VAL;
  Jacobian J;
  for (const JointVector& start : starts) {
    JointVector q = start.cwiseMax(model.lower_limits()).cwiseMin(model.upper_limits());
    double lambda = 1e-3;
    double err_norm = HUGE_VAL;
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

bool has_analytic_ik(const RobotModel& model) {
  const RobotDescription& d = model.description();
  if (model.dof() != 6 || !d.dh_convention || *d.dh_convention != DhConvention::kStandard || d.dh.size() != 6) {
    return false;
  }
  const auto& r = d.dh;
  return is_quarter_turn(r[0].alpha_rad) && near(r[1].alpha_rad, 0.0) && is_quarter_turn(r[2].alpha_rad) &&
         is_quarter_turn(r[3].alpha_rad) && is_quarter_turn(r[4].alpha_rad) && near(r[3].a_m, 0.0) &&
         near(r[4].a_m, 0.0) && near(r[4].d_m, 0.0) && near(r[5].a_m, 0.0) && r[1].a_m > 0.0 &&
         std::hypot(r[2].a_m, r[3].d_m) > 0.0;
}

ArmConfiguration arm_configuration(const RobotModel& model, Workspace& ws, const JointVector& q) {
  ArmConfiguration c;
  const int n = model.dof();
  c.cf1 = quadrant(q[0]);
  c.cf4 = n > 3 ? quadrant(q[3]) : 0;
  c.cf6 = n > 5 ? quadrant(q[5]) : 0;
  if (n < 5) {
    return c;
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
  const bool q5_negative = q[4] < 0.0;
  c.cfx = (behind_axis1 ? 4 : 0) + (behind_lower_arm ? 2 : 0) + (q5_negative ? 1 : 0);
  return c;
}

double jacobian_min_singular_value(const RobotModel& model, Workspace& ws, const JointVector& q) {
  Jacobian J;
  jacobian(model, ws, q, EndPoint::kTcp, J);
  Eigen::JacobiSVD<Jacobian> svd(J);
  return svd.singularValues().minCoeff();
}

namespace {

/// Every 2*pi turn of every branch that fits the joint limits, each checked by FK.
std::vector<IkResult> solutions_of_branches(const RobotModel& model, Workspace& ws, const Pose& base_T_tcp,
                                            const std::vector<Branch>& branches) {
  std::vector<IkResult> out;
  const JointVector& lo = model.lower_limits();
  const JointVector& hi = model.upper_limits();
  for (const Branch& b : branches) {
    // Every 2*pi turn of every joint that fits its limits.
    std::array<std::vector<double>, 6> options;
    for (int i = 0; i < 6; ++i) {
      for (int k = -2; k <= 2; ++k) {
        const double v = b.q[static_cast<std::size_t>(i)] + 2.0 * kPi * k;
        if (v >= lo[i] - 1e-9 && v <= hi[i] + 1e-9) {
          options[static_cast<std::size_t>(i)].push_back(std::clamp(v, lo[i], hi[i]));
        }
      }
    }
    std::array<std::size_t, 6> idx{};
    while (true) {
      bool empty = false;
      for (const auto& o : options) {
        empty = empty || o.empty();
      }
      if (empty) {
        break;
      }
      IkResult r;
      r.q.resize(6);
      for (std::size_t i = 0; i < 6; ++i) {
        r.q[static_cast<int>(i)] = options[i][idx[i]];
      }
      r.analytic = true;
      r.singularity = b.singularity;
      fill_errors(model, ws, base_T_tcp, r);
      // FK is the judge: a branch that does not reproduce the target is dropped.
      if (r.position_error_m < 1e-8 && r.orientation_error_rad < 1e-8) {
        r.configuration = arm_configuration(model, ws, r.q);
        r.status = b.singularity == Singularity::kNone ? IkStatus::kOk : IkStatus::kNearSingular;
        if (b.singularity != Singularity::kNone) {
          r.message = fmt::format("near a {} singularity", to_string(b.singularity));
        }
        out.push_back(r);
      }
      std::size_t i = 0;
      for (; i < 6; ++i) {
        if (++idx[i] < options[i].size()) {
          break;
        }
        idx[i] = 0;
      }
      if (i == 6) {
        break;
      }
    }
  }
  return out;
}

}  // namespace

std::vector<IkResult> all_ik_solutions(const RobotModel& model, Workspace& ws, const Pose& base_T_tcp,
                                       const IkRequest& request) {
  std::vector<Branch> branches;
  std::string message;
  const JointVector* seed = request.seed ? &*request.seed : nullptr;
  if (!has_analytic_ik(model) ||
      !analytic_branches(model, base_T_tcp, seed, request.near_singular_threshold, branches, message)) {
    return {};
  }
  return solutions_of_branches(model, ws, base_T_tcp, branches);
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
  std::vector<Branch> branches;
  std::string message;
  const JointVector* seed = request.seed ? &*request.seed : nullptr;
  if (!analytic_branches(model, base_T_tcp, seed, request.near_singular_threshold, branches, message)) {
    fail.status = IkStatus::kUnreachable;
    fail.message = message;
    return fail;
  }
  const std::vector<IkResult> all = solutions_of_branches(model, ws, base_T_tcp, branches);
  if (all.empty()) {
    fail.status = IkStatus::kOutsideJointLimits;
    fail.message = "the pose is reachable, but every solution violates a joint limit";
    return fail;
  }
  const IkResult* best = nullptr;
  double best_score = HUGE_VAL;
  for (const IkResult& r : all) {
    if (!matches(r.configuration, request)) {
      continue;
    }
    const double score = request.seed ? max_abs_diff(r.q, *request.seed) : r.q.norm();
    if (score < best_score) {
      best_score = score;
      best = &r;
    }
  }
  if (best == nullptr) {
    std::string have;
    for (const IkResult& r : all) {
      have += fmt::format(" [{},{},{},{}]", r.configuration.cf1, r.configuration.cf4, r.configuration.cf6,
                          r.configuration.cfx);
    }
    fail.status = IkStatus::kConfigurationUnavailable;
    const ArmConfiguration& w = *request.configuration;
    fail.message = fmt::format("no solution with configuration [{},{},{},{}]; available [cf1,cf4,cf6,cfx]:{}", w.cf1,
                               w.cf4, w.cf6, w.cfx, have);
    return fail;
  }
  return *best;
}

}  // namespace deflex
