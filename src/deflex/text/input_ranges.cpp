// The range table's lookups.
#include "deflex/text/input_ranges.hpp"

#include <array>
#include <utility>

#include <fmt/format.h>

namespace deflex {

const InputRange& range_for_name(std::string_view name) {
  if (name == "qw" || name == "qx" || name == "qy" || name == "qz") {
    return range::kUnitQuaternion;
  }
  if (name == "weight") {
    return range::kWeight;
  }
  if (name == "index") {
    return range::kIndex;
  }
  static constexpr InputRange kMicro{"length", "um", -1e5, 1e5};
  static constexpr InputRange kMicroRad{"angle", "urad", -1e6, 1e6};
  static constexpr InputRange kMilliRad{"angle", "mrad", -1e5, 1e5};
  static constexpr InputRange kMs{"time", "ms", 0.0, 1e6};
  static constexpr InputRange kHz{"frequency", "Hz", 0.0, 1e5};
  static constexpr InputRange kPct{"percentage", "%", -1000.0, 1000.0};
  static constexpr InputRange kPerS{"rate", "1/s", 0.0, 1e6};
  static constexpr InputRange kDegS{"angular speed", "deg/s", 0.0, 1e5};
  static constexpr InputRange kMradS{"angular speed", "mrad/s", 0.0, 1e6};
  static constexpr InputRange kAccel{"acceleration", "m/s^2", -1e3, 1e3};
  // Longest suffixes first, so "_Nm" is not taken for "_m" nor "_period_ms" for "_ms".
  static constexpr std::array<std::pair<std::string_view, const InputRange*>, 24> kBySuffix{{
      {"_Nm_per_rad", &range::kJointStiffness},
      {"_N_per_10min", &range::kForceN},
      {"_period_ms", &range::kPeriodMs},
      {"_mrad_s", &kMradS},
      {"_deg_s", &kDegS},
      {"_mm_s", &range::kSpeedMmS},
      {"_m_s2", &kAccel},
      {"_per_s", &kPerS},
      {"_urad", &kMicroRad},
      {"_mrad", &kMilliRad},
      {"_pct", &kPct},
      {"_deg", &range::kAngleDeg},
      {"_rad", &range::kAngleRad},
      {"_kg", &range::kMassKg},
      {"_Hz", &kHz},
      {"_hz", &kHz},
      {"_Nm", &range::kMomentNm},
      {"_mm", &range::kLengthMm},
      {"_um", &kMicro},
      {"_ms", &kMs},
      {"_N", &range::kForceN},
      {"_s", &range::kTimeS},
      {"_m", &range::kLengthM},
      {"_per_rad", &range::kJointStiffness},
  }};
  for (const auto& [suffix, r] : kBySuffix) {
    if (name.size() > suffix.size() && name.substr(name.size() - suffix.size()) == suffix) {
      return *r;
    }
  }
  return range::kAnyValue;
}

std::optional<std::string> range_violation(double value, const InputRange& r) {
  if (value >= r.min && value <= r.max) {
    return std::nullopt;
  }
  const std::string unit = r.unit.empty() ? std::string() : fmt::format(" {}", r.unit);
  const std::string sign = r.min > 0.0 && !(value > 0.0) ? "must be positive: " : "";
  return sign + fmt::format("{:g}{} is outside {:g}..{:g}{} (the {} range deflex accepts)", value, unit, r.min, r.max,
                            unit, r.quantity);
}

}  // namespace deflex
