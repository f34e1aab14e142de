// The arm's frames at the configurations of one control cycle, each computed once. A cycle needs the
// frames at the feedback (the sensor's orientation, egm-path's correction frame) and at the target
// (the Jacobian, a force model's prediction, the rotation egm-path cannot correct); the strategy, the
// compensator and the link each ask for them here, and forward kinematics runs once a configuration.
// A configuration is the same when its joints are equal to the last bit: a cycle's feedback and
// target are the very vectors the link holds.
#pragma once

#include <cstdint>

#include "deflex/model/kinematics.hpp"

namespace deflex {

/// Thread safety: one thread at a time (the cycle's), as a Workspace. Never allocates after
/// construction.
class FrameCache {
 public:
  /// `model` must outlive the cache.
  explicit FrameCache(const RobotModel& model);
  FrameCache(const RobotModel&& model) = delete;

  /// The frames at q (forward_kinematics() unless one of the last two configurations asked for is q).
  /// The reference stays valid until the second at() with another configuration: the last two are
  /// kept, the one asked for longer ago replaced first. Throws what forward_kinematics() throws (q of
  /// the wrong size): the cycle checks its joints before.
  const Workspace& at(const JointVector& q);
  [[nodiscard]] const RobotModel& model() const { return model_; }

 private:
  const RobotModel& model_;
  Workspace slot_[2];
  bool valid_[2] = {false, false};
  int newest_ = 1;
};

/// Counts this thread's forward_kinematics() calls on one robot model object while it lives (tests:
/// the kinematics a control cycle runs). One counter at a time a thread.
class KinematicsCallCounter {
 public:
  explicit KinematicsCallCounter(const RobotModel& model);
  KinematicsCallCounter(const RobotModel&& model) = delete;  // it counts calls on that object: a named one
  ~KinematicsCallCounter();
  KinematicsCallCounter(const KinematicsCallCounter&) = delete;
  KinematicsCallCounter& operator=(const KinematicsCallCounter&) = delete;
  [[nodiscard]] std::uint64_t count() const;
};

}  // namespace deflex
