// End to end with the real program: spawns `deflex online` (force from a UDP stream, EGM on an
// ephemeral port), exchanges real EGM packets with it over loopback, checks the corrections against
// the model computed here, then stops it with SIGINT/SIGTERM and checks the clean exit and the log.
// Skipped when the deflex program has not been built (module-only builds).
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "deflex/egm/egm_robot_peer.hpp"
#include "deflex/model/csv_table.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/online/udp_force_source.hpp"

namespace deflex {
namespace {

struct Child {
  pid_t pid = -1;
  std::string stderr_path;
};

Child spawn(const std::vector<std::string>& args, const std::string& stderr_path) {
  Child c;
  c.stderr_path = stderr_path;
  std::filesystem::remove(stderr_path);  // never read a previous run's ports
  c.pid = ::fork();
  if (c.pid == 0) {
    std::FILE* f = std::freopen(stderr_path.c_str(), "w", stderr);
    (void)f;
    std::vector<char*> argv;
    for (const auto& a : args) {
      argv.push_back(const_cast<char*>(a.c_str()));
    }
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    std::_Exit(127);
  }
  return c;
}

std::string read_all(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Waits for the start-up line and reads the two ephemeral ports from it.
bool ports_from_banner(const Child& c, int& egm_port, int& force_port) {
  const std::regex egm("EGM on 127\\.0\\.0\\.1:([0-9]+)"), force("UDP force samples on port ([0-9]+)");
  for (int i = 0; i < 500; ++i) {
    const std::string text = read_all(c.stderr_path);
    std::smatch a, b;
    if (std::regex_search(text, a, egm) && std::regex_search(text, b, force)) {
      egm_port = std::stoi(a[1]);
      force_port = std::stoi(b[1]);
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

// Kills the child if the test fails before stopping it, so no stray process outlives the test.
struct KillOnExit {
  pid_t pid;
  ~KillOnExit() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
};

int wait_exit(pid_t pid) {
  int status = 0;
  for (int i = 0; i < 500; ++i) {
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return -1;
}

TEST(DeflexOnlineProgram, AnswersEgmWithTheModelsCorrectionAndStopsCleanly) {
  const std::string cli = DEFLEX_CLI;
  if (!std::filesystem::exists(cli)) {
    GTEST_SKIP() << "the deflex program is not built: " << cli;
  }
  const std::string dir = ::testing::TempDir();
  const std::string log = dir + "/online_cli_log.csv";
  for (int sig : {SIGINT, SIGTERM}) {
    std::filesystem::remove(log);
    const Child child = spawn({cli, "online", "--egm-port", "0", "--force-source", "udp:0", "--log", log,
                               "--max-rate-deg-s", "100", "--duration-s", "60"},
                              dir + "/online_cli_stderr.txt");
    KillOnExit guard{child.pid};
    int egm_port = 0, force_port = 0;
    ASSERT_TRUE(ports_from_banner(child, egm_port, force_port)) << read_all(child.stderr_path);

    // Built-in robot, no tool: sensor and WAP at the flange. A force in the base frame, read in the
    // flange frame.
    const RobotModel robot = builtin_irb6700();
    JointVector q_deg(6);
    q_deg << -10, 30, 5, 40, -50, 25;
    const JointVector q = q_deg * (kPi / 180.0);
    Workspace ws(robot);
    forward_kinematics(robot, ws, q);
    const Vector3 f_base(-250, 400, -700);
    ForceSample s;
    s.wrench_sensor.head<3>() = ws.base_T_flange.linear().transpose() * f_base;

    // The model's correction, from a finite-difference Jacobian of FK at the flange.
    Jacobian J(6, 6);
    for (int i = 0; i < 6; ++i) {
      JointVector qp = q, qm = q;
      qp[i] += 1e-6;
      qm[i] -= 1e-6;
      forward_kinematics(robot, ws, qp);
      const Vector3 a = ws.base_T_flange.translation();
      forward_kinematics(robot, ws, qm);
      J.block<3, 1>(0, i) = (a - ws.base_T_flange.translation()) / 2e-6;
    }
    JointVector expected_deg = q_deg;
    for (int i = 0; i < 6; ++i) {
      expected_deg[i] -= rad_to_deg(J.col(i).head<3>().dot(f_base) / robot.stiffness()[i]);
    }

    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    const sockaddr_in force_to = make_address("127.0.0.1", static_cast<std::uint16_t>(force_port));
    EgmRobotPeer controller("127.0.0.1", static_cast<std::uint16_t>(egm_port));
    EgmRobotMessage m;
    m.feedback_joints_deg = q_deg;
    m.planned_joints_deg = q_deg;
    EgmSensorMessage reply;
    int replies = 0;
    std::array<unsigned char, kForceDatagramBytes> dgram{};
    for (std::uint32_t k = 1; k <= 50; ++k) {
      s.t_s = 0.004 * k;
      encode_force_datagram(s, k, dgram);
      ::sendto(fd, dgram.data(), dgram.size(), 0, reinterpret_cast<const sockaddr*>(&force_to), sizeof(force_to));
      m.seqno = k;
      ASSERT_TRUE(controller.send(m));
      if (!controller.receive(reply, 2.0)) {
        break;
      }
      ++replies;
    }
    // A garbage packet is ignored, not answered.
    const unsigned char garbage[] = {0xFF, 0x01, 0x02};
    controller.send_raw(garbage, sizeof(garbage));
    EXPECT_FALSE(controller.receive(reply, 0.1));
    ::close(fd);
    EXPECT_EQ(replies, 50);
    const JointVector correction = q_deg - expected_deg;
    ASSERT_GT(correction.norm(), 1e-3);
    EXPECT_LT((reply.planned_joints_deg - expected_deg).norm(), 1e-6 * correction.norm());

    ::kill(child.pid, sig);
    EXPECT_EQ(wait_exit(child.pid), 0) << read_all(child.stderr_path);
    guard.pid = -1;
    const std::string err = read_all(child.stderr_path);
    EXPECT_NE(err.find("stopped after 50 cycles: 50 replies; rejected packets 1 (malformed 1"), std::string::npos)
        << err;
    const CsvTable t = CsvTable::read_file(log);  // flushed and complete
    ASSERT_EQ(t.rows(), 50u);
    EXPECT_NEAR(t.at(49, "q_command2_deg"), reply.planned_joints_deg[1], 1e-8);
  }
}

}  // namespace
}  // namespace deflex
