// The bad-input sweep: generated bad files and options thrown at every subcommand and
// file type. Each must end with exit code 2 and a message naming the input (the file with its line
// or field, or the option), within a time limit, never with an internal error (exit 3, bad_alloc) or
// a silent success; a case whose output cannot be written ends with exit code 1. Files are made
// from the shipped examples by one mutation each; options are found in each subcommand's --help, so
// a new numeric option is swept without touching this file. The file layer's classes (outputs that
// are inputs, links, devices, FIFOs, oversize inputs), malformed programs and values past their
// limits come from file_safety_cases.cpp and program_cases.cpp. After every case the scratch folder
// must hold exactly what it held before: no file deleted, truncated, changed (content or inode) or
// added, not even half-written.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cross/cli_runner.hpp"
#include "sweep/sweep_case.hpp"

namespace deflex::test {
namespace {

namespace fs = std::filesystem;
const std::string kSrc = DEFLEX_SOURCE_DIR;

std::string read(const std::string& rel) { return source_file(rel); }

// Runs deflex with a hard time limit (a hang shows as exit 124); safe to call from several threads.
// stdout goes to a file, or is closed ("-"), or to `stdout_to` (/dev/full).
CliRun run_limited(const std::string& args, int seconds, const std::string& stdout_to = "") {
  static std::atomic<int> counter{0};
  const auto dir = fs::temp_directory_path();
  const std::string tag = std::to_string(::getpid()) + "_" + std::to_string(counter++);
  const auto out = dir / ("deflex_sweep_out_" + tag);
  const auto err = dir / ("deflex_sweep_err_" + tag);
  const std::string stdout_redirect = stdout_to.empty()  ? ">" + out.string()
                                      : stdout_to == "-" ? ">&-"
                                                         : ">" + stdout_to;
  const std::string cmd = "timeout -k 2 " + std::to_string(seconds) + " " + std::string(DEFLEX_CLI) + " " + args + " " +
                          stdout_redirect + " 2>" + err.string() + " </dev/null";
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  fs::remove(out);
  fs::remove(err);
  return r;
}

// --- CSV files: one mutation of one cell, the header or the layout -------------------------------

struct CsvKind {
  std::string kind;     ///< e.g. "wrench"
  std::string base;     ///< a valid file's text
  std::string command;  ///< {F}: the file under test
  std::string column;   ///< the column whose first cell is corrupted
  bool strict_columns;  ///< the reader refuses unknown columns
};

// Line number (1-based) of the header and of the first data row, and the column's index.
struct CsvLayout {
  int header_line = 0, first_row_line = 0;
  std::size_t column = 0;
};

CsvLayout layout_of(const std::string& text, const std::string& column) {
  CsvLayout l;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    if (l.header_line == 0) {
      l.header_line = n;
      std::istringstream cells(line);
      std::string c;
      std::size_t i = 0;
      while (std::getline(cells, c, ',')) {
        if (c == column) l.column = i;
        ++i;
      }
      continue;
    }
    l.first_row_line = n;
    break;
  }
  return l;
}

// The text with line `line_no` (1-based) passed through `edit`.
std::string edit_line(const std::string& text, int line_no, const std::function<std::string(std::string)>& edit) {
  std::istringstream in(text);
  std::string line, out;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    out += (n == line_no ? edit(line) : line) + "\n";
  }
  return out;
}

std::string set_cell(const std::string& line, std::size_t column, const std::string& value) {
  std::vector<std::string> cells;
  std::istringstream in(line);
  std::string c;
  while (std::getline(in, c, ',')) cells.push_back(c);
  cells.at(column) = value;
  std::string out;
  for (std::size_t i = 0; i < cells.size(); ++i) out += (i ? "," : "") + cells[i];
  return out;
}

