// `deflex cutting-coefficients`: the milling model's cutting and edge coefficients from the force logs
// of a few full-slot cuts at different feeds per tooth (docs/machining.md, "Cutting coefficients"),
// written as the coefficient file `--force milling:file=` reads.
#include <cmath>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/machining/coefficient_fit.hpp"
#include "deflex/machining/cutter.hpp"
#include "deflex/machining/milling_force.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/key_value_spec.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::cli {
namespace {

constexpr const char* kCutHelp =
    "One full-slot cut (repeat, two or more at different feeds): "
    "\"log=FILE.csv,F_mm_min=..,S_rpm=..,ap_mm=..[,spindle=M3|M4][,feed_axis=+x][,tool_axis=+z]"
    "[,force_on=tool|workpiece][,window_s=FROM;TO][,air_s=FROM;TO]\". FILE: the force sensor's CSV "
    "(t_s,fx_N,fy_N,fz_N[,mx_Nm,my_Nm,mz_Nm]); feed_axis/tool_axis: the log's axis along the feed and along the "
    "tool (tip to spindle); force_on: what the log measured (a wrist sensor: the tool, the default; a table "
    "dynamometer: the workpiece); window_s: the steady cut (default the whole log); air_s: spindle on, not "
    "cutting, subtracted";

/// At fewer revolutions than this in a cut's window, its mean leans on how the sensor sampled the ripple.
constexpr double kFewRevolutions = 10.0;

struct CoeffOpts {
  std::vector<std::string> cuts;
  std::string cutter, out, material, tool;
  bool json = false;
};

struct ParsedCut {
  std::string log;
  double feed_mm_min = 0.0, spindle_rpm = 0.0, ap_mm = 0.0;
  SpindleTurn turn = SpindleTurn::kClockwise;
  SlotLogOptions options;
};

/// "+x", "-y", "z" -> axis index and sign.
void parse_axis(const KeyValueSpec& keys, const std::string& key, int& axis, double& sign) {
  if (!keys.has(key)) return;
  std::string t = keys.text(key);
  sign = 1.0;
  if (!t.empty() && (t[0] == '+' || t[0] == '-')) {
    sign = t[0] == '-' ? -1.0 : 1.0;
    t = t.substr(1);
  }
  if (t != "x" && t != "y" && t != "z") {
    keys.fail(fmt::format("key '{}': '{}' is not one of +x -x +y -y +z -z", key, keys.text(key)));
  }
  axis = t[0] - 'x';
}

void parse_window(const KeyValueSpec& keys, const std::string& key, std::optional<double>& from,
                  std::optional<double>& to) {
  if (!keys.has(key)) return;
  const auto v = keys.numbers(key, 2);
  if (!(v[1] > v[0]))
    keys.fail(fmt::format("key '{}': {:g};{:g} s is not FROM;TO with TO after FROM", key, v[0], v[1]));
  from = v[0];
  to = v[1];
}

ParsedCut parse_cut(const std::string& spec) {
  const KeyValueSpec keys(
      "--cut " + spec, spec,
      {"log", "F_mm_min", "S_rpm", "ap_mm", "spindle", "feed_axis", "tool_axis", "force_on", "window_s", "air_s"});
  for (const char* k : {"log", "F_mm_min", "S_rpm", "ap_mm"}) {
    if (!keys.has(k)) keys.fail(fmt::format("key '{}' is required", k));
  }
  ParsedCut c;
  c.log = keys.text("log");
  if (c.log.empty()) keys.fail("key 'log': give the force log (CSV)");
  c.feed_mm_min = keys.number("F_mm_min", 0.0);
  c.spindle_rpm = keys.number("S_rpm", 0.0);
  c.ap_mm = keys.number("ap_mm", 0.0);
  if (!(c.feed_mm_min > 0.0))
    keys.fail(fmt::format("key 'F_mm_min': {:g} mm/min: a slot cut needs a feed", c.feed_mm_min));
  if (!(c.spindle_rpm > 0.0) || c.spindle_rpm > 2e5) {
    keys.fail(fmt::format("key 'S_rpm': {:g} rpm is outside 0..200000 rpm (the spindle must turn)", c.spindle_rpm));
  }
  if (!(c.ap_mm > 0.0) || c.ap_mm > 1000.0)
    keys.fail(fmt::format("key 'ap_mm': {:g} mm is outside 0..1000 mm", c.ap_mm));
  if (keys.has("spindle")) {
    const std::string& s = keys.text("spindle");
    if (s != "M3" && s != "M4") keys.fail(fmt::format("key 'spindle': '{}' is neither M3 nor M4", s));
    c.turn = s == "M3" ? SpindleTurn::kClockwise : SpindleTurn::kCounterClockwise;
  }
  parse_axis(keys, "feed_axis", c.options.feed_axis, c.options.feed_sign);
  parse_axis(keys, "tool_axis", c.options.tool_axis, c.options.tool_sign);
  if (c.options.feed_axis == c.options.tool_axis) keys.fail("the feed and tool axes must be two different axes");
  if (keys.has("force_on")) {
    const std::string& f = keys.text("force_on");
    if (f != "tool" && f != "workpiece")
      keys.fail(fmt::format("key 'force_on': '{}' is neither tool nor workpiece", f));
    c.options.force_on_workpiece = f == "workpiece";
  }
  parse_window(keys, "window_s", c.options.window_from_s, c.options.window_to_s);
  parse_window(keys, "air_s", c.options.air_from_s, c.options.air_to_s);
  return c;
}

std::string coefficient_line(const CoefficientFit& fit, int i) {
  const double v = coefficient_in_user_units(fit.k, i), se = coefficient_in_user_units(fit.standard_error, i);
  const char* unit = i < 3 ? "N/mm^2" : "N/mm";
  return std::isfinite(se)
             ? fmt::format("  {:<10} {:9.4g} +- {:<8.3g} {}", kCoefficientKeys[i], v, se, unit)
             : fmt::format("  {:<10} {:9.4g} (no standard error from two cuts) {}", kCoefficientKeys[i], v, unit);
}

// One --cut: its log's mean force over the window, with a note when the window holds few revolutions.
SlotCut read_slot_cut(const std::string& spec, const Cutter& cutter, std::vector<std::string>& notes) {
  ParsedCut c = parse_cut(spec);
  c.options.spindle_rpm = c.spindle_rpm;
  const SlotLogMean m = read_slot_log(c.log, c.options);
  const double revolutions = m.revolutions;
  if (revolutions < 1.0) {
    throw InputError(
        fmt::format("{}: the cut window spans {:.4g} s, less than a revolution at {:g} rpm: a slot's "
                    "mean force needs whole revolutions (10 or more)",
                    c.log, m.duration_s, c.spindle_rpm));
  }
  if (revolutions < kFewRevolutions) {
    notes.push_back(
        fmt::format("{}: the cut window holds only {:g} whole revolutions: its mean leans on the "
                    "sampling of the force's ripple ({:g} or more are safe)",
                    c.log, revolutions, kFewRevolutions));
  }
  SlotCut s;
  s.fz_m = feed_per_tooth_m(c.feed_mm_min, c.spindle_rpm, cutter.flutes);
  s.ap_m = c.ap_mm * 1e-3;
  s.flutes = cutter.flutes;
  s.turn = c.turn;
  s.mean_force_n = m.mean_force_n;
  s.label = c.log;
  return s;
}

std::string coefficient_file(const CoeffOpts& o, const Cutter& cutter, const CoefficientFit& fit,
                             const std::vector<SlotCut>& cuts, const std::vector<std::string>& notes) {
  CoefficientSet set;
  set.k = fit.k;
  if (fit.cuts > 2) set.standard_error = fit.standard_error;
  std::string logs;
  for (const SlotCut& c : cuts) logs += (logs.empty() ? "" : ", ") + c.label;
  set.source = fmt::format("deflex cutting-coefficients from {} full-slot cuts: {}", fit.cuts, logs);
  set.material = o.material;
  set.tool = o.tool.empty() ? describe_cutter(cutter) : o.tool;
  std::string comment = fmt::format(
      "Cutting coefficients fitted by deflex cutting-coefficients (docs/machining.md) from {} full-slot cuts with a "
      "{} cutter.\nfeed per tooth {:.4g}..{:.4g} mm; residual RMS of the mean forces {:.2f} {:.2f} {:.2f} N (feed, "
      "normal, axis).\nCut: fz_mm, ap_mm, mean force on the tool along the feed, normal, axis (N):",
      fit.cuts, describe_cutter(cutter), fit.fz_min_m * 1e3, fit.fz_max_m * 1e3, fit.residual_rms_n[0],
      fit.residual_rms_n[1], fit.residual_rms_n[2]);
  for (const SlotCut& c : cuts) {
    comment += fmt::format("\n  {}: {:.4f}, {:g}, {:.2f}, {:.2f}, {:.2f}", c.label, c.fz_m * 1e3, c.ap_m * 1e3,
                           c.mean_force_n[0], c.mean_force_n[1], c.mean_force_n[2]);
  }
  for (const std::string& n : notes) comment += "\nwarning: " + n;
  return coefficient_file_text(set, comment);
}

void print_coefficients_json(const CoeffOpts& o, const CoefficientFit& fit, const std::vector<SlotCut>& cuts,
                             const std::vector<std::string>& notes) {
  nlohmann::json k, se, cut_list = nlohmann::json::array();
  for (int i = 0; i < 6; ++i) {
    k[kCoefficientKeys[i]] = coefficient_in_user_units(fit.k, i);
    const double e = coefficient_in_user_units(fit.standard_error, i);
    se[kCoefficientKeys[i]] = std::isfinite(e) ? nlohmann::json(e) : nlohmann::json(nullptr);
  }
  for (const SlotCut& c : cuts) {
    cut_list.push_back({{"log", c.label},
                        {"fz_mm", c.fz_m * 1e3},
                        {"ap_mm", c.ap_m * 1e3},
                        {"mean_force_N", vector_to_json(c.mean_force_n)}});
  }
  print_json({{"coefficients", k},
              {"standard_error", se},
              {"residual_rms_N", vector_to_json(fit.residual_rms_n)},
              {"force_frame", "feed, normal, axis (force on the tool)"},
              {"cuts", cut_list},
              {"warnings", notes},
              {"output", o.out}});
}

void run(const CoeffOpts& o, int& exit_code) {
  if (o.cuts.size() < 2) throw InputError("give two or more --cut options (full slots at different feeds per tooth)");
  OutputFile out(o.out, "option -o");  // prepared first: the file written is never one read
  const Cutter cutter = parse_cutter_spec(o.cutter);
  std::vector<SlotCut> cuts;
  std::vector<std::string> notes;
  for (const std::string& spec : o.cuts) cuts.push_back(read_slot_cut(spec, cutter, notes));
  const CoefficientFit fit = fit_cutting_coefficients(cuts);
  notes.insert(notes.end(), fit.warnings.begin(), fit.warnings.end());
  out.write(coefficient_file(o, cutter, fit, cuts, notes));
  out.commit();

  for (const std::string& n : notes) std::cerr << "deflex cutting-coefficients: warning: " << n << "\n";
  if (o.json) {
    print_coefficients_json(o, fit, cuts, notes);
  } else {
    std::cout << fmt::format("{} full-slot cuts, feed per tooth {:.4g}..{:.4g} mm, cutter {}:\n", fit.cuts,
                             fit.fz_min_m * 1e3, fit.fz_max_m * 1e3, describe_cutter(cutter));
    for (int i = 0; i < 6; ++i) std::cout << coefficient_line(fit, i) << "\n";
    std::cout << fmt::format("residual RMS of the mean forces: {:.2f} {:.2f} {:.2f} N (feed, normal, axis)\nwrote {}\n",
                             fit.residual_rms_n[0], fit.residual_rms_n[1], fit.residual_rms_n[2], o.out);
  }
  exit_code = 0;
}

void setup_cutting_coefficients(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<CoeffOpts>();
  sub.add_option("--cut", o->cuts, kCutHelp)->required();
  sub.add_option("--cutter", o->cutter, "The cutter of the cuts: \"diameter_mm=..,flutes=..[,helix_deg=..]\"")
      ->required();
  sub.add_option("-o,--output", o->out, "The coefficient file to write (YAML; --force milling:file= reads it)")
      ->required();
  sub.add_option("--material", o->material, "The workpiece material, recorded in the file");
  sub.add_option("--tool", o->tool, "The tool, recorded in the file (default: the cutter's description)");
  sub.add_flag("--json", o->json, "Print one JSON document on stdout");
  sub.callback([o, &exit_code] { run(*o, exit_code); });
}

}  // namespace

DEFLEX_COMMAND("cutting-coefficients",
               "Fit the milling force model's cutting and edge coefficients from force logs of full-slot cuts",
               setup_cutting_coefficients, 43);

}  // namespace deflex::cli
