// The online compensator's step() for loops a user runs in Python: push raw sensor samples, then one
// step a cycle. The sensor configuration (conditioning) and the compensator's bounds as plain
// classes with the C++ field names.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/identify/payload_identification.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/online/online_compensator.hpp"
#include "deflex/online/sensor_config.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

/// A sensor configuration as plain Python values (pickling), every field.
py::tuple sensor_state(const SensorConfig& s) {
  return py::make_tuple(s.name, s.source, s.components, from_matrix(s.crosstalk), from_pose(s.flange_T_sensor),
                        py::make_tuple(s.payload_mass_kg, from_vector(s.payload_cog_sensor_m),
                                       from_vector(s.bias_sensor), from_vector(s.gravity_base_m_s2)),
                        py::make_tuple(s.lowpass_cutoff_hz, s.lowpass_order, s.sample_rate_hz, s.dead_band_N,
                                       s.dead_band_Nm, s.fault_threshold_N, s.fault_threshold_Nm));
}

SensorConfig sensor_from_state(const py::tuple& t) {
  if (t.size() != 7) throw InputError("deflex.SensorConfig: not a pickled SensorConfig");
  SensorConfig s;
  s.name = t[0].cast<std::string>();
  s.source = t[1].cast<std::string>();
  s.components = t[2].cast<int>();
  s.crosstalk =
      Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(matrix_array(t[3], "crosstalk", 6, 6).data());
  s.flange_T_sensor = pose(t[4], "flange_T_sensor");
  const auto payload = t[5].cast<py::tuple>();
  s.payload_mass_kg = payload[0].cast<double>();
  s.payload_cog_sensor_m = vector3(payload[1], "payload_cog_sensor_m");
  s.bias_sensor = vector6(payload[2], "bias_sensor");
  s.gravity_base_m_s2 = vector3(payload[3], "gravity_base_m_s2");
  const auto c = t[6].cast<py::tuple>();
  s.lowpass_cutoff_hz = c[0].cast<double>();
  s.lowpass_order = c[1].cast<int>();
  s.sample_rate_hz = c[2].cast<double>();
  s.dead_band_N = c[3].cast<double>();
  s.dead_band_Nm = c[4].cast<double>();
  s.fault_threshold_N = c[5].cast<double>();
  s.fault_threshold_Nm = c[6].cast<double>();
  return s;
}

py::tuple online_config_state(const OnlineConfig& c) {
  return py::make_tuple(c.period_s, c.max_joint_correction_rad, c.max_tcp_correction_m, c.max_correction_rate_rad_s,
                        c.max_tcp_rate_m_s, c.watchdog_s, c.fault_hold_s, c.jacobian_at == JacobianAt::kPlanned);
}

OnlineConfig online_config_from_state(const py::tuple& t) {
  if (t.size() != 8) throw InputError("deflex.OnlineConfig: not a pickled OnlineConfig");
  OnlineConfig c;
  c.period_s = t[0].cast<double>();
  c.max_joint_correction_rad = t[1].cast<double>();
  c.max_tcp_correction_m = t[2].cast<double>();
  c.max_correction_rate_rad_s = t[3].cast<double>();
  c.max_tcp_rate_m_s = t[4].cast<double>();
  c.watchdog_s = t[5].cast<double>();
  c.fault_hold_s = t[6].cast<double>();
  c.jacobian_at = t[7].cast<bool>() ? JacobianAt::kPlanned : JacobianAt::kFeedback;
  return c;
}

py::tuple cycle_state(const CycleOutput& o) {
  return py::make_tuple(from_vector(o.q_command), from_vector(o.dtheta), from_vector(o.wrench_base),
                        from_vector(o.wrench_measured_base), static_cast<int>(o.status), o.size_limited, o.rate_limited,
                        o.tcp_correction_m, from_vector(o.tcp_deflection_base_m), o.force_age_s, o.samples_used);
}

