// Paths (circle, line) with inverse kinematics along them, force models evaluated along a path,
// offline compensation of a path for one load or several (a spec string as `deflex offline --force`
// takes it, one wrench (6,) or one a point (N, 6), moment about the WAP unless moment_about="tcp"),
// its outputs (CSV, RAPID module, timed joint trajectories), and an existing RAPID or KRL program
// compensated target by target. The files are written as the program writes them.
#include <fmt/format.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/offline/offline_csv.hpp"
#include "deflex/offline/offline_job.hpp"
#include "deflex/offline/offline_summary.hpp"
#include "deflex/offline/program_compensation.hpp"
#include "deflex/offline/rapid_module.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

/// Wrenches given from Python (one, or one a path point), base frame, with their moment about the
/// WAP or the TCP; handed to the compensation as every ForceModel gives them, about the TCP (moved
/// from the WAP at each pose), which moves it back to the WAP exactly.
class ArrayWrenchModel final : public ForceModel {
 public:
  ArrayWrenchModel(std::vector<Wrench> wrenches, bool table, const Pose& tcp_T_wap, bool about_tcp)
      : wrenches_(std::move(wrenches)), table_(table), tcp_T_wap_(tcp_T_wap), about_tcp_(about_tcp) {}
  [[nodiscard]] Wrench wrench_at(std::size_t index, const Pose& base_T_tcp) const override {
    if (table_ && index >= wrenches_.size()) {
      throw InputError(
          fmt::format("force: the wrench array has {} rows, no row for path point {}", wrenches_.size(), index));
    }
    const Wrench& w = wrenches_[table_ ? index : 0];
    if (about_tcp_) return w;
    return moment_moved(w, (base_T_tcp * tcp_T_wap_).translation(), base_T_tcp.translation());
  }
  [[nodiscard]] std::string describe() const override {
    const char* about = about_tcp_ ? "TCP" : "WAP";
    if (!table_) {
      const Wrench& w = wrenches_.front();
      return fmt::format(
          "constant wrench F = ({:g}, {:g}, {:g}) N, M = ({:g}, {:g}, {:g}) Nm (base frame, moment about "
          "the {})",
          w[0], w[1], w[2], w[3], w[4], w[5], about);
    }
    return fmt::format("a wrench a point from a ({}, 6) array (N, Nm; base frame, moment about the {})",
                       wrenches_.size(), about);
  }
  [[nodiscard]] std::string label() const override { return table_ ? "array" : "constant"; }
  [[nodiscard]] std::optional<std::size_t> points() const override {
    return table_ ? std::optional<std::size_t>(wrenches_.size()) : std::nullopt;
  }

 private:
  std::vector<Wrench> wrenches_;
  bool table_;
  Pose tcp_T_wap_;
  bool about_tcp_;
};

Pose tcp_T_wap(const RobotModel& model) { return model.description().flange_T_tcp.inverse() * model.flange_T_wap(); }

/// The force models of one `force` argument: a spec string (several loads when it lists several
/// force_N values), or wrenches (6,) / (N, 6).
std::vector<std::unique_ptr<ForceModel>> force_models(const RobotModel& model, const py::handle& force,
                                                      const ForceSpecContext& context, const std::string& about) {
  const bool about_tcp = moment_about_tcp(about);
  std::vector<std::unique_ptr<ForceModel>> out;
  if (py::isinstance<py::str>(force)) {
    // A spec names its point itself: its moments are about the TCP (docs/offline.md), whatever `about` says.
    return parse_force_specs(force.cast<std::string>(), context);
  }
  bool table = false;
  const Array w = wrench_rows(force, "force", table);
  std::vector<Wrench> rows(static_cast<std::size_t>(table ? w.shape(0) : 1));
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = Eigen::Map<const Wrench>(w.data() + 6 * i);
  out.push_back(std::make_unique<ArrayWrenchModel>(std::move(rows), table, tcp_T_wap(model), about_tcp));
  return out;
}

