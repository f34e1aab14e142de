// Stiffness identification (from arrays or the measurement CSV) and calibration planning.
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/identify/calibration_planner.hpp"
#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/identify/stiffness_measurements.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

/// Measurements from arrays: q (m, dof) rad, wrench (m, 6) N/Nm, dp (m, 3) m, optional drot (m, 3)
/// rad and weight (m,).
std::vector<StiffnessMeasurement> measurements_from_arrays(const RobotModel& model, const py::handle& q_obj,
                                                           const py::handle& w_obj, const py::handle& dp_obj,
                                                           const py::handle& drot_obj, const py::handle& weight_obj) {
  const Array q = matrix_array(q_obj, "q", -1, model.dof());
  const py::ssize_t n = q.shape(0);
  const Array w = matrix_array(w_obj, "wrench", n, 6);
  const Array dp = matrix_array(dp_obj, "dp", n, 3);
  const bool has_rot = !drot_obj.is_none(), has_weight = !weight_obj.is_none();
  const Array drot = has_rot ? matrix_array(drot_obj, "drot", n, 3) : Array();
  const Array weight = has_weight ? vector_array(weight_obj, "weight", n) : Array();
  // The ranges of the measurement file's columns (q_deg, fx_N, dx_mm ...), in SI here.
  require_in_ranges(q, "q", {&range::kAngleRad});
  require_in_ranges(
      w, "wrench",
      {&range::kForceN, &range::kForceN, &range::kForceN, &range::kMomentNm, &range::kMomentNm, &range::kMomentNm});
  require_in_ranges(dp, "dp", {&range::kLengthM});
  if (has_rot) require_in_ranges(drot, "drot", {&range::kAngleRad});
  if (has_weight) require_in_ranges(weight, "weight", {&range::kWeight});
  std::vector<StiffnessMeasurement> data(static_cast<std::size_t>(n));
  for (py::ssize_t i = 0; i < n; ++i) {
    auto& d = data[static_cast<std::size_t>(i)];
    d.q = Eigen::Map<const Eigen::VectorXd>(q.data() + i * model.dof(), model.dof());
    d.wrench_base = Eigen::Map<const Wrench>(w.data() + 6 * i);
    d.dp_m = Eigen::Map<const Vector3>(dp.data() + 3 * i);
    if (has_rot) d.drot_rad = Eigen::Map<const Vector3>(drot.data() + 3 * i);
    if (has_weight) d.weight = weight.data()[i];
  }
  return data;
}

py::dict measurements_to_dict(const std::vector<StiffnessMeasurement>& data) {
  const py::ssize_t dof = data.empty() ? 0 : data.front().q.size();
  std::vector<Vector3> drot;
  std::vector<double> weight;
  std::vector<int> line;
  bool all_rot = !data.empty();
  for (const auto& d : data) {
    all_rot = all_rot && d.drot_rad.has_value();
    drot.push_back(d.drot_rad.value_or(Vector3::Zero()));
    weight.push_back(d.weight);
    line.push_back(d.line);
  }
  py::dict out("q"_a = rows_of(data, &StiffnessMeasurement::q, dof),
               "wrench"_a = rows_of(data, &StiffnessMeasurement::wrench_base, 6),
               "dp"_a = rows_of(data, &StiffnessMeasurement::dp_m, 3), "weight"_a = from_vector(weight),
               "line"_a = line);
  out["drot"] = all_rot ? py::object(from_rows(drot, 3)) : py::none();
  return out;
}

int plan_dof(const CalibrationPlan& p) { return p.points.empty() ? 0 : static_cast<int>(p.points.front().q.size()); }

