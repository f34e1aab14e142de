// The controller links `deflex online --link NAME` can run, each registered from its own file
// (online_link_egm.cpp, ...), so a further controller adds a file here, not a branch in the command.
// A link kind adds its own options to the `online` subcommand (validated only when it is chosen) and
// builds a session: the sockets it needs and the link itself, from what every link shares.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "deflex/link/controller_link.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/transport/clock.hpp"

namespace deflex::cli {

/// What every link is built from (all owned by the command, outliving the session).
struct OnlineContext {
  const RobotModel& model;
  OnlineCompensator& compensator;
  OnlineStrategy& strategy;
  ForceSource* force;
  const Clock& clock;
  std::string bind_address;  ///< --bind
  std::shared_ptr<const JointTrajectory> program;  ///< --program, for streaming links (null otherwise)
  double period_s;  ///< --period-ms
};

/// A running link and what it owns (its sockets).
class LinkSession {
 public:
  virtual ~LinkSession() = default;
  virtual ControllerLink& link() = 0;
  /// Where the controller reaches deflex, for the start-up line ("EGM on 127.0.0.1:6510").
  [[nodiscard]] virtual std::string where() const = 0;
  /// A link-specific part of the status line (may be empty).
  [[nodiscard]] virtual std::string status() const { return ""; }
  /// The link-specific part of the final summary (may be empty).
  [[nodiscard]] virtual std::string summary() const { return ""; }
};

struct LinkKindInfo {
  std::string name;  ///< the --link value
  std::string help;
  bool streams_program = false;  ///< needs --program (deflex is the motion source)
  std::function<void(CLI::App& online)> add_options;
  /// Validates the link's options (InputError naming the option) and builds the session.
  std::function<std::unique_ptr<LinkSession>(const OnlineContext&)> make;
};

std::vector<LinkKindInfo>& link_kind_registry();

struct LinkKindRegistrar {
  explicit LinkKindRegistrar(LinkKindInfo info);
};

}  // namespace deflex::cli

#define DEFLEX_LINK_CONCAT2(a, b) a##b
#define DEFLEX_LINK_CONCAT(a, b) DEFLEX_LINK_CONCAT2(a, b)
/// DEFLEX_LINK_KIND(LinkKindInfo{...}) at namespace scope in an online_link_*.cpp file.
#define DEFLEX_LINK_KIND(...) \
  static const ::deflex::cli::LinkKindRegistrar DEFLEX_LINK_CONCAT(deflex_link_kind_, __LINE__)(__VA_ARGS__)
