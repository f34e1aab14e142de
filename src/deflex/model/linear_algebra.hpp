// The SVD deflex uses wherever it needs a dynamic one (identification, registration, payload
// identification). Not instantiated explicitly in the library: an explicit instantiation in an
// instrumented build interposed on Orocos KDL's own copy (its LMA solver holds one), and the two
// sides allocate differently under AddressSanitizer.
#pragma once

#include <Eigen/Core>
#include <Eigen/SVD>

namespace deflex {

/// The SVD deflex uses wherever it needs one (identification, registration, payload identification).
using DynamicSvd = Eigen::JacobiSVD<Eigen::MatrixXd>;

}  // namespace deflex
