// `deflex offline`: compensate a planned path for a force model and write the CSV, the RAPID module
// and a summary (paper, Figure 2).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/offline/offline_csv.hpp"
#include "deflex/offline/offline_job.hpp"
#include "deflex/offline/offline_summary.hpp"
#include "deflex/offline/program_compensation.hpp"
#include "deflex/offline/rapid_module.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/paths/pose_source.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"
#include "offline_toolpath.hpp"

namespace deflex::cli {
namespace {

struct OfflineOpts {
  std::string robot, stiffness, circle, line, path_csv, orientation = "0,0,1,0", config, seed, csv_out, rapid_out;
  std::string trajectory_out, nominal_trajectory_out;
  double hold_start_s = 0.0;
  std::vector<std::string> forces;
  std::string program_in, program_out;
  std::vector<std::string> tooldata, wobjdata;
  std::string motion = "absj", zone = "fine", tool = "tool0", wobj = "wobj0", module = "DeflexOffline";
  double speed_mm_s = 10.0;
  bool circle_given = false, orientation_given = false, json = false;
  // --toolpath
  std::string toolpath, workpiece, cutter, stock, tool_spin = "optimize", toolpath_options, plot_out;
  bool zone_given = false, wobj_given = false, module_given = false, speed_given = false, motion_given = false;
};

nlohmann::json program_json(const RobotModel& model, const ProgramCompensation& result) {
  nlohmann::json targets = nlohmann::json::array();
  for (const ProgramTargetReport& t : result.targets) {
    targets.push_back({{"file", t.file},
                       {"line", t.line},
                       {"instruction", t.instruction},
                       {"target", t.target},
                       {"action", t.action},
                       {"configuration", t.configuration_note},
                       {"deflection_mm", t.deflection_m * 1e3},
                       {"deflection_mrad", t.deflection_rad * 1e3},
                       {"correction_mm", t.correction_m * 1e3},
                       {"joint_correction_deg", rad_to_deg(t.joint_correction_rad)},
                       {"wrench_base_N_Nm",
                        {t.wrench_base[0], t.wrench_base[1], t.wrench_base[2], t.wrench_base[3], t.wrench_base[4],
                         t.wrench_base[5]}}});
  }
  nlohmann::json unresolved = nlohmann::json::array();
  for (const UnresolvedConstruct& u : result.unresolved) {
    unresolved.push_back({{"file", u.file}, {"line", u.line}, {"text", u.text}, {"reason", u.reason}});
  }
  nlohmann::json outputs = nlohmann::json::array();
  for (const ProgramFile& f : result.outputs) {
    outputs.push_back(f.path);
  }
  return {{"robot", model.name()}, {"language", result.language}, {"force", result.force_description},
          {"targets", targets},    {"unresolved", unresolved},    {"outputs", outputs}};
}

/// --program-in: an existing RAPID or KRL program compensated target by target. The outputs are
/// prepared before the program is read, so an output that is an input is refused first.
void run_program(const OfflineOpts& o, int& exit_code) {
  if (o.program_out.empty()) {
    throw InputError("option --program-in needs --program-out FILE (the input is never overwritten)");
  }
  if (!o.csv_out.empty() || !o.rapid_out.empty() || !o.trajectory_out.empty() || !o.nominal_trajectory_out.empty()) {
    throw InputError(
        "options -o, --rapid, --joint-trajectory and --nominal-trajectory write a new path's files; "
        "with --program-in the output is --program-out");
  }
  if (!o.config.empty()) {
    throw InputError(
        "option --config: with --program-in every target carries its own configuration (confdata, Status and "
        "Turn); --seed-deg gives the arm's joints at the start");
  }
  OutputTransaction outputs;
  std::vector<OutputFile*> files;
  for (const std::string& path : program_output_paths(o.program_in, o.program_out)) {
    files.push_back(&outputs.add(path, files.empty() ? "option --program-out" : "the data list beside --program-out"));
  }
  const RobotModel model = load_cli_robot("offline", o.robot, o.stiffness);
  require_stiffness(model);
  std::vector<std::unique_ptr<ForceModel>> forces;
  for (const std::string& spec : o.forces) {
    for (auto& m : parse_force_specs(spec, {})) {
      forces.push_back(std::move(m));
    }
  }
  if (forces.size() != 1) {
    throw InputError(
        fmt::format("--program-in compensates for one load: the --force options describe {}", forces.size()));
  }
  ProgramOptions options;
  options.tooldata = o.tooldata;
  options.wobjdata = o.wobjdata;
  if (!o.seed.empty()) options.start_q = parse_joints_deg(o.seed, model, "--seed-deg");
  const ProgramCompensation result = compensate_program(model, *forces.front(), o.program_in, o.program_out, options);
  for (const ProgramFile& f : result.outputs) {
    for (OutputFile* file : files) {
      if (file->path() == f.path) {
        file->write(f.text);
      }
    }
  }
  outputs.commit();  // only once every target has been resolved and compensated: all files or none
  if (!o.json) {
    std::cout << "robot: " << model.name() << "\n" << program_summary(result);
    exit_code = 0;
    return;
  }
  print_json(program_json(model, result));
  exit_code = 0;
}

/// The pose source of --circle, --line or --path, and its description for the outputs.
std::unique_ptr<PoseSource> make_pose_source(const OfflineOpts& o, const std::optional<CirclePath>& circle,
                                             std::string& path_text) {
  if (!o.path_csv.empty()) {
    if (o.orientation_given) {
      std::cerr << "deflex offline: warning: --orientation-wxyz is ignored: the path file gives the orientation\n";
    }
    path_text = fmt::format("poses from {}", o.path_csv);
    return std::make_unique<PoseCsvSource>(o.path_csv);
  }
  const auto qv = parse_numbers(o.orientation, "--orientation-wxyz", 4, range::kUnitQuaternion);
  const Eigen::Quaterniond orientation =
      checked_unit_quaternion(Eigen::Quaterniond(qv[0], qv[1], qv[2], qv[3]), "option --orientation-wxyz", 1e-3);
  if (o.circle_given) {
    const CirclePath& c = *circle;
    path_text = fmt::format(
        "circle centre ({:.1f}, {:.1f}, {:.1f}) mm, radius {:.1f} mm, normal ({:g}, {:g}, {:g}), "
        "{}, {} points",
        c.centre_m.x() * 1e3, c.centre_m.y() * 1e3, c.centre_m.z() * 1e3, c.radius_m * 1e3, c.normal.x(), c.normal.y(),
        c.normal.z(), c.clockwise ? "clockwise" : "counter-clockwise", c.points);
    return std::make_unique<CirclePoseSource>(c, orientation);
  }
  const LinePath l = parse_line_spec(o.line);
  path_text = fmt::format("line from ({:.1f}, {:.1f}, {:.1f}) mm to ({:.1f}, {:.1f}, {:.1f}) mm, {} points",
                          l.start_m.x() * 1e3, l.start_m.y() * 1e3, l.start_m.z() * 1e3, l.end_m.x() * 1e3,
                          l.end_m.y() * 1e3, l.end_m.z() * 1e3, l.points);
  return std::make_unique<LinePoseSource>(l, orientation);
}

/// The first point's IK request from --config and --seed-deg.
IkRequest first_ik_request(const OfflineOpts& o, const RobotModel& model) {
  IkRequest first;
  if (!o.config.empty()) {
    const auto c = parse_numbers(o.config, "--config", 4);
    for (const double v : c) {
      // Whole numbers only (2.5 was cut to 2), and small enough that the cast to int is defined.
      if (v != std::floor(v) || std::abs(v) > 1000.0) {
        throw InputError(fmt::format(
            "option --config: '{}' is not four whole numbers cf1,cf4,cf6,cfx (quadrant numbers, at most 1000 in size)",
            o.config));
      }
    }
    if (c[3] < 0 || c[3] > 7) {
      throw InputError("option --config: cfx must be 0..7");
    }
    first.configuration = ArmConfiguration{static_cast<int>(c[0]), static_cast<int>(c[1]), static_cast<int>(c[2]),
                                           static_cast<int>(c[3])};
  }
  if (!o.seed.empty()) {
    first.seed = parse_joints_deg(o.seed, model, "--seed-deg");
  }
  return first;
}

RapidOptions rapid_options(const OfflineOpts& o) {
  RapidOptions rapid;
  rapid.motion = parse_rapid_motion(o.motion, "option --motion");
  rapid.speed_mm_s = o.speed_mm_s;
  rapid.zone = o.zone;
  rapid.tool = o.tool;
  rapid.wobj = o.wobj;
  if (!o.rapid_out.empty()) {
    rapid.module_name = o.module;
    check_rapid_options(rapid);  // before anything is computed or written
  }
  return rapid;
}

/// One load's run: its force model, its files, and what the job gave it.
struct Run {
  const ForceModel* force = nullptr;
  std::string label;
  std::string module_name;  // of the RAPID module
  OutputFile* csv_file = nullptr;
  OutputFile* rapid_file = nullptr;
  OutputFile* trajectory_file = nullptr;
  std::unique_ptr<OfflineCsvWriter> csv;
  OfflineResult summary;        // with the points when an output needs them whole
  std::optional<BarRange> bar;  // an LDBB's bar length and inclination along the path
  std::string trajectory_text;  // "(compensated joint trajectory, 1.234 s at 10 mm/s)"
};

/// Every output of every run, prepared before the robot and the path are read.
void prepare_outputs(const OfflineOpts& o, std::vector<Run>& runs, OutputTransaction& outputs, OutputFile*& nominal) {
  const bool several = runs.size() > 1;
  const auto name = [&](const std::string& path, const Run& r) {
    return several ? path_with_label(path, r.label) : path;
  };
  for (Run& r : runs) {
    if (!o.csv_out.empty()) {
      r.csv_file = &outputs.add(name(o.csv_out, r), "option -o");
    }
    if (!o.rapid_out.empty()) {
      r.rapid_file = &outputs.add(name(o.rapid_out, r), "option --rapid");
    }
    if (!o.trajectory_out.empty()) {
      r.trajectory_file = &outputs.add(name(o.trajectory_out, r), "option --joint-trajectory");
    }
  }
  if (!o.nominal_trajectory_out.empty()) {
    nominal = &outputs.add(o.nominal_trajectory_out, "option --nominal-trajectory");
  }
}

void check_path_options(const OfflineOpts& o) {
  if (!o.program_out.empty() || !o.tooldata.empty() || !o.wobjdata.empty()) {
    throw InputError("options --program-out, --tooldata and --wobjdata go with --program-in");
  }
  const int sources = (o.circle_given ? 1 : 0) + (o.line.empty() ? 0 : 1) + (o.path_csv.empty() ? 0 : 1);
  if (sources != 1) {
    throw InputError("give exactly one path: --circle [SPEC], --line SPEC, --path FILE.csv or --program-in FILE");
  }
  if (!std::isfinite(o.hold_start_s) || o.hold_start_s < 0.0 || o.hold_start_s > 3600.0) {
    throw InputError(fmt::format("option --hold-start-s: must be 0..3600 s (got {})", o.hold_start_s));
  }
  const bool trajectories = !o.trajectory_out.empty() || !o.nominal_trajectory_out.empty();
  if (trajectories) check_trajectory_speed(o.speed_mm_s, "option --speed-mm-s");
}

/// The one pass over the path (offline_job.hpp): each run's CSV streams, and only what an output needs
/// whole is kept.
OfflineJobResult compensate_along(const OfflineOpts& o, const RobotModel& model, PoseSource& source,
                                  std::vector<Run>& runs) {
  std::vector<OfflineLoad> loads;
  for (Run& r : runs) {
    if (r.csv_file != nullptr) {
      r.csv = std::make_unique<OfflineCsvWriter>(*r.csv_file, model.dof(), model.name(), r.force->describe(), true);
    }
    loads.push_back({r.force, r.csv.get(), r.rapid_file != nullptr || r.trajectory_file != nullptr});
  }
  OfflineJobOptions options;
  options.first = first_ik_request(o, model);
  options.keep_nominal = !o.nominal_trajectory_out.empty();
  OfflineJobResult job = run_offline_job(model, source, loads, options);
  for (std::size_t k = 0; k < runs.size(); ++k) {
    runs[k].summary = std::move(job.loads[k]);
    runs[k].bar = job.bars[k];
  }
  return job;
}

/// The summary (text or JSON) once every output is in place.
void report_offline(const OfflineOpts& o, const RobotModel& model, const std::string& path_text,
                    const ArmConfiguration& configuration, const std::vector<Run>& runs, const OutputFile* nominal,
                    double nominal_s) {
  if (nominal != nullptr) {
    (o.json ? std::cerr : std::cout) << fmt::format("wrote {} (nominal joint trajectory, {:.3f} s)\n", nominal->path(),
                                                    nominal_s);
  }
  nlohmann::json json_runs = nlohmann::json::array();
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const Run& r = runs[k];
    const OfflineResult& result = r.summary;
    nlohmann::json run{{"force", r.force->describe()},
                       {"points", result.point_count},
                       {"max_deflection_mm", result.max_deflection_m * 1e3},
                       {"mean_deflection_mm", result.mean_deflection_m * 1e3},
                       {"max_residual_mm", result.max_residual_m * 1e3},
                       {"max_correction_mm", result.max_correction_m * 1e3},
                       {"max_joint_correction_deg", rad_to_deg(result.max_joint_correction_rad)}};
    std::string extra;
    if (r.bar) {
      const BarRange& b = *r.bar;
      extra = fmt::format("LDBB bar: length {:.2f}..{:.2f} mm, inclination to the XY plane {:.2f}..{:.2f} deg\n",
                          b.length_min_m * 1e3, b.length_max_m * 1e3, rad_to_deg(b.inclination_min_rad),
                          rad_to_deg(b.inclination_max_rad));
      run["bar_length_mm"] = {b.length_min_m * 1e3, b.length_max_m * 1e3};
      run["bar_inclination_deg"] = {rad_to_deg(b.inclination_min_rad), rad_to_deg(b.inclination_max_rad)};
    }
    if (r.csv_file != nullptr) {
      run["csv"] = r.csv_file->path();
      extra += fmt::format("wrote {}\n", r.csv_file->path());
    }
    if (r.trajectory_file != nullptr) {
      run["joint_trajectory"] = r.trajectory_file->path();
      extra += fmt::format("wrote {} {}\n", r.trajectory_file->path(), r.trajectory_text);
    }
    if (r.rapid_file != nullptr) {
      run["rapid"] = r.rapid_file->path();
      extra += fmt::format("wrote {} (module {})\n", r.rapid_file->path(), r.module_name);
    }
    json_runs.push_back(run);
    if (!o.json) {
      std::cout << (k == 0 ? "" : "\n") << offline_summary(result) << extra;
    } else {
      std::cerr << extra;
    }
  }
  if (o.json) {
    print_json({{"robot", model.name()},
                {"path", path_text},
                {"configuration", {configuration.cf1, configuration.cf4, configuration.cf6, configuration.cfx}},
                {"runs", json_runs}});
  }
}

/// One run a load: several --force options, or several force_N values in one, give one each.
std::vector<Run> make_runs(const OfflineOpts& o, const ForceSpecContext& context,
                           std::vector<std::unique_ptr<ForceModel>>& forces) {
  for (const std::string& spec : o.forces) {
    for (auto& m : parse_force_specs(spec, context)) {
      forces.push_back(std::move(m));
    }
  }
  std::vector<const ForceModel*> models;
  for (const auto& f : forces) models.push_back(f.get());
  const std::vector<std::string> labels = offline_load_labels(models);
  std::vector<Run> runs(forces.size());
  for (std::size_t k = 0; k < runs.size(); ++k) {
    runs[k].label = labels[k];
    runs[k].force = models[k];
  }
  return runs;
}

/// The files that need the whole path: the timed joint programs for the streaming links (deflex
/// online --program; the path at the TCP speed, compensated a load or nominal) and the RAPID modules.
/// Returns the nominal trajectory's duration (s).
double write_whole_path_outputs(const OfflineOpts& o, const RobotModel& model, const std::string& path_text,
                                const OfflineJobResult& job, std::vector<Run>& runs, RapidOptions& rapid,
                                OutputFile* nominal_file) {
  const auto write_trajectory = [&](const std::vector<Pose>& poses, const std::vector<JointVector>& q, OutputFile& file,
                                    const std::string& what) {
    const JointTrajectory t = trajectory_at_tcp_speed(poses, q, o.speed_mm_s * 1e-3, model, o.hold_start_s);
    file.write(
        t.csv_text(fmt::format("deflex offline: {} joint trajectory of {} at {:g} mm/s ({} points, {:.3f} s); "
                               "stream it with deflex online --link egm-joint --program {}",
                               what, path_text, o.speed_mm_s, t.size(), t.duration_s(), file.path())));
    return t.duration_s();
  };
  const double nominal_s = nominal_file != nullptr
                               ? write_trajectory(job.poses, job.q_nominal, *nominal_file, "nominal (uncompensated)")
                               : 0.0;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    Run& r = runs[k];
    if (r.trajectory_file != nullptr) {
      std::vector<Pose> poses;
      std::vector<JointVector> q;
      for (const OfflinePoint& pt : r.summary.points) {
        poses.push_back(pt.tcp_desired);
        q.push_back(pt.q_command);
      }
      r.trajectory_text = fmt::format("(compensated joint trajectory, {:.3f} s at {:g} mm/s)",
                                      write_trajectory(poses, q, *r.trajectory_file, "compensated"), o.speed_mm_s);
    }
    if (r.rapid_file != nullptr) {
      rapid.module_name = runs.size() > 1 ? o.module + "_" + r.label : o.module;
      if (rapid.module_name.size() > 32) {
        rapid.module_name = (o.module + "_" + std::to_string(k + 1)).substr(0, 32);
      }
      r.module_name = rapid.module_name;
      r.rapid_file->write(rapid_module(r.summary, rapid));
    }
  }
  return nominal_s;
}

