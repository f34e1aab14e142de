// The physical range of every kind of input value, in one table. A reader checks each number it
// takes against its field's range, so 1e308 in a robot, tool, wrench, tracker or payload file is an
// error naming the file, line and field ("robot.yaml:12: field 'joint_stiffness_Nm_per_rad[2]':
// 1e+308 Nm/rad is outside 100..1e+10 Nm/rad") instead of an inf further on.
//
// The bounds are deliberately wide: they admit every real robot cell (docs/robot-file.md lists
// them) and refuse only values no cell has, which in practice are typos, unit slips and garbage.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace deflex {

/// What a value measures, the unit its bounds are written in, and the bounds (inclusive).
struct InputRange {
  std::string_view quantity;
  std::string_view unit;
  double min;
  double max;
};

namespace range {
// Geometry. A robot cell fits in 100 m; a path or tracker coordinate in 100 m.
inline constexpr InputRange kLengthM{"length", "m", -100.0, 100.0};
inline constexpr InputRange kLengthMm{"length", "mm", -1e5, 1e5};
inline constexpr InputRange kPositiveLengthMm{"length", "mm", 1e-6, 1e5};
// Angles: joint limits and joint values, up to ten turns either way (continuous joints).
inline constexpr InputRange kAngleRad{"angle", "rad", -63.0, 63.0};
inline constexpr InputRange kAngleDeg{"angle", "deg", -3600.0, 3600.0};
inline constexpr InputRange kJointSpeedRadS{"joint speed", "rad/s", 1e-6, 100.0};
// Loads. The heaviest robots carry 2.3 t; forces and moments are bounded well above any process.
inline constexpr InputRange kForceN{"force", "N", -1e6, 1e6};
inline constexpr InputRange kMomentNm{"moment", "Nm", -1e6, 1e6};
inline constexpr InputRange kMassKg{"mass", "kg", 0.0, 1e4};
// A force/torque sensor's count (an int32 on the wire: full scale 2^31 counts): from 0.2 N full scale
// (1e-10 N a count) to 10 N a count, which no sensor fine enough to compensate with comes near; the
// same for torque from 0.02 Nm full scale.
inline constexpr InputRange kForcePerCountN{"force a count", "N", 1e-10, 10.0};
inline constexpr InputRange kTorquePerCountNm{"torque a count", "Nm", 1e-11, 10.0};
// 1 Nm/rad admits benchtop and toy arms; the stiffest industrial joints are around 1e8.
inline constexpr InputRange kJointStiffness{"joint stiffness", "Nm/rad", 1.0, 1e10};
// Time and rates.
inline constexpr InputRange kTimeS{"time", "s", -1e9, 1e9};
inline constexpr InputRange kDurationS{"duration", "s", 0.0, 1e6};
inline constexpr InputRange kPeriodMs{"period", "ms", 0.1, 60e3};
inline constexpr InputRange kRateHz{"rate", "Hz", 1e-3, 1e6};
inline constexpr InputRange kSpeedMmS{"speed", "mm/s", 1e-3, 1e4};
// Dimensionless.
inline constexpr InputRange kUnitQuaternion{"quaternion component", "", -1.001, 1.001};
inline constexpr InputRange kWeight{"weight", "", 0.0, 1e6};
inline constexpr InputRange kIndex{"index", "", 0.0, 1e8};
inline constexpr InputRange kFraction{"fraction", "", 0.0, 1.0};
/// Anything else: bounded so that no inf, nan or overflow reaches the arithmetic.
inline constexpr InputRange kAnyValue{"value", "", -1e12, 1e12};
}  // namespace range

/// The range of a CSV column or a YAML key, from the unit its name carries: "x_mm" a length in mm,
/// "fx_N" a force, "mx_Nm" a moment, "t_s" a time, "q1_deg" an angle, "rate_Hz" a frequency,
/// "servo_period_ms" a period, "force_bias_pct" a percentage, "qw" a quaternion component,
/// "weight", "index"; any other name gets range::kAnyValue. The table is in input_ranges.cpp and
/// docs/robot-file.md ("Value ranges").
[[nodiscard]] const InputRange& range_for_name(std::string_view name);

/// nullopt when `value` lies in `r`, else the message "VALUE UNIT is outside MIN..MAX UNIT"
/// (a NaN is outside every range).
[[nodiscard]] std::optional<std::string> range_violation(double value, const InputRange& r);

}  // namespace deflex
