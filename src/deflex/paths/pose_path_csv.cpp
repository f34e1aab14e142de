// CSV reader for TCP pose paths.
#include "deflex/paths/pose_path_csv.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/model/csv_table.hpp"
#include "deflex/model/errors.hpp"

namespace deflex {
namespace {

std::vector<Pose> poses_from_table(const CsvTable& table) {
  table.require({"x_mm", "y_mm", "z_mm", "qw", "qx", "qy", "qz"});
  table.allow_only({"x_mm", "y_mm", "z_mm", "qw", "qx", "qy", "qz"});
  if (table.rows() > static_cast<std::size_t>(kMaxPathPoints)) {
    throw DataError(fmt::format("{}: {} path points; deflex takes up to {}", table.source(), table.rows(),
                                kMaxPathPoints));
  }
  if (table.rows() == 0) {
    throw DataError(fmt::format("{}: no pose rows", table.source()));
  }
  std::vector<Pose> poses;
  poses.reserve(table.rows());
  for (std::size_t r = 0; r < table.rows(); ++r) {
    Eigen::Quaterniond q(table.at(r, "qw"), table.at(r, "qx"), table.at(r, "qy"), table.at(r, "qz"));
    const double norm = q.norm();
    // Files written with 4-6 decimals are unit to ~1e-5; a larger error is a wrong number.
    if (std::abs(norm - 1.0) > 1e-3) {
      table.fail(r, "qw", fmt::format("quaternion (qw,qx,qy,qz) has norm {:.6f}, not 1", norm));
    }
    Pose p = Pose::Identity();
    p.linear() = q.normalized().toRotationMatrix();
    p.translation() = Vector3(table.at(r, "x_mm"), table.at(r, "y_mm"), table.at(r, "z_mm")) * 1e-3;
    poses.push_back(p);
  }
  return poses;
}

}  // namespace

std::vector<Pose> read_pose_path_csv(const std::string& path) { return poses_from_table(CsvTable::read_file(path)); }

std::vector<Pose> parse_pose_path_csv(const std::string& text, const std::string& source) {
  return poses_from_table(CsvTable::parse(text, source));
}

}  // namespace deflex