void add_csv_cases(const CsvKind& k, std::vector<BadInput>& cases) {
  const CsvLayout l = layout_of(k.base, k.column);
  const std::string file = k.kind + ".csv";
  const std::string at_row = "{D}/" + file + ":" + std::to_string(l.first_row_line);
  const auto cell_case = [&](const std::string& tag, const std::string& value, const std::string& says) {
    cases.push_back(
        {k.kind + "_cell_" + tag,
         replace_all(k.command, "{F}", "{D}/" + file),
         {{file, edit_line(k.base, l.first_row_line, [&](std::string s) { return set_cell(s, l.column, value); })}},
         {at_row, "'" + k.column + "'", says}});
  };
  cell_case("huge", "1e308", "outside");
  cell_case("minus_huge", "-1e308", "outside");
  cell_case("overflow", "1e999", "not a finite number");
  cell_case("nan", "nan", "not a finite number");
  cell_case("inf", "inf", "not a finite number");
  cell_case("text", "abc", "is not a number");
  cell_case("hex", "0x10", "is not a number");
  cell_case("decimal_comma", "1;5", "is not a number");
  cell_case("empty", "", "empty cell");
  cases.push_back({k.kind + "_extra_cell",
                   replace_all(k.command, "{F}", "{D}/" + file),
                   {{file, edit_line(k.base, l.first_row_line, [](std::string s) { return s + ",7"; })}},
                   {at_row, "cells, the header has"}});
  cases.push_back({k.kind + "_semicolons",
                   replace_all(k.command, "{F}", "{D}/" + file),
                   {{file, replace_all(k.base, ",", ";")}},
                   {"{D}/" + file + ":" + std::to_string(l.header_line), "commas"}});
  cases.push_back({k.kind + "_duplicate_column",
                   replace_all(k.command, "{F}", "{D}/" + file),
                   {{file, edit_line(k.base, l.header_line,
                                     [&](std::string s) { return set_cell(s, l.column == 0 ? 1 : 0, k.column); })}},
                   {"{D}/" + file + ":" + std::to_string(l.header_line), "appears twice"}});
  cases.push_back({k.kind + "_empty_file",
                   replace_all(k.command, "{F}", "{D}/" + file),
                   {{file, ""}},
                   {"{D}/" + file, "no header row"}});
  cases.push_back({k.kind + "_missing_file",
                   replace_all(k.command, "{F}", "{D}/no-such-" + file),
                   {},
                   {"{D}/no-such-" + file, "does not exist"}});
  cases.push_back({k.kind + "_directory", replace_all(k.command, "{F}", "{D}"), {}, {"{D}", "directory"}});
  if (k.strict_columns) {
    // A misspelt extra column ("fx_Nx") beside the real ones, a 0 in every row for it.
    std::string text;
    std::istringstream in(k.base);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      const bool data = n > l.header_line && !line.empty() && line[0] != '#';
      text += line + (n == l.header_line ? "," + k.column + "x" : data ? ",0" : "") + "\n";
    }
    cases.push_back({k.kind + "_unknown_column",
                     replace_all(k.command, "{F}", "{D}/" + file),
                     {{file, text}},
                     {"{D}/" + file, "unknown column '" + k.column + "x'", "did you mean '" + k.column + "'"}});
  }
}

// --- YAML files: one mutation each ----------------------------------------------------------------

struct YamlKind {
  std::string kind;
  std::string base;
  std::string command;
  std::vector<std::tuple<std::string, std::string, std::string, std::string>> edits;  ///< tag, from, to, field said
};

