// The online compensator's step() for loops a user runs in Python: push raw sensor samples, then one
// step a cycle. The sensor configuration (conditioning) and the compensator's bounds as plain
// classes with the C++ field names.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/online/online_compensator.hpp"
#include "deflex/online/sensor_config.hpp"

namespace deflex::python {
using namespace pybind11::literals;
void bind_online(py::module_& m) {
  py::class_<SensorConfig> sensor_class(m, "SensorConfig",
                                  "Force-sensor conditioning (docs/online.md): crosstalk, frame, payload, bias, "
                                  "low-pass, dead band, fault threshold. SI units.");
  sensor_class.def(py::init<>())
      .def_readwrite("name", &SensorConfig::name)
      .def_readwrite("components", &SensorConfig::components, "3 (forces) or 6 (forces and moments)")
      .def_property(
          "crosstalk", [](const SensorConfig& s) { return from_matrix(s.crosstalk); },
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
      .def("validate", &SensorConfig::validate)
      .def("to_yaml", [](const SensorConfig& s) { return sensor_config_to_yaml(s); });
  pose_property(sensor_class, "flange_T_sensor", &SensorConfig::flange_T_sensor, "flange to sensor frame, m");
  vector_property(sensor_class, "payload_cog_sensor_m", &SensorConfig::payload_cog_sensor_m);
  vector_property(sensor_class, "bias_sensor", &SensorConfig::bias_sensor, "N, Nm");
  m.def("load_sensor_config", &load_sensor_config, "path"_a, "A sensor configuration YAML (docs/online.md).");

  py::class_<OnlineConfig>(m, "OnlineConfig", "Bounds and timing of the compensation cycle (s, rad, m).")
      .def(py::init<>())
      .def_readwrite("period_s", &OnlineConfig::period_s)
      .def_readwrite("max_joint_correction_rad", &OnlineConfig::max_joint_correction_rad)
      .def_readwrite("max_tcp_correction_m", &OnlineConfig::max_tcp_correction_m)
      .def_readwrite("max_correction_rate_rad_s", &OnlineConfig::max_correction_rate_rad_s)
      .def_readwrite("watchdog_s", &OnlineConfig::watchdog_s)
      .def_readwrite("fault_hold_s", &OnlineConfig::fault_hold_s)
      .def_property(
          "jacobian_at",
          [](const OnlineConfig& c) { return std::string(c.jacobian_at == JacobianAt::kPlanned ? "planned" : "feedback"); },
          [](OnlineConfig& c, const std::string& v) {
            if (v != "planned" && v != "feedback") {
              throw InputError(fmt::format("jacobian_at: '{}' is neither planned nor feedback", v));
            }
            c.jacobian_at = v == "planned" ? JacobianAt::kPlanned : JacobianAt::kFeedback;
          },
          "'planned' (the exact compensation form) or 'feedback' (the paper's current pose)")
      .def("validate", &OnlineConfig::validate);

  py::class_<CycleOutput>(m, "CycleOutput", "One compensation cycle's result.")
      .def_property_readonly("q_command", [](const CycleOutput& o) { return from_vector(o.q_command); },
                             "q_planned - dtheta, rad")
      .def_property_readonly("dtheta", [](const CycleOutput& o) { return from_vector(o.dtheta); }, "applied correction, rad")
      .def_property_readonly("wrench_base", [](const CycleOutput& o) { return from_vector(o.wrench_base); },
                             "wrench the model used, N/Nm (base frame, at the WAP)")
      .def_property_readonly("wrench_measured_base", [](const CycleOutput& o) { return from_vector(o.wrench_measured_base); })
      .def_property_readonly("status", [](const CycleOutput& o) { return std::string(to_string(o.status)); },
                             "ok, no_force_yet, stale_force, force_fault, held or invalid_input")
      .def_property_readonly("usable", [](const CycleOutput& o) { return static_cast<int>(o.status) >= 0; },
                             "False: q_command must not be sent")
      .def_readonly("size_limited", &CycleOutput::size_limited)
      .def_readonly("rate_limited", &CycleOutput::rate_limited)
      .def_readonly("tcp_correction_m", &CycleOutput::tcp_correction_m)
      .def_property_readonly("tcp_deflection_base_m", [](const CycleOutput& o) { return from_vector(o.tcp_deflection_base_m); })
      .def_readonly("force_age_s", &CycleOutput::force_age_s)
      .def_readonly("samples_used", &CycleOutput::samples_used);

  py::class_<OnlineCompensator>(m, "OnlineCompensator",
                                "The online compensation cycle (paper, Figure 3) for a loop of your own: push_force() "
                                "the sensor's samples, step() once a cycle.")
      .def(py::init([](const RobotModel& robot, const SensorConfig& sensor, const OnlineConfig& config) {
             return std::make_unique<OnlineCompensator>(robot, sensor, config);
           }),
           "robot"_a, "sensor"_a = SensorConfig(), "config"_a = OnlineConfig())
      .def(
          "push_force",
          [](OnlineCompensator& c, double t_s, const py::handle& wrench_sensor, bool valid) {
            ForceSample s;
            s.t_s = t_s;
            s.wrench_sensor = vector6(wrench_sensor, "wrench_sensor");
            s.valid = valid;
            c.push_force(s);
          },
          "t_s"_a, "wrench_sensor"_a, "valid"_a = true,
          "Queues one raw sample: [Fx Fy Fz Mx My Mz] (N, Nm) in the sensor frame, at the sensor's time t_s (s).")
      .def(
          "step",
          [](OnlineCompensator& c, double t_s, const py::handle& q_planned, const py::object& q_feedback,
             const py::object& wrench_offset, double wrench_lead_s, bool hold_to_zero) {
            const int dof = c.model().dof();
            CycleInput in;
            in.t_s = t_s;
            in.q_planned = joint_vector(q_planned, "q_planned", dof);
            in.q_feedback = q_feedback.is_none() ? in.q_planned : joint_vector(q_feedback, "q_feedback", dof);
            if (!wrench_offset.is_none()) in.wrench_offset_base = vector6(wrench_offset, "wrench_offset");
            in.wrench_lead_s = wrench_lead_s;
            in.hold_to_zero = hold_to_zero;
            return c.step(in);
          },
          "t_s"_a, "q_planned"_a, "q_feedback"_a = py::none(), "wrench_offset"_a = py::none(), "wrench_lead_s"_a = 0.0,
          "hold_to_zero"_a = false,
          "One cycle at time t_s (s, monotonic): q_planned (rad) is what the command is for, q_feedback (rad; default "
          "q_planned) where the arm is. Never raises once the arguments are valid: see CycleOutput.status.")
      .def("reset", &OnlineCompensator::reset)
      .def_property_readonly("filter_delay_s", &OnlineCompensator::filter_delay_s)
      .def_property_readonly("counters", [](const OnlineCompensator& c) {
        const CompensatorCounters& k = c.counters();
        return py::dict("cycles"_a = k.cycles, "invalid_inputs"_a = k.invalid_inputs, "samples_ok"_a = k.samples_ok,
                        "samples_fault"_a = k.samples_fault, "samples_invalid"_a = k.samples_invalid,
                        "samples_dropped"_a = k.samples_dropped);
      });
}

}  // namespace deflex::python
