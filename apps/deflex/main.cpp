// deflex: the command-line program. Parses options, calls the library, prints. Subcommands live in
// cmd_*.cpp files and register themselves (command.hpp).
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>

#include "command.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"
#include "deflex/text/run_files.hpp"
#include "deflex/version.hpp"
#include "option_ranges.hpp"

namespace deflex::cli {

std::vector<CommandInfo>& command_registry() {
  static std::vector<CommandInfo> registry;
  return registry;
}

CommandRegistrar::CommandRegistrar(std::string name, std::string help, CommandSetup setup, int order) {
  command_registry().push_back({std::move(name), std::move(help), std::move(setup), order});
}

namespace {

/// A standard stream closed by the caller (`deflex ... >&-`) gets a placeholder that fails every
/// write: the read end of a pipe of its own. Otherwise the first file deflex opens would take its
/// number, and the summary meant for stdout would land in an output file.
void hold_closed_standard_streams() {
  for (int fd = STDIN_FILENO; fd <= STDERR_FILENO; ++fd) {
    if (::fcntl(fd, F_GETFD) != -1 || errno != EBADF) {
      continue;
    }
    int p[2];
    if (::pipe(p) != 0) {
      continue;
    }
    if (p[0] != fd) {
      ::dup2(p[0], fd);  // closes p[1] first when that took fd's number
      ::close(p[0]);
    }
    if (p[1] != fd) {
      ::close(p[1]);
    }
    if (fd != STDIN_FILENO) {
      deflex::mark_standard_stream_closed(fd);
    }
  }
}

/// The command's stdout must have reached it: a closed stdout or a full disk is a failed job.
int check_stdout(const std::string& active, int exit_code) {
  std::cout.flush();
  const bool failed = std::cout.fail() || std::fflush(stdout) != 0 || std::ferror(stdout) != 0;
  if (!failed) {
    return exit_code;
  }
  std::cerr << fmt::format("deflex {}: error: writing to stdout failed ({})\n", active,
                           errno != 0 ? std::strerror(errno) : "stream error");
  return exit_code == 0 ? 1 : exit_code;
}

/// The program. What it throws while setting itself up (before a command runs) reaches main().
int run_program(int argc, char** argv) {
  hold_closed_standard_streams();
  deflex::remove_temporaries_on_signals();  // Ctrl-C leaves no temporary file beside an output
  CLI::App app{
      "deflex: predicts and compensates the elastic deflection of industrial robots under process forces.\n"
      "Units: SI inside (m, rad, N, Nm, s); options and CSV columns name their unit (mm, deg where users expect "
      "them)."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("deflex ") + kVersion);
  auto commands = command_registry();
  std::stable_sort(commands.begin(), commands.end(), [](const auto& a, const auto& b) { return a.order < b.order; });
  int exit_code = 0;
  std::string active;
  for (const auto& c : commands) {
    CLI::App* sub = app.add_subcommand(c.name, c.help);
    c.setup(*sub, exit_code);
    sub->preparse_callback([&active, name = c.name](std::size_t) { active = name; });
  }
  add_option_range_checks(app);
  // One run: no file is both read and written by the command (run_files.hpp).
  const deflex::RunFilesScope run_files;
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return check_stdout("", app.exit(e));  // --help, --version: printed, exit 0
  } catch (const CLI::ParseError& e) {
    // Every usage error is bad input: exit 2 like a bad file, never CLI11's own codes (104-114).
    std::cerr << usage_error_message(app, active, std::vector<std::string>(argv + 1, argv + argc), e) << "\n";
    return 2;
  } catch (const deflex::OutputError& e) {
    // An output could not be written: the job failed (nothing was left half-written).
    std::cerr << fmt::format("deflex {}: error: {}\n", active, e.what());
    return check_stdout(active, 1);
  } catch (const deflex::Error& e) {
    std::cerr << fmt::format("deflex {}: error: {}\n", active, e.what());
    return 2;
  } catch (const std::exception& e) {
    std::cerr << fmt::format("deflex {}: internal error: {}\n", active, e.what());
    return 3;
  }
  return check_stdout(active, exit_code);
}

}  // namespace

}  // namespace deflex::cli

int main(int argc, char** argv) {
  // Nothing leaves main as an exception: setting up the commands can still throw (out of memory).
  try {
    return deflex::cli::run_program(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "deflex: internal error: %s\n", e.what());
  } catch (...) {
    std::fputs("deflex: internal error\n", stderr);
  }
  return 3;
}