void add_yaml_cases(const YamlKind& k, std::vector<BadInput>& cases) {
  const std::string file = k.kind + ".yaml";
  const std::string cmd = replace_all(k.command, "{F}", "{D}/" + file);
  for (const auto& [tag, from, to, field] : k.edits) {
    ASSERT_NE(k.base.find(from), std::string::npos) << k.kind << ": " << from;
    std::string text = k.base;
    text.replace(text.find(from), from.size(), to);
    cases.push_back({k.kind + "_" + tag, cmd, {{file, text}}, {"{D}/" + file + ":", field}});
  }
  // The first top-level key again at the end: yaml-cpp would keep the first silently.
  const std::string first_key = k.base.substr(
      k.base.find("\ndeflex_") + 1, k.base.find(':', k.base.find("\ndeflex_")) - k.base.find("\ndeflex_") - 1);
  cases.push_back({k.kind + "_duplicate_key",
                   cmd,
                   {{file, k.base + "\n" + first_key + ": 1\n"}},
                   {"{D}/" + file + ":", "'" + first_key + "'", "given twice"}});
  cases.push_back({k.kind + "_unknown_key",
                   cmd,
                   {{file, k.base + "\nnmae: x\n"}},
                   {"{D}/" + file + ":", "unknown field", "did you mean 'name'"}});
  cases.push_back({k.kind + "_syntax", cmd, {{file, k.base + "\n  - [unclosed\n"}}, {"{D}/" + file + ":", "YAML"}});
  cases.push_back({k.kind + "_empty", cmd, {{file, ""}}, {"{D}/" + file}});
  cases.push_back({k.kind + "_missing",
                   replace_all(k.command, "{F}", "{D}/no-such.yaml"),
                   {},
                   {"{D}/no-such.yaml", "does not exist"}});
}

std::string tracker_csv(double z_mm) {
  std::string s = "t_s,x_mm,y_mm,z_mm\n";
  for (int i = 0; i <= 200; ++i) {
    const double a = 2.0 * 3.14159265358979 * i / 200.0;
    s += std::to_string(i * 0.01) + "," + std::to_string(1500 + 100 * std::cos(a)) + "," +
         std::to_string(100 * std::sin(a)) + "," + std::to_string(z_mm) + "\n";
  }
  return s;
}

