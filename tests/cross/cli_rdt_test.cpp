// deflex's command line on a real RDT sensor's protocol, against the Python stand-in sensor
// (examples/online/rdt_sensor_standin.py, real UDP and HTTP on loopback):
//   - identify-payload records static poses off the sensor (--force-source rdt: --record), and the
//     payload identified from them is the one the test gave the stand-in (closed form: the reading at
//     a pose is m sensor_R_base g + bias, moment c x m g_s + bias);
//   - `deflex online --link egm-joint --force-source rdt:` streams against the EGM stand-in with the
//     sensor's counts turned into newtons by the calibration page (in lbf and lbf-in: a wrong unit
//     would be off by 4.4x), the cycle log showing the force the sensor was set to.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "cross/cli_child.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/model/types.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/transport/udp_transport.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;
using test::Child;

using test::kDeflex;
const std::string kStandin = std::string(DEFLEX_SOURCE_DIR) + "/examples/online/rdt_sensor_standin.py";
constexpr double kLbfInN = 4.4482216152605;        // 1 lbf in N
constexpr double kLbfInInNm = 0.1129848290276167;  // 1 lbf-in in Nm

// The stand-in sensor streaming a constant wrench (N, Nm, sensor frame), in lbf and lbf-in counts.
struct Sensor {
  Child child;
  int rdt_port = -1, http_port = -1;
  Sensor(const Vector6& wrench, const std::string& dir, double noise_lbf = 0.0) {
    const std::string w =
        fmt::format("{:.9f},{:.9f},{:.9f},{:.9f},{:.9f},{:.9f}", wrench[0] / kLbfInN, wrench[1] / kLbfInN,
                    wrench[2] / kLbfInN, wrench[3] / kLbfInInNm, wrench[4] / kLbfInInNm, wrench[5] / kLbfInInNm);
    test::spawn(child,
                {"/usr/bin/env",
                 "python3",
                 kStandin,
                 "--port",
                 "0",
                 "--http-port",
                 "0",
                 "--rate",
                 "1000",
                 "--force-unit",
                 "lbf",
                 "--counts-per-force",
                 "100000",
                 "--torque-unit",
                 "lbf-in",
                 "--counts-per-torque",
                 "100000",
                 "--wrench=" + w,
                 "--noise",
                 fmt::format("{}", noise_lbf)},
                dir + "/sensor_stderr.txt");
    rdt_port = test::port_of(child, "RDT on 127.0.0.1:");
    http_port = test::port_of(child, "HTTP on 127.0.0.1:");
  }
  [[nodiscard]] std::string args() const {
    return fmt::format("--force-source rdt:127.0.0.1:{} --rdt-calibration http://127.0.0.1:{}/netftapi2.xml", rdt_port,
                       http_port);
  }
};

TEST(CliRdt, IdentifyPayloadFromPosesRecordedOffTheSensor) {
  const std::string dir = ::testing::TempDir() + "/cli_rdt_payload";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const RobotModel robot = builtin_irb6700();
  Workspace ws(robot);
  // The payload and the sensor's offset the stand-in reads (sensor at the flange).
  const double mass_kg = 8.5;
  const Vector3 cog_m(0.004, -0.002, 0.090);
  Vector6 bias;
  bias << 1.5, -0.8, 2.2, 0.12, -0.05, 0.03;
  const Vector3 g(0.0, 0.0, -9.81);
  const std::vector<std::vector<double>> poses_deg{
      {0, 20, 10, 0, 60, 0},      {30, 10, 20, 40, -50, 90},   {-40, 30, 0, -60, 80, -30}, {10, 0, 30, 90, 45, 180},
      {60, 25, 15, -90, -70, 45}, {-20, 15, 5, 150, 30, -120}, {0, 35, -10, 0, -30, 0}};
  const std::string poses = dir + "/poses.csv";
  for (std::size_t p = 0; p < poses_deg.size(); ++p) {
    JointVector q(6);
    for (int j = 0; j < 6; ++j) q[j] = poses_deg[p][static_cast<std::size_t>(j)] * kPi / 180.0;
    forward_kinematics(robot, ws, q);
    const Matrix3 sensor_R_base = ws.base_T_flange.linear().transpose();
    const Vector3 f = mass_kg * (sensor_R_base * g);
    Vector6 reading;
    reading << f + bias.head<3>(), cog_m.cross(f) + bias.tail<3>();
    Sensor sensor(reading, dir, 0.01);
    ASSERT_GT(sensor.rdt_port, 0) << test::slurp(sensor.child.stderr_path);
    const std::string joints = fmt::format("{}", fmt::join(poses_deg[p], ","));
    const auto r = test::run_cli(
        fmt::format("identify-payload {} --joints-deg {} --record {} --window-s 0.3", sensor.args(), joints, poses));
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    EXPECT_NE(r.out.find(fmt::format("pose {} recorded into", p + 1)), std::string::npos) << r.out;
  }
  const auto r = test::run_cli(fmt::format("identify-payload --data {} -o {}/payload.yaml --json", poses, dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_NEAR(doc["mass_kg"].get<double>(), mass_kg, 0.01);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(doc["cog_sensor_m"][i].get<double>(), cog_m[i], 0.001) << i;
    EXPECT_NEAR(doc["bias_sensor"][i].get<double>(), bias[i], 0.05) << i;
    EXPECT_NEAR(doc["bias_sensor"][i + 3].get<double>(), bias[i + 3], 0.005) << i;
  }
  EXPECT_EQ(doc["poses"].get<int>(), static_cast<int>(poses_deg.size()));

  // A pose is only added to a file of the same columns; the file is left as it was.
  const std::string before = test::slurp(poses);
  const std::string foreign = std::string(DEFLEX_SOURCE_DIR) + "/examples/online/payload_poses.csv";
  {
    Sensor sensor(Vector6::Zero(), dir);
    const auto bad = test::run_cli(
        fmt::format("identify-payload {} --joints-deg 0,20,10,0,60,0 --record {}", sensor.args(), foreign));
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("has the columns 'qw,qx,qy,qz"), std::string::npos) << bad.err;
  }
  EXPECT_EQ(test::slurp(poses), before);
}

