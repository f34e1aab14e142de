// Compensating an existing robot program: an ABB RAPID module or a KUKA KRL program (.src with its
// .dat) in, the same program out with only its motion targets changed, every other byte kept. The
// language readers are rapid_program.hpp and krl_program.hpp; this is the entry point, the report
// and the writing of the result. Reference: docs/offline.md, "Existing programs".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "deflex/force/force_model.hpp"
#include "deflex/model/robot_model.hpp"

namespace deflex {

/// Data declared outside the program, given on the command line in the program's own syntax:
/// "NAME=VALUE", e.g. RAPID "tGun=[TRUE,[[0,0,250],[1,0,0,0]],[5,[0,0,100],[1,0,0,0],0,0,0]]" or
/// KRL "TOOL_DATA[1]={X 0,Y 0,Z 250,A 0,B 0,C 0}" and "$BASE={X 1200,Y 0,Z 600,A 0,B 0,C 0}".
struct ProgramOptions {
  std::vector<std::string> tooldata;  ///< RAPID tooldata, KRL TOOL_DATA[n] or $TOOL
  std::vector<std::string> wobjdata;  ///< RAPID wobjdata, KRL BASE_DATA[n] or $BASE
  /// The arm's joints when the program starts (rad; `--seed-deg`). Where the controller takes the
  /// configuration nearest the arm - the first target under ConfJ\Off or ConfL\Off, a KRL point
  /// without Status and Turn - the one nearest these joints is taken; without them such a target keeps
  /// its own configuration (RAPID) or is listed as left unchanged (KRL).
  std::optional<JointVector> start_q;
};

/// One compensated use of a target.
struct ProgramTargetReport {
  std::string file;
  int line = 0;
  std::string instruction;
  std::string target;  ///< as written in the input
  std::string action;  ///< "edited in place", "literal edited" or "copy NAME"
  /// How the arm configuration was chosen: "" when the target's own (confdata, Status/Turn);
  /// otherwise why not, e.g. "ConfL\\Off: the configuration nearest the previous target's".
  std::string configuration_note;
  double deflection_m = 0.0;  ///< predicted TCP deflection without compensation
  double deflection_rad = 0.0;
  double correction_m = 0.0;          ///< |p_command - p_desired|
  double joint_correction_rad = 0.0;  ///< largest |q_command - q_desired|
  Wrench wrench_base = Wrench::Zero();
};

/// A construct left unchanged because it cannot be resolved statically.
struct UnresolvedConstruct {
  std::string file;
  int line = 0;
  std::string text;  ///< the instruction or target as written
  std::string reason;
};

struct ProgramFile {
  std::string path;
  std::string text;
};

struct ProgramCompensation {
  std::string language;  ///< "RAPID" or "KRL"
  std::string force_description;
  std::vector<ProgramTargetReport> targets;
  std::vector<UnresolvedConstruct> unresolved;
  std::vector<ProgramFile> outputs;  ///< what write_program_outputs() writes
};

/// The files compensate_program() returns for `output_path`: the module for RAPID; for KRL the .src
/// and the .dat beside it. Throws InputError for an unknown program type or a KRL output that is not
/// a .src.
[[nodiscard]] std::vector<std::string> program_output_paths(const std::string& input_path,
                                                            const std::string& output_path);

/// Reads `input_path` (.mod/.modx/.prg/.sys: RAPID; .src: KRL with the .dat beside it, which must
/// exist), resolves and compensates every motion target, and returns the output texts for
/// `output_path` (program_output_paths()). Writes nothing. Throws DataError or InputError naming the
/// file, the line and the name for malformed input, an undeclared tool or work object, an unknown
/// argument in a motion instruction, an unreachable or singular target, an output that is an input.
[[nodiscard]] ProgramCompensation compensate_program(const RobotModel& model, const ForceModel& force,
                                                     const std::string& input_path, const std::string& output_path,
                                                     const ProgramOptions& options = {});

/// Writes every output file, all or none (output_file.hpp); throws InputError or OutputError naming it.
void write_program_outputs(const ProgramCompensation& result);

/// A few lines per target and per unresolved construct (mm, mrad, deg).
[[nodiscard]] std::string program_summary(const ProgramCompensation& result);

}  // namespace deflex