std::vector<BadInput> file_cases() {
  std::vector<BadInput> cases;
  const std::string robot = "{S}/examples/robots/kuka_kr210_r2700.yaml";
  add_csv_cases({"wrench", read("examples/offline/square_wrench.csv"),
                 "offline --path {S}/examples/offline/square_path.csv --force table:{F} -o {D}/out.csv", "index", true},
                cases);
  add_csv_cases({"wrench_fz", read("examples/offline/square_wrench.csv"),
                 "offline --path {S}/examples/offline/square_path.csv --force table:{F} -o {D}/out.csv", "fz_N", true},
                cases);
  {
    // The issue's case: an index column named "Index" was ignored and every row taken in file order.
    const std::string w = read("examples/offline/square_wrench.csv");
    cases.push_back({"wrench_index_capitalised",
                     "offline --path {S}/examples/offline/square_path.csv --force table:{D}/w.csv -o {D}/out.csv",
                     {{"w.csv", replace_all(w, "index,fx_N", "Index,fx_N")}},
                     {"{D}/w.csv", "unknown column 'Index'", "did you mean 'index'"}});
  }
  add_csv_cases({"path", read("examples/offline/square_path.csv"),
                 "offline --path {F} --force constant:fz_N=-100 -o {D}/out.csv", "x_mm", true},
                cases);
  // Tracker files may carry extra columns (an instrument's quality flag): not strict.
  add_csv_cases({"tracker", tracker_csv(1000.0), "evaluate --unloaded {F} --loaded {S}/examples/evaluate/loaded_uc.csv",
                 "z_mm", false},
                cases);
  add_csv_cases({"tracker_time", tracker_csv(1000.0),
                 "evaluate --unloaded {S}/examples/evaluate/unloaded.csv --loaded {F}", "t_s", false},
                cases);
  add_csv_cases({"measurements", read("examples/identify/kr210_synthetic_measurements.csv"),
                 "identify --robot " + robot + " --data {F}", "fy_N", false},
                cases);
  add_csv_cases({"measurements_joint", read("examples/identify/kr210_synthetic_measurements.csv"),
                 "identify --robot " + robot + " --data {F}", "q2_deg", false},
                cases);
  add_csv_cases({"payload", read("examples/online/payload_poses.csv"), "identify-payload --data {F} -o {D}/p.yaml",
                 "fz_N", false},
                cases);
  add_csv_cases({"force_replay", read("examples/online/force_replay.csv"),
                 "online --link egm-path --egm-port 0 --force-source csv:{F} --duration-s 0.1", "fx_N", true},
                cases);

  // A slot-cut log of `cutting-coefficients`, beside a good second cut.
  const std::string slot_cut =
      " --cut log={S}/examples/machining/slot_cuts/slot_1800.csv,F_mm_min=1800,S_rpm=9000,ap_mm=4";
  add_csv_cases({"slot_log", read("examples/machining/slot_cuts/slot_900.csv"),
                 "cutting-coefficients --cutter diameter_mm=10,flutes=3 -o {D}/k.yaml --cut "
                 "log={F},F_mm_min=900,S_rpm=9000,ap_mm=4" +
                     slot_cut,
                 "fy_N", true},
                cases);
  for (const auto& [tag, cut, cutter, says] :
       std::vector<std::tuple<std::string, std::string, std::string, std::string>>{
           {"zero_feed", "F_mm_min=0,S_rpm=9000,ap_mm=4", "diameter_mm=10,flutes=3", "'F_mm_min': 0 mm/min"},
           {"zero_spindle", "F_mm_min=900,S_rpm=0,ap_mm=4", "diameter_mm=10,flutes=3", "'S_rpm': 0 rpm"},
           {"no_flutes", "F_mm_min=900,S_rpm=9000,ap_mm=4", "diameter_mm=10,flutes=0", "flutes: 0 is not 1..32"},
           {"same_feed", "F_mm_min=1800,S_rpm=9000,ap_mm=4", "diameter_mm=10,flutes=3", "two different feeds"},
           {"tool_axis_twice", "F_mm_min=900,S_rpm=9000,ap_mm=4,feed_axis=z", "diameter_mm=10,flutes=3",
            "two different axes"}}) {
    cases.push_back({"slot_cut_" + tag,
                     "cutting-coefficients --cutter " + cutter +
                         " -o {D}/k.yaml --cut log={S}/examples/machining/"
                         "slot_cuts/slot_900.csv," +
                         cut + slot_cut,
                     {},
                     {says}});
  }

  {
    // In-range forces 10,000 times the example's: a payload of some 85 t, which online would refuse,
    // so identify-payload must not write it.
    std::string heavy;
    std::istringstream in(read("examples/online/payload_poses.csv"));
    for (std::string line; std::getline(in, line);) {
      if (!line.empty() && line[0] != '#' && line.rfind("qw", 0) != 0) {
        std::vector<std::string> cells;
        std::istringstream cs(line);
        for (std::string c; std::getline(cs, c, ',');) cells.push_back(c);
        for (std::size_t k = 4; k < 7; ++k) cells[k] = std::to_string(std::stod(cells[k]) * 1e4);
        line.clear();
        for (std::size_t k = 0; k < cells.size(); ++k) line += (k ? "," : "") + cells[k];
      }
      heavy += line + "\n";
    }
    cases.push_back({"payload_absurd_mass",
                     "identify-payload --data {D}/heavy.csv -o {D}/p.yaml",
                     {{"heavy.csv", heavy}},
                     {"{D}/heavy.csv", "payload mass", "outside"}});
  }
  const std::string fk = "fk --robot {F} --joints-deg 0,30,10,0,50,0";
  add_yaml_cases({"robot",
                  read("examples/robots/kuka_kr210_r2700.yaml"),
                  fk,
                  {{"stiffness_huge", "3.5e6,", "1e308,", "joint_stiffness_Nm_per_rad[1]"},
                   {"stiffness_tiny", "3.5e6,", "1e-3,", "joint_stiffness_Nm_per_rad[1]"},
                   {"stiffness_nan", "3.5e6,", ".nan,", "joint_stiffness_Nm_per_rad[1]"},
                   {"dh_length_huge", "a: 1.150", "a: 1e308", "kinematics.joints[2].a"},
                   {"dh_length_nan", "a: 1.150", "a: nan", "kinematics.joints[2].a"},
                   {"limit_huge", "max: 85}", "max: 1e300}", "kinematics.joints[2].max"},
                   {"tool_huge", "[0.060, 0, 0.250]", "[0.060, 0, 1e308]", "tool_frame.position[3]"},
                   {"tool_far", "[0.060, 0, 0.250]", "[0.060, 0, 1e5]", "tool_frame.position[3]"},
                   {"quaternion_text", "quaternion_wxyz: [1, 0, 0, 0]}\ntool", "quaternion_wxyz: [1, x, 0, 0]}\ntool",
                    "base_frame.quaternion_wxyz[2]"},
                   {"units_unknown", "length: m,", "length: inch,", "units.length"}}},
                 cases);
  add_yaml_cases({"sensor",
                  read("examples/online/sensor_3axis.yaml"),
                  "online --link egm-path --egm-port 0 --sensor-config {F} --force-source "
                  "csv:{S}/examples/online/force_replay.csv --duration-s 0.1",
                  {{"mass_huge", "mass_kg: 8.5", "mass_kg: 2.8e305", "payload.mass_kg"},
                   {"mass_negative", "mass_kg: 8.5", "mass_kg: -1", "payload.mass_kg"},
                   {"rate_huge", "sample_rate_hz: 1000", "sample_rate_hz: 1e300", "sample_rate_hz"},
                   {"bias_nan", "[1.5, -0.8, 2.2]", "[1.5, .nan, 2.2]", "bias.force_N[2]"},
                   {"cog_huge", "[0, 0, 0.09]", "[0, 0, 1e308]", "payload.cog_sensor_m[3]"}}},
                 cases);
  add_yaml_cases(
      {"case",
       read("data/cases/paper.yaml"),
       "case-study --case {F} --quick --seeds 1 --no-sweep --no-budget --no-progress --out {D}/cs",
       {{"sweep_load_negative", "sweep_load_N: 650", "sweep_load_N: -650", "protocol.sweep_load_N"},
        {"sweep_load_huge", "sweep_load_N: 650", "sweep_load_N: 1e9", "protocol.sweep_load_N"},
        {"drift_offset_huge", "offset_um: 12 ", "offset_um: 1e15 ", "drift.offset_um"},
        {"tracker_rate_huge", "rate_Hz: 1000\n", "rate_Hz: 1e12\n", "rate_Hz"},
        {"servo_period_tiny", "servo_period_ms: 4", "servo_period_ms: 1e-9", "controller.servo_period_ms"},
        {"paper_uc_short", "paper_uc_mm: [0.12, 0.38, 0.62]", "paper_uc_mm: [0.12, 0.38]", "setups[1].paper_uc_mm"},
        {"link_unknown", "link: ur-rtde", "link: ur-rtdx", "setups[10].link"},
        {"points_huge", "points: 81 ", "points: 1e9 ", "circle.points"},
        {"lost_motion_short", "lost_motion_urad: [35, 35, 35, 60, 60, 60]", "lost_motion_urad: [35, 35, 35]",
         "true_robot.lost_motion_urad"},
        {"seal_friction_nan", "seal_friction_pct: 25 ", "seal_friction_pct: .nan ", "ldbb.seal_friction_pct"},
        {"clock_rate_huge", "clock_rate_ppm: 50 ", "clock_rate_ppm: 1e300 ", "tracker.clock_rate_ppm"},
        {"moment_crosstalk_negative", "moment_crosstalk_pct: 0.2 ", "moment_crosstalk_pct: -0.2 ",
         "sensor.moment_crosstalk_pct"},
        {"hardening_long", "hardening_softening: [0.5, 0.5, 0.5, 0.5, 0.5, 0.5]",
         "hardening_softening: [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]", "true_robot.hardening_softening"},
        {"sensor_rate_huge", "rate_Hz: 1000\n  gravity_mass", "rate_Hz: 100000\n  gravity_mass", "sensor.rate_Hz"}}},
      cases);

  // URDF structure (the URDF reader names the line and the joint).
  const std::string urdf = read("examples/robots/ros-industrial/abb_irb6700_235_265.urdf");
  const auto urdf_case = [&](const std::string& tag, const std::string& from, const std::string& to,
                             const std::string& says) {
    std::string text = urdf;
    const auto p = text.find(from);
    if (p == std::string::npos) {
      ADD_FAILURE() << "URDF anchor not found: " << from;
      return;
    }
    text.replace(p, from.size(), to);
    cases.push_back({"urdf_" + tag,
                     "fk --robot {D}/arm.urdf --joints-deg 0,30,10,0,50,0",
                     {{"arm.urdf", text}},
                     {"{D}/arm.urdf", says}});
  };
  urdf_case("two_parents", "<child link=\"link_2\"/>", "<child link=\"link_3\"/>", "two parents");
  urdf_case("mimic_on_chain", "<joint name=\"joint_2\" type=\"revolute\">",
            "<joint name=\"joint_2\" type=\"revolute\"><mimic joint=\"joint_1\"/>", "mimic");
  urdf_case("origin_huge", "<origin xyz=\"0 0 1.135\"", "<origin xyz=\"0 0 1e308\"", "outside");
  return cases;
}

