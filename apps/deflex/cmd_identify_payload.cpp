// `deflex identify-payload`: the end effector's mass, centre of gravity and the force sensor's bias
// from static poses (docs/online.md, "Payload identification"); with --force-source, one static pose
// read from the sensor itself and added to a poses CSV (--record).
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/identify/payload_identification.hpp"
#include "deflex/online/sensor_config.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/sensors/force_source_spec.hpp"
#include "deflex/sensors/wrench_tare.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::cli {
namespace {

struct PayloadOpts {
  std::string robot, sensor, data, out;
  bool json = false;
  // Recording a pose from a sensor.
  std::string force_source, bind = "127.0.0.1", rdt_calibration, joints_deg, record;
  double rdt_rate_hz = 0.0, window_s = 1.0, max_std_n = 0.5, max_std_nm = 0.05, timeout_s = 3.0;
  bool rdt_buffered = false;
};

// The poses CSV's columns for a robot's joints and a sensor's components.
std::string pose_header(int dof, bool moments) {
  std::string h;
  for (int j = 1; j <= dof; ++j) h += fmt::format("q{}_deg,", j);
  h += "fx_N,fy_N,fz_N";
  if (moments) h += ",mx_Nm,my_Nm,mz_Nm";
  return h;
}

// The rows a poses CSV holds already, after checking that its columns are the ones a recording adds;
// "" for a file that does not exist yet.
std::string existing_poses(const std::string& path, const std::string& header, int& rows) {
  rows = 0;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return "";
  std::string text = read_file_to_update(path, InputKind::kCsvTable, "option --record");
  bool seen_header = false;
  std::size_t line_no = 0;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    start = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line.front() == '#') continue;
    if (!seen_header) {
      if (line != header) {
        throw InputError(fmt::format(
            "option --record: {} line {} has the columns '{}'; a recorded pose adds '{}' (record into a new file)",
            path, line_no, line, header));
      }
      seen_header = true;
    } else {
      ++rows;
    }
  }
  if (!seen_header) throw InputError(fmt::format("option --record: {} holds no header line '{}'", path, header));
  if (!text.empty() && text.back() != '\n') text += '\n';
  return text;
}

OpenedForceSource open_recording_source(const PayloadOpts& o) {
  ForceSourceOptions fo;
  fo.bind_address = o.bind;
  fo.rdt_calibration.spec = o.rdt_calibration;
  fo.rdt_calibration.rate_hz = o.rdt_rate_hz;
  fo.rdt_stream.buffered = o.rdt_buffered;
  return open_force_source(o.force_source, fo);
}

