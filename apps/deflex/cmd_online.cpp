// `deflex online`: deflex on a controller link (ABB EGM position guidance or path correction, KUKA
// RSI axis correction ...); runs until the session ends, SIGINT or SIGTERM; its field log through
// field_log.hpp, its status and summary through online_report.hpp.
#include <atomic>
#include <cinttypes>
#include <cmath>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "fault_dump.hpp"
#include "field_log.hpp"
#include "online_links.hpp"
#include "online_report.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/online/csv_force_replay.hpp"
#include "deflex/online/udp_force_source.hpp"
#include "deflex/wire/egm_codec.hpp"

namespace deflex::cli {

std::vector<LinkKindInfo>& link_kind_registry() {
  static std::vector<LinkKindInfo> registry;
  return registry;
}

LinkKindRegistrar::LinkKindRegistrar(LinkKindInfo info) { link_kind_registry().push_back(std::move(info)); }

namespace {

const char* const kRobotHelp = "Robot file (.yaml deflex format or .urdf); default: the built-in ABB IRB 6700-300/2.70";

std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int /*signal*/) { g_stop.store(true); }

SensorConfig sensor_or_default(const std::string& path) {
  if (path.empty()) {
    SensorConfig c;  // identity crosstalk, no payload, no bias, sensor at the flange
    c.source = "<default sensor: identity crosstalk, no payload, no bias>";
    return c;
  }
  return load_sensor_config(path);
}

std::unique_ptr<ForceSource> make_force_source(const std::string& spec, bool loop, const std::string& bind,
                                               std::string& description) {
  const std::size_t colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "udp" && !arg.empty()) {
    const double port = parse_numbers(arg, "--force-source", 1)[0];
    if (port < 0 || port > 65535 || port != std::floor(port)) {
      throw InputError(fmt::format("option --force-source: '{}' is not a UDP port", arg));
    }
    auto src = std::make_unique<UdpForceSource>(static_cast<std::uint16_t>(port), bind);
    description = fmt::format("UDP force samples on port {}", src->port());
    return src;
  }
  if (kind == "csv" && !arg.empty()) {
    auto src = std::make_unique<CsvForceReplay>(arg, loop);
    description = fmt::format("CSV replay of {} ({} samples{})", arg, src->size(), loop ? ", looped" : "");
    return src;
  }
  throw InputError(fmt::format("option --force-source: '{}' is not udp:PORT or csv:FILE", spec));
}

// The per-cycle CSV log (degrees, mm, N, microseconds), written outside the link's cycle.
class CycleLog {
 public:
  CycleLog(const std::string& path, int joints) : joints_(joints) {
    if (path.empty()) return;
    file_ = std::fopen(path.c_str(), "w");
    if (file_ == nullptr) {
      throw Error(fmt::format("{}: cannot write the cycle log", path));
    }
    buffer_.resize(1 << 20);
    std::setvbuf(file_, buffer_.data(), _IOFBF, buffer_.size());
    std::string header = "t_s,program_t_s,sequence,status";
    for (const char* name : {"q_nominal", "q_feedback", "q_command", "dtheta"}) {
      for (int j = 1; j <= joints; ++j) header += fmt::format(",{}{}_deg", name, j);
    }
    header += ",corr_x_mm,corr_y_mm,corr_z_mm,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,delay_ms,compute_us";
    // How the cycle's message arrived, and the link's running counts at that cycle.
    header += ",replied,stamp_ms,arrival_delay_ms,jitter_ms,missed_before,duplicates,superseded,rejected,restarts,late,"
              "controller_late\n";
    std::fputs(header.c_str(), file_);
  }
  ~CycleLog() {
    if (file_ != nullptr) std::fclose(file_);
  }
  CycleLog(const CycleLog&) = delete;
  CycleLog& operator=(const CycleLog&) = delete;
  void write(const LinkCycleRecord& r, const LinkCounters& c) {
    if (file_ == nullptr) return;
    std::fprintf(file_, "%.6f,%.9f,%" PRIu64 ",%d", r.t_s, r.program_time_s, r.sequence, static_cast<int>(r.status));
    for (const JointVector* q : {&r.q_nominal, &r.q_feedback, &r.q_command, &r.dtheta}) {
      for (int j = 0; j < joints_ && j < q->size(); ++j) std::fprintf(file_, ",%.10g", rad_to_deg((*q)[j]));
    }
    std::fprintf(file_, ",%.6f,%.6f,%.6f", r.tcp_correction_m.x() * 1e3, r.tcp_correction_m.y() * 1e3,
                 r.tcp_correction_m.z() * 1e3);
    for (int j = 0; j < 6; ++j) std::fprintf(file_, ",%.6g", r.wrench_base[j]);
    std::fprintf(file_, ",%.2f,%.2f", r.delay_s * 1e3, r.compute_s * 1e6);
    std::fprintf(file_, ",%d,%.0f,%.3f,%.3f,%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%" PRIu64
                        ",%" PRIu64 "\n",
                 r.replied ? 1 : 0, r.arrival.stamp_s * 1e3, r.arrival.arrival_delay_s * 1e3, r.arrival.jitter_s * 1e3,
                 r.arrival.missed_before, c.duplicate, c.superseded, c.rejected(), c.restarts, c.late,
                 c.controller_late);
  }

