// Folding a serial chain for forward kinematics (see folded_chain.hpp).
#include "deflex/model/folded_chain.hpp"

#include <cmath>

#include "deflex/model/robot_model.hpp"

namespace deflex {
namespace {

constexpr double kExact = 1e-15;

bool near(double x, double v) { return std::abs(x - v) <= kExact; }

// A constant rotation that carries z onto the unit vector `axis`: exact (a permutation) for the axes
// a URDF usually has, the shortest turn otherwise.
Matrix3 z_onto(const Vector3& axis) {
  for (int k = 0; k < 3; ++k) {
    for (const double sgn : {1.0, -1.0}) {
      if ((axis - sgn * Vector3::Unit(k)).cwiseAbs().maxCoeff() <= kExact) {
        // Columns (x, y, z) of the frame: z along the axis, x and y the next unit vectors in turn.
        Matrix3 a = Matrix3::Zero();
        a.col(2) = sgn * Vector3::Unit(k);
        a.col(0) = Vector3::Unit((k + 1) % 3);
        a.col(1) = a.col(2).cross(a.col(0));
        return a;
      }
    }
  }
  return Eigen::Quaterniond::FromTwoVectors(Vector3::UnitZ(), axis).toRotationMatrix();
}

}  // namespace

FoldedStep fold_step(const Pose& transform) {
  FoldedStep step;
  const Matrix3 r = transform.linear();
  step.rotation = r;
  step.translation = transform.translation();
  for (int k = 0; k < 3; ++k) {
    if (step.translation[k] != 0.0) {
      step.translation_mask = static_cast<std::uint8_t>(step.translation_mask | (1U << k));
    }
  }
  // A signed permutation: one entry of +-1 in each column, the rest zero.
  bool permutation = true;
  for (int j = 0; j < 3 && permutation; ++j) {
    int ones = 0;
    for (int i = 0; i < 3; ++i) {
      if (near(std::abs(r(i, j)), 1.0)) {
        ++ones;
        step.perm[static_cast<std::size_t>(j)] = static_cast<std::uint8_t>(i);
        step.sign[static_cast<std::size_t>(j)] = r(i, j) > 0.0 ? 1.0 : -1.0;
      } else if (!near(r(i, j), 0.0)) {
        permutation = false;
      }
    }
    permutation = permutation && ones == 1;
  }
  if (permutation) {
    const bool identity = step.perm[0] == 0 && step.perm[1] == 1 && step.perm[2] == 2 && step.sign[0] > 0.0 &&
                          step.sign[1] > 0.0 && step.sign[2] > 0.0;
    step.turn = identity ? FoldedStep::Turn::kIdentity : FoldedStep::Turn::kPermutation;
    // The most common permutation, a DH twist of +-90 degrees, gets its own two-column form.
    const bool quarter_x = step.perm[0] == 0 && step.perm[1] == 2 && step.perm[2] == 1 && step.sign[0] > 0.0 &&
                           step.sign[1] == -step.sign[2];
    if (quarter_x) {
      step.turn = FoldedStep::Turn::kQuarterX;
      step.c = 0.0;
      step.s = step.sign[1];
    }
    return step;
  }
  if (near(r(0, 0), 1.0) && near(r(1, 0), 0.0) && near(r(2, 0), 0.0) && near(r(0, 1), 0.0) && near(r(0, 2), 0.0) &&
      near(r(1, 2), -r(2, 1)) && near(r(2, 2), r(1, 1))) {
    step.turn = FoldedStep::Turn::kAboutX;
    step.c = r(1, 1);
    step.s = r(2, 1);
    return step;
  }
  step.turn = FoldedStep::Turn::kGeneral;
  return step;
}

FoldedChain fold_chain(const RobotDescription& d, const Pose& flange_T_wap) {
  FoldedChain chain;
  chain.dof = static_cast<int>(d.joints.size());
  // A_i carries z onto joint i's axis: the joint's turn about its axis is A_i Rz A_i^T, so A_i goes
  // into its own fixed transform and A_i^T into the next one.
  Matrix3 previous_inverse = Matrix3::Identity();  // A_{i-1}^T
  for (int i = 0; i < chain.dof; ++i) {
    const JointSpec& j = d.joints[static_cast<std::size_t>(i)];
    const Matrix3 a = z_onto(j.axis);
    Pose fixed = Pose::Identity();
    fixed.linear() = previous_inverse * j.parent_T_joint.linear() * a;
    fixed.translation() = previous_inverse * j.parent_T_joint.translation();
    if (i == 0) {
      const Pose first = d.base_T_chain * fixed;
      chain.first_rotation = first.linear();
      chain.first_origin = first.translation();
    } else {
      chain.steps[static_cast<std::size_t>(i)] = fold_step(fixed);
    }
    chain.offset_rad[static_cast<std::size_t>(i)] = j.offset_rad;
    previous_inverse = a.transpose();
  }
  Pose last = Pose::Identity();
  last.linear() = previous_inverse * d.last_T_flange.linear();
  last.translation() = previous_inverse * d.last_T_flange.translation();
  chain.last_to_flange = fold_step(last);
  chain.flange_to_tcp = fold_step(d.flange_T_tcp);
  chain.flange_to_wap = fold_step(flange_T_wap);
  return chain;
}

}  // namespace deflex
