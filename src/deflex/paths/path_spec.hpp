// Circle and line paths from a one-line text specification (command line, case files):
//
//   centre_mm=X;Y;Z,radius_mm=R,normal=NX;NY;NZ,start_deg=A,direction=ccw|cw,points=N,reference=RX;RY;RZ
//   start_mm=X;Y;Z,end_mm=X;Y;Z,points=N
//
// Every circle key is optional; the defaults make deflex's reference circle for the IRB6700: centre
// (1500, 0, 1000) mm, radius 100 mm, in the base XY plane (normal +z), starting on +x,
// counter-clockwise, 81 points (4.5 deg apart, the last repeating the first, as the paper's 81
// configurations). A line needs start_mm and end_mm; points defaults to 2.
#pragma once

#include <string>

#include "deflex/paths/circle_path.hpp"
#include "deflex/paths/line_path.hpp"

namespace deflex {

/// The most points of a circle: 0.00036 deg apart, finer than any controller interpolates, and
/// compensated in some 4 s (4 us a point). (A line may have kMaxPathPoints: long streamed paths.)
inline constexpr int kMaxCirclePoints = 1'000'000;

/// The reference circle described above.
[[nodiscard]] CirclePath default_circle();

/// Throws InputError quoting the spec and naming the key at fault.
[[nodiscard]] CirclePath parse_circle_spec(const std::string& spec);
[[nodiscard]] LinePath parse_line_spec(const std::string& spec);

}  // namespace deflex
