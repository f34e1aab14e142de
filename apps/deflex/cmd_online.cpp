// Subcommands of the online strategy: `online` (the EGM sensor-side compensator, runs until SIGINT or
// SIGTERM) and `identify-payload` (end-effector mass, centre of gravity and sensor bias from static
// poses).
#include <atomic>
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
#include "deflex/egm/egm_sensor_endpoint.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/online/csv_force_replay.hpp"
#include "deflex/online/payload_identification.hpp"
#include "deflex/online/udp_force_source.hpp"

namespace deflex::cli {
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

void setup_online(CLI::App& sub, int& exit_code) {
  struct Opts {
    std::string robot, sensor, force, log, bind = "127.0.0.1", fault_dump, jacobian_at = "planned";
    int egm_port = -1;
    double period_ms = 4.0, max_joint_deg = 0.5, max_tcp_mm = 5.0, max_rate_deg_s = 3.0, watchdog_ms = 50.0;
    double duration_s = 0.0, status_s = 1.0;
    bool loop = false;
  };
  auto o = std::make_shared<Opts>();
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--sensor-config", o->sensor,
                 "Force-sensor YAML (docs/online.md); default: identity crosstalk, no payload, no bias, at the flange");
  sub.add_option("--egm-port", o->egm_port, "UDP port the controller's EGM messages arrive on (ABB examples: 6510)")
      ->required();
  sub.add_option("--bind", o->bind, "Address to bind the EGM and UDP force ports to (0.0.0.0 for a real cell)")->capture_default_str();
  sub.add_option("--force-source", o->force, "udp:PORT (docs/online.md, UDP force-sample format) or csv:FILE")
      ->required();
  sub.add_flag("--loop", o->loop, "With csv:FILE, replay the file again and again");
  sub.add_option("--period-ms", o->period_ms, "Nominal cycle in ms (4 for EGM, 100 like the paper)")->capture_default_str();
  sub.add_option("--max-joint-correction-deg", o->max_joint_deg, "Bound on each joint's correction, degrees")->capture_default_str();
  sub.add_option("--max-tcp-correction-mm", o->max_tcp_mm, "Bound on the TCP displacement of the correction, mm")->capture_default_str();
  sub.add_option("--max-rate-deg-s", o->max_rate_deg_s, "Bound on each joint's correction rate, deg/s")->capture_default_str();
  sub.add_option("--watchdog-ms", o->watchdog_ms, "No valid force sample for this long: ramp the correction to zero")->capture_default_str();
  sub.add_option("--jacobian-at", o->jacobian_at, "planned (exact compensation form) or feedback")->capture_default_str();
  sub.add_option("--log", o->log, "CSV log of every cycle");
  sub.add_option("--fault-dump", o->fault_dump, "CSV the last cycles are written to when a fault occurs");
  sub.add_option("--duration-s", o->duration_s, "Stop after this many seconds (0: run until SIGINT/SIGTERM)")->capture_default_str();
  sub.add_option("--status-interval-s", o->status_s, "Live status on stderr every this many seconds")->capture_default_str();
  sub.callback([o, &exit_code] {
    const RobotModel model = load_robot_or_builtin(o->robot);
    const SensorConfig sensor = sensor_or_default(o->sensor);
    if (o->egm_port < 0 || o->egm_port > 65535) {
      throw InputError("option --egm-port: must be 0..65535");
    }
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
    if (!std::isfinite(o->duration_s) || o->duration_s < 0.0) {
      throw InputError(fmt::format("option --duration-s: must be a number >= 0 (got {})", o->duration_s));
    }
    OnlineConfig cfg;
    cfg.period_s = o->period_ms * 1e-3;
    cfg.max_joint_correction_rad = deg_to_rad(o->max_joint_deg);
    cfg.max_tcp_correction_m = o->max_tcp_mm * 1e-3;
    cfg.max_correction_rate_rad_s = deg_to_rad(o->max_rate_deg_s);
    cfg.watchdog_s = o->watchdog_ms * 1e-3;
    if (o->jacobian_at == "planned") {
      cfg.jacobian_at = JacobianAt::kPlanned;
    } else if (o->jacobian_at == "feedback") {
      cfg.jacobian_at = JacobianAt::kFeedback;
    } else {
      throw InputError("option --jacobian-at: must be planned or feedback");
    }
    cfg.validate();
    OnlineCompensator comp(model, sensor, cfg);
    std::string source_text;
    const std::unique_ptr<ForceSource> source = make_force_source(o->force, o->loop, o->bind, source_text);
    EgmEndpointConfig ec;
    ec.bind_address = o->bind;
    ec.port = static_cast<std::uint16_t>(o->egm_port);
    EgmSensorEndpoint endpoint(comp, ec);
    endpoint.set_force_source(source.get());

    std::FILE* log = nullptr;
    std::vector<char> log_buffer;
    const int n = model.dof();
    if (!o->log.empty()) {
      log = std::fopen(o->log.c_str(), "w");
      if (log == nullptr) {
        throw Error(fmt::format("{}: cannot write the cycle log", o->log));
      }
      log_buffer.resize(1 << 20);
      std::setvbuf(log, log_buffer.data(), _IOFBF, log_buffer.size());
      std::string header = "t_s,seqno,status";
      for (const char* name : {"q_planned", "q_feedback", "q_command", "dtheta"}) {
        for (int j = 1; j <= n; ++j) {
          header += fmt::format(",{}{}_deg", name, j);
        }
      }
      header += ",fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,compute_us\n";
      std::fputs(header.c_str(), log);
    }

    std::cerr << fmt::format(
        "deflex online: robot {}; sensor {}; force from {}; EGM on {}:{}; period {} ms; bounds {} deg/joint, "
        "{} mm TCP, {} deg/s; watchdog {} ms. Stop with Ctrl-C.\n",
        model.name(), sensor.source, source_text, o->bind, endpoint.port(), o->period_ms, o->max_joint_deg,
        o->max_tcp_mm, o->max_rate_deg_s, o->watchdog_ms);

    g_stop = false;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);

    const auto start = std::chrono::steady_clock::now();
    auto next_status = start + std::chrono::duration<double>(o->status_s);
    double max_compute_s = 0.0, last_t = -1.0, max_gap_s = 0.0;
    std::uint64_t window_cycles = 0;
    const auto print_status = [&](const EgmCycleRecord& r) {
      const EgmCounters& c = endpoint.counters();
      std::cerr << fmt::format(
          "[{:8.1f} s] cycles {} replies {} rejected {} restarts {} | status {} | |F| {:.1f} N | max dtheta {:.4f} deg "
          "| compute max {:.1f} us | gap max {:.1f} ms | force samples ok {} fault {}\n",
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), window_cycles, c.replies,
          c.rejected(), c.restarts, to_string(r.status), r.wrench_base.head<3>().norm(),
          rad_to_deg(r.dtheta.size() > 0 ? r.dtheta.cwiseAbs().maxCoeff() : 0.0), max_compute_s * 1e6,
          max_gap_s * 1e3, comp.counters().samples_ok, comp.counters().samples_fault);
      max_compute_s = 0.0;
      max_gap_s = 0.0;
    };
    const auto on_cycle = [&](const EgmCycleRecord& r) {
      ++window_cycles;
      max_compute_s = std::max(max_compute_s, r.compute_s);
      if (last_t >= 0.0) {
        max_gap_s = std::max(max_gap_s, r.t_s - last_t);
      }
      last_t = r.t_s;
      if (log != nullptr) {
        std::fprintf(log, "%.6f,%u,%d", r.t_s, r.seqno, static_cast<int>(r.status));
        for (const JointVector* q : {&r.q_planned, &r.q_feedback, &r.q_command, &r.dtheta}) {
          for (int j = 0; j < q->size(); ++j) {
            std::fprintf(log, ",%.10g", rad_to_deg((*q)[j]));
          }
        }
        for (int j = 0; j < 6; ++j) {
          std::fprintf(log, ",%.6g", r.wrench_base[j]);
        }
        std::fprintf(log, ",%.2f\n", r.compute_s * 1e6);
      }
      const auto now = std::chrono::steady_clock::now();
      if (now >= next_status) {
        print_status(r);
        next_status = now + std::chrono::duration<double>(o->status_s);
      }
      if (o->duration_s > 0.0 && std::chrono::duration<double>(now - start).count() >= o->duration_s) {
        return false;
      }
      return true;
    };
    // Our own loop over poll() (not endpoint.run()) so that status and the duration limit keep going
    // while no controller is talking to us.
    std::uint64_t cycles = 0;
    while (!g_stop.load()) {
      const EgmPollResult r = endpoint.poll(0.05);
      const auto now = std::chrono::steady_clock::now();
      if (r == EgmPollResult::kReplied || r == EgmPollResult::kNotAnswered) {
        ++cycles;
        if (endpoint.fault_pending() && !o->fault_dump.empty()) {
          endpoint.write_history_csv(o->fault_dump);
          std::cerr << fmt::format("deflex online: fault ({}); last {} cycles written to {}\n",
                                   to_string(endpoint.last_cycle().status), endpoint.history_size(), o->fault_dump);
          endpoint.clear_fault();
        }
        if (!on_cycle(endpoint.last_cycle())) {
          break;
        }
      } else if (now >= next_status) {
        std::cerr << fmt::format("[{:8.1f} s] waiting for EGM messages on port {} (received {}, rejected {})\n",
                                 std::chrono::duration<double>(now - start).count(), endpoint.port(),
                                 endpoint.counters().datagrams, endpoint.counters().rejected());
        next_status = now + std::chrono::duration<double>(o->status_s);
      }
      if (o->duration_s > 0.0 && std::chrono::duration<double>(now - start).count() >= o->duration_s) {
        break;
      }
    }
    if (log != nullptr) {
      std::fflush(log);
      std::fclose(log);
    }
    const EgmCounters& c = endpoint.counters();
    std::cerr << fmt::format(
        "deflex online: stopped after {} cycles: {} replies; rejected packets {} (malformed {}, truncated {}, "
        "oversized {}, missing joints {}, non-finite {}, duplicate {}, out of order {}); restarts {}; force "
        "samples ok {}, fault {}, invalid {}{}\n",
        cycles, c.replies, c.rejected(), c.malformed, c.truncated, c.oversized, c.missing_joints, c.non_finite,
        c.duplicate, c.out_of_order, c.restarts, comp.counters().samples_ok, comp.counters().samples_fault,
        comp.counters().samples_invalid, o->log.empty() ? "" : fmt::format("; log {}", o->log));
    exit_code = 0;
  });
}

