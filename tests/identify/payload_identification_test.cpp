// Payload identification on synthetic static poses made here from a known mass, centre of gravity
// and bias; plus its CSV reader and its refusals.
#include <cmath>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "deflex/identify/payload_identification.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

Matrix3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

TEST(PayloadIdentification, RecoversMassCogAndBias) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  const double mass = 14.2;
  const Vector3 cog(0.013, -0.021, 0.118);
  Vector6 bias;
  bias << 4.0, -2.5, 7.0, 0.4, -0.3, 0.25;
  const Vector3 g(0, 0, -9.81);
  std::vector<PayloadObservation> poses;
  for (int i = 0; i < 24; ++i) {
    PayloadObservation o;
    o.base_R_sensor = random_rotation(rng);
    // Weight of the payload seen in the sensor frame, its moment about the sensor origin, the bias.
    const Vector3 w_s = o.base_R_sensor.transpose() * (mass * g);
    o.wrench_sensor.head<3>() = w_s + bias.head<3>();
    o.wrench_sensor.tail<3>() = cog.cross(w_s) + bias.tail<3>();
    for (int k = 0; k < 6; ++k) {
      o.wrench_sensor[k] += noise(rng) * (k < 3 ? 1.0 : 0.02);
    }
    poses.push_back(o);
  }
  const PayloadEstimate e = identify_payload(poses, true, g);
  EXPECT_NEAR(e.mass_kg, mass, 0.01);
  EXPECT_LT((e.cog_sensor_m - cog).norm(), 1e-3);
  EXPECT_LT((e.bias_sensor - bias).head<3>().norm(), 0.05);
  EXPECT_LT((e.bias_sensor - bias).tail<3>().norm(), 0.01);
  EXPECT_NEAR(e.force_residual_rms_N, 0.05, 0.02);
  EXPECT_TRUE(e.moments_used);

  // Without moments: mass and force bias only.
  const PayloadEstimate f = identify_payload(poses, false, g);
  EXPECT_NEAR(f.mass_kg, mass, 0.01);
  EXPECT_FALSE(f.moments_used);
  EXPECT_TRUE(f.cog_sensor_m.isZero());
}

TEST(PayloadIdentification, RefusesPosesThatDoNotExciteEveryUnknown) {
  std::vector<PayloadObservation> same(5);
  for (auto& o : same) {
    o.wrench_sensor << 0, 0, -100, 0, 0, 0;
  }
  EXPECT_THROW((void)identify_payload(same, false), InputError);
  EXPECT_THROW((void)identify_payload(std::vector<PayloadObservation>(2), false), InputError);
}

TEST(PayloadIdentification, CsvWithJointsUsesTheRobotAndSensorMount) {
  const RobotModel robot = builtin_irb6700();
  Workspace ws(robot);
  Pose flange_T_sensor = Pose::Identity();
  flange_T_sensor.linear() = Eigen::AngleAxisd(0.5, Vector3::UnitZ()).toRotationMatrix();
  const double mass = 9.0;
  const Vector3 cog(0.0, 0.01, 0.1);
  const std::string path = ::testing::TempDir() + "/payload_poses.csv";
  std::ofstream out(path);
  out.precision(17);
  out << "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm\n";
  const double poses_deg[6][6] = {{0, 0, 0, 0, 30, 0},   {0, 0, 0, 90, 45, 0}, {0, 10, 0, -90, 60, 90},
                                  {0, 0, 0, 0, -60, 45}, {0, 0, 0, 45, 90, 0}, {0, 0, 10, 180, 30, -90}};
  for (const auto& p : poses_deg) {
    JointVector q(6);
    for (int j = 0; j < 6; ++j) {
      q[j] = deg_to_rad(p[j]);
    }
    forward_kinematics(robot, ws, q);
    const Matrix3 R = ws.base_T_flange.linear() * flange_T_sensor.linear();
    const Vector3 f = R.transpose() * Vector3(0, 0, -9.81 * mass);
    const Vector3 m = cog.cross(f);
    for (double v : p) {
      out << v << ",";
    }
    out << f.x() + 1.0 << "," << f.y() << "," << f.z() << "," << m.x() << "," << m.y() << "," << m.z() << "\n";
  }
  out.close();
  bool has_moments = false;
  const auto obs = read_payload_observations(path, &robot, flange_T_sensor, Matrix6::Identity(), has_moments);
  ASSERT_TRUE(has_moments);
  const PayloadEstimate e = identify_payload(obs, true);
  EXPECT_NEAR(e.mass_kg, mass, 1e-6);
  EXPECT_LT((e.cog_sensor_m - cog).norm(), 1e-6);
  EXPECT_NEAR(e.bias_sensor[0], 1.0, 1e-6);

  std::ofstream bad(path);
  bad << "qw,qx,qy,qz,fx_N,fy_N,fz_N\n1,0,0,0,1,2,3\n0.5,0.5,0.5,0.6,1,2,3\n";
  bad.close();
  try {
    (void)read_payload_observations(path, nullptr, Pose::Identity(), Matrix6::Identity(), has_moments);
    ADD_FAILURE() << "non-unit quaternion accepted";
  } catch (const DataError& err) {
    EXPECT_NE(std::string(err.what()).find(":3"), std::string::npos) << err.what();
  }

  // Too few poses: the error names the file (identify_payload alone cannot).
  std::ofstream two(path);
  two << "qw,qx,qy,qz,fx_N,fy_N,fz_N\n1,0,0,0,1,2,3\n0,1,0,0,1,2,3\n";
  two.close();
  try {
    (void)read_payload_observations(path, nullptr, Pose::Identity(), Matrix6::Identity(), has_moments);
    ADD_FAILURE() << "two poses accepted";
  } catch (const DataError& err) {
    EXPECT_NE(std::string(err.what()).find(path + ": 2 static poses"), std::string::npos) << err.what();
  }
}

}  // namespace
}  // namespace deflex
