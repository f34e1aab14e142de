// The Loaded Double Ball Bar (LDBB) of the paper's case study as a force model: a bar between a
// ball on a table pivot and a ball at the robot's TCP, with a pneumatic actuator that pushes (or
// pulls) with a set force along the bar.
#pragma once

#include "deflex/force/force_model.hpp"

namespace deflex {

/// Force along the bar, zero moment (the ball joint at the TCP transmits no moment).
///
/// Direction convention: push means the actuator extends the bar, so it presses the TCP ball away
/// from the pivot: F = force_N * (p_tcp - pivot) / |p_tcp - pivot|. Pull is the opposite. This is
/// the force on the robot, the sign the compliance model needs; a push therefore deflects the TCP
/// away from the pivot. As the TCP goes round a circle whose axis passes through the pivot, the
/// force keeps its inclination phi to the circle's plane and its horizontal part turns with the TCP
/// (paper, Figure 4).
/// Thread safety: immutable once built: any number of threads may share one.
class LdbbForceModel final : public ForceModel {
 public:
  /// Throws InputError for a non-finite pivot or a force magnitude that is not positive and finite.
  LdbbForceModel(Vector3 pivot_base_m, double force_N, bool push);

  /// Throws InputError when the TCP position is not finite or is at the pivot (no bar direction).
  [[nodiscard]] Wrench wrench_at(std::size_t index, const Pose& base_T_tcp) const override;
  [[nodiscard]] bool wrench_at_pose(const Pose& base_T_tcp, Wrench& out) const noexcept override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::string label() const override;

  [[nodiscard]] const Vector3& pivot_base_m() const { return pivot_base_m_; }
  [[nodiscard]] double force_N() const { return force_N_; }
  [[nodiscard]] bool push() const { return push_; }

  /// Bar length |p_tcp - pivot|, m, and its inclination to the base XY plane, rad (positive when
  /// the TCP is above the pivot).
  [[nodiscard]] double bar_length_m(const Pose& base_T_tcp) const;
  [[nodiscard]] double inclination_rad(const Pose& base_T_tcp) const;

 private:
  Vector3 pivot_base_m_;
  double force_N_;
  bool push_;
};

}  // namespace deflex
