// Reading an existing ABB RAPID module and writing it back compensated: robtarget and jointtarget
// declarations (CONST, PERS, VAR, arrays), MoveL, MoveJ, MoveC and MoveAbsJ with literal or named
// targets, Offs() and RelTool() on them, tooldata and wobjdata from the module or the command line.
// Only the numbers of the targets the motions reach change; a target whose uses need different
// values, or that other code refers to, gets a compensated copy per use declared right after it.
#pragma once

#include <string>

#include "deflex/offline/program_compensation.hpp"

namespace deflex {

/// Compensates the module `text` read from `file`; the output is for `output_path`. See
/// compensate_program() for what it throws.
[[nodiscard]] ProgramCompensation compensate_rapid_module(const RobotModel& model, const ForceModel& force,
                                                          const std::string& file, const std::string& text,
                                                          const std::string& output_path,
                                                          const ProgramOptions& options);

}  // namespace deflex
