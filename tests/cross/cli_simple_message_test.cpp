// `deflex online --link simple-message` end to end: the real program connects over loopback TCP to the
// simulated cell's RAPID streaming server (run here in real time, the test accepting the connections as
// the robot program would). Every logged command stays within the bound of a nominal that is the
// program itself; Ctrl-C sends STOP_TRAJECTORY and exits 0; a start away from the program is refused
// with the joint named and nothing sent (exit 4); a lost connection stops the motion with exit 6
// (controller stopped) and says which; a frame that cannot be one is bad input (exit 2, naming the
// LENGTH); bad options are refused before anything connects, naming the option.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

#include "cross/cli_child.hpp"
#include "deflex/cell/simple_message_server.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/transport/tcp_stream.hpp"
#include "support/simple_message_frames.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

using test::kDeflex;

// deflex running in a child process, its stderr in a file.
struct Deflex {
  pid_t pid = -1;
  std::string err_path;
  Deflex(const std::vector<std::string>& args, const std::string& err) : err_path(err) {
    fs::remove(err);
    pid = ::fork();
    if (pid == 0) {
      std::FILE* f = std::freopen(err.c_str(), "w", stderr);
      (void)f;
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(kDeflex.c_str()));
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      std::_Exit(127);
    }
  }
  ~Deflex() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
  Deflex(const Deflex&) = delete;
  Deflex& operator=(const Deflex&) = delete;
  // The exit code, or -1 when it did not exit within `timeout_s` (then it is killed: a test never hangs).
  int wait(double timeout_s = 30.0) {
    int status = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        pid = -1;
        return -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  // True once it exited (its code in `code`); never waits.
  bool exited(int& code) {
    int status = 0;
    if (pid <= 0 || ::waitpid(pid, &status, WNOHANG) != pid) return pid <= 0;
    pid = -1;
    code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return true;
  }
  [[nodiscard]] std::string err() const { return test::slurp(err_path); }
};

// The controller's two servers: listening, then the connections deflex makes.
struct Controller {
  TcpListener motion_listener{"127.0.0.1", 0}, state_listener{"127.0.0.1", 0};
  std::unique_ptr<TcpStream> motion, state;
  [[nodiscard]] std::vector<std::string> ports() const {
    return {"--robot-host",  "127.0.0.1",
            "--motion-port", std::to_string(motion_listener.port()),
            "--state-port",  std::to_string(state_listener.port())};
  }
  bool accept() {
    motion = motion_listener.accept(10.0);
    state = state_listener.accept(10.0);
    return motion != nullptr && state != nullptr;
  }
};

// Ticks the server every 4 ms of real time until `until_s` on its clock (or until `done`); the clock
// starts with the first call and runs on across calls.
struct RealTime {
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  template <class Done>
  void run(cell::SimpleMessageServer& server, double until_s, Done done) {
    auto next = std::chrono::steady_clock::now();
    for (;;) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (t > until_s || done()) break;
      server.tick(t);
      next += std::chrono::milliseconds(4);
      std::this_thread::sleep_until(next);
    }
  }
};
const auto kNever = [] { return false; };

