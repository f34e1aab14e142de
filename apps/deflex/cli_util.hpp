// Small helpers every subcommand uses: parsing comma-separated numbers with errors that name the
// option, and printing JSON or text.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "deflex/model/robot_model.hpp"
#include "deflex/text/input_ranges.hpp"

namespace deflex::cli {

/// The --robot option's help where a robot file is optional.
inline constexpr const char* kRobotHelp =
    "Robot file (.yaml deflex format or .urdf); default: the built-in ABB IRB 6700-300/2.70";

/// "1, 2.5,3" -> {1, 2.5, 3}. Throws InputError naming `option` on a bad number, NaN/inf, a value
/// outside `range` (input_ranges.hpp), or when `expected` (if non-zero) does not match the count.
std::vector<double> parse_numbers(const std::string& text, const std::string& option, std::size_t expected = 0,
                                  const InputRange& range = range::kAnyValue);

/// Joint values given in degrees on the command line (each within +-3600 deg), to rad, checked
/// against the robot's dof.
JointVector parse_joints_deg(const std::string& text, const RobotModel& model, const std::string& option);

/// A wrench "Fx,Fy,Fz,Mx,My,Mz" in N and Nm, each within the force and moment ranges (+-1e6).
Wrench parse_wrench(const std::string& text, const std::string& option);

/// The robot of `--robot` (empty or "builtin": the built-in IRB6700). `stiffness_text` (the option
/// --stiffness-Nm-per-rad, "k1,...,kN" in Nm/rad) replaces the file's joint stiffness when given.
/// The loader's notes (e.g. which URDF chain was chosen) go to stderr as "deflex COMMAND: note: ...".
/// Throws ModelError or InputError naming the file or the option.
RobotModel load_cli_robot(const std::string& command, const std::string& robot_path,
                          const std::string& stiffness_text = "");

/// Help text of --stiffness-Nm-per-rad, shared by the subcommands that take it.
extern const char* const kStiffnessHelp;

/// Throws InputError unless the robot has joint stiffness, saying how to give it.
void require_stiffness(const RobotModel& model);

/// JSON array of an Eigen vector or matrix (row-major nested arrays for matrices).
nlohmann::json to_json(const Eigen::Ref<const Eigen::MatrixXd>& m);
nlohmann::json vector_to_json(const Eigen::Ref<const Eigen::VectorXd>& v);

/// Prints a JSON document on stdout (only the document, so scripts can pipe it).
void print_json(const nlohmann::json& doc);

/// A long study's progress on stderr: on a terminal a bar redrawn in place; into a log or a pipe a
/// plain line "deflex COMMAND:  40 % label" at each tenth of the way (a carriage-return bar would
/// leave one line of some 50 kB there). Called under the study's progress lock.
void draw_study_progress(const char* command, double fraction, const std::string& label);
/// Ends the bar's line on a terminal (after a study drawn with draw_study_progress).
void end_study_progress();

}  // namespace deflex::cli
