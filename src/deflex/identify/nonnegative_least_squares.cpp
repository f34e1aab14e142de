// Lawson-Hanson active-set NNLS.
#include "deflex/identify/detail/nonnegative_least_squares.hpp"

#include <Eigen/QR>

namespace deflex {
namespace {

// Unconstrained least squares on the passive columns only; the others are held at zero.
Eigen::VectorXd solve_passive(const Eigen::MatrixXd& A, const Eigen::VectorXd& y,
                              const Eigen::Array<bool, Eigen::Dynamic, 1>& passive) {
  const Eigen::Index n = A.cols();
  Eigen::Index p = passive.count();
  Eigen::MatrixXd Ap(A.rows(), p);
  for (Eigen::Index j = 0, k = 0; j < n; ++j) {
    if (passive[j]) {
      Ap.col(k++) = A.col(j);
    }
  }
  const Eigen::VectorXd zp = Ap.colPivHouseholderQr().solve(y);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
  for (Eigen::Index j = 0, k = 0; j < n; ++j) {
    if (passive[j]) {
      z[j] = zp[k++];
    }
  }
  return z;
}

}  // namespace

NnlsResult nonnegative_least_squares(const Eigen::MatrixXd& A, const Eigen::VectorXd& y, double tolerance,
                                     int max_iterations) {
  const Eigen::Index n = A.cols();
  NnlsResult r;
  r.x = Eigen::VectorXd::Zero(n);
  r.at_bound = Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(n, true);
  if (max_iterations <= 0) {
    max_iterations = 3 * static_cast<int>(n) + 10;
  }
  Eigen::Array<bool, Eigen::Dynamic, 1> passive = Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(n, false);
  // No columns: nothing to solve (and maxCoeff of an empty vector is undefined).
  const double scale = n == 0 ? 0.0 : (A.transpose() * y).cwiseAbs().maxCoeff();
  if (scale == 0.0) {
    r.converged = true;
    return r;
  }
  const double tol = tolerance * scale;
  Eigen::VectorXd& x = r.x;
  while (r.iterations < max_iterations) {
    const Eigen::VectorXd w = A.transpose() * (y - A * x);
    Eigen::Index t = -1;
    double best = tol;
    for (Eigen::Index j = 0; j < n; ++j) {
      if (!passive[j] && w[j] > best) {
        best = w[j];
        t = j;
      }
    }
    if (t < 0) {
      r.converged = true;
      break;
    }
    passive[t] = true;
    // Inner loop: step towards the unconstrained solution on the passive set, dropping columns
    // that would turn negative, until that solution is feasible.
    while (true) {
      ++r.iterations;
      const Eigen::VectorXd z = solve_passive(A, y, passive);
      bool feasible = true;
      for (Eigen::Index j = 0; j < n; ++j) {
        if (passive[j] && z[j] <= 0.0) {
          feasible = false;
        }
      }
      if (feasible) {
        x = z;
        break;
      }
      double alpha = 1.0;
      for (Eigen::Index j = 0; j < n; ++j) {
        if (passive[j] && z[j] <= 0.0) {
          alpha = std::min(alpha, x[j] / (x[j] - z[j]));
        }
      }
      x += alpha * (z - x);
      for (Eigen::Index j = 0; j < n; ++j) {
        if (passive[j] && x[j] <= 0.0) {
          passive[j] = false;
          x[j] = 0.0;
        }
      }
      if (r.iterations >= max_iterations) {
        break;
      }
    }
  }
  r.at_bound = !passive;
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!passive[j]) {
      x[j] = 0.0;
    }
  }
  return r;
}

}  // namespace deflex
