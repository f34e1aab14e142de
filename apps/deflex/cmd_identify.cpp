// Subcommands of the identification layer: identify (joint stiffness from measured deflections)
// and plan-calibration (poses and loads for the measurement campaign).
#include <cmath>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/identify/calibration_planner.hpp"
#include "deflex/identify/calibration_simulation.hpp"
#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::cli {
namespace {

// Required: fitting the built-in IRB 6700 to another arm's data gives confident nonsense (J5 negative).
const char* const kDataRobotHelp =
    "Robot file (.yaml deflex format or .urdf) whose kinematics, tool and WAP the data were taken with; required "
    "('builtin' names the built-in ABB IRB 6700-300/2.70 with no tool: WAP and TCP at the flange centre)";

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

// "6=2e5,4=6e5" -> per-joint fixed stiffness.
std::vector<std::optional<double>> parse_fixed(const std::string& text, int dof, const std::string& option) {
  std::vector<std::optional<double>> fixed(static_cast<std::size_t>(dof));
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, end - start);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      throw InputError(fmt::format("option {}: '{}' is not JOINT=STIFFNESS (e.g. 6=2.0e5)", option, item));
    }
    const auto j = parse_numbers(item.substr(0, eq), option, 1)[0];
    const auto k = parse_numbers(item.substr(eq + 1), option, 1)[0];
    if (j < 1 || j > dof || j != std::floor(j)) {
      throw InputError(fmt::format("option {}: joint {} is not 1..{}", option, j, dof));
    }
    if (const auto bad = range_violation(k, range::kJointStiffness)) {
      throw InputError(fmt::format("option {}: stiffness of joint {}: {}", option, j, *bad));
    }
    if (fixed[static_cast<std::size_t>(j) - 1]) {
      throw InputError(fmt::format("option {}: joint {} is given twice ('{}'); give each joint once", option, j, text));
    }
    fixed[static_cast<std::size_t>(j) - 1] = k;
    start = end + 1;
  }
  return fixed;
}

struct IdentifyOpts {
  std::string robot, data, write_robot, fixed;
  bool json = false, no_robust = false;
  double rotation_scale_m = 1.0, max_rel = 0.5;
};

void add_identify_options(CLI::App& sub, IdentifyOpts& o) {
  sub.add_option("--robot", o.robot, kDataRobotHelp)->required();
  sub.add_option("--data", o.data,
                 "Measurement CSV: q1_deg..q6_deg, fx_N,fy_N,fz_N, mx_Nm,my_Nm,mz_Nm (at the WAP, base frame), "
                 "dx_mm,dy_mm,dz_mm (TCP, loaded minus unloaded, base frame); optional drx_rad,dry_rad,drz_rad, weight")
      ->required();
  sub.add_option("--fix-stiffness-Nm-per-rad", o.fixed,
                 "Hold joints at known stiffness and leave them out of the fit: \"6=2.0e5,5=3.5e5\"");
  sub.add_flag("--no-robust", o.no_robust, "Plain (weighted) nonnegative least squares, no outlier re-weighting");
  sub.add_option("--rotation-scale-m", o.rotation_scale_m,
                 "Length that weighs orientation rows against positions (1: 1 urad counts like 1 um)");
  sub.add_option("--max-relative-std-error", o.max_rel,
                 "Relative standard error above which a joint is reported unidentifiable (default 0.5)");
  sub.add_option("--write-robot", o.write_robot,
                 "Write the robot file with the identified stiffness (unidentified joints keep the file's value)");
  sub.add_flag("--json", o.json, "Print one JSON document on stdout");
}

IdentificationOptions identification_options(const IdentifyOpts& o, const RobotModel& model) {
  IdentificationOptions opt;
  opt.robust = !o.no_robust;
  opt.rotation_scale_m = o.rotation_scale_m;
  opt.max_relative_std_error = o.max_rel;
  if (!o.fixed.empty()) {
    opt.fixed_stiffness_nm_per_rad = parse_fixed(o.fixed, model.dof(), "--fix-stiffness-Nm-per-rad");
  }
  return opt;
}

