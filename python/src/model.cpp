// deflex.Robot: loading (built-in, YAML, URDF), FK, Jacobian, deflection and IK. Every
// per-configuration call takes one configuration (dof,) or a batch (N, dof) and runs the batch in
// C++ with the GIL released, spread over threads (one Workspace a thread). Wrenches have their moment
// about the WAP unless the call's moment_about says "tcp".
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "parallel.hpp"

namespace deflex::python {
using namespace pybind11::literals;

/// Where a wrench's moment is taken: "wap" (the model's point, the default of every call) or "tcp".
bool moment_about_tcp(const std::string& about) {
  if (about == "wap") return false;
  if (about == "tcp") return true;
  throw InputError(fmt::format("argument moment_about: '{}' is neither wap nor tcp", about));
}

Wrench wrench_at_wap(const RobotModel& model, Workspace& ws, const JointVector& q, const double* wrenches, bool per_row,
                     std::ptrdiff_t row, bool about_tcp) {
  Wrench w = Eigen::Map<const Wrench>(wrenches + (per_row ? 6 * row : 0));
  if (!about_tcp) return w;
  forward_kinematics(model, ws, q);
  return moment_moved(w, ws.base_T_tcp.translation(), ws.base_T_wap.translation());
}

namespace {

/// A frame of the arm fk() and jacobian() name: an end point, or the moving frame of joint k
/// (after its rotation), named "jointK" (1-based) or by the joint's name in the robot file.
struct Frame {
  EndPoint end = EndPoint::kTcp;
  int joint = -1;  ///< 0-based joint index; -1: an end point
};

Frame frame_of(const RobotModel& model, const std::string& name) {
  if (name == "tcp") return {EndPoint::kTcp, -1};
  if (name == "flange") return {EndPoint::kFlange, -1};
  if (name == "wap") return {EndPoint::kWap, -1};
  for (int i = 0; i < model.dof(); ++i) {
    if (name == fmt::format("joint{}", i + 1) || (!model.joint(i).name.empty() && name == model.joint(i).name)) {
      return {EndPoint::kTcp, i};
    }
  }
  std::string names = "tcp, flange, wap";
  for (int i = 0; i < model.dof(); ++i) {
    names += fmt::format(", joint{}", i + 1);
    if (!model.joint(i).name.empty()) names += fmt::format(" ({})", model.joint(i).name);
  }
  throw InputError(fmt::format("argument point: '{}' is no frame of {}: {}", name, model.name(), names));
}

/// The moving frame of joint `k` at q: the chain's transforms multiplied out to it.
Pose joint_frame(const RobotModel& model, const JointVector& q, int k) {
  Pose t = model.description().base_T_chain;
  for (int i = 0; i <= k; ++i) {
    const JointSpec& j = model.joint(i);
    t = t * j.parent_T_joint * Eigen::AngleAxisd(q[i] + j.offset_rad, j.axis);
  }
  return t;
}

/// Shape of a result: (rest...) for one configuration, (N, rest...) for a batch.
std::vector<py::ssize_t> result_shape(bool batch, py::ssize_t rows, std::vector<py::ssize_t> rest) {
  if (batch) rest.insert(rest.begin(), rows);
  return rest;
}

/// Runs body(ws, i, q_i) for every row of q (rows of dof values), spread over `threads` threads (0:
/// every core), each with its own Workspace; the GIL released for a batch (kGilRows rows or more: for
/// fewer, releasing and taking it back costs more than the rows).
template <typename Body>
void for_each_row(const RobotModel& model, const double* qd, py::ssize_t rows, int threads, Body&& body) {
  const int dof = model.dof();
  const int n_threads = batch_threads(threads, rows);
  std::optional<py::gil_scoped_release> release;
  if (rows >= kGilRows) release.emplace();
  parallel_rows(rows, n_threads, [&](std::ptrdiff_t begin, std::ptrdiff_t end) {
    Workspace ws(model);
    JointVector qi(dof);
    for (std::ptrdiff_t i = begin; i < end; ++i) {
      qi = Eigen::Map<const Eigen::VectorXd>(qd + i * dof, dof);
      body(ws, i, qi);
    }
  });
}

/// The result of a per-configuration call over q: `rest` is its shape for one configuration;
/// body(ws, i, q_i, out_i) fills the rest-shaped block of row i.
template <typename Body>
Array batch_of(const RobotModel& model, const py::handle& q_obj, const char* q_name, std::vector<py::ssize_t> rest,
               int threads, Body&& body) {
  bool batch = false;
  const Array q = joint_rows(q_obj, q_name, model.dof(), batch);
  const py::ssize_t rows = batch ? q.shape(0) : 1;
  py::ssize_t block = 1;
  for (const py::ssize_t r : rest) block *= r;
  Array out = new_array(result_shape(batch, rows, std::move(rest)));
  double* o = out.mutable_data();
  for_each_row(model, q.data(), rows, threads,
               [&](Workspace& ws, std::ptrdiff_t i, const JointVector& qi) { body(ws, i, qi, o + i * block); });
  return out;
}

Array fk(const RobotModel& model, const ArrayLike& q_obj, const std::string& point, int threads) {
  const Frame f = frame_of(model, point);
  return batch_of(model, q_obj, "q", {4, 4}, threads,
                  [&](Workspace& ws, std::ptrdiff_t, const JointVector& qi, double* out) {
                    if (f.joint >= 0) {
                      write_pose(joint_frame(model, qi, f.joint), out);
                      return;
                    }
                    forward_kinematics(model, ws, qi);
                    write_pose(end_pose(ws, f.end), out);
                  });
}

Array jacobian_of(const RobotModel& model, const ArrayLike& q_obj, const std::string& point, int threads) {
  const Frame f = frame_of(model, point);
  const int dof = model.dof();
  return batch_of(model, q_obj, "q", {6, dof}, threads,
                  [&](Workspace& ws, std::ptrdiff_t, const JointVector& qi, double* out) {
                    Eigen::Map<Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor>> o(out, 6, dof);
                    if (f.joint >= 0) {
                      forward_kinematics(model, ws, qi);
                      point_jacobian(ws, joint_frame(model, qi, f.joint).translation(), ws.jacobian);
                      o = ws.jacobian;
                      o.rightCols(dof - 1 - f.joint).setZero();  // the joints after it do not move the frame
                      return;
                    }
                    jacobian(model, ws, qi, f.end, ws.jacobian);
                    o = ws.jacobian;
                  });
}

/// What deflect() returns: arrays of one configuration or of a batch.
struct Deflection {
  Array dtheta_rad;      ///< (dof,) or (N, dof)
  Array tcp_deflection;  ///< (6,) or (N, 6): [m, m, m, rad, rad, rad], base frame
};

/// Wrenches (6,) or one a configuration (N, 6) beside q (dof,) or (N, dof).
Array wrenches_for(const py::handle& w_obj, bool batch, py::ssize_t rows, bool& w_batch) {
  Array w = wrench_rows(w_obj, "wrench", w_batch);
  if (w_batch && (!batch || w.shape(0) != rows)) {
    throw InputError(
        fmt::format("argument wrench: expected shape (6,) or ({}, 6) (one wrench a configuration), got "
                    "({}, 6)",
                    rows, w.shape(0)));
  }
  return w;
}

Deflection deflect(const RobotModel& model, const ArrayLike& q_obj, const ArrayLike& w_obj, bool complementary,
                   const std::string& about, int threads) {
  if (!model.has_stiffness()) (void)model.stiffness();  // throws ModelError naming the file
  const bool about_tcp = moment_about_tcp(about);
  bool batch = false, w_batch = false;
  const Array q = joint_rows(q_obj, "q", model.dof(), batch);
  const py::ssize_t rows = batch ? q.shape(0) : 1;
  const Array w = wrenches_for(w_obj, batch, rows, w_batch);
  const int dof = model.dof();
  Deflection out{new_array(result_shape(batch, rows, {dof})), new_array(result_shape(batch, rows, {6}))};
  double* dt = out.dtheta_rad.mutable_data();
  double* dx = out.tcp_deflection.mutable_data();
  const double* wd = w.data();
  ComplianceOptions options;
  options.complementary_stiffness = complementary;
  for_each_row(model, q.data(), rows, threads, [&](Workspace& ws, std::ptrdiff_t i, const JointVector& qi) {
    const Wrench wi = wrench_at_wap(model, ws, qi, wd, w_batch, i, about_tcp);
    JointVector dtheta(dof);
    Eigen::Map<Displacement>(dx + 6 * i) = tcp_deflection(model, ws, qi, wi, dtheta, options);
    Eigen::Map<Eigen::VectorXd>(dt + i * dof, dof) = dtheta;
  });
  return out;
}

/// compensated_configuration or deflected_configuration over q (dof,) or (N, dof).
Array configurations_under(const RobotModel& model, const ArrayLike& q_obj, const char* q_name, const ArrayLike& w_obj,
                           const std::string& about, int threads, bool deflected) {
  if (!model.has_stiffness()) (void)model.stiffness();
  const bool about_tcp = moment_about_tcp(about);
  bool batch = false, w_batch = false;
  const Array q = joint_rows(q_obj, q_name, model.dof(), batch);
  const py::ssize_t rows = batch ? q.shape(0) : 1;
  const Array w = wrenches_for(w_obj, batch, rows, w_batch);
  const int dof = model.dof();
  Array out = new_array(result_shape(batch, rows, {dof}));
  double* o = out.mutable_data();
  const double* wd = w.data();
  std::vector<char> failed(static_cast<std::size_t>(rows), 0);
  for_each_row(model, q.data(), rows, threads, [&](Workspace& ws, std::ptrdiff_t i, const JointVector& qi) {
    const Wrench wi = wrench_at_wap(model, ws, qi, wd, w_batch, i, about_tcp);
    JointVector r(dof);
    if (deflected) {
      failed[static_cast<std::size_t>(i)] =
          deflected_configuration(model, ws, qi, wi, r) != DeflectionStatus::kConverged ? 1 : 0;
    } else {
      compensated_configuration(model, ws, qi, wi, r);
    }
    Eigen::Map<Eigen::VectorXd>(o + i * dof, dof) = r;
  });
  for (py::ssize_t i = 0; i < rows; ++i) {
    if (failed[static_cast<std::size_t>(i)]) {
      throw InputError(
          fmt::format("deflected_configuration: {}the fixed-point iteration did not converge (load too "
                      "large for the model)",
                      batch ? fmt::format("row {}: ", i) : std::string()));
    }
  }
  return out;
}

/// Every IK solution of one pose, nearest the seed first (the largest joint difference), so that
/// [0] is the solution at the turn nearest the seed.
std::vector<IkResult> ik_solutions(const RobotModel& r, Workspace& ws, const Pose& p, const IkRequest& req) {
  if (!has_analytic_ik(r)) {
    IkResult one = inverse_kinematics(r, ws, p, req);
    return one.ok() ? std::vector<IkResult>{one} : std::vector<IkResult>{};
  }
  return all_ik_solutions(r, ws, p, req);  // nearest the seed first
}

/// The seeds of an IK call, read while the GIL is held: none, one (dof,) for every pose, or one a
/// pose (N, dof) when `poses` > 0 (a batch of poses).
struct Seeds {
  std::optional<JointVector> one;
  std::optional<Array> rows;

