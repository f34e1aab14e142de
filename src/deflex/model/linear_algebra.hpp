// The singular value decomposition deflex uses wherever it needs a dynamic one (stiffness
// identification, frame registration, payload identification).
//
// Written here rather than taken as Eigen::JacobiSVD<Eigen::MatrixXd> directly, for build time: that
// type with its default column-pivoting QR preconditioner took 15-18 s of compiler time in every
// translation unit that used it (measured with GCC 12 at -O3, against 3 s without the preconditioner),
// and an explicit instantiation of it in the library took the place of Orocos KDL's own copy in the
// sanitizer build (KDL's LMA solver holds one; the two sides allocated differently). Here a tall matrix
// is reduced to its square triangle by Householder QR (same singular values and right singular vectors),
// and the square one goes to Jacobi's SVD without preconditioner, compiled once, in linear_algebra.cpp,
// as a type KDL does not use.
#pragma once

#include <Eigen/Core>

namespace deflex {

/// The singular values of `a` (m x n), descending, min(m, n) of them.
/// Thread safety: a pure function.
[[nodiscard]] Eigen::VectorXd singular_values(const Eigen::Ref<const Eigen::MatrixXd>& a);

/// A = U diag(s) V^T for a dynamic matrix A (m x n): the singular values (descending, min(m, n) of
/// them), the full right singular vectors V (n x n: with fewer rows than columns its trailing n - m
/// columns span A's null space) and the minimum-norm least-squares solution of A x = b.
/// Thread safety: immutable once built; share it across threads freely.
class Svd {
 public:
  explicit Svd(const Eigen::Ref<const Eigen::MatrixXd>& a);

  [[nodiscard]] const Eigen::VectorXd& values() const { return values_; }
  [[nodiscard]] const Eigen::MatrixXd& right_vectors() const { return v_; }
  /// The minimum-norm least-squares solution: the singular values at most min(m, n) * epsilon times the
  /// largest count as zero (Eigen's default rank rule for its SVDs).
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::Ref<const Eigen::VectorXd>& b) const;

 private:
  Eigen::VectorXd values_;
  Eigen::MatrixXd u_;  // m x min(m, n): the left singular vectors of the non-zero singular values
  Eigen::MatrixXd v_;
};

}  // namespace deflex