// Streamed: a row at a time from the file into the identifier's compact store.
StiffnessEstimate identify_from(StiffnessMeasurementReader& reader, const IdentifyOpts& o, const RobotModel& model,
                                const IdentificationOptions& opt) {
  if (reader.joints() != model.dof()) {
    throw InputError(fmt::format("{}: {} joint columns, robot '{}' has {} joints", o.data, reader.joints(),
                                 model.name(), model.dof()));
  }
  StiffnessIdentifier identifier(model, opt);
  for (StiffnessMeasurement m; reader.next(m);) {
    identifier.add(m);
  }
  StiffnessEstimate est;
  try {
    est = identifier.solve();
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", o.data, e.what()));  // the data that cannot identify the joints
  }
  if (identifier.scratch_bytes() > 0) {
    std::cerr << fmt::format(
        "deflex identify: {} measurements; {:.0f} MiB of their rows were kept in a scratch file in the temporary "
        "directory (TMPDIR) beyond the {:.0f} MiB held in memory\n",
        identifier.measurements(), static_cast<double>(identifier.scratch_bytes()) / 1048576.0,
        static_cast<double>(opt.rows_in_memory_bytes) / 1048576.0);
  }
  return est;
}

void print_identify_json(const IdentifyOpts& o, const RobotModel& model, const IdentificationOptions& opt,
                         const StiffnessEstimate& est) {
  const auto n = static_cast<std::size_t>(model.dof());
  nlohmann::json k = nlohmann::json::array(), se = nlohmann::json::array(), rel = nlohmann::json::array();
  for (std::size_t j = 0; j < n; ++j) {
    k.push_back(number_or_null(est.stiffness_nm_per_rad[j]));
    se.push_back(number_or_null(est.std_error_nm_per_rad[j]));
    rel.push_back(number_or_null(est.std_error_nm_per_rad[j] / est.stiffness_nm_per_rad[j]));
  }
  const nlohmann::json rejected = est.rejected_lines;
  print_json({{"robot", model.name()},
              {"data", o.data},
              {"measurements", est.measurements},
              {"stiffness_Nm_per_rad", k},
              {"std_error_Nm_per_rad", se},
              {"relative_std_error", rel},
              {"residual_rms_mm", est.residual_rms_m * 1e3},
              {"residual_max_mm", est.residual_max_m * 1e3},
              {"noise_sigma_mm", number_or_null(est.sigma_m * 1e3)},
              {"condition_number", number_or_null(est.condition_number)},
              {"unidentifiable_joints", est.unidentifiable_joints},
              {"fixed_joints", est.fixed_joints},
              {"rejected_lines", rejected},
              {"estimator", opt.robust ? "NNLS, Huber then Tukey bisquare IRLS" : "NNLS"},
              {"warnings", est.warnings}});
}

bool has_joint(const std::vector<int>& joints, std::size_t j) {
  return std::find(joints.begin(), joints.end(), static_cast<int>(j) + 1) != joints.end();
}

void print_identify_row(const RobotModel& model, const StiffnessEstimate& est, std::size_t j) {
  const double k = est.stiffness_nm_per_rad[j], se = est.std_error_nm_per_rad[j];
  const bool fixed = has_joint(est.fixed_joints, j);
  const double file_k = model.has_stiffness() ? model.stiffness()[static_cast<Eigen::Index>(j)] : NAN;
  std::string dev = "-";
  if (std::isfinite(k) && std::isfinite(file_k) && se > 0.0) {
    dev = fmt::format("{:+.2f}", (k - file_k) / se);
  }
  const bool flagged = has_joint(est.unidentifiable_joints, j);
  std::cout << fmt::format("{:>5}  {:>14}  {:>16}  {:>9}  {:>16}  {:>12}\n", j + 1,
                           std::isfinite(k) && !flagged ? fmt::format("{:.4e}", k)
                           : std::isfinite(k)           ? fmt::format("({:.2e})?", k)
                                                        : "not identified",
                           fixed ? "fixed" : (std::isfinite(se) ? fmt::format("{:.3e}", se) : "-"),
                           std::isfinite(se) && std::isfinite(k) && !fixed ? fmt::format("{:.2f}%", 100 * se / k) : "-",
                           std::isfinite(file_k) ? fmt::format("{:.4e}", file_k) : "-", dev);
}

