// `deflex online --link ur-rtde` end to end: the real program against the simulated cell's stand-in of a
// Universal Robots controller (cell/ur_rtde_controller.hpp, run here in real time over a loopback TCP
// connection the test accepts as the controller's RTDE server would): the RTDE handshake, one output
// package every 2 ms loop cycle, the script handing the newest registers to servoj with its lookahead
// as dead time, the speed limit as a protective stop and the watchdog. Under a constant force the arm
// is held at the program's start while the correction settles: the last commands carry the model's
// correction (K^-1 J^T W with a finite-difference Jacobian, computed here from the logged wrench)
// within 1 %, every target servoj took is within the per-cycle step limit computed here, and the
// session ends on its time limit. Bad UR options are refused naming them.
#include <filesystem>
#include <fstream>
#include <memory>

#include <gtest/gtest.h>

#include "cross/cli_child.hpp"
#include "cross/cli_runner.hpp"
#include "deflex/cell/ur_rtde_controller.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/transport/tcp_stream.hpp"
#include "online/fd_jacobian.hpp"
#include "support/sampled_speed.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;
using test::Child;
using test::run_in_real_time;
using test::spawn;

TEST(CliUrRtde, StreamsTheProgramWithTheModelsCorrectionWithinTheStepLimit) {
  const std::string dir = ::testing::TempDir() + "/cli_ur_rtde";
  fs::create_directories(dir);
  // Held 10 s at its start: the correction settles on a still arm.
  const std::string program_path = test::nominal_program(dir, 30.0, 10.0);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  TcpListener listener("127.0.0.1", 0);
  const std::string log = dir + "/log.csv";
  Child deflex;
  spawn(deflex,
        {test::kDeflex,
         "online",
         "--link",
         "ur-rtde",
         "--program",
         program_path,
         "--robot-host",
         "127.0.0.1",
         "--robot-port",
         std::to_string(listener.port()),
         "--period-ms",
         "2",
         "--force-source",
         "csv:" + test::held_force_csv(dir),
         "--loop",
         "--log",
         log,
         "--duration-s",
         "4",
         "--status-interval-s",
         "1"},
        dir + "/stderr.txt");
  std::unique_ptr<TcpStream> connection = listener.accept(10.0);
  ASSERT_NE(connection, nullptr) << test::slurp(dir + "/stderr.txt");
  cell::UrRtdeControllerConfig cc;
  cc.watchdog_s = 0.5;  // this machine is shared: a scheduling hiccup is not what is tested here
  cell::UrRtdeController controller(cc, program.points().front(), *connection);
  run_in_real_time(controller, 6.0);
  const int exit_code = deflex.wait();
  const std::string err = test::slurp(dir + "/stderr.txt");
  EXPECT_EQ(exit_code, 0) << err;
  EXPECT_EQ(controller.safety_mode(), 1) << controller.stopped();
  EXPECT_GT(controller.counters().servo_cycles, 300u);
  // The step limit computed here: the program's peak speed (0.1 % margin), the blend's 1.5 deg over the
  // 1 s ramp-in and the 3 deg/s correction rate, over the 2 ms cycle.
  const JointVector peak = test::sampled_peak_speed(program);
  const JointVector limit = 0.002 * (peak * 1.001).array() + 0.002 * deg_to_rad(1.5 + 3.0) + 1e-12;
  JointVector prev = program.points().front();
  for (const JointVector& q : controller.targets()) {
    for (int j = 0; j < 6; ++j) ASSERT_LE(std::abs(q[j] - prev[j]), limit[j]) << "joint " << j + 1;
    prev = q;
  }

  const CsvTable table = CsvTable::read_file(log);
  ASSERT_GT(table.rows(), 300u);
  const std::size_t last = table.rows() - 1;
  JointVector q(6), dtheta(6);
  for (int j = 0; j < 6; ++j) {
    q[j] = deg_to_rad(table.at(last, "q_nominal" + std::to_string(j + 1) + "_deg"));
    dtheta[j] = deg_to_rad(table.at(last, "dtheta" + std::to_string(j + 1) + "_deg"));
  }
  Wrench w;
  int k = 0;
  for (const char* c : {"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"}) w[k++] = table.at(last, c);
  ASSERT_GT(w.head<3>().norm(), 250.0);
  const JointVector expected = robot.compliance().cwiseProduct(test::fd_wap_jacobian(robot, q).transpose() * w);
  EXPECT_LT((dtheta - expected).cwiseAbs().maxCoeff(), 0.01 * expected.cwiseAbs().maxCoeff())
      << "sent " << dtheta.transpose() << "\nmodel " << expected.transpose();
  // servoj's last target is the last logged command.
  ASSERT_FALSE(controller.targets().empty());
  for (int j = 0; j < 6; ++j) {
    EXPECT_NEAR(rad_to_deg(controller.targets().back()[j]),
                table.at(last, "q_command" + std::to_string(j + 1) + "_deg"), 1e-4);
  }
  EXPECT_NE(err.find("UR RTDE to 127.0.0.1"), std::string::npos) << err;
}

TEST(CliUrRtde, BadUrOptionsAreRefusedNamingThem) {
  const std::string dir = ::testing::TempDir() + "/cli_ur_rtde_bad";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir);
  const std::string base = "online --link ur-rtde --program " + program_path +
                           " --robot-host 127.0.0.1 --force-source csv:" + test::kForceReplay;
  struct Case {
    std::string args;
    std::string words;
  };
  const Case cases[] = {
      {" --period-ms 2 --ur-lookahead-ms 10", "--ur-lookahead-ms"},
      {" --period-ms 2 --ur-gain 5000", "--ur-gain"},
      {" --period-ms 2 --ur-register-offset 12", "--ur-register-offset"},
      {" --period-ms 4", "--period-ms"},
      {" --period-ms 2 --robot-port 70000", "--robot-port"},
      {" --period-ms 2 --motoros2-group 1", "applies to --link motoros2-rt, not ur-rtde"},
  };
  for (const Case& c : cases) {
    const auto r = test::run_cli(base + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.words), std::string::npos) << c.args << "\n" << r.err;
  }
}

}  // namespace
}  // namespace deflex
