// Paths (circle, line) with inverse kinematics along them, and offline compensation of a path for a
// force model: a spec string as `deflex offline --force` takes it, one constant wrench (6,) or a
// wrench a point (N, 6) (base frame, moment about the TCP).
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/offline/offline_csv.hpp"
#include "deflex/offline/offline_summary.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/path_spec.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

/// A wrench a path point given as an (N, 6) array: base frame, moment about the TCP.
class ArrayWrenchModel final : public ForceModel {
 public:
  explicit ArrayWrenchModel(std::vector<Wrench> wrenches) : wrenches_(std::move(wrenches)) {}
  [[nodiscard]] Wrench wrench_at(std::size_t index, const Pose& /*base_T_tcp*/) const override {
    if (index >= wrenches_.size()) {
      throw InputError(fmt::format("force: the wrench array has {} rows, no row for path point {}", wrenches_.size(), index));
    }
    return wrenches_[index];
  }
  [[nodiscard]] std::string describe() const override {
    return fmt::format("a wrench a point from a ({}, 6) array (N, Nm; base frame, moment about the TCP)", wrenches_.size());
  }
  [[nodiscard]] std::string label() const override { return "array"; }
  [[nodiscard]] std::optional<std::size_t> points() const override { return wrenches_.size(); }

 private:
  std::vector<Wrench> wrenches_;
};

std::unique_ptr<ForceModel> force_model(const py::handle& force, const ForceSpecContext& context) {
  if (py::isinstance<py::str>(force)) return parse_force_spec(force.cast<std::string>(), context);
  bool table = false;
  const Array w = wrench_rows(force, "force", table);
  if (!table) return std::make_unique<ConstantWrenchModel>(Eigen::Map<const Wrench>(w.data()));
  std::vector<Wrench> rows(static_cast<std::size_t>(w.shape(0)));
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = Eigen::Map<const Wrench>(w.data() + 6 * i);
  return std::make_unique<ArrayWrenchModel>(std::move(rows));
}

IkRequest first_request(const RobotModel& model, const py::object& configuration, const py::object& seed) {
  IkRequest first;
  first.configuration = arm_configuration_arg(configuration);
  if (!seed.is_none()) first.seed = joint_vector(seed, "seed", model.dof());
  return first;
}

/// The path's poses: (N, 4, 4) as given, or a Circle sampled with the orientation.
std::vector<Pose> path_poses(const py::handle& path, const py::handle& orientation, ForceSpecContext& context) {
  if (py::isinstance<CirclePath>(path)) {
    const auto& c = path.cast<const CirclePath&>();
    context.circle = c;
    return sample_circle(c, unit_quaternion(orientation, "orientation_wxyz"));
  }
  return poses(path, "path");
}

py::ssize_t dof_of(const OfflineResult& r) { return r.points.empty() ? 0 : r.points.front().q_desired.size(); }

}  // namespace

