// Every numeric command-line option checked the way file values are: parsed locale-independently,
// finite, and inside the physical range its unit allows, in one table keyed by the option's unit
// suffix ("--period-ms", "--speed-mm-s", "--load-N"); and every usage error reported with exit code 2,
// the option named and, for a typo, the nearest known name.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace deflex::cli {

/// Adds the range check of its unit to every numeric option of every subcommand of `app` (options
/// that carry their own CLI11 check keep it and get the finite-number check only).
void add_option_range_checks(CLI::App& app);

/// The message for a CLI11 parse error, with the subcommand's help hint; an unknown option or
/// subcommand among `args` (argv without the program name) is named first, with "did you mean
/// '--joints-deg'?". `active` is the subcommand being parsed ("" if none).
[[nodiscard]] std::string usage_error_message(const CLI::App& app, const std::string& active,
                                              const std::vector<std::string>& args, const CLI::ParseError& e);

}  // namespace deflex::cli
