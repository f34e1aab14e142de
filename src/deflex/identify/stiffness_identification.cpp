// Joint stiffness identification: regressor, identifiability checks, robust NNLS, standard errors.
#include "deflex/identify/stiffness_identification.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "deflex/identify/detail/nonnegative_least_squares.hpp"
#include "deflex/identify/detail/spill_file.hpp"
#include "deflex/model/linear_algebra.hpp"
#include "deflex/text/errors.hpp"

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

// The median of v, which it reorders (the caller's scratch: no copy of a million values).
double median_in_place(std::vector<double>& v) {
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

}  // namespace

// Not in the anonymous namespace: StiffnessIdentifier::RowStoreHolder (declared in the header) holds one.
namespace identify_detail {

// The stacked problem in compact form: per measurement its 3 (or 6) rows [A_i | b_i], already
// multiplied by sqrt(weight) (rotation rows also by rotation_scale_m), in chunks of 64k rows so that
// growing never copies what is stored (a doubling vector would hold up to three times the data at
// its peak). That is what the robust re-weighting needs: each measurement's residual against every
// new estimate; recomputing the regressor instead (FK and two Jacobians) would cost about 0.3 us a
// measurement an iteration. 8 (dof + 1) bytes a row: 168 bytes for a 6-joint position measurement.
// Chunks beyond IdentificationOptions::rows_in_memory_bytes go to an unlinked scratch file and are
// read back a chunk at a time on every pass: the same doubles in the same order, so the results are
// bit for bit those of an all-in-memory store, with memory bounded by the budget (plus two chunks)
// and the per-measurement scalars the re-weighting keeps (37 bytes: weights, residual norms, lines).
class RowStore {
 public:
  RowStore(int dof, std::size_t memory_bytes) : width_(dof + 1), memory_budget_(memory_bytes) {}
  // Space for `rows` contiguous rows of the next measurement.
  double* append(int rows) {
    const std::size_t need = static_cast<std::size_t>(rows) * static_cast<std::size_t>(width_);
    if (chunks_.empty() || chunks_.back().values.size() + need > chunk_capacity()) {
      if (!chunks_.empty()) {
        retire(chunks_.back());
      }
      chunks_.emplace_back();
      chunks_.back().values.reserve(chunk_capacity());
    }
    std::vector<double>& c = chunks_.back().values;
    const std::size_t at = c.size();
    c.resize(at + need);
    rows_.push_back(static_cast<std::uint8_t>(rows));
    total_rows_ += rows;
    return c.data() + at;
  }
  // f(i, rows, block): block is rows x (dof + 1), row-major, A_i then b_i in the last column.
  template <typename F>
  void for_each(F&& f) const {
    std::size_t i = 0;
    for (const Chunk& c : chunks_) {
      const double* data = c.on_disk() ? load(c) : c.values.data();
      for (std::size_t at = 0; at < c.count(); ++i) {
        const int rows = rows_[i];
        f(i, rows, data + at);
        at += static_cast<std::size_t>(rows * width_);
      }
    }
  }
  template <typename F>
  void for_each_mutable(F&& f) {
    std::size_t i = 0;
    for (Chunk& c : chunks_) {
      double* data = c.on_disk() ? load(c) : c.values.data();
      for (std::size_t at = 0; at < c.count(); ++i) {
        const int rows = rows_[i];
        f(i, rows, data + at);
        at += static_cast<std::size_t>(rows * width_);
      }
      if (c.on_disk()) {
        spill_.write_at(static_cast<std::uint64_t>(c.offset), data, c.size);
      }
    }
  }
  [[nodiscard]] std::size_t size() const { return rows_.size(); }
  [[nodiscard]] int rows(std::size_t i) const { return rows_[i]; }
  [[nodiscard]] Eigen::Index total_rows() const { return total_rows_; }
  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] std::uint64_t bytes_on_disk() const { return spill_.bytes(); }

 private:
  struct Chunk {
    std::vector<double> values;  // empty once on disk
    std::size_t size = 0;        // doubles, once on disk
    std::int64_t offset = -1;    // in the scratch file, or -1
    [[nodiscard]] bool on_disk() const { return offset >= 0; }
    [[nodiscard]] std::size_t count() const { return on_disk() ? size : values.size(); }  // doubles held
  };
  static constexpr std::size_t kChunkRows = 65536;
  [[nodiscard]] std::size_t chunk_capacity() const { return kChunkRows * static_cast<std::size_t>(width_); }
  // A chunk is full: keep it while the budget lasts, else write it out and free it.
  void retire(Chunk& c) {
    const std::size_t bytes = c.values.size() * sizeof(double);
    if (in_memory_ + bytes <= memory_budget_) {
      in_memory_ += bytes;
      return;
    }
    c.size = c.values.size();
    c.offset = static_cast<std::int64_t>(spill_.append(c.values.data(), c.size));
    std::vector<double>().swap(c.values);
  }
  double* load(const Chunk& c) const {
    buffer_.resize(c.size);
    spill_.read_at(static_cast<std::uint64_t>(c.offset), buffer_.data(), c.size);
    return buffer_.data();
  }