  Seeds(const RobotModel& r, const std::optional<ArrayLike>& seed, py::ssize_t poses) {
    if (!seed || seed->is_none()) return;
    if (poses == 0) {
      one = joint_vector(*seed, "seed", r.dof());
      return;
    }
    bool batch = false;
    Array s = joint_rows(*seed, "seed", r.dof(), batch);
    if (!batch) {
      one = Eigen::Map<const Eigen::VectorXd>(s.data(), r.dof());
    } else if (s.shape(0) != poses) {
      throw InputError(fmt::format("argument seed: expected shape ({},) or ({}, {}) (one seed a pose), got ({}, {})",
                                   r.dof(), poses, r.dof(), s.shape(0), r.dof()));
    } else {
      rows = std::move(s);
    }
  }

  /// The request for pose i (no Python call: safe without the GIL).
  [[nodiscard]] IkRequest request(int dof, py::ssize_t i) const {
    IkRequest req;
    if (rows) {
      req.seed = Eigen::Map<const Eigen::VectorXd>(rows->data() + i * dof, dof);
    } else {
      req.seed = one;
    }
    return req;
  }
};

bool is_pose_batch(const py::handle& obj) {
  const py::array a = py::array::ensure(obj);
  return a && a.ndim() == 3;
}

Returns<IkSolutionsTag> ik(const RobotModel& r, const ArrayLike& target, const std::optional<ArrayLike>& seed) {
  if (!is_pose_batch(target)) {
    Workspace ws(r);
    return {py::cast(ik_solutions(r, ws, pose(target, "pose"), Seeds(r, seed, 0).request(r.dof(), 0)))};
  }
  const std::vector<Pose> p = poses(target, "pose");
  const Seeds seeds(r, seed, static_cast<py::ssize_t>(p.size()));
  std::vector<std::vector<IkResult>> out(p.size());
  {
    py::gil_scoped_release release;
    Workspace ws(r);
    for (std::size_t i = 0; i < p.size(); ++i) {
      out[i] = ik_solutions(r, ws, p[i], seeds.request(r.dof(), static_cast<py::ssize_t>(i)));
    }
  }
  return {py::cast(out)};
}

Returns<IkResultsTag> inverse_kinematics_of(const RobotModel& r, const ArrayLike& target,
                                            const ConfigurationArg& configuration,
                                            const std::optional<ArrayLike>& seed) {
  const std::optional<ArmConfiguration> conf = arm_configuration_arg(configuration);
  if (!is_pose_batch(target)) {
    IkRequest req = Seeds(r, seed, 0).request(r.dof(), 0);
    req.configuration = conf;
    Workspace ws(r);
    return {py::cast(inverse_kinematics(r, ws, pose(target, "pose"), req))};
  }
  const std::vector<Pose> p = poses(target, "pose");
  const Seeds seeds(r, seed, static_cast<py::ssize_t>(p.size()));
  std::vector<IkResult> out(p.size());
  {
    py::gil_scoped_release release;
    Workspace ws(r);
    for (std::size_t i = 0; i < p.size(); ++i) {
      IkRequest req = seeds.request(r.dof(), static_cast<py::ssize_t>(i));
      req.configuration = conf;
      out[i] = inverse_kinematics(r, ws, p[i], req);
    }
  }
  return {py::cast(out)};
}

RobotHolder robot_from_state(const py::tuple& state) {
  if (state.size() != 2) throw InputError("deflex.Robot: a pickled robot is (yaml text, source)");
  RobotModel m = load_robot_yaml_text(state[0].cast<std::string>(), state[1].cast<std::string>());
  return std::make_shared<RobotModel>(std::move(m));
}

}  // namespace

py::tuple configuration_tuple(const ArmConfiguration& c) { return py::make_tuple(c.cf1, c.cf4, c.cf6, c.cfx); }

std::optional<ArmConfiguration> arm_configuration_arg(const py::handle& c) {
  if (c.is_none()) return std::nullopt;
  std::vector<int> v;
  try {
    v = c.cast<std::vector<int>>();
  } catch (const py::cast_error&) {
    throw InputError("argument configuration: expected ABB confdata (cf1, cf4, cf6, cfx): four whole numbers");
  }
  if (v.size() != 4 || v[3] < 0 || v[3] > 7) {
    throw InputError("argument configuration: expected ABB confdata (cf1, cf4, cf6, cfx) with cfx 0..7");
  }
  return ArmConfiguration{v[0], v[1], v[2], v[3]};
}

namespace {

// What deflect() and ik() return.
void bind_model_result_types(py::module_& m) {
  py::class_<Deflection>(m, "Deflection",
                         "Joint deflection dtheta_rad = K^-1 J_wap^T W (rad) and the first-order TCP deflection "
                         "J_tcp dtheta [m, m, m, rad, rad, rad] (base frame), J at q itself.")
      .def_property_readonly("dtheta_rad", [](const Deflection& d) { return frozen(d.dtheta_rad); })
      .def_property_readonly("tcp_deflection", [](const Deflection& d) { return frozen(d.tcp_deflection); })
      .def(py::pickle([](const Deflection& d) { return py::make_tuple(d.dtheta_rad, d.tcp_deflection); },
                      [](const py::tuple& t) {
                        return Deflection{t[0].cast<Array>(), t[1].cast<Array>()};
                      }))
      .def("__repr__", [](const Deflection& d) {
        return fmt::format("Deflection(dtheta_rad={}, tcp_deflection={})", py::repr(d.dtheta_rad).cast<std::string>(),
                           py::repr(d.tcp_deflection).cast<std::string>());
      });

  py::class_<IkResult>(m, "IkResult", "One inverse-kinematics solution (joints in rad) or why there is none.")
      .def_property_readonly("status", [](const IkResult& r) { return std::string(to_string(r.status)); })
      .def_property_readonly("ok", &IkResult::ok)
      .def_property_readonly("q", [](const IkResult& r) { return frozen(from_vector(r.q)); })
      .def_property_readonly(
          "configuration", [](const IkResult& r) { return configuration_tuple(r.configuration); },
          "ABB confdata (cf1, cf4, cf6, cfx)")
      .def_property_readonly("kuka_status", [](const IkResult& r) { return r.kuka.status; })
      .def_property_readonly("kuka_turn", [](const IkResult& r) { return r.kuka.turn; })
      .def_property_readonly("singularity", [](const IkResult& r) { return std::string(to_string(r.singularity)); })
      .def_readonly("position_error_m", &IkResult::position_error_m)
      .def_readonly("orientation_error_rad", &IkResult::orientation_error_rad)
      .def_readonly("analytic", &IkResult::analytic)
      .def_readonly("message", &IkResult::message)
      .def(py::pickle(
          [](const IkResult& r) {
            return py::make_tuple(static_cast<int>(r.status), from_vector(r.q), configuration_tuple(r.configuration),
                                  r.kuka.status, r.kuka.turn, static_cast<int>(r.singularity), r.position_error_m,
                                  r.orientation_error_rad, r.analytic, r.message);
          },
          [](const py::tuple& t) {
            if (t.size() != 10) throw InputError("deflex.IkResult: not a pickled IkResult");
            IkResult r;
            r.status = static_cast<IkStatus>(t[0].cast<int>());
            const Array q = t[1].cast<Array>();
            r.q = Eigen::Map<const Eigen::VectorXd>(q.data(), q.size());
            r.configuration = *arm_configuration_arg(t[2]);
            r.kuka.status = t[3].cast<int>();
            r.kuka.turn = t[4].cast<int>();
            r.singularity = static_cast<decltype(r.singularity)>(t[5].cast<int>());
            r.position_error_m = t[6].cast<double>();
            r.orientation_error_rad = t[7].cast<double>();
            r.analytic = t[8].cast<bool>();
            r.message = t[9].cast<std::string>();
            return r;
          }))
      .def("__repr__", [](const IkResult& r) {
        return fmt::format("IkResult(status={}, q={}, configuration=({}, {}, {}, {}))", to_string(r.status),
                           py::repr(from_vector(r.q)).cast<std::string>(), r.configuration.cf1, r.configuration.cf4,
                           r.configuration.cf6, r.configuration.cfx);
      });
}

// Robot's constructors and what the robot file says.
void bind_model_robot_description(py::class_<RobotModel, RobotHolder>& robot_class) {
  robot_class
      .def_static(
          "builtin", [] { return std::make_shared<RobotModel>(builtin_irb6700()); },
          "The built-in ABB IRB 6700-300/2.70.")
      .def_static(
          "from_file", [](const PathArg& path) { return std::make_shared<RobotModel>(load_robot(path_text(path))); },
          "path"_a, "A deflex YAML (.yaml/.yml) or URDF (.urdf) file; ModelError names the file, line, field.")
      .def_static(
          "from_yaml",
          [](const std::string& text, const PathArg& base_dir) {
            return std::make_shared<RobotModel>(load_robot_yaml_text(text, "<yaml text>", path_text(base_dir)));
          },
          "text"_a, "base_dir"_a = PathArg("."),
          "deflex robot YAML from a string (relative URDF paths against base_dir).")
      .def_property_readonly("name", &RobotModel::name)
      .def_property_readonly("dof", &RobotModel::dof)
      .def_property_readonly("source", [](const RobotModel& r) { return r.description().source; })
      .def_property_readonly("notes", [](const RobotModel& r) { return r.description().notes; })
      .def_property_readonly("has_stiffness", &RobotModel::has_stiffness)
      .def_property_readonly(
          "stiffness",
          [](const RobotModel& r) -> std::optional<Array> {
            if (!r.has_stiffness()) return std::nullopt;
            return frozen(from_vector(r.stiffness()));
          },
          "Joint stiffness, Nm/rad; None when the robot file gives none (a bare URDF).")
      .def_property_readonly(
          "lower_limits", [](const RobotModel& r) { return frozen(from_vector(r.lower_limits())); }, "rad")
      .def_property_readonly(
          "upper_limits", [](const RobotModel& r) { return frozen(from_vector(r.upper_limits())); }, "rad")
      .def_property_readonly("has_analytic_ik", [](const RobotModel& r) { return has_analytic_ik(r); })
      .def_property_readonly(
          "frames",
          [](const RobotModel& r) {
            std::vector<std::string> names{"tcp", "flange", "wap"};
            for (int i = 0; i < r.dof(); ++i) names.push_back(fmt::format("joint{}", i + 1));
            return names;
          },
          "The frames fk() and jacobian() take: tcp, flange, wap and the moving frame of each joint (joint1.., "
          "also by the joint's name in the robot file).")
      .def_property_readonly("joint_names", [](const RobotModel& r) {
        std::vector<std::string> names;
        for (int i = 0; i < r.dof(); ++i) names.push_back(r.joint(i).name);
        return names;
      });
}

// Robot's stiffness copy, limits check, YAML and pickle.
void bind_model_robot_copies(py::class_<RobotModel, RobotHolder>& robot_class) {
  robot_class
      .def(
          "with_stiffness",
          [](const RobotModel& r, const ArrayLike& k, const std::string& note) {
            const Array a = vector_array(k, "stiffness_nm_per_rad", r.dof());
            return std::make_shared<RobotModel>(
                r.with_stiffness(std::vector<double>(a.data(), a.data() + a.size()), note));
          },
          "stiffness_nm_per_rad"_a, "note"_a = "given from Python", "A copy with another joint stiffness (Nm/rad).")
      .def(
          "within_limits",
          [](const RobotModel& r, const ArrayLike& q_obj, double tol) -> Returns<BoolOrArrayTag> {
            bool batch = false;
            const Array q = joint_rows(q_obj, "q", r.dof(), batch);
            if (!batch) return {py::bool_(r.within_limits(Eigen::Map<const Eigen::VectorXd>(q.data(), r.dof()), tol))};
            py::array_t<bool> out(q.shape(0));
            bool* o = out.mutable_data();
            for (py::ssize_t i = 0; i < q.shape(0); ++i) {
              o[i] = r.within_limits(Eigen::Map<const Eigen::VectorXd>(q.data() + i * r.dof(), r.dof()), tol);
            }
            return {out};
          },
          "q"_a, "tolerance_rad"_a = 1e-9,
          "True when every joint is inside its limits; a bool array for a batch (N, dof).")
      .def(
          "to_yaml", [](const RobotModel& r) { return robot_to_yaml(r); }, "deflex YAML of the robot (m, deg).")
      .def(py::pickle([](const RobotModel& r) { return py::make_tuple(robot_to_yaml(r), r.description().source); },
                      &robot_from_state));
}

// Robot's kinematics, deflection and compensation, batched.
void bind_model_robot_kinematics(py::class_<RobotModel, RobotHolder>& robot_class) {
  robot_class
      .def("fk", &fk, "q"_a, "point"_a = "tcp", "threads"_a = 0,
           "Pose of a frame in the base frame as a 4x4 homogeneous matrix (m): 'tcp' (default), 'flange', 'wap' or a "
           "joint's moving frame ('joint1'.., or its name; see .frames). q: (dof,) rad, or (N, dof) for a batch "
           "giving (N, 4, 4), spread over `threads` threads (0: every core).")
      .def("jacobian", &jacobian_of, "q"_a, "point"_a = "tcp", "threads"_a = 0,
           "Geometric Jacobian (6, dof) of a frame's origin (see fk), base frame, linear rows first (Pinocchio's "
           "LOCAL_WORLD_ALIGNED); (N, 6, dof) for a batch.")
      .def("deflect", &deflect, "q"_a, "wrench"_a, "complementary_stiffness"_a = false, "moment_about"_a = "wap",
           "threads"_a = 0,
           "Deflection under a wrench [N, Nm] (base frame, moment about the WAP, or the TCP with moment_about='tcp') "
           "at q (rad): (dof,) with (6,), or a batch (N, dof) with one wrench (6,) or one a row (N, 6).")
      .def(
          "cartesian_compliance",
          [](const RobotModel& r, const ArrayLike& q, int threads) {
            return batch_of(r, q, "q", {6, 6}, threads,
                            [&](Workspace& ws, std::ptrdiff_t, const JointVector& qi, double* out) {
                              Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> c(out);
                              c = cartesian_compliance(r, ws, qi);
                            });
          },
          "q"_a, "threads"_a = 0,
          "C = J_wap K^-1 J_wap^T (6x6): [m, rad] per [N, Nm], at the WAP; (N, 6, 6) for a batch (N, dof).")
      .def(
          "compensated_configuration",
          [](const RobotModel& r, const ArrayLike& q, const ArrayLike& w, const std::string& about, int threads) {
            return configurations_under(r, q, "q_desired", w, about, threads, false);
          },
          "q_desired"_a, "wrench"_a, "moment_about"_a = "wap", "threads"_a = 0,
          "q_desired - K^-1 J_wap(q_desired)^T W (rad): the exact command for a known wrench (moment about the WAP, or "
          "the TCP with moment_about='tcp'); (N, dof) for a batch with one wrench or one a row.")
      .def(
          "deflected_configuration",
          [](const RobotModel& r, const ArrayLike& q, const ArrayLike& w, const std::string& about, int threads) {
            return configurations_under(r, q, "q_command", w, about, threads, true);
          },
          "q_command"_a, "wrench"_a, "moment_about"_a = "wap", "threads"_a = 0,
          "The configuration (rad) the arm takes under the wrench when commanded to q_command (the moment moved from "
          "the TCP at q_command when moment_about='tcp'); (N, dof) for a batch.")
      .def("ik", &ik, "pose"_a, "seed"_a = py::none(),
           "Every solution (IkResult, joints in rad) of a TCP pose (4x4, m) inside the joint limits, every turn of "
           "each joint, the nearest the seed first ([0]: each joint at the turn nearest the seed); empty when there "
           "is none. Poses (N, 4, 4) give a list a pose (seed (dof,) or (N, dof)). Arms outside the analytic (OPW) "
           "family: the numerical solver's one solution.")
      .def("inverse_kinematics", &inverse_kinematics_of, "pose"_a, "configuration"_a = py::none(),
           "seed"_a = py::none(),
           "One solution chosen by ABB confdata and/or the seed, with its status and message (never raises for an "
           "unreachable pose: see status); a list for poses (N, 4, 4).")
      .def("__repr__", [](const RobotModel& r) {
        return fmt::format("<deflex.Robot '{}', {} joints, {}, from {}>", r.name(), r.dof(),
                           r.has_stiffness() ? "with stiffness" : "no stiffness", r.description().source);
      });
}

void bind_model_functions(py::module_& m) {
  m.def(
      "load_robot", [](const PathArg& path) { return std::make_shared<RobotModel>(load_robot(path_text(path))); },
      "path"_a, "Robot.from_file(path).");
  m.def(
      "pose",
      [](const ArrayLike& position, const ArrayLike& quaternion) {
        const Eigen::Quaterniond quat = unit_quaternion(quaternion, "quaternion_wxyz");
        Pose p = Pose::Identity();
        p.linear() = quat.toRotationMatrix();
        p.translation() = vector3(position, "position_m");
        return from_pose(p);
      },
      "position_m"_a, "quaternion_wxyz"_a,
      "A 4x4 homogeneous transform from a position (m) and a unit quaternion (w, x, y, z).");
}

}  // namespace

void bind_model(py::module_& m) {
  bind_model_result_types(m);
  py::class_<RobotModel, RobotHolder> robot_class(
      m, "Robot",
      "A validated, immutable robot (kinematics, joint limits, joint stiffness). Joints in rad, lengths in m, "
      "wrenches [Fx Fy Fz Mx My Mz] in N and Nm in the base frame with the moment about the WAP (moment_about='tcp' "
      "to give it about the TCP). Pickles (as its deflex YAML).");
  bind_model_robot_description(robot_class);
  bind_model_robot_copies(robot_class);
  bind_model_robot_kinematics(robot_class);
  bind_model_functions(m);
}

}  // namespace deflex::python
