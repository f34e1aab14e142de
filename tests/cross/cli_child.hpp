// Test helpers for running `deflex online` as a real process beside a controller stand-in: a child
// process with its stderr (and stdout) in files, the port it bound read from its start-up line, and a
// stand-in ticked in real time every 4 ms.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "cross/cli_runner.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "support/sampled_speed.hpp"

namespace deflex::test {

struct Child {
  pid_t pid = -1;
  std::string stderr_path;
  ~Child() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
  int stop() {  // SIGINT, then the exit code (-1 if it did not exit)
    ::kill(pid, SIGINT);
    return wait();
  }
  int wait() {
    int status = 0;
    ::waitpid(pid, &status, 0);
    pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
};

/// Starts args[0] with args, stderr into `stderr_path` and, when given, stdout into `stdout_path`.
inline void spawn(Child& c, const std::vector<std::string>& args, const std::string& stderr_path,
                  const std::string& stdout_path = "") {
  c.stderr_path = stderr_path;
  std::filesystem::remove(stderr_path);
  c.pid = ::fork();
  if (c.pid == 0) {
    std::FILE* f = std::freopen(stderr_path.c_str(), "w", stderr);
    if (!stdout_path.empty()) f = std::freopen(stdout_path.c_str(), "w", stdout);
    (void)f;
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    std::_Exit(127);
  }
}

/// The port after `key` ("EGM on 127.0.0.1:") in the child's start-up line; -1 when it never came.
inline int port_of(const Child& c, const std::string& key) {
  for (int i = 0; i < 500; ++i) {
    const std::string text = slurp(c.stderr_path);
    const auto at = text.find(key);
    if (at != std::string::npos) {
      const auto end = text.find(';', at);
      if (end != std::string::npos) return std::stoi(text.substr(at + key.size(), end - at - key.size()));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return -1;
}

/// Ticks a controller stand-in in real time every 4 ms for `seconds`, calling `after_tick()` after each
/// tick (to record what the controller took).
template <class Controller, class AfterTick = void (*)()>
void run_in_real_time(
    Controller& controller, double seconds, AfterTick after_tick = [] {}) {
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  for (;;) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (t > seconds) break;
    controller.tick(t);
    after_tick();
    next += std::chrono::milliseconds(4);
    std::this_thread::sleep_until(next);
  }
}

/// The per-cycle step limit of `deflex online` as these tests run it (4 ms cycle, the default
/// 1 s ramp-in with its 1.5 x 1 deg blend, a 3 deg/s correction rate), deg a joint, computed here: the
/// program's peak speed sampled every 0.5 ms (0.1 % margin), the blend's and the correction's rates,
/// over one cycle.
inline JointVector cli_step_limit_deg(const JointTrajectory& program) {
  const JointVector peak = sampled_peak_speed(program);
  return (0.004 * (peak * 1.001).array() + 0.004 * deg_to_rad(1.5 + 3.0)) * (180.0 / kPi);
}

/// The command-line program under test.
inline const std::string kDeflex = DEFLEX_CLI;

/// The recorded force replay the online tests stream (examples/online/force_replay.csv).
inline const std::string kForceReplay = std::string(DEFLEX_SOURCE_DIR) + "/examples/online/force_replay.csv";

/// `deflex offline --nominal-trajectory` of the paper's circle (r 129.9 mm about (1800, 0, 900) mm) at
/// `speed_mm_s` after `hold_s` at rest, into DIR/nominal.csv; returns its path.
inline std::string nominal_program(const std::string& dir, double speed_mm_s = 30.0, double hold_s = 0.5) {
  const std::string path = dir + "/nominal.csv";
  const auto r = run_cli(
      "offline --circle \"centre_mm=1800;0;900,radius_mm=129.9,points=81\" --force "
      "\"ldbb:phi_deg=30,force_N=400\" --speed-mm-s " +
      std::to_string(speed_mm_s) + " --hold-start-s " + std::to_string(hold_s) + " --nominal-trajectory " + path);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return path;
}

/// A constant reading of the sensor (its frame, N) for 1 s, into DIR/force.csv (loop it for longer): 300
/// N along the tool's axis, 120 N across; returns its path.
inline std::string held_force_csv(const std::string& dir) {
  const std::string path = dir + "/force.csv";
  std::ofstream out(path);
  out << "t_s,fx_N,fy_N,fz_N\n";
  for (int k = 0; k <= 100; ++k) out << k * 0.01 << ",120.0,0.0,300.0\n";
  return path;
}

}  // namespace deflex::test
