// The serial chain as forward kinematics walks it, folded once when a RobotModel is built: every
// joint turns about the z axis of its own frame (a joint about another axis gets a constant rotation
// that carries z onto its axis, and the inverse of that rotation is folded into the next fixed
// transform), the mounting is folded into the first joint's fixed transform, and each fixed rotation
// is classified by the work it needs (none, a quarter turn about x as a DH twist of +-90 degrees is,
// a signed permutation of the columns, a turn about x as in every other Denavit-Hartenberg row, or a
// general 3x3 product). A translation keeps a mask of its non-zero components. Forward kinematics
// then costs, per joint of a DH arm, one sin/cos pair, a 2-column turn for the joint, a 2-column turn
// (or a swap of two columns) for the link twist and one or two scaled column additions for the
// link's lengths, instead of two general 3x3 products and a 3x3 times vector.
#pragma once

#include <array>
#include <cstdint>

#include "deflex/model/types.hpp"

namespace deflex {

struct RobotDescription;

/// One constant rigid transform [R t] of the folded chain, with what applying it costs.
/// Thread safety: plain data, immutable once built.
struct FoldedStep {
  enum class Turn : std::uint8_t {
    kIdentity,     ///< R = I
    kQuarterX,     ///< R = Rx(+-90 deg), a DH twist of +-90: y' = s z, z' = -s y (s = +-1), x kept
    kPermutation,  ///< column j of R is sign[j] times unit vector perm[j]: a product with it only moves columns
    kAboutX,       ///< R = Rx(angle): columns 1 and 2 turn by (c, s)
    kGeneral,      ///< any rotation: a 3x3 product
  };
  Turn turn = Turn::kIdentity;
  std::array<std::uint8_t, 3> perm{0, 1, 2};
  std::array<double, 3> sign{1.0, 1.0, 1.0};
  double c = 1.0, s = 0.0;  ///< kAboutX: cos and sin of the turn; kQuarterX: s = +-1
  Matrix3 rotation = Matrix3::Identity();
  Vector3 translation = Vector3::Zero();
  std::uint8_t translation_mask = 0;  ///< bit k set: component k of the translation is non-zero
};

/// The whole chain, folded (see the file's comment). Built by fold_chain(); immutable after.
/// Thread safety: immutable once built (part of a RobotModel): any number of threads may read it.
struct FoldedChain {
  int dof = 0;
  /// The first joint's frame in the base frame, before its turn: constant (mounting and first fixed
  /// transform folded together).
  Matrix3 first_rotation = Matrix3::Identity();
  Vector3 first_origin = Vector3::Zero();
  /// steps[i], i >= 1: joint i-1's turned frame to joint i's frame (before its turn).
  std::array<FoldedStep, kMaxJoints> steps{};
  FoldedStep last_to_flange;  ///< last joint's turned frame to the flange
  FoldedStep flange_to_tcp;   ///< the tool: flange to TCP
  FoldedStep flange_to_wap;   ///< flange to the wrench application point (the TCP's when the file gives none)
  std::array<double, kMaxJoints> offset_rad{};
};

/// Classifies a rigid transform: entries within 1e-15 of 0 or +-1 count as exact (a DH twist of
/// -90 degrees is stored with cos = 6e-17), so the folded chain differs from the plain products by
/// no more than rounding.
[[nodiscard]] FoldedStep fold_step(const Pose& transform);

/// Folds a (validated) description's chain: its joints, mounting, flange, tool and the wrench
/// application point `flange_T_wap`.
[[nodiscard]] FoldedChain fold_chain(const RobotDescription& description, const Pose& flange_T_wap);

}  // namespace deflex
