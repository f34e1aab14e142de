// `deflex online` as a real process through the faults a cell PC has, beside a controller stand-in
// ticked in real time over loopback UDP: the process stopped (SIGSTOP) and continued mid-run never
// steps the target (read from its cycle log against the program, independently of deflex's own
// step check); a controller that stops ends the run by itself with a non-zero exit code naming it;
// --realtime that the system refuses exits 2 naming the missing permission.
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cross/cli_child.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/cell/rsi_controller.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/transport/udp_transport.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;
using test::Child;

using test::kDeflex;

// Ticks `controller` in real time every 4 ms for `seconds`; `at(t)` is called before each tick.
template <class Controller, class Hook>
void run_with(Controller& controller, double seconds, Hook at) {
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  for (;;) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (t > seconds) break;
    at(t);
    controller.tick(t);
    next += std::chrono::milliseconds(4);
    std::this_thread::sleep_until(next);
  }
}

TEST(CliRuntimeFaults, AStoppedAndContinuedProcessNeverStepsTheTarget) {
  const std::string dir = ::testing::TempDir() + "/cli_sigstop";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir, 50.0, 0.2);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  const std::string log = dir + "/log.csv";
  Child deflex;
  test::spawn(deflex,
              {kDeflex, "online", "--link", "egm-joint", "--program", program_path, "--egm-port", "0", "--force-source",
               "csv:" + test::kForceReplay, "--loop", "--log", log},
              dir + "/stderr.txt");
  const int port = test::port_of(deflex, "EGM on 127.0.0.1:");
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  UdpTransport transport("127.0.0.1", 0);
  cell::ControllerConfig cc;
  cell::EgmPositionGuidanceController controller(cc, program.points().front(), transport,
                                                 make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  bool stopped = false, continued = false;
  run_with(controller, 3.0, [&](double t) {
    if (!stopped && t > 1.0) {
      ::kill(deflex.pid, SIGSTOP);  // the PC stalls: scheduler, swap, a debugger
      stopped = true;
    }
    if (stopped && !continued && t > 1.45) {
      ::kill(deflex.pid, SIGCONT);
      continued = true;
    }
  });
  EXPECT_FALSE(controller.counters().timed_out);  // 0.45 s is inside EGM's 1 s CommTimeout
  EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);

  const CsvTable table = CsvTable::read_file(log);
  ASSERT_GT(table.rows(), 400u);
  // The per-cycle limit, computed here: the program's peak speed (sampled every 0.5 ms), the ramp-in
  // blend's (1.5 x 1 deg over 1 s), the correction's rate (3 deg/s), over 4 ms.
  const JointVector limit_deg = test::cli_step_limit_deg(program);
  double worst = 0.0, longest_gap = 0.0, largest_program_step = 0.0;
  for (std::size_t r = 1; r < table.rows(); ++r) {
    if (table.at(r, "replied") == 0.0 || table.at(r - 1, "replied") == 0.0) continue;
    for (int j = 1; j <= 6; ++j) {
      const std::string c = "q_command" + std::to_string(j) + "_deg";
      worst = std::max(worst, std::abs(table.at(r, c) - table.at(r - 1, c)) / limit_deg[j - 1]);
    }
    longest_gap = std::max(longest_gap, table.at(r, "t_s") - table.at(r - 1, "t_s"));
    largest_program_step = std::max(largest_program_step, table.at(r, "program_t_s") - table.at(r - 1, "program_t_s"));
  }
  EXPECT_GT(longest_gap, 0.4);                    // the stall is in the log
  EXPECT_LE(largest_program_step, 0.004 + 1e-9);  // the program never ran ahead of what was consumed
  EXPECT_LE(worst, 1.0);                          // and no command stepped beyond the limit
  const std::string err = test::slurp(deflex.stderr_path);
  EXPECT_NE(err.find("the controller was silent for 0.4"), std::string::npos) << err;
}

