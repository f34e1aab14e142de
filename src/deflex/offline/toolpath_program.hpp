// A compensated toolpath as a robot program, written a point at a time (a program of a million
// points costs no memory): ABB RAPID (a module of MoveL instructions with inline robtargets in a
// work object that is the workpiece frame, the program's feed as the TCP speed) or KUKA KRL (a .src
// of LIN motions in $BASE = the workpiece frame, $VEL.CP at the program's feed). The compensated
// G-code goes through toolpath/gcode_write_back.hpp instead.
#pragma once

#include <string>

#include "deflex/offline/compensate_path.hpp"
#include "deflex/text/output_file.hpp"
#include "deflex/toolpath/toolpath_point.hpp"

namespace deflex {

/// What a --program-out of a toolpath run is, from its extension (any case).
enum class ToolpathOutputKind {
  kGcode,  ///< .nc .gcode .tap: the source program with its motions moved (toolpaths read from G-code)
  kRapid,  ///< .mod .modx .prg: an ABB RAPID module
  kKrl,    ///< .src: a KUKA KRL program
};

/// Throws InputError naming the file and listing the extensions for any other.
[[nodiscard]] ToolpathOutputKind toolpath_output_kind(const std::string& path);

struct ToolpathProgramOptions {
  /// RAPID module and KRL DEF name: a letter, then letters, digits or _, at most 24 characters.
  std::string name = "DeflexToolpath";
  /// RAPID tooldata (the controller's; its TCP must be the robot model's: the tool tip, z out of
  /// the spindle along the tool).
  std::string tool = "tool0";
  /// RAPID work object the module declares from the workpiece placement.
  std::string wobj = "wobjDeflex";
  /// "fine" or a fly-by zone z0, z1, ... (RAPID zonedata; KRL: C_DIS with $APO.CDIS the zone's mm,
  /// 0.3 for z0).
  std::string zone = "z0";
  Pose base_T_workpiece = Pose::Identity();
  double rapid_speed_mm_s = 250.0;  ///< positioning moves (G0, RAPID) and the first move
  std::string header;               ///< comment lines at the top (what was compensated, for what force)
};

/// Thread safety: one thread at a time.
class ToolpathProgramWriter {
 public:
  /// Writes the program's head into `out`. Throws InputError for a name, tool, work object or zone
  /// that is not valid, or a robot that does not have 6 joints.
  ToolpathProgramWriter(OutputFile& out, ToolpathOutputKind kind, const ToolpathProgramOptions& options,
                        const RobotModel& model);
  ToolpathProgramWriter(OutputFile& out, ToolpathOutputKind kind, const ToolpathProgramOptions& options,
                        RobotModel&& model) = delete;
  ~ToolpathProgramWriter();
  ToolpathProgramWriter(const ToolpathProgramWriter&) = delete;
  ToolpathProgramWriter& operator=(const ToolpathProgramWriter&) = delete;

  /// The next point: a move to its compensated pose (tcp_command, in the workpiece frame) with its
  /// configuration, at the point's feed (a rapid at the rapid speed); the first point by joint motion.
  void add(const ToolpathPoint& point, const OfflinePoint& compensated);
  /// Closes the program; `trailer` (lines) goes in as comments before its end.
  void finish(const std::string& trailer);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace deflex
