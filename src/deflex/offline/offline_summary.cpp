// Summary text of an offline compensation.
#include "deflex/offline/offline_summary.hpp"

#include <fmt/format.h>

namespace deflex {

std::string offline_summary(const OfflineResult& result) {
  std::string s;
  s += fmt::format("robot: {}\n", result.robot_name);
  s += fmt::format("force: {}\n", result.force_description);
  s += fmt::format("points: {}\n", result.point_count);
  if (result.predicted) {
    s += fmt::format(
        "predicted TCP deflection, uncompensated: max {:.4f} mm, mean {:.4f} mm (max rotation {:.4f} "
        "mrad)\n",
        result.max_deflection_m * 1e3, result.mean_deflection_m * 1e3, result.max_deflection_rad * 1e3);
  }
  s += fmt::format("compensation: largest TCP offset {:.4f} mm, largest joint correction {:.5f} deg\n",
                   result.max_correction_m * 1e3, rad_to_deg(result.max_joint_correction_rad));
  if (result.predicted) {
    s += fmt::format("predicted residual after compensation (model-consistent check): max {:.2e} mm, {:.2e} mrad\n",
                     result.max_residual_m * 1e3, result.max_residual_rad * 1e3);
  }
  return s;
}

}  // namespace deflex
