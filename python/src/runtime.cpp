// The online runtime from Python: deflex.Session runs a controller link the way `deflex online` does
// (the same session object: runtime/session.hpp), against a real controller's address; deflex.StandIn
// runs one against an in-memory stand-in of the controller (standin/standin_session.hpp) with the
// faults of a cell on request. Both hand back the cycle log as NumPy arrays and the summary as a dict.
// Settings are keyword arguments: the keys of the library's settings table (runtime/session_settings.hpp),
// in SI units, checked by the library as the command line's options are; an unknown one is an
// InputError naming it.
#include <cmath>
#include <memory>
#include <vector>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/runtime/session_force.hpp"
#include "deflex/runtime/session_settings.hpp"
#include "deflex/standin/standin_session.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

// A keyword's value as the settings table takes it; a value of the wrong kind is passed on as it is,
// so that the library refuses it with the words the command line gets.
runtime::SettingValue setting_value(const runtime::SessionSetting& s, const py::handle& v) {
  const bool is_bool = py::isinstance<py::bool_>(v);
  switch (s.type) {
    case runtime::SettingType::kReal:
    case runtime::SettingType::kInteger:
      if (!is_bool && (py::isinstance<py::int_>(v) || py::isinstance<py::float_>(v))) return v.cast<double>();
      return std::string();  // the wrong kind: "expects a number"
    case runtime::SettingType::kFlag:
      if (is_bool) return v.cast<bool>();
      break;
    case runtime::SettingType::kText:
      if (py::isinstance<py::str>(v)) return v.cast<std::string>();
      break;
  }
  return 0.0;  // the wrong kind: "expects True or False", "expects words"
}

std::string setting_keys() {
  std::string keys;
  for (const runtime::SessionSetting& s : runtime::session_settings())
    keys += fmt::format("{}{}", keys.empty() ? "" : ", ", s.key);
  return keys;
}

// The session's configuration from the keyword settings (runtime/session_settings.hpp: the command
// line's options under their SI keys), checked by the library. `extra` are settings given as named
// arguments (the force source).
runtime::SessionConfig config_from(const std::string& link, const std::string& strategy, const py::kwargs& kwargs,
                                   std::vector<runtime::GivenSetting> given = {}) {
  bool status_given = false;
  for (const auto& [key, value] : kwargs) {
    const std::string name = key.cast<std::string>();
    const runtime::SessionSetting* s = runtime::find_session_setting(name);
    if (s == nullptr || s->key != name) {
      throw InputError(fmt::format("setting '{}' is not one of {}", name, setting_keys()));
    }
    status_given = status_given || s->key == "status_interval_s";
    given.push_back({s, setting_value(*s, value)});
  }
  // A Python caller reads the summary: no status lines unless asked.
  if (!status_given) given.push_back({runtime::find_session_setting("status_interval_s"), 0.0});
  runtime::SessionConfig c = runtime::make_session_config(link, strategy, given);
  c.collect_cycles = true;
  return c;
}

std::shared_ptr<const JointTrajectory> program_of(const py::object& program, const RobotModel& robot) {
  if (program.is_none()) return nullptr;
  if (py::isinstance<py::str>(program)) {
    return std::make_shared<const JointTrajectory>(JointTrajectory::read_csv(program.cast<std::string>(), robot));
  }
  // (t_s, q_rad): times (N,) and joints (N, dof).
  const auto pair = program.cast<py::tuple>();
  if (pair.size() != 2) throw InputError("argument program: a CSV path or a tuple (t_s (N,), q_rad (N, dof))");
  const Array t = to_array(pair[0], "program t_s", 1);
  require_finite(t, "program t_s");
  const Array q = matrix_array(pair[1], "program q_rad", t.shape(0), robot.dof());
  std::vector<double> times(t.data(), t.data() + t.shape(0));
  std::vector<JointVector> joints;
  for (py::ssize_t i = 0; i < q.shape(0); ++i) {
    joints.push_back(Eigen::Map<const Eigen::VectorXd>(q.data() + i * robot.dof(), robot.dof()));
  }
  return std::make_shared<const JointTrajectory>(std::move(times), std::move(joints), robot, "<python>");
}

