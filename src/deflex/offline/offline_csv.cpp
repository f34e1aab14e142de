// Writing offline compensation results as CSV.
#include "deflex/offline/offline_csv.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/offline/detail/quaternion_sign.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

// Rounding noise (1e-15 mm, -0 deg) written as 0, so files diff and read cleanly.
double clean(double v) { return std::abs(v) < 1e-11 ? 0.0 : v; }

void add_pose(std::vector<double>& row, const Pose& p, const Eigen::Quaterniond& q) {
  const Vector3 t = p.translation() * 1e3;
  row.insert(row.end(),
             {clean(t.x()), clean(t.y()), clean(t.z()), clean(q.w()), clean(q.x()), clean(q.y()), clean(q.z())});
}

}  // namespace

std::vector<std::string> offline_csv_columns(int dof) {
  std::vector<std::string> c{"index"};
  for (const char* which : {"des", "cmd"}) {
    for (int j = 1; j <= dof; ++j) {
      c.push_back(fmt::format("q{}_{}_deg", j, which));
    }
  }
  for (const char* which : {"des", "cmd"}) {
    for (const char* axis : {"x", "y", "z"}) {
      c.push_back(fmt::format("{}_{}_mm", axis, which));
    }
    for (const char* comp : {"qw", "qx", "qy", "qz"}) {
      c.push_back(fmt::format("{}_{}", comp, which));
    }
  }
  c.insert(c.end(), {"cf1_cmd", "cf4_cmd", "cf6_cmd", "cfx_cmd", "fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm",
                     "deflection_x_mm", "deflection_y_mm", "deflection_z_mm", "deflection_rx_mrad",
                     "deflection_ry_mrad", "deflection_rz_mrad", "deflection_mm", "residual_mm", "residual_mrad"});
  return c;
}

namespace {

std::vector<std::string> with_extra(int dof, const std::vector<std::string>& extra) {
  std::vector<std::string> c = offline_csv_columns(dof);
  c.insert(c.end(), extra.begin(), extra.end());
  return c;
}

}  // namespace

OfflineCsvWriter::OfflineCsvWriter(OutputFile& out, int dof, const std::string& robot_name,
                                   const std::string& force_description, bool predicted)
    : OfflineCsvWriter(out, dof, robot_name, force_description, predicted, {}, "") {}

OfflineCsvWriter::OfflineCsvWriter(OutputFile& out, int dof, const std::string& robot_name,
                                   const std::string& force_description, bool predicted,
                                   const std::vector<std::string>& extra_columns, const std::string& note)
    : dof_(dof), extra_(extra_columns.size()), out_(out, with_extra(dof, extra_columns)) {
  out_.comment(
      fmt::format("deflex offline: robot {}; force {}; wrench in the base frame, moment about the WAP; "
                  "deflection = loaded minus unloaded TCP pose when commanded to the desired joints{}{}",
                  robot_name, force_description, predicted ? "" : " (not predicted: columns are zero)", note));
  row_.reserve(offline_csv_columns(dof).size() + extra_);
}

void OfflineCsvWriter::write(std::size_t index, const OfflinePoint& p, std::span<const double> extra) {
  if (extra.size() != extra_) {
    throw InputError(fmt::format("path point {}: {} extra values for {} extra columns", index, extra.size(), extra_));
  }
  if (p.q_desired.size() != dof_ || p.q_command.size() != dof_) {
    throw InputError(fmt::format("path point {}: {} desired and {} command joints for a {}-joint file", index,
                                 p.q_desired.size(), p.q_command.size(), dof_));
  }
  if (index == 0 || !have_quaternion_) {
    q_desired_ = canonical_quaternion(p.tcp_desired);
    have_quaternion_ = true;
  }
  row_.clear();
  row_.push_back(static_cast<double>(index));
  for (const JointVector* q : {&p.q_desired, &p.q_command}) {
    for (int j = 0; j < dof_; ++j) {
      row_.push_back(clean(rad_to_deg((*q)[j])));
    }
  }
  // Signs follow the path and the command follows its desired pose: no flips between columns.
  q_desired_ = quaternion_near(p.tcp_desired, q_desired_);
  add_pose(row_, p.tcp_desired, q_desired_);
  add_pose(row_, p.tcp_command, quaternion_near(p.tcp_command, q_desired_));
  const ArmConfiguration& c = p.configuration_command;
  row_.insert(row_.end(), {static_cast<double>(c.cf1), static_cast<double>(c.cf4), static_cast<double>(c.cf6),
                           static_cast<double>(c.cfx)});
  for (int k = 0; k < 6; ++k) {
    row_.push_back(clean(p.wrench_base[k]));
  }
  for (int k = 0; k < 6; ++k) {
    row_.push_back(clean(p.predicted_deflection[k] * 1e3));  // m -> mm, rad -> mrad
  }
  row_.push_back(p.predicted_deflection.head<3>().norm() * 1e3);
  row_.push_back(p.predicted_residual.head<3>().norm() * 1e3);
  row_.push_back(p.predicted_residual.tail<3>().norm() * 1e3);
  row_.insert(row_.end(), extra.begin(), extra.end());
  out_.row(row_);
}

void OfflineCsvWriter::finish() { out_.finish(); }

void write_offline_csv(const OfflineResult& result, const std::string& path) {
  if (result.points.empty()) {
    throw InputError(fmt::format("{}: no compensated points to write", path));
  }
  OutputFile file(path);
  OfflineCsvWriter out(file, static_cast<int>(result.points.front().q_desired.size()), result.robot_name,
                       result.force_description, result.predicted);
  for (std::size_t i = 0; i < result.points.size(); ++i) {
    out.write(i, result.points[i]);
  }
  out.finish();
  file.commit();
}

}  // namespace deflex
