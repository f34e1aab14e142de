// The SVD deflex compiles once (model/linear_algebra.hpp) against matrices built from known factors
// A = U diag(s) V^T (random orthogonal U and V, chosen s), the normal equations and the minimum-norm
// formula x = A^T (A A^T)^-1 b, tall, wide and square, of full and deficient rank.
#include <algorithm>
#include <functional>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "deflex/model/linear_algebra.hpp"

namespace deflex {
namespace {

// A random orthogonal matrix: Q of a Gaussian matrix's QR.
Eigen::MatrixXd random_orthogonal(Eigen::Index n, std::mt19937& rng) {
  std::normal_distribution<double> g;
  const Eigen::MatrixXd m = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return g(rng); });
  return Eigen::HouseholderQR<Eigen::MatrixXd>(m).householderQ();
}

// A (rows x cols) with the given singular values (descending, min(rows, cols) of them).
Eigen::MatrixXd with_singular_values(Eigen::Index rows, Eigen::Index cols, const Eigen::VectorXd& s,
                                     std::mt19937& rng) {
  Eigen::MatrixXd sigma = Eigen::MatrixXd::Zero(rows, cols);
  sigma.diagonal().head(s.size()) = s;
  return random_orthogonal(rows, rng) * sigma * random_orthogonal(cols, rng).transpose();
}

struct Shape {
  Eigen::Index rows;
  Eigen::Index cols;
};

TEST(Svd, SingularValuesOfKnownFactorsTallWideAndSquare) {
  std::mt19937 rng(7);
  for (const Shape shape : {Shape{40, 6}, Shape{6, 6}, Shape{3, 50}, Shape{5, 7}, Shape{1, 4}, Shape{9, 1}}) {
    const Eigen::Index k = std::min(shape.rows, shape.cols);
    Eigen::VectorXd s = Eigen::VectorXd::LinSpaced(k, 1.0, 1e-3 + 1.0 / static_cast<double>(k));
    s[0] = 250.0;  // a spread of several decades
    std::sort(s.data(), s.data() + k, std::greater<>());
    const Eigen::MatrixXd a = with_singular_values(shape.rows, shape.cols, s, rng);
    const Eigen::VectorXd values = singular_values(a);
    ASSERT_EQ(values.size(), k) << shape.rows << " x " << shape.cols;
    EXPECT_LT((values - s).cwiseAbs().maxCoeff(), 1e-12 * s[0]) << shape.rows << " x " << shape.cols;

    const Svd svd(a);
    ASSERT_EQ(svd.values().size(), k);
    EXPECT_LT((svd.values() - s).cwiseAbs().maxCoeff(), 1e-12 * s[0]);
    const Eigen::MatrixXd& v = svd.right_vectors();
    ASSERT_EQ(v.rows(), shape.cols);
    ASSERT_EQ(v.cols(), shape.cols);
    // V is orthogonal, and |A v_i| is the i-th singular value (0 for the null space's columns).
    EXPECT_LT((v.transpose() * v - Eigen::MatrixXd::Identity(shape.cols, shape.cols)).cwiseAbs().maxCoeff(), 1e-12);
    for (Eigen::Index i = 0; i < shape.cols; ++i) {
      const double expected = i < k ? s[i] : 0.0;
      EXPECT_NEAR((a * v.col(i)).norm(), expected, 1e-11 * s[0]) << "column " << i;
    }
  }
}

TEST(Svd, SolveIsTheLeastSquaresSolutionOfAFullRankTallSystem) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  const Eigen::MatrixXd a = Eigen::MatrixXd::NullaryExpr(60, 10, [&] { return g(rng); });
  const Eigen::VectorXd b = Eigen::VectorXd::NullaryExpr(60, [&] { return g(rng); });
  // The normal equations A^T A x = A^T b, solved by Cholesky.
  const Eigen::VectorXd expected = (a.transpose() * a).llt().solve(a.transpose() * b);
  const Eigen::VectorXd x = Svd(a).solve(b);
  EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Svd, SolveIsTheMinimumNormSolutionOfAWideSystem) {
  std::mt19937 rng(13);
  std::normal_distribution<double> g;
  const Eigen::MatrixXd a = Eigen::MatrixXd::NullaryExpr(4, 9, [&] { return g(rng); });
  const Eigen::VectorXd b = Eigen::VectorXd::NullaryExpr(4, [&] { return g(rng); });
  const Eigen::VectorXd expected = a.transpose() * (a * a.transpose()).llt().solve(b);
  const Eigen::VectorXd x = Svd(a).solve(b);
  EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((a * x - b).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Svd, ARankDeficientSystemSolvesInTheRowSpaceOnly) {
  // Rank 3 of 5 columns: the exact singular values 0 count as zero, so the solution has no component in
  // the null space (the minimum-norm least-squares solution), whatever the right-hand side.
  std::mt19937 rng(17);
  Eigen::VectorXd s(5);
  s << 4.0, 2.0, 0.5, 0.0, 0.0;
  const Eigen::MatrixXd a = with_singular_values(12, 5, s, rng);
  std::normal_distribution<double> g;
  const Eigen::VectorXd b = Eigen::VectorXd::NullaryExpr(12, [&] { return g(rng); });
  const Svd svd(a);
  const Eigen::VectorXd x = svd.solve(b);
  const Eigen::MatrixXd null_space = svd.right_vectors().rightCols(2);
  EXPECT_LT((null_space.transpose() * x).cwiseAbs().maxCoeff(), 1e-12);
  // The residual is orthogonal to A's columns (the least-squares condition A^T (A x - b) = 0).
  EXPECT_LT((a.transpose() * (a * x - b)).cwiseAbs().maxCoeff(), 1e-11);
}

}  // namespace
}  // namespace deflex