// The cycle log as arrays: the columns of the --log CSV in SI units.
py::dict cycle_log(const std::vector<LinkCycleRecord>& records, int dof) {
  const auto n = static_cast<py::ssize_t>(records.size());
  const auto column = [&](auto get) {
    Array a = new_array({n});
    for (py::ssize_t i = 0; i < n; ++i) a.mutable_data()[i] = get(records[static_cast<std::size_t>(i)]);
    return a;
  };
  const auto joints = [&](JointVector LinkCycleRecord::*field) { return rows_of(records, field, dof); };
  py::dict d;
  d["t_s"] = column([](const LinkCycleRecord& r) { return r.t_s; });
  d["program_t_s"] = column([](const LinkCycleRecord& r) { return r.program_time_s; });
  d["sequence"] = column([](const LinkCycleRecord& r) { return static_cast<double>(r.sequence); });
  d["status"] = column([](const LinkCycleRecord& r) { return static_cast<double>(r.status); });
  d["replied"] = column([](const LinkCycleRecord& r) { return r.replied ? 1.0 : 0.0; });
  d["session_start"] = column([](const LinkCycleRecord& r) { return r.session_start ? 1.0 : 0.0; });
  d["q_nominal_rad"] = joints(&LinkCycleRecord::q_nominal);
  d["q_blend_rad"] = joints(&LinkCycleRecord::q_blend);
  d["q_feedback_rad"] = joints(&LinkCycleRecord::q_feedback);
  d["q_command_rad"] = joints(&LinkCycleRecord::q_command);
  d["dtheta_rad"] = joints(&LinkCycleRecord::dtheta);
  d["tcp_correction_m"] = rows_of(records, &LinkCycleRecord::tcp_correction_m, 3);
  d["wrench_base"] = rows_of(records, &LinkCycleRecord::wrench_base, 6);
  d["deviation_rad"] = column([](const LinkCycleRecord& r) { return r.deviation_rad; });
  d["deviation_m"] = column([](const LinkCycleRecord& r) { return r.deviation_m; });
  d["step_rad"] = column([](const LinkCycleRecord& r) { return r.step_rad; });
  d["step_m"] = column([](const LinkCycleRecord& r) { return r.step_m; });
  d["step_fraction"] = column([](const LinkCycleRecord& r) { return r.step_fraction; });
  d["delay_s"] = column([](const LinkCycleRecord& r) { return r.delay_s; });
  d["compute_s"] = column([](const LinkCycleRecord& r) { return r.compute_s; });
  d["answer_s"] = column([](const LinkCycleRecord& r) { return r.answer_s; });
  return d;
}

py::dict summary_of(const runtime::SessionSummary& s) {
  py::dict d = py::module_::import("json").attr("loads")(s.json_text);
  d["text"] = s.text;
  return d;
}

// deflex.Session: what it owns besides the runtime session.
struct PySession {
  RobotHolder robot;
  std::unique_ptr<ForceModel> force_model;
  OpenedForceSource force;
  SteadyClock clock;
  std::unique_ptr<runtime::Session> session;
};

// Runs `session` for up to `seconds` with the GIL released, in steps short enough that Ctrl-C in the
// interpreter stops the session (planned: a user stop) and is then raised.
runtime::StopReason run_releasing(runtime::Session& session, double seconds) {
  const double until = std::isfinite(seconds) ? seconds : 1e300;
  double ran = 0.0;
  while (!session.ended() && ran < until) {
    const double chunk = std::min(0.1, until - ran);
    {
      py::gil_scoped_release release;
      (void)session.run(chunk);
    }
    ran += chunk;
    if (PyErr_CheckSignals() != 0) {
      // A user stop as SIGINT is in `deflex online`: the arm brought to rest over the stop ramp first.
      session.request_stop();
      {
        py::gil_scoped_release release;
        (void)session.run(session.config().stop_ramp_s + 2.0);
      }
      throw py::error_already_set();
    }
  }
  return session.stop_reason();
}

}  // namespace