/// --toolpath: the options of a path and of an existing program do not apply.
void run_toolpath(const OfflineOpts& o, int& exit_code) {
  if (o.circle_given || !o.line.empty() || !o.path_csv.empty() || !o.program_in.empty()) {
    throw InputError("--toolpath is the path: give no --circle, --line, --path or --program-in");
  }
  if (!o.rapid_out.empty() || !o.trajectory_out.empty() || !o.nominal_trajectory_out.empty() || o.orientation_given ||
      o.speed_given || o.motion_given || !o.tooldata.empty() || !o.wobjdata.empty()) {
    throw InputError(
        "with --toolpath the program's feed is the speed and the tool axis the orientation: the robot program is "
        "--program-out part.mod (RAPID), part.src (KRL) or part.nc (G-code); --rapid, --joint-trajectory, "
        "--nominal-trajectory, --orientation-wxyz, --speed-mm-s, --motion, --tooldata and --wobjdata do not apply");
  }
  ToolpathRunOptions t;
  t.robot = o.robot;
  t.stiffness = o.stiffness;
  t.toolpath = o.toolpath;
  t.workpiece = o.workpiece;
  t.cutter = o.cutter;
  t.stock = o.stock;
  t.tool_spin = o.tool_spin;
  t.reader_options = o.toolpath_options;
  t.forces = o.forces;
  t.csv_out = o.csv_out;
  t.program_out = o.program_out;
  t.plot_out = o.plot_out;
  t.zone = o.zone_given ? o.zone : "";
  t.tool = o.tool;
  t.wobj = o.wobj_given ? o.wobj : "";
  t.name = o.module_given ? o.module : "";
  t.json = o.json;
  run_offline_toolpath(
      t, [&](const RobotModel& model) { return first_ik_request(o, model); }, exit_code);
}

