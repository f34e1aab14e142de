// Machining from Python: a CAM toolpath compensated for its milling force with the spindle's angle
// chosen for stiffness (compensate_toolpath, the job `deflex offline --toolpath` runs), the milling
// force of one engagement (milling_force), and the cutting coefficients fitted from slot cuts
// (fit_cutting_coefficients, as `deflex cutting-coefficients`).
#include <fmt/format.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/machining/coefficient_fit.hpp"
#include "deflex/machining/milling_force_model.hpp"
#include "deflex/machining/stock_spec.hpp"
#include "deflex/offline/toolpath_job.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/toolpath/workpiece_spec.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

SpindleTurn turn_arg(const std::string& turn) {
  if (turn == "M3") return SpindleTurn::kClockwise;
  if (turn == "M4") return SpindleTurn::kCounterClockwise;
  throw InputError(fmt::format("argument turn: '{}' is neither M3 nor M4", turn));
}

/// The job's points as arrays, one row a point.
py::dict toolpath_points(const std::vector<ToolpathJobPoint>& p, int dof) {
  const auto n = static_cast<py::ssize_t>(p.size());
  Array position = new_array({n, 3}), axis = new_array({n, 3}), tip_cmd = new_array({n, 3});
  Array wrench = new_array({n, 6}), deflection = new_array({n, 6}), residual = new_array({n, 6});
  Array q_des = new_array({n, dof}), q_cmd = new_array({n, dof});
  Array tcp_des = new_array({n, 4, 4}), tcp_cmd = new_array({n, 4, 4});
  Array line = new_array({n}), feed = new_array({n}), rpm = new_array({n}), ae = new_array({n}), ap = new_array({n});
  Array fz = new_array({n}), peak = new_array({n}), tooth = new_array({n}), spin = new_array({n});
  py::array_t<bool> cutting(n);
  for (py::ssize_t i = 0; i < n; ++i) {
    const ToolpathJobPoint& t = p[static_cast<std::size_t>(i)];
    Eigen::Map<Vector3>(position.mutable_data() + 3 * i) = t.source.position_m;
    Eigen::Map<Vector3>(axis.mutable_data() + 3 * i) = t.source.tool_axis;
    Eigen::Map<Vector3>(tip_cmd.mutable_data() + 3 * i) = t.command_tip_workpiece_m;
    Eigen::Map<Wrench>(wrench.mutable_data() + 6 * i) = t.compensated.wrench_base;
    Eigen::Map<Vector6>(deflection.mutable_data() + 6 * i) = t.compensated.predicted_deflection;
    Eigen::Map<Vector6>(residual.mutable_data() + 6 * i) = t.compensated.predicted_residual;
    for (int j = 0; j < dof; ++j) {
      q_des.mutable_data()[i * dof + j] = t.compensated.q_desired[j];
      q_cmd.mutable_data()[i * dof + j] = t.compensated.q_command[j];
    }
    write_pose(t.compensated.tcp_desired, tcp_des.mutable_data() + 16 * i);
    write_pose(t.compensated.tcp_command, tcp_cmd.mutable_data() + 16 * i);
    line.mutable_data()[i] = static_cast<double>(t.source.line);
    feed.mutable_data()[i] = t.source.feed_m_s * 6e4;
    rpm.mutable_data()[i] = t.source.spindle_rpm;
    ae.mutable_data()[i] = t.force.ae_m;
    ap.mutable_data()[i] = t.force.ap_m;
    fz.mutable_data()[i] = t.force.fz_m;
    peak.mutable_data()[i] = t.force.peak_force_n;
    tooth.mutable_data()[i] = t.force.tooth_passing_hz;
    spin.mutable_data()[i] = t.spin_rad;
    cutting.mutable_data()[i] = t.force.state == MillingPointState::kCut;
  }
  return py::dict("position_m"_a = position, "tool_axis"_a = axis, "line"_a = line, "feed_mm_min"_a = feed,
                  "spindle_rpm"_a = rpm, "cutting"_a = cutting, "ae_m"_a = ae, "ap_m"_a = ap, "fz_m"_a = fz,
                  "peak_force_n"_a = peak, "tooth_passing_hz"_a = tooth, "spin_rad"_a = spin, "wrench"_a = wrench,
                  "q_desired"_a = q_des, "q_command"_a = q_cmd, "tcp_desired"_a = tcp_des, "tcp_command"_a = tcp_cmd,
                  "predicted_deflection"_a = deflection, "predicted_residual"_a = residual,
                  "command_tip_workpiece_m"_a = tip_cmd);
}

