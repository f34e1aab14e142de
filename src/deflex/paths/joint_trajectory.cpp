// Timed joint trajectory (see joint_trajectory.hpp).
#include "deflex/paths/joint_trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include <fmt/format.h>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {
namespace {

// Hermite basis on u in [0, 1] for a segment of length h: position and derivative.
void hermite(double u, double h, const JointVector& q0, const JointVector& q1, const JointVector& m0,
             const JointVector& m1, JointVector& q, JointVector* qd) {
  const double u2 = u * u, u3 = u2 * u;
  const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
  q = h00 * q0 + (h10 * h) * m0 + h01 * q1 + (h11 * h) * m1;
  if (qd != nullptr) {
    const double d00 = (6 * u2 - 6 * u) / h, d10 = 3 * u2 - 4 * u + 1, d01 = (-6 * u2 + 6 * u) / h,
                 d11 = 3 * u2 - 2 * u;
    *qd = d00 * q0 + d10 * m0 + d01 * q1 + d11 * m1;
  }
}

// Largest |q'(t)| of one joint's cubic Hermite segment: the derivative is a quadratic in u, so its
// extreme lies at an end or at the vertex.
double segment_peak_speed(double h, double q0, double q1, double m0, double m1) {
  // q'(u) = a u^2 + b u + c (per unit time), from the derivative of the basis above.
  const double a = (6 * q0 - 6 * q1) / h + 3 * m0 + 3 * m1;
  const double b = (-6 * q0 + 6 * q1) / h - 4 * m0 - 2 * m1;
  const double c = m0;
  double peak = std::max(std::abs(c), std::abs(a + b + c));
  if (a != 0.0) {
    const double u = -b / (2 * a);
    if (u > 0.0 && u < 1.0) {
      peak = std::max(peak, std::abs(a * u * u + b * u + c));
    }
  }
  return peak;
}

}  // namespace

JointTrajectory::JointTrajectory(std::vector<double> t_s, std::vector<JointVector> q, const RobotModel& model,
                                 std::string source, std::vector<int> lines)
    : t_(std::move(t_s)), q_(std::move(q)), source_(std::move(source)) {
  const auto where = [&](std::size_t i) {
    return i < lines.size() ? fmt::format("{}:{}", source_, lines[i]) : fmt::format("{}: point {}", source_, i + 1);
  };
  if (t_.size() != q_.size()) {
    throw InputError(fmt::format("{}: {} times for {} joint points", source_, t_.size(), q_.size()));
  }
  if (t_.size() < 2) {
    throw InputError(fmt::format("{}: a trajectory needs at least two points (has {})", source_, t_.size()));
  }
  const int n = model.dof();
  for (std::size_t i = 0; i < t_.size(); ++i) {
    if (!std::isfinite(t_[i])) {
      throw InputError(fmt::format("{}: time t_s is not a finite number", where(i)));
    }
    if (i > 0 && !(t_[i] > t_[i - 1])) {
      throw InputError(
          fmt::format("{}: time t_s = {} s does not increase (previous point {} s)", where(i), t_[i], t_[i - 1]));
    }
    if (q_[i].size() != n) {
      throw InputError(fmt::format("{}: {} joints for a robot of {}", where(i), q_[i].size(), n));
    }
    for (int j = 0; j < n; ++j) {
      const double v = q_[i][j];
      if (!std::isfinite(v)) {
        throw InputError(fmt::format("{}: joint {} is not a finite number", where(i), j + 1));
      }
      if (v < model.lower_limits()[j] - 1e-9 || v > model.upper_limits()[j] + 1e-9) {
        throw InputError(fmt::format("{}: joint {} at {:.4f} deg is beyond its limits [{:.1f}, {:.1f}] deg", where(i),
                                     j + 1, rad_to_deg(v), rad_to_deg(model.lower_limits()[j]),
                                     rad_to_deg(model.upper_limits()[j])));
      }
    }
  }
  // Tangents: the slope of the parabola through each point and its neighbours (second-order
  // accurate on uneven spacing); zero at both ends (start and end at rest) and for a joint that
  // holds still on either side (no overshoot out of a hold, and a reversal stops where it should).
  const std::size_t m = t_.size();
  m_.assign(m, JointVector::Zero(n));
  for (std::size_t i = 1; i + 1 < m; ++i) {
    const double h0 = t_[i] - t_[i - 1], h1 = t_[i + 1] - t_[i];
    for (int j = 0; j < n; ++j) {
      const double s0 = (q_[i][j] - q_[i - 1][j]) / h0, s1 = (q_[i + 1][j] - q_[i][j]) / h1;
      m_[i][j] = (s0 == 0.0 || s1 == 0.0) ? 0.0 : (h0 * s1 + h1 * s0) / (h0 + h1);
    }
  }
  peak_speed_ = JointVector::Zero(n);
  for (std::size_t i = 0; i + 1 < m; ++i) {
    const double h = t_[i + 1] - t_[i];
    for (int j = 0; j < n; ++j) {
      const double peak = segment_peak_speed(h, q_[i][j], q_[i + 1][j], m_[i][j], m_[i + 1][j]);
      peak_speed_[j] = std::max(peak_speed_[j], peak);
      const double limit = model.max_speed()[j];
      if (peak > limit * (1.0 + 1e-9)) {
        throw InputError(fmt::format(
            "{}: joint {} would move at {:.2f} deg/s between t = {} s and {} s, above its speed limit of {:.1f} deg/s "
            "(slow the program down or add points)",
            where(i + 1), j + 1, rad_to_deg(peak), t_[i], t_[i + 1], rad_to_deg(limit)));
      }
    }
  }
}

