// Nonnegative least squares (Lawson and Hanson's active-set method) for the small, square
// triangular systems the stiffness identification reduces to: minimise ||R x - y|| with x >= 0.
#pragma once

#include <Eigen/Core>

namespace deflex {

struct NnlsResult {
  Eigen::VectorXd x;                               ///< the solution, every entry >= 0
  Eigen::Array<bool, Eigen::Dynamic, 1> at_bound;  ///< true where x_j = 0 is held by the constraint
  int iterations = 0;
  bool converged = false;  ///< false only when the iteration limit was hit (degenerate input)
};

/// Solves min ||A x - y||_2 subject to x >= 0 (Lawson and Hanson, "Solving Least Squares Problems",
/// 1974, ch. 23). A is m x n with any m; meant for n up to a few dozen. `tolerance` is relative to
/// the largest entry of |A^T y| and decides when a gradient counts as positive.
[[nodiscard]] NnlsResult nonnegative_least_squares(const Eigen::MatrixXd& A, const Eigen::VectorXd& y,
                                                   double tolerance = 1e-12, int max_iterations = 0);

}  // namespace deflex
