// `deflex identify-payload`: the end effector's mass, centre of gravity and the force sensor's bias
// from static poses (docs/online.md, "Payload identification").
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/model/output_file.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/online/payload_identification.hpp"
#include "deflex/online/sensor_config.hpp"

namespace deflex::cli {
namespace {

const char* const kRobotHelp = "Robot file (.yaml deflex format or .urdf); default: the built-in ABB IRB 6700-300/2.70";

SensorConfig sensor_or_default(const std::string& path) {
  if (path.empty()) {
    SensorConfig c;  // identity crosstalk, no payload, no bias, sensor at the flange
    c.source = "<default sensor: identity crosstalk, no payload, no bias>";
    return c;
  }
  return load_sensor_config(path);
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
    OutputFile out(o->out, "option -o");  // prepared first: the file written is never one read
    SensorConfig sensor = sensor_or_default(o->sensor);
    const RobotModel model = load_cli_robot("identify-payload", o->robot);
    bool has_moments = false;
    const auto poses = read_payload_observations(o->data, &model, sensor.flange_T_sensor, sensor.crosstalk, has_moments);
    PayloadEstimate e;
    try {
      e = identify_payload(poses, has_moments, sensor.gravity_base_m_s2);
    } catch (const InputError& error) {
      throw InputError(fmt::format("{}: {}", o->data, error.what()));  // the poses that cannot identify it
    }
    sensor.payload_mass_kg = e.mass_kg;
    sensor.payload_cog_sensor_m = e.cog_sensor_m;
    sensor.bias_sensor = e.bias_sensor;
    if (!has_moments) {
      sensor.components = 3;
    }
    // What `online` would refuse is not written: a payload of 2.8e305 kg, a centre of gravity 1 km away.
    sensor.source = o->data + " (identified payload)";
    sensor.validate();
    out.write(fmt::format("# identified by deflex identify-payload from {} ({} static poses)\n", o->data, e.poses));
    out.write(sensor_config_to_yaml(sensor));
    out.commit();
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

DEFLEX_COMMAND("identify-payload",
               "Identify the end effector's mass, centre of gravity and the force-sensor bias from static poses (CSV)",
               setup_identify_payload, 41);

}  // namespace deflex::cli
