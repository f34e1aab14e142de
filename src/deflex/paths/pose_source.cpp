// Poses a point at a time.
#include "deflex/paths/pose_source.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/paths/detail/pose_path_csv.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

void check_held_path_points(std::size_t held) {
  if (held >= kMaxHeldPathPoints) {
    throw InputError(
        fmt::format("path: more than {} poses to hold in memory; deflex offline streams longer paths to "
                    "CSV (without --rapid, --joint-trajectory and --nominal-trajectory)",
                    kMaxHeldPathPoints));
  }
}

CirclePoseSource::CirclePoseSource(const CirclePath& circle, const Eigen::Quaterniond& tcp_orientation)
    : circle_(circle) {
  if (!std::isfinite(circle.radius_m) || circle.radius_m <= 0.0) {
    throw InputError(fmt::format("circle: radius must be positive and finite (got {} m)", circle.radius_m));
  }
  if (!circle.centre_m.allFinite() || !std::isfinite(circle.start_angle_rad)) {
    throw InputError("circle: centre and start angle must be finite");
  }
  if (circle.points < 3) {
    throw InputError(fmt::format("circle: needs at least 3 points (got {})", circle.points));
  }
  rotation_ = checked_unit_quaternion(tcp_orientation, "circle: TCP orientation").toRotationMatrix();
  circle_frame(circle, u_, v_);
  sign_ = circle.clockwise ? -1.0 : 1.0;
  step_ = 2.0 * kPi / static_cast<double>(circle.points - 1);
}

bool CirclePoseSource::next(Pose& out) {
  if (index_ >= circle_.points) {
    return false;
  }
  // The last point is set to the first exactly (not by rounding of cos/sin at 2 pi), so a closed
  // path really closes.
  const double angle = circle_.start_angle_rad + sign_ * step_ * static_cast<double>(index_ % (circle_.points - 1));
  out = Pose::Identity();
  out.linear() = rotation_;
  out.translation() = circle_.centre_m + circle_.radius_m * (std::cos(angle) * u_ + std::sin(angle) * v_);
  ++index_;
  return true;
}

LinePoseSource::LinePoseSource(const LinePath& line, const Eigen::Quaterniond& tcp_orientation) : line_(line) {
  if (line.points < 2) {
    throw InputError(fmt::format("line: needs at least 2 points (got {})", line.points));
  }
  if (!line.start_m.allFinite() || !line.end_m.allFinite()) {
    throw InputError("line: start and end must be finite");
  }
  if ((line.end_m - line.start_m).norm() < 1e-9) {
    throw InputError("line: start and end coincide");
  }
  rotation_ = checked_unit_quaternion(tcp_orientation, "line: TCP orientation").toRotationMatrix();
}

bool LinePoseSource::next(Pose& out) {
  if (index_ >= line_.points) {
    return false;
  }
  const double s = static_cast<double>(index_) / static_cast<double>(line_.points - 1);
  out = Pose::Identity();
  out.linear() = rotation_;
  out.translation() = (1.0 - s) * line_.start_m + s * line_.end_m;
  ++index_;
  return true;
}

PoseCsvSource::PoseCsvSource(const std::string& path) : reader_(path) { find_columns(); }

PoseCsvSource::PoseCsvSource(std::string text, std::string source) : reader_(std::move(text), std::move(source)) {
  find_columns();
}

void PoseCsvSource::find_columns() {
  reader_.require({"x_mm", "y_mm", "z_mm", "qw", "qx", "qy", "qz"});
  reader_.allow_only({"x_mm", "y_mm", "z_mm", "qw", "qx", "qy", "qz"});
  x_ = reader_.column("x_mm");
  y_ = reader_.column("y_mm");
  z_ = reader_.column("z_mm");
  qw_ = reader_.column("qw");
  qx_ = reader_.column("qx");
  qy_ = reader_.column("qy");
  qz_ = reader_.column("qz");
}

bool PoseCsvSource::next(Pose& out) {
  if (rows_ >= static_cast<std::size_t>(kMaxPathPoints)) {
    throw DataError(fmt::format("{}: more than {} path points; deflex takes up to {}", reader_.source(), kMaxPathPoints,
                                kMaxPathPoints));
  }
  if (!reader_.next()) {
    if (rows_ == 0) {
      throw DataError(fmt::format("{}: no pose rows", reader_.source()));
    }
    return false;
  }
  ++rows_;
  const Eigen::Quaterniond q(reader_[qw_], reader_[qx_], reader_[qy_], reader_[qz_]);
  const double norm = q.norm();
  // Files written with 4-6 decimals are unit to ~1e-5; a larger error is a wrong number.
  if (std::abs(norm - 1.0) > 1e-3) {
    reader_.fail("qw", fmt::format("quaternion (qw,qx,qy,qz) has norm {:.6f}, not 1", norm));
  }
  out = Pose::Identity();
  out.linear() = q.normalized().toRotationMatrix();
  out.translation() = Vector3(reader_[x_], reader_[y_], reader_[z_]) * 1e-3;
  return true;
}

}  // namespace deflex
