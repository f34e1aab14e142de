// Test helper: the KDL chain of a URDF chain read by urdf_reference.hpp (independent of deflex's
// loader), so KDL's FK and numerical IK can judge deflex on ROS-Industrial robots.
#pragma once

#include <kdl/chain.hpp>
#include <kdl/frames.hpp>

#include "urdf_reference.hpp"

namespace deflex::test {

inline KDL::Chain kdl_chain_from_reference(const std::vector<ReferenceJoint>& joints) {
  KDL::Chain chain;
  for (const ReferenceJoint& j : joints) {
    chain.addSegment(KDL::Segment(
        KDL::Joint(KDL::Joint::None),
        KDL::Frame(KDL::Rotation::RPY(j.rpy.x(), j.rpy.y(), j.rpy.z()), KDL::Vector(j.xyz.x(), j.xyz.y(), j.xyz.z()))));
    if (j.type != "fixed") {
      chain.addSegment(KDL::Segment(
          KDL::Joint(j.name, KDL::Vector::Zero(), KDL::Vector(j.axis.x(), j.axis.y(), j.axis.z()), KDL::Joint::RotAxis),
          KDL::Frame::Identity()));
    }
  }
  return chain;
}

inline Eigen::Isometry3d to_eigen(const KDL::Frame& f) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      T.linear()(r, c) = f.M(static_cast<unsigned>(r), static_cast<unsigned>(c));
    }
    T.translation()[r] = f.p(static_cast<unsigned>(r));
  }
  return T;
}

inline KDL::Frame to_kdl(const Eigen::Isometry3d& p) {
  const Eigen::Matrix3d R = p.linear();
  return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)),
                    KDL::Vector(p.translation().x(), p.translation().y(), p.translation().z()));
}

}  // namespace deflex::test
