// NNLS against a brute-force search over every active set (an independent path: the optimum of a
// convex problem is the best feasible solution among the unconstrained fits on each subset).
#include <random>

#include <gtest/gtest.h>
#include <Eigen/QR>

#include "deflex/identify/detail/nonnegative_least_squares.hpp"

namespace deflex {
namespace {

TEST(NonnegativeLeastSquares, MatchesExhaustiveSearchOverActiveSets) {
  std::mt19937 rng(1);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + trial % 6;
    const int m = n + static_cast<int>(rng() % 8);
    Eigen::MatrixXd A(m, n);
    Eigen::VectorXd y(m);
    for (int i = 0; i < m; ++i) {
      y[i] = n01(rng);
      for (int j = 0; j < n; ++j) {
        A(i, j) = n01(rng);
      }
    }
    double best = (y).squaredNorm();  // x = 0
    Eigen::VectorXd best_x = Eigen::VectorXd::Zero(n);
    for (int mask = 1; mask < (1 << n); ++mask) {
      std::vector<int> cols;
      for (int j = 0; j < n; ++j) {
        if (mask & (1 << j)) {
          cols.push_back(j);
        }
      }
      Eigen::MatrixXd As(m, static_cast<Eigen::Index>(cols.size()));
      for (std::size_t k = 0; k < cols.size(); ++k) {
        As.col(static_cast<Eigen::Index>(k)) = A.col(cols[k]);
      }
      const Eigen::VectorXd z = As.householderQr().solve(y);
      if ((z.array() < 0.0).any()) {
        continue;
      }
      Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
      for (std::size_t k = 0; k < cols.size(); ++k) {
        x[cols[k]] = z[static_cast<Eigen::Index>(k)];
      }
      const double f = (A * x - y).squaredNorm();
      if (f < best) {
        best = f;
        best_x = x;
      }
    }
    const NnlsResult r = nonnegative_least_squares(A, y);
    EXPECT_TRUE(r.converged);
    EXPECT_TRUE((r.x.array() >= 0.0).all());
    EXPECT_NEAR((A * r.x - y).squaredNorm(), best, 1e-10 * (1.0 + best)) << "trial " << trial;
    EXPECT_LT((r.x - best_x).norm(), 1e-8) << "trial " << trial;
    for (int j = 0; j < n; ++j) {
      EXPECT_EQ(r.at_bound[j], r.x[j] == 0.0);
    }
  }
}

TEST(NonnegativeLeastSquares, UnconstrainedOptimumInsideTheOrthantIsReturnedAsIs) {
  Eigen::MatrixXd A(4, 2);
  A << 1, 0, 0, 1, 1, 1, 2, -1;
  const Eigen::Vector2d x_true(0.5, 2.0);
  const Eigen::VectorXd y = A * x_true;
  const NnlsResult r = nonnegative_least_squares(A, y);
  EXPECT_LT((r.x - x_true).norm(), 1e-14);
  EXPECT_FALSE(r.at_bound.any());
}

TEST(NonnegativeLeastSquares, NegativeUnconstrainedComponentIsClampedWithTheOtherRefitted) {
  // Unconstrained solution (1, -1); with x2 = 0 the best x1 is the projection of y on column 1.
  Eigen::MatrixXd A(3, 2);
  A << 1, 0, 0, 1, 1, 1;
  const Eigen::VectorXd y = A * Eigen::Vector2d(1.0, -1.0);
  const NnlsResult r = nonnegative_least_squares(A, y);
  EXPECT_NEAR(r.x[0], A.col(0).dot(y) / A.col(0).squaredNorm(), 1e-14);
  EXPECT_EQ(r.x[1], 0.0);
  EXPECT_TRUE(r.at_bound[1]);
}

TEST(NonnegativeLeastSquares, NoColumnsGiveAnEmptyConvergedSolution) {
  const NnlsResult r = nonnegative_least_squares(Eigen::MatrixXd(3, 0), Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.x.size(), 0);
  EXPECT_EQ(r.at_bound.size(), 0);
  EXPECT_EQ(r.iterations, 0);
}

}  // namespace
}  // namespace deflex
