// Constant wrench model.
#include "deflex/force/constant_wrench_model.hpp"

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

ConstantWrenchModel::ConstantWrenchModel(const Wrench& wrench_base) : wrench_(wrench_base) {
  if (!wrench_.allFinite()) {
    throw InputError("constant wrench: values must be finite");
  }
}

Wrench ConstantWrenchModel::wrench_at(std::size_t /*index*/, const Pose& /*base_T_tcp*/) const { return wrench_; }

std::string ConstantWrenchModel::describe() const {
  return fmt::format("constant wrench F = ({:g}, {:g}, {:g}) N, M = ({:g}, {:g}, {:g}) Nm about the TCP, base frame",
                     wrench_[0], wrench_[1], wrench_[2], wrench_[3], wrench_[4], wrench_[5]);
}

}  // namespace deflex
