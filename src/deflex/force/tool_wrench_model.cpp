// Tool-frame constant wrench.
#include "deflex/force/tool_wrench_model.hpp"

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

ToolWrenchModel::ToolWrenchModel(const Wrench& wrench_tool) : wrench_tool_(wrench_tool) {
  if (!wrench_tool_.allFinite()) {
    throw InputError("tool wrench: values must be finite");
  }
}

Wrench ToolWrenchModel::wrench_at(std::size_t /*index*/, const Pose& base_T_tcp) const {
  const Matrix3& R = base_T_tcp.linear();
  if (!R.allFinite()) {
    throw InputError("tool wrench: the TCP orientation is not finite");
  }
  Wrench w;
  w.head<3>() = R * wrench_tool_.head<3>();
  w.tail<3>() = R * wrench_tool_.tail<3>();
  return w;
}

std::string ToolWrenchModel::describe() const {
  return fmt::format(
      "wrench constant in the tool frame F = ({:g}, {:g}, {:g}) N, M = ({:g}, {:g}, {:g}) Nm about "
      "the TCP (turns with the tool)",
      wrench_tool_[0], wrench_tool_[1], wrench_tool_[2], wrench_tool_[3], wrench_tool_[4], wrench_tool_[5]);
}

}  // namespace deflex
