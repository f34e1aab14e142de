// deflex offline streams a path (pose file in, CSV out, a point at a time); its file must hold what
// the in-memory library calls give for the same poses, point for point, and a failure must leave no
// half-written file behind.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "cli_runner.hpp"
#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/paths/detail/pose_path_csv.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

// A wavy line of poses, long enough (about 1.6 MiB) that the reader's 1 MiB chunks split rows.
fs::path write_pose_file(std::size_t n) {
  const fs::path p = fs::temp_directory_path() / "deflex_stream_poses.csv";
  std::ofstream out(p);
  out << "x_mm,y_mm,z_mm,qw,qx,qy,qz\n";
  char line[160];
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) / static_cast<double>(n - 1);
    std::snprintf(line, sizeof line, "%.9f,%.9f,%.9f,0,0,1,0\n", 1400.0 + 200.0 * s, -300.0 + 600.0 * s,
                  900.0 + 40.0 * std::sin(12.0 * s));
    out << line;
  }
  return p;
}

TEST(OfflineStream, TheStreamedFileHoldsTheInMemoryResultPointForPoint) {
  const std::size_t n = 25000;
  const fs::path poses_file = write_pose_file(n);
  const fs::path out = fs::temp_directory_path() / "deflex_stream_out.csv";
  const test::CliRun r = test::run_cli("offline --path " + poses_file.string() +
                                       " --force constant:fx_N=120,fz_N=-450 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;

  // The library, all in memory: poses, path IK, compensation.
  const RobotModel model = builtin_irb6700();
  const std::vector<Pose> poses = read_pose_path_csv(poses_file.string());
  ASSERT_EQ(poses.size(), n);
  const JointPath path = solve_path_ik(model, poses, IkRequest{});
  Wrench w = Wrench::Zero();
  w[0] = 120.0;
  w[2] = -450.0;
  const OfflineResult expected = compensate_path(model, path, poses, ConstantWrenchModel(w));

  const CsvTable t = CsvTable::read_file(out.string());
  ASSERT_EQ(t.rows(), n);
  double worst_deg = 0.0, worst_mm = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_EQ(t.at(i, "index"), static_cast<double>(i));
    const OfflinePoint& p = expected.points[i];
    for (int j = 0; j < model.dof(); ++j) {
      worst_deg =
          std::max(worst_deg, std::abs(t.at(i, fmt::format("q{}_des_deg", j + 1)) - rad_to_deg(p.q_desired[j])));
      worst_deg =
          std::max(worst_deg, std::abs(t.at(i, fmt::format("q{}_cmd_deg", j + 1)) - rad_to_deg(p.q_command[j])));
    }
    worst_mm = std::max(worst_mm, std::abs(t.at(i, "deflection_mm") - p.predicted_deflection.head<3>().norm() * 1e3));
  }
  // %.10g of values up to 180 deg: 1e-7 deg; of deflections below 10 mm: 1e-9 mm.
  EXPECT_LT(worst_deg, 2e-7);
  EXPECT_LT(worst_mm, 1e-8);
  EXPECT_NE(r.out.find("points: 25000"), std::string::npos) << r.out;
  fs::remove(out);
  fs::remove(poses_file);
}

TEST(OfflineStream, AnUnreachablePointHalfwayLeavesNoFileBehind) {
  const fs::path poses_file = fs::temp_directory_path() / "deflex_stream_unreachable.csv";
  {
    std::ofstream p(poses_file);
    p << "x_mm,y_mm,z_mm,qw,qx,qy,qz\n";
    for (int i = 0; i < 300; ++i) {
      p << 1500 << "," << i << ",1000,0,0,1,0\n";
    }
    p << "9000,0,1000,0,0,1,0\n";  // 9 m away: out of reach
  }
  const fs::path out = fs::temp_directory_path() / "deflex_stream_unreachable_out.csv";
  const test::CliRun r =
      test::run_cli("offline --path " + poses_file.string() + " --force constant:fz_N=-300 -o " + out.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("path point 300"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out)) << "a half-written output stayed";
  fs::remove(poses_file);
}

}  // namespace
}  // namespace deflex
