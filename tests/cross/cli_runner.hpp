// Test helper: runs the deflex program (DEFLEX_CLI) with arguments and captures its exit code,
// stdout and stderr separately.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

namespace deflex::test {

struct CliRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Runs `command` with sh (quote its words yourself), capturing its exit code, stdout and stderr.
inline CliRun run_shell(const std::string& command) {
  static int counter = 0;
  const auto dir = std::filesystem::temp_directory_path();
  const std::string tag = std::to_string(::getpid()) + "_" + std::to_string(counter++);
  const auto out = dir / ("deflex_cli_out_" + tag);
  const auto err = dir / ("deflex_cli_err_" + tag);
  const std::string cmd = command + " >" + out.string() + " 2>" + err.string() + " </dev/null";
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

/// `args` is appended to the program path as shell words (quote them yourself).
inline CliRun run_cli(const std::string& args) { return run_shell(std::string(DEFLEX_CLI) + " " + args); }

}  // namespace deflex::test