void run(const OfflineOpts& o, int& exit_code) {
  if (o.forces.empty()) {
    throw InputError("give a force model: --force ldbb:...|constant:...|tool:...|table:FILE.csv|milling:...");
  }
  if (!o.toolpath.empty()) {
    run_toolpath(o, exit_code);
    return;
  }
  for (const auto& [given, name] :
       {std::pair{!o.workpiece.empty(), "--workpiece"}, std::pair{!o.cutter.empty(), "--cutter"},
        std::pair{!o.stock.empty(), "--stock"}, std::pair{!o.plot_out.empty(), "--plot"},
        std::pair{!o.toolpath_options.empty(), "--toolpath-options"}}) {
    if (given) throw InputError(fmt::format("option {} goes with --toolpath", name));
  }
  if (!o.program_in.empty()) {
    if (o.circle_given || !o.line.empty() || !o.path_csv.empty()) {
      throw InputError("--program-in takes its targets from the program: give no --circle, --line or --path");
    }
    run_program(o, exit_code);
    return;
  }
  check_path_options(o);
  ForceSpecContext context;
  std::optional<CirclePath> circle;
  if (o.circle_given) {
    circle = parse_circle_spec(o.circle == "default" ? "" : o.circle);
    context.circle = *circle;
  }
  std::vector<std::unique_ptr<ForceModel>> forces;
  std::vector<Run> runs = make_runs(o, context, forces);
  RapidOptions rapid = rapid_options(o);
  OutputTransaction outputs;
  OutputFile* nominal_file = nullptr;
  prepare_outputs(o, runs, outputs, nominal_file);

  const RobotModel model = load_cli_robot("offline", o.robot, o.stiffness);
  require_stiffness(model);  // before any path is solved
  std::string path_text;
  const std::unique_ptr<PoseSource> source = make_pose_source(o, circle, path_text);
  const OfflineJobResult job = compensate_along(o, model, *source, runs);
  const ArmConfiguration& configuration = job.configuration;
  rapid.note = fmt::format("Path: {}; arm configuration [cf1,cf4,cf6,cfx] at the start [{},{},{},{}].", path_text,
                           configuration.cf1, configuration.cf4, configuration.cf6, configuration.cfx);
  const double nominal_s = write_whole_path_outputs(o, model, path_text, job, runs, rapid, nominal_file);
  outputs.commit();  // every file of every load, or none
  report_offline(o, model, path_text, configuration, runs, nominal_file, nominal_s);
  exit_code = 0;
}