/// A plan as plain Python values (pickling): its rows, then the figures.
py::tuple plan_state(const CalibrationPlan& p) {
  py::list rows;
  for (const CalibrationPoint& c : p.points) {
    rows.append(py::make_tuple(c.pose, from_vector(c.q), from_pose(c.base_T_tcp), from_vector(c.wrench_base),
                               from_vector(c.load_point_base), from_vector(c.expected_dp_m)));
  }
  return py::make_tuple(rows, p.min_singular_value_m, p.condition_number, p.predicted_relative_std_error,
                        p.candidate_poses, p.reachable_poses, p.warnings);
}

CalibrationPlan plan_from_state(const py::tuple& t) {
  if (t.size() != 7) throw InputError("deflex.CalibrationPlan: not a pickled CalibrationPlan");
  CalibrationPlan p;
  for (const py::handle row : t[0].cast<py::list>()) {
    const auto r = row.cast<py::tuple>();
    CalibrationPoint c;
    c.pose = r[0].cast<int>();
    const Array q = to_array(r[1], "q", 1);
    c.q = Eigen::Map<const Eigen::VectorXd>(q.data(), q.shape(0));
    c.base_T_tcp = pose(r[2], "base_T_tcp");
    c.wrench_base = vector6(r[3], "wrench");
    c.load_point_base = vector3(r[4], "load_point");
    c.expected_dp_m = vector3(r[5], "expected_dp");
    p.points.push_back(c);
  }
  p.min_singular_value_m = t[1].cast<double>();
  p.condition_number = t[2].cast<double>();
  p.predicted_relative_std_error = t[3].cast<std::vector<double>>();
  p.candidate_poses = t[4].cast<int>();
  p.reachable_poses = t[5].cast<int>();
  p.warnings = t[6].cast<std::vector<std::string>>();
  return p;
}

}  // namespace