// The window's statistics (expected zero, so the "offset" is the mean reading), read until the window
// is full or refused, or until --timeout-s past its length.
TareResult read_still_window(const PayloadOpts& o, const OpenedForceSource& force, double rate_hz) {
  TareSettings settings;
  settings.window_s = o.window_s;
  settings.max_std_force_n = o.max_std_n;
  settings.max_std_torque_nm = o.max_std_nm;
  WrenchTare window;
  window.start(settings, rate_hz);
  std::cerr << fmt::format("identify-payload: hold the arm still at {} deg for {:g} s; reading {}\n", o.joints_deg,
                           o.window_s, force.description);
  const auto t0 = std::chrono::steady_clock::now();
  const auto deadline = t0 + std::chrono::duration<double>(o.window_s + o.timeout_s);
  ForceSample sample;
  while (window.result().state == TareState::kCollecting) {
    bool any = false;
    while (window.result().state == TareState::kCollecting && force.source->latest(sample)) {
      window.add(sample);
      any = true;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      throw Error(fmt::format(
          "identify-payload: {} gave {} of the {} samples of the window in {:g} s: check the "
          "sensor's rate (--rdt-rate-hz, the sensor configuration's sample_rate_hz) and its stream",
          force.description, window.result().samples, window.result().samples_wanted, o.window_s + o.timeout_s));
    }
    if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return window.result();
}

void require_still_window(const PayloadOpts& o, const TareResult& r) {
  if (r.state == TareState::kDone) return;
  if (r.faulty > 0) {
    throw InputError(
        fmt::format("identify-payload: the pose was not recorded: {} of the window's samples were "
                    "faulty (flagged by the sensor or saturated)",
                    r.faulty));
  }
  throw InputError(fmt::format(
      "identify-payload: the pose was not recorded: the reading moved during the {:g} s window (standard deviation "
      "{:.3f} {:.3f} {:.3f} N, {:.4f} {:.4f} {:.4f} Nm; limits {:g} N, {:g} Nm): hold the arm still and stop the "
      "tool",
      o.window_s, r.std_sensor[0], r.std_sensor[1], r.std_sensor[2], r.std_sensor[3], r.std_sensor[4], r.std_sensor[5],
      o.max_std_n, o.max_std_nm));
}

std::string pose_row(const JointVector& q, int dof, const TareResult& r, bool moments) {
  std::string row;
  for (int j = 0; j < dof; ++j) row += fmt::format("{:.6f},", q[j] * 180.0 / kPi);
  row += fmt::format("{:.6f},{:.6f},{:.6f}", r.mean_sensor[0], r.mean_sensor[1], r.mean_sensor[2]);
  if (moments) row += fmt::format(",{:.7f},{:.7f},{:.7f}", r.mean_sensor[3], r.mean_sensor[4], r.mean_sensor[5]);
  return row;
}

void print_recorded_pose(const PayloadOpts& o, const JointVector& q, const TareResult& r, bool moments, int rows) {
  if (o.json) {
    print_json({{"record", o.record},
                {"poses", rows},
                {"joints_deg", vector_to_json(q * (180.0 / kPi))},
                {"mean_sensor", vector_to_json(r.mean_sensor)},
                {"std_sensor", vector_to_json(r.std_sensor)},
                {"units", "N, N, N, Nm, Nm, Nm (sensor frame, raw)"},
                {"samples", r.samples}});
    return;
  }
  std::cout << fmt::format(
      "pose {} recorded into {}: {:.3f} {:.3f} {:.3f} N{} (mean of {} samples; std up to {:.3f} N)\n", rows, o.record,
      r.mean_sensor[0], r.mean_sensor[1], r.mean_sensor[2],
      moments ? fmt::format(", {:.4f} {:.4f} {:.4f} Nm", r.mean_sensor[3], r.mean_sensor[4], r.mean_sensor[5]) : "",
      r.samples, r.std_sensor.head<3>().maxCoeff());
  if (rows < 6) {
    std::cout << fmt::format(
        "record {} more (6 or more poses that turn the tool about different axes), then: "
        "deflex identify-payload --data {} -o payload.yaml\n",
        6 - rows, o.record);
  } else {
    std::cout << fmt::format("identify with: deflex identify-payload --data {} -o payload.yaml\n", o.record);
  }
}

// --force-source: the arm held still at --joints-deg, the mean raw reading over --window-s (refused
// when the arm or the tool moves, as the tare is), added as one row to --record's poses CSV. The file
// is rewritten whole through a temporary file and renamed into place: a failed recording leaves it
// as it was.
void record_pose(const PayloadOpts& o, int& exit_code) {
  const RobotModel model = load_cli_robot("identify-payload", o.robot);
  const SensorConfig sensor = load_sensor_config_or_defaults(o.sensor);
  const JointVector q = parse_joints_deg(o.joints_deg, model, "--joints-deg");
  const bool moments = sensor.components == 6;
  const std::string header = pose_header(model.dof(), moments);
  int rows = 0;
  const std::string previous = existing_poses(o.record, header, rows);
  OutputFile out(o.record, "option --record");
  if (!(o.window_s > 0.0 && o.window_s <= 60.0)) throw InputError("option --window-s: 0 < s <= 60");
  if (!(o.timeout_s > 0.0 && o.timeout_s <= 60.0)) throw InputError("option --timeout-s: 0 < s <= 60");

  const OpenedForceSource force = open_recording_source(o);
  const double rate_hz = force.sample_rate_hz > 0.0 ? force.sample_rate_hz : sensor.sample_rate_hz;
  const TareResult r = read_still_window(o, force, rate_hz);
  require_still_window(o, r);
  if (previous.empty()) {
    out.write(
        fmt::format("# Static poses for deflex identify-payload, recorded from {}: the raw readings (sensor "
                    "frame, N and Nm) averaged over {:g} s with the arm still\n",
                    force.description, o.window_s));
    out.write(header + "\n");
  } else {
    out.write(previous);
  }
  out.write(pose_row(q, model.dof(), r, moments) + "\n");
  out.commit();
  ++rows;
  print_recorded_pose(o, q, r, moments, rows);
  exit_code = 0;
}

void identify(const PayloadOpts& o, int& exit_code) {
  OutputFile out(o.out, "option -o");  // prepared first: the file written is never one read
  SensorConfig sensor = load_sensor_config_or_defaults(o.sensor);
  const RobotModel model = load_cli_robot("identify-payload", o.robot);
  bool has_moments = false;
  const auto poses = read_payload_observations(o.data, &model, sensor.flange_T_sensor, sensor.crosstalk, has_moments);
  PayloadEstimate e;
  try {
    e = identify_payload(poses, has_moments, sensor.gravity_base_m_s2);
  } catch (const InputError& error) {
    throw InputError(fmt::format("{}: {}", o.data, error.what()));  // the poses that cannot identify it
  }
  sensor.payload_mass_kg = e.mass_kg;
  sensor.payload_cog_sensor_m = e.cog_sensor_m;
  sensor.bias_sensor = e.bias_sensor;
  if (!has_moments) {
    sensor.components = 3;
  }
  // What `online` would refuse is not written: a payload of 2.8e305 kg, a centre of gravity 1 km away.
  sensor.source = o.data + " (identified payload)";
  sensor.validate();
  out.write(fmt::format("# identified by deflex identify-payload from {} ({} static poses)\n", o.data, e.poses));
  out.write(sensor_config_to_yaml(sensor));
  out.commit();
  if (o.json) {
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
                {"output", o.out}});
  } else {
    std::cout << fmt::format(
        "payload from {} static poses:\n  mass {:.4f} kg\n  centre of gravity (sensor frame) {:.2f} {:.2f} {:.2f} "
        "mm{}\n"
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
                             e.force_condition_number, o.out);
  }
  exit_code = 0;
}