// The robot, the path and the force along it.
void add_offline_path_options(CLI::App& sub, OfflineOpts& o) {
  sub.add_option("--robot", o.robot,
                 "Robot file (.yaml deflex format or .urdf) with joint stiffness; default: the built-in ABB IRB 6700");
  sub.add_option("--stiffness-Nm-per-rad", o.stiffness, kStiffnessHelp);
  sub.add_option("--circle", o.circle,
                 "Circle path \"centre_mm=X;Y;Z,radius_mm=R,normal=NX;NY;NZ,start_deg=A,direction=ccw|cw,points=N\"; "
                 "every key optional (default: centre 1500;0;1000 mm, radius 100 mm, normal +z, ccw, 81 points, the "
                 "last repeating the first); \"--circle default\" takes them all")
      ->expected(0, 1);
  sub.add_option("--line", o.line, "Straight path \"start_mm=X;Y;Z,end_mm=X;Y;Z,points=N\"");
  sub.add_option("--path", o.path_csv, "Path CSV with columns x_mm,y_mm,z_mm,qw,qx,qy,qz (base frame)");
  sub.add_option("--orientation-wxyz", o.orientation,
                 "TCP orientation held along a circle or line, unit quaternion \"w,x,y,z\" (default 0,0,1,0: tool "
                 "z axis pointing down for the IRB6700's tool0)");
  sub.add_option("--config", o.config, "ABB confdata \"cf1,cf4,cf6,cfx\" at the first point (cfx kept along the path)");
  sub.add_option("--seed-deg", o.seed,
                 "Preferred joint values at the first point, degrees \"j1,...,j6\"; with --program-in the arm's joints "
                 "when the program starts (ConfJ\\Off's first target, a KRL point without Status and Turn)");
  sub.add_option("--force", o.forces,
                 "Force model (repeatable): \"ldbb:pivot_mm=X;Y;Z,force_N=F[;F2..],mode=push|pull\", "
                 "\"ldbb:phi_deg=A,force_N=...\" (circle only: pivot on the circle's axis, bar inclined by A), "
                 "\"constant:fx_N=..,fy_N=..,fz_N=..,mx_Nm=..,my_Nm=..,mz_Nm=..\" (base frame), \"tool:fz_N=..,...\" "
                 "(the same keys in the TCP frame: a drilling or milling thrust that turns with the tool), "
                 "\"table:FILE.csv\", \"milling:Ktc_N_mm2=..,...|file=COEFFS.yaml[,ae_mm=..,ap_mm=..]\" (with "
                 "--toolpath)")
      ->required();
}