void print_identify_text(const IdentifyOpts& o, const RobotModel& model, const IdentificationOptions& opt,
                         const StiffnessEstimate& est) {
  std::cout << fmt::format("robot: {}\ndata: {} ({} measurements, {} rejected as outliers)\n", model.name(), o.data,
                           est.measurements, est.rejected_measurements.size());
  std::cout << fmt::format("{:>5}  {:>14}  {:>14}  {:>9}  {:>16}  {:>12}\n", "joint", "k (Nm/rad)", "std err (Nm/rad)",
                           "rel. err", "robot file k", "(k-file)/se");
  for (std::size_t j = 0; j < static_cast<std::size_t>(model.dof()); ++j) {
    print_identify_row(model, est, j);
  }
  std::cout << fmt::format(
      "residual RMS {:.4f} mm (max {:.4f} mm), noise sigma {:.4f} mm, condition number {:.1f}\n"
      "estimator: {}, {} re-weighting iterations\n",
      est.residual_rms_m * 1e3, est.residual_max_m * 1e3, est.sigma_m * 1e3, est.condition_number,
      opt.robust ? "nonnegative least squares with Huber then Tukey-bisquare IRLS" : "nonnegative least squares",
      est.iterations);
  if (!est.unidentifiable_joints.empty()) {
    std::cout << fmt::format("unidentifiable joints: {} (a value in brackets must not be used; see the warnings)\n",
                             fmt::join(est.unidentifiable_joints, ", "));
  }
}

void run_identify(const IdentifyOpts& o) {
  OutputTransaction outputs;  // prepared first: the robot file written is never one read
  OutputFile* robot_out = o.write_robot.empty() ? nullptr : &outputs.add(o.write_robot, "option --write-robot");
  const RobotModel model = load_cli_robot("identify", o.robot);
  StiffnessMeasurementReader reader(o.data);
  const IdentificationOptions opt = identification_options(o, model);
  const StiffnessEstimate est = identify_from(reader, o, model, opt);
  if (robot_out != nullptr) {
    try {
      robot_out->write(robot_to_yaml(identified_robot(model, est, o.data)));
    } catch (const InputError& e) {
      throw InputError(fmt::format("--write-robot: {}; nothing written", e.what()));
    }
  }
  outputs.commit();
  if (robot_out != nullptr) {
    std::cerr << fmt::format("deflex identify: wrote {}\n", o.write_robot);
  }
  if (o.json) {
    print_identify_json(o, model, opt, est);
  } else {
    print_identify_text(o, model, opt, est);
  }
  for (const auto& w : est.warnings) {
    std::cerr << "deflex identify: warning: " << w << "\n";
  }
}

void setup_identify(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<IdentifyOpts>();
  add_identify_options(sub, *o);
  sub.callback([o, &exit_code] {
    run_identify(*o);
    exit_code = 0;
  });
}

struct PlanOpts {
  std::string robot, region, quaternion, spin = "0,90,180,270", out, synth_out, synth_robot;
  double load = 0.0, lever_mm = 250.0, noise_mm = 0.01, synth_noise_mm = 0.01;
  int poses = 12, loads_per_pose = 2, grid = 4;
  unsigned seed = 1;
  bool json = false;
};