TEST(CliRuntimeFaults, SigintWhileMovingBringsTheProgramToRestThenEndsAsPlanned) {
  // Before, the loop saw the signal only every 0.1 s: 25 more answers at full speed, then nothing.
  const std::string dir = ::testing::TempDir() + "/cli_sigint_ramp";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir, 50.0, 0.2);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  const std::string log = dir + "/log.csv";
  Child deflex;
  test::spawn(deflex,
              {kDeflex, "online", "--link", "egm-joint", "--program", program_path, "--egm-port", "0", "--force-source",
               "csv:" + test::kForceReplay, "--loop", "--log", log, "--stop-ramp-s", "0.4"},
              dir + "/stderr.txt");
  const int port = test::port_of(deflex, "EGM on 127.0.0.1:");
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  UdpTransport transport("127.0.0.1", 0);
  cell::ControllerConfig cc;
  cell::EgmPositionGuidanceController controller(cc, program.points().front(), transport,
                                                 make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  double signalled_at = -1.0;
  run_with(controller, 3.0, [&](double t) {
    if (signalled_at < 0.0 && t > 1.5) {
      ::kill(deflex.pid, SIGINT);
      signalled_at = t;
    }
  });
  const int code = deflex.wait();
  const std::string err = test::slurp(deflex.stderr_path);
  EXPECT_EQ(code, 0) << err;
  EXPECT_NE(err.find("user-stop (exit code 0): stopped on request (SIGINT, SIGTERM or the caller): the program was "
                     "brought to a standstill on its path over 0.40 s"),
            std::string::npos)
      << err;
  // The log: the program's clock slowed to a stop over the ramp, and no step on the wire beyond the
  // per-cycle limit (computed here from the program).
  const CsvTable table = CsvTable::read_file(log);
  const JointVector limit_deg = test::cli_step_limit_deg(program);
  double worst = 0.0, last_advance = 1.0, first_advance = 0.0;
  std::size_t replied = 0;
  for (std::size_t r = 1; r < table.rows(); ++r) {
    if (table.at(r, "replied") == 0.0 || table.at(r - 1, "replied") == 0.0) continue;
    ++replied;
    for (int j = 1; j <= 6; ++j) {
      const std::string c = "q_command" + std::to_string(j) + "_deg";
      worst = std::max(worst, std::abs(table.at(r, c) - table.at(r - 1, c)) / limit_deg[j - 1]);
    }
    const double advance = table.at(r, "program_t_s") - table.at(r - 1, "program_t_s");
    if (first_advance == 0.0) first_advance = advance;
    last_advance = advance;
  }
  EXPECT_GT(replied, 300u);
  EXPECT_LE(worst, 1.0);
  EXPECT_NEAR(first_advance, 0.004, 1e-9);  // the program ran at its own speed before
  EXPECT_LT(last_advance, 0.0004);          // and at under a tenth of it in the ramp's last cycle
}

TEST(CliRuntimeFaults, ALogOnAFullDiskEndsTheRunWithExit1NamingItAndTheSummary) {
  // /dev/full fails every write with ENOSPC, as a full disk does. Before, the cycle log aborted the
  // process (SIGABRT, exit 134) mid-session, and --log-file lost the field log silently with exit 0.
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this machine";
  const std::string dir = ::testing::TempDir() + "/cli_full_disk";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir, 50.0, 0.2);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  for (const char* option : {"--log", "--log-file"}) {
    Child deflex;
    test::spawn(
        deflex,
        {kDeflex, "online", "--link", "egm-joint", "--program", program_path, "--egm-port", "0", "--force-source",
         "csv:" + test::kForceReplay, "--loop", option, "/dev/full", "--status-interval-s", "0.2"},
        dir + "/stderr.txt");
    const int port = test::port_of(deflex, "EGM on 127.0.0.1:");
    ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
    UdpTransport transport("127.0.0.1", 0);
    cell::ControllerConfig cc;
    cell::EgmPositionGuidanceController controller(
        cc, program.points().front(), transport, make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
    run_with(controller, 4.0, [](double) {});
    const int code = deflex.wait();  // it ends by itself
    const std::string err = test::slurp(deflex.stderr_path);
    EXPECT_EQ(code, 1) << option << ": " << err;
    EXPECT_NE(err.find("session ended: output-failed (exit code 1)"), std::string::npos) << option << ": " << err;
    EXPECT_NE(err.find("/dev/full"), std::string::npos) << option << ": " << err;
    EXPECT_NE(err.find("on the wire: largest"), std::string::npos) << option << ": the summary: " << err;
    EXPECT_EQ(err.find("terminate called"), std::string::npos) << option << ": " << err;
  }
}