  int width_;
  std::size_t memory_budget_;
  std::size_t in_memory_ = 0;
  std::vector<Chunk> chunks_;
  std::vector<std::uint8_t> rows_;
  Eigen::Index total_rows_ = 0;
  SpillFile spill_{"identification rows"};
  mutable std::vector<double> buffer_;  // one chunk read back from the scratch file
};

}  // namespace identify_detail

namespace {

using identify_detail::RowStore;

using RowBlock = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

// R (p x p, upper) and Q^T y (p) of the tall system whose rows are measurement i's rows, columns
// `cols` of A divided by scale[col], and b, all multiplied by sqrt(omega_i): Householder QR of the
// rows a slab at a time, each slab stacked under the R found so far (the same R, up to the signs of
// its rows, as one QR of the whole tall matrix, without holding it).
struct Triangular {
  Eigen::MatrixXd R;  // p x p, zero below row `rows`
  Eigen::VectorXd qty;
  Eigen::Index rows = 0;  // min(equations, p): fewer equations than unknowns leave R short
};
Triangular blocked_qr(const RowStore& s, const std::vector<int>& cols, const Eigen::VectorXd& scale,
                      const std::vector<double>& omega) {
  const auto p = static_cast<Eigen::Index>(cols.size());
  const Eigen::Index w = p + 1;
  constexpr Eigen::Index kSlab = 512;
  Eigen::MatrixXd buf(w + kSlab, w);
  Eigen::Index top = 0;   // rows of R so far (at most w)
  Eigen::Index fill = 0;  // rows in the buffer
  const Eigen::Index bcol = s.width() - 1;
  const auto reduce = [&]() {
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(buf.topRows(fill));
    top = std::min(fill, w);
    buf.topRows(top) = qr.matrixQR().topRows(top).triangularView<Eigen::Upper>();
    fill = top;
  };
  s.for_each([&](std::size_t i, int rows, const double* block) {
    const RowBlock B(block, rows, s.width());
    const double sw = std::sqrt(omega[i]);
    for (int r = 0; r < rows; ++r) {
      for (Eigen::Index k = 0; k < p; ++k) {
        const int j = cols[static_cast<std::size_t>(k)];
        buf(fill, k) = sw * B(r, j) / scale[j];
      }
      buf(fill, p) = sw * B(r, bcol);
      ++fill;
    }
    if (fill + 6 > buf.rows()) {
      reduce();
    }
  });
  reduce();
  Triangular t;
  t.R = Eigen::MatrixXd::Zero(p, p);
  t.qty = Eigen::VectorXd::Zero(p);
  const Eigen::Index k = std::min(top, p);
  t.R.topRows(k) = buf.block(0, 0, k, p).triangularView<Eigen::Upper>();
  t.qty.head(k) = buf.block(0, p, k, 1);
  t.rows = k;
  return t;
}

// Singular values (descending) and right singular vectors of the scaled, weighted columns `cols`.
Svd svd_of(const RowStore& s, const std::vector<int>& cols, const Eigen::VectorXd& scale,
           const std::vector<double>& omega) {
  const Triangular t = blocked_qr(s, cols, scale, omega);
  return Svd(t.R.topRows(t.rows));
}

// The estimate before anything is known: every joint's values NaN, the measurement count set.
StiffnessEstimate estimate_without_values(int n, std::size_t measurements) {
  StiffnessEstimate est;
  const auto nz = static_cast<std::size_t>(n);
  est.stiffness_nm_per_rad.assign(nz, kNaN);
  est.std_error_nm_per_rad.assign(nz, kNaN);
  est.compliance_rad_per_nm.assign(nz, kNaN);
  est.compliance_std_error_rad_per_nm.assign(nz, kNaN);
  est.measurements = static_cast<int>(measurements);
  return est;
}

// b -= A.col(j) * c for a joint whose compliance c is known (in place: b is the last column).
void move_known_compliance_to_rhs(RowStore& s, int j, double c) {
  const int width = s.width();
  const int n = width - 1;
  s.for_each_mutable([&](std::size_t, int rows, double* block) {
    for (int r = 0; r < rows; ++r) {
      block[r * width + n] -= block[r * width + j] * c;
    }
  });
}

// Joints held at a known value: their contribution moves to the right-hand side and their given values into
// the estimate. Returns the joints left to identify.
std::vector<int> hold_fixed_joints(RowStore& s, const IdentificationOptions& options, StiffnessEstimate& est) {
  const int n = s.width() - 1;
  std::vector<int> free_joints;
  for (int j = 0; j < n; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    if (!options.fixed_stiffness_nm_per_rad.empty() && options.fixed_stiffness_nm_per_rad[ju]) {
      const double k = *options.fixed_stiffness_nm_per_rad[ju];
      if (!(k > 0.0) || !std::isfinite(k)) {
        throw InputError(fmt::format("identify_stiffness: fixed stiffness of joint {} must be finite and > 0", j + 1));
      }
      move_known_compliance_to_rhs(s, j, 1.0 / k);
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
  return free_joints;
}

// The norm of each regressor column over all stored rows (weighted, as stored).
Eigen::VectorXd regressor_column_norms(const RowStore& s) {
  const int width = s.width();
  const int n = width - 1;
  Eigen::VectorXd col_norm = Eigen::VectorXd::Zero(n);
  s.for_each([&](std::size_t, int rows, const double* block) {
    const RowBlock B(block, rows, width);
    col_norm += B.leftCols(n).colwise().squaredNorm().transpose();
  });
  return col_norm.cwiseSqrt();
}

// Identifiability before fitting, first check: a free joint the loads never turn (or whose turning never moves
// the measured point) has a (near) zero column; it joins left_out with a warning. Returns the excited joints.
std::vector<int> excited_joints(const Eigen::VectorXd& col_norm, const std::vector<int>& free_joints,
                                const IdentificationOptions& options, std::vector<int>& left_out,
                                std::vector<std::string>& warnings) {
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
  for (int j : free_joints) {
    if (col_norm[j] < options.min_relative_excitation * max_norm) {
      left_out.push_back(j);
      warnings.push_back(fmt::format(
          "joint {}: not excited by the data (no load ever turns it, or its turning never moves the measured "
          "point); its stiffness cannot be identified: add loads with a moment about its axis",
          j + 1));
    } else {
      estimated.push_back(j);
    }
  }
  return estimated;
}

// Identifiability before fitting, second check: a group of joints whose scaled columns are collinear (or that
// fewer equations than unknowns leave undetermined) can only be identified as a combination; each such group
// moves from `estimated` to left_out with a warning, until the rest are well conditioned.
void drop_collinear_joint_groups(const RowStore& s, const Eigen::VectorXd& col_norm, const std::vector<double>& omega,
                                 double min_relative_singular_value, std::vector<int>& estimated,
                                 std::vector<int>& left_out, std::vector<std::string>& warnings) {
  while (estimated.size() > 1) {
    const auto svd = svd_of(s, estimated, col_norm, omega);
    const Eigen::VectorXd& sv = svd.values();
    const Eigen::Index last = sv.size() - 1;
    // Fewer equations than joints: the SVD has fewer singular values than columns, and V's trailing
    // columns span a null space the smallest singular value does not show.
    const bool underdetermined = sv.size() < static_cast<Eigen::Index>(estimated.size());
    if (!underdetermined && sv[last] >= min_relative_singular_value * sv[0]) {
      break;
    }
    // The joints in the unobservable direction: the smallest singular value's vector or, with fewer
    // equations than joints, every joint with a component in the null space (V's trailing columns).
    const Eigen::MatrixXd null_basis =
        underdetermined ? Eigen::MatrixXd(svd.right_vectors().rightCols(svd.right_vectors().cols() - sv.size()))
                        : Eigen::MatrixXd(svd.right_vectors().col(last));
    std::vector<int> group;
    for (Eigen::Index k = 0; k < null_basis.rows(); ++k) {
      if (null_basis.row(k).norm() > 0.1) {
        group.push_back(estimated[static_cast<std::size_t>(k)]);
      }
    }
    warnings.push_back(
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
}

// A joint left out still deflects: with a value from the robot file it is held there, so the
// others are not biased; without one it is taken as rigid, which the warning says. Sorts left_out.
void hold_left_out_joints(RowStore& s, const RobotModel& model, std::vector<int>& left_out,
                          std::vector<std::string>& warnings) {
  std::sort(left_out.begin(), left_out.end());
  for (int j : left_out) {
    if (model.has_stiffness()) {
      const double k = model.stiffness()[j];
      move_known_compliance_to_rhs(s, j, 1.0 / k);
      warnings.push_back(
          fmt::format("joint {}: not identified (NaN in the estimate); the others were fitted "
                      "with it held at the robot file's {:.4g} Nm/rad",
                      j + 1, k));
    } else {
      warnings.push_back(fmt::format(
          "joint {}: not identified (NaN in the estimate); the others were fitted with it taken as rigid (the robot "
          "file gives no stiffness to hold it at)",
          j + 1));
    }
  }
}

// The scaled normal equations a re-weighting iteration sums, and one measurement's scaled rows: fixed capacity,
// so the pass over the stored rows does not allocate.
using GramMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxJoints, kMaxJoints>;
using GramVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxJoints, 1>;
using ScaledRows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 6, kMaxJoints>;

// The current fit of the estimated joints.
struct WeightedFit {
  Eigen::VectorXd scaled;                          // compliance times column norm, per estimated joint
  Eigen::Array<bool, Eigen::Dynamic, 1> at_bound;  // per estimated joint: held at c = 0 by the constraint
  Eigen::VectorXd c_full;                          // compliance per joint, 0 where not estimated
  std::vector<double> d;                           // per measurement: d_i = |b_i - A_i c| over its stored rows
};

// One re-weighting iteration's NNLS by the normal equations G s = h, G = sum omega_i A_i^T A_i and
// h = sum omega_i A_i^T b_i over the compact rows: one pass over the stored rows instead of a QR of the tall
// system. False (r untouched) when G is not positive definite.
bool nnls_by_normal_equations(const RowStore& s, const std::vector<int>& estimated, const Eigen::VectorXd& col_norm,
                              const std::vector<double>& omega, NnlsResult& r) {
  const auto p = static_cast<Eigen::Index>(estimated.size());
  const int width = s.width();
  const int n = width - 1;
  GramMatrix G = GramMatrix::Zero(p, p);
  GramVector h = GramVector::Zero(p);
  ScaledRows Ai;
  s.for_each([&](std::size_t i, int rows, const double* block) {
    if (omega[i] == 0.0) {
      return;
    }
    const RowBlock B(block, rows, width);
    Ai.resize(rows, p);
    for (Eigen::Index k = 0; k < p; ++k) {
      const int j = estimated[static_cast<std::size_t>(k)];
      Ai.col(k) = B.col(j) / col_norm[j];
    }
    G.noalias() += omega[i] * (Ai.transpose() * Ai);
    h.noalias() += omega[i] * (Ai.transpose() * B.col(n));
  });
  const Eigen::LLT<Eigen::MatrixXd> llt{Eigen::MatrixXd(G)};
  if (llt.info() != Eigen::Success) {
    return false;
  }
  // min ||R s - y|| with R = L^T, y = L^-1 h has the normal equations G s = h.
  const Eigen::MatrixXd R = llt.matrixU();
  const Eigen::VectorXd y = llt.matrixL().solve(Eigen::VectorXd(h));
  r = nonnegative_least_squares(R, y);
  return true;
}

// Fits the estimated joints' compliances (c >= 0) to the rows weighted by omega, by QR when `exact` (or when the
// normal equations fail), else by the normal equations; then each measurement's residual norm d_i.
void fit_weighted_nnls(const RowStore& s, const std::vector<int>& estimated, const Eigen::VectorXd& col_norm,
                       const std::vector<double>& omega, bool exact, WeightedFit& fit) {
  NnlsResult r;
  if (exact || !nnls_by_normal_equations(s, estimated, col_norm, omega, r)) {
    // One QR of the tall system reduces NNLS to a p x p triangular problem with the same solution.
    const Triangular t = blocked_qr(s, estimated, col_norm, omega);
    r = nonnegative_least_squares(t.R, t.qty);
  }
  fit.scaled = r.x;
  fit.at_bound = r.at_bound;
  fit.c_full.setZero();
  for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(estimated.size()); ++k) {
    const int j = estimated[static_cast<std::size_t>(k)];
    fit.c_full[j] = fit.scaled[k] / col_norm[j];
  }
  const int width = s.width();
  const int n = width - 1;
  s.for_each([&](std::size_t i, int rows, const double* block) {
    const RowBlock B(block, rows, width);
    fit.d[i] = (B.col(n) - B.leftCols(n) * fit.c_full).norm();
  });
}

// The robust weight of a measurement whose residual norm is u noise sigmas, with k = rows degrees of freedom:
// stage 0 Huber's (full weight up to the chi quantile at z = 1.645), stage 1 Tukey's bisquare (zero beyond 1.42
// times the chi quantile at z = 3.090).
double irls_measurement_weight(int stage, int rows, double u) {
  if (stage == 0) {
    const double h = std::sqrt(chi_square_quantile(rows, 1.645));
    return u <= h ? 1.0 : h / u;
  }
  const double c = 1.42 * std::sqrt(chi_square_quantile(rows, 3.090));
  const double t = u / c;
  return t < 1.0 ? (1.0 - t * t) * (1.0 - t * t) : 0.0;
}

// Robust NNLS: Huber IRLS (convex, from the least-squares start), then Tukey's bisquare from the
// Huber solution with the scale frozen (rejects gross outliers outright). Each measurement is
// weighted as a whole by its residual norm d_i, which is chi-distributed with k_i = 3 (or 6)
// degrees of freedom in units of the noise sigma. The first and the final solve are by QR; omega ends as the
// final weights, `iterations` counts the re-weightings.
WeightedFit fit_robustly(const RowStore& s, const std::vector<int>& estimated, const Eigen::VectorXd& col_norm,
                         const IdentificationOptions& options, std::vector<double>& omega, int& iterations) {
  const std::size_t m = s.size();
  const int width = s.width();
  const int n = width - 1;
  WeightedFit fit;
  fit.c_full = Eigen::VectorXd::Zero(n);
  fit.d.assign(m, 0.0);
  const auto chi_median = [](int k) { return std::sqrt(chi_square_quantile(k, 0.0)); };
  fit_weighted_nnls(s, estimated, col_norm, omega, true, fit);
  if (!options.robust) {
    return fit;
  }
  double b2 = 0.0;
  s.for_each(
      [&](std::size_t, int rows, const double* block) { b2 += RowBlock(block, rows, width).col(n).squaredNorm(); });
  const double rhs_scale = std::sqrt(b2 / static_cast<double>(s.total_rows()));
  std::vector<double> d_over(m);
  double sigma = 0.0;
  for (int stage = 0; stage < 2; ++stage) {
    for (int it = 0; it < options.max_robust_iterations; ++it) {
      if (stage == 0) {
        for (std::size_t i = 0; i < m; ++i) {
          d_over[i] = fit.d[i] / chi_median(s.rows(i));
        }
        sigma = median_in_place(d_over);
      }
      if (!(sigma > 1e-12 * rhs_scale)) {
        break;  // an exact fit: nothing to re-weight
      }
      for (std::size_t i = 0; i < m; ++i) {
        omega[i] = irls_measurement_weight(stage, s.rows(i), fit.d[i] / sigma);
      }
      const Eigen::VectorXd before = fit.scaled;
      fit_weighted_nnls(s, estimated, col_norm, omega, false, fit);
      ++iterations;
      if ((fit.scaled - before).norm() <= 1e-10 * fit.scaled.norm()) {
        break;
      }
    }
  }
  fit_weighted_nnls(s, estimated, col_norm, omega, true, fit);
  return fit;
}

// What the noise estimate sums over every measurement: sum omega_i d_i^2 and sum omega_i k_i.
struct WeightedResidualSums {
  double wr2 = 0.0;
  double wdof = 0.0;
};

// Into est, the figures of the measurements kept (position residual RMS and largest norm, orientation RMS, in
// the measured units) and the measurements rejected (weight 0) with their lines; returns the weighted sums.
WeightedResidualSums summarise_residuals(const RowStore& s, const WeightedFit& fit, const std::vector<double>& omega,
                                         const std::vector<double>& sqrt_weight, const std::vector<int>& lines,
                                         double rotation_scale_m, StiffnessEstimate& est) {
  const int width = s.width();
  const int n = width - 1;
  WeightedResidualSums sums;
  double pos2 = 0.0, rot2 = 0.0;
  int kept = 0, kept_rot = 0;
  s.for_each([&](std::size_t i, int rows, const double* block) {
    sums.wr2 += omega[i] * fit.d[i] * fit.d[i];
    sums.wdof += omega[i] * rows;
    if (omega[i] > 0.0) {
      const RowBlock B(block, rows, width);
      const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1> r =
          (B.col(n) - B.leftCols(n) * fit.c_full) / sqrt_weight[i];
      pos2 += r.head<3>().squaredNorm();
      est.residual_max_m = std::max(est.residual_max_m, r.head<3>().norm());
      ++kept;
      if (rows == 6) {
        rot2 += r.tail<3>().squaredNorm() / (rotation_scale_m * rotation_scale_m);
        ++kept_rot;
      }
    } else {
      est.rejected_measurements.push_back(static_cast<int>(i));
      est.rejected_lines.push_back(lines[i]);
    }
  });
  est.residual_rms_m = kept > 0 ? std::sqrt(pos2 / (3.0 * kept)) : 0.0;
  est.residual_rms_rad = kept_rot > 0 ? std::sqrt(rot2 / (3.0 * kept_rot)) : 0.0;
  return sums;
}

// The estimated joints the fit leaves off the c >= 0 bound (the passive set of the NNLS).
std::vector<int> joints_off_bound(const std::vector<int>& estimated,
                                  const Eigen::Array<bool, Eigen::Dynamic, 1>& at_bound) {
  std::vector<int> passive;
  for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(estimated.size()); ++k) {
    if (!at_bound[k]) {
      passive.push_back(estimated[static_cast<std::size_t>(k)]);
    }
  }
  return passive;
}

// The residual variance per component, sigma^2 = sum omega r^2 / (sum omega k - p), the usual IRLS
// approximation that treats the final robust weights as known; NaN, with a warning, when no degrees of freedom
// are left. Sets est.sigma_m.
double residual_variance(const WeightedResidualSums& sums, std::size_t passive_joints, StiffnessEstimate& est) {
  const double dof_left = sums.wdof - static_cast<double>(passive_joints);
  const double sigma2 = dof_left > 0.0 ? sums.wr2 / dof_left : kNaN;
  est.sigma_m = std::sqrt(sigma2);
  if (!(dof_left > 0.0)) {
    est.warnings.push_back("no more data than unknowns: standard errors cannot be estimated");
  }
  return sigma2;
}

// Condition number of the weighted regressor of the estimated joints, columns scaled to unit norm.
double scaled_condition_number(const RowStore& s, const std::vector<int>& estimated, const Eigen::VectorXd& col_norm,
                               const std::vector<double>& omega) {
  const auto svd = svd_of(s, estimated, col_norm, omega);
  const Eigen::VectorXd& sv = svd.values();
  return sv[sv.size() - 1] > 0.0 ? sv[0] / sv[sv.size() - 1] : std::numeric_limits<double>::infinity();
}

// Variance of each scaled compliance of the joints off the bound: sigma^2 times the diagonal of (R^T R)^-1.
Eigen::VectorXd scaled_compliance_variances(const RowStore& s, const std::vector<int>& passive,
                                            const Eigen::VectorXd& col_norm, const std::vector<double>& omega,
                                            double sigma2) {
  Eigen::VectorXd var_scaled = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(passive.size()));
  if (!passive.empty()) {
    const auto pp = static_cast<Eigen::Index>(passive.size());
    const Eigen::MatrixXd R = blocked_qr(s, passive, col_norm, omega).R;
    // (R^T R)^-1 = R^-1 R^-T: diagonal = squared row norms of R^-1.
    const Eigen::MatrixXd Rinv = R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(pp, pp));
    var_scaled = sigma2 * Rinv.rowwise().squaredNorm();
  }
  return var_scaled;
}

// Each estimated joint's compliance, stiffness and their standard errors into est. A joint the fit holds at the
// c >= 0 bound, or whose relative standard error exceeds the limit, joins left_out with a warning.
void report_estimated_joints(const std::vector<int>& estimated, const WeightedFit& fit, const std::vector<int>& passive,
                             const Eigen::VectorXd& var_scaled, const Eigen::VectorXd& col_norm,
                             double max_relative_std_error, std::vector<int>& left_out, StiffnessEstimate& est) {
  for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(estimated.size()); ++k) {
    const int j = estimated[static_cast<std::size_t>(k)];
    const auto ju = static_cast<std::size_t>(j);
    if (fit.at_bound[k]) {
      est.compliance_rad_per_nm[ju] = 0.0;
      left_out.push_back(j);
      est.warnings.push_back(
          fmt::format("joint {}: the fit puts its compliance at the c >= 0 bound (the data want it rigid or negative); "
                      "its stiffness is not identified",
                      j + 1));
      continue;
    }
    const auto pk = static_cast<Eigen::Index>(std::find(passive.begin(), passive.end(), j) - passive.begin());
    const double c = fit.scaled[k] / col_norm[j];
    const double se_c = std::sqrt(var_scaled[pk]) / col_norm[j];
    est.compliance_rad_per_nm[ju] = c;
    est.compliance_std_error_rad_per_nm[ju] = se_c;
    est.stiffness_nm_per_rad[ju] = 1.0 / c;
    est.std_error_nm_per_rad[ju] = se_c / (c * c);  // delta method: dk = -dc / c^2
    const double rel = se_c / c;
    // NaN (no residual degrees of freedom: as many equations as unknowns) counts as unidentified.
    if (!(rel <= max_relative_std_error)) {
      left_out.push_back(j);
      est.warnings.push_back(fmt::format(
          "joint {}: poorly identified (relative standard error {:.0f}% > {:.0f}%); the value is shown but should "
          "not be used: add poses or loads that turn this joint",
          j + 1, 100.0 * rel, 100.0 * max_relative_std_error));
    }
  }
}

