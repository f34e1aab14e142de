// `deflex online` end to end, the real program against stand-in controllers that behave as ABB's do
// (the simulated cell's, run in this test in real time over loopback UDP): with --link egm-joint the
// arm is driven through the nominal program written by `deflex offline`, every logged command stays
// within the bound of a nominal that is the program itself (never the controller's echo); a start
// away from the program is refused with the joints named and nothing is sent; with --link egm-path
// the controller runs its own program and gets absolute offsets. Bad options and programs are refused
// before anything runs, naming the option, file, line or joint.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "cross/cli_child.hpp"
#include "cross/cli_runner.hpp"
#include "deflex/cell/egm_path_controller.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/transport/udp_transport.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

using test::Child;
using test::run_in_real_time;
using test::spawn;

// The EGM port deflex bound, from its start-up line.
int egm_port_of(const Child& c) { return test::port_of(c, "EGM on 127.0.0.1:"); }

using test::kDeflex;

TEST(CliOnline, EgmJointStreamsTheProgramWithinTheBoundOfIt) {
  const std::string dir = ::testing::TempDir() + "/cli_online_joint";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  const std::string log = dir + "/log.csv";
  Child deflex;
  spawn(deflex,
        {kDeflex, "online", "--link", "egm-joint", "--program", program_path, "--egm-port", "0", "--force-source",
         "csv:" + test::kForceReplay, "--loop", "--log", log, "--max-joint-correction-deg", "0.5",
         "--status-interval-s", "0.5"},
        dir + "/stderr.txt");
  const int port = egm_port_of(deflex);
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  UdpTransport transport("127.0.0.1", 0);
  cell::ControllerConfig cc;
  cell::EgmPositionGuidanceController controller(cc, program.points().front(), transport,
                                                 make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  run_in_real_time(controller, 2.5);
  EXPECT_FALSE(controller.counters().timed_out);
  EXPECT_GT(controller.counters().targets, 200u);
  EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);

  // The log: the nominal is the program at the program time of the cycle, and every command is within
  // 0.5 deg of it; the program clock advanced with the link's clock.
  const CsvTable table = CsvTable::read_file(log);
  ASSERT_GT(table.rows(), 200u);
  const std::size_t last = table.rows() - 1;
  EXPECT_GT(table.at(last, "program_t_s") - table.at(0, "program_t_s"), 1.0);
  // Not ahead of the link's clock by more than one 4 ms cycle: the first and last rows' stamps carry the
  // scheduling jitter of a loaded machine (0.13 ms seen in a full ctest run beside a build), while a
  // program clock running ahead would gain a cycle every few cycles.
  EXPECT_LE(table.at(last, "program_t_s") - table.at(0, "program_t_s"),
            table.at(last, "t_s") - table.at(0, "t_s") + 0.004);
  double worst_nominal = 0.0, worst_command = 0.0, largest = 0.0;
  JointVector q(6);
  for (std::size_t r = 0; r < table.rows(); ++r) {
    program.sample(table.at(r, "program_t_s"), q);
    for (int j = 1; j <= 6; ++j) {
      const double nominal = table.at(r, "q_nominal" + std::to_string(j) + "_deg");
      const double command = table.at(r, "q_command" + std::to_string(j) + "_deg");
      worst_nominal = std::max(worst_nominal, std::abs(nominal - rad_to_deg(q[j - 1])));
      worst_command = std::max(worst_command, std::abs(command - nominal));
      largest = std::max(largest, std::abs(table.at(r, "dtheta" + std::to_string(j) + "_deg")));
    }
  }
  EXPECT_LT(worst_nominal, 1e-6);
  EXPECT_LE(worst_command, 0.5);
  EXPECT_GT(largest, 1e-4);  // a correction was made (the replay pushes with 400 N)
}