/// The vector of a pickled result: any length (a joint vector), values as they were (NaN included).
Eigen::VectorXd state_vector(const py::handle& h) {
  const Array a = to_array(h, "state", 1);
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.shape(0));
}

CycleOutput cycle_from_state(const py::tuple& t) {
  if (t.size() != 11) throw InputError("deflex.CycleOutput: not a pickled CycleOutput");
  CycleOutput o;
  o.q_command = state_vector(t[0]);
  o.dtheta = state_vector(t[1]);
  o.wrench_base = state_vector(t[2]);
  o.wrench_measured_base = state_vector(t[3]);
  o.status = static_cast<CycleStatus>(t[4].cast<int>());
  o.size_limited = t[5].cast<bool>();
  o.rate_limited = t[6].cast<bool>();
  o.tcp_correction_m = t[7].cast<double>();
  o.tcp_deflection_base_m = state_vector(t[8]);
  o.force_age_s = t[9].cast<double>();
  o.samples_used = t[10].cast<int>();
  return o;
}

/// A raw sensor reading: (6,) [Fx Fy Fz Mx My Mz], or (3,) forces for a 3-axis sensor (no moments).
Vector6 sensor_wrench(const OnlineCompensator& c, const py::handle& obj, const char* name) {
  const Array a = to_array(obj, name, 1);
  if (a.shape(0) == 3 && c.pipeline().config().components == 3) {
    Vector6 w = Vector6::Zero();
    w.head<3>() = vector3(obj, name);
    return w;
  }
  if (a.shape(0) == 3) {
    throw InputError(
        fmt::format("argument {}: 3 values for a 6-axis sensor (SensorConfig.components 6): give "
                    "[Fx, Fy, Fz, Mx, My, Mz]",
                    name));
  }
  return vector6(obj, name);
}

/// Raw readings (n, 6), or (n, 3) forces for a 3-axis sensor (moments zero: its pipeline ignores them).
Array sensor_wrench_rows(const OnlineCompensator& c, const py::handle& obj, py::ssize_t n) {
  const Array a = to_array(obj, "wrench_sensor", 2);
  if (a.shape(1) != 3) return matrix_array(obj, "wrench_sensor", n, 6);
  if (c.pipeline().config().components != 3) {
    throw InputError(
        fmt::format("argument wrench_sensor: ({}, 3) for a 6-axis sensor (SensorConfig.components 6): "
                    "give ({}, 6) [Fx, Fy, Fz, Mx, My, Mz]",
                    a.shape(0), n));
  }
  const Array forces = matrix_array(obj, "wrench_sensor", n, 3);
  Array out = new_array({n, 6});
  double* d = out.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    for (int k = 0; k < 6; ++k) d[6 * i + k] = k < 3 ? forces.data()[3 * i + k] : 0.0;
  }
  return out;
}

