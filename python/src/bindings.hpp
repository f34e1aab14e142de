// The parts of the deflex Python module, one function a part of the library (model, identify,
// offline, machining, evaluate, online, study, runtime), each in its own file; module.cpp calls them in this order.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/pybind11.h>
#include <nlohmann/json_fwd.hpp>

#include "deflex/model/arm_configuration.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/model/robot_model.hpp"

namespace deflex::python {

namespace py = pybind11;

/// The Python class deflex.Robot holds its RobotModel by shared pointer, so results and compensators
/// made from it may outlive the Python object.
using RobotHolder = std::shared_ptr<RobotModel>;

/// ABB confdata (cf1, cf4, cf6, cfx) as a tuple, and from a Python sequence (None: not given).
py::tuple configuration_tuple(const ArmConfiguration& c);
std::optional<ArmConfiguration> arm_configuration_arg(const py::handle& c);

/// Where a wrench's moment is taken, from a `moment_about` argument: "wap" (false) or "tcp" (true).
bool moment_about_tcp(const std::string& about);
/// The wrench of row `row` of `wrenches` ((6,) for every row when not `per_row`, else (N, 6)) with its
/// moment about the WAP at q, moved there from the TCP when `about_tcp` (FK at q into `ws`).
Wrench wrench_at_wap(const RobotModel& model, Workspace& ws, const JointVector& q, const double* wrenches, bool per_row,
                     std::ptrdiff_t row, bool about_tcp);

/// A library message as Python says it: the command line's option names replaced by the arguments the
/// Python calls take (errors.cpp). Every exception's text goes through it, and so do warnings.
std::string python_message(std::string text);
std::vector<std::string> python_messages(std::vector<std::string> texts);

/// A JSON document as the Python objects json.loads makes of it (dict, list, str, float, ...).
py::object json_to_python(const nlohmann::json& doc);

void bind_errors(py::module_& m);
void bind_model(py::module_& m);
void bind_identify(py::module_& m);
void bind_offline(py::module_& m);
void bind_machining(py::module_& m);
void bind_evaluate(py::module_& m);
void bind_online(py::module_& m);
void bind_study(py::module_& m);
void bind_machining_study(py::module_& m);
void bind_runtime(py::module_& m);

}  // namespace deflex::python
