// `deflex offline --toolpath`: G-code or APT/CL data in, the milling force predicted along it from
// the cutter, the coefficients and the stock, the spindle angle chosen for stiffness, and the
// compensated program out (G-code over the source, RAPID or KRL), with the per-point CSV and a chart.
#include <filesystem>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/machining/milling_force_model.hpp"
#include "deflex/machining/stock_spec.hpp"
#include "deflex/offline/toolpath_job.hpp"
#include "deflex/report/svg_charts.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"
#include "deflex/toolpath/workpiece_spec.hpp"
#include "offline_toolpath.hpp"

namespace deflex::cli {
namespace {

/// The one milling model of the --force options.
std::unique_ptr<MillingForceModel> toolpath_force(const ToolpathRunOptions& o, const Cutter& cutter) {
  ForceSpecContext context;
  context.milling = milling_force_specs(cutter);
  if (o.forces.size() != 1) {
    throw InputError(fmt::format(
        "--toolpath compensates for one milling force: give one --force \"milling:...\" ({} given)", o.forces.size()));
  }
  std::vector<std::unique_ptr<ForceModel>> models = parse_force_specs(o.forces.front(), context);
  auto* milling = dynamic_cast<MillingForceModel*>(models.front().get());
  if (milling == nullptr) {
    throw InputError(fmt::format(
        "--toolpath takes the milling force (--force \"milling:...\"): '{}' does not follow the feed and the "
        "engagement",
        o.forces.front()));
  }
  return std::unique_ptr<MillingForceModel>(static_cast<MillingForceModel*>(models.front().release()));
}

/// The outputs, prepared before anything is read.
struct ToolpathOutputs {
  OutputTransaction transaction;
  OutputFile* csv = nullptr;
  OutputFile* program = nullptr;
  OutputFile* plot = nullptr;
  ToolpathOutputKind kind = ToolpathOutputKind::kGcode;
};

void prepare_toolpath_outputs(const ToolpathRunOptions& o, ToolpathOutputs& out) {
  if (!o.program_out.empty()) {
    out.kind = toolpath_output_kind(o.program_out);
    if (out.kind == ToolpathOutputKind::kGcode && toolpath_format_for(o.toolpath) != ToolpathFormat::kGcode) {
      throw InputError(fmt::format(
          "option --program-out: {} is G-code, written over the source program, and {} is APT/CL data: write a robot "
          "program (.mod, .src) instead",
          o.program_out, o.toolpath));
    }
    out.program = &out.transaction.add(o.program_out, "option --program-out");
  }
  if (!o.csv_out.empty()) out.csv = &out.transaction.add(o.csv_out, "option -o");
  if (!o.plot_out.empty()) out.plot = &out.transaction.add(o.plot_out, "option --plot");
}

nlohmann::json toolpath_json(const RobotModel& model, const ToolpathRunOptions& o, const ToolpathJobResult& r,
                             const MillingForceModel& force, const std::string& stock, const ToolSpinOptions& spin,
                             bool gcode) {
  nlohmann::json j{
      {"robot", model.name()},
      {"toolpath", o.toolpath},
      {"force", force.describe()},
      {"stock", stock},
      {"tool_spin", describe_tool_spin(spin)},
      {"configuration", {r.configuration.cf1, r.configuration.cf4, r.configuration.cf6, r.configuration.cfx}},
      {"points", r.points},
      {"cutting_points", r.counts.cut},
      {"in_air_points", r.counts.in_air},
      {"plunges", r.counts.plunges},
      {"rapids", r.counts.rapids},
      {"path_length_mm", r.path_length_m * 1e3},
      {"removed_volume_mm3", r.removed_volume_m3 * 1e9},
      {"mean_cutting_deflection_mm", r.mean_cutting_deflection_m * 1e3},
      {"max_cutting_deflection_mm", r.max_cutting_deflection_m * 1e3},
      {"max_force_N", r.max_force_n},
      {"max_peak_force_N", r.max_peak_force_n},
      {"tooth_passing_Hz", r.tooth_passing_hz},
      {"spin_range_deg", {rad_to_deg(r.spin_min_rad), rad_to_deg(r.spin_max_rad)}},
      {"max_spin_rate_deg_per_mm", rad_to_deg(r.max_spin_rate_rad_per_m) * 1e-3},
      {"spin_margin_violations", r.spin.margin_violations},
      {"max_residual_mm", r.summary.max_residual_m * 1e3},
      {"max_correction_mm", r.summary.max_correction_m * 1e3},
      {"max_joint_correction_deg", rad_to_deg(r.summary.max_joint_correction_rad)}};
  if (gcode) {
    j["gcode"] = {{"max_orientation_correction_mrad", r.max_orientation_correction_rad * 1e3},
                  {"mean_residual_mm", r.mean_gcode_residual_m * 1e3},
                  {"max_residual_mm", r.max_gcode_residual_m * 1e3}};
  }
  nlohmann::json outputs = nlohmann::json::array();
  for (const std::string* f : {&o.program_out, &o.csv_out, &o.plot_out}) {
    if (!f->empty()) outputs.push_back(*f);
  }
  j["outputs"] = outputs;
  return j;
}

}  // namespace

void run_offline_toolpath(const ToolpathRunOptions& o, const std::function<IkRequest(const RobotModel&)>& first_request,
                          int& exit_code) {
  if (o.workpiece.empty()) {
    throw InputError("option --toolpath needs --workpiece \"x_mm=..,y_mm=..,z_mm=..[,qw=..,qx=..,qy=..,qz=..]\"");
  }
  if (o.cutter.empty()) {
    throw InputError(
        "option --toolpath needs --cutter \"diameter_mm=..,flutes=..,helix_deg=..[,corner_radius_mm=..]\"");
  }
  const Cutter cutter = parse_cutter_spec(o.cutter);
  const std::unique_ptr<MillingForceModel> force = toolpath_force(o, cutter);
  std::unique_ptr<Stock> stock;
  if (!o.stock.empty()) stock = parse_stock_spec(o.stock);
  if (!stock && !force->has_full_override()) {
    throw InputError(
        "option --toolpath: give --stock \"box:min_mm=..,max_mm=..,cell_mm=..\" for the engagement, or both ae_mm= and "
        "ap_mm= in --force milling:...");
  }
  ToolpathJobOptions job;
  job.base_T_workpiece = parse_workpiece_spec(o.workpiece);
  job.spin = parse_tool_spin_spec(o.tool_spin);
  const ToolpathOptions reading =
      o.reader_options.empty() ? ToolpathOptions{} : parse_toolpath_options_spec(o.reader_options);
  ToolpathOutputs out;
  prepare_toolpath_outputs(o, out);
  if (out.plot != nullptr) job.chart_samples = 4000;

  const RobotModel model = load_cli_robot("offline", o.robot, o.stiffness);
  require_stiffness(model);
  job.first = first_request(model);
  const std::unique_ptr<ToolpathReader> reader = open_toolpath(o.toolpath, reading);
  const bool gcode = out.program != nullptr && out.kind == ToolpathOutputKind::kGcode;
  std::unique_ptr<GcodeWriteBack> write_back;
  std::unique_ptr<ToolpathProgramWriter> program;
  const std::string header =
      fmt::format("Robot: {}\nToolpath: {}\nForce: {}\nStock: {}\nSpindle angle: {}", model.name(), o.toolpath,
                  force->describe(), stock ? stock->describe() : "none (ae, ap given)", describe_tool_spin(job.spin));
  if (gcode) write_back = std::make_unique<GcodeWriteBack>(o.toolpath, *out.program, reading);
  if (out.program != nullptr && !gcode) {
    ToolpathProgramOptions p;
    p.name = o.name.empty() ? "DeflexToolpath" : o.name;
    p.tool = o.tool;
    p.wobj = o.wobj.empty() ? "wobjDeflex" : o.wobj;
    p.zone = o.zone.empty() ? "z0" : o.zone;
    p.base_T_workpiece = job.base_T_workpiece;
    p.header = header;
    program = std::make_unique<ToolpathProgramWriter>(*out.program, out.kind, p, model);
  }
  std::unique_ptr<OfflineCsvWriter> csv;
  if (out.csv != nullptr) {
    csv = std::make_unique<OfflineCsvWriter>(
        *out.csv, model.dof(), model.name(), force->describe(), true, toolpath_csv_columns(),
        fmt::format("; toolpath {}; spindle angle {}", o.toolpath, describe_tool_spin(job.spin)));
  }
  ToolpathSinks sinks;
  sinks.csv = csv.get();
  sinks.gcode = write_back.get();
  sinks.program = program.get();
  const ToolpathJobResult r = run_toolpath_job(model, *reader, *force, stock.get(), job, sinks);
  const std::string summary = toolpath_summary_text(r, gcode);
  if (write_back) write_back->finish();
  if (program) program->finish(summary);
  if (csv) csv->finish();
  if (out.plot != nullptr) {
    out.plot->write(svg_toolpath_chart(r.chart, std::filesystem::path(o.toolpath).filename().string(), gcode));
  }
  out.transaction.commit();  // every file, or none
  if (o.json) {
    print_json(toolpath_json(model, o, r, *force, stock ? stock->describe() : "", job.spin, gcode));
  } else {
    std::cout << fmt::format("robot: {}\nforce: {}\nstock: {}\nspindle angle: {}\n", model.name(), force->describe(),
                             stock ? stock->describe() : "none (ae_mm, ap_mm given)", describe_tool_spin(job.spin))
              << summary;
    for (const std::string* f : {&o.program_out, &o.csv_out, &o.plot_out}) {
      if (!f->empty()) std::cout << "wrote " << *f << "\n";
    }
  }
  exit_code = 0;
}

}  // namespace deflex::cli
