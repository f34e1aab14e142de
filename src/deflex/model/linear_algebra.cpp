#include "deflex/model/linear_algebra.hpp"

#include <algorithm>
#include <limits>

#include <Eigen/QR>
#include <Eigen/SVD>

namespace deflex {
namespace {

// Jacobi's SVD of a square matrix: no QR preconditioner is needed (or wanted: it is what makes the
// default instantiation slow to compile).
using SquareSvd = Eigen::JacobiSVD<Eigen::MatrixXd, Eigen::NoQRPreconditioner>;

// The n x n upper triangle R of a tall A = QR (m >= n): A and R share singular values and right
// singular vectors.
Eigen::MatrixXd triangle_of(const Eigen::HouseholderQR<Eigen::MatrixXd>& qr) {
  const Eigen::Index n = qr.matrixQR().cols();
  return qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
}

}  // namespace

Eigen::VectorXd singular_values(const Eigen::Ref<const Eigen::MatrixXd>& a) {
  // A and its transpose share singular values: reduce whichever is tall.
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr =
      a.rows() >= a.cols() ? Eigen::HouseholderQR<Eigen::MatrixXd>(a)
                           : Eigen::HouseholderQR<Eigen::MatrixXd>(Eigen::MatrixXd(a.transpose()));
  return SquareSvd(triangle_of(qr)).singularValues();
}

Svd::Svd(const Eigen::Ref<const Eigen::MatrixXd>& a) {
  const Eigen::Index m = a.rows();
  const Eigen::Index n = a.cols();
  if (m >= n) {
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
    const SquareSvd svd(triangle_of(qr), Eigen::ComputeFullU | Eigen::ComputeFullV);
    values_ = svd.singularValues();
    v_ = svd.matrixV();
    // U = Q [U_R; 0].
    u_ = Eigen::MatrixXd::Zero(m, n);
    u_.topRows(n) = svd.matrixU();
    u_.applyOnTheLeft(qr.householderQ());
  } else {
    // Fewer rows than columns: [A; 0] is square, with A's singular values followed by n - m zeros, the
    // same right singular vectors, and left singular vectors that are A's (with zero bottom rows) for the
    // non-zero singular values.
    Eigen::MatrixXd square = Eigen::MatrixXd::Zero(n, n);
    square.topRows(m) = a;
    const SquareSvd svd(square, Eigen::ComputeFullU | Eigen::ComputeFullV);
    values_ = svd.singularValues().head(m);
    v_ = svd.matrixV();
    u_ = svd.matrixU().topLeftCorner(m, m);
  }
}

Eigen::VectorXd Svd::solve(const Eigen::Ref<const Eigen::VectorXd>& b) const {
  const Eigen::Index k = values_.size();
  if (k == 0) {
    return Eigen::VectorXd::Zero(v_.rows());
  }
  // Eigen's rank rule for its SVDs: a singular value counts when it is at least min(m, n) * epsilon
  // times the largest.
  const double threshold = std::max<double>(
      values_[0] * static_cast<double>(std::max<Eigen::Index>(1, k)) * std::numeric_limits<double>::epsilon(),
      std::numeric_limits<double>::min());
  Eigen::Index rank = k;
  while (rank > 0 && values_[rank - 1] < threshold) {
    --rank;
  }
  const Eigen::VectorXd coefficients = (u_.leftCols(rank).transpose() * b).cwiseQuotient(values_.head(rank));
  return v_.leftCols(rank) * coefficients;
}

}  // namespace deflex
