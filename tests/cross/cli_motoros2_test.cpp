// `deflex online --link motoros2-rt` end to end: the real program against the simulated cell's
// stand-in of Yaskawa's MotoROS2 real-time controller (cell/motoros2_rt_controller.hpp, run here in real
// time over loopback UDP), which takes one command an interpolation clock, answers each once, drops
// its session on a sequence jump, a second sender or garbage, and moves its command position by each
// increment taken. Under a constant force the arm is held at the program's start while the correction
// settles: the last commands carry the model's correction (K^-1 J^T W with a finite-difference
// Jacobian, computed here from the logged wrench) within 1 %, every increment the controller took is
// within the per-cycle step limit computed here, and the session ends on its time limit. The link is
// lock-step, so a host that stalls deflex only pauses the stream (the controller applies nothing
// meanwhile): nothing here depends on this machine's scheduling. Bad MotoROS2 options are refused
// naming them.
#include <filesystem>
#include <fstream>
#include <memory>

#include <gtest/gtest.h>

#include "cross/cli_child.hpp"
#include "cross/cli_runner.hpp"
#include "deflex/cell/motoros2_rt_controller.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/transport/udp_transport.hpp"
#include "online/fd_jacobian.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;
using test::Child;
using test::run_in_real_time;
using test::spawn;

TEST(CliMotoros2, StreamsTheProgramWithTheModelsCorrectionWithinTheStepLimit) {
  const std::string dir = ::testing::TempDir() + "/cli_motoros2";
  fs::create_directories(dir);
  // Held 10 s at its start: the correction settles on a still arm.
  const std::string program_path = test::nominal_program(dir, 30.0, 10.0);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  UdpTransport transport("127.0.0.1", 0);
  cell::Motoros2RtController controller({}, program.points().front(), transport);
  const std::string log = dir + "/log.csv";
  Child deflex;
  spawn(deflex,
        {test::kDeflex, "online", "--link", "motoros2-rt", "--program", program_path, "--robot-host", "127.0.0.1",
         "--robot-port", std::to_string(transport.local_address().port), "--force-source",
         "csv:" + test::held_force_csv(dir), "--loop", "--log", log, "--duration-s", "4", "--status-interval-s", "1"},
        dir + "/stderr.txt");
  run_in_real_time(controller, 6.0);
  const int exit_code = deflex.wait();
  const std::string err = test::slurp(dir + "/stderr.txt");
  EXPECT_EQ(exit_code, 0) << err;
  EXPECT_EQ(controller.dropped(), "") << err;
  EXPECT_GT(controller.counters().taken, 300u);
  const JointVector limit_deg = test::cli_step_limit_deg(program);
  for (const JointVector& inc : controller.increments()) {
    for (int j = 0; j < 6; ++j) ASSERT_LE(rad_to_deg(std::abs(inc[j])), limit_deg[j]) << "joint " << j + 1;
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
  // The controller's command position is the last logged command: the increments reached it.
  for (int j = 0; j < 6; ++j) {
    EXPECT_NEAR(rad_to_deg(controller.command_position()[j]),
                table.at(last, "q_command" + std::to_string(j + 1) + "_deg"), 1e-4);
  }
  EXPECT_NE(err.find("MotoROS2 real-time to 127.0.0.1"), std::string::npos) << err;
}

TEST(CliMotoros2, BadMotoros2OptionsAreRefusedNamingThem) {
  const std::string dir = ::testing::TempDir() + "/cli_motoros2_bad";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir);
  const std::string base = "online --link motoros2-rt --program " + program_path +
                           " --robot-host 127.0.0.1 --force-source csv:" + test::kForceReplay;
  struct Case {
    std::string args;
    std::string words;
  };
  const Case cases[] = {
      {" --motoros2-group 8", "--motoros2-group"},
      {" --motoros2-tool 64", "--motoros2-tool"},
      {" --motoros2-resend-ms 0", "--motoros2-resend-ms"},
      {" --motoros2-max-truncations -1", "--motoros2-max-truncations"},
      {" --robot-port 70000", "--robot-port"},
      {" --fanuc-version 3", "applies to --link fanuc-j519, not motoros2-rt"},
  };
  for (const Case& c : cases) {
    const auto r = test::run_cli(base + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.words), std::string::npos) << c.args << "\n" << r.err;
  }
  const auto no_host = test::run_cli("online --link motoros2-rt --program " + program_path +
                                     " --force-source csv:" + test::kForceReplay);
  EXPECT_EQ(no_host.exit_code, 2);
  EXPECT_NE(no_host.err.find("--robot-host"), std::string::npos) << no_host.err;
}

}  // namespace
}  // namespace deflex
