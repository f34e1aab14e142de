// A path's TCP poses one at a time: circles and lines computed point by point, pose files read row
// by row, so a path of ten million points costs no memory of its own (deflex offline streams them).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "deflex/paths/circle_path.hpp"
#include "deflex/paths/line_path.hpp"
#include "deflex/text/csv_table.hpp"

namespace deflex {

/// The most poses held in memory at once (sample_circle, sample_line, read_pose_path_csv, and deflex
/// offline's RAPID module and timed trajectories): about 1 GB at 1 kB a point. A path streamed to
/// CSV holds none of them and may be longer.
inline constexpr std::size_t kMaxHeldPathPoints = 1'000'000;

/// Throws InputError "path: more than N poses to hold in memory..." when `held` reaches the bound.
void check_held_path_points(std::size_t held);

/// Thread safety: one thread at a time (next() moves it on), for every source.
class PoseSource {
 public:
  virtual ~PoseSource() = default;
  /// The next base_T_tcp pose (m); false after the last. Throws InputError / DataError for a bad one.
  virtual bool next(Pose& out) = 0;
  /// Number of poses, when known before reading (sampled paths); none for a file.
  [[nodiscard]] virtual std::optional<std::size_t> size() const { return std::nullopt; }

 protected:
  PoseSource() = default;
};

/// The poses of sample_circle(), in the same order and to the last bit.
/// Thread safety: one thread at a time (next() moves it on).
class CirclePoseSource final : public PoseSource {
 public:
  /// Throws InputError for a radius, centre, point count or orientation sample_circle refuses.
  CirclePoseSource(const CirclePath& circle, const Eigen::Quaterniond& tcp_orientation);
  bool next(Pose& out) override;
  [[nodiscard]] std::optional<std::size_t> size() const override { return static_cast<std::size_t>(circle_.points); }

 private:
  CirclePath circle_;
  Eigen::Matrix3d rotation_;
  Vector3 u_, v_;
  double sign_ = 1.0, step_ = 0.0;
  int index_ = 0;
};

/// The poses of sample_line(), in the same order and to the last bit.
/// Thread safety: one thread at a time (next() moves it on).
class LinePoseSource final : public PoseSource {
 public:
  LinePoseSource(const LinePath& line, const Eigen::Quaterniond& tcp_orientation);
  bool next(Pose& out) override;
  [[nodiscard]] std::optional<std::size_t> size() const override { return static_cast<std::size_t>(line_.points); }

 private:
  LinePath line_;
  Eigen::Matrix3d rotation_;
  int index_ = 0;
};

/// Poses held by the caller, in order. It keeps a reference to them (the ownership rule of
/// docs/architecture.md), so a temporary vector does not compile.
/// Thread safety: one thread at a time (next() moves it on); threads may share the poses.
class PoseListSource final : public PoseSource {
 public:
  explicit PoseListSource(const std::vector<Pose>& poses) : poses_(poses) {}
  explicit PoseListSource(std::vector<Pose>&& poses) = delete;
  bool next(Pose& out) override {
    if (index_ >= poses_.size()) return false;
    out = poses_[index_++];
    return true;
  }
  [[nodiscard]] std::optional<std::size_t> size() const override { return poses_.size(); }

 private:
  const std::vector<Pose>& poses_;
  std::size_t index_ = 0;
};

/// The poses of read_pose_path_csv(), read a row at a time (columns x_mm,y_mm,z_mm,qw,qx,qy,qz in
/// any order). Throws DataError naming the file, line and column, as read_pose_path_csv does.
/// Thread safety: one thread at a time (next() reads the file on).
class PoseCsvSource final : public PoseSource {
 public:
  explicit PoseCsvSource(const std::string& path);
  /// From text held in memory; `source` names it in messages.
  PoseCsvSource(std::string text, std::string source);
  bool next(Pose& out) override;
  /// The file's line of the last pose read.
  [[nodiscard]] int line() const { return reader_.line(); }

 private:
  void find_columns();

  CsvReader reader_;
  std::size_t x_, y_, z_, qw_, qx_, qy_, qz_;
  std::size_t rows_ = 0;
};

}  // namespace deflex