void setup_identify_payload(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<PayloadOpts>();
  sub.add_option("--data", o->data,
                 "CSV of static poses: fx_N,fy_N,fz_N[,mx_Nm,my_Nm,mz_Nm] raw readings and the orientation as "
                 "qw,qx,qy,qz (base_R_sensor) or q1_deg..q6_deg (needs the robot and the sensor mount)");
  sub.add_option("-o,--output", o->out,
                 "Sensor YAML to write: the --sensor-config (or defaults) with the payload and "
                 "bias identified");
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--sensor-config", o->sensor,
                 "Sensor YAML giving the crosstalk matrix and the flange-to-sensor mount (and, when recording, the "
                 "number of components and the sample rate)");
  sub.add_flag("--json", o->json, "Print one JSON document on stdout");
  // Recording a pose from the sensor itself.
  sub.add_option(
      "--force-source", o->force_source,
      "Record one static pose from this sensor instead of identifying: rdt:HOST[:PORT], udp:PORT or csv:FILE "
      "(with --joints-deg and --record)");
  sub.add_option("--record", o->record,
                 "With --force-source: the poses CSV the pose is added to (created when missing; q1_deg..,fx_N.. "
                 "columns)");
  sub.add_option("--joints-deg", o->joints_deg, "With --force-source: the joints the arm holds still, deg");
  sub.add_option("--window-s", o->window_s, "With --force-source: the averaging window, s")->capture_default_str();
  sub.add_option("--max-std-N", o->max_std_n,
                 "With --force-source: the largest standard deviation of a force axis over the window (the arm "
                 "moving), N")
      ->capture_default_str();
  sub.add_option("--max-std-Nm", o->max_std_nm,
                 "With --force-source: the largest standard deviation of a torque axis over the window, Nm")
      ->capture_default_str();
  sub.add_option("--timeout-s", o->timeout_s,
                 "With --force-source: how long past the window to wait for its samples, s")
      ->capture_default_str();
  sub.add_option("--bind", o->bind, "udp: the address the port is bound on")->capture_default_str();
  sub.add_option(
      "--rdt-calibration", o->rdt_calibration,
      "rdt: counts to N and Nm: sensor, FILE.xml, http://URL, onrobot-hex or counts:... (docs/rdt-sensors.md)");
  sub.add_option("--rdt-rate-hz", o->rdt_rate_hz, "rdt: the sensor's RDT rate, Hz (default: its page's)");
  sub.add_flag("--rdt-buffered", o->rdt_buffered, "rdt: buffered streaming");
  sub.callback([o, &sub, &exit_code] {
    const char* const record_only[] = {"--record",      "--joints-deg",  "--window-s", "--max-std-N",
                                       "--max-std-Nm",  "--timeout-s",   "--bind",     "--rdt-calibration",
                                       "--rdt-rate-hz", "--rdt-buffered"};
    if (!o->force_source.empty()) {
      if (!o->data.empty() || !o->out.empty()) {
        throw InputError(
            "option --force-source records a pose into --record; identify from the poses in a second "
            "call (--data FILE -o payload.yaml)");
      }
      if (o->record.empty()) throw InputError("option --force-source: give --record FILE, the poses CSV to add to");
      if (o->joints_deg.empty()) throw InputError("option --force-source: give --joints-deg, the joints the arm holds");
      record_pose(*o, exit_code);
      return;
    }
    for (const char* name : record_only) {
      if (sub.get_option(name)->count() > 0)
        throw InputError(fmt::format("option {}: applies with --force-source", name));
    }
    if (o->data.empty()) throw InputError("option --data is required (or --force-source to record a pose)");
    if (o->out.empty()) throw InputError("option -o is required: the sensor YAML to write");
    identify(*o, exit_code);
  });
}

}  // namespace

DEFLEX_COMMAND("identify-payload",
               "Identify the end effector's mass, centre of gravity and the force-sensor bias from static poses (CSV)",
               setup_identify_payload, 41);

}  // namespace deflex::cli
