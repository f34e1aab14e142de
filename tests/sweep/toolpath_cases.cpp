// Sweep cases of `deflex offline --toolpath`: the shipped pocket (G-code) and swarf pass (APT) with one
// malformation each, the milling options past their limits, a stock the tool never touches and a
// point out of the arm's reach. The expected line is found by the test in the text it wrote.
#include <algorithm>

#include "sweep/sweep_case.hpp"

namespace deflex::test {
namespace {

int toolpath_line_of(const std::string& text, const std::string& anchor) {
  const auto p = text.find(anchor);
  if (p == std::string::npos) throw std::runtime_error("sweep: anchor not found: " + anchor);
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(p), '\n'));
}

const char* const kRobot = "--robot {S}/examples/machining/irb6700_spindle.yaml";
const char* const kCutter = " --cutter diameter_mm=10,flutes=3,helix_deg=30";
const char* const kWorkpiece = " --workpiece x_mm=2000,y_mm=0,z_mm=800";
const char* const kStock = " --stock 'box:min_mm=-50;-40;-20,max_mm=50;40;0,cell_mm=0.5'";
const char* const kOut = " -o {D}/out.csv";

std::string pocket_command(const std::string& file, const std::string& force_extra = "") {
  return std::string("offline ") + kRobot + " --toolpath {D}/" + file + kWorkpiece + kCutter +
         " --force milling:file={S}/data/machining/al7075-t6.yaml" + force_extra + kStock + kOut +
         " --program-out {D}/out.nc";
}

std::string swarf_command(const std::string& file) {
  return std::string("offline ") + kRobot + " --toolpath {D}/" + file + kWorkpiece + kCutter +
         " --force milling:file={S}/data/machining/al7075-t6.yaml,ae_mm=0.5,ap_mm=20" + kOut +
         " --program-out {D}/out.mod";
}

void add_gcode_cases(std::vector<BadInput>& cases) {
  const std::string pocket = source_file("examples/machining/pocket_contour.nc");
  struct Edit {
    std::string tag, from, to, word;
    std::string error_at = {};  ///< the line the error names, when not the edited one
  };
  const std::vector<Edit> edits = {
      {"canned_cycle", "N70 G0 Z1.", "N70 G81 X0 Y0 Z-5. R1.", "G81"},
      {"feed_zero", "N90 G1 X-25. F2000.", "N90 G1 X-25. F0", "F0"},
      {"cut_after_m5", "N70 G0 Z1.", "N70 G0 Z1. M5", "M5", "N80 G1"},
      {"r_arc_short", "N110 G3 X-22. Y-5. I3. J0.", "N110 G3 X-22. Y-5. R1.", "R1."},
      {"coordinate_huge", "N120 G1 X22.", "N120 G1 X200000", "X200000"},
      {"coordinate_nan", "N120 G1 X22.", "N120 G1 Xnan", "Xnan"},
  };
  for (const Edit& e : edits) {
    const std::string text = with(pocket, e.from, e.to);
    cases.push_back(
        {"toolpath_gcode_" + e.tag,
         pocket_command("p.nc"),
         {{"p.nc", text}},
         {"{D}/p.nc:" + std::to_string(toolpath_line_of(text, e.error_at.empty() ? e.to : e.error_at)), e.word}});
  }
  cases.push_back({"toolpath_extension_mpf", pocket_command("p.mpf"), {{"p.mpf", pocket}}, {"{D}/p.mpf", ".mpf"}});
  cases.push_back({"toolpath_program_out_is_the_toolpath",
                   replace_all(pocket_command("p.nc"), "--program-out {D}/out.nc", "--program-out {D}/p.nc"),
                   {{"p.nc", pocket}},
                   {"{D}/p.nc"}});
  cases.push_back({"toolpath_stock_never_touched",
                   replace_all(pocket_command("p.nc"), "box:min_mm=-50;-40;-20,max_mm=50;40;0",
                               "box:min_mm=500;500;-20,max_mm=600;600;0"),
                   {{"p.nc", pocket}},
                   {"{D}/p.nc", "never touches the stock"}});
  {
    const std::string far = with(pocket, "N830 G0 X0. Y0.", "N830 G0 X0. Y3000.");
    cases.push_back({"toolpath_point_out_of_reach",
                     pocket_command("p.nc"),
                     {{"p.nc", far}},
                     {"{D}/p.nc: line " + std::to_string(toolpath_line_of(far, "N830")), "any"}});
  }
  const auto option_case = [&](const std::string& tag, const std::string& from, const std::string& to,
                               const std::vector<std::string>& says) {
    cases.push_back(
        {"toolpath_option_" + tag, replace_all(pocket_command("p.nc"), from, to), {{"p.nc", pocket}}, says});
  };
  option_case("no_flutes", "flutes=3", "flutes=0", {"flutes: 0 is not 1..32"});
  option_case("ae_wider_than_cutter", "al7075-t6.yaml", "al7075-t6.yaml,ae_mm=20", {"ae_mm", "wider"});
  option_case("spin_step", "--program-out", "--tool-spin optimize:step_deg=7 --program-out", {"step_deg", "360"});
  option_case("spin_angle", "--program-out", "--tool-spin fixed:abc --program-out", {"fixed:abc"});
  option_case("workpiece_quaternion", "z_mm=800", "z_mm=800,qw=2,qx=0,qy=0,qz=0", {"qw"});
  option_case("stock_inverted", "max_mm=50;40;0", "max_mm=50;40;-30", {"max_mm", "z"});
  option_case("stock_cell_zero", "cell_mm=0.5", "cell_mm=0", {"cell_mm"});
  option_case("stock_cell_too_fine", "cell_mm=0.5", "cell_mm=0.001", {"cell"});
  option_case("no_workpiece", kWorkpiece, "", {"--workpiece"});
  option_case("no_stock_no_override", kStock, "", {"--stock", "ae_mm"});
  option_case("program_out_unknown", "--program-out {D}/out.nc", "--program-out {D}/out.txt", {"{D}/out.txt", ".txt"});
  option_case("force_not_milling", "--force milling:file={S}/data/machining/al7075-t6.yaml", "--force tool:fz_N=-100",
              {"milling"});
  option_case("milling_without_toolpath", "--toolpath {D}/p.nc",
              "--line 'start_mm=1800;0;800,end_mm=1900;0;800,points=5'", {"--workpiece", "--toolpath"});
}

