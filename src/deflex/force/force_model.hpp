// The process-force model of the offline strategy: the wrench expected at each point of a planned
// path, in the robot base frame. LDBB, constant and tabulated models plug in behind one interface.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "deflex/model/types.hpp"

namespace deflex {

/// Expected process wrench along a path.
///
/// Convention for every model: the wrench the process exerts ON the robot (what the joint
/// compliance model takes), [F; M] in N and Nm, robot base frame, with the moment taken about the
/// TCP — the only point a force model knows. compensate_path() moves the moment to the robot's
/// wrench application point when the two differ.
/// Thread safety: deflex's models are immutable once built, so any number of threads may share one;
/// a model of your own is as safe to share as its const calls are.
class ForceModel {
 public:
  virtual ~ForceModel() = default;
  /// Wrench at path point `index` (0-based) whose desired pose is `base_T_tcp`. May throw
  /// InputError for an index the model has no data for (see points()).
  [[nodiscard]] virtual Wrench wrench_at(std::size_t index, const Pose& base_T_tcp) const = 0;
  /// One line for humans and report headers, with units.
  [[nodiscard]] virtual std::string describe() const = 0;
  /// Short name usable in file names ("ldbb_625N_push"); models outside deflex may keep the default.
  [[nodiscard]] virtual std::string label() const { return "force"; }
  /// Number of path points the model has data for, when it is limited (tables); none otherwise.
  [[nodiscard]] virtual std::optional<std::size_t> points() const { return std::nullopt; }
  /// The wrench at a pose alone, for the online strategies' real-time cycle (hybrid, predictive):
  /// never throws or allocates. False when the model cannot say: it needs a path index (tables), or
  /// the pose is degenerate for it. Models of the pose override it.
  [[nodiscard]] virtual bool wrench_at_pose(const Pose& /*base_T_tcp*/, Wrench& /*out*/) const noexcept {
    return false;
  }

 protected:
  ForceModel() = default;
  ForceModel(const ForceModel&) = default;
  ForceModel& operator=(const ForceModel&) = default;
};

}  // namespace deflex
