// Eigen's JacobiSVD of a dynamic matrix, compiled once. Each translation unit that instantiates
// Eigen::JacobiSVD<Eigen::MatrixXd> spends about 20 s of CPU at -O3 on it (measured with GCC 12 on the
// build host: inverse_kinematics.cpp 37 s with it, 13 s without), and four modules use it; declared
// here as an explicit instantiation that linear_algebra.cpp defines, they share one.
#pragma once

#include <Eigen/Core>
#include <Eigen/SVD>

extern template class Eigen::JacobiSVD<Eigen::MatrixXd>;

namespace deflex {

/// The SVD deflex uses wherever it needs one (identification, registration, payload identification).
using DynamicSvd = Eigen::JacobiSVD<Eigen::MatrixXd>;

/// The singular values of `m`, largest first.
[[nodiscard]] Eigen::VectorXd singular_values(const Eigen::MatrixXd& m);

}  // namespace deflex