namespace {

// StiffnessEstimate: the identified stiffness, its errors and its pickle.
void bind_identify_estimate(py::module_& m) {
  py::class_<StiffnessEstimate>(m, "StiffnessEstimate",
                                "Identified joint stiffness (Nm/rad) with standard errors and identifiability flags.")
      .def_property_readonly("stiffness_nm_per_rad",
                             [](const StiffnessEstimate& e) { return frozen(from_vector(e.stiffness_nm_per_rad)); })
      .def_property_readonly("std_error_nm_per_rad",
                             [](const StiffnessEstimate& e) { return frozen(from_vector(e.std_error_nm_per_rad)); })
      .def_property_readonly("compliance_rad_per_nm",
                             [](const StiffnessEstimate& e) { return frozen(from_vector(e.compliance_rad_per_nm)); })
      .def_property_readonly(
          "compliance_std_error_rad_per_nm",
          [](const StiffnessEstimate& e) { return frozen(from_vector(e.compliance_std_error_rad_per_nm)); })
      .def_readonly("residual_rms_m", &StiffnessEstimate::residual_rms_m)
      .def_readonly("residual_max_m", &StiffnessEstimate::residual_max_m)
      .def_readonly("residual_rms_rad", &StiffnessEstimate::residual_rms_rad)
      .def_readonly("sigma_m", &StiffnessEstimate::sigma_m)
      .def_readonly("condition_number", &StiffnessEstimate::condition_number)
      .def_readonly("unidentifiable_joints", &StiffnessEstimate::unidentifiable_joints, "1-based joint numbers")
      .def_readonly("fixed_joints", &StiffnessEstimate::fixed_joints, "1-based joint numbers")
      .def_property_readonly("warnings", [](const StiffnessEstimate& e) { return python_messages(e.warnings); })
      .def_property_readonly("robust_weights",
                             [](const StiffnessEstimate& e) { return frozen(from_vector(e.robust_weights)); })
      .def_readonly("rejected_measurements", &StiffnessEstimate::rejected_measurements, "0-based indices")
      .def_readonly("measurements", &StiffnessEstimate::measurements)
      .def_readonly("iterations", &StiffnessEstimate::iterations)
      .def(py::pickle(
          [](const StiffnessEstimate& e) {
            return py::make_tuple(
                e.stiffness_nm_per_rad, e.std_error_nm_per_rad, e.compliance_rad_per_nm,
                e.compliance_std_error_rad_per_nm,
                py::make_tuple(e.residual_rms_m, e.residual_max_m, e.residual_rms_rad, e.sigma_m, e.condition_number),
                e.unidentifiable_joints, e.fixed_joints, e.warnings, e.robust_weights, e.rejected_measurements,
                e.rejected_lines, e.measurements, e.iterations);
          },
          [](const py::tuple& t) {
            if (t.size() != 13) throw InputError("deflex.StiffnessEstimate: not a pickled StiffnessEstimate");
            StiffnessEstimate e;
            e.stiffness_nm_per_rad = t[0].cast<std::vector<double>>();
            e.std_error_nm_per_rad = t[1].cast<std::vector<double>>();
            e.compliance_rad_per_nm = t[2].cast<std::vector<double>>();
            e.compliance_std_error_rad_per_nm = t[3].cast<std::vector<double>>();
            const auto f = t[4].cast<py::tuple>();
            e.residual_rms_m = f[0].cast<double>();
            e.residual_max_m = f[1].cast<double>();
            e.residual_rms_rad = f[2].cast<double>();
            e.sigma_m = f[3].cast<double>();
            e.condition_number = f[4].cast<double>();
            e.unidentifiable_joints = t[5].cast<std::vector<int>>();
            e.fixed_joints = t[6].cast<std::vector<int>>();
            e.warnings = t[7].cast<std::vector<std::string>>();
            e.robust_weights = t[8].cast<std::vector<double>>();
            e.rejected_measurements = t[9].cast<std::vector<int>>();
            e.rejected_lines = t[10].cast<std::vector<int>>();
            e.measurements = t[11].cast<int>();
            e.iterations = t[12].cast<int>();
            return e;
          }))
      .def("__repr__", [](const StiffnessEstimate& e) {
        std::string s =
            fmt::format("StiffnessEstimate(stiffness_nm_per_rad={}, condition_number={:.3g}",
                        py::repr(from_vector(e.stiffness_nm_per_rad)).cast<std::string>(), e.condition_number);
        std::vector<int> nan, poor;
        for (const int j : e.unidentifiable_joints) {
          (std::isnan(e.stiffness_nm_per_rad[j - 1]) ? nan : poor).push_back(j);
        }
        if (!nan.empty()) s += fmt::format(", not identified (NaN): joints {}", fmt::join(nan, ", "));
        if (!poor.empty())
          s += fmt::format(", poorly identified (shown, not to be used): joints {}", fmt::join(poor, ", "));
        return s + fmt::format(", {} warnings)", e.warnings.size());
      });
}

// Measurements and the stiffness fit.
void bind_identify_stiffness(py::module_& m) {
  m.def(
      "read_stiffness_measurements",
      [](const PathArg& path) { return measurements_to_dict(read_stiffness_measurements(path_text(path))); }, "path"_a,
      "The measurement CSV (docs/identify.md) as arrays in SI units: q (m, dof) rad, wrench (m, 6) N/Nm, dp (m, 3) "
      "m, drot (m, 3) rad or None, weight (m,), line (file line of each row).");

  m.def(
      "identify_stiffness",
      [](const RobotModel& model, const DataArg& q_or_path, const std::optional<ArrayLike>& wrench_pos,
         const std::optional<ArrayLike>& dp_pos, const std::optional<ArrayLike>& drot,
         const std::optional<ArrayLike>& weight, const OptionalFloats& fixed, bool robust, double rotation_scale_m,
         double max_relative_std_error, const DataArg& csv_path, const DataArg& data) {
        std::vector<StiffnessMeasurement> measurements;
        const auto given = [](const std::optional<ArrayLike>& a) { return a && !a->is_none(); };
        // The measurements: the second positional argument (q's place: arrays or a CSV path), csv_path=,
        // or data= (either), one of them.
        const int places = static_cast<int>(!q_or_path.is_none()) + static_cast<int>(!csv_path.is_none()) +
                           static_cast<int>(!data.is_none());
        if (places > 1) {
          throw InputError("identify_stiffness: the measurements given twice (give q, csv_path or data, one of them)");
        }
        const py::object first = !q_or_path.is_none() ? q_or_path.obj : !csv_path.is_none() ? csv_path.obj : data.obj;
        const bool is_file = py::isinstance<py::str>(first) || py::hasattr(first, "__fspath__");
        if (is_file) {
          if (given(wrench_pos) || given(dp_pos)) {
            throw InputError(
                "identify_stiffness: give either the measurement CSV's path or the arrays q, wrench, dp, not both");
          }
          measurements = read_stiffness_measurements(first.cast<PathArg>().string());
        } else {
          if (!csv_path.is_none()) throw InputError("argument csv_path: a str or os.PathLike, not arrays");
          const py::object none = py::none();
          const py::object& q = first;
          const py::object w = given(wrench_pos) ? wrench_pos->obj : none;
          const py::object dp = given(dp_pos) ? dp_pos->obj : none;
          if (q.is_none() || w.is_none() || dp.is_none()) {
            throw InputError(
                "identify_stiffness: give the measurement CSV's path, or the arrays q (m, dof) rad, wrench "
                "(m, 6) N/Nm and dp (m, 3) m");
          }
          measurements = measurements_from_arrays(model, q, w, dp, given(drot) ? drot->obj : none,
                                                  given(weight) ? weight->obj : none);
        }
        IdentificationOptions options;
        options.robust = robust;
        options.rotation_scale_m = rotation_scale_m;
        options.max_relative_std_error = max_relative_std_error;
        if (!fixed.is_none()) {
          try {
            options.fixed_stiffness_nm_per_rad = fixed.obj.cast<std::vector<std::optional<double>>>();
          } catch (const py::cast_error&) {
            throw InputError("argument fixed_stiffness_nm_per_rad: one entry a joint, a number (Nm/rad) or None");
          }
        }
        py::gil_scoped_release release;
        return identify_stiffness(model, measurements, options);
      },
      "robot"_a, "q"_a = py::none(), "wrench"_a = py::none(), "dp"_a = py::none(), "drot"_a = py::none(),
      "weight"_a = py::none(), "fixed_stiffness_nm_per_rad"_a = py::none(), "robust"_a = true,
      "rotation_scale_m"_a = 1.0, "max_relative_std_error"_a = 0.5, py::kw_only(), "csv_path"_a = py::none(),
      "data"_a = py::none(),
      "Joint stiffness from measured TCP deflections: the measurement CSV's path (str or os.PathLike: "
      "identify_stiffness(robot, csv_path) or csv_path=), or the arrays q (m, dof) rad, wrench (m, 6) N/Nm (base "
      "frame, moment about the WAP) and dp (m, 3) m, positionally (robot, q, wrench, dp, drot, weight) or by keyword; "
      "optional drot (m, 3) rad and weight (m,). fixed_stiffness_nm_per_rad: one entry a joint, a value to hold or "
      "None to estimate. data= takes either form.");
}

void bind_identify_robot(py::module_& m) {
  m.def(
      "identified_robot",
      [](const RobotModel& model, const StiffnessEstimate& estimate, const std::string& data_name) {
        return std::make_shared<RobotModel>(identified_robot(model, estimate, data_name));
      },
      "robot"_a, "estimate"_a, "data_name"_a = "<arrays>",
      "The robot with its identified stiffness, as `deflex identify --write-robot` writes it: a joint the estimate "
      "did not identify keeps the robot file's value (the note says which); InputError when it has none to keep.");
}

// Planning a calibration: CalibrationPlan and plan_calibration.
void bind_identify_plan(py::module_& m) {
  py::class_<CalibrationPlan>(m, "CalibrationPlan", "Poses and loads of a compliance-calibration experiment.")
      .def_property_readonly(
          "pose",
          [](const CalibrationPlan& p) {
            std::vector<int> v;
            for (const auto& c : p.points) v.push_back(c.pose);
            return v;
          },
          "1-based pose number of each row")
      .def_property_readonly(
          "q", [](const CalibrationPlan& p) { return frozen(rows_of(p.points, &CalibrationPoint::q, plan_dof(p))); },
          "(rows, dof) rad")
      .def_property_readonly(
          "base_T_tcp",
          [](const CalibrationPlan& p) { return frozen(poses_of(p.points, &CalibrationPoint::base_T_tcp)); },
          "(rows, 4, 4), m")
      .def_property_readonly(
          "wrench",
          [](const CalibrationPlan& p) { return frozen(rows_of(p.points, &CalibrationPoint::wrench_base, 6)); },
          "(rows, 6) N, Nm at the WAP, base frame")
      .def_property_readonly(
          "load_point",
          [](const CalibrationPlan& p) { return frozen(rows_of(p.points, &CalibrationPoint::load_point_base, 3)); },
          "(rows, 3) m, where the force acts")
      .def_property_readonly(
          "expected_dp",
          [](const CalibrationPlan& p) { return frozen(rows_of(p.points, &CalibrationPoint::expected_dp_m, 3)); },
          "(rows, 3) m, first-order deflection with the robot file's stiffness")
      .def_readonly("min_singular_value_m", &CalibrationPlan::min_singular_value_m)
      .def_readonly("condition_number", &CalibrationPlan::condition_number)
      .def_property_readonly(
          "predicted_relative_std_error",
          [](const CalibrationPlan& p) { return frozen(from_vector(p.predicted_relative_std_error)); })
      .def_readonly("candidate_poses", &CalibrationPlan::candidate_poses)
      .def_readonly("reachable_poses", &CalibrationPlan::reachable_poses)
      .def_property_readonly("warnings", [](const CalibrationPlan& p) { return python_messages(p.warnings); })
      .def(
          "write_csv",
          [](const CalibrationPlan& p, const PathArg& path) { write_calibration_plan(path_text(path), p); }, "path"_a,
          "The plan as the operator's CSV (the same as deflex plan-calibration -o).")
      .def(py::pickle(&plan_state, &plan_from_state));

  m.def(
      "plan_calibration",
      [](const RobotModel& model, const ArrayLike& region_min, const ArrayLike& region_max, double load_n, int poses,
         int loads_per_pose, double lever_m, const ArrayLike& orientation, int grid_per_axis, double noise_m) {
        CalibrationPlanOptions o;
        o.region_min_m = vector3(region_min, "region_min_m");
        o.region_max_m = vector3(region_max, "region_max_m");
        o.load_n = load_n;
        o.poses = poses;
        o.loads_per_pose = loads_per_pose;
        o.lever_m = lever_m;
        o.orientation = unit_quaternion(orientation, "orientation_wxyz");
        o.grid_per_axis = grid_per_axis;
        o.noise_m = noise_m;
        py::gil_scoped_release release;
        return plan_calibration(model, o);
      },
      "robot"_a, "region_min_m"_a, "region_max_m"_a, "load_n"_a = 500.0, "poses"_a = 12, "loads_per_pose"_a = 2,
      "lever_m"_a = 0.25, "orientation_wxyz"_a = std::vector<double>{0.0, 0.0, 1.0, 0.0}, "grid_per_axis"_a = 4,
      "noise_m"_a = 10e-6,
      "Chooses calibration poses and loads in a box of TCP positions (m, base frame) so that every joint's "
      "compliance is observable; load in N, lever and noise in m.");
}

}  // namespace

void bind_identify(py::module_& m) {
  bind_identify_estimate(m);
  bind_identify_stiffness(m);
  bind_identify_robot(m);
  bind_identify_plan(m);
}

}  // namespace deflex::python