// The joints not identified into est (1-based, sorted), and a warning naming the measurements rejected as
// outliers (file line where known; the first ten). `lines` has one entry per measurement.
void list_unidentified_and_rejected(std::vector<int>& left_out, const std::vector<int>& lines, StiffnessEstimate& est) {
  std::sort(left_out.begin(), left_out.end());
  for (int j : left_out) {
    est.unidentifiable_joints.push_back(j + 1);
  }
  if (!est.rejected_measurements.empty()) {
    std::vector<std::string> which;
    for (int i : est.rejected_measurements) {
      const int line = lines[static_cast<std::size_t>(i)];
      which.push_back(line > 0 ? fmt::format("line {}", line) : fmt::format("#{}", i + 1));
    }
    if (which.size() > 10) {
      which.resize(10);
      which.emplace_back("...");
    }
    est.warnings.push_back(fmt::format("{} of {} measurements rejected as outliers (Tukey weight 0): {}",
                                       est.rejected_measurements.size(), lines.size(), fmt::join(which, ", ")));
  }
}

}  // namespace

StiffnessIdentifier::StiffnessIdentifier(const RobotModel& model, const IdentificationOptions& options)
    : model_(model), options_(options), ws_(model), block_(6, model.dof()) {
  const int n = model.dof();
  if (!options.fixed_stiffness_nm_per_rad.empty() && static_cast<int>(options.fixed_stiffness_nm_per_rad.size()) != n) {
    throw InputError(fmt::format("identify_stiffness: {} fixed-stiffness entries for a {}-joint robot",
                                 options.fixed_stiffness_nm_per_rad.size(), n));
  }
  if (!(options.rotation_scale_m > 0.0) || !std::isfinite(options.rotation_scale_m)) {
    throw InputError("identify_stiffness: rotation_scale_m must be finite and > 0");
  }
  if (!(options.max_relative_std_error > 0.0) || !std::isfinite(options.max_relative_std_error)) {
    throw InputError("identify_stiffness: max_relative_std_error must be finite and > 0");
  }
  // Fractions of the largest column or singular value, compared with < and >= in solve(): a NaN
  // switched the excitation check off and made every joint "collinear".
  const auto fraction = [](double v, const char* name) {
    if (!(v >= 0.0 && v < 1.0)) {
      throw InputError(fmt::format("identify_stiffness: {} must be in [0, 1) (got {})", name, v));
    }
  };
  fraction(options.min_relative_excitation, "min_relative_excitation");
  fraction(options.min_relative_singular_value, "min_relative_singular_value");
  if (options.max_robust_iterations < 0) {
    throw InputError(
        fmt::format("identify_stiffness: max_robust_iterations must be >= 0 (got {})", options.max_robust_iterations));
  }
  store_ = std::make_unique<RowStoreHolder>(n, options.rows_in_memory_bytes);
}