py::dict toolpath_figures(const ToolpathJobResult& r, bool gcode) {
  return py::dict(
      "points"_a = r.points, "cutting_points"_a = r.counts.cut, "in_air_points"_a = r.counts.in_air,
      "plunges"_a = r.counts.plunges, "rapids"_a = r.counts.rapids, "path_length_m"_a = r.path_length_m,
      "removed_volume_m3"_a = r.removed_volume_m3, "mean_cutting_deflection_m"_a = r.mean_cutting_deflection_m,
      "max_cutting_deflection_m"_a = r.max_cutting_deflection_m, "max_force_n"_a = r.max_force_n,
      "max_peak_force_n"_a = r.max_peak_force_n, "tooth_passing_hz"_a = r.tooth_passing_hz,
      "spin_range_rad"_a = py::make_tuple(r.spin_min_rad, r.spin_max_rad),
      "max_spin_rate_rad_per_m"_a = r.max_spin_rate_rad_per_m, "spin_margin_violations"_a = r.spin.margin_violations,
      "max_residual_m"_a = r.summary.max_residual_m, "max_correction_m"_a = r.summary.max_correction_m,
      "configuration"_a = configuration_tuple(r.configuration), "summary"_a = toolpath_summary_text(r, gcode));
}

/// The outputs of compensate_toolpath, prepared before the job as the command does.
struct PyToolpathOutputs {
  OutputTransaction transaction;
  std::unique_ptr<OfflineCsvWriter> csv;
  std::unique_ptr<GcodeWriteBack> gcode;
  std::unique_ptr<ToolpathProgramWriter> program;
};

