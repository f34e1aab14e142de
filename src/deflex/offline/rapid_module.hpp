// ABB RAPID export of a compensated path: one program module that moves through the compensated
// targets, either joint targets (MoveAbsJ) or Cartesian robtargets with confdata (MoveL).
#pragma once

#include <string>

#include "deflex/offline/compensate_path.hpp"

namespace deflex {

enum class RapidMotion {
  kMoveAbsJ,  ///< jointtargets of q_command: exactly the compensated joints, joint interpolation
  kMoveL,     ///< robtargets of tcp_command with confdata (ConfL\On): straight TCP lines between points
};

struct RapidOptions {
  std::string module_name = "DeflexOffline";  ///< RAPID identifier: letter first, [A-Za-z0-9_], <= 32 chars
  RapidMotion motion = RapidMotion::kMoveAbsJ;
  /// TCP speed (speeddata v_tcp), mm/s; the paper ran 10, 30 and 50 mm/s. 0 < v <= 7000.
  double speed_mm_s = 10.0;
  /// Predefined zonedata: "fine" (stop at each point, the default: the compensated pose is reached
  /// exactly) or a fly-by zone z0, z1, z5, z10, ... (corner cut of that many mm).
  std::string zone = "fine";
  std::string tool = "tool0";  ///< tooldata the controller knows (the robot model's TCP must match it)
  std::string wobj = "wobj0";  ///< work object; robtargets are in the robot base frame (wobj0)
  std::string note;            ///< extra header comment lines (e.g. the command that produced it)
};

/// The module's text. Checks the options and the result (6 joints, finite values) and throws
/// InputError naming the one at fault. Numbers: mm and degrees with 4 decimals, quaternions with 8,
/// external axes 9E+09 (unused), as ABB's own programs write them.
[[nodiscard]] std::string rapid_module(const OfflineResult& result, const RapidOptions& options);

/// The option checks of rapid_module() alone (names, speed, zone), so a caller can fail before it
/// computes or writes anything. Throws InputError.
void check_rapid_options(const RapidOptions& options);

/// rapid_module() to a file of its own (output_file.hpp). Throws InputError or OutputError naming it.
void write_rapid_module(const OfflineResult& result, const RapidOptions& options, const std::string& path);

/// True for a valid RAPID identifier (used to check module, tool and work object names).
[[nodiscard]] bool is_rapid_identifier(const std::string& name);

}  // namespace deflex
