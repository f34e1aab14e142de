// `deflex offline --toolpath`: a CAM toolpath compensated for its milling force, the spindle's free
// angle chosen for stiffness; the options the toolpath run takes from the offline command.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "deflex/model/inverse_kinematics.hpp"

namespace deflex::cli {

struct ToolpathRunOptions {
  std::string robot, stiffness;
  std::string toolpath, workpiece, cutter, stock, tool_spin = "optimize", reader_options;
  std::vector<std::string> forces;
  std::string csv_out, program_out, plot_out;
  std::string zone, tool = "tool0", wobj, name;  // empty: the toolpath defaults (z0, wobjDeflex, DeflexToolpath)
  bool json = false;
};

/// Runs it; `first_request` gives the first point's IK request from --config and --seed-deg.
void run_offline_toolpath(const ToolpathRunOptions& options,
                          const std::function<IkRequest(const RobotModel&)>& first_request, int& exit_code);

}  // namespace deflex::cli
