// A process wrench constant in the tool frame: the thrust and torque of drilling, milling or
// deburring, which turn with the tool rather than staying fixed in the base frame.
#pragma once

#include "deflex/force/force_model.hpp"

namespace deflex {

/// Thread safety: immutable once built: any number of threads may share one.
class ToolWrenchModel final : public ForceModel {
 public:
  /// [Fx Fy Fz Mx My Mz], N and Nm, in the TCP frame, moment about the TCP: the wrench the process
  /// exerts on the tool (a drill pushed along +z of the tool feels fz_N < 0). Throws InputError if
  /// not finite.
  explicit ToolWrenchModel(const Wrench& wrench_tool);

  /// The tool-frame wrench rotated into the base frame by the TCP orientation of `base_T_tcp`. Throws
  /// InputError when that orientation is not finite.
  [[nodiscard]] Wrench wrench_at(std::size_t index, const Pose& base_T_tcp) const override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::string label() const override { return "tool"; }

 private:
  Wrench wrench_tool_;
};

}  // namespace deflex