TEST(CliOnline, EgmJointRefusesAStartAwayFromTheProgramAndNamesTheJoint) {
  const std::string dir = ::testing::TempDir() + "/cli_online_refuse";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  Child deflex;
  spawn(deflex,
        {kDeflex, "online", "--link", "egm-joint", "--program", program_path, "--egm-port", "0", "--force-source",
         "csv:" + test::kForceReplay, "--loop"},
        dir + "/stderr.txt");
  const int port = egm_port_of(deflex);
  ASSERT_GT(port, 0);
  JointVector start = program.points().front();
  start[2] += deg_to_rad(2.0);
  UdpTransport transport("127.0.0.1", 0);
  cell::ControllerConfig cc;
  cell::EgmPositionGuidanceController controller(cc, start, transport,
                                                 make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  run_in_real_time(controller, 0.3);
  EXPECT_EQ(deflex.wait(), 4);
  EXPECT_EQ(controller.counters().targets, 0u);  // nothing was ever sent to the controller
  const std::string err = test::slurp(deflex.stderr_path);
  EXPECT_NE(err.find("refusing to start"), std::string::npos) << err;
  EXPECT_NE(err.find("joint 3 is 2.000 deg away"), std::string::npos) << err;
  EXPECT_EQ(err.find("joint 2 is"), std::string::npos) << err;
}

TEST(CliOnline, EgmPathAnswersTheControllersOwnProgramWithAbsoluteOffsets) {
  const std::string dir = ::testing::TempDir() + "/cli_online_path";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir);
  const RobotModel robot = builtin_irb6700();
  auto program = std::make_shared<const JointTrajectory>(JointTrajectory::read_csv(program_path, robot));
  Child deflex;
  spawn(deflex,
        {kDeflex, "online", "--link", "egm-path", "--period-ms", "24", "--egm-port", "0", "--force-source",
         "csv:" + test::kForceReplay, "--loop", "--path-corr-frame", "tool"},
        dir + "/stderr.txt");
  const int port = egm_port_of(deflex);
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  UdpTransport transport("127.0.0.1", 0);
  cell::ControllerConfig cc;
  cc.path_corr_period_s = 0.024;
  cell::EgmPathCorrectionController controller(cc, robot, program, transport,
                                               make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  run_in_real_time(controller, 2.0);
  EXPECT_GT(controller.counters().targets, 50u);
  // The replay's 400 N push, seen at this pose, deflects the TCP by some tenths of a mm: the applied
  // offset is that size and well inside the 5 mm bound.
  EXPECT_GT(controller.applied_offset_m().norm(), 1e-5);
  EXPECT_LT(controller.applied_offset_m().norm(), 5e-3);
  EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);
}

TEST(CliOnline, BadOptionsAndProgramsAreRefusedBeforeAnythingRuns) {
  const std::string dir = ::testing::TempDir() + "/cli_online_bad";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir);
  const std::string base = "online --egm-port 0 --force-source csv:" + test::kForceReplay + " ";
  const auto expect = [&](const std::string& args, const std::string& fragment) {
    const auto r = test::run_cli(base + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << args << "\n" << r.err;
  };
  expect("--link fanuc", "--link");
  {
    const auto r = test::run_cli("online --link egm-path --force-source csv:" + test::kForceReplay);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--egm-port"), std::string::npos) << r.err;
  }
  expect("--link egm-joint", "--program");
  expect("--link egm-path --program " + program_path, "--program");
  expect("--link egm-joint --program " + program_path + " --status-interval-s nan", "--status-interval-s");
  expect("--link egm-joint --program " + program_path + " --duration-s -1", "--duration-s");
  expect("--link egm-joint --program " + program_path + " --strategy hybrid", "needs a force model");
  expect("--link egm-joint --program " + program_path + " --strategy guess", "strategy 'guess'");
  expect("--link egm-path --path-corr-frame world", "world");
  expect("--link egm-joint --program " + program_path + " --fault-dump /dev/null/dir/dump.csv",
         "option --fault-dump '/dev/null/dir/dump.csv': '/dev/null' is not a directory");
  // Programs the robot cannot follow, named by file, line and joint.
  const auto write = [&](const std::string& name, const std::string& text) {
    const std::string p = dir + "/" + name;
    std::ofstream(p) << text;
    return p;
  };
  const std::string header = "t_s,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n";
  expect("--link egm-joint --program " +
             write("back.csv", header + "0,0,20,10,0,60,0\n1,0,20,10,0,60,0\n0.5,0,20,10,0,60,0\n"),
         "back.csv:4");
  expect("--link egm-joint --program " + write("limit.csv", header + "0,0,20,10,0,60,0\n1,0,20,75,0,60,0\n"),
         "joint 3 at 75.0000 deg is beyond its limits");
  expect("--link egm-joint --program " + write("fast.csv", header + "0,0,20,10,0,60,0\n0.1,30,20,10,0,60,0\n"),
         "fast.csv:3: joint 1 would move at");
  expect("--link egm-joint --program " + write("columns.csv", "t_s,q1_deg\n0,0\n1,0\n"), "missing column");
}

}  // namespace
}  // namespace deflex
