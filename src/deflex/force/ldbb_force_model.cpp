// LDBB bar force.
#include "deflex/force/ldbb_force_model.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

LdbbForceModel::LdbbForceModel(Vector3 pivot_base_m, double force_N, bool push)
    : pivot_base_m_(std::move(pivot_base_m)), force_N_(force_N), push_(push) {
  if (!pivot_base_m_.allFinite()) {
    throw InputError("LDBB: pivot position is not finite");
  }
  if (!std::isfinite(force_N_) || force_N_ <= 0.0) {
    throw InputError(fmt::format("LDBB: force magnitude must be positive and finite (got {} N)", force_N_));
  }
}

Wrench LdbbForceModel::wrench_at(std::size_t index, const Pose& base_T_tcp) const {
  if (!base_T_tcp.translation().allFinite()) {
    throw InputError(fmt::format("LDBB: path point {}: the TCP position is not finite", index));
  }
  const Vector3 bar = base_T_tcp.translation() - pivot_base_m_;
  const double length = bar.norm();
  // A real bar is 100-600 mm long; under 1 mm the direction is rounding noise.
  if (!(length > 1e-3)) {
    throw InputError(
        fmt::format("LDBB: path point {} is {:.3g} mm from the pivot: no bar direction", index, length * 1e3));
  }
  Wrench w = Wrench::Zero();
  w.head<3>() = (push_ ? force_N_ : -force_N_) / length * bar;
  return w;
}

bool LdbbForceModel::wrench_at_pose(const Pose& base_T_tcp, Wrench& out) const noexcept {
  const Vector3 bar = base_T_tcp.translation() - pivot_base_m_;
  const double length = bar.norm();
  if (!(length > 1e-3)) {
    return false;
  }
  out.setZero();
  out.head<3>() = (push_ ? force_N_ : -force_N_) / length * bar;
  return true;
}

double LdbbForceModel::bar_length_m(const Pose& base_T_tcp) const {
  return (base_T_tcp.translation() - pivot_base_m_).norm();
}

double LdbbForceModel::inclination_rad(const Pose& base_T_tcp) const {
  const Vector3 bar = base_T_tcp.translation() - pivot_base_m_;
  return std::atan2(bar.z(), bar.head<2>().norm());
}

std::string LdbbForceModel::describe() const {
  return fmt::format("LDBB {} {:g} N along the bar from the pivot ({:.1f}, {:.1f}, {:.1f}) mm to the TCP ball",
                     push_ ? "push" : "pull", force_N_, pivot_base_m_.x() * 1e3, pivot_base_m_.y() * 1e3,
                     pivot_base_m_.z() * 1e3);
}

std::string LdbbForceModel::label() const { return fmt::format("ldbb_{:g}N_{}", force_N_, push_ ? "push" : "pull"); }

}  // namespace deflex