void add_plan_options(CLI::App& sub, PlanOpts& o) {
  sub.add_option("--robot", o.robot, kDataRobotHelp)->required();
  sub.add_option("--region-mm", o.region,
                 "Box of TCP positions to calibrate in, base frame: \"xmin,xmax,ymin,ymax,zmin,zmax\" (mm)")
      ->required();
  sub.add_option("--load-N", o.load, "Force applied at each measurement, N")->required();
  sub.add_option("--poses", o.poses, "Number of distinct poses (default 12)");
  sub.add_option("--loads-per-pose", o.loads_per_pose, "Loads applied at each pose (default 2)");
  sub.add_option("--lever-mm", o.lever_mm,
                 "Distance from the WAP, perpendicular to the tool axis, at which the force may act (a calibration "
                 "bar), so it also twists the wrist; 0: forces at the WAP only (default 250)");
  sub.add_option("--quaternion-wxyz", o.quaternion,
                 "TCP orientation \"w,x,y,z\" in the base frame (default 0,0,1,0: tool pointing down)");
  sub.add_option("--spin-deg", o.spin, "Candidate turns of the tool about its axis, deg (default \"0,90,180,270\")");
  sub.add_option("--grid", o.grid, "Candidate positions per axis of the region (default 4)");
  sub.add_option("--noise-mm", o.noise_mm, "Tracker noise per axis for the predicted standard errors (default 0.01)");
  sub.add_option("-o,--output", o.out, "Plan CSV to write")->required();
  sub.add_option("--synthetic-measurements", o.synth_out,
                 "Also write what a tracker would measure running the plan on --synthetic-robot (a measurement CSV "
                 "for deflex identify): exact deflection by the core model plus Gaussian noise");
  sub.add_option("--synthetic-robot", o.synth_robot,
                 "The 'true' robot for --synthetic-measurements (default: --robot)");
  sub.add_option("--synthetic-noise-mm", o.synth_noise_mm,
                 "Noise per axis of the synthetic measurements (default 0.01)");
  sub.add_option("--seed", o.seed, "Seed of the synthetic noise (default 1)");
  sub.add_flag("--json", o.json, "Print one JSON document on stdout");
}

CalibrationPlanOptions plan_options(const PlanOpts& o) {
  const auto r = parse_numbers(o.region, "--region-mm", 6, range::kLengthMm);
  CalibrationPlanOptions opt;
  opt.region_min_m = Vector3(r[0], r[2], r[4]) * 1e-3;
  opt.region_max_m = Vector3(r[1], r[3], r[5]) * 1e-3;
  if ((opt.region_max_m - opt.region_min_m).minCoeff() < 0.0) {
    throw InputError("option --region-mm: give \"xmin,xmax,ymin,ymax,zmin,zmax\" with each min <= max");
  }
  opt.load_n = o.load;
  opt.poses = o.poses;
  opt.loads_per_pose = o.loads_per_pose;
  opt.lever_m = o.lever_mm * 1e-3;
  opt.grid_per_axis = o.grid;
  opt.noise_m = o.noise_mm * 1e-3;
  if (!o.quaternion.empty()) {
    const auto q = parse_numbers(o.quaternion, "--quaternion-wxyz", 4, range::kUnitQuaternion);
    opt.orientation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    if (std::abs(opt.orientation.norm() - 1.0) > 1e-3) {
      throw InputError("option --quaternion-wxyz: not a unit quaternion");
    }
  }
  opt.spin_rad.clear();
  const std::vector<double> spins = parse_numbers(o.spin, "--spin-deg", 0, range::kAngleDeg);
  if (spins.size() > 360) {
    throw InputError(
        fmt::format("option --spin-deg: {} turns; give at most 360 (each multiplies the candidates)", spins.size()));
  }
  for (double s : spins) {
    opt.spin_rad.push_back(deg_to_rad(s));
  }
  return opt;
}

std::vector<std::string> plan_comments(const RobotModel& model, const CalibrationPlanOptions& opt,
                                       const CalibrationPlan& plan) {
  std::vector<double> percent;
  for (double x : plan.predicted_relative_std_error) percent.push_back(100 * x);
  return {fmt::format("calibration plan for {} made by deflex plan-calibration", model.name()),
          "at each row: move to q (x_mm.. is the TCP), measure the TCP, apply the force fx_N,fy_N,fz_N at load_x_mm.. "
          "(the WAP moment mx_Nm.. follows), measure again; dx_mm = loaded - unloaded (base frame)",
          fmt::format("condition number {:.2f}, smallest singular value {:.4f} mm, predicted relative standard errors "
                      "({:.3f} mm noise): {:.2f}%",
                      plan.condition_number, plan.min_singular_value_m * 1e3, opt.noise_m * 1e3,
                      fmt::join(percent, "%, "))};
}

