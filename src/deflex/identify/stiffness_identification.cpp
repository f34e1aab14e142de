// Joint stiffness identification: regressor, identifiability checks, robust NNLS, standard errors.
#include "deflex/identify/stiffness_identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <fmt/format.h>

#include "deflex/identify/nonnegative_least_squares.hpp"
#include "deflex/model/errors.hpp"

namespace deflex {

void stiffness_regressor(const RobotModel& model, Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                         Jacobian& block) {
  forward_kinematics(model, ws, q);
  point_jacobian(ws, ws.base_T_wap.translation(), ws.jacobian);
  // Torque each joint feels: the WAP Jacobian's transpose maps the wrench to joint space.
  const JointVector tau = ws.jacobian.transpose() * wrench_base;
  point_jacobian(ws, ws.base_T_tcp.translation(), block);
  for (int j = 0; j < ws.dof; ++j) {
    block.col(j) *= tau[j];
  }
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Wilson-Hilferty approximation of the chi-square quantile with k degrees of freedom at the
// standard normal quantile z; good to a few percent for k >= 1, enough to set robust thresholds.
double chi_square_quantile(int k, double z) {
  const double a = 2.0 / (9.0 * k);
  const double t = 1.0 - a + z * std::sqrt(a);
  return k * t * t * t;
}

std::string where(const StiffnessMeasurement& m, std::size_t i) {
  return m.line > 0 ? fmt::format("measurement {} (line {})", i + 1, m.line) : fmt::format("measurement {}", i + 1);
}

double median(std::vector<double> v) {
  if (v.empty()) {
    return 0.0;
  }
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  double m = *mid;
  if (v.size() % 2 == 0) {
    m = 0.5 * (m + *std::max_element(v.begin(), mid));
  }
  return m;
}

std::string joint_list(const std::vector<int>& joints) {
  std::vector<std::string> s;
  for (int j : joints) {
    s.push_back(std::to_string(j + 1));
  }
  return fmt::format("{}", fmt::join(s, ", "));
}

// The stacked problem, rows already multiplied by sqrt(weight).
struct Stack {
  Eigen::MatrixXd A;                 // rows x dof, all joints
  Eigen::VectorXd b;                 // rows
  std::vector<Eigen::Index> start;   // first row of each measurement
  std::vector<int> rows;             // 3 or 6
  std::vector<double> sqrt_weight;
};

Stack build_stack(const RobotModel& model, const std::vector<StiffnessMeasurement>& data,
                  const IdentificationOptions& opt) {
  const int n = model.dof();
  Stack s;
  s.start.reserve(data.size());
  s.rows.reserve(data.size());
  Eigen::Index total = 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const StiffnessMeasurement& m = data[i];
    if (m.q.size() != n) {
      throw InputError(fmt::format("{}: {} joint values for a {}-joint robot ({})", where(m, i), m.q.size(), n,
                                   model.name()));
    }
    if (!m.q.allFinite() || !m.wrench_base.allFinite() || !m.dp_m.allFinite() ||
        (m.drot_rad && !m.drot_rad->allFinite())) {
      throw InputError(fmt::format("{}: a value is not finite", where(m, i)));
    }
    if (!(m.weight > 0.0) || !std::isfinite(m.weight)) {
      throw InputError(fmt::format("{}: weight {} must be finite and > 0", where(m, i), m.weight));
    }
    s.start.push_back(total);
    s.rows.push_back(m.drot_rad ? 6 : 3);
    total += s.rows.back();
  }
  s.A.resize(total, n);
  s.b.resize(total);
  Workspace ws(model);
  Jacobian block(6, n);
  for (std::size_t i = 0; i < data.size(); ++i) {
    const StiffnessMeasurement& m = data[i];
    stiffness_regressor(model, ws, m.q, m.wrench_base, block);
    const double sw = std::sqrt(m.weight);
    s.sqrt_weight.push_back(sw);
    const Eigen::Index r0 = s.start[i];
    s.A.block(r0, 0, 3, n) = sw * block.topRows(3);
    s.b.segment<3>(r0) = sw * m.dp_m;
    if (m.drot_rad) {
      s.A.block(r0 + 3, 0, 3, n) = (sw * opt.rotation_scale_m) * block.bottomRows(3);
      s.b.segment<3>(r0 + 3) = (sw * opt.rotation_scale_m) * *m.drot_rad;
    }
  }
  return s;
}

// Columns `cols` of A, each divided by scale[j], rows of measurement i multiplied by sqrt(omega_i).
Eigen::MatrixXd scaled_columns(const Stack& s, const std::vector<int>& cols, const Eigen::VectorXd& scale,
                               const std::vector<double>& omega) {
  Eigen::MatrixXd M(s.A.rows(), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t k = 0; k < cols.size(); ++k) {
    M.col(static_cast<Eigen::Index>(k)) = s.A.col(cols[k]) / scale[cols[k]];
  }
  for (std::size_t i = 0; i < s.start.size(); ++i) {
    if (omega[i] != 1.0) {
      M.middleRows(s.start[i], s.rows[i]) *= std::sqrt(omega[i]);
    }
  }
  return M;
}

Eigen::VectorXd weighted_rhs(const Stack& s, const Eigen::VectorXd& b, const std::vector<double>& omega) {
  Eigen::VectorXd y = b;
  for (std::size_t i = 0; i < s.start.size(); ++i) {
    if (omega[i] != 1.0) {
      y.segment(s.start[i], s.rows[i]) *= std::sqrt(omega[i]);
    }
  }
  return y;
}

// Singular values (descending) and right singular vectors of a tall matrix, through its R factor.
Eigen::JacobiSVD<Eigen::MatrixXd> svd_of(const Eigen::MatrixXd& M) {
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(M);
  const Eigen::Index p = M.cols();
  const Eigen::MatrixXd R = qr.matrixQR().topRows(std::min(p, M.rows())).triangularView<Eigen::Upper>();
  return Eigen::JacobiSVD<Eigen::MatrixXd>(R, Eigen::ComputeFullV);
}

}  // namespace

