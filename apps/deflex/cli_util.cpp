// Command-line parsing helpers shared by the subcommands.
#include "cli_util.hpp"

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include <fmt/format.h>

#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex::cli {

std::vector<double> parse_numbers(const std::string& text, const std::string& option, std::size_t expected,
                                  const InputRange& range) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto b = item.find_first_not_of(" \t");
    const auto e = item.find_last_not_of(" \t");
    const std::string t = b == std::string::npos ? "" : item.substr(b, e - b + 1);
    const std::optional<double> v = parse_double(t);
    if (!v) {
      throw InputError(fmt::format("option {}: {} (value {} of '{}')", option, not_a_number(t), out.size() + 1, text));
    }
    if (const auto bad = range_violation(*v, range)) {
      throw InputError(fmt::format("option {}: value {}: {}", option, out.size() + 1, *bad));
    }
    out.push_back(*v);
  }
  if (expected != 0 && out.size() != expected) {
    throw InputError(
        fmt::format("option {}: expected {} comma-separated numbers, got {}", option, expected, out.size()));
  }
  return out;
}

JointVector parse_joints_deg(const std::string& text, const RobotModel& model, const std::string& option) {
  const auto v = parse_numbers(text, option, static_cast<std::size_t>(model.dof()), range::kAngleDeg);
  JointVector q(model.dof());
  for (int i = 0; i < model.dof(); ++i) {
    q[i] = deg_to_rad(v[static_cast<std::size_t>(i)]);
  }
  return q;
}

Wrench parse_wrench(const std::string& text, const std::string& option) {
  const auto v = parse_numbers(text, option, 6);
  Wrench w;
  for (int i = 0; i < 6; ++i) {
    w[i] = v[static_cast<std::size_t>(i)];
    if (const auto bad = range_violation(w[i], i < 3 ? range::kForceN : range::kMomentNm)) {
      throw InputError(fmt::format("option {}: value {} ({}): {}", option, i + 1,
                                   std::array{"Fx", "Fy", "Fz", "Mx", "My", "Mz"}[static_cast<std::size_t>(i)], *bad));
    }
  }
  return w;
}

const char* const kStiffnessHelp =
    "Joint stiffness \"k1,...,kN\" in Nm/rad, one value a joint; replaces the robot file's (a bare URDF has none)";

RobotModel load_cli_robot(const std::string& command, const std::string& robot_path,
                          const std::string& stiffness_text) {
  RobotModel model = load_robot_or_builtin(robot_path == "builtin" ? std::string() : robot_path);
  for (const std::string& note : model.description().notes) {
    std::cerr << fmt::format("deflex {}: note: {}\n", command, note);
  }
  if (stiffness_text.empty()) {
    return model;
  }
  const std::vector<double> k =
      parse_numbers(stiffness_text, "--stiffness-Nm-per-rad", static_cast<std::size_t>(model.dof()));
  for (std::size_t i = 0; i < k.size(); ++i) {
    if (const auto bad = range_violation(k[i], range::kJointStiffness)) {
      throw InputError(fmt::format("option --stiffness-Nm-per-rad: value {}: {}", i + 1, *bad));
    }
  }
  return model.with_stiffness(k, "given on the command line (--stiffness-Nm-per-rad)");
}

void require_stiffness(const RobotModel& model) {
  if (!model.has_stiffness()) {
    throw InputError(
        fmt::format("robot '{}' ({}) has no joint stiffness: give it with --stiffness-Nm-per-rad "
                    "\"k1,...,k{}\" (Nm/rad) or in a robot file (joint_stiffness_Nm_per_rad, "
                    "docs/robot-file.md)",
                    model.name(), model.description().source, model.dof()));
  }
}

nlohmann::json to_json(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      row.push_back(m(r, c));
    }
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json vector_to_json(const Eigen::Ref<const Eigen::VectorXd>& v) {
  nlohmann::json out = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    out.push_back(v[i]);
  }
  return out;
}

void print_json(const nlohmann::json& doc) {
  // A byte that is not UTF-8 (a file name, a program's text) becomes U+FFFD rather than an exception:
  // the readers refuse such text in the fields they take, names given by the shell may still carry it.
  std::cout << doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << std::endl;
}

void draw_study_progress(const char* command, double fraction, const std::string& label) {
  static const bool terminal = ::isatty(STDERR_FILENO) != 0;
  if (!terminal) {
    static int tenths_shown = -1;
    const int tenths = static_cast<int>(std::floor(fraction * 10.0 + 1e-9));
    if (tenths > tenths_shown) {
      tenths_shown = tenths;
      std::fprintf(stderr, "deflex %s: %3d %% %s\n", command, tenths * 10, label.c_str());
      std::fflush(stderr);
    }
    return;
  }
  constexpr int kWidth = 32;
  const int filled = static_cast<int>(std::lround(fraction * kWidth));
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(kWidth, '.');
  std::fprintf(stderr, "\r[%s] %3.0f%% %-40.40s", bar.c_str(), fraction * 100.0, label.c_str());
  std::fflush(stderr);
}

void end_study_progress() {
  if (::isatty(STDERR_FILENO) != 0) std::cerr << "\n";
}

}  // namespace deflex::cli