// OnlineCompensator.replay: every force sample stamped at or before a cycle pushed, then one step().
py::dict replay_force_log(OnlineCompensator& c, const ArrayLike& t_force, const ArrayLike& w_obj,
                          const ArrayLike& t_cycle, const ArrayLike& q_obj, const std::optional<ArrayLike>& valid_obj) {
  const int dof = c.model().dof();
  const Array tf = to_array(t_force, "t_force_s", 1);
  require_finite(tf, "t_force_s");
  const Array w = sensor_wrench_rows(c, w_obj, tf.shape(0));
  const Array tc = to_array(t_cycle, "t_cycle_s", 1);
  require_finite(tc, "t_cycle_s");
  const py::ssize_t n = tc.shape(0), m_samples = tf.shape(0);
  bool batch = false;
  const Array q = joint_rows(q_obj, "q_planned", dof, batch);
  if (batch && q.shape(0) != n) {
    throw InputError(fmt::format("argument q_planned: expected shape ({},) or ({}, {}), got ({}, {})", dof, n, dof,
                                 q.shape(0), dof));
  }
  std::vector<char> valid(static_cast<std::size_t>(m_samples), 1);
  if (valid_obj && !valid_obj->is_none()) {
    const Array v = to_array(*valid_obj, "valid", 1);
    if (v.shape(0) != m_samples) throw InputError("argument valid: one value a force sample");
    for (py::ssize_t i = 0; i < m_samples; ++i) valid[static_cast<std::size_t>(i)] = v.data()[i] != 0.0 ? 1 : 0;
  }
  for (py::ssize_t i = 1; i < m_samples; ++i) {
    if (tf.data()[i] < tf.data()[i - 1]) {
      throw InputError(fmt::format("argument t_force_s: sample {} ({} s) is before sample {} ({} s)", i, tf.data()[i],
                                   i - 1, tf.data()[i - 1]));
    }
  }
  Array q_cmd = new_array({n, dof}), dtheta = new_array({n, dof}), wrench = new_array({n, 6});
  py::array_t<int> status(n);
  Array used = new_array({n});
  {
    py::gil_scoped_release release;
    CycleInput in;
    py::ssize_t next = 0;
    for (py::ssize_t k = 0; k < n; ++k) {
      if (k > 0 && !(tc.data()[k] > tc.data()[k - 1])) {
        throw InputError(
            fmt::format("argument t_cycle_s: cycle {} ({} s) is not after cycle {}", k, tc.data()[k], k - 1));
      }
      int pushed = 0;
      for (; next < m_samples && tf.data()[next] <= tc.data()[k]; ++next, ++pushed) {
        if (c.queued() == c.queue_capacity()) {
          throw Error(
              fmt::format("replay: {} force samples fall before cycle {} ({} s), more than the "
                          "queue's {} (two cycles at the sensor's rate): the cycles are further "
                          "apart than SensorConfig.sample_rate_hz and OnlineConfig.period_s say",
                          pushed + 1, k, tc.data()[k], c.queue_capacity()));
        }
        ForceSample s;
        s.t_s = tf.data()[next];
        s.wrench_sensor = Eigen::Map<const Vector6>(w.data() + 6 * next);
        s.valid = valid[static_cast<std::size_t>(next)] != 0;
        c.push_force(s);
      }
      in.t_s = tc.data()[k];
      in.q_planned = Eigen::Map<const Eigen::VectorXd>(q.data() + (batch ? k * dof : 0), dof);
      in.q_feedback = in.q_planned;
      const CycleOutput o = c.step(in);
      Eigen::Map<Eigen::VectorXd>(q_cmd.mutable_data() + k * dof, dof) = o.q_command;
      Eigen::Map<Eigen::VectorXd>(dtheta.mutable_data() + k * dof, dof) = o.dtheta;
      Eigen::Map<Wrench>(wrench.mutable_data() + 6 * k) = o.wrench_base;
      status.mutable_data()[k] = static_cast<int>(o.status);
      used.mutable_data()[k] = o.samples_used;
    }
  }
  py::list names;
  for (py::ssize_t k = 0; k < n; ++k) names.append(to_string(static_cast<CycleStatus>(status.data()[k])));
  return py::dict("q_command"_a = q_cmd, "dtheta"_a = dtheta, "wrench_base"_a = wrench, "status"_a = names,
                  "usable"_a = py::array(status).attr("__ge__")(0), "samples_used"_a = used);
}

}  // namespace