py::dict run_compensate_toolpath(const RobotModel& model, const PathArg& toolpath, const std::string& workpiece,
                                 const std::string& cutter_spec, const std::string& force_spec,
                                 const std::string& stock_spec, const std::string& tool_spin,
                                 const ConfigurationArg& configuration, const std::optional<ArrayLike>& seed,
                                 const std::string& reader_options, bool predict, const std::optional<PathArg>& csv,
                                 const std::optional<PathArg>& program_out) {
  ForceSpecContext context;
  context.milling = milling_force_specs(parse_cutter_spec(cutter_spec));
  std::vector<std::unique_ptr<ForceModel>> models = parse_force_specs(force_spec, context);
  const auto* force = dynamic_cast<const MillingForceModel*>(models.front().get());
  if (force == nullptr) throw InputError("argument force: a toolpath takes the milling force (\"milling:...\")");
  std::unique_ptr<Stock> stock;
  if (!stock_spec.empty()) stock = parse_stock_spec(stock_spec);
  ToolpathJobOptions o;
  o.base_T_workpiece = parse_workpiece_spec(workpiece);
  o.spin = parse_tool_spin_spec(tool_spin);
  o.compensation.predict = predict;
  o.first.configuration = arm_configuration_arg(configuration);
  if (seed && !seed->is_none()) o.first.seed = joint_vector(*seed, "seed", model.dof());
  const ToolpathOptions reading =
      reader_options.empty() ? ToolpathOptions{} : parse_toolpath_options_spec(reader_options);
  const std::string source = path_text(toolpath);
  PyToolpathOutputs out;
  ToolpathSinks sinks;
  std::vector<ToolpathJobPoint> points;
  sinks.keep = &points;
  bool gcode = false;
  if (program_out) {
    const ToolpathOutputKind kind = toolpath_output_kind(path_text(*program_out));
    OutputFile& file = out.transaction.add(path_text(*program_out), "argument program_out");
    gcode = kind == ToolpathOutputKind::kGcode;
    if (gcode) {
      out.gcode = std::make_unique<GcodeWriteBack>(source, file, reading);
    } else {
      ToolpathProgramOptions p;
      p.base_T_workpiece = o.base_T_workpiece;
      p.header = fmt::format("Robot: {}\nToolpath: {}\nForce: {}", model.name(), source, force->describe());
      out.program = std::make_unique<ToolpathProgramWriter>(file, kind, p, model);
    }
  }
  if (csv) {
    OutputFile& file = out.transaction.add(path_text(*csv), "argument csv");
    out.csv = std::make_unique<OfflineCsvWriter>(file, model.dof(), model.name(), force->describe(), predict,
                                                 toolpath_csv_columns(), fmt::format("; toolpath {}", source));
  }
  sinks.csv = out.csv.get();
  sinks.gcode = out.gcode.get();
  sinks.program = out.program.get();
  ToolpathJobResult r;
  {
    py::gil_scoped_release release;
    const std::unique_ptr<ToolpathReader> reader = open_toolpath(source, reading);
    r = run_toolpath_job(model, *reader, *force, stock.get(), o, sinks);
    if (out.gcode) out.gcode->finish();
    if (out.program) out.program->finish(toolpath_summary_text(r, gcode));
    if (out.csv) out.csv->finish();
    out.transaction.commit();
  }
  py::dict d = toolpath_figures(r, gcode);
  d["point"] = toolpath_points(points, model.dof());
  d["force"] = force->describe();
  d["tool_spin"] = describe_tool_spin(o.spin);
  return d;
}

}  // namespace

