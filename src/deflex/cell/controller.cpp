// The simulated controller's program interpolation, lap schedule and correction channel.
#include "deflex/cell/controller.hpp"

#include <cmath>

#include "deflex/model/errors.hpp"

namespace deflex::cell {

JointProgram::JointProgram(std::vector<JointVector> points) : points_(std::move(points)) {
  if (points_.size() < 4) {
    throw InputError("a joint program needs at least 4 points");
  }
}

void JointProgram::at(double angle_rad, JointVector& q) const {
  const int n = size();
  const double u = angle_rad / (2.0 * kPi) * n;
  const double fl = std::floor(u);
  const double s = u - fl;
  int i1 = static_cast<int>(std::fmod(fl, static_cast<double>(n)));
  if (i1 < 0) i1 += n;
  const int i0 = (i1 + n - 1) % n, i2 = (i1 + 1) % n, i3 = (i1 + 2) % n;
  const auto& p0 = points_[static_cast<std::size_t>(i0)];
  const auto& p1 = points_[static_cast<std::size_t>(i1)];
  const auto& p2 = points_[static_cast<std::size_t>(i2)];
  const auto& p3 = points_[static_cast<std::size_t>(i3)];
  // Uniform Catmull-Rom: passes through every programmed point with continuous velocity.
  const double s2 = s * s, s3 = s2 * s;
  q = 0.5 * ((2.0 * p1) + (-p0 + p2) * s + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s2 +
             (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * s3);
}

double LapSchedule::motion_s() const { return omega_rad_s > 0 ? 2.0 * kPi * (laps_cw + laps_ccw) / omega_rad_s : 0.0; }

double LapSchedule::angle(double t_s) const {
  const double tm = t_s - settle_s;
  if (tm <= 0.0) return 0.0;
  const double t_cw = 2.0 * kPi * laps_cw / omega_rad_s;
  if (tm <= t_cw) return -omega_rad_s * tm;
  const double t_end = motion_s();
  return -omega_rad_s * t_cw + omega_rad_s * (std::min(tm, t_end) - t_cw);
}

int LapSchedule::direction(double t_s) const {
  const double tm = t_s - settle_s;
  if (tm <= 0.0 || tm > motion_s()) return 0;
  return tm <= 2.0 * kPi * laps_cw / omega_rad_s ? -1 : 1;
}

bool CorrectionChannel::push(const CorrectionMessage& m) {
  if (count_ == buffer_.size()) return false;
  buffer_[(head_ + count_) % buffer_.size()] = m;
  ++count_;
  return true;
}

bool CorrectionChannel::pop_arrived(double now_s, CorrectionMessage& out) {
  bool got = false;
  while (count_ > 0 && buffer_[head_].arrival_s <= now_s) {
    out = buffer_[head_];
    head_ = (head_ + 1) % buffer_.size();
    --count_;
    got = true;
  }
  return got;
}

}  // namespace deflex::cell