TEST(CliRuntimeFaults, AFieldLogInAFolderThatDoesNotExistYetIsMadeThere) {
  // Every output of deflex makes its missing folders; the field log did not ("cannot append").
  const std::string dir = ::testing::TempDir() + "/cli_log_folder";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir, 50.0, 0.2);
  const std::string log = dir + "/logs/today/online.log";
  Child deflex;
  test::spawn(deflex,
              {kDeflex, "online", "--link", "egm-joint", "--program", program_path, "--egm-port", "0", "--force-source",
               "csv:" + test::kForceReplay, "--loop", "--log-file", log, "--duration-s", "0.3"},
              dir + "/stderr.txt");
  EXPECT_EQ(deflex.wait(), 0) << test::slurp(deflex.stderr_path);
  ASSERT_TRUE(fs::exists(log));
  EXPECT_NE(test::slurp(log).find("the egm-joint session ended: duration"), std::string::npos) << test::slurp(log);
}

TEST(CliRuntimeFaults, AStoppedRsiControllerEndsTheRunWithANonZeroCodeNamingIt) {
  const std::string dir = ::testing::TempDir() + "/cli_rsi_stop";
  fs::create_directories(dir);
  Child deflex;
  test::spawn(deflex,
              {kDeflex, "online", "--link", "rsi", "--rsi-port", "0", "--force-source", "csv:" + test::kForceReplay,
               "--loop", "--json"},
              dir + "/stderr.txt", dir + "/stdout.json");
  const int port = test::port_of(deflex, "RSI on 127.0.0.1:");
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  const RobotModel robot = builtin_irb6700();
  JointVector q(6);
  q << 0.0, 0.35, 0.17, 0.0, 1.05, 0.0;
  const auto hold = std::make_shared<const JointTrajectory>(std::vector<double>{0.0, 60.0},
                                                            std::vector<JointVector>{q, q}, robot, "hold");
  UdpTransport transport("127.0.0.1", 0);
  cell::RsiControllerConfig cc;
  cell::RsiController controller(cc, robot, hold, transport,
                                 make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  test::run_in_real_time(controller, 1.0);  // then the controller stops sending (RSI off, a cable out)
  const auto stopped = std::chrono::steady_clock::now();
  const int code = deflex.wait();  // it ends by itself
  const double after = std::chrono::duration<double>(std::chrono::steady_clock::now() - stopped).count();
  const std::string err = test::slurp(deflex.stderr_path);
  EXPECT_EQ(code, 5) << err;
  EXPECT_LT(after, 2.5) << "the 1 s stop silence of the rsi link";
  EXPECT_NE(err.find("controller-silent (exit code 5)"), std::string::npos) << err;
  const auto summary = nlohmann::json::parse(test::slurp(dir + "/stdout.json"));
  EXPECT_EQ(summary["stop_reason"], "controller-silent");
  EXPECT_EQ(summary["exit_code"], 5);
  EXPECT_GT(summary["answers"].get<int>(), 100);
}

TEST(CliRuntimeFaults, RealTimeTheSystemRefusesIsExitTwoNamingThePermission) {
  const std::string dir = ::testing::TempDir() + "/cli_realtime";
  fs::create_directories(dir);
  const std::string program_path = test::nominal_program(dir, 50.0, 0.2);
  // Without CAP_SYS_NICE and with a real-time priority limit of 0 (root keeps the capability unless
  // it is taken out of the bounding set).
  const std::string drop = ::geteuid() == 0 ? "setpriv --bounding-set=-sys_nice,-ipc_lock " : "prlimit --rtprio=0 ";
  if (std::system(("command -v " + drop.substr(0, drop.find(' ')) + " >/dev/null").c_str()) != 0) {
    GTEST_SKIP() << "no " << drop << "on this machine";
  }
  const auto r = test::run_shell(drop + kDeflex + " online --link egm-joint --egm-port 0 --force-source csv:" +
                                 test::kForceReplay + " --program " + program_path + " --realtime --duration-s 1");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("option --realtime: the system refused SCHED_FIFO priority 80"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("CAP_SYS_NICE"), std::string::npos) << r.err;
  // Options for real time without it are refused too, naming them.
  const auto o = test::run_cli("online --link egm-joint --egm-port 0 --force-source csv:" + test::kForceReplay +
                               " --program " + program_path + " --rt-cpu 1");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("setting rt_cpu (--rt-cpu): applies with realtime (--realtime)"), std::string::npos) << o.err;
}

}  // namespace
}  // namespace deflex