JointTrajectory JointTrajectory::read_csv(const std::string& path, const RobotModel& model) {
  const CsvTable table = CsvTable::read_file(path);
  const int n = model.dof();
  std::vector<std::string> expected{"t_s"};
  for (int j = 1; j <= n; ++j) {
    expected.push_back(fmt::format("q{}_deg", j));
  }
  table.require(expected);
  for (const auto& c : table.columns()) {
    if (std::find(expected.begin(), expected.end(), c) == expected.end()) {
      throw DataError(fmt::format("{}: unknown column '{}' (a joint trajectory has t_s,q1_deg..q{}_deg for this robot)",
                                  path, c, n));
    }
  }
  std::vector<double> t;
  std::vector<JointVector> q;
  std::vector<int> lines;
  t.reserve(table.rows());
  q.reserve(table.rows());
  for (std::size_t r = 0; r < table.rows(); ++r) {
    t.push_back(table.at(r, "t_s"));
    JointVector v(n);
    for (int j = 0; j < n; ++j) {
      v[j] = deg_to_rad(table.at(r, static_cast<std::size_t>(table.column(expected[static_cast<std::size_t>(j) + 1]))));
    }
    q.push_back(v);
    lines.push_back(table.line_of(r));
  }
  return JointTrajectory(std::move(t), std::move(q), model, path, std::move(lines));
}

std::string JointTrajectory::csv_text(const std::string& comment) const {
  fmt::memory_buffer out;
  if (!comment.empty()) {
    fmt::format_to(std::back_inserter(out), "# {}\n", comment);
  }
  fmt::format_to(std::back_inserter(out), "t_s");
  for (int j = 1; j <= dof(); ++j) {
    fmt::format_to(std::back_inserter(out), ",q{}_deg", j);
  }
  out.push_back('\n');
  for (std::size_t i = 0; i < t_.size(); ++i) {
    fmt::format_to(std::back_inserter(out), "{:.9f}", t_[i]);
    for (int j = 0; j < dof(); ++j) {
      fmt::format_to(std::back_inserter(out), ",{:.10f}", rad_to_deg(q_[i][j]));
    }
    out.push_back('\n');
  }
  return fmt::to_string(out);
}

void JointTrajectory::write_csv(const std::string& path, const std::string& comment) const {
  write_output_file(path, csv_text(comment), "joint trajectory");
}

void JointTrajectory::sample(double t_s, JointVector& q, JointVector* qd) const noexcept {
  if (t_.empty()) {
    return;
  }
  if (!(t_s > t_.front())) {  // also NaN: hold the start
    q = q_.front();
    if (qd != nullptr) qd->setZero(q.size());
    return;
  }
  if (t_s >= t_.back()) {
    q = q_.back();
    if (qd != nullptr) qd->setZero(q.size());
    return;
  }
  const auto it = std::upper_bound(t_.begin(), t_.end(), t_s);
  const auto i = static_cast<std::size_t>(it - t_.begin()) - 1;
  const double h = t_[i + 1] - t_[i];
  hermite((t_s - t_[i]) / h, h, q_[i], q_[i + 1], m_[i], m_[i + 1], q, qd);
}

JointTrajectory trajectory_at_tcp_speed(const std::vector<Pose>& poses, const std::vector<JointVector>& q,
                                        double speed_m_s, const RobotModel& model, double hold_start_s) {
  if (!std::isfinite(speed_m_s) || !(speed_m_s > 0.0)) {
    throw InputError(fmt::format("trajectory: TCP speed must be a positive number of m/s (got {})", speed_m_s));
  }
  if (!std::isfinite(hold_start_s) || hold_start_s < 0.0) {
    throw InputError(fmt::format("trajectory: hold at the start must be >= 0 s (got {})", hold_start_s));
  }
  if (poses.size() != q.size() || poses.empty()) {
    throw InputError(fmt::format("trajectory: {} poses for {} joint points", poses.size(), q.size()));
  }
  for (std::size_t i = 0; i < poses.size(); ++i) {
    // The times come from the positions: a NaN one would surface as a time "not a finite number".
    if (!poses[i].translation().allFinite()) {
      throw InputError(fmt::format("trajectory: pose {} has a non-finite position", i));
    }
  }
  std::vector<double> t;
  std::vector<JointVector> points;
  if (hold_start_s > 0.0) {
    t.push_back(0.0);
    points.push_back(q.front());
  }
  t.push_back(hold_start_s);
  points.push_back(q.front());
  for (std::size_t i = 1; i < poses.size(); ++i) {
    const double d = (poses[i].translation() - poses[i - 1].translation()).norm();
    t.push_back(t.back() + std::max(d / speed_m_s, 1e-3));
    points.push_back(q[i]);
  }
  return JointTrajectory(std::move(t), std::move(points), model, fmt::format("path at {:g} mm/s", speed_m_s * 1e3));
}

}  // namespace deflex
