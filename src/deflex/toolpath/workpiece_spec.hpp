// The workpiece's frame in the robot's base frame, from the key=value text of a command-line option or
// a script: "x_mm=2000,y_mm=0,z_mm=750,qw=1,qx=0,qy=0,qz=0". A toolpath's points are in this frame.
#pragma once

#include <string>

#include "deflex/model/types.hpp"

namespace deflex {

/// The quaternion's norm may differ from 1 by at most this (a quaternion written with 4 to 6
/// decimals is unit to about 1e-5); it is then normalised. A larger difference is refused.
inline constexpr double kWorkpieceQuaternionTolerance = 1e-3;

/// base_T_workpiece from `spec`: keys x_mm, y_mm, z_mm (required; the workpiece origin in the base
/// frame, mm, each within +-1e5 mm) and qw, qx, qy, qz (all four or none; none: the workpiece's axes
/// are the base's). Throws InputError quoting the spec and naming the key: an unknown or repeated key,
/// a value that is not a finite number, a missing key, a quaternion that is not unit within
/// kWorkpieceQuaternionTolerance.
[[nodiscard]] Pose parse_workpiece_spec(const std::string& spec);

}  // namespace deflex