namespace {

// Session: the online session against a real controller.
void bind_runtime_session(py::module_& m) {
  py::class_<PySession>(m, "Session",
                        "An online compensation session on a controller link, run as `deflex online` runs it "
                        "(docs/online.md): link 'egm-joint', 'egm-path', 'rsi' or 'simple-message'; force_source "
                        "'udp:PORT', 'csv:FILE' or 'rdt:HOST[:PORT]'; settings as keyword arguments in SI units "
                        "(egm_port=6510, period_s=0.004, max_joint_correction_rad=..., duration_s=..., log_path=...).")
      .def(py::init([](const RobotHolder& robot, const std::string& link, const std::string& force_source,
                       const py::object& program, const py::object& sensor, const std::string& strategy,
                       const std::string& force_model, bool loop, const std::string& rdt_calibration,
                       const py::kwargs& kwargs) {
             auto s = std::make_unique<PySession>();
             s->robot = robot;
             std::vector<runtime::GivenSetting> force;
             force.push_back({runtime::find_session_setting("force_source"), force_source});
             if (loop) force.push_back({runtime::find_session_setting("loop"), true});
             if (!rdt_calibration.empty()) {
               force.push_back({runtime::find_session_setting("rdt_calibration"), rdt_calibration});
             }
             const runtime::SessionConfig config = config_from(link, strategy, kwargs, std::move(force));
             SensorConfig sc = sensor.is_none() ? SensorConfig{} : sensor.cast<SensorConfig>();
             if (!force_model.empty()) s->force_model = parse_force_spec(force_model);
             const std::shared_ptr<const JointTrajectory> nominal = program_of(program, *robot);
             s->force = runtime::open_session_force(config, *robot, sc, nominal.get());
             s->session = std::make_unique<runtime::Session>(config, *robot, sc, nominal, s->force_model.get(),
                                                             s->force.source.get(), s->clock);
             return s;
           }),
           "robot"_a, "link"_a, "force_source"_a, py::kw_only(), "program"_a = py::none(), "sensor"_a = py::none(),
           "strategy"_a = "online", "force_model"_a = "", "loop"_a = false, "rdt_calibration"_a = "")
      .def(
          "run",
          [](PySession& s, double seconds) {
            return std::string(runtime::to_string(run_releasing(*s.session, seconds)));
          },
          "seconds"_a = std::numeric_limits<double>::infinity(),
          "Runs the loop until the session ends (the stop reason is returned) or `seconds` pass ('running'). "
          "Ctrl-C stops it as a user stop and raises KeyboardInterrupt.")
      .def(
          "stop", [](PySession& s) { s.session->request_stop(); },
          "Asks the loop to end the session (a user stop): the arm is brought to rest over stop_ramp_s first; a "
          "second call ends it at once.")
      .def(
          "finish", [](PySession& s) { return summary_of(s.session->finish()); },
          "Ends the session and returns its summary (the dict of `deflex online --json`, plus 'text').")
      .def_property_readonly("ended", [](const PySession& s) { return s.session->ended(); })
      .def_property_readonly("where", [](const PySession& s) { return s.session->where(); })
      .def_property_readonly("description", [](const PySession& s) { return s.session->describe(); })
      .def(
          "cycle_log", [](PySession& s) { return cycle_log(s.session->collected(), s.robot->dof()); },
          "Every cycle so far as NumPy arrays (SI units): t_s, program_t_s, q_nominal_rad (N, dof), q_blend_rad, "
          "q_feedback_rad, q_command_rad, dtheta_rad, tcp_correction_m (N, 3), wrench_base (N, 6), deviation and step "
          "against the invariants, delay_s, compute_s, answer_s ...");
}

// StandIn's construction: the session's settings and the stand-in's own.
void bind_runtime_standin_init(py::class_<standin::StandInSession>& standin_class) {
  standin_class.def(
      py::init([](const RobotHolder& robot, const std::string& link, const py::object& program,
                  const py::handle& force_base_n, const py::object& sensor, const std::string& strategy,
                  double server_read_period_s, double comm_timeout_s, const py::kwargs& kwargs) {
        for (const char* key : {"force_source", "loop", "rdt_calibration", "rdt_rate_hz", "rdt_buffered", "tare"}) {
          if (kwargs.contains(key)) {
            throw InputError(fmt::format("{}: a stand-in has its own sensor (force_base_N, sensor_silent())",
                                         runtime::setting_name(*runtime::find_session_setting(key))));
          }
        }
        const runtime::SessionConfig config = config_from(link, strategy, kwargs);
        standin::StandInConfig sc;
        sc.force_base_n = vector3(force_base_n, "force_base_N");
        if (!(server_read_period_s >= 0.0 && server_read_period_s <= 10.0)) {
          throw InputError(fmt::format("server_read_period_s: {} s is not in 0..10 s", server_read_period_s));
        }
        sc.server.read_period_s = server_read_period_s;
        if (!(comm_timeout_s > 0.0 && comm_timeout_s <= 60.0)) {
          throw InputError(fmt::format("comm_timeout_s: {} s is not in 0..60 s", comm_timeout_s));
        }
        sc.controller.egm_comm_timeout_s = comm_timeout_s;
        const SensorConfig sensor_config = sensor.is_none() ? SensorConfig{} : sensor.cast<SensorConfig>();
        return std::make_unique<standin::StandInSession>(config, *robot, sensor_config, program_of(program, *robot),
                                                         nullptr, sc);
      }),
      "robot"_a, "link"_a, "program"_a, py::kw_only(), "force_base_N"_a = std::vector<double>{0.0, 0.0, 0.0},
      "sensor"_a = py::none(), "strategy"_a = "online", "server_read_period_s"_a = 0.0, "comm_timeout_s"_a = 1.0,
      py::keep_alive<1, 2>());
}

// StandIn's clock, the cell's faults on request, and the session's end.
void bind_runtime_standin_faults(py::class_<standin::StandInSession>& standin_class) {
  standin_class
      .def("run_for", &standin::StandInSession::run_for, "seconds"_a,
           "Ticks the stand-in for `seconds` of its own clock (or until the session ended).")
      .def("outage", &standin::StandInSession::outage, "seconds"_a, "Every datagram of the next `seconds` is lost.")
      .def("reorder", &standin::StandInSession::reorder, "count"_a,
           "The controller's next `count` messages are overtaken in the network by the one after them.")
      .def(
          "stop", [](standin::StandInSession& s) { s.session().request_stop(); },
          "Asks for a planned stop, as SIGINT does (the stop ramp first; a second call stops at once).")
      .def("stall", &standin::StandInSession::stall, "stalled"_a, "deflex stops reading (a stalled PC) or goes on.")
      .def("restart", &standin::StandInSession::restart, "reset_reference"_a = true, "off_s"_a = 0.0,
           "The controller starts a new session (EGM, path correction; RSI after off_s of RSI_OFF).")
      .def("end_session", &standin::StandInSession::end_session, "mci_state"_a = 2, "EGM ends: 2 STOPPED, 1 ERROR.")
      .def("motors_off", &standin::StandInSession::motors_off, "An emergency stop.")
      .def("sensor_silent", &standin::StandInSession::sensor_silent, "silent"_a,
           "The force sensor stops or comes back.")
      .def(
          "set_force", [](standin::StandInSession& s, const ArrayLike& f) { s.set_force(vector3(f, "force_base_N")); },
          "force_base_N"_a)
      .def_property_readonly("time_s", &standin::StandInSession::time_s)
      .def_property_readonly("ended", [](standin::StandInSession& s) { return s.session().ended(); })
      .def("finish", [](standin::StandInSession& s) { return summary_of(s.session().finish()); })
      .def(
          "cycle_log",
          [](standin::StandInSession& s) {
            s.session().service();
            return cycle_log(s.session().collected(), static_cast<int>(s.arm().size()));
          },
          "As deflex.Session.cycle_log().")
      .def_property_readonly(
          "wire",
          [](const standin::StandInSession& s) {
            const auto& w = s.wire();
            py::dict d;
            Array t = new_array({static_cast<py::ssize_t>(w.size())});
            for (std::size_t i = 0; i < w.size(); ++i) t.mutable_data()[i] = w[i].t_s;
            d["t_s"] = t;
            if (s.link() == runtime::LinkKind::kEgmPath) {
              d["offset_m"] = rows_of(w, &standin::WireCommand::offset_m, 3);
            } else {
              d["joints_rad"] = rows_of(w, &standin::WireCommand::joints, static_cast<int>(s.arm().size()));
            }
            return d;
          },
          "What the controller received, decoded with the wire's own codec: t_s, joints_rad (absolute for egm-joint, "
          "the offset for rsi, the command position each increment moved the controller to for motoros2-rt, each "
          "target the servo program handed to servoj for ur-rtde), "
          "offset_m (egm-path, in its correction frame)");
}

}  // namespace

void bind_runtime(py::module_& m) {
  bind_runtime_session(m);
  py::class_<standin::StandInSession> standin_class(
      m, "StandIn",
      "A session against an in-memory stand-in of the controller (the simulated cell's, with the real controller's "
      "behaviour, dead time included), on a clock it advances itself, with the faults of a cell on request: "
      "outage(), reorder(), stall(), restart(), end_session(), motors_off(), sensor_silent(), stop(). force_base_N: "
      "the process force "
      "at the TCP in the base frame; server_read_period_s: simple message, the robot program takes a point at most "
      "this "
      "often (a slow consumer); comm_timeout_s: EGM's \\CommTimeout, s. Settings as deflex.Session's.");
  bind_runtime_standin_init(standin_class);
  bind_runtime_standin_faults(standin_class);
}

}  // namespace deflex::python
