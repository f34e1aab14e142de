// The cycle's frames, computed once a configuration (see frame_cache.hpp).
#include "deflex/model/frame_cache.hpp"

#include "deflex/model/detail/kinematics_count.hpp"

namespace deflex {

FrameCache::FrameCache(const RobotModel& model) : model_(model), slot_{Workspace(model), Workspace(model)} {}

const Workspace& FrameCache::at(const JointVector& q) {
  for (int i : {newest_, 1 - newest_}) {
    const Workspace& ws = slot_[i];
    if (valid_[i] && ws.q.size() == q.size() && ws.q == q) {
      newest_ = i;
      return ws;
    }
  }
  const int i = 1 - newest_;
  valid_[i] = false;  // a throw below leaves no stale frames under the new joints
  forward_kinematics(model_, slot_[i], q);
  valid_[i] = true;
  newest_ = i;
  return slot_[i];
}

KinematicsCallCounter::KinematicsCallCounter(const RobotModel& model) {
  detail::kinematics_count.model = &model;
  detail::kinematics_count.calls = 0;
}

KinematicsCallCounter::~KinematicsCallCounter() { detail::kinematics_count.model = nullptr; }

std::uint64_t KinematicsCallCounter::count() const { return detail::kinematics_count.calls; }

}  // namespace deflex