// --- Options: every subcommand, found in --help ------------------------------------------------

std::vector<std::string> subcommands() {
  const CliRun r = run_cli("--help");
  std::vector<std::string> out;
  const std::regex line(R"(^  ([a-z][a-z0-9-]+)\s{2,})");
  std::istringstream in(r.out);
  std::string l;
  bool in_list = false;
  while (std::getline(in, l)) {
    in_list = in_list || l.rfind("Subcommands:", 0) == 0;
    std::smatch m;
    if (in_list && std::regex_search(l, m, line)) out.push_back(m[1]);
  }
  return out;
}

// Numeric options of a subcommand (CLI11 shows them as "--name FLOAT" / "INT" / "UINT").
std::vector<std::pair<std::string, bool>> numeric_options(const std::string& sub) {
  const CliRun r = run_cli(sub + " --help");
  std::vector<std::pair<std::string, bool>> out;
  const std::regex opt(R"((--[A-Za-z0-9-]+) (FLOAT|INT|UINT)\b)");
  for (auto it = std::sregex_iterator(r.out.begin(), r.out.end(), opt); it != std::sregex_iterator(); ++it) {
    out.emplace_back((*it)[1], (*it)[2] != "FLOAT");
  }
  return out;
}

std::vector<BadInput> option_cases() {
  std::vector<BadInput> cases;
  const auto subs = subcommands();
  EXPECT_GE(subs.size(), 12U) << "subcommands not found in deflex --help";
  for (const std::string& sub : subs) {
    const std::string tag = replace_all(sub, "-", "_");
    cases.push_back({sub + "_unknown_option", sub + " --no-such-option 1", {}, {"unknown option '--no-such-option'"}});
    for (const auto& [opt, integer] : numeric_options(sub)) {
      const std::string o = replace_all(opt.substr(2), "-", "_");
      for (const auto& [vtag, value] : std::vector<std::pair<std::string, std::string>>{
               {"nan", "nan"}, {"huge", "1e308"}, {"minus_huge", "-1e308"}, {"text", "abc"}}) {
        cases.push_back({tag + "_" + o + "_" + vtag, sub + " " + opt + " " + value, {}, {opt}});
      }
      if (integer) {
        cases.push_back({tag + "_" + o + "_fraction", sub + " " + opt + " 1.5", {}, {opt, "whole number"}});
      }
    }
  }
  // Typos named with the nearest option or subcommand.
  cases.push_back(
      {"typo_option", "fk --jionts-deg 0,30,10,0,50,0", {}, {"'--jionts-deg'", "did you mean '--joints-deg'"}});
  cases.push_back({"typo_subcommand", "defelct", {}, {"'defelct'", "did you mean 'deflect'"}});
  cases.push_back({"missing_required", "fk", {}, {"--joints-deg", "required"}});
  cases.push_back({"threads_negative", "case-study --threads -1", {}, {"--threads", "0..256"}});
  cases.push_back({"identify_without_robot",
                   "identify --data {S}/examples/identify/kr210_synthetic_measurements.csv",
                   {},
                   {"--robot", "required"}});
  cases.push_back({"plan_without_robot",
                   "plan-calibration --region-mm 1300,1900,-400,400,500,1100 --load-N 800 -o {D}/p.csv",
                   {},
                   {"--robot", "required"}});
  cases.push_back({"max_rel_nan",
                   "identify --robot builtin --data {S}/examples/identify/kr210_synthetic_measurements.csv "
                   "--max-relative-std-error nan",
                   {},
                   {"--max-relative-std-error"}});
  cases.push_back({"deflect_without_stiffness",
                   "deflect --robot {S}/examples/robots/ros-industrial/fanuc_m10ia.urdf --joints-deg 0,0,0,0,-90,0 "
                   "--wrench 0,0,-100,0,0,0",
                   {},
                   {"no joint stiffness", "--stiffness-Nm-per-rad"}});
  cases.push_back({"joints_wrong_count", "fk --joints-deg 0,30,10", {}, {"--joints-deg", "expected 6"}});
  cases.push_back({"joints_decimal_comma", "fk --joints-deg '0;5,30,10,0,50,0'", {}, {"--joints-deg"}});
  cases.push_back({"stiffness_option_huge",
                   "deflect --joints-deg 0,30,10,0,50,0 --wrench 0,0,-1,0,0,0 "
                   "--stiffness-Nm-per-rad 1e308,1e6,1e6,1e6,1e6,1e6",
                   {},
                   {"--stiffness-Nm-per-rad", "outside"}});
  cases.push_back({"force_spec_typo",
                   "offline --circle default --force 'ldbb:phi_deg=45,forse_N=125' -o {D}/o.csv",
                   {},
                   {"forse_N", "did you mean 'force_N'"}});
  cases.push_back({"circle_points_huge",
                   "offline --circle points=1000000000 --force constant:fz_N=1 -o {D}/o.csv",
                   {},
                   {"key 'points'", "3..1000000"}});
  cases.push_back({"line_points_huge",
                   "offline --line 'start_mm=1500;0;1000,end_mm=1600;0;1000,points=1000000000' --force constant:fz_N=1 "
                   "-o {D}/o.csv",
                   {},
                   {"key 'points'", "2..100000000"}});
  cases.push_back({"force_spec_huge",
                   "offline --circle default --force 'constant:fz_N=1e308' -o {D}/o.csv",
                   {},
                   {"fz_N", "outside"}});
  return cases;
}

