// Sign choice of output quaternions: the rotation is kept, and the sign follows the stated rule
// (first non-zero of w, x, y, z positive; or a non-negative dot product with the previous one).
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/offline/detail/quaternion_sign.hpp"

namespace deflex {
namespace {

Pose rotated(const Eigen::AngleAxisd& r) {
  Pose p = Pose::Identity();
  p.linear() = r.toRotationMatrix();
  p.translation() = Vector3(1.0, 2.0, 3.0);
  return p;
}

TEST(QuaternionSign, CanonicalSignFromTheFirstNonZeroComponent) {
  // 180 deg about x: w = 0 exactly, so x decides: (0, 1, 0, 0), not (0, -1, 0, 0).
  const Eigen::Quaterniond a = canonical_quaternion(rotated(Eigen::AngleAxisd(kPi, -Vector3::UnitX())));
  EXPECT_NEAR(a.w(), 0.0, 1e-12);
  EXPECT_NEAR(a.x(), 1.0, 1e-12);
  // 180 deg about (0, -1, 1)/sqrt(2): w = 0, x = 0, y = -z; y must come out positive.
  const Eigen::Quaterniond b =
      canonical_quaternion(rotated(Eigen::AngleAxisd(kPi, Vector3(0.0, -1.0, 1.0).normalized())));
  EXPECT_NEAR(b.w(), 0.0, 1e-12);
  EXPECT_NEAR(b.x(), 0.0, 1e-12);
  EXPECT_NEAR(b.y(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(b.z(), -std::sqrt(0.5), 1e-12);
  // 170 deg about -x: the matrix-to-quaternion conversion (trace < 0) makes x positive and w
  // negative; the rule wants w positive: (cos 85, -sin 85, 0, 0).
  const Eigen::Quaterniond c = canonical_quaternion(rotated(Eigen::AngleAxisd(deg_to_rad(170.0), -Vector3::UnitX())));
  EXPECT_NEAR(c.w(), std::cos(deg_to_rad(85.0)), 1e-12);
  EXPECT_NEAR(c.x(), -std::sin(deg_to_rad(85.0)), 1e-12);
  EXPECT_NEAR(c.norm(), 1.0, 1e-15);
}

TEST(QuaternionSign, NearSignFollowsTheReferenceAndKeepsTheRotation) {
  const Pose p = rotated(Eigen::AngleAxisd(0.7, Vector3(1.0, 2.0, -0.5).normalized()));
  const Eigen::Quaterniond plus(Eigen::AngleAxisd(0.7, Vector3(1.0, 2.0, -0.5).normalized()));
  Eigen::Quaterniond minus = plus;
  minus.coeffs() = -plus.coeffs();
  const Eigen::Quaterniond a = quaternion_near(p, plus);
  const Eigen::Quaterniond b = quaternion_near(p, minus);
  EXPECT_GT(a.dot(plus), 0.0);
  EXPECT_GT(b.dot(minus), 0.0);
  EXPECT_NEAR((a.coeffs() + b.coeffs()).norm(), 0.0, 1e-12);  // the two signs of one rotation
  EXPECT_TRUE(a.toRotationMatrix().isApprox(p.linear(), 1e-12));
  EXPECT_TRUE(b.toRotationMatrix().isApprox(p.linear(), 1e-12));
}

}  // namespace
}  // namespace deflex
