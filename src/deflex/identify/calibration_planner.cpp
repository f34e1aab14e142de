// Greedy maximin selection of calibration poses and loads from a grid of reachable candidates.
#include "deflex/identify/calibration_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_ranges.hpp"

namespace deflex {
namespace {

struct Candidate {
  Wrench wrench;
  Vector3 load_point;
  // 3 x n, columns scaled by the nominal compliance (m); fixed capacity, so scoring never allocates.
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, kMaxJoints> block;
};

struct CandidatePose {
  JointVector q;
  Pose base_T_tcp;
  std::vector<Candidate> loads;
  bool used = false;
};

double min_eigenvalue(const JointMatrix& G) {
  return Eigen::SelfAdjointEigenSolver<JointMatrix>(G, Eigen::EigenvaluesOnly).eigenvalues()[0];
}

double log_det(const JointMatrix& G) { return Eigen::LDLT<JointMatrix>(G).vectorD().array().abs().log().sum(); }

void check_options(const CalibrationPlanOptions& o) {
  // The ranges of input_ranges.hpp, which the command line applies to its options too (the Python
  // module calls this directly).
  for (int i = 0; i < 3; ++i) {
    for (const double v : {o.region_min_m[i], o.region_max_m[i]}) {
      if (const auto bad = range_violation(v, range::kLengthM)) {
        throw InputError("plan_calibration: region: " + *bad);
      }
    }
  }
  if ((o.region_max_m - o.region_min_m).minCoeff() < 0.0) {
    throw InputError("plan_calibration: the region's minimum must not exceed its maximum on any axis");
  }
  if (!(o.load_n > 0.0) || !std::isfinite(o.load_n)) {
    throw InputError("plan_calibration: the load must be a force > 0 N");
  }
  if (const auto bad = range_violation(o.load_n, range::kForceN)) {
    throw InputError("plan_calibration: the load: " + *bad);
  }
  if (o.poses < 1 || o.poses > 100000 || o.loads_per_pose < 1 || o.loads_per_pose > 30) {
    throw InputError("plan_calibration: poses must be 1..100000 and loads per pose 1..30");
  }
  if (!(o.lever_m >= 0.0) || !std::isfinite(o.lever_m)) {
    throw InputError("plan_calibration: the lever must be >= 0 m");
  }
  if (const auto bad = range_violation(o.lever_m, range::kLengthM)) {
    throw InputError("plan_calibration: the lever: " + *bad);
  }
  if (o.grid_per_axis < 1 || o.grid_per_axis > 50 || o.spin_rad.empty()) {
    throw InputError("plan_calibration: grid per axis must be 1..50 and at least one tool spin given");
  }
  if (std::abs(o.orientation.norm() - 1.0) > 1e-3) {
    throw InputError("plan_calibration: the orientation is not a unit quaternion");
  }
  if (!(o.noise_m > 0.0) || range_violation(o.noise_m, range::kLengthM)) {
    throw InputError("plan_calibration: the noise must be > 0 m and at most 100 m");
  }
}

// The candidate loads at one pose, in the tool's own terms: a force along +-x, +-y, +-z of the base frame,
// applied at the WAP or at the end of a lever along +-x or +-y of the tool; each with its regressor rows scaled
// by the nominal compliance. `base_T_wap` is the WAP at cp.q; ws and block are scratch.
void add_candidate_loads(const RobotModel& model, Workspace& ws, const CalibrationPlanOptions& o,
                         const JointVector& c_nom, const Pose& base_T_wap, Jacobian& block, CandidatePose& cp) {
  std::vector<Vector3> directions;
  for (int a = 0; a < 3; ++a) {
    directions.push_back(Vector3::Unit(a));
    directions.push_back(-Vector3::Unit(a));
  }
  std::vector<Vector3> levers = {Vector3::Zero()};
  if (o.lever_m > 0.0) {
    for (int a = 0; a < 2; ++a) {
      levers.push_back(o.lever_m * base_T_wap.linear().col(a));
      levers.push_back(-o.lever_m * base_T_wap.linear().col(a));
    }
  }
  for (const Vector3& d : directions) {
    for (const Vector3& r : levers) {
      if (r.norm() > 0.0 && r.cross(d).norm() < 1e-6 * r.norm()) {
        continue;  // force along the lever: the same as no lever
      }
      Candidate c;
      c.wrench.head<3>() = o.load_n * d;
      c.wrench.tail<3>() = r.cross(c.wrench.head<3>());
      c.load_point = base_T_wap.translation() + r;
      stiffness_regressor(model, ws, cp.q, c.wrench, block);
      c.block = block.topRows(3) * c_nom.asDiagonal();
      cp.loads.push_back(std::move(c));
    }
  }
}

// Every point of the region's grid with every tool spin: the poses IK reaches inside the joint limits, each with
// its candidate loads. `tried` counts the poses tried.
std::vector<CandidatePose> reachable_candidate_poses(const RobotModel& model, const CalibrationPlanOptions& o,
                                                     int& tried) {
  const int n = model.dof();
  const JointVector& c_nom = model.compliance();
  Workspace ws(model);
  const Eigen::Quaterniond base_q = o.orientation.normalized();
  const int g = o.grid_per_axis;
  std::vector<CandidatePose> poses;
  Jacobian block(6, n);
  for (int ix = 0; ix < g; ++ix) {
    for (int iy = 0; iy < g; ++iy) {
      for (int iz = 0; iz < g; ++iz) {
        const Eigen::Array3d t(g == 1 ? 0.5 : ix / double(g - 1), g == 1 ? 0.5 : iy / double(g - 1),
                               g == 1 ? 0.5 : iz / double(g - 1));
        const Vector3 p = o.region_min_m + ((o.region_max_m - o.region_min_m).array() * t).matrix();
        for (double spin : o.spin_rad) {
          ++tried;
          Pose target = Pose::Identity();
          target.linear() = (base_q * Eigen::AngleAxisd(spin, Vector3::UnitZ())).toRotationMatrix();
          target.translation() = p;
          const IkResult ik = inverse_kinematics(model, ws, target);
          if (ik.status != IkStatus::kOk || !model.within_limits(ik.q)) {
            continue;
          }
          CandidatePose cp;
          cp.q = ik.q;
          forward_kinematics(model, ws, cp.q);
          cp.base_T_tcp = ws.base_T_tcp;
          const Pose base_T_wap = ws.base_T_wap;
          add_candidate_loads(model, ws, o, c_nom, base_T_wap, block, cp);
          poses.push_back(std::move(cp));
        }
      }
    }
  }
  return poses;
}

// The scales of the greedy selection, from the candidates' information.
struct SelectionScales {
  double info_scale = 0.0;  // the largest information one candidate load carries
  // Regulariser for the log-determinant while A^T A is singular: tiny against any real information.
  JointMatrix eps;
  // A joint no candidate can observe would pin the smallest eigenvalue at zero and blind the
  // criterion to the others: it gets a large constant in the selection only.
  JointMatrix unobservable_pad;
};

// The selection's scales for these candidates (n joints).
SelectionScales selection_scales(const std::vector<CandidatePose>& poses, int n) {
  SelectionScales sc;
  for (const auto& cp : poses) {
    for (const auto& c : cp.loads) {
      sc.info_scale = std::max(sc.info_scale, c.block.squaredNorm());
    }
  }
  sc.eps = 1e-9 * sc.info_scale * JointMatrix::Identity(n, n);
  sc.unobservable_pad = JointMatrix::Zero(n, n);
  Eigen::VectorXd all_diag = Eigen::VectorXd::Zero(n);
  for (const auto& cp : poses) {
    for (const auto& c : cp.loads) {
      all_diag += c.block.colwise().squaredNorm().transpose();
    }
  }
  for (int j = 0; j < n; ++j) {
    if (all_diag[j] <= 1e-16 * all_diag.maxCoeff()) {
      sc.unobservable_pad(j, j) = 1e6 * sc.info_scale;
    }
  }
  return sc;
}

// A candidate load (pose and load index) with an upper bound of the smallest eigenvalue it can give.
struct ScoredLoad {
  int pose, load;
  double bound;
};

// The candidate load that most raises the smallest eigenvalue of the information G (or, while every candidate
// leaves it ~0, the log-determinant), among the loads of pose `only_pose`, or of every unused pose when it is
// -1; returns {pose, load} or {-1, -1}.
std::pair<int, int> best_candidate_load(const std::vector<CandidatePose>& poses, const JointMatrix& G,
                                        const SelectionScales& sc, int only_pose) {
  const JointMatrix G0 = G + sc.unobservable_pad;
  const Eigen::SelfAdjointEigenSolver<JointMatrix> es(G0);
  const JointVector v0 = es.eigenvectors().col(0);
  // lambda_min(G0 + B^T B) <= v0^T (G0 + B^T B) v0 = lambda_min(G0) + |B v0|^2: a tight upper
  // bound that lets most candidates be skipped without an eigenvalue solve.
  std::vector<ScoredLoad> items;
  for (int pi = 0; pi < static_cast<int>(poses.size()); ++pi) {
    const CandidatePose& cp = poses[static_cast<std::size_t>(pi)];
    if (only_pose >= 0 ? pi != only_pose : cp.used) {
      continue;
    }
    for (int li = 0; li < static_cast<int>(cp.loads.size()); ++li) {
      const auto& B = cp.loads[static_cast<std::size_t>(li)].block;
      items.push_back({pi, li, es.eigenvalues()[0] + (B * v0).squaredNorm()});
    }
  }
  const auto block_of = [&](const ScoredLoad& it) -> const auto& {
    return poses[static_cast<std::size_t>(it.pose)].loads[static_cast<std::size_t>(it.load)].block;
  };
  // Mirror-image loads score the same up to round-off: of scores within 1e-9 of each other the
  // candidate first in the candidate list wins, whichever order they were scored in, so plans do not
  // depend on the compiler's rounding (which reorders the bounds of a mirror pair).
  int best_p = -1, best_l = -1;
  double best = -std::numeric_limits<double>::infinity();
  auto consider = [&](const ScoredLoad& it, double score) {
    const double tol = 1e-9 * std::abs(best);
    const bool better = best_p < 0 || score > best + tol;
    const bool tie_earlier = !better && score >= best - tol && std::pair(it.pose, it.load) < std::pair(best_p, best_l);
    if (better || tie_earlier) {
      best = better ? score : std::max(best, score);
      best_p = it.pose;
      best_l = it.load;
    }
  };
  std::vector<ScoredLoad> by_bound = items;
  std::stable_sort(by_bound.begin(), by_bound.end(),
                   [](const ScoredLoad& x, const ScoredLoad& y) { return x.bound > y.bound; });
  for (const ScoredLoad& it : by_bound) {
    if (best_p >= 0 && it.bound < best - 1e-9 * std::abs(best)) {
      break;  // no remaining candidate can beat or tie the best
    }
    const auto& B = block_of(it);
    consider(it, min_eigenvalue(G0 + B.transpose() * B));
  }
  // Until the information matrix has full rank every smallest eigenvalue is ~0; then the
  // log-determinant (D-optimality) spreads the information over the missing directions.
  if (!(best > 1e-6 * sc.info_scale)) {
    best_p = -1;
    for (const ScoredLoad& it : items) {
      const auto& B = block_of(it);
      consider(it, log_det(G0 + B.transpose() * B + sc.eps));
    }
  }
  return std::pair<int, int>(best_p, best_l);
}

// The greedy selection: up to `wanted` poses, each the best unused one, with up to loads_per_pose of its loads,
// each the best left there; the chosen loads' information is added to G and their points to `points`.
void choose_calibration_points(std::vector<CandidatePose>& poses, int wanted, int loads_per_pose,
                               const SelectionScales& sc, JointMatrix& G, std::vector<CalibrationPoint>& points) {
  for (int k = 0; k < wanted; ++k) {
    auto [pi, li] = best_candidate_load(poses, G, sc, -1);
    if (pi < 0) {
      break;
    }
    CandidatePose& cp = poses[static_cast<std::size_t>(pi)];
    cp.used = true;
    for (int l = 0; l < loads_per_pose && !cp.loads.empty(); ++l) {
      if (l > 0) {
        li = best_candidate_load(poses, G, sc, pi).second;
      }
      const Candidate& c = cp.loads[static_cast<std::size_t>(li)];
      G += c.block.transpose() * c.block;
      CalibrationPoint pt;
      pt.pose = k + 1;
      pt.q = cp.q;
      pt.base_T_tcp = cp.base_T_tcp;
      pt.wrench_base = c.wrench;
      pt.load_point_base = c.load_point;
      pt.expected_dp_m = c.block.rowwise().sum();  // sum_j c_nom_j * column_j
      points.push_back(pt);
      cp.loads.erase(cp.loads.begin() + li);
    }
  }
}

// Figures of the chosen design (information G) into plan: the smallest singular value, the condition number and
// the predicted relative standard errors. A joint whose column is negligible (no load turns it, or the
// TCP lies on its axis) is unobservable; the others are judged on their own.
void design_figures(const JointMatrix& G, double noise_m, CalibrationPlan& plan) {
  const auto n = static_cast<int>(G.rows());
  const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<JointMatrix>(G, Eigen::EigenvaluesOnly).eigenvalues();
  plan.min_singular_value_m = std::sqrt(std::max(0.0, eig[0]));
  const double max_diag = G.diagonal().maxCoeff();
  std::vector<int> observable;
  for (int j = 0; j < n; ++j) {
    if (G(j, j) > 1e-16 * max_diag) {
      observable.push_back(j);
    }
  }
  const auto no = static_cast<Eigen::Index>(observable.size());
  Eigen::MatrixXd Go(no, no), Gn(no, no);
  for (Eigen::Index a = 0; a < no; ++a) {
    for (Eigen::Index b = 0; b < no; ++b) {
      const int ja = observable[static_cast<std::size_t>(a)], jb = observable[static_cast<std::size_t>(b)];
      Go(a, b) = G(ja, jb);
      Gn(a, b) = G(ja, jb) / std::sqrt(G(ja, ja) * G(jb, jb));
    }
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  plan.condition_number = kInf;
  plan.predicted_relative_std_error.assign(static_cast<std::size_t>(n), kInf);
  if (no > 0) {
    const Eigen::VectorXd en = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Gn, Eigen::EigenvaluesOnly).eigenvalues();
    const bool full_rank = en[0] > 1e-12 * en[no - 1];
    if (full_rank && no == n) {
      plan.condition_number = std::sqrt(en[no - 1] / en[0]);
    }
    if (full_rank) {
      const Eigen::MatrixXd cov = Go.inverse();
      for (Eigen::Index a = 0; a < no; ++a) {
        plan.predicted_relative_std_error[static_cast<std::size_t>(observable[static_cast<std::size_t>(a)])] =
            noise_m * std::sqrt(cov(a, a));
      }
    }
  }
}

// A warning for each joint the plan leaves unobservable or predicts worse than 10% (relative standard error).
void warn_about_weak_joints(double noise_m, CalibrationPlan& plan) {
  for (int j = 0; j < static_cast<int>(plan.predicted_relative_std_error.size()); ++j) {
    const double r = plan.predicted_relative_std_error[static_cast<std::size_t>(j)];
    if (!std::isfinite(r)) {
      plan.warnings.push_back(fmt::format(
          "joint {}: not observable with this plan (no load turns it, its turning never moves the TCP, or it is "
          "confounded with other joints); use a lever (--lever-mm), a TCP off the flange axis, more spins or a "
          "larger region",
          j + 1));
    } else if (r > 0.1) {
      plan.warnings.push_back(fmt::format(
          "joint {}: predicted relative standard error {:.0f}% with {:.0f} um tracker noise; use more poses, a "
          "larger load, a longer lever or a larger region",
          j + 1, 100.0 * r, noise_m * 1e6));
    }
  }
}

// The commonest cause of an infinite condition number: the measured point (the TCP) on the last axis,
// so turning that joint never moves it and no load or lever can show its stiffness.
void warn_about_tcp_on_last_axis(const RobotModel& model, CalibrationPlan& plan) {
  const auto last = static_cast<std::size_t>(model.dof() - 1);
  const Vector3 tcp_in_flange = model.description().flange_T_tcp.translation();
  if (std::isfinite(plan.predicted_relative_std_error[last]) || tcp_in_flange.head<2>().norm() >= 1e-6) return;
  plan.warnings.push_back(fmt::format(
      "the TCP of '{}' lies on axis {} (tool_frame x = y = 0), so joint {} cannot be observed from positions "
      "whatever the loads: measure a point off the axis (a tool_frame with x or y of, say, 60 mm in the robot "
      "file, and that point on the tracker), measure the TCP's rotation too (a 6-DoF probe: drot), or hold joint "
      "{} at a known stiffness (identify --fix-stiffness-Nm-per-rad {}=K, fixed_stiffness_nm_per_rad in Python)",
      model.name(), last + 1, last + 1, last + 1, last + 1));
}

}  // namespace

CalibrationPlan plan_calibration(const RobotModel& model, const CalibrationPlanOptions& o) {
  check_options(o);
  if (!model.has_stiffness()) {
    throw InputError(
        fmt::format("plan_calibration: robot '{}' has no joint stiffness; nominal values (even rough "
                    "ones) are needed to weigh the joints against each other",
                    model.name()));
  }
  const int n = model.dof();
  CalibrationPlan plan;
  std::vector<CandidatePose> poses = reachable_candidate_poses(model, o, plan.candidate_poses);
  plan.reachable_poses = static_cast<int>(poses.size());
  if (poses.empty()) {
    throw InputError(
        fmt::format("plan_calibration: no pose of the region is reachable with the requested tool "
                    "orientation inside the joint limits and away from singularities ({} tried)",
                    plan.candidate_poses));
  }
  int wanted = o.poses;
  if (wanted > plan.reachable_poses) {
    plan.warnings.push_back(
        fmt::format("only {} reachable poses in the region; the plan uses all of them", plan.reachable_poses));
    wanted = plan.reachable_poses;
  }

  const SelectionScales scales = selection_scales(poses, n);
  JointMatrix G = JointMatrix::Zero(n, n);
  choose_calibration_points(poses, wanted, o.loads_per_pose, scales, G, plan.points);
  if (plan.points.empty()) {
    throw InputError("plan_calibration: no load could be chosen (no candidate has a finite score)");
  }
  design_figures(G, o.noise_m, plan);
  warn_about_weak_joints(o.noise_m, plan);
  warn_about_tcp_on_last_axis(model, plan);
  return plan;
}

void write_calibration_plan(const std::string& path, const CalibrationPlan& plan,
                            const std::vector<std::string>& comments) {
  OutputFile out(path, "calibration plan");
  write_calibration_plan(out, plan, comments);
  out.commit();
}

void write_calibration_plan(OutputFile& out, const CalibrationPlan& plan, const std::vector<std::string>& comments) {
  const Eigen::Index n = plan.points.empty() ? 0 : plan.points.front().q.size();
  std::vector<std::string> cols = {"pose"};
  for (Eigen::Index j = 1; j <= n; ++j) {
    cols.push_back(fmt::format("q{}_deg", j));
  }
  for (const char* c :
       {"x_mm", "y_mm", "z_mm", "qw", "qx", "qy", "qz", "fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm", "load_x_mm",
        "load_y_mm", "load_z_mm", "expected_dx_mm", "expected_dy_mm", "expected_dz_mm"}) {
    cols.emplace_back(c);
  }
  CsvWriter w(out, cols);
  for (const auto& c : comments) {
    w.comment(c);
  }
  std::vector<double> row;
  for (const CalibrationPoint& p : plan.points) {
    row.clear();
    row.push_back(p.pose);
    for (Eigen::Index j = 0; j < n; ++j) {
      row.push_back(rad_to_deg(p.q[j]));
    }
    const Vector3 x = p.base_T_tcp.translation() * 1e3;
    const Eigen::Quaterniond q(p.base_T_tcp.linear());
    row.insert(row.end(), {x.x(), x.y(), x.z(), q.w(), q.x(), q.y(), q.z()});
    for (int k = 0; k < 6; ++k) {
      row.push_back(p.wrench_base[k]);
    }
    for (int k = 0; k < 3; ++k) {
      row.push_back(p.load_point_base[k] * 1e3);
    }
    for (int k = 0; k < 3; ++k) {
      row.push_back(p.expected_dp_m[k] * 1e3);
    }
    // Round-off dust (1e-15 deg) would only distract the operator.
    for (double& v : row) {
      if (std::abs(v) < 1e-9) {
        v = 0.0;
      }
    }
    w.row(row);
  }
  w.finish();
}

}  // namespace deflex