// The files written: joint trajectories, CSV, RAPID, a compensated program.
void add_offline_output_options(CLI::App& sub, OfflineOpts& o) {
  sub.add_option("--speed-mm-s", o.speed_mm_s,
                 "TCP speed, mm/s (default 10): the RAPID speeddata and the timing of the joint trajectories");
  sub.add_option(
      "--joint-trajectory", o.trajectory_out,
      "Write the compensated path as a timed joint trajectory CSV (t_s,q1_deg..) at --speed-mm-s, for deflex "
      "online --program (hybrid strategy); one file per load when several");
  sub.add_option("--nominal-trajectory", o.nominal_trajectory_out,
                 "Write the uncompensated path as a timed joint trajectory CSV at --speed-mm-s, for deflex online "
                 "--program (online and predictive strategies)");
  sub.add_option("--hold-start-s", o.hold_start_s,
                 "Joint trajectories: hold the first point this long before moving, s (default 0)");
  sub.add_option("--zone", o.zone, "RAPID zonedata: fine (default) or z0, z1, z5, z10, ...");
  sub.add_option("--motion", o.motion,
                 "RAPID motion: absj (MoveAbsJ over jointtargets, default) or movel "
                 "(MoveL over robtargets with confdata)");
  sub.add_option("--tool", o.tool, "RAPID tooldata name (default tool0)");
  sub.add_option("--wobj", o.wobj, "RAPID wobjdata name (default wobj0)");
  sub.add_option("--module", o.module, "RAPID module name (default DeflexOffline; the load is appended when several)");
  sub.add_option("-o,--output", o.csv_out, "Write the per-point CSV here (one file per load when several)");
  sub.add_option("--rapid", o.rapid_out, "Write the ABB RAPID module here (.mod; one per load when several)");
  sub.add_option("--program-in", o.program_in,
                 "An existing robot program to compensate target by target: ABB RAPID module (.mod, .modx, .prg, "
                 ".sys) or KUKA KRL program (.src, its .dat beside it); every other byte is kept");
  sub.add_option("--program-out", o.program_out,
                 "Where the compensated program goes (KRL: the .src; its .dat is written beside it). With --toolpath: "
                 ".nc/.gcode/.tap (G-code over the source), .mod/.modx/.prg (RAPID) or .src (KRL)");
  sub.add_option("--tooldata", o.tooldata,
                 "Tool declared outside the program, in its own syntax (repeatable): RAPID "
                 "\"tGun=[TRUE,[[x,y,z],[q1,q2,q3,q4]],[mass,[cx,cy,cz],[1,0,0,0],0,0,0]]\" (mm), KRL "
                 "\"TOOL_DATA[1]={X ..,Y ..,Z ..,A ..,B ..,C ..}\" or \"$TOOL={...}\" (mm, deg)");
  sub.add_option("--wobjdata", o.wobjdata,
                 "Work object or base declared outside the program (repeatable): RAPID "
                 "\"wobjTable=[FALSE,TRUE,\"\",[[x,y,z],[q1,q2,q3,q4]],[[0,0,0],[1,0,0,0]]]\", KRL "
                 "\"BASE_DATA[2]={X ..,Y ..,Z ..,A ..,B ..,C ..}\" or \"$BASE={...}\"");
}