std::vector<BadInput> all_cases() {
  std::vector<BadInput> cases = file_cases();
  for (auto* more : {option_cases, output_cases, input_file_cases, program_cases, limit_cases, tracker_sensor_cases,
                     toolpath_cases}) {
    for (auto& c : more()) cases.push_back(std::move(c));
  }
  return cases;
}

// --- Nothing lost: the scratch folder before and after a case --------------------------------

struct FileState {
  char type = '?';  // f file, l link, d folder, p FIFO, o other
  std::uintmax_t size = 0;
  ino_t inode = 0;
  std::string content;  // a file's bytes (up to 1 MiB; larger ones by size and inode), a link's target
  friend bool operator==(const FileState&, const FileState&) = default;
};

// Every entry under `dir`, by relative path, looked at without following links or opening FIFOs.
std::map<std::string, FileState> snapshot(const fs::path& dir) {
  std::map<std::string, FileState> out;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    struct stat st {};
    if (::lstat(it->path().c_str(), &st) != 0) continue;
    FileState f;
    f.inode = st.st_ino;
    f.size = static_cast<std::uintmax_t>(st.st_size);
    if (S_ISREG(st.st_mode)) {
      f.type = 'f';
      if (f.size <= (1u << 20)) f.content = slurp(it->path());
    } else if (S_ISLNK(st.st_mode)) {
      f.type = 'l';
      f.content = fs::read_symlink(it->path(), ec).string();
    } else if (S_ISDIR(st.st_mode)) {
      f.type = 'd';
      f.size = 0;
    } else {
      f.type = S_ISFIFO(st.st_mode) ? 'p' : 'o';
    }
    out[fs::relative(it->path(), dir).string()] = f;
  }
  return out;
}

