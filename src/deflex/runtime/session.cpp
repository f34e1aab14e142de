// An online compensation session (see session.hpp).
#include "deflex/runtime/session.hpp"

#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "deflex/online/online_strategy.hpp"
#include "deflex/runtime/session_settings.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/transport/tcp_stream.hpp"
#include "deflex/transport/udp_transport.hpp"
#include "deflex/wire/egm_codec.hpp"

namespace deflex::runtime {

namespace {

std::uint16_t port_option(int port, const char* option, const char* what, int lowest) {
  if (port == -1) throw InputError(fmt::format("option {}: {}", option, what));
  if (port < lowest || port > 65535) {
    throw InputError(fmt::format("option {}: must be a port {}..65535 (got {})", option, lowest, port));
  }
  return static_cast<std::uint16_t>(port);
}

void check_config(const SessionConfig& c, const LinkKindInfo& kind, const JointTrajectory* program) {
  c.online.validate();
  c.realtime.validate();
  const auto non_negative = [](double v, const char* option) {
    if (!std::isfinite(v) || v < 0.0)
      throw InputError(fmt::format("option {}: must be a number >= 0 (got {})", option, v));
  };
  non_negative(c.duration_s, "--duration-s");
  non_negative(c.status_interval_s, "--status-interval-s");
  if (!std::isfinite(c.stop_ramp_s) || c.stop_ramp_s < 0.05 || c.stop_ramp_s > 10.0) {
    throw InputError(fmt::format("option --stop-ramp-s: 0.05..10 s (got {})", c.stop_ramp_s));
  }
  if (c.monitor && !(c.monitor_window_s >= 1.0 && c.monitor_window_s <= 3600.0)) {
    throw InputError(fmt::format("option --monitor-window-s: 1..3600 s (got {})", c.monitor_window_s));
  }
  if (!std::isfinite(c.fault_quiet_s) || !(c.fault_quiet_s > 0.0)) {
    throw InputError("session: the fault episode's quiet time must be > 0 s");
  }
  if (c.history_cycles < 1 || c.history_cycles > 1000000) throw InputError("session: 1..1000000 history cycles");
  if (c.queue_entries < 16 || c.queue_entries > (std::size_t{1} << 24)) {
    throw InputError("session: the reporter's queue holds 16..16777216 entries");
  }
  if (kind.streams_program && program == nullptr) {
    throw InputError(
        fmt::format("option --program: {} streams a nominal program: give --program P.csv (deflex offline "
                    "--nominal-trajectory writes one)",
                    kind.name));
  }
  if (!kind.streams_program && program != nullptr) {
    throw InputError(
        fmt::format("option --program: {} corrects the controller's own program; deflex streams none", kind.name));
  }
}

}  // namespace

Session::Session(const SessionConfig& config, const RobotModel& robot, const SensorConfig& sensor,
                 std::shared_ptr<const JointTrajectory> program, const ForceModel* force_model, ForceSource* force,
                 const Clock& clock, const SessionEndpoints& endpoints, LogSink sink)
    : config_(config), clock_(clock), sink_(std::move(sink)), program_(program) {
  const LinkKindInfo& info = link_kind(config_.link);
  check_config(config_, info, program.get());
  compensator_ = std::make_unique<OnlineCompensator>(robot, sensor, config_.online);
  strategy_ = std::make_unique<OnlineStrategy>(robot, config_.strategy, force_model);
  force_ = force;
  open_link(endpoints, std::move(program));
  link_->read_force_from(force);  // straight to the cycle: no link's own code sees the force

  reporting_ = !config_.log_path.empty() || !config_.fault_dump_path.empty() || static_cast<bool>(sink_) ||
               config_.collect_cycles || config_.monitor;
  entry_.record = link_->history().blank();
  if (reporting_) {
    ReportSetup setup;
    setup.link_name = info.name;
    setup.joints = robot.dof();
    setup.period_s = config_.online.period_s;
    setup.force_components = sensor.components;
    setup.force_fault_n = sensor.fault_threshold_N;
    SessionConfig ran = config_;  // the silence that stops it as the link resolved it, not "the link's"
    ran.stop_silence_s = link_->stop_rules().stop_silence_s;
    setup.settings = settings_shown(ran);
    setup.limits = link_->limits();
    setup.streams_program = info.streams_program;
    if (program_) {
      setup.program_start_s = program_->start_time_s();
      setup.program_duration_s = program_->duration_s();
    }
    setup.log_path = config_.log_path;
    setup.dump_path = config_.fault_dump_path;
    setup.dump_cycles = config_.history_cycles;
    setup.fault_quiet_s = config_.fault_quiet_s;
    setup.status_interval_s = config_.status_interval_s > 0.0 ? config_.status_interval_s : 1e300;
    setup.collect = config_.collect_cycles;
    setup.sink = sink_;
    setup.on_output_failure = [this](const std::string& text) { report_output_failure(text); };
    if (config_.monitor) {
      MonitorSetup ms;
      ms.link = info.name;
      ms.joints = robot.dof();
      ms.force_components = sensor.components;
      ms.period_s = config_.online.period_s;
      ms.force_fault_n = sensor.fault_threshold_N;
      ms.joint_bound_deg = rad_to_deg(setup.limits.joint_bound_rad);
      ms.tcp_bound_mm = setup.limits.tcp_bound_m * 1e3;
      ms.program_duration_s = setup.program_duration_s;
      ms.window_s = config_.monitor_window_s;
      ms.settings = setup.settings;
      monitor_ = std::make_shared<MonitorFeed>(ms);
      setup.monitor = monitor_;
    }
    reporter_ = std::make_unique<SessionReporter>(std::move(setup));
    queue_ = std::make_unique<SpscRing<SessionEntry>>(config_.queue_entries, entry_);
  }
  start_s_ = clock_.now_s();
}

Session::~Session() {
  if (reporter_thread_.joinable()) {
    reporter_stop_.store(true);
    reporter_thread_.join();
  }
}

// FANUC Stream Motion: deflex is the client; its datagrams go to the controller's address and port.
void Session::open_fanuc_j519(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program,
                              const LinkStopRules& rules) {
  FanucJ519LinkConfig c = config_.fanuc_j519;
  c.stop = rules;
  c.history_cycles = config_.history_cycles;
  const NetworkConfig& net = config_.network;
  const double period_ms = config_.online.period_s * 1e3;
  if (std::abs(period_ms - 8.0) > 1e-9 && std::abs(period_ms - 4.0) > 1e-9 && std::abs(period_ms - 1.0) > 1e-9) {
    throw InputError(fmt::format(
        "option --period-ms: FANUC's communication interval ($STMO.$COM_INT) is 8, 4 or 1 ms (got {:g})", period_ms));
  }
  DatagramTransport* t = endpoints.datagram;
  if (!net.robot_host.empty() || t == nullptr) {
    if (net.robot_host.empty()) {
      throw InputError("option --robot-host: the fanuc-j519 link needs the controller's IPv4 address");
    }
    const std::uint16_t port = port_option(net.robot_port == -1 ? 60015 : net.robot_port, "--robot-port", "", 1);
    c.controller = make_datagram_address(net.robot_host, port);
  }
  if (t == nullptr) {
    own_datagram_ = std::make_unique<UdpTransport>(net.bind_address, 0);
    t = own_datagram_.get();
  }
  link_ = std::make_unique<FanucJ519Link>(*compensator_, *strategy_, std::move(program), *t, clock_, c);
  where_ = fmt::format("FANUC Stream Motion to {} (protocol {}), from {}", to_string(c.controller), c.version,
                       to_string(t->local_address()));
}

// MotoROS2 real-time: deflex is the client, as for FANUC; the controller answers to the command's source.
void Session::open_motoros2_rt(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program,
                               const LinkStopRules& rules) {
  Motoros2RtLinkConfig c = config_.motoros2_rt;
  c.stop = rules;
  c.history_cycles = config_.history_cycles;
  c.validate();
  const NetworkConfig& net = config_.network;
  DatagramTransport* t = endpoints.datagram;
  if (!net.robot_host.empty() || t == nullptr) {
    if (net.robot_host.empty()) {
      throw InputError("option --robot-host: the motoros2-rt link needs the controller's IPv4 address");
    }
    const std::uint16_t port =
        port_option(net.robot_port == -1 ? motoros2_rt::kDefaultPort : net.robot_port, "--robot-port", "", 1);
    c.controller = make_datagram_address(net.robot_host, port);
  }
  if (t == nullptr) {
    own_datagram_ = std::make_unique<UdpTransport>(net.bind_address, 0);
    t = own_datagram_.get();
  }
  DatagramTransport* status = endpoints.status;
  if (c.status_port >= 0 && status == nullptr) {
    own_status_ =
        std::make_unique<UdpTransport>(net.bind_address, port_option(c.status_port, "--motoros2-status-port", "", 1));
    status = own_status_.get();
  }
  if (c.status_port < 0) status = nullptr;
  link_ = std::make_unique<Motoros2RtLink>(*compensator_, *strategy_, std::move(program), *t, clock_, c, status);
  where_ = fmt::format("MotoROS2 real-time to {} (group {}), from {}{}", to_string(c.controller), c.group,
                       to_string(t->local_address()),
                       status != nullptr ? fmt::format(", its status on {}", to_string(status->local_address())) : "");
}

// Universal Robots RTDE: deflex is the client of the controller's RTDE server (one TCP connection).
void Session::open_ur_rtde(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program,
                           const LinkStopRules& rules) {
  UrRtdeLinkConfig c = config_.ur_rtde;
  c.stop = rules;
  c.history_cycles = config_.history_cycles;
  c.validate();  // before any connection is made
  const NetworkConfig& net = config_.network;
  const double period_ms = config_.online.period_s * 1e3;
  if (std::abs(period_ms - 2.0) > 1e-9 && std::abs(period_ms - 8.0) > 1e-9) {
    throw InputError(fmt::format(
        "option --period-ms: a UR controller's loop is 2 ms (e-Series) or 8 ms (CB3) (got {:g})", period_ms));
  }
  StreamTransport* t = endpoints.motion;
  if (t == nullptr) {
    if (net.robot_host.empty()) {
      throw InputError("option --robot-host: the ur-rtde link needs the controller's address");
    }
    if (!std::isfinite(net.connect_timeout_s) || !(net.connect_timeout_s > 0.0)) {
      throw InputError(fmt::format("option --connect-timeout-s: must be > 0 (got {})", net.connect_timeout_s));
    }
    const std::uint16_t port =
        port_option(net.robot_port == -1 ? rtde::kDefaultPort : net.robot_port, "--robot-port", "", 1);
    own_motion_ = TcpStream::connect(net.robot_host, port, net.connect_timeout_s);
    t = own_motion_.get();
    where_ = fmt::format("UR RTDE to {}:{}", net.robot_host, port);
  } else {
    where_ = "UR RTDE";
  }
  link_ = std::make_unique<UrRtdeLink>(*compensator_, *strategy_, std::move(program), *t, clock_, c);
  where_ += fmt::format(" (servoj lookahead {:g} ms, gain {:g}, registers from {})", c.lookahead_s * 1e3, c.gain,
                        c.register_offset);
}

void Session::open_simple_message(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program,
                                  const LinkStopRules& rules) {
  const NetworkConfig& net = config_.network;
  SimpleMessageLinkConfig c = config_.simple_message;
  c.stop = rules;
  c.history_cycles = config_.history_cycles;
  c.validate();  // before any connection is made
  StreamTransport* motion = endpoints.motion;
  StreamTransport* state = endpoints.state;
  if (motion == nullptr || state == nullptr) {
    if (net.robot_host.empty()) {
      throw InputError("option --robot-host: the simple-message link needs the controller's address");
    }
    if (!std::isfinite(net.connect_timeout_s) || !(net.connect_timeout_s > 0.0)) {
      throw InputError(fmt::format("option --connect-timeout-s: must be > 0 (got {})", net.connect_timeout_s));
    }
    const std::uint16_t mp = port_option(net.motion_port, "--motion-port", "", 1);
    const std::uint16_t sp = port_option(net.state_port, "--state-port", "", 1);
    own_motion_ = TcpStream::connect(net.robot_host, mp, net.connect_timeout_s);
    own_state_ = TcpStream::connect(net.robot_host, sp, net.connect_timeout_s);
    motion = own_motion_.get();
    state = own_state_.get();
    where_ = fmt::format("simple message to {} (motion {}, state {}, {}-endian)", net.robot_host, mp, sp,
                         simple_message::to_string(c.byte_order));
  } else {
    where_ = fmt::format("simple message ({}-endian)", simple_message::to_string(c.byte_order));
  }
  link_ =
      std::make_unique<SimpleMessageLink>(*compensator_, *strategy_, std::move(program), *motion, *state, clock_, c);
}

void Session::open_link(const SessionEndpoints& endpoints, std::shared_ptr<const JointTrajectory> program) {
  const LinkKindInfo& info = link_kind(config_.link);
  LinkStopRules rules;
  rules.stop_silence_s = config_.stop_silence_s.value_or(info.default_stop_silence_s);
  rules.end_silence_s = config_.end_silence_s;
  rules.end_on_silence = config_.end_on_silence;
  rules.validate();
  const NetworkConfig& net = config_.network;
  const auto datagram = [&](int port, const char* option, const char* what) -> DatagramTransport& {
    if (endpoints.datagram != nullptr) return *endpoints.datagram;
    // Port 0: the system picks one (where() tells which).
    own_datagram_ = std::make_unique<UdpTransport>(net.bind_address, port_option(port, option, what, 0));
    return *own_datagram_;
  };
  switch (config_.link) {
    case LinkKind::kEgmJoint: {
      EgmJointLinkConfig c = config_.egm_joint;
      c.stop = rules;
      c.history_cycles = config_.history_cycles;
      DatagramTransport& t =
          datagram(net.egm_port, "--egm-port", "the EGM links need the port the controller sends to");
      link_ = std::make_unique<EgmJointLink>(*compensator_, *strategy_, std::move(program), t, clock_, c);
      where_ = fmt::format("EGM on {}", to_string(t.local_address()));
      break;
    }
    case LinkKind::kEgmPath: {
      EgmPathLinkConfig c = config_.egm_path;
      c.stop = rules;
      c.history_cycles = config_.history_cycles;
      DatagramTransport& t =
          datagram(net.egm_port, "--egm-port", "the EGM links need the port the controller sends to");
      link_ = std::make_unique<EgmPathLink>(*compensator_, *strategy_, t, clock_, c);
      where_ = fmt::format("EGM on {} (corrections in the {} frame)", to_string(t.local_address()), to_string(c.frame));
      break;
    }
    case LinkKind::kRsi: {
      RsiLinkConfig c = config_.rsi;
      c.stop = rules;
      c.history_cycles = config_.history_cycles;
      DatagramTransport& t =
          datagram(net.rsi_port, "--rsi-port", "the RSI link needs the port the controller sends to");
      link_ = std::make_unique<RsiLink>(*compensator_, *strategy_, t, clock_, c);
      where_ = fmt::format("RSI on {}; answers <Sen Type=\"{}\">", to_string(t.local_address()), c.sentype);
      break;
    }
    case LinkKind::kSimpleMessage:
      open_simple_message(endpoints, std::move(program), rules);
      break;
    case LinkKind::kFanucJ519:
      open_fanuc_j519(endpoints, std::move(program), rules);
      break;
    case LinkKind::kMotoros2Rt:
      open_motoros2_rt(endpoints, std::move(program), rules);
      break;
    case LinkKind::kUrRtde:
      open_ur_rtde(endpoints, std::move(program), rules);
      break;
  }
}

std::string Session::describe() const {
  const LinkKindInfo& info = kind();
  const OnlineConfig& o = config_.online;
  std::string program;
  if (program_) {
    program =
        fmt::format("; program {} ({} points, {:.1f} s)", program_->source(), program_->size(), program_->duration_s());
  }
  return fmt::format(
      "{} link, strategy {}; {}{}; {}; rate bounds {:g} deg/s a joint and {:g} mm/s at the TCP; watchdog {:g} ms; "
      "period {:g} ms; ends after {:g} s of controller silence",
      info.name, to_string(config_.strategy), where_, program, link_->limits().describe(),
      rad_to_deg(o.max_correction_rate_rad_s), o.max_tcp_rate_m_s * 1e3, o.watchdog_s * 1e3, o.period_s * 1e3,
      link_->stop_rules().stop_silence_s);
}

void Session::push(SessionEntry::Kind kind, double now) noexcept {
  entry_.kind = kind;
  entry_.t_s = now;
  entry_.state = link_->state();
  if (kind == SessionEntry::Kind::kCycle) entry_.record = link_->last_cycle();
  entry_.counters = link_->counters();
  entry_.compensator = compensator_->counters();
  if (force_ != nullptr) entry_.force = force_->stats();
  if (!queue_->push(entry_)) dropped_.fetch_add(1, std::memory_order_relaxed);
  last_push_s_ = now;
}

void Session::end(StopReason reason) noexcept {
  if (reason_ == StopReason::kRunning) reason_ = reason;
}

LinkPollResult Session::poll(double timeout_s) noexcept {
  if (ended()) return LinkPollResult::kIdle;
  const LinkPollResult r = link_->poll(timeout_s);
  const double now = clock_.now_s();
  if (reporting_) {
    // A cycle entry for every answer (a FANUC stream's last-data command repeats the last cycle's) and
    // for a message left unanswered by a cycle; one left unanswered without a cycle (a controller not
    // ready yet, before the first) has no record of its own, and a blank one would read as a silence
    // from time 0 to the first cycle.
    const std::uint64_t cycles = link_->cycle_stats().cycles;
    const bool new_cycle = cycles != pushed_cycles_;
    if (r == LinkPollResult::kAnswered || (r == LinkPollResult::kNotAnswered && new_cycle)) {
      pushed_cycles_ = cycles;
      push(SessionEntry::Kind::kCycle, now);
    } else if (now - last_push_s_ >= 0.05) {
      push(SessionEntry::Kind::kHeartbeat, now);
    }
  }
  if (r == LinkPollResult::kRefused) {
    end(StopReason::kStartRefused);
  } else if (r == LinkPollResult::kStopped) {
    const bool asked = link_->stop_cause() == LinkStopCause::kRequested && planned_stop_ != StopReason::kRunning;
    end(asked ? planned_stop_ : stop_reason_of(link_->stop_cause()));
  } else {
    const int requests = stop_requests_.load();
    if (output_failed_.load(std::memory_order_acquire) && planned_stop_ == StopReason::kRunning) {
      planned_stop(StopReason::kOutputFailed, now);
      return r;
    }
    if (requests >= 2) {  // asked again: at once
      link_->stop();
      end(planned_stop_ != StopReason::kRunning ? planned_stop_ : StopReason::kUserStop);
    } else if (requests == 1 && planned_stop_ == StopReason::kRunning) {
      planned_stop(StopReason::kUserStop, now);
    } else if (config_.duration_s > 0.0 && now - start_s_ >= config_.duration_s &&
               planned_stop_ == StopReason::kRunning) {
      planned_stop(StopReason::kDuration, now);
    }
  }
  return r;
}

void Session::report_output_failure(const std::string& text) {
  {
    const std::lock_guard<std::mutex> lock(output_failure_mutex_);
    if (output_failure_.empty()) output_failure_ = text;
  }
  output_failed_.store(true, std::memory_order_release);
}

void Session::planned_stop(StopReason why, double now) noexcept {
  planned_stop_ = why;
  link_->request_planned_stop(config_.stop_ramp_s);
  if (reporting_) push(SessionEntry::Kind::kHeartbeat, now);
  // A link with nothing to ramp (not started, the program over) stopped at once.
  if (link_->state() == LinkState::kStopped) end(why);
}

void Session::drain_reporter(double now) {
  if (!reporter_) return;
  SessionEntry e;
  while (queue_->pop(e)) reporter_->consume(e);
  reporter_->status_if_due(now);
}

void Session::service() {
  if (reporter_thread_.joinable()) return;  // the reporter's own thread does it
  drain_reporter(clock_.now_s());
}

void Session::reporter_loop() {
  while (!reporter_stop_.load()) {
    drain_reporter(clock_.now_s());
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

StopReason Session::run(double max_s) {
  if (!started_) {
    started_ = true;
    // The reporter's thread first: a thread inherits its creator's scheduling and CPUs, and the
    // reporter (files, the terminal) must stay an ordinary thread on any CPU.
    if (reporting_) reporter_thread_ = std::thread(&Session::reporter_loop, this);
    realtime_ = make_current_thread_realtime(config_.realtime);
  }
  const double until = clock_.now_s() + max_s;
  while (!ended()) {
    (void)poll(0.02);
    if (clock_.now_s() >= until) break;
  }
  return reason_;
}

const std::vector<LinkCycleRecord>& Session::collected() const {
  static const std::vector<LinkCycleRecord> none;
  return reporter_ ? reporter_->collected() : none;
}

std::string Session::ramp_text() const {
  // The link's own sentence when it ramped down (request_planned_stop) before it stopped.
  constexpr std::string_view kRamped = "stopped on request: ";
  const std::string_view said = link_->stop_reason();
  if (link_->stop_cause() != LinkStopCause::kRequested || said.substr(0, kRamped.size()) != kRamped) return {};
  return fmt::format(": {}", said.substr(kRamped.size()));
}

const SessionSummary& Session::finish() {
  if (finished_) return summary_;
  finished_ = true;
  if (!ended()) {
    link_->stop();
    end(StopReason::kUserStop);
  }
  // A stopped link flushes what it still owes the controller (STOP_TRAJECTORY and reading its reply),
  // for at most a few tenths of a second.
  (void)link_->poll(0.0);
  for (int k = 0; k < 30 && link_->winding_down(); ++k) (void)link_->poll(0.01);
  const double now = clock_.now_s();
  // Why, in a sentence.
  switch (reason_) {
    case StopReason::kUserStop:
      reason_text_ = "stopped on request (SIGINT, SIGTERM or the caller)" + ramp_text();
      break;
    case StopReason::kDuration:
      reason_text_ = fmt::format("the session's time limit of {:g} s passed", config_.duration_s) + ramp_text();
      break;
    case StopReason::kStartRefused: {
      std::string joints;
      const JointVector& d = link_->start_distance();
      const double tolerance = config_.link == LinkKind::kSimpleMessage
                                   ? config_.simple_message.stream.start_tolerance_rad
                               : config_.link == LinkKind::kFanucJ519  ? config_.fanuc_j519.stream.start_tolerance_rad
                               : config_.link == LinkKind::kMotoros2Rt ? config_.motoros2_rt.stream.start_tolerance_rad
                               : config_.link == LinkKind::kUrRtde     ? config_.ur_rtde.stream.start_tolerance_rad
                                                                       : config_.egm_joint.stream.start_tolerance_rad;
      for (int j = 0; j < d.size(); ++j) {
        if (d[j] > tolerance) {
          joints += fmt::format("{}joint {} is {:.3f} deg away", joints.empty() ? "" : ", ", j + 1, rad_to_deg(d[j]));
        }
      }
      reason_text_ = fmt::format(
          "refusing to start: the controller reports the arm more than {:g} deg from where the program {} is ({}). "
          "Move the robot to the program's start first; nothing was sent to the controller",
          rad_to_deg(tolerance), program_ ? program_->source() : std::string("?"), joints);
      break;
    }
    case StopReason::kOutputFailed: {
      const std::lock_guard<std::mutex> lock(output_failure_mutex_);
      reason_text_ = output_failure_ + ramp_text();
      break;
    }
    default:
      reason_text_ = link_->stop_reason();
      break;
  }
  if (reporter_) {
    if (reporter_thread_.joinable()) {
      reporter_stop_.store(true);
      reporter_thread_.join();
    }
    drain_reporter(now);
    reporter_->end(now, reason_, reason_text_);
  }
  build_summary();
  return summary_;
}

// The summary: the session's figures, then the same as text (stderr) and as JSON (--summary-json).
void Session::build_summary() {
  gather_summary();
  summary_.text = summary_text();
  summary_.json_text = summary_json();
}

void Session::gather_summary() {
  SessionSummary& s = summary_;
  const ControllerLink& l = *link_;
  const LinkCounters& c = l.counters();
  s.reason = reason_;
  s.exit_code = exit_code(reason_);
  s.reason_text = reason_text_;
  s.link = kind().name;
  s.duration_s = clock_.now_s() - start_s_;
  s.counters = c;
  s.stats = l.cycle_stats();
  s.limits = l.limits();
  s.cycles = s.stats.cycles;
  s.answers = s.stats.sent;
  s.compensator = compensator_->counters();
  const DelayEstimator* delay = l.delay_estimator();
  s.measured_delay_s = delay != nullptr ? delay->mean_s() : std::numeric_limits<double>::quiet_NaN();
  s.log_dropped = dropped_.load();
  if (force_ != nullptr) s.force_source = force_->stats();
  if (reporter_) {
    s.fault_episodes = reporter_->episodes();
    s.faulted_cycles = reporter_->faulted_cycles();
    s.late_answers = reporter_->late_answers();
    s.program_behind_s = reporter_->program_behind_s();
  }
  if (program_) s.program_time_s = l.last_cycle().program_time_s - program_->start_time_s();
  if (reporter_) s.output_error = reporter_->log_error();
  if (s.output_error.empty() && output_failed_.load()) {
    const std::lock_guard<std::mutex> lock(output_failure_mutex_);
    s.output_error = output_failure_;
  }
}

std::string Session::summary_text() const {
  const SessionSummary& s = summary_;
  const ControllerLink& l = *link_;
  const LinkCounters& c = s.counters;
  const bool tcp = s.limits.form == CommandForm::kTcpOffset;
  const std::string invariants =
      tcp ? fmt::format(
                "largest TCP offset {:.4f} mm of the {:g} mm bound, largest step {:.4f} mm ({:.0f}% of its {:.4f} "
                "mm limit)",
                s.stats.max_deviation_m * 1e3, s.limits.tcp_bound_m * 1e3, s.stats.max_step_m * 1e3,
                s.stats.max_step_fraction * 100.0, s.limits.tcp_step_m * 1e3)
          : fmt::format(
                "largest |command - nominal| {:.5f} deg of the {:g} deg bound, largest TCP correction {:.4f} mm of "
                "{:g} mm, largest step {:.5f} deg ({:.0f}% of its limit){}",
                rad_to_deg(s.stats.max_deviation_rad), rad_to_deg(s.limits.joint_bound_rad),
                s.stats.max_deviation_m * 1e3, s.limits.tcp_bound_m * 1e3, rad_to_deg(s.stats.max_step_rad),
                s.stats.max_step_fraction * 100.0,
                s.limits.form == CommandForm::kJointTarget
                    ? fmt::format(", largest |command - program| {:.5f} deg (with the ramp-in blend)",
                                  rad_to_deg(s.stats.max_program_deviation_rad))
                    : std::string());
  std::string text = fmt::format(
      "deflex online: the {} session ended: {} (exit code {}): {}\n"
      "  {} cycles, {} answers in {:.1f} s; rejected datagrams {} (malformed {}, truncated {}, oversized {}, empty {}, "
      "missing header {}, missing joints {}, missing required {}, non-finite {}, duplicate {}, out of order {}, far "
      "ahead {}, sequence out of range {}, beyond limits {}, other sender {}, foreign document {}); superseded {}; "
      "restarts {}; silences ridden through {} (longest {:.3f} s); controller clock jumps {}; guard trips {}; "
      "step-limited cycles {}\n"
      "  on the wire: {}\n",
      s.link, to_string(s.reason), s.exit_code, s.reason_text, s.cycles, s.answers, s.duration_s, c.rejected(),
      c.malformed, c.truncated, c.oversized, c.empty, c.missing_header, c.missing_joints, c.missing_required,
      c.non_finite, c.duplicate, c.out_of_order, c.far_ahead, c.sequence_out_of_range, c.out_of_limits,
      c.foreign_sender, c.foreign_document, c.superseded, c.restarts, c.silences, c.longest_silence_s, c.clock_jumps,
      c.guard_trips, c.step_limited, invariants);
  if (reporter_) text += fmt::format("  timing: {}\n", reporter_->timing_text());
  if (const std::string protocol = l.protocol_summary(); !protocol.empty()) text += fmt::format("  {}\n", protocol);
  text += fmt::format(
      "  measured delay {}; force samples ok {}, fault {}, invalid {}, dropped {}; fault episodes {} ({} faulted "
      "cycles)\n",
      std::isfinite(s.measured_delay_s)
          ? fmt::format("{:.1f} ms", s.measured_delay_s * 1e3)
          : std::string("not measured (the controller reported no setpoint to time its feedback against)"),
      s.compensator.samples_ok, s.compensator.samples_fault, s.compensator.samples_invalid,
      s.compensator.samples_dropped, s.fault_episodes, s.faulted_cycles);
  if (force_ != nullptr) {
    const ForceSourceStats& f = s.force_source;
    text += fmt::format(
        "  force source: {} samples received, {} accepted; {} flagged faulty by the sensor ({} at its range limits, "
        "last status word 0x{:08X}); {} lost, {} out of order, {} duplicates, {} malformed; {} stream re-requests, "
        "{} restarts\n",
        f.received, f.accepted, f.faulty, f.saturated, f.last_status, f.lost, f.out_of_order, f.duplicates, f.malformed,
        f.re_requests, f.restarts);
  }
  if (program_) {
    text += fmt::format("  program {:.2f} of {:.2f} s streamed, {:.2f} s behind real time\n", s.program_time_s,
                        program_->duration_s(), s.program_behind_s);
  }
  if (!config_.log_path.empty() && reporter_) {
    text +=
        fmt::format("  cycle log {}: {} rows{}\n", config_.log_path, reporter_->log_rows(),
                    s.log_dropped > 0
                        ? fmt::format(" ({} cycles never reached it: the disk was slower than the loop)", s.log_dropped)
                        : std::string());
  }
  return text;
}

std::string Session::summary_json() const {
  const SessionSummary& s = summary_;
  const LinkCounters& c = s.counters;
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json j = {{"link", s.link},
                      {"strategy", to_string(config_.strategy)},
                      {"stop_reason", to_string(s.reason)},
                      {"exit_code", s.exit_code},
                      {"reason", s.reason_text},
                      {"duration_s", s.duration_s},
                      {"cycles", s.cycles},
                      {"answers", s.answers},
                      {"counters", counters_json(c)},
                      {"invariants",
                       {{"form", to_string(s.limits.form)},
                        {"max_deviation_deg", rad_to_deg(s.stats.max_deviation_rad)},
                        {"joint_bound_deg", rad_to_deg(s.limits.joint_bound_rad)},
                        {"max_tcp_correction_mm", s.stats.max_deviation_m * 1e3},
                        {"tcp_bound_mm", s.limits.tcp_bound_m * 1e3},
                        {"max_step_deg", rad_to_deg(s.stats.max_step_rad)},
                        {"max_step_mm", s.stats.max_step_m * 1e3},
                        {"max_step_fraction", s.stats.max_step_fraction},
                        {"max_program_deviation_deg", rad_to_deg(s.stats.max_program_deviation_rad)}}},
                      {"measured_delay_ms", number(s.measured_delay_s * 1e3)},
                      {"force_samples",
                       {{"ok", s.compensator.samples_ok},
                        {"fault", s.compensator.samples_fault},
                        {"invalid", s.compensator.samples_invalid},
                        {"dropped", s.compensator.samples_dropped}}},
                      {"fault_episodes", s.fault_episodes},
                      {"faulted_cycles", s.faulted_cycles},
                      {"log", config_.log_path.empty() ? nlohmann::json(nullptr) : nlohmann::json(config_.log_path)},
                      {"log_dropped", s.log_dropped},
                      {"realtime", realtime_.text}};
  j["protobuf_log_messages"] = egm_protobuf_log_messages();  // the EGM codec's messages kept off stderr
  if (reporter_) j["timing"] = reporter_->timing_json();
  if (force_ != nullptr) {
    const ForceSourceStats& f = s.force_source;
    j["force_source"] = {{"received", f.received},         {"accepted", f.accepted},       {"faulty", f.faulty},
                         {"saturated", f.saturated},       {"last_status", f.last_status}, {"lost", f.lost},
                         {"out_of_order", f.out_of_order}, {"duplicates", f.duplicates},   {"malformed", f.malformed},
                         {"re_requests", f.re_requests},   {"restarts", f.restarts}};
  }
  if (program_) {
    j["program"] = {
        {"time_s", s.program_time_s}, {"duration_s", program_->duration_s()}, {"behind_s", s.program_behind_s}};
  }
  // A path that is not UTF-8 (a log folder) is written with U+FFFD rather than refused.
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace deflex::runtime
