// deflex: the command-line program. Parses options, calls the library, prints. Subcommands live in
// cmd_*.cpp files and register themselves (command.hpp).
#include <algorithm>
#include <iostream>

#include <fmt/format.h>

#include "command.hpp"
#include "option_ranges.hpp"
#include "deflex/model/errors.hpp"

namespace deflex::cli {

std::vector<CommandInfo>& command_registry() {
  static std::vector<CommandInfo> registry;
  return registry;
}

CommandRegistrar::CommandRegistrar(std::string name, std::string help, CommandSetup setup, int order) {
  command_registry().push_back({std::move(name), std::move(help), std::move(setup), order});
}

}  // namespace deflex::cli

int main(int argc, char** argv) {
  using namespace deflex::cli;
  CLI::App app{
      "deflex: predicts and compensates the elastic deflection of industrial robots under process forces.\n"
      "Units: SI inside (m, rad, N, Nm, s); options and CSV columns name their unit (mm, deg where users expect them)."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "deflex 0.1.0");
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
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version: printed, exit 0
  } catch (const CLI::ParseError& e) {
    // Every usage error is bad input: exit 2 like a bad file, never CLI11's own codes (104-114).
    std::cerr << usage_error_message(app, active, std::vector<std::string>(argv + 1, argv + argc), e) << "\n";
    return 2;
  } catch (const deflex::Error& e) {
    std::cerr << fmt::format("deflex {}: error: {}\n", active, e.what());
    return 2;
  } catch (const std::exception& e) {
    std::cerr << fmt::format("deflex {}: internal error: {}\n", active, e.what());
    return 3;
  }
  return exit_code;
}
