// A constant process wrench (e.g. a drilling thrust): the same base-frame wrench at every point.
#pragma once

#include "deflex/force/force_model.hpp"

namespace deflex {

/// Thread safety: immutable once built: any number of threads may share one.
class ConstantWrenchModel final : public ForceModel {
 public:
  /// [Fx Fy Fz Mx My Mz], N and Nm, base frame, moment about the TCP. Throws InputError if not finite.
  explicit ConstantWrenchModel(const Wrench& wrench_base);

  [[nodiscard]] Wrench wrench_at(std::size_t index, const Pose& base_T_tcp) const override;
  [[nodiscard]] bool wrench_at_pose(const Pose& /*base_T_tcp*/, Wrench& out) const noexcept override {
    out = wrench_;
    return true;
  }
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::string label() const override { return "constant"; }

 private:
  Wrench wrench_;
};

}  // namespace deflex