IkRequest first_request(const RobotModel& model, const ConfigurationArg& configuration,
                        const std::optional<ArrayLike>& seed) {
  IkRequest first;
  first.configuration = arm_configuration_arg(configuration);
  if (seed && !seed->is_none()) first.seed = joint_vector(*seed, "seed", model.dof());
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

/// Every load of `force` compensated along the path: one OfflineResult each. With `list_is_loads`
/// a list or tuple is one load an item; otherwise a nested list is a wrench table (N, 6).
std::vector<OfflineResult> compensate_each(const RobotModel& model, const PathOrPoses& path, const ForceArg& force,
                                           const ConfigurationArg& configuration, const std::optional<ArrayLike>& seed,
                                           const ArrayLike& orientation, bool predict, const std::string& about,
                                           bool list_is_loads) {
  ForceSpecContext context;
  const std::vector<Pose> p = path_poses(path, orientation, context);
  std::vector<std::unique_ptr<ForceModel>> forces;
  if (list_is_loads && (py::isinstance<py::list>(force.obj) || py::isinstance<py::tuple>(force.obj))) {
    // A list of loads: spec strings or wrench arrays, one load each (a list of six numbers is one wrench).
    const py::sequence seq = force.obj;
    const bool one_wrench = seq.size() == 6 && (py::isinstance<py::float_>(seq[0]) || py::isinstance<py::int_>(seq[0]));
    if (!one_wrench) {
      for (const py::handle item : seq) {
        for (auto& f : force_models(model, item, context, about)) forces.push_back(std::move(f));
      }
    }
  }
  if (forces.empty()) forces = force_models(model, force, context, about);
  if (forces.empty()) throw InputError("argument force: no load given");
  // The job deflex offline runs (offline_job.hpp), every point kept.
  std::vector<OfflineLoad> loads;
  for (const auto& f : forces) loads.push_back({f.get(), nullptr, true});
  OfflineJobOptions options;
  options.compensation.predict = predict;
  options.first = first_request(model, configuration, seed);
  py::gil_scoped_release release;
  PoseListSource source(p);
  return run_offline_job(model, source, loads, options).loads;
}

RapidOptions rapid_options(const std::string& module, const std::string& motion, double speed_mm_s,
                           const std::string& zone, const std::string& tool, const std::string& wobj,
                           const std::string& note) {
  RapidOptions rapid;
  rapid.motion = parse_rapid_motion(motion, "argument motion");
  rapid.module_name = module;
  rapid.speed_mm_s = speed_mm_s;
  rapid.zone = zone;
  rapid.tool = tool;
  rapid.wobj = wobj;
  rapid.note = note;
  check_rapid_options(rapid);
  return rapid;
}

/// The compensated (or nominal) path timed at a TCP speed, as `deflex offline --joint-trajectory`.
JointTrajectory timed(const RobotModel& model, const OfflineResult& r, double speed_mm_s, double hold_start_s,
                      bool nominal) {
  if (r.points.empty()) throw InputError("the result holds no points");
  check_trajectory_speed(speed_mm_s, "argument speed_mm_s");
  std::vector<Pose> p;
  std::vector<JointVector> q;
  for (const OfflinePoint& pt : r.points) {
    p.push_back(pt.tcp_desired);
    q.push_back(nominal ? pt.q_desired : pt.q_command);
  }
  return trajectory_at_tcp_speed(p, q, speed_mm_s * 1e-3, model, hold_start_s);
}

py::tuple trajectory_arrays(const JointTrajectory& t) {
  return py::make_tuple(from_vector(t.times_s()), from_rows(t.points(), t.dof()));
}

JointTrajectory trajectory_from(const RobotModel& model, const ArrayLike& t_obj, const ArrayLike& q_obj) {
  const Array t = to_array(t_obj, "t_s", 1);
  require_finite(t, "t_s");
  bool batch = false;
  const Array q = joint_rows(q_obj, "q", model.dof(), batch);
  if (!batch || q.shape(0) != t.shape(0)) {
    throw InputError(fmt::format("argument q: expected shape ({}, {}) (one row a time), got {} rows", t.shape(0),
                                 model.dof(), batch ? q.shape(0) : 1));
  }
  std::vector<double> ts(t.data(), t.data() + t.size());
  std::vector<JointVector> qs;
  for (py::ssize_t i = 0; i < q.shape(0); ++i)
    qs.emplace_back(Eigen::Map<const Eigen::VectorXd>(q.data() + i * model.dof(), model.dof()));
  return JointTrajectory(std::move(ts), std::move(qs), model, "<arrays>");
}

py::dict program_dict(const RobotModel& model, const ProgramCompensation& result) {
  py::list targets;
  for (const ProgramTargetReport& t : result.targets) {
    py::dict d;
    d["file"] = t.file;
    d["line"] = t.line;
    d["instruction"] = t.instruction;
    d["target"] = t.target;
    d["action"] = t.action;
    d["configuration"] = t.configuration_note;
    d["deflection_m"] = t.deflection_m;
    d["deflection_rad"] = t.deflection_rad;
    d["correction_m"] = t.correction_m;
    d["joint_correction_rad"] = t.joint_correction_rad;
    d["wrench_base"] = from_vector(Eigen::VectorXd(t.wrench_base));
    targets.append(d);
  }
  py::list unresolved;
  for (const UnresolvedConstruct& u : result.unresolved) {
    unresolved.append(py::dict("file"_a = u.file, "line"_a = u.line, "text"_a = u.text, "reason"_a = u.reason));
  }
  py::list outputs;
  for (const ProgramFile& f : result.outputs) outputs.append(f.path);
  return py::dict("robot"_a = model.name(), "language"_a = result.language, "force"_a = result.force_description,
                  "targets"_a = targets, "unresolved"_a = unresolved, "outputs"_a = outputs,
                  "summary"_a = program_summary(result));
}

Array point_rows(const OfflineResult& r, JointVector OfflinePoint::*field) {
  return frozen(rows_of(r.points, field, dof_of(r)));
}

}  // namespace