// A directory of this test process's own (other checkouts' tests may run on this machine at once).
std::string temp_dir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/" + name + "_" + std::to_string(::getpid());
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> join(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

TEST(CliSimpleMessage, StreamsTheProgramWithinTheBoundAndCtrlCStopsTheArm) {
  const std::string dir = temp_dir("cli_sm_stream");
  const std::string program_path = test::nominal_program(dir);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  const std::string log = dir + "/log.csv";
  Controller c;
  Deflex deflex(
      join({"online", "--link", "simple-message", "--program", program_path, "--period-ms", "100", "--force-source",
            "csv:" + test::kForceReplay, "--loop", "--log", log, "--status-interval-s", "0.5"},
           c.ports()),
      dir + "/stderr.txt");
  ASSERT_TRUE(c.accept()) << deflex.err();
  cell::SimpleMessageServer server({}, robot, program.points().front(), *c.motion, *c.state);
  RealTime clock;
  clock.run(server, 3.0, kNever);
  EXPECT_GT(server.counters().accepted, 20u);
  EXPECT_EQ(server.counters().refused_full + server.counters().refused_invalid, 0u);
  // Ctrl-C while the controller runs on: the points ramp to rest over the stop ramp, the controller runs
  // out its queue, then STOP_TRAJECTORY reaches it and the arm stands.
  ::kill(deflex.pid, SIGINT);
  int code = -2;
  clock.run(server, 8.0, [&] { return deflex.exited(code); });
  EXPECT_EQ(code, 0) << deflex.err();
  clock.run(server, 8.5, [&] { return server.counters().stops > 0 && server.motion().at_rest(); });
  EXPECT_EQ(server.counters().stops, 1u);
  EXPECT_TRUE(server.motion().at_rest());
  const std::string err = deflex.err();
  EXPECT_NE(err.find("STOP_TRAJECTORY sent 1"), std::string::npos) << err;
  EXPECT_NE(err.find("buffer 2 points = 200 ms of lag"), std::string::npos) << err;

  // The log: the nominal is the program at the point's program time (after the ramp-in, which blends
  // out the float32 rounding of the arm's reported start), and every command within 0.5 deg of it.
  const CsvTable table = CsvTable::read_file(log);
  ASSERT_GT(table.rows(), 20u);
  double worst_nominal = 0.0, worst_command = 0.0, largest = 0.0;
  JointVector q(6);
  // The program's clock: a point's worth a point (100 ms) while it ran, then slower and slower over the
  // stop ramp after Ctrl-C, never faster.
  for (std::size_t r = 0; r < table.rows(); ++r) {
    if (r < 20) {
      EXPECT_NEAR(table.at(r, "program_t_s") - program.start_time_s(), 0.1 * table.at(r, "sequence"), 1e-9);
    } else {
      const double advance = table.at(r, "program_t_s") - table.at(r - 1, "program_t_s");
      EXPECT_LE(advance, 0.1 + 1e-9);
      EXPECT_GE(advance, 0.0);
    }
    program.sample(table.at(r, "program_t_s"), q);
    for (int j = 1; j <= 6; ++j) {
      const double nominal = table.at(r, "q_nominal" + std::to_string(j) + "_deg");
      const double command = table.at(r, "q_command" + std::to_string(j) + "_deg");
      worst_nominal = std::max(worst_nominal, std::abs(nominal - rad_to_deg(q[j - 1])));
      worst_command = std::max(worst_command, std::abs(command - nominal));
      largest = std::max(largest, std::abs(table.at(r, "dtheta" + std::to_string(j) + "_deg")));
    }
  }
  EXPECT_LT(table.at(table.rows() - 1, "program_t_s") - table.at(table.rows() - 2, "program_t_s"), 0.02);
  EXPECT_LT(worst_nominal, 2e-5);
  EXPECT_LE(worst_command, 0.5);
  EXPECT_GT(largest, 1e-4);  // the replay pushes with 400 N: a correction was made
}

TEST(CliSimpleMessage, RefusesAStartAwayFromTheProgramAndSendsNothing) {
  const std::string dir = temp_dir("cli_sm_refuse");
  const std::string program_path = test::nominal_program(dir);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  Controller c;
  Deflex deflex(join({"online", "--link", "simple-message", "--program", program_path, "--period-ms", "100",
                      "--force-source", "csv:" + test::kForceReplay, "--loop"},
                     c.ports()),
                dir + "/stderr.txt");
  ASSERT_TRUE(c.accept()) << deflex.err();
  JointVector start = program.points().front();
  start[2] += deg_to_rad(2.0);
  cell::SimpleMessageServer server({}, robot, start, *c.motion, *c.state);
  RealTime().run(server, 1.0, kNever);
  EXPECT_EQ(deflex.wait(), 4);
  EXPECT_EQ(server.counters().requests, 0u);
  const std::string err = deflex.err();
  EXPECT_NE(err.find("refusing to start"), std::string::npos) << err;
  EXPECT_NE(err.find("joint 3 is 2.000 deg away"), std::string::npos) << err;
}

TEST(CliSimpleMessage, ALostConnectionStopsWithExitCodeSixAndSaysWhich) {
  const std::string dir = temp_dir("cli_sm_lost");
  const std::string program_path = test::nominal_program(dir);
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory program = JointTrajectory::read_csv(program_path, robot);
  Controller c;
  Deflex deflex(join({"online", "--link", "simple-message", "--program", program_path, "--period-ms", "100",
                      "--force-source", "csv:" + test::kForceReplay, "--loop", "--fault-dump", dir + "/dump.csv"},
                     c.ports()),
                dir + "/stderr.txt");
  ASSERT_TRUE(c.accept()) << deflex.err();
  cell::SimpleMessageServer server({}, robot, program.points().front(), *c.motion, *c.state);
  RealTime clock;
  clock.run(server, 1.0, kNever);
  c.state->close();  // the state server's connection goes
  clock.run(server, 3.0, [&] { return server.counters().stops > 0; });
  EXPECT_EQ(deflex.wait(), 6);
  EXPECT_EQ(server.counters().stops, 1u);  // the motion connection still carried STOP_TRAJECTORY
  const std::string err = deflex.err();
  EXPECT_NE(err.find("controller-stopped (exit code 6): the controller closed the state connection"), std::string::npos)
      << err;
  EXPECT_TRUE(fs::exists(dir + "/dump.csv"));
}

TEST(CliSimpleMessage, AFrameThatCannotBeOneIsBadInputAndNamed) {
  const std::string dir = temp_dir("cli_sm_bad");
  const std::string program_path = test::nominal_program(dir);
  Controller c;
  Deflex deflex(join({"online", "--link", "simple-message", "--program", program_path, "--period-ms", "100",
                      "--force-source", "csv:" + test::kForceReplay, "--loop"},
                     c.ports()),
                dir + "/stderr.txt");
  ASSERT_TRUE(c.accept()) << deflex.err();
  test::HandFrame bad{false, {}};
  bad.i32(5000).i32(10).i32(1).i32(0);
  ASSERT_EQ(c.state->write(bad.bytes.data(), bad.bytes.size()), static_cast<long>(bad.bytes.size()));
  EXPECT_EQ(deflex.wait(), 2);
  const std::string err = deflex.err();
  EXPECT_NE(err.find("state connection: frame LENGTH 5000"), std::string::npos) << err;
  EXPECT_NE(err.find("ended: protocol (exit code 2)"), std::string::npos) << err;
}

TEST(CliSimpleMessage, BadOptionsAreRefusedBeforeAnythingConnects) {
  const std::string dir = temp_dir("cli_sm_options");
  const std::string program_path = test::nominal_program(dir);
  const std::string base =
      "online --link simple-message --force-source csv:" + test::kForceReplay + " --program " + program_path;
  const auto expect = [](const std::string& args, const std::string& fragment) {
    const auto r = test::run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << args << "\n" << r.err;
  };
  expect(base + " --period-ms 100", "--robot-host");
  expect(base + " --robot-host 127.0.0.1 --period-ms 4",
         "setting period_s (--period-ms): simple-message sends one point a cycle");
  expect(base + " --robot-host 127.0.0.1 --period-ms 100 --egm-port 6510",
         "setting egm_port (--egm-port): applies to --link egm-joint or egm-path, not simple-message");
  expect(base + " --robot-host 127.0.0.1 --period-ms 100 --byte-order middle",
         "setting byte_order (--byte-order): byte order 'middle'");
  expect(base + " --robot-host 127.0.0.1 --period-ms 100 --buffer-depth 0", "(--buffer-depth)");
  expect(base + " --robot-host 127.0.0.1 --period-ms 100 --motion-port 70000", "(--motion-port)");
  expect(base + " --robot-host 127.0.0.1 --period-ms 100 --reply-timeout-s 0", "(--reply-timeout-s)");
  expect("online --link simple-message --force-source csv:" + test::kForceReplay +
             " --robot-host 127.0.0.1 --period-ms 100",
         "--program");
  // Nobody listening: the error names the address and port.
  auto gone = std::make_unique<TcpListener>("127.0.0.1", 0);
  const std::string port = std::to_string(gone->port());
  gone.reset();
  expect(base + " --robot-host 127.0.0.1 --period-ms 100 --connect-timeout-s 1 --motion-port " + port,
         "cannot connect to 127.0.0.1:" + port);
}

}  // namespace
}  // namespace deflex
