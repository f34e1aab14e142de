// The thread's count of forward_kinematics() calls on one model object (frame_cache.hpp's
// KinematicsCallCounter): a pointer compare a call when nobody counts.
#pragma once

#include <cstdint>

namespace deflex {
class RobotModel;
namespace detail {

struct KinematicsCount {
  const RobotModel* model = nullptr;
  std::uint64_t calls = 0;
};
inline thread_local KinematicsCount kinematics_count;

}  // namespace detail
}  // namespace deflex
