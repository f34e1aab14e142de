// deflex.Robot: loading (built-in, YAML, URDF), FK, Jacobian, deflection and IK. fk, jacobian and
// deflect take one configuration (dof,) or a batch (N, dof) and run the batch in C++ with the GIL
// released, on one Workspace for the whole loop (no allocation per row).
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/model/robot_io.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

EndPoint end_point(const std::string& name) {
  if (name == "tcp") return EndPoint::kTcp;
  if (name == "flange") return EndPoint::kFlange;
  if (name == "wap") return EndPoint::kWap;
  throw InputError(fmt::format("argument point: '{}' is none of tcp, flange, wap", name));
}

/// Runs body(i, q_i) for every row of a (dof,) or (N, dof) array, GIL released.
template <typename Body>
void for_each_row(const RobotModel& model, const Array& q, py::ssize_t rows, Body&& body) {
  const double* qd = q.data();
  const int dof = model.dof();
  py::gil_scoped_release release;
  JointVector qi(dof);
  for (py::ssize_t i = 0; i < rows; ++i) {
    qi = Eigen::Map<const Eigen::VectorXd>(qd + i * dof, dof);
    body(i, qi);
  }
}

/// Shape of a result: (rest...) for one configuration, (N, rest...) for a batch.
std::vector<py::ssize_t> result_shape(bool batch, py::ssize_t rows, std::vector<py::ssize_t> rest) {
  if (batch) rest.insert(rest.begin(), rows);
  return rest;
}

/// The result of a per-configuration call over q: `rest` is its shape for one configuration;
/// body(q_i, out_i) fills the rest-shaped block of row i, GIL released.
template <typename Body>
Array batch_of(const RobotModel& model, const py::handle& q_obj, std::vector<py::ssize_t> rest, Body&& body) {
  bool batch = false;
  const Array q = joint_rows(q_obj, "q", model.dof(), batch);
  const py::ssize_t rows = batch ? q.shape(0) : 1;
  py::ssize_t block = 1;
  for (const py::ssize_t r : rest) block *= r;
  Array out = new_array(result_shape(batch, rows, std::move(rest)));
  double* o = out.mutable_data();
  for_each_row(model, q, rows, [&](py::ssize_t i, const JointVector& qi) { body(qi, o + i * block); });
  return out;
}

Array fk(const RobotModel& model, const py::handle& q_obj, const std::string& point) {
  const EndPoint ep = end_point(point);
  Workspace ws(model);
  return batch_of(model, q_obj, {4, 4}, [&](const JointVector& qi, double* out) {
    forward_kinematics(model, ws, qi);
    write_pose(end_pose(ws, ep), out);
  });
}

Array jacobian_of(const RobotModel& model, const py::handle& q_obj, const std::string& point) {
  const EndPoint ep = end_point(point);
  const int dof = model.dof();
  Workspace ws(model);
  Jacobian J(6, dof);
  return batch_of(model, q_obj, {6, dof}, [&](const JointVector& qi, double* out) {
    jacobian(model, ws, qi, ep, J);
    Eigen::Map<Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor>>(out, 6, dof) = J;
  });
}

/// What deflect() returns: arrays of one configuration or of a batch.
struct Deflection {
  Array dtheta_rad;      ///< (dof,) or (N, dof)
  Array tcp_deflection;  ///< (6,) or (N, 6): [m, m, m, rad, rad, rad], base frame
};

Deflection deflect(const RobotModel& model, const py::handle& q_obj, const py::handle& w_obj, bool complementary) {
  if (!model.has_stiffness()) (void)model.stiffness();  // throws ModelError naming the file
  bool batch = false, w_batch = false;
  const Array q = joint_rows(q_obj, "q", model.dof(), batch);
  const Array w = wrench_rows(w_obj, "wrench", w_batch);
  const py::ssize_t rows = batch ? q.shape(0) : 1;
  if (w_batch && (!batch || w.shape(0) != rows)) {
    throw InputError(fmt::format("argument wrench: expected shape (6,) or ({}, 6) (one wrench a configuration), got "
                                 "({}, 6)",
                                 rows, w.shape(0)));
  }
  const int dof = model.dof();
  Deflection out{new_array(result_shape(batch, rows, {dof})), new_array(result_shape(batch, rows, {6}))};
  double* dt = out.dtheta_rad.mutable_data();
  double* dx = out.tcp_deflection.mutable_data();
  const double* wd = w.data();
  ComplianceOptions options;
  options.complementary_stiffness = complementary;
  Workspace ws(model);
  JointVector dtheta(dof);
  for_each_row(model, q, rows, [&](py::ssize_t i, const JointVector& qi) {
    const Eigen::Map<const Wrench> wi(wd + (w_batch ? 6 * i : 0));
    Eigen::Map<Displacement>(dx + 6 * i) = tcp_deflection(model, ws, qi, wi, dtheta, options);
    Eigen::Map<Eigen::VectorXd>(dt + i * dof, dof) = dtheta;
  });
  return out;
}

}  // namespace

