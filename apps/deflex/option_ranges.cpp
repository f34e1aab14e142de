// Range checks of numeric options, and usage error messages with suggestions.
#include "option_ranges.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "deflex/text/input_ranges.hpp"
#include "deflex/text/nearest_name.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex::cli {
namespace {

bool ends_with(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

// The range of a numeric option, by its long name. Exact names first (where the unit alone is too
// wide: a period of 1e-9 ms would spin, a count of 1e9 poses would never end), then unit suffixes.
InputRange option_range(const std::string& name, bool integer) {
  // A noise is never negative, a limit on a standard deviation and an averaging window never zero.
  static constexpr InputRange kNoiseMm{"noise", "mm", 0.0, 1e3};
  static constexpr InputRange kStdN{"standard deviation", "N", 1e-9, 1e6};
  static constexpr InputRange kStdNm{"standard deviation", "Nm", 1e-9, 1e6};
  static constexpr InputRange kWindowS{"averaging window", "s", 1e-3, 3600.0};
  static const std::array<std::pair<std::string_view, InputRange>, 21> kByName{{
      {"--period-ms", range::kPeriodMs},
      {"--threads", {"thread count", "", 0.0, 256.0}},
      {"--seeds", {"seed count", "", 1.0, 1000.0}},
      {"--seed", {"seed", "", 0.0, 4294967295.0}},
      {"--poses", {"pose count", "", 1.0, 100000.0}},
      {"--loads-per-pose", {"load count", "", 1.0, 100.0}},
      {"--evaluation-points", {"point count", "", 1.0, 100000.0}},
      {"--buffer-depth", {"buffer depth", "", 1.0, 1000.0}},
      {"--max-relative-std-error", {"relative standard error", "", 1e-6, 1e3}},
      {"--rsi-monitor-factor", {"factor", "", 0.0, 1000.0}},
      {"--rotation-scale-m", {"length", "m", 1e-6, 100.0}},
      {"--clock-offset-s", range::kTimeS},  // a clock difference: either sign
      {"--noise-mm", kNoiseMm},
      {"--synthetic-noise-mm", kNoiseMm},
      {"--max-std-N", kStdN},
      {"--tare-max-std-N", kStdN},
      {"--max-std-Nm", kStdNm},
      {"--tare-max-std-Nm", kStdNm},
      {"--window-s", kWindowS},
      {"--tare-window-s", kWindowS},
      {"--max-rms-mm", {"RMS limit", "mm", 1e-6, 1e5}},
  }};
  for (const auto& [n, r] : kByName) {
    if (name == n) {
      return r;
    }
  }
  if (name.find("port") != std::string::npos) {
    return {"UDP/TCP port", "", 0.0, 65535.0};
  }
  static const std::array<std::pair<std::string_view, InputRange>, 9> kBySuffix{{
      {"-ms", {"time", "ms", 0.0, 60e3}},
      {"-deg-s", {"joint speed", "deg/s", 0.0, 1e5}},
      {"-mm-s", range::kSpeedMmS},
      {"-hz", range::kRateHz},
      {"-s", range::kDurationS},
      {"-deg", range::kAngleDeg},
      {"-mm", range::kLengthMm},
      {"-m", range::kLengthM},
      {"-N", range::kForceN},
  }};
  for (const auto& [suffix, r] : kBySuffix) {
    if (ends_with(name, suffix)) {
      return r;
    }
  }
  return integer ? InputRange{"count", "", 0.0, 1e7} : range::kAnyValue;
}

CLI::Validator range_validator(const InputRange& r, bool integer) {
  return CLI::Validator(
      [r, integer](std::string& text) -> std::string {
        const std::optional<double> v = parse_double(trim_view(text));
        if (!v) {
          return not_a_number(text);
        }
        if (integer && *v != std::floor(*v)) {
          return fmt::format("'{}' is not a whole number", text);
        }
        const auto bad = range_violation(*v, r);
        return bad ? *bad : std::string();
      },
      "", "deflex range");
}

// An empty value never means the default: `--robot ""` (a variable that was not set) would otherwise
// run on the built-in arm, `--expect-frame ""` check nothing.
CLI::Validator not_empty() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        return trim_view(text).empty() ? "an empty value: give one, or leave the option out for its default"
                                       : std::string();
      },
      "", "not empty");
}

void add_checks(CLI::App& app) {
  for (CLI::Option* opt : app.get_options()) {
    const std::string type = opt->get_type_name();
    const bool integer = type == "INT" || type == "UINT";
    if (type == "TEXT" && !opt->get_lnames().empty()) {
      if (opt->get_expected_min() > 0) {  // `--circle` alone (no value) means its defaults
        opt->check(not_empty());
      }
      continue;
    }
    if (!(integer || type == "FLOAT") || opt->get_lnames().empty()) {
      continue;
    }
    opt->check(range_validator(option_range("--" + opt->get_lnames().front(), integer), integer));
  }
  for (CLI::App* sub : app.get_subcommands({})) {
    add_checks(*sub);
  }
}

std::vector<std::string> option_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* opt : app.get_options()) {
    for (const std::string& l : opt->get_lnames()) {
      names.push_back("--" + l);
    }
  }
  return names;
}

}  // namespace

void add_option_range_checks(CLI::App& app) { add_checks(app); }

std::string usage_error_message(const CLI::App& app, const std::string& active, const std::vector<std::string>& args,
                                const CLI::ParseError& e) {
  const std::string command = active.empty() ? "deflex" : "deflex " + active;
  std::string message = e.what();
  // CLI11 reports a missing required option before an unknown one, so `fk --jionts-deg 1` would say
  // only that --joints-deg is required: the misspelt names are found in the arguments themselves.
  std::vector<std::string> unknown;
  std::vector<std::string> candidates;
  if (active.empty()) {
    for (const CLI::App* sub : app.get_subcommands({})) {
      candidates.push_back(sub->get_name());
    }
    if (!args.empty() && !args.front().empty() && args.front()[0] != '-') {
      unknown.push_back(args.front());
    }
  } else {
    candidates = option_names(*app.get_subcommand(active));
    for (const std::string& o : option_names(app)) {
      candidates.push_back(o);
    }
    bool after_command = false;
    for (const std::string& a : args) {
      if (!after_command) {
        after_command = a == active;
        continue;
      }
      const std::string key = a.substr(0, a.find('='));
      const bool is_option_name = key.size() > 2 && key.rfind("--", 0) == 0 && !parse_double(key);
      if (is_option_name && std::find(candidates.begin(), candidates.end(), key) == candidates.end()) {
        unknown.push_back(key);
      }
    }
  }
  if (!unknown.empty()) {
    message.clear();
    for (const std::string& u : unknown) {
      message += fmt::format("{}unknown {} '{}'{}", message.empty() ? "" : "; ",
                             active.empty() ? "subcommand" : "option", u, did_you_mean(u, candidates));
    }
  }
  if (message.rfind("--", 0) == 0) {
    message = "option " + message;  // the way deflex's own option errors read
  }
  return fmt::format("{}: error: {} (see '{} --help')", command, message, command);
}

}  // namespace deflex::cli
