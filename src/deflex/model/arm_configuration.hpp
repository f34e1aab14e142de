// The arm configuration of a 6R arm as the two controller families write it in their programs:
// ABB's confdata [cf1, cf4, cf6, cfx] and KUKA's Status and Turn. Both pick one of the up to eight
// inverse-kinematics branches (shoulder front/back, elbow up/down, wrist flip) and the turn of the
// joints that go round more than once.
#pragma once

#include <cmath>

#include "deflex/model/types.hpp"

namespace deflex {

/// ABB's confdata. cf1, cf4, cf6: quadrant of joints 1, 4, 6 (floor(q / 90 deg): 0 for [0, 90),
/// -1 for [-90, 0), ...). cfx (0..7) = 4*b1 + 2*b2 + b3 with
///   b1: wrist centre behind axis 1 (along the x axis of joint 1's moving frame),
///   b2: wrist centre behind the lower arm (reached from the axis-2-to-axis-3 direction by a
///       negative rotation about joint 2's axis),
///   b3: joint 5 negative.
struct ArmConfiguration {
  int cf1 = 0;
  int cf4 = 0;
  int cf6 = 0;
  int cfx = 0;
  // Written out (not `= default`): the model's headers compile as C++17 for a consumer that is.
  bool operator==(const ArmConfiguration& o) const {
    return cf1 == o.cf1 && cf4 == o.cf4 && cf6 == o.cf6 && cfx == o.cfx;
  }
  bool operator!=(const ArmConfiguration& o) const { return !(*this == o); }
};

/// KUKA's Status and Turn (KRL E6POS/POS components S and T), for a model whose joint values are
/// the controller's axis values A1..A6 (as in the ROS-Industrial URDFs).
///   status bit 0: wrist root point (the wrist centre) at negative x in the A1 frame (overhead area),
///   status bit 1: A3 >= phi, phi the A3 angle at which the wrist centre lies on the line of the
///                 upper arm (0 when axes 3 and 4 intersect; set by the A3-A4 offset otherwise),
///   status bit 2: A5 < 0,
///   turn bit i:   axis i+1 negative (A(i+1) < 0).
struct KukaConfiguration {
  int status = 0;
  int turn = 0;
  bool operator==(const KukaConfiguration& o) const { return status == o.status && turn == o.turn; }
  bool operator!=(const KukaConfiguration& o) const { return !(*this == o); }
};

/// floor(q / 90 deg), the quadrant number confdata uses.
[[nodiscard]] inline int abb_quadrant(double q_rad) {
  return static_cast<int>(std::floor(q_rad / (kPi / 2.0) + 1e-12));
}

/// A joint value below zero for Turn and confdata bits: -1e-17 is a zero that lost its sign to
/// rounding, not a negative angle.
[[nodiscard]] inline bool negative_joint(double q_rad) { return q_rad < -1e-12; }

/// The Turn bits of joint values (bit i set when joint i+1 is negative). Joints beyond the sixth
/// are ignored (KRL's Turn has six axis bits).
[[nodiscard]] inline int kuka_turn(const JointVector& q) {
  int t = 0;
  for (int i = 0; i < q.size() && i < 6; ++i) {
    t |= negative_joint(q[i]) ? (1 << i) : 0;
  }
  return t;
}

}  // namespace deflex