py::tuple configuration_tuple(const ArmConfiguration& c) { return py::make_tuple(c.cf1, c.cf4, c.cf6, c.cfx); }

std::optional<ArmConfiguration> arm_configuration_arg(const py::object& c) {
  if (c.is_none()) return std::nullopt;
  const auto v = c.cast<std::vector<int>>();
  if (v.size() != 4 || v[3] < 0 || v[3] > 7) {
    throw InputError("argument configuration: expected ABB confdata (cf1, cf4, cf6, cfx) with cfx 0..7");
  }
  return ArmConfiguration{v[0], v[1], v[2], v[3]};
}


void bind_model(py::module_& m) {
  py::class_<Deflection>(m, "Deflection",
                         "Joint deflection dtheta_rad = K^-1 J_wap^T W (rad) and the first-order TCP deflection "
                         "J_tcp dtheta [m, m, m, rad, rad, rad] (base frame), J at q itself.")
      .def_readonly("dtheta_rad", &Deflection::dtheta_rad)
      .def_readonly("tcp_deflection", &Deflection::tcp_deflection)
      .def("__repr__", [](const Deflection& d) {
        return fmt::format("Deflection(dtheta_rad={}, tcp_deflection={})", py::repr(d.dtheta_rad).cast<std::string>(),
                           py::repr(d.tcp_deflection).cast<std::string>());
      });

  py::class_<IkResult>(m, "IkResult", "One inverse-kinematics solution (joints in rad) or why there is none.")
      .def_property_readonly("status", [](const IkResult& r) { return std::string(to_string(r.status)); })
      .def_property_readonly("ok", &IkResult::ok)
      .def_property_readonly("q", [](const IkResult& r) { return from_vector(r.q); })
      .def_property_readonly("configuration", [](const IkResult& r) { return configuration_tuple(r.configuration); },
                             "ABB confdata (cf1, cf4, cf6, cfx)")
      .def_property_readonly("kuka_status", [](const IkResult& r) { return r.kuka.status; })
      .def_property_readonly("kuka_turn", [](const IkResult& r) { return r.kuka.turn; })
      .def_property_readonly("singularity", [](const IkResult& r) { return std::string(to_string(r.singularity)); })
      .def_readonly("position_error_m", &IkResult::position_error_m)
      .def_readonly("orientation_error_rad", &IkResult::orientation_error_rad)
      .def_readonly("analytic", &IkResult::analytic)
      .def_readonly("message", &IkResult::message)
      .def("__repr__", [](const IkResult& r) {
        return fmt::format("IkResult(status={}, q={}, configuration=({}, {}, {}, {}))", to_string(r.status),
                           py::repr(from_vector(r.q)).cast<std::string>(), r.configuration.cf1, r.configuration.cf4,
                           r.configuration.cf6, r.configuration.cfx);
      });

  py::class_<RobotModel, RobotHolder>(
      m, "Robot",
      "A validated, immutable robot (kinematics, joint limits, joint stiffness). Joints in rad, lengths in m, "
      "wrenches [Fx Fy Fz Mx My Mz] in N and Nm in the base frame with the moment about the WAP.")
      .def_static("builtin", [] { return std::make_shared<RobotModel>(builtin_irb6700()); },
                  "The built-in ABB IRB 6700-300/2.70.")
      .def_static("from_file", [](const std::string& path) { return std::make_shared<RobotModel>(load_robot(path)); },
                  "path"_a, "A deflex YAML (.yaml/.yml) or URDF (.urdf) file; ModelError names the file, line, field.")
      .def_static(
          "from_yaml",
          [](const std::string& text, const std::string& base_dir) {
            return std::make_shared<RobotModel>(load_robot_yaml_text(text, "<yaml text>", base_dir));
          },
          "text"_a, "base_dir"_a = ".", "deflex robot YAML from a string (relative URDF paths against base_dir).")
      .def_property_readonly("name", &RobotModel::name)
      .def_property_readonly("dof", &RobotModel::dof)
      .def_property_readonly("source", [](const RobotModel& r) { return r.description().source; })
      .def_property_readonly("notes", [](const RobotModel& r) { return r.description().notes; })
      .def_property_readonly("has_stiffness", &RobotModel::has_stiffness)
      .def_property_readonly("stiffness", [](const RobotModel& r) { return from_vector(r.stiffness()); },
                             "Joint stiffness, Nm/rad (ModelError when the file gives none).")
      .def_property_readonly("lower_limits", [](const RobotModel& r) { return from_vector(r.lower_limits()); }, "rad")
      .def_property_readonly("upper_limits", [](const RobotModel& r) { return from_vector(r.upper_limits()); }, "rad")
      .def_property_readonly("has_analytic_ik", [](const RobotModel& r) { return has_analytic_ik(r); })
      .def(
          "with_stiffness",
          [](const RobotModel& r, const py::handle& k, const std::string& note) {
            const Array a = vector_array(k, "stiffness_nm_per_rad", r.dof());
            return std::make_shared<RobotModel>(
                r.with_stiffness(std::vector<double>(a.data(), a.data() + a.size()), note));
          },
          "stiffness_nm_per_rad"_a, "note"_a = "given from Python", "A copy with another joint stiffness (Nm/rad).")
      .def(
          "within_limits",
          [](const RobotModel& r, const py::handle& q, double tol) {
            return r.within_limits(joint_vector(q, "q", r.dof()), tol);
          },
          "q"_a, "tolerance_rad"_a = 1e-9)
      .def("to_yaml", [](const RobotModel& r) { return robot_to_yaml(r); }, "deflex YAML of the robot (m, deg).")
      .def("fk", &fk, "q"_a, "point"_a = "tcp",
           "Pose of the TCP (or 'flange', 'wap') in the base frame as a 4x4 homogeneous matrix (m). q: (dof,) rad, "
           "or (N, dof) for a batch giving (N, 4, 4).")
      .def("jacobian", &jacobian_of, "q"_a, "point"_a = "tcp",
           "Geometric Jacobian (6, dof) of the TCP (or 'flange', 'wap'), base frame, linear rows first; (N, 6, dof) "
           "for a batch.")
      .def("deflect", &deflect, "q"_a, "wrench"_a, "complementary_stiffness"_a = false,
           "Deflection under a wrench [N, Nm] (base frame, moment about the WAP) at q (rad): (dof,) with (6,), or a "
           "batch (N, dof) with one wrench (6,) or one a row (N, 6).")
      .def(
          "cartesian_compliance",
          [](const RobotModel& r, const py::handle& q) {
            Workspace ws(r);
            return from_matrix(cartesian_compliance(r, ws, joint_vector(q, "q", r.dof())));
          },
          "q"_a, "C = J_wap K^-1 J_wap^T (6x6): [m, rad] per [N, Nm], at the WAP.")
      .def(
          "compensated_configuration",
          [](const RobotModel& r, const py::handle& q, const py::handle& w) {
            Workspace ws(r);
            JointVector out;
            compensated_configuration(r, ws, joint_vector(q, "q_desired", r.dof()), wrench_vector(w, "wrench"), out);
            return from_vector(out);
          },
          "q_desired"_a, "wrench"_a, "q_desired - K^-1 J_wap(q_desired)^T W (rad): the exact command for a known wrench.")
      .def(
          "deflected_configuration",
          [](const RobotModel& r, const py::handle& q, const py::handle& w) {
            Workspace ws(r);
            JointVector out;
            if (deflected_configuration(r, ws, joint_vector(q, "q_command", r.dof()), wrench_vector(w, "wrench"), out) !=
                DeflectionStatus::kConverged) {
              throw InputError("deflected_configuration: the fixed-point iteration did not converge (load too large)");
            }
            return from_vector(out);
          },
          "q_command"_a, "wrench"_a, "The configuration (rad) the arm takes under the wrench when commanded to q_command.")
      .def(
          "ik",
          [](const RobotModel& r, const py::handle& target, const py::object& seed) {
            const Pose p = pose(target, "pose");
            IkRequest req;
            if (!seed.is_none()) req.seed = joint_vector(seed, "seed", r.dof());
            Workspace ws(r);
            if (has_analytic_ik(r)) return all_ik_solutions(r, ws, p, req);
            IkResult one = inverse_kinematics(r, ws, p, req);
            return one.ok() ? std::vector<IkResult>{one} : std::vector<IkResult>{};
          },
          "pose"_a, "seed"_a = py::none(),
          "Every solution (IkResult, joints in rad) of a TCP pose (4x4, m) inside the joint limits, each joint at the "
          "turn nearest the seed; empty when there is none. Arms outside the analytic (OPW) family: the numerical "
          "solver's one solution.")
      .def(
          "inverse_kinematics",
          [](const RobotModel& r, const py::handle& target, const py::object& configuration, const py::object& seed) {
            IkRequest req;
            req.configuration = arm_configuration_arg(configuration);
            if (!seed.is_none()) req.seed = joint_vector(seed, "seed", r.dof());
            Workspace ws(r);
            return inverse_kinematics(r, ws, pose(target, "pose"), req);
          },
          "pose"_a, "configuration"_a = py::none(), "seed"_a = py::none(),
          "One solution chosen by ABB confdata and/or the seed, with its status and message (never raises for an "
          "unreachable pose: see status).")
      .def("__repr__", [](const RobotModel& r) { return fmt::format("<deflex.Robot '{}', {} joints>", r.name(), r.dof()); });

  m.def("load_robot", [](const std::string& path) { return std::make_shared<RobotModel>(load_robot(path)); }, "path"_a,
        "Robot.from_file(path).");
  m.def(
      "pose",
      [](const py::handle& position, const py::handle& quaternion) {
        const Eigen::Quaterniond quat = unit_quaternion(quaternion, "quaternion_wxyz");
        Pose p = Pose::Identity();
        p.linear() = quat.toRotationMatrix();
        p.translation() = vector3(position, "position_m");
        return from_pose(p);
      },
      "position_m"_a, "quaternion_wxyz"_a, "A 4x4 homogeneous transform from a position (m) and a unit quaternion.");
}

}  // namespace deflex::python