// A CAM toolpath compensated for its milling force.
void add_offline_toolpath_options(CLI::App& sub, OfflineOpts& o) {
  sub.add_option("--toolpath", o.toolpath,
                 "A CAM toolpath to compensate for its milling force: G-code (.nc, .gcode, .tap) or APT/CL data (.apt, "
                 ".cls), points in the workpiece frame (docs/machining.md)");
  sub.add_option(
      "--workpiece", o.workpiece,
      "--toolpath: the workpiece frame in the robot's base frame \"x_mm=..,y_mm=..,z_mm=..,qw=..,qx=..,qy=..,"
      "qz=..\" (the quaternion optional)");
  sub.add_option("--cutter", o.cutter,
                 "--toolpath: the milling cutter \"diameter_mm=..,flutes=..,helix_deg=..[,corner_radius_mm=..]\"");
  sub.add_option("--stock", o.stock,
                 "--toolpath: the stock the program cuts, workpiece frame \"box:min_mm=X;Y;Z,max_mm=X;Y;Z,cell_mm=C"
                 "[,model=zmap|dexel][,layer_mm=L]\" (z-map by default)");
  sub.add_option("--tool-spin", o.tool_spin,
                 "--toolpath: the spindle's free angle: optimize (default: chosen for stiffness; keys step_deg, "
                 "rate_deg_per_mm, limit_margin_deg, singularity_floor, lag_stages after optimize:) or fixed:DEG");
  sub.add_option("--toolpath-options", o.toolpath_options,
                 "--toolpath: reading \"chord_mm=0.01,arc_tolerance_mm=0.01,step_mm=0,rotary=head-head|table-table,"
                 "dialect=iso|siemens,apt_units=mm|inch\"");
  sub.add_option("--plot", o.plot_out,
                 "--toolpath: write an SVG chart of the force, the deflection with and without compensation and the "
                 "spindle angle along the path");
}

void setup_offline(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<OfflineOpts>();
  add_offline_path_options(sub, *o);
  add_offline_output_options(sub, *o);
  add_offline_toolpath_options(sub, *o);
  sub.add_flag("--json", o->json, "Print one JSON document on stdout");
  sub.callback([o, &exit_code, &sub] {
    o->circle_given = sub.count("--circle") > 0;
    o->orientation_given = sub.count("--orientation-wxyz") > 0;
    o->zone_given = sub.count("--zone") > 0;
    o->wobj_given = sub.count("--wobj") > 0;
    o->module_given = sub.count("--module") > 0;
    o->speed_given = sub.count("--speed-mm-s") > 0;
    o->motion_given = sub.count("--motion") > 0;
    run(*o, exit_code);
  });
}

}  // namespace

DEFLEX_COMMAND("offline",
               "Offline compensation: a path (circle, line, CSV or a CAM toolpath) and a force model to compensated "
               "joints, CSV and a robot program",
               setup_offline, 30);

}  // namespace deflex::cli