namespace {

// Circle: a circular path, its poses and its pickle.
void bind_offline_circle(py::module_& m) {
  py::class_<CirclePath> circle(m, "Circle",
                                "A circle in the base frame (m): centre_m, radius_m, normal, start_angle_rad, "
                                "clockwise, points (closed: the last repeats the first). Circle() is `deflex offline "
                                "--circle default`; keywords change any field.");
  vector_property(circle, "centre_m", &CirclePath::centre_m);
  vector_property(circle, "normal", &CirclePath::normal);
  circle
      .def(py::init([](const std::optional<ArrayLike>& centre, std::optional<double> radius,
                       const std::optional<ArrayLike>& normal, std::optional<double> start,
                       std::optional<bool> clockwise, std::optional<int> points) {
             CirclePath c = default_circle();
             if (centre) c.centre_m = vector3(*centre, "centre_m");
             if (radius) c.radius_m = *radius;
             if (normal) c.normal = vector3(*normal, "normal");
             if (start) c.start_angle_rad = *start;
             if (clockwise) c.clockwise = *clockwise;
             if (points) c.points = *points;
             if (!(c.radius_m > 0.0) || !std::isfinite(c.radius_m)) {
               throw InputError(fmt::format("argument radius_m: must be positive (got {})", c.radius_m));
             }
             if (c.points < 3) throw InputError(fmt::format("argument points: at least 3 (got {})", c.points));
             if (!(c.normal.norm() > 1e-9)) throw InputError("argument normal: must not be zero");
             c.normal.normalize();
             return c;
           }),
           "centre_m"_a = py::none(), "radius_m"_a = py::none(), "normal"_a = py::none(),
           "start_angle_rad"_a = py::none(), "clockwise"_a = py::none(), "points"_a = py::none())
      .def_readwrite("radius_m", &CirclePath::radius_m)
      .def_readwrite("start_angle_rad", &CirclePath::start_angle_rad)
      .def_readwrite("clockwise", &CirclePath::clockwise)
      .def_readwrite("points", &CirclePath::points)
      .def(
          "poses",
          [](const CirclePath& c, const ArrayLike& orientation) {
            return from_poses(sample_circle(c, unit_quaternion(orientation, "orientation_wxyz")));
          },
          "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0}, "The TCP poses (points, 4, 4), m.")
      .def(py::pickle(
          [](const CirclePath& c) {
            return py::make_tuple(from_vector(c.centre_m), c.radius_m, from_vector(c.normal), c.start_angle_rad,
                                  c.clockwise, c.points);
          },
          [](const py::tuple& t) {
            CirclePath c = default_circle();
            c.centre_m = vector3(t[0], "centre_m");
            c.radius_m = t[1].cast<double>();
            c.normal = vector3(t[2], "normal");
            c.start_angle_rad = t[3].cast<double>();
            c.clockwise = t[4].cast<bool>();
            c.points = t[5].cast<int>();
            return c;
          }))
      .def("__repr__", [](const CirclePath& c) {
        return fmt::format(
            "Circle(centre_m=[{:g}, {:g}, {:g}], radius_m={:g}, normal=[{:g}, {:g}, {:g}], "
            "start_angle_rad={:g}, clockwise={}, points={})",
            c.centre_m.x(), c.centre_m.y(), c.centre_m.z(), c.radius_m, c.normal.x(), c.normal.y(), c.normal.z(),
            c.start_angle_rad, c.clockwise ? "True" : "False", c.points);
      });
}

// Paths as poses, their IK and the force along them.
void bind_offline_paths(py::module_& m) {
  m.def(
      "line_path",
      [](const ArrayLike& start, const ArrayLike& end, int points, const ArrayLike& orientation) {
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
      [](const RobotModel& model, const PathOrPoses& path, const ConfigurationArg& configuration,
         const std::optional<ArrayLike>& seed, const ArrayLike& orientation) {
        ForceSpecContext context;
        const std::vector<Pose> p = path_poses(path, orientation, context);
        const JointPath jp = solve_path_ik(model, p, first_request(model, configuration, seed));
        return py::make_tuple(from_rows(jp.q, model.dof()), configuration_tuple(jp.configuration));
      },
      "robot"_a, "path"_a, "configuration"_a = py::none(), "seed"_a = py::none(),
      "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0},
      "Joints (N, dof) rad along a path ((N, 4, 4) poses or a Circle) with one arm configuration kept, and that "
      "configuration (cf1, cf4, cf6, cfx). InputError names the path point.");

  m.def(
      "force_along_path",
      [](const RobotModel& model, const PathOrPoses& path, const ForceArg& force, const std::string& about,
         const ArrayLike& orientation) {
        ForceSpecContext context;
        const std::vector<Pose> p = path_poses(path, orientation, context);
        const bool about_tcp = moment_about_tcp(about);
        const Pose t_w = tcp_T_wap(model);
        py::list loads;
        for (const auto& f : force_models(model, force, context, about)) {
          Array w = new_array({static_cast<py::ssize_t>(p.size()), 6});
          Array length = new_array({static_cast<py::ssize_t>(p.size())});
          Array incline = new_array({static_cast<py::ssize_t>(p.size())});
          const auto* ldbb = dynamic_cast<const LdbbForceModel*>(f.get());
          for (std::size_t i = 0; i < p.size(); ++i) {
            Wrench wi = f->wrench_at(i, p[i]);  // moment about the TCP, as every force model gives it
            if (!about_tcp) wi = moment_moved(wi, p[i].translation(), (p[i] * t_w).translation());
            Eigen::Map<Wrench>(w.mutable_data() + 6 * i) = wi;
            length.mutable_data()[i] = ldbb != nullptr ? ldbb->bar_length_m(p[i]) : std::nan("");
            incline.mutable_data()[i] = ldbb != nullptr ? ldbb->inclination_rad(p[i]) : std::nan("");
          }
          if (f->points() && *f->points() != p.size()) {
            throw InputError(
                fmt::format("force: {} has {} points, the path {}", f->describe(), *f->points(), p.size()));
          }
          py::dict d("description"_a = f->describe(), "label"_a = f->label(), "wrench"_a = w,
                     "moment_about"_a = about_tcp ? "tcp" : "wap");
          d["bar_length_m"] = ldbb != nullptr ? py::object(length) : py::object(py::none());
          d["bar_inclination_rad"] = ldbb != nullptr ? py::object(incline) : py::object(py::none());
          loads.append(d);
        }
        return loads;
      },
      "robot"_a, "path"_a, "force"_a, "moment_about"_a = "wap",
      "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0},
      "The force model evaluated at every path pose, one dict a load (a spec with several force_N values gives "
      "several): `wrench` (N, 6) N, Nm in the base frame with the moment about the WAP (or the TCP), `description`, "
      "`label`, and for an LDBB the bar's `bar_length_m` and `bar_inclination_rad` (to the base XY plane) a point.");
}

// OfflineResult's arrays and figures.
void bind_offline_result_arrays(py::class_<OfflineResult>& offline_result) {
  offline_result
      .def_property_readonly(
          "q_desired", [](const OfflineResult& r) { return point_rows(r, &OfflinePoint::q_desired); },
          "(N, dof) rad, from the path's IK")
      .def_property_readonly(
          "q_command", [](const OfflineResult& r) { return point_rows(r, &OfflinePoint::q_command); },
          "(N, dof) rad: q_desired - K^-1 J_wap(q_desired)^T W")
      .def_property_readonly(
          "tcp_desired", [](const OfflineResult& r) { return frozen(poses_of(r.points, &OfflinePoint::tcp_desired)); },
          "(N, 4, 4) m")
      .def_property_readonly(
          "tcp_command", [](const OfflineResult& r) { return frozen(poses_of(r.points, &OfflinePoint::tcp_command)); },
          "(N, 4, 4) m: FK(q_command)")
      .def_property_readonly(
          "wrench", [](const OfflineResult& r) { return frozen(rows_of(r.points, &OfflinePoint::wrench_base, 6)); },
          "(N, 6) N, Nm: base frame, moment about the WAP (see moment_about)")
      .def_property_readonly(
          "moment_about", [](const OfflineResult&) { return "wap"; },
          "Where the moments of `wrench` are taken: always the WAP (the TCP unless the robot file "
          "puts it elsewhere).")
      .def_property_readonly(
          "predicted_deflection",
          [](const OfflineResult& r) { return frozen(rows_of(r.points, &OfflinePoint::predicted_deflection, 6)); },
          "(N, 6) [m, rad]: uncompensated TCP displacement under the load")
      .def_property_readonly(
          "predicted_residual",
          [](const OfflineResult& r) { return frozen(rows_of(r.points, &OfflinePoint::predicted_residual, 6)); },
          "(N, 6) [m, rad]: after compensation (a check of the exact form)")
      .def_readonly("max_deflection_m", &OfflineResult::max_deflection_m)
      .def_readonly("mean_deflection_m", &OfflineResult::mean_deflection_m)
      .def_readonly("max_deflection_rad", &OfflineResult::max_deflection_rad)
      .def_readonly("max_residual_m", &OfflineResult::max_residual_m)
      .def_readonly("max_residual_rad", &OfflineResult::max_residual_rad)
      .def_readonly("max_correction_m", &OfflineResult::max_correction_m)
      .def_readonly("max_joint_correction_rad", &OfflineResult::max_joint_correction_rad)
      .def_readonly("force_description", &OfflineResult::force_description);
}

// OfflineResult's summary, CSV, RAPID and joint trajectories.
void bind_offline_result_outputs(py::class_<OfflineResult>& offline_result) {
  offline_result
      .def(
          "summary", [](const OfflineResult& r) { return offline_summary(r); }, "The summary `deflex offline` prints.")
      .def(
          "write_csv", [](const OfflineResult& r, const PathArg& path) { write_offline_csv(r, path_text(path)); },
          "path"_a, "The CSV `deflex offline -o` writes.")
      .def(
          "rapid_module",
          [](const OfflineResult& r, const std::string& module, const std::string& motion, double speed_mm_s,
             const std::string& zone, const std::string& tool, const std::string& wobj, const std::string& note) {
            return rapid_module(r, rapid_options(module, motion, speed_mm_s, zone, tool, wobj, note));
          },
          "module"_a = "DeflexOffline", "motion"_a = "absj", "speed_mm_s"_a = 10.0, "zone"_a = "fine",
          "tool"_a = "tool0", "wobj"_a = "wobj0", "note"_a = "",
          "The ABB RAPID module `deflex offline --rapid` writes (absj: MoveAbsJ over the compensated joints; movel: "
          "MoveL over robtargets with confdata), as text.")
      .def(
          "write_rapid",
          [](const OfflineResult& r, const PathArg& path, const std::string& module, const std::string& motion,
             double speed_mm_s, const std::string& zone, const std::string& tool, const std::string& wobj,
             const std::string& note) {
            write_rapid_module(r, rapid_options(module, motion, speed_mm_s, zone, tool, wobj, note), path_text(path));
          },
          "path"_a, "module"_a = "DeflexOffline", "motion"_a = "absj", "speed_mm_s"_a = 10.0, "zone"_a = "fine",
          "tool"_a = "tool0", "wobj"_a = "wobj0", "note"_a = "",
          "rapid_module() written to a file of its own (all or nothing, never over a file on failure).")
      .def(
          "joint_trajectory",
          [](const OfflineResult& r, const RobotModel& model, double speed_mm_s, double hold_start_s, bool nominal) {
            return trajectory_arrays(timed(model, r, speed_mm_s, hold_start_s, nominal));
          },
          "robot"_a, "speed_mm_s"_a = 10.0, "hold_start_s"_a = 0.0, "nominal"_a = false,
          "The compensated path (nominal=True: the uncompensated one) timed at a TCP speed (mm/s): (t_s (N,), q_rad "
          "(N, dof)), as `deflex offline --joint-trajectory` (--nominal-trajectory) writes it, checked against the "
          "robot's joint limits and speeds.")
      .def(
          "write_joint_trajectory",
          [](const OfflineResult& r, const PathArg& path, const RobotModel& model, double speed_mm_s,
             double hold_start_s, bool nominal, const std::string& comment) {
            timed(model, r, speed_mm_s, hold_start_s, nominal).write_csv(path_text(path), comment);
          },
          "path"_a, "robot"_a, "speed_mm_s"_a = 10.0, "hold_start_s"_a = 0.0, "nominal"_a = false, "comment"_a = "",
          "joint_trajectory() as the CSV `t_s,q1_deg,...` deflex online --program reads.");
}

// OfflineResult's pickle and repr.
void bind_offline_result_pickle(py::class_<OfflineResult>& offline_result) {
  offline_result
      .def(py::pickle(
          [](const OfflineResult& r) {
            py::list points;
            for (const OfflinePoint& p : r.points) {
              points.append(py::make_tuple(from_vector(p.q_desired), from_vector(p.q_command), from_pose(p.tcp_desired),
                                           from_pose(p.tcp_command), configuration_tuple(p.configuration_command),
                                           from_vector(Eigen::VectorXd(p.wrench_base)),
                                           from_vector(Eigen::VectorXd(p.predicted_deflection)),
                                           from_vector(Eigen::VectorXd(p.predicted_residual))));
            }
            return py::make_tuple(points, r.point_count, r.max_deflection_m, r.mean_deflection_m, r.max_deflection_rad,
                                  r.max_residual_m, r.max_residual_rad, r.max_correction_m, r.max_joint_correction_rad,
                                  r.robot_name, r.stiffness_note, r.force_description, r.predicted);
          },
          [](const py::tuple& t) {
            if (t.size() != 13) throw InputError("deflex.OfflineResult: not a pickled OfflineResult");
            OfflineResult r;
            for (const py::handle item : t[0].cast<py::list>()) {
              const auto p = item.cast<py::tuple>();
              OfflinePoint pt;
              const Array qd = p[0].cast<Array>(), qc = p[1].cast<Array>();
              pt.q_desired = Eigen::Map<const Eigen::VectorXd>(qd.data(), qd.size());
              pt.q_command = Eigen::Map<const Eigen::VectorXd>(qc.data(), qc.size());
              pt.tcp_desired = pose(p[2], "tcp_desired");
              pt.tcp_command = pose(p[3], "tcp_command");
              pt.configuration_command = *arm_configuration_arg(p[4]);
              pt.wrench_base = vector6(p[5], "wrench");
              pt.predicted_deflection = vector6(p[6], "predicted_deflection");
              pt.predicted_residual = vector6(p[7], "predicted_residual");
              r.points.push_back(std::move(pt));
            }
            r.point_count = t[1].cast<std::size_t>();
            r.max_deflection_m = t[2].cast<double>();
            r.mean_deflection_m = t[3].cast<double>();
            r.max_deflection_rad = t[4].cast<double>();
            r.max_residual_m = t[5].cast<double>();
            r.max_residual_rad = t[6].cast<double>();
            r.max_correction_m = t[7].cast<double>();
            r.max_joint_correction_rad = t[8].cast<double>();
            r.robot_name = t[9].cast<std::string>();
            r.stiffness_note = t[10].cast<std::string>();
            r.force_description = t[11].cast<std::string>();
            r.predicted = t[12].cast<bool>();
            return r;
          }))
      .def("__repr__", [](const OfflineResult& r) {
        return fmt::format(
            "<deflex.OfflineResult {} points, force: {}, max deflection {:.4f} mm, max residual {:.2e} mm>",
            r.point_count, r.force_description, r.max_deflection_m * 1e3, r.max_residual_m * 1e3);
      });
}

// Offline compensation of a path for one or several loads.
void bind_offline_compensate(py::module_& m) {
  m.def(
      "compensate_path",
      [](const RobotModel& model, const PathOrPoses& path, const ForceArg& force, const ConfigurationArg& configuration,
         const std::optional<ArrayLike>& seed, const ArrayLike& orientation, bool predict, const std::string& about) {
        std::vector<OfflineResult> all =
            compensate_each(model, path, force, configuration, seed, orientation, predict, about, false);
        if (all.size() != 1) {
          throw InputError(
              fmt::format("argument force: describes {} loads; compensate_path takes one (compensate_loads "
                          "gives one result a load)",
                          all.size()));
        }
        return std::move(all.front());
      },
      "robot"_a, "path"_a, "force"_a, "configuration"_a = py::none(), "seed"_a = py::none(),
      "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0}, "predict"_a = true, "moment_about"_a = "wap",
      "Offline compensation (paper, Figure 2) of a path ((N, 4, 4) TCP poses in m, or a Circle sampled with "
      "orientation_wxyz) for one load: a spec string as `deflex offline --force` takes it (e.g. "
      "'ldbb:phi_deg=30,force_N=400' with a Circle, 'constant:fz_N=-500'; a spec's moments are about the TCP), or one "
      "wrench (6,) or one a point (N, 6) (N, Nm; base frame, moment about the WAP, or the TCP with "
      "moment_about='tcp').");
  m.def(
      "compensate_loads",
      [](const RobotModel& model, const PathOrPoses& path, const ForceArg& force, const ConfigurationArg& configuration,
         const std::optional<ArrayLike>& seed, const ArrayLike& orientation, bool predict, const std::string& about) {
        return compensate_each(model, path, force, configuration, seed, orientation, predict, about, true);
      },
      "robot"_a, "path"_a, "force"_a, "configuration"_a = py::none(), "seed"_a = py::none(),
      "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0}, "predict"_a = true, "moment_about"_a = "wap",
      "compensate_path for several loads on one path (one IK): a spec with several force_N values "
      "('ldbb:phi_deg=30,force_N=125;325;650'), or a list of specs and wrench arrays; one OfflineResult a load, in "
      "order, as `deflex offline` with several --force options.");
}

// Offline compensation of an existing robot program.
void bind_offline_program(py::module_& m) {
  m.def(
      "compensate_program",
      [](const RobotModel& model, const ForceArg& force, const PathArg& program_in, const PathArg& program_out,
         const std::vector<std::string>& tooldata, const std::vector<std::string>& wobjdata, bool write) {
        std::vector<std::unique_ptr<ForceModel>> forces = force_models(model, force, {}, "tcp");
        if (forces.size() != 1) {
          throw InputError(
              fmt::format("argument force: a program is compensated for one load; it describes {}", forces.size()));
        }
        ProgramOptions options;
        options.tooldata = tooldata;
        options.wobjdata = wobjdata;
        ProgramCompensation result;
        {
          py::gil_scoped_release release;
          result = compensate_program(model, *forces.front(), path_text(program_in), path_text(program_out), options);
          if (write) write_program_outputs(result);  // all files or none
        }
        py::dict d = program_dict(model, result);
        py::dict texts;
        for (const ProgramFile& f : result.outputs) texts[py::str(f.path)] = f.text;
        d["texts"] = texts;
        return d;
      },
      "robot"_a, "force"_a, "program_in"_a, "program_out"_a, "tooldata"_a = std::vector<std::string>{},
      "wobjdata"_a = std::vector<std::string>{}, "write"_a = true,
      "An existing ABB RAPID module (.mod, .modx, .prg, .sys) or KUKA KRL program (.src with its .dat) compensated "
      "target by target, as `deflex offline --program-in ... --program-out ...`: every other byte kept; the input is "
      "never overwritten. force: one load (spec or wrench about the TCP). Returns the dict of that command's --json "
      "in SI units (targets with deflection_m, correction_m, joint_correction_rad, ...; unresolved; outputs), the "
      "summary text and the output texts; write=False writes nothing.");
}

// Timed joint trajectory files.
void bind_offline_trajectory_files(py::module_& m) {
  m.def(
      "read_joint_trajectory",
      [](const PathArg& path, const RobotModel& model) {
        return trajectory_arrays(JointTrajectory::read_csv(path_text(path), model));
      },
      "path"_a, "robot"_a,
      "A timed joint trajectory CSV `t_s,q1_deg,...` (deflex online --program) as (t_s (N,), q_rad (N, dof)), checked "
      "against the robot (times increasing, limits, joint speeds); errors name the file and line.");
  m.def(
      "write_joint_trajectory",
      [](const PathArg& path, const RobotModel& model, const ArrayLike& t, const ArrayLike& q,
         const std::string& comment) { trajectory_from(model, t, q).write_csv(path_text(path), comment); },
      "path"_a, "robot"_a, "t_s"_a, "q"_a, "comment"_a = "",
      "Times (s) and joints (N, dof) rad written as the CSV deflex online --program reads (deg), checked as it reads "
      "them; all or nothing.");
}

}  // namespace

void bind_offline(py::module_& m) {
  bind_offline_circle(m);
  bind_offline_paths(m);
  py::class_<OfflineResult> offline_result(m, "OfflineResult", "A compensated path: one row a point (rad, m, N, Nm).");
  bind_offline_result_arrays(offline_result);
  bind_offline_result_outputs(offline_result);
  bind_offline_result_pickle(offline_result);
  bind_offline_compensate(m);
  bind_offline_program(m);
  bind_offline_trajectory_files(m);
}

}  // namespace deflex::python