// "" when `after` is `before`, else what was deleted, added or changed.
std::string changes(const std::map<std::string, FileState>& before, const std::map<std::string, FileState>& after) {
  std::string out;
  for (const auto& [name, f] : before) {
    const auto it = after.find(name);
    if (it == after.end()) {
      out += "deleted " + name + "; ";
    } else if (!(it->second == f)) {
      out += "changed " + name + (it->second.inode != f.inode ? " (inode)" : "") +
             (it->second.size != f.size
                  ? " (size " + std::to_string(f.size) + " -> " + std::to_string(it->second.size) + ")"
                  : "") +
             "; ";
    }
  }
  for (const auto& [name, f] : after) {
    if (before.count(name) == 0) out += "added " + name + "; ";
  }
  return out;
}

// "" when the case behaves, else what went wrong.
std::string check(const BadInput& c) {
  const fs::path dir = fs::temp_directory_path() / ("deflex_sweep_" + std::to_string(::getpid()) + "_" + c.name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto expand = [&](const std::string& s) {
    return replace_all(replace_all(s, "{D}", dir.string()), "{S}", kSrc);
  };
  std::string problems;
  try {
    for (const auto& [name, text] : c.files) {
      std::ofstream(dir / name, std::ios::binary) << text;
    }
    if (c.setup) c.setup(dir);
  } catch (const std::exception& e) {
    problems += std::string("setup failed: ") + e.what() + "; ";
  }
  const auto before = snapshot(dir);
  const CliRun r = run_limited(expand(c.args), 20, c.stdout_to);
  const std::string lost = changes(before, snapshot(dir));
  if (!lost.empty()) {
    problems += "the folder changed: " + lost;
  }
  if (r.exit_code != c.exit_code) {
    problems += "exit code " + std::to_string(r.exit_code) + " (expected " + std::to_string(c.exit_code) + "); ";
  }
  for (const std::string& e : c.expect) {
    if (r.err.find(expand(e)) == std::string::npos) {
      problems += "stderr does not say '" + expand(e) + "'; ";
    }
  }
  fs::remove_all(dir);
  if (problems.empty()) {
    return {};
  }
  return c.name + ": " + problems + "\n  deflex " + expand(c.args) + "\n  stderr: " + r.err.substr(0, 1500) +
         (r.out.empty() ? "" : "\n  stdout: " + r.out.substr(0, 500));
}

// One test over all cases, two at a time: each case is a process start, and a ctest entry per case
// would re-run the option discovery in every process.
TEST(BadInputSweep, EveryBadInputExitsTwoNamingIt) {
  std::vector<BadInput> cases = all_cases();
  // DEFLEX_SWEEP_ONLY=TEXT runs the cases whose name holds TEXT (to look at one class while fixing it).
  const char* only = std::getenv("DEFLEX_SWEEP_ONLY");
  if (only != nullptr) {
    std::erase_if(cases, [&](const BadInput& c) { return c.name.find(only) == std::string::npos; });
  }
  std::set<std::string> names;
  for (const auto& c : cases) {
    EXPECT_TRUE(names.insert(c.name).second) << "two cases named " << c.name;
  }
  std::vector<std::string> failures(cases.size());
  std::atomic<std::size_t> next{0};
  const auto worker = [&] {
    for (std::size_t i = next++; i < cases.size(); i = next++) {
      failures[i] = check(cases[i]);
    }
  };
  std::thread a(worker), b(worker);
  a.join();
  b.join();
  int failed = 0;
  for (const auto& f : failures) {
    if (!f.empty()) {
      ADD_FAILURE() << f;
      ++failed;
    }
  }
  std::cout << cases.size() << " bad inputs thrown at deflex, " << failed << " misbehaved\n";
  EXPECT_GE(cases.size(), only != nullptr ? 1U : 700U);
  // The devices the cases wrote to are still devices (deflex never renames or removes one).
  for (const char* device : {"/dev/null", "/dev/full", "/dev/zero"}) {
    struct stat st {};
    EXPECT_TRUE(::lstat(device, &st) == 0 && S_ISCHR(st.st_mode)) << device;
  }
}

}  // namespace
}  // namespace deflex::test