namespace {

// SensorConfig: the force sensor, its payload and filter, and its file.
void bind_online_sensor_config(py::module_& m) {
  py::class_<SensorConfig> sensor_class(m, "SensorConfig",
                                        "Force-sensor conditioning (docs/online.md): crosstalk, frame, payload, bias, "
                                        "low-pass, dead band, fault threshold. SI units.");
  sensor_class.def(py::init<>())
      .def_readwrite("name", &SensorConfig::name)
      .def_readwrite("components", &SensorConfig::components, "3 (forces) or 6 (forces and moments)")
      .def_property(
          "crosstalk", [](const SensorConfig& s) { return frozen(from_matrix(s.crosstalk)); },
          [](SensorConfig& s, const py::handle& v) {
            s.crosstalk = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(
                matrix_array(v, "crosstalk", 6, 6).data());
          },
          "6x6 decoupling matrix, sensor frame")
      .def_readwrite("payload_mass_kg", &SensorConfig::payload_mass_kg)
      .def_readwrite("lowpass_cutoff_hz", &SensorConfig::lowpass_cutoff_hz)
      .def_readwrite("lowpass_order", &SensorConfig::lowpass_order)
      .def_readwrite("sample_rate_hz", &SensorConfig::sample_rate_hz)
      .def_readwrite("dead_band_N", &SensorConfig::dead_band_N)
      .def_readwrite("dead_band_Nm", &SensorConfig::dead_band_Nm)
      .def_readwrite("fault_threshold_N", &SensorConfig::fault_threshold_N)
      .def_readwrite("fault_threshold_Nm", &SensorConfig::fault_threshold_Nm)
      .def_readwrite("source", &SensorConfig::source, "the file it came from")
      .def("validate", &SensorConfig::validate)
      .def("to_yaml", [](const SensorConfig& s) { return sensor_config_to_yaml(s); })
      .def(py::pickle(&sensor_state, &sensor_from_state));
  pose_property(sensor_class, "flange_T_sensor", &SensorConfig::flange_T_sensor, "flange to sensor frame, m");
  vector_property(sensor_class, "payload_cog_sensor_m", &SensorConfig::payload_cog_sensor_m);
  vector_property(sensor_class, "bias_sensor", &SensorConfig::bias_sensor, "N, Nm");
  vector_property(sensor_class, "gravity_base_m_s2", &SensorConfig::gravity_base_m_s2,
                  "gravity in the base frame, m/s^2");
  m.def(
      "load_sensor_config", [](const PathArg& p) { return load_sensor_config(path_text(p)); }, "path"_a,
      "A sensor configuration YAML (docs/online.md).");
}

// The cycle's settings and one cycle's result.
void bind_online_cycle_types(py::module_& m) {
  py::class_<OnlineConfig>(m, "OnlineConfig", "Bounds and timing of the compensation cycle (s, rad, m).")
      .def(py::init<>())
      .def_readwrite("period_s", &OnlineConfig::period_s)
      .def_readwrite("max_joint_correction_rad", &OnlineConfig::max_joint_correction_rad)
      .def_readwrite("max_tcp_correction_m", &OnlineConfig::max_tcp_correction_m)
      .def_readwrite("max_correction_rate_rad_s", &OnlineConfig::max_correction_rate_rad_s)
      .def_readwrite("max_tcp_rate_m_s", &OnlineConfig::max_tcp_rate_m_s)
      .def_readwrite("watchdog_s", &OnlineConfig::watchdog_s)
      .def_readwrite("fault_hold_s", &OnlineConfig::fault_hold_s)
      .def_property(
          "jacobian_at",
          [](const OnlineConfig& c) {
            return std::string(c.jacobian_at == JacobianAt::kPlanned ? "planned" : "feedback");
          },
          [](OnlineConfig& c, const std::string& v) {
            if (v != "planned" && v != "feedback") {
              throw InputError(fmt::format("jacobian_at: '{}' is neither planned nor feedback", v));
            }
            c.jacobian_at = v == "planned" ? JacobianAt::kPlanned : JacobianAt::kFeedback;
          },
          "'planned' (the exact compensation form) or 'feedback' (the paper's current pose)")
      .def("validate", &OnlineConfig::validate)
      .def(py::pickle(&online_config_state, &online_config_from_state));

  py::class_<CycleOutput>(m, "CycleOutput", "One compensation cycle's result.")
      .def_property_readonly(
          "q_command", [](const CycleOutput& o) { return frozen(from_vector(o.q_command)); }, "q_planned - dtheta, rad")
      .def_property_readonly(
          "dtheta", [](const CycleOutput& o) { return frozen(from_vector(o.dtheta)); }, "applied correction, rad")
      .def_property_readonly(
          "wrench_base", [](const CycleOutput& o) { return frozen(from_vector(o.wrench_base)); },
          "wrench the model used, N/Nm (base frame, at the WAP)")
      .def_property_readonly("wrench_measured_base",
                             [](const CycleOutput& o) { return frozen(from_vector(o.wrench_measured_base)); })
      .def_property_readonly(
          "status", [](const CycleOutput& o) { return std::string(to_string(o.status)); },
          "ok, no_force_yet, stale_force, force_fault, held, invalid_input or outside_limits")
      .def_property_readonly(
          "usable", [](const CycleOutput& o) { return static_cast<int>(o.status) >= 0; },
          "False: q_command must not be sent")
      .def_readonly("size_limited", &CycleOutput::size_limited)
      .def_readonly("rate_limited", &CycleOutput::rate_limited)
      .def_readonly("tcp_correction_m", &CycleOutput::tcp_correction_m)
      .def_property_readonly("tcp_deflection_base_m",
                             [](const CycleOutput& o) { return frozen(from_vector(o.tcp_deflection_base_m)); })
      .def_readonly("force_age_s", &CycleOutput::force_age_s)
      .def_readonly("samples_used", &CycleOutput::samples_used)
      .def(py::pickle(&cycle_state, &cycle_from_state));
}

// OnlineCompensator's construction and force queue.
void bind_online_compensator_setup(py::class_<OnlineCompensator>& compensator) {
  compensator
      .def(py::init([](const RobotModel& robot, const SensorConfig& sensor, const OnlineConfig& config) {
             return std::make_unique<OnlineCompensator>(robot, sensor, config);
           }),
           "robot"_a, "sensor"_a = SensorConfig(), "config"_a = OnlineConfig())
      .def(
          "push_force",
          [](OnlineCompensator& c, double t_s, const ArrayLike& wrench_sensor, bool valid, const std::string& on_full) {
            const bool drop = on_full == "drop";
            if (!drop && on_full != "raise") {
              throw InputError(fmt::format("argument on_full: '{}' is neither raise nor drop", on_full));
            }
            if (!drop && c.queued() == c.queue_capacity()) {
              throw Error(
                  fmt::format("push_force: the queue is full ({} samples, two cycles at the sensor's rate): "
                              "call step() between pushes as a real loop does, use replay() for a recorded "
                              "log, or on_full='drop' to drop the oldest",
                              c.queue_capacity()));
            }
            ForceSample s;
            s.t_s = t_s;
            s.wrench_sensor = sensor_wrench(c, wrench_sensor, "wrench_sensor");
            s.valid = valid;
            c.push_force(s);
          },
          "t_s"_a, "wrench_sensor"_a, "valid"_a = true, "on_full"_a = "raise",
          "Queues one raw sample: [Fx Fy Fz Mx My Mz] (N, Nm) in the sensor frame ([Fx Fy Fz] for a 3-axis sensor), at "
          "the sensor's time t_s (s). "
          "The queue holds queue_capacity samples (two cycles at the sensor's rate, at least 64) until the next "
          "step(); a push into a full queue raises deflex.Error (on_full='drop': drops the oldest and counts it, as "
          "the C++ cycle does).")
      .def_property_readonly("queue_capacity", &OnlineCompensator::queue_capacity,
                             "Samples push_force() queues between two step() calls.")
      .def_property_readonly("queued", &OnlineCompensator::queued, "Samples queued now.");
}

// OnlineCompensator's cycle: step, replay, reset and counters.
void bind_online_compensator_cycle(py::class_<OnlineCompensator>& compensator) {
  compensator
      .def(
          "step",
          [](OnlineCompensator& c, double t_s, const ArrayLike& q_planned, const std::optional<ArrayLike>& q_feedback,
             const std::optional<ArrayLike>& wrench_offset, double wrench_lead_s, bool hold_to_zero,
             const std::string& about) {
            const int dof = c.model().dof();
            CycleInput in;
            in.t_s = t_s;
            in.q_planned = joint_vector(q_planned, "q_planned", dof);
            in.q_feedback =
                !q_feedback || q_feedback->is_none() ? in.q_planned : joint_vector(*q_feedback, "q_feedback", dof);
            const bool about_tcp = moment_about_tcp(about);
            if (wrench_offset && !wrench_offset->is_none()) {
              in.wrench_offset_base = vector6(*wrench_offset, "wrench_offset");
              if (about_tcp) {
                Workspace ws(c.model());
                forward_kinematics(c.model(), ws, in.q_planned);
                in.wrench_offset_base =
                    moment_moved(in.wrench_offset_base, ws.base_T_tcp.translation(), ws.base_T_wap.translation());
              }
            }
            in.wrench_lead_s = wrench_lead_s;
            in.hold_to_zero = hold_to_zero;
            return c.step(in);
          },
          "t_s"_a, "q_planned"_a, "q_feedback"_a = py::none(), "wrench_offset"_a = py::none(), "wrench_lead_s"_a = 0.0,
          "hold_to_zero"_a = false, "moment_about"_a = "wap",
          "One cycle at time t_s (s, monotonic): q_planned (rad) is what the command is for, q_feedback (rad; default "
          "q_planned) where the arm is; wrench_offset (N, Nm, base frame) is added to the measured wrench, its moment "
          "about the WAP (or the TCP with moment_about='tcp'). Never raises once the arguments are valid: see "
          "CycleOutput.status.")
      .def(
          "replay",
          [](OnlineCompensator& c, const ArrayLike& t_force, const ArrayLike& w_obj, const ArrayLike& t_cycle,
             const ArrayLike& q_obj, const std::optional<ArrayLike>& valid_obj) {
            return replay_force_log(c, t_force, w_obj, t_cycle, q_obj, valid_obj);
          },
          "t_force_s"_a, "wrench_sensor"_a, "t_cycle_s"_a, "q_planned"_a, "valid"_a = py::none(),
          "A recorded force log (wrench_sensor (N, 6) N, Nm in the sensor frame; (N, 3) forces for a 3-axis sensor) "
          "through the cycle: before each cycle time (s), every sample stamped at or before it is "
          "pushed, then one step(). Nothing is dropped: a cycle with more samples before it than queue_capacity raises "
          "deflex.Error. Returns arrays a cycle: q_command, dtheta (N, dof) rad, wrench_base (N, 6) N, Nm at the WAP, "
          "status (names), usable, samples_used.")
      .def("reset", &OnlineCompensator::reset)
      .def_property_readonly("filter_delay_s", &OnlineCompensator::filter_delay_s)
      .def_property_readonly("counters", [](const OnlineCompensator& c) {
        const CompensatorCounters& k = c.counters();
        return py::dict("cycles"_a = k.cycles, "invalid_inputs"_a = k.invalid_inputs, "samples_ok"_a = k.samples_ok,
                        "samples_fault"_a = k.samples_fault, "samples_invalid"_a = k.samples_invalid,
                        "samples_dropped"_a = k.samples_dropped);
      });
}

// Payload identification from static poses.
void bind_online_identify_payload(py::module_& m) {
  m.def(
      "identify_payload",
      [](const DataArg& data, const std::shared_ptr<RobotModel>& robot, const std::optional<SensorConfig>& sensor_arg,
         const std::optional<ArrayLike>& wrench_obj) {
        SensorConfig sensor = sensor_arg ? *sensor_arg : SensorConfig();
        std::vector<PayloadObservation> poses;
        bool has_moments = false;
        std::string source = "<arrays>";
        if (py::isinstance<py::str>(data.obj) || py::hasattr(data.obj, "__fspath__")) {
          if (wrench_obj && !wrench_obj->is_none()) {
            throw InputError(
                "identify_payload: give either data (a CSV path) or the arrays base_R_sensor and wrench_sensor");
          }
          source = data.obj.cast<PathArg>().string();
          poses = read_payload_observations(source, robot.get(), sensor.flange_T_sensor, sensor.crosstalk, has_moments);
        } else {
          const Array r = to_array(data, "base_R_sensor", 3);
          require_finite(r, "base_R_sensor");
          if (r.shape(1) != 3 || r.shape(2) != 3) throw InputError("argument base_R_sensor: expected shape (N, 3, 3)");
          if (!wrench_obj || wrench_obj->is_none())
            throw InputError("identify_payload: wrench_sensor (N, 3) or (N, 6) is missing");
          const Array w = to_array(*wrench_obj, "wrench_sensor", 2);
          require_finite(w, "wrench_sensor");
          if (w.shape(0) != r.shape(0) || (w.shape(1) != 3 && w.shape(1) != 6)) {
            throw InputError(
                fmt::format("argument wrench_sensor: expected shape ({}, 3) or ({}, 6)", r.shape(0), r.shape(0)));
          }
          has_moments = w.shape(1) == 6;
          for (py::ssize_t i = 0; i < r.shape(0); ++i) {
            PayloadObservation o;
            o.base_R_sensor = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r.data() + 9 * i);
            Vector6 raw = Vector6::Zero();
            for (py::ssize_t j = 0; j < w.shape(1); ++j) raw[j] = w.data()[i * w.shape(1) + j];
            o.wrench_sensor = sensor.crosstalk * raw;
            poses.push_back(o);
          }
        }
        PayloadEstimate e;
        try {
          e = identify_payload(poses, has_moments, sensor.gravity_base_m_s2);
        } catch (const InputError& error) {
          throw InputError(fmt::format("{}: {}", source, error.what()));
        }
        sensor.payload_mass_kg = e.mass_kg;
        sensor.payload_cog_sensor_m = e.cog_sensor_m;
        sensor.bias_sensor = e.bias_sensor;
        if (!has_moments) sensor.components = 3;
        sensor.source = source + " (identified payload)";
        sensor.validate();
        return py::dict("mass_kg"_a = e.mass_kg, "cog_sensor_m"_a = from_vector(Eigen::VectorXd(e.cog_sensor_m)),
                        "bias_sensor"_a = from_vector(Eigen::VectorXd(e.bias_sensor)),
                        "moments_used"_a = e.moments_used, "poses"_a = e.poses,
                        "force_residual_rms_N"_a = e.force_residual_rms_N,
                        "moment_residual_rms_Nm"_a = e.moment_residual_rms_Nm,
                        "force_condition_number"_a = e.force_condition_number,
                        "moment_condition_number"_a = e.moment_condition_number, "sensor"_a = sensor);
      },
      "data"_a, "robot"_a = nullptr, "sensor"_a = py::none(), "wrench_sensor"_a = py::none(),
      "The end effector's mass (kg), centre of gravity (m, sensor frame) and the sensor's bias (N, Nm) from static "
      "poses, as `deflex identify-payload --data`: data is that command's CSV (orientations as qw,qx,qy,qz or as "
      "joints q1_deg.., which need robot and sensor.flange_T_sensor), or base_R_sensor (N, 3, 3) with raw readings "
      "wrench_sensor (N, 3) or (N, 6) (sensor.crosstalk applied). Returns the figures and `sensor`: a copy of the "
      "sensor configuration with the payload and bias in it (its to_yaml() is the file that command writes).");
}

}  // namespace

void bind_online(py::module_& m) {
  bind_online_sensor_config(m);
  bind_online_cycle_types(m);
  py::class_<OnlineCompensator> compensator(
      m, "OnlineCompensator",
      "The online compensation cycle (paper, Figure 3) for a loop of your own: push_force() "
      "the sensor's samples, step() once a cycle.");
  bind_online_compensator_setup(compensator);
  bind_online_compensator_cycle(compensator);
  bind_online_identify_payload(m);
}

}  // namespace deflex::python
