// Human-readable summary of an offline compensation (mm, mrad, degrees).
#pragma once

#include <string>

#include "deflex/offline/compensate_path.hpp"

namespace deflex {

/// A few lines: robot, force model, points, max and mean predicted deflection, largest correction
/// and the residual after compensation.
[[nodiscard]] std::string offline_summary(const OfflineResult& result);

}  // namespace deflex
