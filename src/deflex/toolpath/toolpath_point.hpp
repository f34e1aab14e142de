// The points of a CAM toolpath as deflex reads them from G-code or APT/CL data: the tool tip and the
// tool axis in the workpiece frame (SI units), with the feed, the spindle and the tool that travel with
// every point, and the program line it came from. docs/machining.md states the conventions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "deflex/model/types.hpp"

namespace deflex {

/// How the program moves to a point. Arcs arrive already interpolated into points (chord tolerance of
/// ToolpathOptions); the kind says what the source block was.
enum class MotionKind {
  kRapid,   ///< G0, APT RAPID: positioning, no cutting
  kLinear,  ///< G1, APT GOTO at the feed
  kArcCw,   ///< G2; an APT CIRCLE turning clockwise seen from the spindle (its axis against the tool's)
  kArcCcw,  ///< G3; an APT CIRCLE turning counter-clockwise seen from the spindle
};

// The spindle's turning direction is SpindleTurn (model/types.hpp), shared with the cutting force.

/// One point of a toolpath. Every field is the program's value in effect at the point (modal words
/// carried from earlier blocks).
struct ToolpathPoint {
  Vector3 position_m = Vector3::Zero();  ///< tool tip, workpiece frame, m
  Vector3 tool_axis = Vector3::UnitZ();  ///< unit vector from the tip into the spindle, workpiece frame
  double feed_m_s = 0.0;                 ///< programmed feed (F, at the tool tip), m/s; 0 for rapids
  double spindle_rpm = 0.0;              ///< programmed spindle speed (S), rev/min, >= 0
  SpindleTurn spindle = SpindleTurn::kOff;
  int tool = 0;  ///< tool number in the spindle (T with M6, LOADTL); 0 when none
  MotionKind motion = MotionKind::kRapid;
  std::size_t line = 0;       ///< 1-based line of the source file the point comes from
  std::uint32_t segment = 0;  ///< index of the source motion block (0-based); an arc's points share one
};

/// The unit of lengths in a program (G20/G21, APT UNITS); inside deflex every length is in m.
enum class LengthUnit { kMillimetre, kInch };

/// The plane of G-code arcs (G17, G18, G19).
enum class ArcPlane { kXy, kZx, kYz };

/// What a toolpath file holds, from its extension (toolpath_format_for()).
enum class ToolpathFormat {
  kGcode,  ///< ISO 6983 G-code: .nc .gcode .tap
  kApt,    ///< APT / CL data: .apt .cls
};

/// A milling cutter's shape as the program states it (APT CUTTER/, NX TLDATA/MILL). G-code does not
/// carry it: the cutter then comes from the caller.
struct CutterGeometry {
  double diameter_m = 0.0;
  double corner_radius_m = 0.0;  ///< 0: flat end mill; diameter / 2: ball end mill
  std::size_t line = 0;          ///< where the program states it
};

/// A tool the program uses.
struct ToolEntry {
  int number = 0;
  std::size_t line = 0;                  ///< first line naming it (T word, LOADTL, LOAD/TOOL)
  std::optional<CutterGeometry> cutter;  ///< from the program, when it states one for this tool
};

/// What a reader has seen of a program so far; complete once next() has returned false.
struct ToolpathSummary {
  ToolpathFormat format = ToolpathFormat::kGcode;
  std::string source;                          ///< the file's path (or the name given to text in memory)
  LengthUnit units = LengthUnit::kMillimetre;  ///< in effect at the first point
  bool units_changed = false;                  ///< the program switched units after its first point
  ArcPlane plane = ArcPlane::kXy;              ///< G-code: the plane in effect at the first point
  bool multi_axis = false;                     ///< some point's tool axis is not +z
  /// The cutter stated before the first point, or the first stated (APT CUTTER/, TLDATA/MILL); none
  /// for G-code.
  std::optional<CutterGeometry> cutter;
  std::vector<ToolEntry> tools;   ///< in the order the program names them
  std::size_t lines = 0;          ///< lines read
  std::size_t points = 0;         ///< points given out
  std::size_t motion_blocks = 0;  ///< motion blocks (G0-G3 blocks, GOTOs) that gave points
  std::size_t arcs = 0;           ///< of which arcs
  /// G-code rapids before the position was known on all three axes (a post's first "G0 X.. Y.."
  /// before its "G43 Z.. H.."): they give no point (there is no start to move from). Counted here.
  std::size_t rapids_before_position_known = 0;
};

}  // namespace deflex