void write_synthetic_measurements(const PlanOpts& o, const RobotModel& model, const CalibrationPlan& plan,
                                  OutputFile& out) {
  const RobotModel truth = o.synth_robot.empty() ? model : load_robot(o.synth_robot);
  const auto data = simulate_calibration(truth, plan, o.synth_noise_mm * 1e-3, o.seed);
  write_stiffness_measurements(
      out, data,
      {fmt::format("SYNTHETIC measurements: plan {} run on '{}' (stiffness {} Nm/rad) by deflex plan-calibration "
                   "--synthetic-measurements; exact deflection + Gaussian noise {:.4f} mm per axis, seed {}",
                   o.out, truth.name(), fmt::join(truth.description().stiffness_nm_per_rad, ", "), o.synth_noise_mm,
                   o.seed)});
}

void print_plan_json(const PlanOpts& o, const RobotModel& model, const CalibrationPlan& plan) {
  nlohmann::json rel = nlohmann::json::array();
  for (double x : plan.predicted_relative_std_error) {
    rel.push_back(number_or_null(x));
  }
  print_json({{"robot", model.name()},
              {"plan", o.out},
              {"rows", plan.points.size()},
              {"poses", plan.points.empty() ? 0 : plan.points.back().pose},
              {"condition_number", number_or_null(plan.condition_number)},
              {"min_singular_value_mm", plan.min_singular_value_m * 1e3},
              {"predicted_relative_std_error", rel},
              {"candidate_poses", plan.candidate_poses},
              {"reachable_poses", plan.reachable_poses},
              {"warnings", plan.warnings}});
}

void print_plan_text(const PlanOpts& o, const RobotModel& model, const CalibrationPlanOptions& opt,
                     const CalibrationPlan& plan) {
  std::cout << fmt::format(
      "robot: {}\nplan: {} ({} poses, {} measurements; {} of {} candidate poses reachable)\n"
      "condition number {:.2f} (columns scaled to unit norm{}), smallest singular value {:.4f} mm "
      "(columns scaled by the file's compliance)\n",
      model.name(), o.out, plan.points.empty() ? 0 : plan.points.back().pose, plan.points.size(), plan.reachable_poses,
      plan.candidate_poses, plan.condition_number,
      std::isfinite(plan.condition_number)
          ? ""
          : "; inf: some joint's stiffness cannot be told from this plan's measurements, the warnings say which "
            "and what to do",
      plan.min_singular_value_m * 1e3);
  std::cout << fmt::format("predicted relative standard error with {:.3f} mm noise:", opt.noise_m * 1e3);
  for (std::size_t j = 0; j < plan.predicted_relative_std_error.size(); ++j) {
    std::cout << fmt::format(" J{} {:.2f}%", j + 1, 100 * plan.predicted_relative_std_error[j]);
  }
  std::cout << "\n";
}

void run_plan(const PlanOpts& o) {
  OutputTransaction outputs;  // both files or neither
  OutputFile& plan_out = outputs.add(o.out, "option -o");
  OutputFile* synthetic_out =
      o.synth_out.empty() ? nullptr : &outputs.add(o.synth_out, "option --synthetic-measurements");
  const RobotModel model = load_cli_robot("plan-calibration", o.robot);
  const CalibrationPlanOptions opt = plan_options(o);
  const CalibrationPlan plan = plan_calibration(model, opt);
  write_calibration_plan(plan_out, plan, plan_comments(model, opt, plan));
  if (synthetic_out != nullptr) {
    write_synthetic_measurements(o, model, plan, *synthetic_out);
  }
  outputs.commit();
  if (synthetic_out != nullptr) {
    std::cerr << fmt::format("deflex plan-calibration: wrote synthetic measurements {}\n", o.synth_out);
  }
  if (o.json) {
    print_plan_json(o, model, plan);
  } else {
    print_plan_text(o, model, opt, plan);
  }
  for (const auto& w : plan.warnings) {
    std::cerr << "deflex plan-calibration: warning: " << w << "\n";
  }
}

void setup_plan(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<PlanOpts>();
  add_plan_options(sub, *o);
  sub.callback([o, &exit_code] {
    run_plan(*o);
    exit_code = 0;
  });
}

}  // namespace

DEFLEX_COMMAND("identify", "Identify joint stiffness (Nm/rad) from measured TCP deflections under known loads (CSV)",
               setup_identify, 40);
DEFLEX_COMMAND("plan-calibration",
               "Plan a stiffness calibration: poses in a region and load directions that make every joint observable",
               setup_plan, 41);

}  // namespace deflex::cli
