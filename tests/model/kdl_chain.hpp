// Test helper: the same DH chain built in Orocos KDL, an independent implementation.
#pragma once

#include <kdl/chain.hpp>
#include <kdl/frames.hpp>

#include "deflex/model/robot_model.hpp"

namespace deflex::test {

/// KDL chain of a standard or modified DH table with base_T_chain and last_T_flange*flange_T_tcp
/// folded in, so KDL's tip is the TCP.
inline KDL::Chain kdl_chain_from_dh(const RobotModel& model) {
  const RobotDescription& d = model.description();
  auto to_kdl = [](const Pose& p) {
    const Matrix3 R = p.linear();
    return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)),
                      KDL::Vector(p.translation().x(), p.translation().y(), p.translation().z()));
  };
  KDL::Chain chain;
  chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), to_kdl(d.base_T_chain)));
  const std::size_t n = d.dh.size();
  if (*d.dh_convention == DhConvention::kStandard) {
    for (std::size_t i = 0; i < n; ++i) {
      const DhRow& r = d.dh[i];
      chain.addSegment(
          KDL::Segment(KDL::Joint(KDL::Joint::RotZ), KDL::Frame::DH(r.a_m, r.alpha_rad, r.d_m, r.theta_offset_rad)));
    }
  } else {
    // Craig's convention: Rx(alpha_{i-1}) Tx(a_{i-1}) before joint i, Rz(q_i) Tz(d_i) at it.
    for (std::size_t i = 0; i < n; ++i) {
      const DhRow& r = d.dh[i];
      chain.addSegment(KDL::Segment(
          KDL::Joint(KDL::Joint::None),
          KDL::Frame(KDL::Rotation::RotX(r.alpha_rad), KDL::Vector(0, 0, 0)) * KDL::Frame(KDL::Vector(r.a_m, 0, 0))));
      chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ),
                                    KDL::Frame(KDL::Rotation::RotZ(r.theta_offset_rad), KDL::Vector(0, 0, r.d_m))));
    }
  }
  chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), to_kdl(d.flange_T_tcp)));
  return chain;
}

}  // namespace deflex::test
