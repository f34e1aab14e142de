// Reading an existing KUKA KRL program (.src with its .dat) and writing it back compensated: PTP,
// LIN and CIRC to E6POS/POS/FRAME and E6AXIS/AXIS points declared in the .dat (arrays included) or
// written inline, their Status and Turn, $TOOL and $BASE followed through the .src (assignments of
// a literal frame, a FRAME of the .dat or TOOL_DATA[n]/BASE_DATA[n], FDAT_ACT of the inline forms,
// BAS(#TOOL/#BASE, n)), with TOOL_DATA and BASE_DATA (the controller's $config.dat) from the command
// line.
// Only the numbers of the points the motions reach change; a point whose uses need different
// values, or that other code refers to, gets a compensated copy per use declared after it.
#pragma once

#include <string>

#include "deflex/offline/program_compensation.hpp"

namespace deflex {

/// Compensates the program `src_text` (read from `src_file`) with its data list `dat_text` (read from
/// `dat_file`, empty when the program has none); the outputs are `output_src` and the .dat beside it.
/// The robot's joint values are taken as the controller's axis values A1..A6 (the ROS-Industrial
/// convention). See compensate_program() for what it throws.
[[nodiscard]] ProgramCompensation compensate_krl_program(const RobotModel& model, const ForceModel& force,
                                                         const std::string& src_file, const std::string& src_text,
                                                         const std::string& dat_file, const std::string& dat_text,
                                                         const std::string& output_src, const ProgramOptions& options);

}  // namespace deflex