 private:
  std::FILE* file_ = nullptr;
  std::vector<char> buffer_;
  int joints_;
};


std::string refusal_text(const ControllerLink& link, const JointTrajectory& program, double tolerance_deg) {
  std::string joints;
  const JointVector& d = link.start_distance();
  for (int j = 0; j < d.size(); ++j) {
    if (rad_to_deg(d[j]) > tolerance_deg) {
      joints += fmt::format("{}joint {} is {:.3f} deg away", joints.empty() ? "" : ", ", j + 1, rad_to_deg(d[j]));
    }
  }
  return fmt::format(
      "deflex online: refusing to start: the controller reports the arm more than {:g} deg from where the program "
      "{} is ({}). Move the robot to the program's start first; nothing was sent to the controller.",
      tolerance_deg, program.source(), joints);
}

std::string link_names() {
  std::string names;
  for (const auto& k : link_kind_registry()) names += (names.empty() ? "" : ", ") + k.name;
  return names;
}

void setup_online(CLI::App& sub, int& exit_code) {
  struct Opts {
    std::string link, robot, sensor, force_source, program, strategy = "online", force_model, log, bind = "127.0.0.1",
        fault_dump, jacobian_at = "nominal";
    double period_ms = 4.0, max_joint_deg = 0.5, max_tcp_mm = 5.0, max_rate_deg_s = 3.0, watchdog_ms = 50.0;
    double end_silence_s = 2.0, duration_s = 0.0, status_s = 1.0;
    bool loop = false, json = false;
    LogOptions log_options;
  };
  auto o = std::make_shared<Opts>();
  std::string link_help = "Controller link:";
  for (const auto& k : link_kind_registry()) link_help += fmt::format(" {} ({});", k.name, k.help);
  sub.add_option("--link", o->link, link_help)->required();
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--sensor-config", o->sensor,
                 "Force-sensor YAML (docs/online.md); default: identity crosstalk, no payload, no bias, at the flange");
  sub.add_option("--bind", o->bind, "Address to bind the link's and the UDP force port to (0.0.0.0 for a real cell)")
      ->capture_default_str();
  sub.add_option("--force-source", o->force_source, "udp:PORT (docs/online.md, UDP force-sample format) or csv:FILE")
      ->required();
  sub.add_flag("--loop", o->loop, "With csv:FILE, replay the file again and again");
  sub.add_option("--program", o->program,
                 "Streaming links: the nominal joint trajectory deflex streams, CSV t_s,q1_deg..qN_deg (deflex offline "
                 "--nominal-trajectory / --joint-trajectory write one)");
  sub.add_option("--strategy", o->strategy,
                 "online (the paper's), hybrid (--program is the offline-compensated one; corrects measured minus "
                 "--force), predictive (wrench predicted where the command is executed), none (stream only)")
      ->capture_default_str();
  sub.add_option("--force", o->force_model,
                 "Force model of the process, a pose model: ldbb:pivot_mm=X;Y;Z,force_N=F,mode=push|pull or "
                 "constant:fx_N=.. (hybrid: required; predictive: optional)");
  sub.add_option("--period-ms", o->period_ms,
                 "The controller's cycle in ms (egm-joint: 4; egm-path: the EGMActMove SampleRate; simple-message: "
                 "the point cycle, the paper's 100)")
      ->capture_default_str();
  sub.add_option("--max-joint-correction-deg", o->max_joint_deg,
                 "Bound on each joint's correction, degrees: no command leaves the nominal by more")
      ->capture_default_str();
  sub.add_option("--max-tcp-correction-mm", o->max_tcp_mm, "Bound on the TCP displacement of the correction, mm")
      ->capture_default_str();
  sub.add_option("--max-rate-deg-s", o->max_rate_deg_s, "Bound on each joint's correction rate, deg/s")
      ->capture_default_str();
  sub.add_option("--watchdog-ms", o->watchdog_ms, "No valid force sample for this long: ramp the correction to zero")
      ->capture_default_str();
  sub.add_option("--jacobian-at", o->jacobian_at, "nominal (the configuration the command is for) or feedback")
      ->capture_default_str();
  sub.add_option("--end-silence-s", o->end_silence_s,
                 "Streaming links: after the program's end, a controller silence this long ends the session, s")
      ->capture_default_str();
  sub.add_option("--log", o->log, "CSV log of every cycle");
  sub.add_option("--fault-dump", o->fault_dump,
                 "CSV the last cycles are written to, once per fault episode (checked for writability at start)");
  sub.add_flag("--json", o->json, "At the end, print one JSON document of the counters and timing on stdout");
  add_log_options(sub, o->log_options);
  sub.add_option("--duration-s", o->duration_s, "Stop after this many seconds (0: run until SIGINT/SIGTERM)")
      ->capture_default_str();
  sub.add_option("--status-interval-s", o->status_s, "Live status on stderr every this many seconds")
      ->capture_default_str();
  for (const auto& k : link_kind_registry()) k.add_options(sub);
  sub.callback([o, &exit_code] {
    const LinkKindInfo* kind_info = nullptr;
    for (const auto& k : link_kind_registry()) {
      if (k.name == o->link) kind_info = &k;
    }
    if (kind_info == nullptr) {
      throw InputError(fmt::format("option --link: '{}' is not one of {}", o->link, link_names()));
    }
    const RobotModel model = load_cli_robot("online", o->robot);
    const SensorConfig sensor = sensor_or_default(o->sensor);
    const auto positive = [](double v, const char* option) {
      if (!std::isfinite(v) || !(v > 0.0)) {
        throw InputError(fmt::format("option {}: must be a number > 0 (got {})", option, v));
      }
    };
    positive(o->period_ms, "--period-ms");
    positive(o->max_joint_deg, "--max-joint-correction-deg");
    positive(o->max_tcp_mm, "--max-tcp-correction-mm");
    positive(o->max_rate_deg_s, "--max-rate-deg-s");
    positive(o->watchdog_ms, "--watchdog-ms");
    positive(o->status_s, "--status-interval-s");
    positive(o->end_silence_s, "--end-silence-s");
    if (!std::isfinite(o->duration_s) || o->duration_s < 0.0) {
      throw InputError(fmt::format("option --duration-s: must be a number >= 0 (got {})", o->duration_s));
    }
    if (o->period_ms > 1000.0) throw InputError("option --period-ms: at most 1000 ms");
    if (o->max_joint_deg > 10.0) {
      throw InputError("option --max-joint-correction-deg: at most 10 deg (a compliance correction is a fraction of one)");
    }
    const StrategyKind kind = parse_strategy(o->strategy);
    if (kind_info->streams_program && o->program.empty()) {
      throw InputError(fmt::format("option --program: {} streams a nominal program: give --program P.csv (deflex "
                                   "offline --nominal-trajectory writes one)",
                                   kind_info->name));
    }
    if (!kind_info->streams_program && !o->program.empty()) {
      throw InputError(fmt::format("option --program: {} corrects the controller's own program; deflex streams none",
                                   kind_info->name));
    }
    OnlineConfig cfg;
    cfg.period_s = o->period_ms * 1e-3;
    cfg.max_joint_correction_rad = deg_to_rad(o->max_joint_deg);
    cfg.max_tcp_correction_m = o->max_tcp_mm * 1e-3;
    cfg.max_correction_rate_rad_s = deg_to_rad(o->max_rate_deg_s);
    cfg.watchdog_s = o->watchdog_ms * 1e-3;
    if (o->jacobian_at == "nominal" || o->jacobian_at == "planned") {
      cfg.jacobian_at = JacobianAt::kPlanned;
    } else if (o->jacobian_at == "feedback") {
      cfg.jacobian_at = JacobianAt::kFeedback;
    } else {
      throw InputError("option --jacobian-at: must be nominal or feedback");
    }
    cfg.validate();
    std::unique_ptr<ForceModel> force_model;
    if (!o->force_model.empty()) {
      force_model = parse_force_spec(o->force_model);
    }
    OnlineCompensator comp(model, sensor, cfg);
    OnlineStrategy strategy(model, kind, force_model.get());
    std::shared_ptr<const JointTrajectory> program;
    if (kind_info->streams_program) {
      program = std::make_shared<const JointTrajectory>(JointTrajectory::read_csv(o->program, model));
    }
    const auto log = make_field_logger("online", o->log_options);
    // The fault dump's path is checked now, not at the first fault in the middle of a run; an episode
    // ends after twice the compensator's fault hold without a fault.
    FaultDump fault_dump(o->fault_dump, 2.0 * cfg.fault_hold_s, log);
    std::string source_text;
    const std::unique_ptr<ForceSource> source = make_force_source(o->force_source, o->loop, o->bind, source_text);
    SteadyClock clock;
    const OnlineContext context{model, comp, strategy, source.get(), clock, o->bind, program, cfg.period_s};
    const std::unique_ptr<LinkSession> session = kind_info->make(context);
    ControllerLink& link = session->link();
    CycleLog cycle_log(o->log, model.dof());
    if (kind_info->streams_program && !model.has_max_speed()) {
      log->warn("the robot file gives no joint speed limits, so the program's speeds were not checked (add max_speed "
                "to the robot file)");
    }

    log->info(
        "deflex online: {} link, strategy {}; robot {}; sensor {}; force from {}; {}; {}bounds {} deg/joint, {} mm TCP, "
        "{} deg/s; watchdog {} ms; period {} ms. Stop with Ctrl-C.",
        link.name(), to_string(kind), model.name(), sensor.source, source_text, session->where(),
        program ? fmt::format("program {} ({} points, {:.1f} s); ", o->program, program->size(), program->duration_s())
                : "",
        o->max_joint_deg, o->max_tcp_mm, o->max_rate_deg_s, o->watchdog_ms, o->period_ms);

    g_stop = false;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);

    const double start = clock.now_s();
    double next_status = start + o->status_s, last_message = -1.0;
    OnlineReport report(start);
    bool refused = false, stopped = false;
    // Our own loop over poll(), so that status and the duration limit keep going while no controller
    // is talking to us. Everything between two polls (log lines, the CSV row, a fault dump's copy)
    // is outside the cycle.
    while (!g_stop.load()) {
      const LinkPollResult r = link.poll(0.05);
      const double now = clock.now_s();
      if (r == LinkPollResult::kRefused) {
        refused = true;
        break;
      }
      if (r == LinkPollResult::kStopped) {  // a streaming link stopped the motion for a fault
        stopped = true;
        break;
      }
      if (r == LinkPollResult::kAnswered || r == LinkPollResult::kNotAnswered) {
        last_message = now;
        const LinkCycleRecord& rec = link.last_cycle();
        report.on_cycle(rec);
        cycle_log.write(rec, link.counters());
        fault_dump.on_cycle(now, link);
      }
      if (now >= next_status) {
        if (link.state() == LinkState::kWaiting) {
          log->info("waiting for the controller ({}; received {}, rejected {})", session->where(),
                    link.counters().datagrams, link.counters().rejected());
        } else {
          log->info("{}", report.status_line(now, now - start, link, session->status()));
        }
        next_status = now + o->status_s;
      }
      if (link.state() == LinkState::kFinished && last_message >= 0.0 && now - last_message > o->end_silence_s) {
        log->info("the program has ended and the controller went quiet: session over");
        break;
      }
      if (o->duration_s > 0.0 && now - start >= o->duration_s) {
        break;
      }
    }
    // A streaming link stops the controller's motion now (simple message: STOP_TRAJECTORY on Ctrl-C,
    // SIGTERM, --duration-s or the end of the session); the others have nothing to stop.
    link.stop();
    fault_dump.finish(clock.now_s());
    if (refused) {
      log->error("{}", refusal_text(link, *program, 1.0));
      exit_code = 2;
      return;
    }
    if (stopped) {
      if (!o->fault_dump.empty()) link.write_history_csv(o->fault_dump);
      log->error("the {} link stopped the robot's motion ({}): {}{}", link.name(), to_string(link.stop_cause()),
                 link.stop_reason(),
                 o->fault_dump.empty() ? "" : fmt::format("; last cycles written to {}", o->fault_dump));
    }
    const LinkCounters& c = link.counters();
    const std::string extra = session->summary();
    const std::uint64_t protobuf_lines = egm_protobuf_log_messages();
    log->info(
        "deflex online: stopped after {} cycles: {} answers; rejected datagrams {} (malformed {}, truncated {}, "
        "oversized {}, empty {}, missing header {}, missing joints {}, missing required {}, non-finite {}, duplicate {}, "
        "out of order {}, far ahead {}, sequence out of range {}, beyond limits {}, other sender {}, foreign document "
        "{}); superseded {}; restarts {}; guard stops {}; fault episodes {} ({} faulted cycles); force samples ok {}, "
        "fault {}, invalid {}; {}{}{}{}{}",
        report.cycles(), c.replies, c.rejected(), c.malformed, c.truncated, c.oversized, c.empty, c.missing_header,
        c.missing_joints, c.missing_required, c.non_finite, c.duplicate, c.out_of_order, c.far_ahead,
        c.sequence_out_of_range, c.out_of_limits, c.foreign_sender, c.foreign_document, c.superseded, c.restarts,
        c.guard_trips, fault_dump.episodes(), fault_dump.faulted_cycles(), comp.counters().samples_ok,
        comp.counters().samples_fault, comp.counters().samples_invalid, report.timing_text(link),
        extra.empty() ? "" : "; ", extra, protobuf_lines > 0 ? fmt::format("; protobuf messages {}", protobuf_lines) : "",
        o->log.empty() ? "" : fmt::format("; log {}", o->log));
    if (o->json) {
      nlohmann::json doc = report.json(link);
      doc["link"] = link.name();
      doc["strategy"] = to_string(kind);
      doc["duration_s"] = clock.now_s() - start;
      doc["fault_episodes"] = fault_dump.episodes();
      doc["faulted_cycles"] = fault_dump.faulted_cycles();
      doc["force_samples"] = {{"ok", comp.counters().samples_ok},
                              {"fault", comp.counters().samples_fault},
                              {"invalid", comp.counters().samples_invalid},
                              {"dropped", comp.counters().samples_dropped}};
      doc["protobuf_log_messages"] = protobuf_lines;
      doc["log"] = o->log.empty() ? nlohmann::json(nullptr) : nlohmann::json(o->log);
      print_json(doc);
    }
    // What the controller sent that the protocol does not allow is bad input (2); a lost connection, a
    // refusing or faulted controller, a safety stop: the job failed (1).
    exit_code = !stopped ? 0 : link.stop_cause() == LinkStopCause::kProtocol ? 2 : 1;
  });
}

}  // namespace

DEFLEX_COMMAND("online",
               "Online compensation on a controller link (--link egm-joint|egm-path|...): condition force samples and "
               "answer the controller, never beyond the bound of the nominal",
               setup_online, 40);

}  // namespace deflex::cli
