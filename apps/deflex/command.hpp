// Subcommand registry of the deflex program. Each apps/deflex/cmd_*.cpp registers its subcommands
// with a static DEFLEX_COMMAND(...) object, so adding a subcommand touches no shared file.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace deflex::cli {

/// Adds options to the subcommand and sets its callback. The callback returns the exit code
/// (0 success, 1 the job failed, 2 bad input); deflex::Error thrown from it is reported as
/// "deflex NAME: error: ..." with exit code 2.
using CommandSetup = std::function<void(CLI::App& sub, int& exit_code)>;

struct CommandInfo {
  std::string name;
  std::string help;
  CommandSetup setup;
  int order = 100;  ///< position in --help
};

std::vector<CommandInfo>& command_registry();

struct CommandRegistrar {
  CommandRegistrar(std::string name, std::string help, CommandSetup setup, int order = 100);
};

}  // namespace deflex::cli

#define DEFLEX_CLI_CONCAT2(a, b) a##b
#define DEFLEX_CLI_CONCAT(a, b) DEFLEX_CLI_CONCAT2(a, b)
/// DEFLEX_COMMAND("name", "help", setup [, order]) at namespace scope in a cmd_*.cpp file.
/// The registrar's name is numbered by __COUNTER__, not __LINE__: in a unity build several cmd_*.cpp
/// files share one translation unit, and two invocations on the same line would collide (clang counts
/// a multi-line invocation's line differently from GCC, so one compiler's success proves nothing).
#define DEFLEX_COMMAND(...) \
  static const ::deflex::cli::CommandRegistrar DEFLEX_CLI_CONCAT(deflex_command_, __COUNTER__)(__VA_ARGS__)