void bind_offline(py::module_& m) {
  py::class_<CirclePath> circle(m, "Circle",
                                "A circle in the base frame (m): centre_m, radius_m, normal, start_angle_rad, "
                                "clockwise, points (closed: the last repeats the first).");
  vector_property(circle, "centre_m", &CirclePath::centre_m);
  vector_property(circle, "normal", &CirclePath::normal);
  circle.def(py::init([] { return default_circle(); }), "deflex's reference circle (as `deflex offline --circle`).")
      .def_readwrite("radius_m", &CirclePath::radius_m)
      .def_readwrite("start_angle_rad", &CirclePath::start_angle_rad)
      .def_readwrite("clockwise", &CirclePath::clockwise)
      .def_readwrite("points", &CirclePath::points)
      .def(
          "poses",
          [](const CirclePath& c, const py::handle& orientation) {
            return from_poses(sample_circle(c, unit_quaternion(orientation, "orientation_wxyz")));
          },
          "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0}, "The TCP poses (points, 4, 4), m.");

  m.def(
      "line_path",
      [](const py::handle& start, const py::handle& end, int points, const py::handle& orientation) {
        LinePath l;
        l.start_m = vector3(start, "start_m");
        l.end_m = vector3(end, "end_m");
        l.points = points;
        return from_poses(sample_line(l, unit_quaternion(orientation, "orientation_wxyz")));
      },
      "start_m"_a, "end_m"_a, "points"_a = 2, "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0},
      "TCP poses (points, 4, 4) along a straight segment (m), orientation held.");

  m.def(
      "solve_path_ik",
      [](const RobotModel& model, const py::handle& path, const py::object& configuration, const py::object& seed,
         const py::handle& orientation) {
        ForceSpecContext context;
        const std::vector<Pose> p = path_poses(path, orientation, context);
        const JointPath jp = solve_path_ik(model, p, first_request(model, configuration, seed));
        return py::make_tuple(from_rows(jp.q, model.dof()), configuration_tuple(jp.configuration));
      },
      "robot"_a, "path"_a, "configuration"_a = py::none(), "seed"_a = py::none(),
      "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0},
      "Joints (N, dof) rad along a path ((N, 4, 4) poses or a Circle) with one arm configuration kept, and that "
      "configuration (cf1, cf4, cf6, cfx). InputError names the path point.");

  py::class_<OfflineResult>(m, "OfflineResult", "A compensated path: one row a point (rad, m, N, Nm).")
      .def_property_readonly("q_desired", [](const OfflineResult& r) { return rows_of(r.points, &OfflinePoint::q_desired, dof_of(r)); },
                             "(N, dof) rad, from the path's IK")
      .def_property_readonly("q_command", [](const OfflineResult& r) { return rows_of(r.points, &OfflinePoint::q_command, dof_of(r)); },
                             "(N, dof) rad: q_desired - K^-1 J_wap(q_desired)^T W")
      .def_property_readonly("tcp_desired", [](const OfflineResult& r) { return poses_of(r.points, &OfflinePoint::tcp_desired); },
                             "(N, 4, 4) m")
      .def_property_readonly("tcp_command", [](const OfflineResult& r) { return poses_of(r.points, &OfflinePoint::tcp_command); },
                             "(N, 4, 4) m: FK(q_command)")
      .def_property_readonly("wrench", [](const OfflineResult& r) { return rows_of(r.points, &OfflinePoint::wrench_base, 6); },
                             "(N, 6) N, Nm: base frame, moment about the WAP")
      .def_property_readonly("predicted_deflection",
                             [](const OfflineResult& r) { return rows_of(r.points, &OfflinePoint::predicted_deflection, 6); },
                             "(N, 6) [m, rad]: uncompensated TCP displacement under the load")
      .def_property_readonly("predicted_residual",
                             [](const OfflineResult& r) { return rows_of(r.points, &OfflinePoint::predicted_residual, 6); },
                             "(N, 6) [m, rad]: after compensation (a check of the exact form)")
      .def_readonly("max_deflection_m", &OfflineResult::max_deflection_m)
      .def_readonly("mean_deflection_m", &OfflineResult::mean_deflection_m)
      .def_readonly("max_deflection_rad", &OfflineResult::max_deflection_rad)
      .def_readonly("max_residual_m", &OfflineResult::max_residual_m)
      .def_readonly("max_residual_rad", &OfflineResult::max_residual_rad)
      .def_readonly("max_correction_m", &OfflineResult::max_correction_m)
      .def_readonly("max_joint_correction_rad", &OfflineResult::max_joint_correction_rad)
      .def_readonly("force_description", &OfflineResult::force_description)
      .def("summary", [](const OfflineResult& r) { return offline_summary(r); }, "The summary `deflex offline` prints.")
      .def("write_csv", [](const OfflineResult& r, const std::string& path) { write_offline_csv(r, path); }, "path"_a,
           "The CSV `deflex offline -o` writes.");

  m.def(
      "compensate_path",
      [](const RobotModel& model, const py::handle& path, const py::handle& force, const py::object& configuration,
         const py::object& seed, const py::handle& orientation, bool predict) {
        ForceSpecContext context;
        const std::vector<Pose> p = path_poses(path, orientation, context);
        const std::unique_ptr<ForceModel> f = force_model(force, context);
        const JointPath jp = solve_path_ik(model, p, first_request(model, configuration, seed));
        OfflineOptions options;
        options.predict = predict;
        py::gil_scoped_release release;
        return compensate_path(model, jp, p, *f, options);
      },
      "robot"_a, "path"_a, "force"_a, "configuration"_a = py::none(), "seed"_a = py::none(),
      "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0}, "predict"_a = true,
      "Offline compensation (paper, Figure 2) of a path ((N, 4, 4) TCP poses in m, or a Circle sampled with "
      "orientation_wxyz) for a force: a spec string as `deflex offline --force` takes it (e.g. "
      "'ldbb:phi_deg=30,force_N=400' with a Circle, 'constant:fz_N=-500'), one wrench (6,) or one a point (N, 6) "
      "(N, Nm; base frame, moment about the TCP).");
}

}  // namespace deflex::python