void bind_machining(py::module_& m) {
  m.def(
      "compensate_toolpath", &run_compensate_toolpath, "robot"_a, "toolpath"_a, "workpiece"_a, "cutter"_a, "force"_a,
      "stock"_a = "", "tool_spin"_a = "optimize", "configuration"_a = py::none(), "seed"_a = py::none(),
      "toolpath_options"_a = "", "predict"_a = true, "csv"_a = py::none(), "program_out"_a = py::none(),
      "A CAM toolpath (G-code .nc/.gcode/.tap or APT/CL data .apt/.cls) compensated for its milling force, as "
      "`deflex offline --toolpath`: workpiece \"x_mm=..,y_mm=..,z_mm=..[,qw..]\", cutter \"diameter_mm=..,flutes=..,"
      "helix_deg=..\", force \"milling:...\", stock \"box:min_mm=..;..;..,max_mm=..,cell_mm=..\" (or ae_mm= and ap_mm= "
      "in the force), tool_spin \"optimize[:...]\" or \"fixed:DEG\". Returns the run's figures (SI), its summary "
      "text, and `point`: arrays a point (position_m, tool_axis in the workpiece frame; spin_rad; wrench in the "
      "base frame about the WAP; q_desired, q_command, tcp_desired, tcp_command, predicted_deflection, ...). csv "
      "and program_out (.nc over the source, .mod RAPID, .src KRL) are written all or none.");

  m.def(
      "milling_force",
      [](const std::string& cutter, const std::string& force, double ae_m, double ap_m, double feed_mm_min,
         double spindle_rpm, const std::string& side, const std::string& turn) {
        const Cutter c = parse_cutter_spec(cutter);
        MillingCut cut;
        cut.cutter = c;
        cut.k = parse_milling_spec(force).coefficients.k;
        cut.fz_m = feed_per_tooth_m(feed_mm_min, spindle_rpm, c.flutes);
        cut.turn = turn_arg(turn);
        if (side != "climb" && side != "conventional") {
          throw InputError(fmt::format("argument side: '{}' is neither climb nor conventional", side));
        }
        if (!(ae_m > 0.0 && ae_m <= c.diameter_m * (1.0 + 1e-9)) || !(ap_m > 0.0 && ap_m <= 1.0)) {
          throw InputError("arguments ae_m, ap_m: the radial width must be in (0, D] and the depth in (0, 1] m");
        }
        const Engagement e =
            uniform_engagement(ae_m, ap_m, c.diameter_m, side == "climb" ? CutSide::kClimb : CutSide::kConventional);
        const MillingForce f = average_milling_force(cut, e);
        const MillingPeak peak = peak_milling_force(cut, e);
        return py::dict("force_n"_a = from_vector(f.force_n), "moment_tip_nm"_a = from_vector(f.moment_tip_nm),
                        "application_height_m"_a = f.application_height_m, "peak_force_n"_a = peak.peak_force_n,
                        "tooth_passing_hz"_a = tooth_passing_frequency_hz(spindle_rpm, c.flutes), "fz_m"_a = cut.fz_m,
                        "entry_rad"_a = e.entry_rad, "exit_rad"_a = e.exit_rad);
      },
      "cutter"_a, "force"_a, "ae_m"_a, "ap_m"_a, "feed_mm_min"_a, "spindle_rpm"_a, "side"_a = "climb", "turn"_a = "M3",
      "The milling force on the tool averaged over a revolution for a radial width ae_m and depth ap_m (m), in the "
      "cut frame (feed, normal = axis x feed, axis from the tip into the spindle), N; its moment about the tip (Nm), "
      "the per-revolution peak (N) and the tooth-passing frequency (Hz). force: \"milling:Ktc_N_mm2=..,...\" or "
      "\"milling:file=COEFFS.yaml\".");

  m.def(
      "fit_cutting_coefficients",
      [](const ArrayLike& fz_m, const ArrayLike& ap_m, const ArrayLike& mean_force_n, int flutes,
         const std::string& turn) {
        const Array fz = to_array(fz_m, "fz_m", 1), ap = to_array(ap_m, "ap_m", 1);
        const Array f = matrix_array(mean_force_n, "mean_force_n", fz.shape(0), 3);
        if (ap.shape(0) != fz.shape(0)) throw InputError("arguments fz_m and ap_m: one value a cut each");
        std::vector<SlotCut> cuts;
        for (py::ssize_t i = 0; i < fz.shape(0); ++i) {
          SlotCut c;
          c.fz_m = fz.data()[i];
          c.ap_m = ap.data()[i];
          c.flutes = flutes;
          c.turn = turn_arg(turn);
          c.mean_force_n = Eigen::Map<const Vector3>(f.data() + 3 * i);
          c.label = fmt::format("cut {}", i + 1);
          cuts.push_back(c);
        }
        const CoefficientFit fit = fit_cutting_coefficients(cuts);
        py::dict k, se;
        for (int i = 0; i < 6; ++i) {
          k[kCoefficientKeys[i]] = coefficient_in_user_units(fit.k, i);
          se[kCoefficientKeys[i]] = coefficient_in_user_units(fit.standard_error, i);
        }
        return py::dict("coefficients"_a = k, "standard_error"_a = se,
                        "residual_rms_n"_a = from_vector(fit.residual_rms_n), "warnings"_a = fit.warnings);
      },
      "fz_m"_a, "ap_m"_a, "mean_force_n"_a, "flutes"_a, "turn"_a = "M3",
      "The cutting and edge coefficients fitted to full-slot cuts, as `deflex cutting-coefficients`: each cut's feed "
      "per tooth and depth (m) and its mean force on the tool in the cut frame (feed, normal, axis), N. Returns the "
      "coefficients and their standard errors in the keys' units (Ktc_N_mm2, ..., Kae_N_mm), the residual RMS per "
      "direction (N) and the warnings.");
}

}  // namespace deflex::python