StiffnessIdentifier::~StiffnessIdentifier() = default;

struct StiffnessIdentifier::RowStoreHolder {
  RowStoreHolder(int n, std::size_t memory_bytes) : rows(n, memory_bytes) {}
  RowStore rows;
  std::vector<double> sqrt_weight;
  std::vector<int> lines;
};

void StiffnessIdentifier::add(const StiffnessMeasurement& m) {
  const int n = model_.dof();
  const std::size_t i = store_->rows.size();
  if (m.q.size() != n) {
    throw InputError(
        fmt::format("{}: {} joint values for a {}-joint robot ({})", where(m, i), m.q.size(), n, model_.name()));
  }
  if (!m.q.allFinite() || !m.wrench_base.allFinite() || !m.dp_m.allFinite() ||
      (m.drot_rad && !m.drot_rad->allFinite())) {
    throw InputError(fmt::format("{}: a value is not finite", where(m, i)));
  }
  if (!(m.weight > 0.0) || !std::isfinite(m.weight)) {
    throw InputError(fmt::format("{}: weight {} must be finite and > 0", where(m, i), m.weight));
  }
  stiffness_regressor(model_, ws_, m.q, m.wrench_base, block_);
  const double sw = std::sqrt(m.weight);
  const int rows = m.drot_rad ? 6 : 3;
  double* out = store_->rows.append(rows);
  const int width = n + 1;
  for (int r = 0; r < 3; ++r) {
    for (int j = 0; j < n; ++j) {
      out[r * width + j] = sw * block_(r, j);
    }
    out[r * width + n] = sw * m.dp_m[r];
  }
  if (m.drot_rad) {
    const double f = sw * options_.rotation_scale_m;
    for (int r = 0; r < 3; ++r) {
      for (int j = 0; j < n; ++j) {
        out[(3 + r) * width + j] = f * block_(3 + r, j);
      }
      out[(3 + r) * width + n] = f * (*m.drot_rad)[r];
    }
  }
  store_->sqrt_weight.push_back(sw);
  store_->lines.push_back(m.line);
}

