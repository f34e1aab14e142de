// Command-line parsing helpers shared by the subcommands.
#include "cli_util.hpp"

#include <cmath>
#include <iostream>
#include <sstream>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex::cli {

std::vector<double> parse_numbers(const std::string& text, const std::string& option, std::size_t expected) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto b = item.find_first_not_of(" \t");
    const auto e = item.find_last_not_of(" \t");
    const std::string t = b == std::string::npos ? "" : item.substr(b, e - b + 1);
    double v = 0.0;
    std::size_t used = 0;
    try {
      v = std::stod(t, &used);
    } catch (const std::logic_error&) {
      used = 0;
    }
    if (t.empty() || used != t.size()) {
      throw InputError(fmt::format("option {}: '{}' is not a number (value {} of '{}')", option, t, out.size() + 1, text));
    }
    if (!std::isfinite(v)) {
      throw InputError(fmt::format("option {}: value {} is not finite", option, out.size() + 1));
    }
    out.push_back(v);
  }
  if (expected != 0 && out.size() != expected) {
    throw InputError(fmt::format("option {}: expected {} comma-separated numbers, got {}", option, expected, out.size()));
  }
  return out;
}

JointVector parse_joints_deg(const std::string& text, const RobotModel& model, const std::string& option) {
  const auto v = parse_numbers(text, option, static_cast<std::size_t>(model.dof()));
  JointVector q(model.dof());
  for (int i = 0; i < model.dof(); ++i) {
    q[i] = deg_to_rad(v[static_cast<std::size_t>(i)]);
  }
  return q;
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

void print_json(const nlohmann::json& doc) { std::cout << doc.dump(2) << std::endl; }

}  // namespace deflex::cli