void add_coefficient_cases(std::vector<BadInput>& cases) {
  const std::string pocket = source_file("examples/machining/pocket_contour.nc");
  const std::string k = source_file("data/machining/al7075-t6.yaml");
  for (const auto& [tag, from, to, key] : std::vector<std::tuple<std::string, std::string, std::string, std::string>>{
           {"negative", "Krc_N_mm2: 168.8", "Krc_N_mm2: -168.8", "Krc_N_mm2"},
           {"absurd", "Ktc_N_mm2: 767", "Ktc_N_mm2: 767e6", "Ktc_N_mm2"},
           {"nan", "Kte_N_mm: 27.7", "Kte_N_mm: .nan", "Kte_N_mm"}}) {
    const std::string text = with(k, from, to);
    cases.push_back({"toolpath_coefficients_" + tag,
                     replace_all(pocket_command("p.nc"), "{S}/data/machining/al7075-t6.yaml", "{D}/k.yaml"),
                     {{"p.nc", pocket}, {"k.yaml", text}},
                     {"{D}/k.yaml:" + std::to_string(toolpath_line_of(text, to)), key}});
  }
}

void add_apt_cases(std::vector<BadInput>& cases) {
  const std::string swarf = source_file("examples/machining/swarf_wall.apt");
  const std::string first_goto = "GOTO/-10.0000,5.5848,-20.0000,0.000000,0.173648,0.984808";
  {
    const std::string text = with(swarf, first_goto, "GOTO/1,2");
    cases.push_back({"toolpath_apt_goto_two_values",
                     swarf_command("s.apt"),
                     {{"s.apt", text}},
                     {"{D}/s.apt:" + std::to_string(toolpath_line_of(text, "GOTO/1,2")), "GOTO"}});
  }
  {
    const std::string anchor = "RAPID\nGOTO/70.0000,24.0515";
    const std::string text = with(swarf, anchor, "CIRCLE/0,0,-20,0,0,1,5\n" + anchor);
    cases.push_back(
        {"toolpath_apt_circle_without_goto", swarf_command("s.apt"), {{"s.apt", text}}, {"{D}/s.apt:", "CIRCLE"}});
  }
  {
    const std::string text = with(swarf, "FEDRAT/MMPM,1500.0000", "FEDRAT/MMPM,0");
    cases.push_back({"toolpath_apt_feed_zero", swarf_command("s.apt"), {{"s.apt", text}}, {"{D}/s.apt:", "feed"}});
  }
  cases.push_back({"toolpath_apt_cutter_disagrees",
                   replace_all(swarf_command("s.apt"), "diameter_mm=10", "diameter_mm=12"),
                   {{"s.apt", swarf}},
                   {"{D}/s.apt: line " + std::to_string(toolpath_line_of(swarf, "CUTTER/")), "10 mm", "12 mm"}});
  cases.push_back({"toolpath_apt_tilted_with_stock",
                   replace_all(swarf_command("s.apt"), ",ae_mm=0.5,ap_mm=20", "") +
                       " --stock 'box:min_mm=-20;-10;-20,max_mm=80;30;0,cell_mm=0.5'",
                   {{"s.apt", swarf}},
                   {"{D}/s.apt: line", "tilted"}});
  cases.push_back({"toolpath_apt_gcode_output",
                   replace_all(swarf_command("s.apt"), "out.mod", "out.nc"),
                   {{"s.apt", swarf}},
                   {"{D}/out.nc", "APT"}});
}

}  // namespace

std::vector<BadInput> toolpath_cases() {
  std::vector<BadInput> cases;
  add_gcode_cases(cases);
  add_coefficient_cases(cases);
  add_apt_cases(cases);
  return cases;
}

}  // namespace deflex::test