std::size_t StiffnessIdentifier::measurements() const { return store_->rows.size(); }

std::uint64_t StiffnessIdentifier::scratch_bytes() const { return store_->rows.bytes_on_disk(); }

StiffnessEstimate identify_stiffness(const RobotModel& model, const std::vector<StiffnessMeasurement>& data,
                                     const IdentificationOptions& options) {
  StiffnessIdentifier id(model, options);
  for (const StiffnessMeasurement& m : data) {
    id.add(m);
  }
  return id.solve();
}

StiffnessEstimate StiffnessIdentifier::solve() {
  RowStore& s = store_->rows;
  if (s.size() == 0) {
    throw InputError("identify_stiffness: no measurements");
  }
  if (solved_) {
    throw InputError("identify_stiffness: solve() runs once (it moves the fixed joints' part into the data)");
  }
  solved_ = true;

  // What is fitted: the free joints that the data excite and that are not collinear with others.
  const std::size_t m = s.size();
  StiffnessEstimate est = estimate_without_values(model_.dof(), m);
  const std::vector<int> free_joints = hold_fixed_joints(s, options_, est);
  const Eigen::VectorXd col_norm = regressor_column_norms(s);
  std::vector<int> left_out;
  std::vector<int> estimated = excited_joints(col_norm, free_joints, options_, left_out, est.warnings);
  std::vector<double> omega(m, 1.0);
  drop_collinear_joint_groups(s, col_norm, omega, options_.min_relative_singular_value, estimated, left_out,
                              est.warnings);
  hold_left_out_joints(s, model_, left_out, est.warnings);
  if (estimated.empty()) {
    throw InputError(fmt::format("identify_stiffness: no joint can be identified from these data: {}",
                                 fmt::join(est.warnings, "; ")));
  }

  // The fit, its figures and the standard errors.
  const WeightedFit fit = fit_robustly(s, estimated, col_norm, options_, omega, est.iterations);
  const WeightedResidualSums sums =
      summarise_residuals(s, fit, omega, store_->sqrt_weight, store_->lines, options_.rotation_scale_m, est);
  const std::vector<int> passive = joints_off_bound(estimated, fit.at_bound);
  const double sigma2 = residual_variance(sums, passive.size(), est);
  est.condition_number = scaled_condition_number(s, estimated, col_norm, omega);
  const Eigen::VectorXd var_scaled = scaled_compliance_variances(s, passive, col_norm, omega, sigma2);
  report_estimated_joints(estimated, fit, passive, var_scaled, col_norm, options_.max_relative_std_error, left_out,
                          est);
  list_unidentified_and_rejected(left_out, store_->lines, est);
  est.robust_weights = std::move(omega);
  return est;
}