void setup_identify_payload(CLI::App& sub, int& exit_code) {
  struct Opts {
    std::string robot, sensor, data, out;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  sub.add_option("--data", o->data,
                 "CSV of static poses: fx_N,fy_N,fz_N[,mx_Nm,my_Nm,mz_Nm] raw readings and the orientation as "
                 "qw,qx,qy,qz (base_R_sensor) or q1_deg..q6_deg (needs the robot and the sensor mount)")
      ->required();
  sub.add_option("-o,--output", o->out, "Sensor YAML to write: the --sensor-config (or defaults) with the payload and "
                                        "bias identified")
      ->required();
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--sensor-config", o->sensor, "Sensor YAML giving the crosstalk matrix and the flange-to-sensor mount");
  sub.add_flag("--json", o->json, "Print one JSON document on stdout");
  sub.callback([o, &exit_code] {
    SensorConfig sensor = sensor_or_default(o->sensor);
    const RobotModel model = load_robot_or_builtin(o->robot);
    bool has_moments = false;
    const auto poses = read_payload_observations(o->data, &model, sensor.flange_T_sensor, sensor.crosstalk, has_moments);
    const PayloadEstimate e = identify_payload(poses, has_moments, sensor.gravity_base_m_s2);
    sensor.payload_mass_kg = e.mass_kg;
    sensor.payload_cog_sensor_m = e.cog_sensor_m;
    sensor.bias_sensor = e.bias_sensor;
    if (!has_moments) {
      sensor.components = 3;
    }
    std::ofstream out(o->out);
    if (!out) {
      throw Error(fmt::format("{}: cannot write", o->out));
    }
    out << fmt::format("# identified by deflex identify-payload from {} ({} static poses)\n", o->data, e.poses)
        << sensor_config_to_yaml(sensor);
    if (o->json) {
      print_json({{"mass_kg", e.mass_kg},
                  {"cog_sensor_m", vector_to_json(e.cog_sensor_m)},
                  {"bias_sensor", vector_to_json(e.bias_sensor)},
                  {"bias_units", "N, N, N, Nm, Nm, Nm (sensor frame)"},
                  {"moments_used", e.moments_used},
                  {"poses", e.poses},
                  {"force_residual_rms_N", e.force_residual_rms_N},
                  {"moment_residual_rms_Nm", e.moment_residual_rms_Nm},
                  {"force_condition_number", e.force_condition_number},
                  {"moment_condition_number", e.moment_condition_number},
                  {"output", o->out}});
    } else {
      std::cout << fmt::format(
          "payload from {} static poses:\n  mass {:.4f} kg\n  centre of gravity (sensor frame) {:.2f} {:.2f} {:.2f} mm{}\n"
          "  force bias {:.3f} {:.3f} {:.3f} N\n",
          e.poses, e.mass_kg, e.cog_sensor_m.x() * 1e3, e.cog_sensor_m.y() * 1e3, e.cog_sensor_m.z() * 1e3,
          e.moments_used ? "" : " (not identified: no moment columns)", e.bias_sensor[0], e.bias_sensor[1],
          e.bias_sensor[2]);
      if (e.moments_used) {
        std::cout << fmt::format("  moment bias {:.4f} {:.4f} {:.4f} Nm\n", e.bias_sensor[3], e.bias_sensor[4],
                                 e.bias_sensor[5]);
      }
      std::cout << fmt::format("  residual RMS {:.3f} N{}; condition number {:.1f}\nwrote {}\n", e.force_residual_rms_N,
                               e.moments_used ? fmt::format(", {:.4f} Nm", e.moment_residual_rms_Nm) : "",
                               e.force_condition_number, o->out);
    }
    exit_code = 0;
  });
}

}  // namespace

DEFLEX_COMMAND("online",
               "Online compensation: condition force samples and answer ABB EGM messages with compensated joints "
               "(runs until SIGINT/SIGTERM)",
               setup_online, 40);
DEFLEX_COMMAND("identify-payload",
               "Identify the end effector's mass, centre of gravity and the force-sensor bias from static poses (CSV)",
               setup_identify_payload, 41);

}  // namespace deflex::cli
