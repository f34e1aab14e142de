// The online runtime from Python: deflex.Session runs a controller link the way `deflex online` does
// (the same session object: runtime/session.hpp), against a real controller's address; deflex.StandIn
// runs one against an in-memory stand-in of the controller (standin/standin_session.hpp) with the
// faults of a cell on request. Both hand back the cycle log as NumPy arrays and the summary as a dict.
// Settings are keyword arguments with the C++ field names and SI units; an unknown one is an
// InputError naming it.
#include <cmath>
#include <functional>
#include <map>
#include <memory>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/sensors/force_source_spec.hpp"
#include "deflex/standin/standin_session.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

// One setting: its name, and how a Python value sets it in the session's configuration.
using Setter = std::function<void(runtime::SessionConfig&, const py::handle&)>;

template <typename T>
T as(const py::handle& v, const std::string& name) {
  try {
    return v.cast<T>();
  } catch (const py::cast_error&) {
    throw InputError(fmt::format("setting {}: {} is not a {}", name, py::str(py::repr(v)).cast<std::string>(),
                                 std::is_same_v<T, bool>          ? "bool"
                                 : std::is_same_v<T, std::string> ? "str"
                                                                  : "number"));
  }
}

const std::map<std::string, Setter>& settings() {
  using C = runtime::SessionConfig;
  static const std::map<std::string, Setter> table = [] {
    std::map<std::string, Setter> t;
    const auto real = [&t](const char* name, std::function<double&(C&)> field) {
      t[name] = [field, name](C& c, const py::handle& v) { field(c) = as<double>(v, name); };
    };
    const auto integer = [&t](const char* name, std::function<int&(C&)> field) {
      t[name] = [field, name](C& c, const py::handle& v) { field(c) = as<int>(v, name); };
    };
    const auto flag = [&t](const char* name, std::function<bool&(C&)> field) {
      t[name] = [field, name](C& c, const py::handle& v) { field(c) = as<bool>(v, name); };
    };
    const auto text = [&t](const char* name, std::function<std::string&(C&)> field) {
      t[name] = [field, name](C& c, const py::handle& v) { field(c) = as<std::string>(v, name); };
    };
    real("period_s", [](C& c) -> double& { return c.online.period_s; });
    real("max_joint_correction_rad", [](C& c) -> double& { return c.online.max_joint_correction_rad; });
    real("max_tcp_correction_m", [](C& c) -> double& { return c.online.max_tcp_correction_m; });
    real("max_correction_rate_rad_s", [](C& c) -> double& { return c.online.max_correction_rate_rad_s; });
    real("max_tcp_rate_m_s", [](C& c) -> double& { return c.online.max_tcp_rate_m_s; });
    real("watchdog_s", [](C& c) -> double& { return c.online.watchdog_s; });
    t["stop_silence_s"] = [](C& c, const py::handle& v) { c.stop_silence_s = as<double>(v, "stop_silence_s"); };
    real("end_silence_s", [](C& c) -> double& { return c.end_silence_s; });
    flag("end_on_silence", [](C& c) -> bool& { return c.end_on_silence; });
    real("duration_s", [](C& c) -> double& { return c.duration_s; });
    real("stop_ramp_s", [](C& c) -> double& { return c.stop_ramp_s; });
    real("status_interval_s", [](C& c) -> double& { return c.status_interval_s; });
    text("log_path", [](C& c) -> std::string& { return c.log_path; });
    text("fault_dump_path", [](C& c) -> std::string& { return c.fault_dump_path; });
    text("bind_address", [](C& c) -> std::string& { return c.network.bind_address; });
    integer("egm_port", [](C& c) -> int& { return c.network.egm_port; });
    integer("rsi_port", [](C& c) -> int& { return c.network.rsi_port; });
    text("robot_host", [](C& c) -> std::string& { return c.network.robot_host; });
    integer("motion_port", [](C& c) -> int& { return c.network.motion_port; });
    integer("state_port", [](C& c) -> int& { return c.network.state_port; });
    real("connect_timeout_s", [](C& c) -> double& { return c.network.connect_timeout_s; });
    t["ramp_in_s"] = [](C& c, const py::handle& v) {
      c.egm_joint.stream.ramp_in_s = c.simple_message.stream.ramp_in_s = c.fanuc_j519.stream.ramp_in_s =
          c.motoros2_rt.stream.ramp_in_s = as<double>(v, "ramp_in_s");
    };
    integer("robot_port", [](C& c) -> int& { return c.network.robot_port; });
    t["fanuc_version"] = [](C& c, const py::handle& v) {
      const int version = as<int>(v, "fanuc_version");
      if (!fanuc_j519::known_version(version < 0 ? 0U : static_cast<std::uint32_t>(version))) {
        throw InputError(fmt::format("setting fanuc_version: {} is not 1, 3 or 4", version));
      }
      c.fanuc_j519.version = static_cast<std::uint32_t>(version);
    };
    t["fanuc_limits"] = [](C& c, const py::handle& v) {
      c.fanuc_j519.limits = parse_fanuc_limits(as<std::string>(v, "fanuc_limits"), "fanuc_limits");
    };
    real("fanuc_correction_share", [](C& c) -> double& { return c.fanuc_j519.correction_share; });
    integer("fanuc_catch_up", [](C& c) -> int& { return c.fanuc_j519.max_catch_up; });
    integer("motoros2_group", [](C& c) -> int& { return c.motoros2_rt.group; });
    integer("motoros2_tool", [](C& c) -> int& { return c.motoros2_rt.tool; });
    real("motoros2_resend_s", [](C& c) -> double& { return c.motoros2_rt.resend_after_s; });
    integer("motoros2_max_truncations", [](C& c) -> int& { return c.motoros2_rt.max_truncation_run; });
    integer("motoros2_status_port", [](C& c) -> int& { return c.motoros2_rt.status_port; });
    flag("send_speed_reference", [](C& c) -> bool& { return c.egm_joint.send_speed_reference; });
    t["path_corr_frame"] = [](C& c, const py::handle& v) {
      c.egm_path.frame = parse_path_corr_frame(as<std::string>(v, "path_corr_frame"));
    };
    text("rsi_sentype", [](C& c) -> std::string& { return c.rsi.sentype; });
    integer("rsi_timeout", [](C& c) -> int& { return c.rsi.controller_timeout; });
    integer("buffer_depth", [](C& c) -> int& { return c.simple_message.buffer_depth; });
    real("max_behind_s", [](C& c) -> double& { return c.simple_message.max_behind_s; });
    t["byte_order"] = [](C& c, const py::handle& v) {
      c.simple_message.byte_order = simple_message::parse_byte_order(as<std::string>(v, "byte_order"));
    };
    t["jacobian_at"] = [](C& c, const py::handle& v) {
      const std::string s = as<std::string>(v, "jacobian_at");
      if (s != "planned" && s != "feedback") throw InputError("setting jacobian_at: 'planned' or 'feedback'");
      c.online.jacobian_at = s == "planned" ? JacobianAt::kPlanned : JacobianAt::kFeedback;
    };
    flag("realtime", [](C& c) -> bool& { return c.realtime.enabled; });
    integer("rt_priority", [](C& c) -> int& { return c.realtime.priority; });
    integer("rt_cpu", [](C& c) -> int& { return c.realtime.cpu; });
    return t;
  }();
  return table;
}