RobotModel identified_robot(const RobotModel& model, const StiffnessEstimate& estimate, const std::string& data_name) {
  const auto n = static_cast<std::size_t>(model.dof());
  if (estimate.stiffness_nm_per_rad.size() != n) {
    throw InputError(fmt::format("identified_robot: the estimate has {} joints, {} has {}",
                                 estimate.stiffness_nm_per_rad.size(), model.name(), n));
  }
  std::vector<double> k(n);
  std::vector<std::string> kept;
  for (std::size_t j = 0; j < n; ++j) {
    const bool flagged = std::find(estimate.unidentifiable_joints.begin(), estimate.unidentifiable_joints.end(),
                                   static_cast<int>(j) + 1) != estimate.unidentifiable_joints.end();
    const double value = estimate.stiffness_nm_per_rad[j];
    if (std::isfinite(value) && !flagged) {
      k[j] = value;
    } else if (model.has_stiffness()) {
      k[j] = model.stiffness()[static_cast<Eigen::Index>(j)];
      kept.push_back(std::to_string(j + 1));
    } else {
      throw InputError(fmt::format("joint {} is not identified and the robot file gives no value to keep", j + 1));
    }
  }
  std::string note = fmt::format("identified by deflex identify from {} ({} measurements, residual RMS {:.4f} mm)",
                                 data_name, estimate.measurements, estimate.residual_rms_m * 1e3);
  if (!kept.empty()) {
    note += fmt::format("; joints {} kept from the previous file", fmt::join(kept, ", "));
  }
  return model.with_stiffness(k, note);
}

}  // namespace deflex
