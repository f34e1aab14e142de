// Joint stiffness identification: regressor, identifiability checks, robust NNLS, standard errors.
#include "deflex/identify/stiffness_identification.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <span>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "deflex/identify/detail/nonnegative_least_squares.hpp"
#include "deflex/identify/detail/robust_median.hpp"
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

// Each measurement's file line, as runs of consecutive lines (a file's rows, a comment between them starting a new
// run): a few bytes for a million measurements instead of 4 MB.
class MeasurementLines {
 public:
  void push_back(int line) {
    if (runs_.empty() || line != last_ + 1) {
      runs_.push_back({size_, line});
    }
    last_ = line;
    ++size_;
  }
  [[nodiscard]] int operator[](std::size_t i) const {
    const auto run = std::prev(std::upper_bound(runs_.begin(), runs_.end(), i,
                                                [](std::size_t index, const Run& r) { return index < r.first; }));
    return run->line + static_cast<int>(i - run->first);
  }
  [[nodiscard]] std::size_t size() const { return size_; }

 private:
  struct Run {
    std::size_t first;  // measurement index
    int line;           // its line
  };
  std::vector<Run> runs_;
  std::size_t size_ = 0;
  int last_ = 0;
};

// The stacked problem in compact form: per measurement its 3 (or 6) rows [A_i | b_i], already
// multiplied by sqrt(weight) (rotation rows also by rotation_scale_m), in chunks of 16k rows so that
// growing never copies what is stored (a doubling vector would hold up to three times the data at
// its peak). That is what the robust re-weighting needs: each measurement's residual against every
// new estimate; recomputing the regressor instead (FK and two Jacobians) would cost about 0.3 us a
// measurement an iteration. 8 (dof + 1) bytes a row: 168 bytes for a 6-joint position measurement.
// Chunks beyond IdentificationOptions::rows_in_memory_bytes go to an unlinked scratch file and are
// seen in place a chunk at a time on every pass (a read-only map, no copy; for_each_mutable reads and
// writes them back): the same doubles in the same order, so the results are bit for bit those of an
// all-in-memory store, with memory bounded by the budget (plus two chunks) and the per-measurement
// scalars the re-weighting keeps (17 bytes: robust weight, residual norm, row count; the sqrt of the
// given weight only once one differs from 1, the file lines as runs).
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
  // One measurement's rows as for_each hands them over.
  struct Measurement {
    std::size_t i;
    int rows;
    const double* block;
  };
  static constexpr std::size_t kBatch = 64;
  // f(batch): the measurements in order, up to kBatch at a time (never across a chunk: its rows are seen only while
  // it is), so a pass can work out every measurement's weight before it uses any of them.
  template <typename F>
  void for_each_batch(F&& f) const {
    std::array<Measurement, kBatch> batch{};
    std::size_t i = 0;
    for (const Chunk& c : chunks_) {
      std::optional<SpillFile::View> view;
      if (c.on_disk()) {
        view.emplace(spill_, static_cast<std::uint64_t>(c.offset), c.size);
      }
      const double* data = c.on_disk() ? view->data() : c.values.data();
      std::size_t n = 0;
      for (std::size_t at = 0; at < c.count(); ++i) {
        const int rows = rows_[i];
        batch[n++] = {i, rows, data + at};
        if (n == kBatch) {
          f(std::span<const Measurement>(batch.data(), n));
          n = 0;
        }
        at += static_cast<std::size_t>(rows * width_);
      }
      if (n > 0) {
        f(std::span<const Measurement>(batch.data(), n));
      }
    }
  }
  // f(i, rows, block): block is rows x (dof + 1), row-major, A_i then b_i in the last column.
  template <typename F>
  void for_each(F&& f) const {
    for_each_batch([&](std::span<const Measurement> batch) {
      for (const Measurement& m : batch) f(m.i, m.rows, m.block);
    });
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
  static constexpr std::size_t kChunkRows =
      16384;  // 0.9 MB of 7-wide rows: two of them (one filling, one seen from the file) in the peak
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

// Two doubles in one register (GCC's vector extension: SSE2 on x86-64, NEON on ARM). Each lane's arithmetic is the
// scalar operation's, so a loop that takes its values two at a time gives the same bits.
using DoublePair = double __attribute__((vector_size(16)));

// R (p x p, upper) and Q^T y (p) of the tall system whose rows are measurement i's rows, columns
// `cols` of A divided by scale[col], and b, all multiplied by sqrt(omega_i): Householder QR of the
// rows a slab at a time, each slab stacked under the R found so far (the same R, up to the signs of
// its rows, as one QR of the whole tall matrix, without holding it).
struct Triangular {
  Eigen::MatrixXd R;  // p x p, zero below row `rows`
  Eigen::VectorXd qty;
  Eigen::Index rows = 0;  // min(equations, p): fewer equations than unknowns leave R short
};
// `visit(i, rows, block)` sees each measurement first, so a pass that needs the rows anyway (the residuals
// of the previous fit) rides on this one instead of reading every row again.
template <typename Visit>
Triangular blocked_qr(const RowStore& s, const std::vector<int>& cols, const Eigen::VectorXd& scale,
                      const std::vector<double>& omega, Visit&& visit) {
  const auto p = static_cast<Eigen::Index>(cols.size());
  const Eigen::Index w = p + 1;
  constexpr Eigen::Index kSlab = 512;
  Eigen::MatrixXd buf(w + kSlab, w);
  Eigen::Index top = 0;   // rows of R so far (at most w)
  Eigen::Index fill = 0;  // rows in the buffer
  const Eigen::Index bcol = s.width() - 1;
  std::vector<double> col_scale;  // the scale of each column taken
  for (const int j : cols) {
    col_scale.push_back(scale[j]);
  }
  const auto reduce = [&]() {
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(buf.topRows(fill));
    top = std::min(fill, w);
    buf.topRows(top) = qr.matrixQR().topRows(top).triangularView<Eigen::Upper>();
    fill = top;
  };
  s.for_each([&](std::size_t i, int rows, const double* block) {
    visit(i, rows, block);
    const RowBlock B(block, rows, s.width());
    const double sw = std::sqrt(omega[i]);
    // sw * a / scale two columns at a time: the division was most of what filling the slab cost (perf: 5 % of a
    // million-row identification), and two lanes divide in about the time of one.
    for (int r = 0; r < rows; ++r) {
      std::size_t k = 0;
      for (; k + 1 < col_scale.size(); k += 2) {
        const DoublePair a{B(r, cols[k]), B(r, cols[k + 1])};
        const DoublePair v = sw * a / DoublePair{col_scale[k], col_scale[k + 1]};
        buf(fill, static_cast<Eigen::Index>(k)) = v[0];
        buf(fill, static_cast<Eigen::Index>(k) + 1) = v[1];
      }
      if (k < col_scale.size()) {
        buf(fill, static_cast<Eigen::Index>(k)) = sw * B(r, cols[k]) / col_scale[k];
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
Triangular blocked_qr(const RowStore& s, const std::vector<int>& cols, const Eigen::VectorXd& scale,
                      const std::vector<double>& omega) {
  return blocked_qr(s, cols, scale, omega, [](std::size_t, int, const double*) {});
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
// `accepted_qr` ends as the QR of the set accepted (when the check ran on it), for the first fit to reuse.
void drop_collinear_joint_groups(const RowStore& s, const Eigen::VectorXd& col_norm, const std::vector<double>& omega,
                                 double min_relative_singular_value, std::vector<int>& estimated,
                                 std::vector<int>& left_out, std::vector<std::string>& warnings,
                                 std::optional<Triangular>& accepted_qr) {
  accepted_qr.reset();
  while (estimated.size() > 1) {
    Triangular qr = blocked_qr(s, estimated, col_norm, omega);
    const Svd svd(qr.R.topRows(qr.rows));
    const Eigen::VectorXd& sv = svd.values();
    const Eigen::Index last = sv.size() - 1;
    // Fewer equations than joints: the SVD has fewer singular values than columns, and V's trailing
    // columns span a null space the smallest singular value does not show.
    const bool underdetermined = sv.size() < static_cast<Eigen::Index>(estimated.size());
    if (!underdetermined && sv[last] >= min_relative_singular_value * sv[0]) {
      accepted_qr = std::move(qr);
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
// Returns whether the stored rows changed.
bool hold_left_out_joints(RowStore& s, const RobotModel& model, std::vector<int>& left_out,
                          std::vector<std::string>& warnings) {
  std::sort(left_out.begin(), left_out.end());
  bool changed = false;
  for (int j : left_out) {
    if (model.has_stiffness()) {
      changed = true;
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
  return changed;
}

// The weighted sums of one pass, upper triangle of [A b]^T diag(omega) [A b] over every stored column (dof + 1),
// unscaled: the fit picks its columns and scales them afterwards, G_kl = S_kl / (norm_k norm_l). Our own loop
// instead of Eigen's small dynamic products of each measurement's copied, divided columns, because it measured
// faster: perf of a million-row run, 2.7 s of 7.2 s CPU in that product before (37 %, under load), the passes
// with this loop (sums, residuals and weights together) 1.2 s of 3.2 s after. The sums differ from the per-row
// scaled ones by rounding only (docs/identify.md, "Exactness").
struct WeightedSums {
  std::array<double, static_cast<std::size_t>((kMaxJoints + 1) * (kMaxJoints + 2) / 2)> upper{};
  void clear() { upper.fill(0.0); }
};

// Index of (k, l), k <= l, in the packed upper triangle of a width x width matrix.
constexpr int packed(int width, int k, int l) { return k * width - k * (k - 1) / 2 + (l - k); }

// S += omega [A b]^T [A b] for one measurement's `rows` rows of `width` values. W > 0: the width known at compile
// time (a 6-joint arm: 7), R > 0 the rows (3 or 6), so the compiler unrolls the 28 sums of products. Each sum is
// loaded once, takes the rows' products in row order and is stored once: the same operations in the same order as
// adding a row at a time, but a row at a time stored every sum after every row, as the compiler must when the sums
// may share memory with the rows (perf of a million-row identification: 84 stores a measurement, a quarter of the
// run in the passes that sum).
template <int W, int R>
void add_weighted_products(const double* block, int runtime_rows, int runtime_width, double omega, double* upper) {
  if constexpr (W > 0 && R > 0) {
    // Two sums at a time (DoublePair): each lane does what the scalar loop below does to its sum.
    using Pair = DoublePair;
    const auto load = [](const double* p) {
      Pair v;
      std::memcpy(&v, p, sizeof v);
      return v;
    };
    std::array<const double*, static_cast<std::size_t>(R)> x{};
    for (std::size_t r = 0; r < x.size(); ++r) {
      x[r] = block + static_cast<std::ptrdiff_t>(r) * W;
    }
    int at = 0;
#pragma GCC unroll 8
    for (int k = 0; k < W; ++k) {
      std::array<double, static_cast<std::size_t>(R)> wx{};
      for (std::size_t r = 0; r < x.size(); ++r) {
        wx[r] = omega * x[r][k];
      }
      int l = k;
#pragma GCC unroll 4
      for (; l + 1 < W; l += 2, at += 2) {
        Pair sum = load(upper + at);
        for (std::size_t r = 0; r < x.size(); ++r) {
          sum += wx[r] * load(x[r] + l);
        }
        std::memcpy(upper + at, &sum, sizeof sum);
      }
      if (l < W) {
        double sum = upper[at];
        for (std::size_t r = 0; r < x.size(); ++r) {
          sum += wx[r] * x[r][l];
        }
        upper[at++] = sum;
      }
    }
  } else {
    const int width = W > 0 ? W : runtime_width;
    const int rows = R > 0 ? R : runtime_rows;
    int at = 0;
    for (int k = 0; k < width; ++k) {
      for (int l = k; l < width; ++l) {
        double sum = upper[at];
        for (int r = 0; r < rows; ++r) {
          const double* x = block + static_cast<std::ptrdiff_t>(r) * width;
          sum += omega * x[k] * x[l];  // (omega x_k) x_l, as the row-at-a-time loop had it
        }
        upper[at++] = sum;
      }
    }
  }
}

// The same for any row count, the common 3 and 6 unrolled.
template <int W>
void add_weighted_products(const double* block, int rows, int runtime_width, double omega, double* upper) {
  if (rows == 3) {
    add_weighted_products<W, 3>(block, rows, runtime_width, omega, upper);
  } else if (rows == 6) {
    add_weighted_products<W, 6>(block, rows, runtime_width, omega, upper);
  } else {
    add_weighted_products<W, 0>(block, rows, runtime_width, omega, upper);
  }
}

// |b - A c| over one measurement's rows (c: one compliance per stored column, 0 where not estimated).
template <int W>
double residual_norm(const double* block, int rows, int runtime_width, const double* c) {
  const int width = W > 0 ? W : runtime_width;
  const int n = width - 1;
  double sum = 0.0;
  for (int r = 0; r < rows; ++r) {
    const double* x = block + static_cast<std::ptrdiff_t>(r) * width;
    double ac = 0.0;
#pragma GCC unroll 8
    for (int j = 0; j < n; ++j) {
      ac += x[j] * c[j];
    }
    const double e = x[n] - ac;
    sum += e * e;
  }
  return std::sqrt(sum);
}

// Calls f.template operator()<W>() with W the width when it is the common 7 (six joints), else 0.
template <typename F>
void with_width(int width, F&& f) {
  if (width == 7) {
    f.template operator()<7>();
  } else {
    f.template operator()<0>();
  }
}

// The current fit of the estimated joints.
struct WeightedFit {
  Eigen::VectorXd scaled;                          // compliance times column norm, per estimated joint
  Eigen::Array<bool, Eigen::Dynamic, 1> at_bound;  // per estimated joint: held at c = 0 by the constraint
  Eigen::VectorXd c_full;                          // compliance per joint, 0 where not estimated
  std::vector<double> d;                           // per measurement: d_i = |b_i - A_i c| over its stored rows
  std::optional<Triangular> qr;                    // the QR of the last exact fit (the final weights)
};

// The NNLS of the estimated joints from the weighted sums, by the normal equations G s = h with the columns scaled
// to unit norm. False (r untouched) when G is not positive definite.
bool nnls_from_sums(const WeightedSums& sums, int width, const std::vector<int>& estimated,
                    const Eigen::VectorXd& col_norm, NnlsResult& r) {
  const auto p = static_cast<Eigen::Index>(estimated.size());
  const int n = width - 1;
  Eigen::MatrixXd G(p, p);
  Eigen::VectorXd h(p);
  for (Eigen::Index a = 0; a < p; ++a) {
    const int j = estimated[static_cast<std::size_t>(a)];
    for (Eigen::Index b = a; b < p; ++b) {
      const int l = estimated[static_cast<std::size_t>(b)];
      G(a, b) = G(b, a) = sums.upper[static_cast<std::size_t>(packed(width, j, l))] / (col_norm[j] * col_norm[l]);
    }
    h[a] = sums.upper[static_cast<std::size_t>(packed(width, j, n))] / col_norm[j];
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(G);
  if (llt.info() != Eigen::Success) {
    return false;
  }
  // min ||R s - y|| with R = L^T, y = L^-1 h has the normal equations G s = h.
  const Eigen::MatrixXd R = llt.matrixU();
  const Eigen::VectorXd y = llt.matrixL().solve(h);
  r = nonnegative_least_squares(R, y);
  return true;
}

// The fit from an NNLS result: scaled and full compliances.
void take_solution(const NnlsResult& r, const std::vector<int>& estimated, const Eigen::VectorXd& col_norm,
                   WeightedFit& fit) {
  fit.scaled = r.x;
  fit.at_bound = r.at_bound;
  fit.c_full.setZero();
  for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(estimated.size()); ++k) {
    const int j = estimated[static_cast<std::size_t>(k)];
    fit.c_full[j] = fit.scaled[k] / col_norm[j];
  }
}

// The exact fit by one QR of the tall system (a p x p triangular NNLS with the same solution); `qr` when the
// caller has it already (the identifiability check's, same rows and weights), else a pass that also lets
// `visit` see each measurement. Keeps the QR for the condition number and the standard errors.
template <typename Visit>
void fit_by_qr(const RowStore& s, const std::vector<int>& estimated, const Eigen::VectorXd& col_norm,
               const std::vector<double>& omega, std::optional<Triangular> qr, WeightedFit& fit, Visit&& visit) {
  if (!qr) {
    qr = blocked_qr(s, estimated, col_norm, omega, visit);
  }
  take_solution(nonnegative_least_squares(qr->R, qr->qty), estimated, col_norm, fit);
  fit.qr = std::move(qr);
}

// The robust weight of a measurement whose residual norm is u noise sigmas, with k = rows degrees of freedom:
// stage 0 Huber's (full weight up to the chi quantile at z = 1.645), stage 1 Tukey's bisquare (zero beyond 1.42
// times the chi quantile at z = 3.090).
// The thresholds depend only on the row count (3 or 6): computed once, not per measurement and pass (that
// was 10 % of a million-row run).
struct RobustThresholds {
  std::array<double, 7> huber{}, tukey{}, chi_median{};
  RobustThresholds() {
    for (int k : {3, 6}) {
      const auto ku = static_cast<std::size_t>(k);
      huber[ku] = std::sqrt(chi_square_quantile(k, 1.645));
      tukey[ku] = 1.42 * std::sqrt(chi_square_quantile(k, 3.090));
      chi_median[ku] = std::sqrt(chi_square_quantile(k, 0.0));
    }
  }
};
const RobustThresholds& robust_thresholds() {
  static const RobustThresholds t;
  return t;
}

double irls_measurement_weight(int stage, int rows, double u, const RobustThresholds& th = robust_thresholds()) {
  if (stage == 0) {
    const double h = th.huber[static_cast<std::size_t>(rows)];
    return u <= h ? 1.0 : h / u;
  }
  const double c = th.tukey[static_cast<std::size_t>(rows)];
  const double t = u / c;
  return t < 1.0 ? (1.0 - t * t) * (1.0 - t * t) : 0.0;
}

// One pass over the rows for the robust loop: each measurement's residual norm against the fit into d and, with
// `tukey_sigma` > 0 (stage 1, scale frozen), its new weight into omega and the weighted sums of the next fit.
// The residuals of one fit and the sums of the next are one read of the rows instead of two.
void residual_pass(const RowStore& s, const Eigen::VectorXd& c_full, std::vector<double>& d, double tukey_sigma,
                   std::vector<double>& omega, WeightedSums* next, double* b2) {
  const int width = s.width();
  if (next != nullptr) {
    next->clear();
  }
  const RobustThresholds& th = robust_thresholds();
  // A batch of measurements at a time: first every residual norm and weight (a square root and two divisions each,
  // independent from one measurement to the next, so they overlap), then the products of those kept. A measurement
  // at a time, its products waited for its weight: perf of a million-row identification showed the pass stalled on
  // the square root and the divisions. The same operations in the same order, so the same bits.
  with_width(width, [&]<int W>() {
    s.for_each_batch([&](std::span<const RowStore::Measurement> batch) {
      for (const RowStore::Measurement& m : batch) {
        d[m.i] = residual_norm<W>(m.block, m.rows, width, c_full.data());
        if (b2 != nullptr) {
          for (int r = 0; r < m.rows; ++r) {
            *b2 += m.block[r * width + width - 1] * m.block[r * width + width - 1];
          }
        }
        if (next != nullptr) {
          omega[m.i] = irls_measurement_weight(1, m.rows, d[m.i] / tukey_sigma, th);
        }
      }
      if (next != nullptr) {
        for (const RowStore::Measurement& m : batch) {
          if (omega[m.i] != 0.0) {
            add_weighted_products<W>(m.block, m.rows, width, omega[m.i], next->upper.data());
          }
        }
      }
    });
  });
}

// The weighted sums of the current weights (a pass of its own: stage 0, whose weights need every residual's
// median first).
void sums_pass(const RowStore& s, const std::vector<double>& omega, WeightedSums& sums) {
  const int width = s.width();
  sums.clear();
  with_width(width, [&]<int W>() {
    s.for_each([&](std::size_t i, int rows, const double* block) {
      if (omega[i] != 0.0) {
        add_weighted_products<W>(block, rows, width, omega[i], sums.upper.data());
      }
    });
  });
}

// Robust NNLS: Huber IRLS (convex, from the least-squares start), then Tukey's bisquare from the
// Huber solution with the scale frozen (rejects gross outliers outright). Each measurement is
// weighted as a whole by its residual norm d_i, which is chi-distributed with k_i = 3 (or 6)
// degrees of freedom in units of the noise sigma. The first and the final solve are by QR (the first reuses
// `first_qr`, the identifiability check's, when given); omega ends as the final weights, `iterations` counts the
// re-weightings. The passes over the rows: the QR, the first residuals, per Huber iteration the sums and the
// residuals, per Tukey iteration one (residuals, weights and the next sums together), and the final QR.
WeightedFit fit_robustly(const RowStore& s, const std::vector<int>& estimated, const Eigen::VectorXd& col_norm,
                         const IdentificationOptions& options, std::vector<double>& omega, int& iterations,
                         std::optional<Triangular> first_qr) {
  const std::size_t m = s.size();
  const int n = s.width() - 1;
  const auto none = [](std::size_t, int, const double*) {};
  WeightedFit fit;
  fit.c_full = Eigen::VectorXd::Zero(n);
  fit_by_qr(s, estimated, col_norm, omega, std::move(first_qr), fit, none);
  if (!options.robust) {
    return fit;
  }
  fit.d.assign(m, 0.0);
  double b2 = 0.0;
  residual_pass(s, fit.c_full, fit.d, 0.0, omega, nullptr, &b2);
  const double rhs_scale = std::sqrt(b2 / static_cast<double>(s.total_rows()));
  const auto& chi_median = robust_thresholds().chi_median;
  double sigma = 0.0;
  WeightedSums sums;
  bool sums_ready = false;  // the Tukey weights and their sums came with the last residual pass
  for (int stage = 0; stage < 2; ++stage) {
    for (int it = 0; it < options.max_robust_iterations; ++it) {
      if (stage == 0) {
        sigma = median_of_nonnegative(
            m, [&](std::size_t i) { return fit.d[i] / chi_median[static_cast<std::size_t>(s.rows(i))]; });
      }
      if (!(sigma > 1e-12 * rhs_scale)) {
        break;  // an exact fit: nothing to re-weight
      }
      if (!sums_ready) {
        const RobustThresholds& th = robust_thresholds();
        for (std::size_t i = 0; i < m; ++i) {
          omega[i] = irls_measurement_weight(stage, s.rows(i), fit.d[i] / sigma, th);
        }
        sums_pass(s, omega, sums);
      }
      const Eigen::VectorXd before = fit.scaled;
      NnlsResult r;
      if (nnls_from_sums(sums, s.width(), estimated, col_norm, r)) {
        take_solution(r, estimated, col_norm, fit);
      } else {
        fit_by_qr(s, estimated, col_norm, omega, std::nullopt, fit, none);
      }
      ++iterations;
      const bool converged = (fit.scaled - before).norm() <= 1e-10 * fit.scaled.norm();
      // What reads the residuals of this fit next: another Huber iteration (their median first), a Tukey
      // iteration (weights from them at once: one pass), or nothing (the final QR needs only the weights).
      const bool last_of_stage = converged || it + 1 == options.max_robust_iterations;
      const bool tukey_next = stage == 0 ? last_of_stage : !last_of_stage;
      if (tukey_next) {
        residual_pass(s, fit.c_full, fit.d, sigma, omega, &sums, nullptr);
      } else if (!last_of_stage) {
        residual_pass(s, fit.c_full, fit.d, 0.0, omega, nullptr, nullptr);
      }
      sums_ready = tukey_next;
      if (converged) {
        break;
      }
    }
  }
  fit_by_qr(s, estimated, col_norm, omega, std::nullopt, fit, none);
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
                                         const std::vector<double>& sqrt_weight,
                                         const identify_detail::MeasurementLines& lines, double rotation_scale_m,
                                         StiffnessEstimate& est) {
  const int width = s.width();
  const int n = width - 1;
  WeightedResidualSums sums;
  double pos2 = 0.0, rot2 = 0.0;
  int kept = 0, kept_rot = 0;
  s.for_each([&](std::size_t i, int rows, const double* block) {
    // The residual rows, weighted as stored, then in the measured units.
    std::array<double, 6> e{};
    double d2 = 0.0;
    for (int r = 0; r < rows; ++r) {
      const double* x = block + static_cast<std::ptrdiff_t>(r) * width;
      double ac = 0.0;
      for (int j = 0; j < n; ++j) {
        ac += x[j] * fit.c_full[j];
      }
      e[static_cast<std::size_t>(r)] = x[n] - ac;
      d2 += e[static_cast<std::size_t>(r)] * e[static_cast<std::size_t>(r)];
    }
    const double d = std::sqrt(d2);
    sums.wr2 += omega[i] * d * d;
    sums.wdof += omega[i] * rows;
    if (omega[i] > 0.0) {
      const double sw = sqrt_weight.empty() ? 1.0 : sqrt_weight[i];
      const Vector3 p(e[0] / sw, e[1] / sw, e[2] / sw);
      pos2 += p.squaredNorm();
      est.residual_max_m = std::max(est.residual_max_m, p.norm());
      ++kept;
      if (rows == 6) {
        const Vector3 q(e[3] / sw, e[4] / sw, e[5] / sw);
        rot2 += q.squaredNorm() / (rotation_scale_m * rotation_scale_m);
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
// From the QR of the final fit (the estimated joints, the final weights).
double scaled_condition_number(const Triangular& final_qr) {
  const Svd svd(final_qr.R.topRows(final_qr.rows));
  const Eigen::VectorXd& sv = svd.values();
  return sv[sv.size() - 1] > 0.0 ? sv[0] / sv[sv.size() - 1] : std::numeric_limits<double>::infinity();
}

// Variance of each scaled compliance of the joints off the bound: sigma^2 times the diagonal of (R^T R)^-1.
// When every estimated joint is off the bound, the final fit's QR is this one (the same rows, columns and
// weights): no pass.
Eigen::VectorXd scaled_compliance_variances(const RowStore& s, const std::vector<int>& estimated,
                                            const std::vector<int>& passive, const Triangular& final_qr,
                                            const Eigen::VectorXd& col_norm, const std::vector<double>& omega,
                                            double sigma2) {
  Eigen::VectorXd var_scaled = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(passive.size()));
  if (!passive.empty()) {
    const auto pp = static_cast<Eigen::Index>(passive.size());
    const Eigen::MatrixXd R = passive == estimated ? final_qr.R : blocked_qr(s, passive, col_norm, omega).R;
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
void list_unidentified_and_rejected(std::vector<int>& left_out, const identify_detail::MeasurementLines& lines,
                                    StiffnessEstimate& est) {
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
  RowStoreHolder(int n, std::size_t memory_bytes) : rows(n, memory_bytes), col_sq(Eigen::VectorXd::Zero(n)) {}
  RowStore rows;
  Eigen::VectorXd col_sq;           // sum of squares of each stored regressor column (fixed joints move only b)
  std::vector<double> sqrt_weight;  // empty while every weight is 1 (8 bytes a measurement saved)
  identify_detail::MeasurementLines lines;
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
  // Each column's squares summed over the measurement's rows, in the order Eigen 3.4's column-wise squaredNorm
  // sums them (packetwise_redux: the first, then four at a time in pairs, then the rest one by one), which a pass
  // of its own over the stored rows did before: the same bits, without the pass.
  const auto sq = [&](int r, int j) { return out[r * width + j] * out[r * width + j]; };
  for (int j = 0; j < n; ++j) {
    double sum = sq(0, j);
    int r = 1;
    for (; r < ((rows - 1) & ~3); r += 4) {
      sum = sum + ((sq(r, j) + sq(r + 1, j)) + (sq(r + 2, j) + sq(r + 3, j)));
    }
    for (; r < rows; ++r) {
      sum = sum + sq(r, j);
    }
    store_->col_sq[j] += sum;
  }
  if (sw != 1.0 || !store_->sqrt_weight.empty()) {
    store_->sqrt_weight.resize(i, 1.0);  // the measurements before the first weight other than 1
    store_->sqrt_weight.push_back(sw);
  }
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
  const Eigen::VectorXd col_norm = store_->col_sq.cwiseSqrt();
  std::vector<int> left_out;
  std::vector<int> estimated = excited_joints(col_norm, free_joints, options_, left_out, est.warnings);
  std::vector<double> omega(m, 1.0);
  std::optional<Triangular> accepted_qr;
  drop_collinear_joint_groups(s, col_norm, omega, options_.min_relative_singular_value, estimated, left_out,
                              est.warnings, accepted_qr);
  if (hold_left_out_joints(s, model_, left_out, est.warnings)) {
    accepted_qr.reset();  // its Q^T b is of the rows before
  }
  if (estimated.empty()) {
    throw InputError(fmt::format("identify_stiffness: no joint can be identified from these data: {}",
                                 fmt::join(est.warnings, "; ")));
  }

  // The fit, its figures and the standard errors.
  const WeightedFit fit = fit_robustly(s, estimated, col_norm, options_, omega, est.iterations, std::move(accepted_qr));
  const WeightedResidualSums sums =
      summarise_residuals(s, fit, omega, store_->sqrt_weight, store_->lines, options_.rotation_scale_m, est);
  const std::vector<int> passive = joints_off_bound(estimated, fit.at_bound);
  const double sigma2 = residual_variance(sums, passive.size(), est);
  est.condition_number = scaled_condition_number(*fit.qr);
  const Eigen::VectorXd var_scaled =
      scaled_compliance_variances(s, estimated, passive, *fit.qr, col_norm, omega, sigma2);
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