TEST(CliRdt, OnlineOverRdtAgainstTheEgmStandIn) {
  const std::string dir = ::testing::TempDir() + "/cli_rdt_online";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir, 50.0, 0.2);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  Vector6 wrench;
  wrench << 120.0, -80.0, -450.0, 0.0, 0.0, 0.0;  // N, sensor frame
  Sensor sensor(wrench, dir);
  ASSERT_GT(sensor.rdt_port, 0) << test::slurp(sensor.child.stderr_path);
  const std::string log = dir + "/log.csv";
  Child deflex;
  std::vector<std::string> args{kDeflex,      "online", "--link", "egm-joint", "--program", program_path,
                                "--egm-port", "0",      "--log",  log,         "--json"};
  for (const std::string& a :
       {std::string("--force-source"), fmt::format("rdt:127.0.0.1:{}", sensor.rdt_port),
        std::string("--rdt-calibration"), fmt::format("http://127.0.0.1:{}/netftapi2.xml", sensor.http_port)}) {
    args.push_back(a);
  }
  test::spawn(deflex, args, dir + "/stderr.txt", dir + "/stdout.json");
  const int port = test::port_of(deflex, "EGM on 127.0.0.1:");
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  UdpTransport transport("127.0.0.1", 0);
  cell::ControllerConfig cc;
  cell::EgmPositionGuidanceController controller(cc, program.points().front(), transport,
                                                 make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  test::run_in_real_time(controller, 2.0);
  EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);
  const std::string err = test::slurp(deflex.stderr_path);
  EXPECT_NE(err.find("RDT sensor at 127.0.0.1"), std::string::npos) << err;

  const auto summary = nlohmann::json::parse(test::slurp(dir + "/stdout.json"));
  EXPECT_EQ(summary["stop_reason"], "user-stop");
  EXPECT_GT(summary["force_samples"]["ok"].get<double>(), 1000.0) << summary.dump();
  const CsvTable table = CsvTable::read_file(log);
  ASSERT_GT(table.rows(), 200u);
  // Once the filter has settled: the measured force in the base frame has the magnitude the sensor was
  // set to (a rotation keeps it), in newtons.
  int checked = 0;
  for (std::size_t r = table.rows() / 2; r < table.rows(); ++r) {
    const Vector3 f(table.at(r, "meas_fx_N"), table.at(r, "meas_fy_N"), table.at(r, "meas_fz_N"));
    EXPECT_NEAR(f.norm(), wrench.head<3>().norm(), 0.5) << "row " << r;
    ++checked;
  }
  EXPECT_GT(checked, 100);
  // The invariants as for every source, read off the log: every command within the 0.5 deg bound of
  // the nominal it was sent for (the program plus the ramp-in blend), and no step between consecutive
  // commands above the per-cycle limit the test computes (test::cli_step_limit_deg: the program's
  // peak speed sampled every 0.5 ms, the blend's 1.5 x 1 deg over 1 s, the correction's 3 deg/s, over
  // 4 ms).
  const JointVector limit_deg = test::cli_step_limit_deg(program);
  double worst_bound = 0.0, worst_step = 0.0;
  for (std::size_t r = 0; r < table.rows(); ++r) {
    if (table.at(r, "replied") == 0.0) continue;
    for (int j = 1; j <= 6; ++j) {
      const std::string n = std::to_string(j) + "_deg";
      worst_bound = std::max(worst_bound, std::abs(table.at(r, "q_command" + n) - table.at(r, "q_nominal" + n) -
                                                   table.at(r, "q_blend" + n)));
      if (r > 0 && table.at(r - 1, "replied") != 0.0) {
        worst_step = std::max(
            worst_step, std::abs(table.at(r, "q_command" + n) - table.at(r - 1, "q_command" + n)) / limit_deg[j - 1]);
      }
    }
  }
  EXPECT_LE(worst_bound, 0.5 + 1e-6);
  EXPECT_GT(worst_bound, 0.005);  // the sensor's force was compensated
  EXPECT_LE(worst_step, 1.0);
}

}  // namespace
}  // namespace deflex