StiffnessEstimate identify_stiffness(const RobotModel& model, const std::vector<StiffnessMeasurement>& data,
                                     const IdentificationOptions& options) {
  const int n = model.dof();
  if (data.empty()) {
    throw InputError("identify_stiffness: no measurements");
  }
  if (!options.fixed_stiffness_nm_per_rad.empty() &&
      static_cast<int>(options.fixed_stiffness_nm_per_rad.size()) != n) {
    throw InputError(fmt::format("identify_stiffness: {} fixed-stiffness entries for a {}-joint robot",
                                 options.fixed_stiffness_nm_per_rad.size(), n));
  }
  if (!(options.rotation_scale_m > 0.0) || !std::isfinite(options.rotation_scale_m)) {
    throw InputError("identify_stiffness: rotation_scale_m must be finite and > 0");
  }
  if (!(options.max_relative_std_error > 0.0) || !std::isfinite(options.max_relative_std_error)) {
    throw InputError("identify_stiffness: max_relative_std_error must be finite and > 0");
  }

  StiffnessEstimate est;
  const auto nz = static_cast<std::size_t>(n);
  est.stiffness_nm_per_rad.assign(nz, kNaN);
  est.std_error_nm_per_rad.assign(nz, kNaN);
  est.compliance_rad_per_nm.assign(nz, kNaN);
  est.compliance_std_error_rad_per_nm.assign(nz, kNaN);
  est.measurements = static_cast<int>(data.size());

  Stack s = build_stack(model, data, options);
  const std::size_t m = data.size();

  // Joints held at a known value: move their contribution to the right-hand side.
  Eigen::VectorXd b = s.b;
  std::vector<int> free_joints;
  for (int j = 0; j < n; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    if (!options.fixed_stiffness_nm_per_rad.empty() && options.fixed_stiffness_nm_per_rad[ju]) {
      const double k = *options.fixed_stiffness_nm_per_rad[ju];
      if (!(k > 0.0) || !std::isfinite(k)) {
        throw InputError(fmt::format("identify_stiffness: fixed stiffness of joint {} must be finite and > 0", j + 1));
      }
      b -= s.A.col(j) / k;
      est.stiffness_nm_per_rad[ju] = k;
      est.std_error_nm_per_rad[ju] = 0.0;
      est.compliance_rad_per_nm[ju] = 1.0 / k;
      est.compliance_std_error_rad_per_nm[ju] = 0.0;
      est.fixed_joints.push_back(j + 1);
    } else {
      free_joints.push_back(j);
    }
  }
  if (free_joints.empty()) {
    throw InputError("identify_stiffness: every joint is fixed; nothing to identify");
  }

  // Identifiability before fitting: a joint the loads never turn (or whose turning never moves the
  // measured point) has a zero column; a group of joints whose columns are collinear can only be
  // identified as a combination. Both are flagged and left out of the fit.
  Eigen::VectorXd col_norm = s.A.colwise().norm().transpose();
  const double max_norm = [&] {
    double v = 0.0;
    for (int j : free_joints) {
      v = std::max(v, col_norm[j]);
    }
    return v;
  }();
  if (!(max_norm > 0.0)) {
    throw InputError("identify_stiffness: the loads excite no joint (every wrench is zero, or only loads the base)");
  }
  std::vector<int> estimated;
  std::vector<int> left_out;
  for (int j : free_joints) {
    if (col_norm[j] < options.min_relative_excitation * max_norm) {
      left_out.push_back(j);
      est.warnings.push_back(fmt::format(
          "joint {}: not excited by the data (no load ever turns it, or its turning never moves the measured "
          "point); its stiffness cannot be identified: add loads with a moment about its axis",
          j + 1));
    } else {
      estimated.push_back(j);
    }
  }
  std::vector<double> omega(m, 1.0);
  while (estimated.size() > 1) {
    const auto svd = svd_of(scaled_columns(s, estimated, col_norm, omega));
    const Eigen::VectorXd sv = svd.singularValues();
    const Eigen::Index last = sv.size() - 1;
    // Fewer equations than joints: the SVD has fewer singular values than columns, and V's trailing
    // columns span a null space the smallest singular value does not show.
    const bool underdetermined = sv.size() < static_cast<Eigen::Index>(estimated.size());
    if (!underdetermined && sv[last] >= options.min_relative_singular_value * sv[0]) {
      break;
    }
    // The joints in the unobservable direction: the smallest singular value's vector or, with fewer
    // equations than joints, every joint with a component in the null space (V's trailing columns).
    const Eigen::MatrixXd null_basis =
        underdetermined ? Eigen::MatrixXd(svd.matrixV().rightCols(svd.matrixV().cols() - sv.size()))
                        : Eigen::MatrixXd(svd.matrixV().col(last));
    std::vector<int> group;
    for (Eigen::Index k = 0; k < null_basis.rows(); ++k) {
      if (null_basis.row(k).norm() > 0.1) {
        group.push_back(estimated[static_cast<std::size_t>(k)]);
      }
    }
    est.warnings.push_back(
        underdetermined
            ? fmt::format("joints {}: {} equations for {} unknown compliances; these joints are not determined by "
                          "the data: add measurements (deflex plan-calibration)",
                          joint_list(group), sv.size(), estimated.size())
            : fmt::format(
                  "joints {}: their effects on the measured displacements are collinear in these data (relative "
                  "singular value {:.1e}); only a combination is observable, so none of them is identified: add "
                  "poses or load directions that separate them (deflex plan-calibration)",
                  joint_list(group), sv[last] / sv[0]));
    for (int j : group) {
      left_out.push_back(j);
      estimated.erase(std::find(estimated.begin(), estimated.end(), j));
    }
  }
  std::sort(left_out.begin(), left_out.end());
  // A joint left out still deflects: with a value from the robot file it is held there, so the
  // others are not biased; without one it is taken as rigid, which the warning says.
  for (int j : left_out) {
    if (model.has_stiffness()) {
      const double k = model.stiffness()[j];
      b -= s.A.col(j) / k;
      est.warnings.push_back(fmt::format("joint {}: held at the robot file's {:.4g} Nm/rad while the others were fitted",
                                         j + 1, k));
    } else {
      est.warnings.push_back(fmt::format(
          "joint {}: taken as rigid while the others were fitted (the robot file gives no stiffness to hold it at)",
          j + 1));
    }
  }
  if (estimated.empty()) {
    throw InputError(fmt::format("identify_stiffness: no joint can be identified from these data: {}",
                                 fmt::join(est.warnings, "; ")));
  }

  // Robust NNLS: Huber IRLS (convex, from the least-squares start), then Tukey's bisquare from the
  // Huber solution with the scale frozen (rejects gross outliers outright). Each measurement is
  // weighted as a whole by its residual norm d_i, which is chi-distributed with k_i = 3 (or 6)
  // degrees of freedom in units of the noise sigma.
  const auto p = static_cast<Eigen::Index>(estimated.size());
  Eigen::VectorXd scaled(p);  // compliance times column norm
  Eigen::Array<bool, Eigen::Dynamic, 1> at_bound;
  std::vector<double> d(m), d_over(m);
  // Per-measurement normal-equation pieces of the scaled system, so a re-weighting iteration costs
  // a matrix-vector product instead of a QR of the tall system; the final solve is done by QR.
  Eigen::MatrixXd gram_parts, rhs_parts;
  if (options.robust) {
    gram_parts.resize(p * p, static_cast<Eigen::Index>(m));
    rhs_parts.resize(p, static_cast<Eigen::Index>(m));
    using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 6, kMaxJoints>;
    using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxJoints, kMaxJoints>;
    Block Ai;
    for (std::size_t i = 0; i < m; ++i) {
      Ai.resize(s.rows[i], p);
      for (Eigen::Index k = 0; k < p; ++k) {
        const int j = estimated[static_cast<std::size_t>(k)];
        Ai.col(k) = s.A.col(j).segment(s.start[i], s.rows[i]) / col_norm[j];
      }
      const Small Gi = Ai.transpose() * Ai;
      gram_parts.col(static_cast<Eigen::Index>(i)) = Eigen::Map<const Eigen::VectorXd>(Gi.data(), p * p);
      rhs_parts.col(static_cast<Eigen::Index>(i)) = Ai.transpose() * b.segment(s.start[i], s.rows[i]);
    }
  }
  auto solve = [&](bool exact) {
    NnlsResult r;
    bool done = false;
    if (!exact) {
      const Eigen::VectorXd w = Eigen::Map<const Eigen::VectorXd>(omega.data(), static_cast<Eigen::Index>(m));
      const Eigen::VectorXd gv = gram_parts * w;
      const Eigen::Map<const Eigen::MatrixXd> G(gv.data(), p, p);
      const Eigen::LLT<Eigen::MatrixXd> llt(G);
      if (llt.info() == Eigen::Success) {
        // min ||R s - y|| with R = L^T, y = L^-1 h has the normal equations G s = h.
        const Eigen::MatrixXd R = llt.matrixU();
        const Eigen::VectorXd y = llt.matrixL().solve(rhs_parts * w);
        r = nonnegative_least_squares(R, y);
        done = true;
      }
    }
    if (!done) {
      const Eigen::MatrixXd M = scaled_columns(s, estimated, col_norm, omega);
      const Eigen::VectorXd y = weighted_rhs(s, b, omega);
      // One QR of the tall system reduces NNLS to a p x p triangular problem with the same solution.
      Eigen::HouseholderQR<Eigen::MatrixXd> qr(M);
      const Eigen::MatrixXd R = qr.matrixQR().topRows(p).triangularView<Eigen::Upper>();
      const Eigen::VectorXd qty = (qr.householderQ().transpose() * y).head(p);
      r = nonnegative_least_squares(R, qty);
    }
    scaled = r.x;
    at_bound = r.at_bound;
    Eigen::VectorXd c_full = Eigen::VectorXd::Zero(n);
    for (Eigen::Index k = 0; k < p; ++k) {
      const int j = estimated[static_cast<std::size_t>(k)];
      c_full[j] = scaled[k] / col_norm[j];
    }
    const Eigen::VectorXd res = b - s.A * c_full;
    for (std::size_t i = 0; i < m; ++i) {
      d[i] = res.segment(s.start[i], s.rows[i]).norm();
    }
    return res;
  };
  auto chi_median = [](int k) { return std::sqrt(chi_square_quantile(k, 0.0)); };
  Eigen::VectorXd res = solve(true);
  if (options.robust) {
    const double rhs_scale = b.norm() / std::sqrt(static_cast<double>(b.size()));
    double sigma = 0.0;
    for (int stage = 0; stage < 2; ++stage) {
      for (int it = 0; it < options.max_robust_iterations; ++it) {
        if (stage == 0) {
          for (std::size_t i = 0; i < m; ++i) {
            d_over[i] = d[i] / chi_median(s.rows[i]);
          }
          sigma = median(d_over);
        }
        if (!(sigma > 1e-12 * rhs_scale)) {
          break;  // an exact fit: nothing to re-weight
        }
        for (std::size_t i = 0; i < m; ++i) {
          const double u = d[i] / sigma;
          if (stage == 0) {
            const double h = std::sqrt(chi_square_quantile(s.rows[i], 1.645));
            omega[i] = u <= h ? 1.0 : h / u;
          } else {
            const double c = 1.42 * std::sqrt(chi_square_quantile(s.rows[i], 3.090));
            const double t = u / c;
            omega[i] = t < 1.0 ? (1.0 - t * t) * (1.0 - t * t) : 0.0;
          }
        }
        const Eigen::VectorXd before = scaled;
        res = solve(false);
        ++est.iterations;
        if ((scaled - before).norm() <= 1e-10 * scaled.norm()) {
          break;
        }
      }
    }
    res = solve(true);
  }

  // Fit figures. The residual covariance: sigma^2 = sum omega r^2 / (sum omega k - p), the usual
  // IRLS approximation that treats the final robust weights as known.
  double wr2 = 0.0, wdof = 0.0, pos2 = 0.0, rot2 = 0.0;
  int kept = 0, kept_rot = 0;
  for (std::size_t i = 0; i < m; ++i) {
    wr2 += omega[i] * d[i] * d[i];
    wdof += omega[i] * s.rows[i];
    if (omega[i] > 0.0) {
      const auto r = res.segment(s.start[i], s.rows[i]) / s.sqrt_weight[i];
      pos2 += r.head<3>().squaredNorm();
      est.residual_max_m = std::max(est.residual_max_m, r.head<3>().norm());
      ++kept;
      if (s.rows[i] == 6) {
        rot2 += r.tail<3>().squaredNorm() / (options.rotation_scale_m * options.rotation_scale_m);
        ++kept_rot;
      }
    } else {
      est.rejected_measurements.push_back(static_cast<int>(i));
    }
  }
  est.robust_weights = omega;
  est.residual_rms_m = kept > 0 ? std::sqrt(pos2 / (3.0 * kept)) : 0.0;
  est.residual_rms_rad = kept_rot > 0 ? std::sqrt(rot2 / (3.0 * kept_rot)) : 0.0;
  std::vector<int> passive;
  for (Eigen::Index k = 0; k < p; ++k) {
    if (!at_bound[k]) {
      passive.push_back(estimated[static_cast<std::size_t>(k)]);
    }
  }
  const double dof_left = wdof - static_cast<double>(passive.size());
  const double sigma2 = dof_left > 0.0 ? wr2 / dof_left : kNaN;
  est.sigma_m = std::sqrt(sigma2);
  if (!(dof_left > 0.0)) {
    est.warnings.push_back("no more data than unknowns: standard errors cannot be estimated");
  }
  {
    const auto svd = svd_of(scaled_columns(s, estimated, col_norm, omega));
    const Eigen::VectorXd sv = svd.singularValues();
    est.condition_number = sv[sv.size() - 1] > 0.0 ? sv[0] / sv[sv.size() - 1] : std::numeric_limits<double>::infinity();
  }
  Eigen::VectorXd var_scaled = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(passive.size()));
  if (!passive.empty()) {
    const Eigen::MatrixXd M = scaled_columns(s, passive, col_norm, omega);
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(M);
    const auto pp = static_cast<Eigen::Index>(passive.size());
    const Eigen::MatrixXd R = qr.matrixQR().topRows(pp).triangularView<Eigen::Upper>();
    // (R^T R)^-1 = R^-1 R^-T: diagonal = squared row norms of R^-1.
    const Eigen::MatrixXd Rinv =
        R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(pp, pp));
    var_scaled = sigma2 * Rinv.rowwise().squaredNorm();
  }
  for (Eigen::Index k = 0; k < p; ++k) {
    const int j = estimated[static_cast<std::size_t>(k)];
    const auto ju = static_cast<std::size_t>(j);
    if (at_bound[k]) {
      est.compliance_rad_per_nm[ju] = 0.0;
      left_out.push_back(j);
      est.warnings.push_back(fmt::format(
          "joint {}: the fit puts its compliance at the c >= 0 bound (the data want it rigid or negative); "
          "its stiffness is not identified",
          j + 1));
      continue;
    }
    const auto pk = static_cast<Eigen::Index>(std::find(passive.begin(), passive.end(), j) - passive.begin());
    const double c = scaled[k] / col_norm[j];
    const double se_c = std::sqrt(var_scaled[pk]) / col_norm[j];
    est.compliance_rad_per_nm[ju] = c;
    est.compliance_std_error_rad_per_nm[ju] = se_c;
    est.stiffness_nm_per_rad[ju] = 1.0 / c;
    est.std_error_nm_per_rad[ju] = se_c / (c * c);  // delta method: dk = -dc / c^2
    const double rel = se_c / c;
    // NaN (no residual degrees of freedom: as many equations as unknowns) counts as unidentified.
    if (!(rel <= options.max_relative_std_error)) {
      left_out.push_back(j);
      est.warnings.push_back(fmt::format(
          "joint {}: poorly identified (relative standard error {:.0f}% > {:.0f}%); the value is shown but should "
          "not be used: add poses or loads that turn this joint",
          j + 1, 100.0 * rel, 100.0 * options.max_relative_std_error));
    }
  }
  std::sort(left_out.begin(), left_out.end());
  for (int j : left_out) {
    est.unidentifiable_joints.push_back(j + 1);
  }
  if (!est.rejected_measurements.empty()) {
    std::vector<std::string> which;
    for (int i : est.rejected_measurements) {
      const auto& mm = data[static_cast<std::size_t>(i)];
      which.push_back(mm.line > 0 ? fmt::format("line {}", mm.line) : fmt::format("#{}", i + 1));
    }
    if (which.size() > 10) {
      which.resize(10);
      which.emplace_back("...");
    }
    est.warnings.push_back(fmt::format("{} of {} measurements rejected as outliers (Tukey weight 0): {}",
                                       est.rejected_measurements.size(), m, fmt::join(which, ", ")));
  }
  return est;
}

}  // namespace deflex
