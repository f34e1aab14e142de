// The one instantiation of Eigen's dynamic JacobiSVD (see linear_algebra.hpp).
#include "deflex/model/linear_algebra.hpp"

template class Eigen::JacobiSVD<Eigen::MatrixXd>;

namespace deflex {

Eigen::VectorXd singular_values(const Eigen::MatrixXd& m) { return DynamicSvd(m).singularValues(); }

}  // namespace deflex