std::string setting_names() {
  std::string names;
  for (const auto& [name, setter] : settings()) names += (names.empty() ? "" : ", ") + name;
  return names;
}

runtime::SessionConfig config_from(const std::string& link, const std::string& strategy, const py::kwargs& kwargs) {
  runtime::SessionConfig c;
  c.link = runtime::parse_link_kind(link);
  c.strategy = parse_strategy(strategy);
  c.online.period_s = runtime::link_kind(c.link).default_period_s;
  c.status_interval_s = 0.0;  // a Python caller reads the summary; no status lines unless asked
  for (const auto& [key, value] : kwargs) {
    const std::string name = key.cast<std::string>();
    const auto it = settings().find(name);
    if (it == settings().end()) {
      throw InputError(fmt::format("setting '{}' is not one of {}", name, setting_names()));
    }
    it->second(c, value);
  }
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

void bind_runtime(py::module_& m) {
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
             const runtime::SessionConfig config = config_from(link, strategy, kwargs);
             SensorConfig sc = sensor.is_none() ? SensorConfig{} : sensor.cast<SensorConfig>();
             if (!force_model.empty()) s->force_model = parse_force_spec(force_model);
             ForceSourceOptions fo;
             fo.loop = loop;
             fo.bind_address = config.network.bind_address;
             fo.rdt_calibration.spec = rdt_calibration;
             s->force = open_force_source(force_source, fo);
             if (s->force.sample_rate_hz > 0.0) sc.sample_rate_hz = s->force.sample_rate_hz;
             s->session = std::make_unique<runtime::Session>(config, *robot, sc, program_of(program, *robot),
                                                             s->force_model.get(), s->force.source.get(), s->clock);
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

  py::class_<standin::StandInSession>(
      m, "StandIn",
      "A session against an in-memory stand-in of the controller (the simulated cell's, with the real controller's "
      "behaviour, dead time included), on a clock it advances itself, with the faults of a cell on request: "
      "outage(), reorder(), stall(), restart(), end_session(), motors_off(), sensor_silent(), stop(). force_base_N: "
      "the process force "
      "at the TCP in the base frame; server_read_period_s: simple message, the robot program takes a point at most "
      "this "
      "often (a slow consumer); comm_timeout_s: EGM's \\CommTimeout, s. Settings as deflex.Session's.")
      .def(py::init([](const RobotHolder& robot, const std::string& link, const py::object& program,
                       const py::handle& force_base_n, const py::object& sensor, const std::string& strategy,
                       double server_read_period_s, double comm_timeout_s, const py::kwargs& kwargs) {
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
             return std::make_unique<standin::StandInSession>(config, *robot, sensor_config,
                                                              program_of(program, *robot), nullptr, sc);
           }),
           "robot"_a, "link"_a, "program"_a, py::kw_only(), "force_base_N"_a = std::vector<double>{0.0, 0.0, 0.0},
           "sensor"_a = py::none(), "strategy"_a = "online", "server_read_period_s"_a = 0.0, "comm_timeout_s"_a = 1.0,
           py::keep_alive<1, 2>())
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
          "the offset for rsi, the command position each increment moved the controller to for motoros2-rt), "
          "offset_m (egm-path, in its correction frame)");
}

}  // namespace deflex::python
