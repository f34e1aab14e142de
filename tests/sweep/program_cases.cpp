// Sweep cases about what files say: the shipped RAPID module and KRL program with one malformation
// each, every RAPID one in the module's own CR LF, in LF and in CR alone (the line the error names
// must be the same in all three); URDF, YAML and option values past their limits; keys repeated in
// option specs. The expected line is found by the test in the text it wrote, not taken from deflex.
#include <algorithm>
#include <cstdio>
#include <tuple>

#include "sweep/sweep_case.hpp"

namespace deflex::test {
namespace {

/// The 1-based line of the first `anchor` in `text` (lines counted by '\n').
int line_of(const std::string& text, const std::string& anchor) {
  const auto p = text.find(anchor);
  if (p == std::string::npos) {
    throw std::runtime_error("sweep: anchor not found: " + anchor);
  }
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(p), '\n'));
}

/// The text with every line end made `eol`.
std::string with_line_ends(const std::string& text, const std::string& eol) {
  std::string lf = replace_all(text, "\r\n", "\n");
  return replace_all(lf, "\n", eol);
}

struct Mutation {
  std::string tag;
  std::string from, to;
  std::string error_at;  ///< the anchor (in the mutated text) of the line the error names; "" the mutation's own
  std::vector<std::string> says;
};

void add_rapid_cases(std::vector<BadInput>& cases) {
  const std::string module = replace_all(source_file("examples/programs/deburr_housing.mod"), "\r\n", "\n");
  const std::string cmd = "offline --program-in {D}/m.mod --force tool:fz_N=-150 --program-out {D}/out.mod";
  const std::vector<Mutation> mutations = {
      {"five_external_axes",
       "Target_10:=[[0,0,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]",
       "Target_10:=[[0,0,0],[0,1,0,0],[-1,-1,1,0],[9E+09,9E+09,9E+09,9E+09,9E+09]]",
       "",
       {"field 'extax'", "5 values"}},
      {"nan_quaternion",
       "Target_20:=[[250,0,0],[0,1,0,0]",
       "Target_20:=[[250,0,0],[nan,1,0,0]",
       "",
       {"field 'rot.q1'", "'nan' is not a number"}},
      {"four_element_position",
       "Target_30:=[[325,75,0]",
       "Target_30:=[[325,75,0,1]",
       "",
       {"field 'trans'", "4 values"}},
      {"three_element_confdata",
       "Target_40:=[[250,150,0],[0,1,0,0],[-1,-1,1,0]",
       "Target_40:=[[250,150,0],[0,1,0,0],[-1,-1,1]",
       "",
       {"field 'robconf'", "3 values"}},
      {"five_value_jointtarget",
       "jHome:=[[0,10,10,0,60,0]",
       "jHome:=[[0,10,10,0,60]",
       "",
       {"field 'robax'", "5 values"}},
      {"nan_tooldata", "[4.5,[0,0,120]", "[nan,[0,0,120]", "", {"tooldata 'tDeburr'", "field 'tload.mass'"}},
      {"tooldata_quaternion_norm_3",
       "[0.965926,0,0.258819,0]",
       "[3,0,0,0]",
       "MoveAbsJ jHome",
       {"tooldata 'tDeburr'", "not of unit length"}},
      {"wobjdata_string_not_string",
       "[FALSE,TRUE,\"\",[[1400",
       "[FALSE,TRUE,7,[[1400",
       "",
       {"wobjdata 'wobjHousing'", "field 'ufmec'"}},
      {"offs_three_arguments",
       "MoveJ Offs(Target_10,0,0,nApproach)",
       "MoveJ Offs(Target_10,0,nApproach)",
       "",
       {"Offs takes 4 arguments", "3 given"}},
      {"offs_optional_argument",
       "MoveJ Offs(Target_10,0,0,nApproach)",
       "MoveJ Offs(Target_10,0,0,nApproach\\Rz:=3)",
       "",
       {"Offs takes no optional argument"}},
      {"reltool_unknown_switch", "\\Rz:=15", "\\Rq:=15", "", {"RelTool: unknown optional argument '\\Rq'"}},
      {"unknown_motion_argument",
       "MoveL Target_20,vDeburr",
       "MoveL Target_20\\Speed:=3,vDeburr",
       "",
       {"MoveL: unknown optional argument '\\Speed'"}},
      {"declared_twice",
       "    CONST num nApproach:=50;",
       "    CONST num nApproach:=50;\n    CONST num nApproach:=60;",
       "nApproach:=60",
       {"'nApproach' is declared twice"}},
      {"number_as_target",
       "MoveL Target_10,v50",
       "MoveL nApproach,v50",
       "",
       {"'nApproach' is a num", "not a robtarget"}},
      {"index_past_the_end", "MoveL Edge{2}", "MoveL Edge{4}", "", {"index 4 is outside Edge{3}"}},
      // RAPID numbers elements from 1: Edge{0} and Edge{-1} stop the controller, they are no array used whole.
      {"index_zero", "MoveL Edge{2}", "MoveL Edge{0}", "", {"index 0 is outside Edge{...}", "from 1"}},
      {"index_negative", "MoveL Edge{2}", "MoveL Edge{-1}", "", {"index -1 is outside Edge{...}"}},
      // A routine without its end: the controller refuses the module (main would run into ENDMODULE).
      {"no_endproc", "    ENDPROC\n", "", "PROC main()", {"PROC has no ENDPROC before ENDMODULE"}},
      {"endfunc_ends_a_proc", "    ENDPROC\n", "    ENDFUNC\n", "", {"ENDFUNC ends the PROC of line"}},
      {"array_too_short", "CONST robtarget Edge{3}", "CONST robtarget Edge{4}", "", {"3 values for 4 elements"}},
      {"conf_switch_unknown", "ConfL\\On;", "ConfL\\Maybe;", "", {"ConfL takes one switch"}},
      {"declaration_without_semicolon",
       "CONST num nApproach:=50;",
       "CONST num nApproach:=50",
       "",
       {"';' expected after the value of 'nApproach'"}},
      {"unclosed_string", "[FALSE,TRUE,\"\",[[1400", "[FALSE,TRUE,\",[[1400", "", {"string not closed"}},
      {"wrong_argument_count",
       "MoveL Target_20,vDeburr,zDeburr,tDeburr",
       "MoveL Target_20,vDeburr,tDeburr",
       "",
       {"MoveL: 4 arguments", "3 given"}},
  };
  for (const Mutation& m : mutations) {
    const std::string text = with(module, m.from, m.to);
    const int line = line_of(text, m.error_at.empty() ? m.to : m.error_at);
    for (const auto& [eol_tag, eol] :
         std::vector<std::pair<std::string, std::string>>{{"crlf", "\r\n"}, {"lf", "\n"}, {"cr", "\r"}}) {
      std::vector<std::string> says = m.says;
      says.push_back("{D}/m.mod:" + std::to_string(line) + ":");
      cases.push_back({"rapid_" + m.tag + "_" + eol_tag, cmd, {{"m.mod", with_line_ends(text, eol)}}, says});
    }
  }
  cases.push_back({"rapid_empty_module", cmd, {{"m.mod", ""}}, {"{D}/m.mod: the program is empty"}});
  cases.push_back({"rapid_no_motion",
                   cmd,
                   {{"m.mod", "MODULE M\r\n  PROC main()\r\n    WaitTime 1;\r\n  ENDPROC\r\nENDMODULE\r\n"}},
                   {"{D}/m.mod: no motion instruction"}});
  cases.push_back({"rapid_only_run_time_targets",
                   cmd,
                   {{"m.mod", "MODULE M\r  PROC main()\r    MoveL CRobT(),v100,fine,tool0;\r  ENDPROC\rENDMODULE\r"}},
                   {"{D}/m.mod: none of its motion targets", "{D}/m.mod:3:", "CRobT() is computed at run time"}});
  cases.push_back({"rapid_not_a_module",
                   cmd,
                   {{"m.mod", "PROC main()\n  MoveL p,v100,fine,tool0;\nENDPROC\n"}},
                   {"{D}/m.mod:1:", "not a RAPID module"}});
  cases.push_back({"rapid_tooldata_option_quaternion_norm_3",
                   "offline --program-in {D}/m.mod --force tool:fz_N=-150 --program-out {D}/out.mod --tooldata "
                   "'tGun=[TRUE,[[0,0,200],[3,0,0,0]],[5,[0,0,100],[1,0,0,0],0,0,0]]'",
                   {{"m.mod", module}},
                   {"option --tooldata 'tGun=", "not of unit length"}});
  cases.push_back({"rapid_tooldata_option_twice",
                   cmd + " --tooldata 'tX=[TRUE,[[0,0,1],[1,0,0,0]],[1,[0,0,0],[1,0,0,0],0,0,0]]' --tooldata "
                         "'tX=[TRUE,[[0,0,2],[1,0,0,0]],[1,[0,0,0],[1,0,0,0],0,0,0]]'",
                   {{"m.mod", module}},
                   {"option --tooldata", "'tX' is given twice"}});
  // A migrated RobotStudio module: ConfJ\Off, and its first MoveJ's confdata not one the arm can take.
  // The controller takes the configuration nearest the arm; without the arm's joints deflex cannot, and
  // says which option gives them.
  const std::string migrated =
      with(with(with(module, "ConfJ\\On;", "ConfJ\\Off;"),
                "        MoveAbsJ jHome\\NoEOffs,v1000,z50,tDeburr\\WObj:=wobjHousing;\n", ""),
           "Target_10:=[[0,0,0],[0,1,0,0],[-1,-1,1,0]", "Target_10:=[[0,0,0],[0,1,0,0],[0,0,0,0]");
  cases.push_back({"rapid_confj_off_first_target_needs_the_start_joints",
                   cmd,
                   {{"m.mod", migrated}},
                   {"{D}/m.mod:" + std::to_string(line_of(migrated, "MoveJ Offs(Target_10")) + ":",
                    "ConfJ\\Off (line " + std::to_string(line_of(migrated, "ConfJ\\Off")) + ")", "--seed-deg"}});
}

void add_krl_cases(std::vector<BadInput>& cases) {
  const std::string src = source_file("examples/programs/deburr_bracket.src");
  const std::string dat = source_file("examples/programs/deburr_bracket.dat");
  const std::string cmd =
      "offline --robot {S}/examples/robots/kuka_kr210_r3100_2_flange.yaml --program-in {D}/p.src --force "
      "tool:fx_N=-150 --tooldata 'TOOL_DATA[1]={X 250,Y 0,Z 0,A 0,B 0,C 0}' --tooldata 'TOOL_DATA[2]={X 320,Y 0,Z "
      "40,A 0,B -10,C 0}' --wobjdata 'BASE_DATA[1]={X 1800,Y -300,Z 500,A 0,B 0,C 0}' --program-out {D}/out.src";
  const std::vector<Mutation> dat_mutations = {
      {"nan_component", "XP1={X 0.0", "XP1={X nan", "", {"E6POS 'XP1'", "component 'X'", "not a number"}},
      {"unknown_component", "XP3={X 300.0", "XP3={Q 1,X 300.0", "", {"E6POS has no component 'Q'"}},
      {"component_twice", "XP4={X 380.0,Y 80.0", "XP4={X 380.0,X 80.0", "", {"component 'X' is given twice"}},
      {"unterminated_brace",
       "E6 0.0}\r\nDECL FDAT FP1",
       "E6 0.0\r\nDECL FDAT FP1",
       "XP1=",
       {"E6POS 'XP1'", "not an aggregate"}},
      {"declared_twice",
       "DECL E6POS XP2=",
       "DECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0}\r\nDECL E6POS XP2=",
       "XP1={X 1,",
       {"'XP1' is declared twice"}},
      {"status_text",
       "XP5={X 300.0,Y 160.0,Z 0.0,A 20.0,B 75.0,C 15.0,S 2",
       "XP5={X 300.0,Y 160.0,Z 0.0,A 20.0,B 75.0,C 15.0,S two",
       "",
       {"component 'S'", "not a number"}},
      {"no_defdat", "DEFDAT  deburr_bracket", "", "&ACCESS", {"not a KRL data list"}},
      {"declaration_after_enddat",
       "ENDDAT",
       "ENDDAT\r\nDECL E6POS XP7={X 1,Y 2,Z 3,A 0,B 0,C 0}",
       "DECL E6POS XP7",
       {"after ENDDAT (line"}},
  };
  for (const Mutation& m : dat_mutations) {
    const std::string text = with(dat, m.from, m.to);
    std::vector<std::string> says = m.says;
    says.push_back(m.tag == "no_defdat"
                       ? "{D}/p.dat"
                       : "{D}/p.dat:" + std::to_string(line_of(text, m.error_at.empty() ? m.to : m.error_at)) + ":");
    cases.push_back({"krl_dat_" + m.tag, cmd, {{"p.src", src}, {"p.dat", text}}, says});
  }
  const std::vector<Mutation> src_mutations = {
      {"missing_component", "", "", "LIN XP6 C_DIS", {"the point 'XP6'", "does not give every component"}},
      {"motion_to_fdat", "LIN XP3 C_DIS", "LIN FP3 C_DIS", "", {"'FP3' is a FDAT", "not a point"}},
      {"inline_status_text", "PTP {A1 0,A2 -90", "PTP {A1 0,A2 xx", "", {"component 'A2'", "not a number"}},
      {"inline_unclosed",
       "PTP {A1 0,A2 -90,A3 90,A4 0,A5 35,A6 0}",
       "PTP {A1 0,A2 -90,A3 90,A4 0,A5 35,A6 0",
       "",
       {"PTP", "do not close"}},
      {"lin_to_axis_point", "PTP {A1 0,A2 -90", "LIN {A1 0,A2 -90", "", {"PTP only"}},
      {"unknown_keyword", "LIN XP3 C_DIS", "LIN XP3 C_FOO", "", {"unknown 'C_FOO'"}},
      {"declaration_after_motion",
       "LIN XP9\r\n",
       "LIN XP9\r\nDECL INT n\r\n",
       "DECL INT n",
       {"a declaration after the routine's first statement (line"}},
      {"declaration_without_decl_after_motion",
       "LIN XP9\r\n",
       "LIN XP9\r\nE6POS pExtra\r\n",
       "E6POS pExtra",
       {"a declaration after the routine's first statement"}},
  };
  for (const Mutation& m : src_mutations) {
    const std::string s = m.tag == "missing_component" ? src : with(src, m.from, m.to);
    const std::string d = m.tag == "missing_component" ? with(dat, "XP6={X 0.0,Y 160.0,", "XP6={X 0.0,") : dat;
    std::vector<std::string> says = m.says;
    says.push_back("{D}/p.src:" + std::to_string(line_of(s, m.error_at.empty() ? m.to : m.error_at)) + ":");
    cases.push_back({"krl_src_" + m.tag, cmd, {{"p.src", s}, {"p.dat", d}}, says});
  }
  cases.push_back({"krl_missing_dat", cmd, {{"p.src", src}}, {"{D}/p.src: its data list {D}/p.dat does not exist"}});
  cases.push_back({"krl_dat_is_a_folder",
                   cmd,
                   {{"p.src", src}},
                   {"{D}/p.dat: is a directory"},
                   2,
                   [](const std::filesystem::path& d) { std::filesystem::create_directories(d / "p.dat"); }});
  cases.push_back({"krl_empty_src", cmd, {{"p.src", ""}, {"p.dat", dat}}, {"{D}/p.src: the program is empty"}});
  cases.push_back({"krl_no_motion",
                   cmd,
                   {{"p.src", "DEF p()\r\n  WAIT SEC 1\r\nEND\r\n"}, {"p.dat", dat}},
                   {"{D}/p.src: no motion instruction"}});
  cases.push_back({"krl_tooldata_option_twice",
                   cmd + " --tooldata 'TOOL_DATA[1]={X 1,Y 0,Z 0,A 0,B 0,C 0}'",
                   {{"p.src", src}, {"p.dat", dat}},
                   {"option --tooldata", "TOOL_DATA[1] is given twice"}});
}

/// Messages that named no file or option before: each now names its own.
void add_message_cases(std::vector<BadInput>& cases) {
  const std::string evaluate =
      "evaluate --unloaded {S}/examples/evaluate/unloaded.csv --loaded {S}/examples/evaluate/loaded_uc.csv ";
  const std::string record =
      "identify-payload --force-source rdt:127.0.0.1:1 --rdt-calibration onrobot-hex "
      "--joints-deg 0,0,0,0,90,0 --record {D}/p.csv ";
  const std::string tare = "online --link rsi --force-source rdt:127.0.0.1 --rdt-calibration onrobot-hex --tare ";
  const std::vector<std::tuple<std::string, std::string, std::vector<std::string>>> options = {
      // An empty value is never the default: `--robot ""` (an unset variable) ran on the built-in arm.
      {"empty_robot", "fk --robot '' --joints-deg 0,30,10,0,50,0", {"option --robot", "an empty value"}},
      {"empty_robot_offline",
       "offline --robot '' --circle default --force constant:fz_N=-1 -o {D}/o.csv",
       {"option --robot", "an empty value"}},
      {"empty_expect_frame", evaluate + "--expect-frame ''", {"option --expect-frame", "an empty value"}},
      {"synthetic_noise_negative",
       "plan-calibration --robot builtin --region-mm 1300,1900,-400,400,500,1100 --load-N 800 --poses 3 --grid 2 "
       "-o {D}/p.csv --synthetic-measurements {D}/s.csv --synthetic-noise-mm -1",
       {"option --synthetic-noise-mm", "outside 0..1000 mm"}},
      {"record_max_std_zero", record + "--max-std-N 0", {"option --max-std-N"}},
      {"record_max_std_nm_negative", record + "--max-std-Nm -0.1", {"option --max-std-Nm"}},
      {"record_window_zero", record + "--window-s 0", {"option --window-s"}},
      {"tare_window_zero", tare + "--tare-window-s 0", {"(--tare-window-s)"}},
      {"tare_max_std_negative", tare + "--tare-max-std-N -1", {"(--tare-max-std-N)"}},
  };
  for (const auto& [tag, args, says] : options) {
    cases.push_back({"message_" + tag, args, {}, says});
  }
  cases.push_back({"message_overlay_empty_urdf_file",
                   "fk --robot {D}/ov.yaml --joints-deg 0,30,10,0,50,0",
                   {{"ov.yaml",
                     "deflex_robot: 1\nunits: {length: m, angle: deg}\n"
                     "kinematics: {convention: urdf, file: \"\", tip_link: flange}\n"
                     "joint_stiffness_Nm_per_rad: [3.5e6, 4.0e6, 2.2e6, 4.5e5, 3.5e5, 2.0e5]\n"}},
                   {"{D}/ov.yaml:3:", "field 'kinematics.file'", "empty"}});
  cases.push_back({"message_mean_reference_one_point",
                   "evaluate --unloaded {D}/one.csv --loaded {S}/examples/evaluate/loaded_uc.csv --mean-reference",
                   {{"one.csv", "t_s,x_mm,y_mm,z_mm\n0,1930,0,900\n"}},
                   {"option --mean-reference", "{D}/one.csv", "1 sample(s)"}});
}

}  // namespace

std::vector<BadInput> program_cases() {
  std::vector<BadInput> cases;
  add_rapid_cases(cases);
  add_krl_cases(cases);
  return cases;
}

std::vector<BadInput> limit_cases() {
  std::vector<BadInput> cases;
  // URDF: structure and numbers.
  const std::string urdf = source_file("examples/robots/ros-industrial/abb_irb6700_235_265.urdf");
  const std::string fk = "fk --robot {D}/arm.urdf --joints-deg 0,30,10,0,50,0";
  const auto urdf_case = [&](const std::string& tag, const std::string& text, const std::vector<std::string>& says) {
    cases.push_back({"urdf_" + tag, fk, {{"arm.urdf", text}}, says});
  };
  std::string deep = "<?xml version=\"1.0\"?>\n<robot name=\"deep\">\n<link name=\"a\"/>\n";
  for (int i = 0; i < 200000; ++i) deep += "<x>";
  for (int i = 0; i < 200000; ++i) deep += "</x>";
  urdf_case("nested_200000_deep", deep + "\n</robot>\n", {"{D}/arm.urdf:4:", "nested deeper than 100"});
  urdf_case("rpy_1e300",
            with(urdf, "<origin xyz=\"0 0 1.135\" rpy=\"0 0 0\"", "<origin xyz=\"0 0 1.135\" rpy=\"0 1e300 0\""),
            {"{D}/arm.urdf:", "origin rpy: 1e+300 rad is outside"});
  urdf_case("xyz_two_numbers", with(urdf, "<origin xyz=\"0 0 1.135\"", "<origin xyz=\"0 1.135\""),
            {"{D}/arm.urdf:", "is not three numbers"});
  urdf_case("axis_huge", with(urdf, "<axis xyz=\"0 1 0\"/>", "<axis xyz=\"0 1e300 0\"/>"),
            {"{D}/arm.urdf:", "axis xyz"});
  urdf_case("second_root", urdf + "<robot name=\"another\"/>\n", {"{D}/arm.urdf:", "a second root element"});
  urdf_case("name_not_utf8", with(urdf, "<robot name=\"abb_irb6700_235_265\"", "<robot name=\"abb\xC0\xAF\""),
            {"{D}/arm.urdf:8:", "robot name", "not UTF-8"});
  std::string chain = "<?xml version=\"1.0\"?>\n<robot name=\"chain\">\n";
  for (int i = 0; i <= 5000; ++i) chain += "<link name=\"l" + std::to_string(i) + "\"/>\n";
  for (int i = 0; i < 5000; ++i) {
    chain += "<joint name=\"j" + std::to_string(i) + "\" type=\"revolute\"><parent link=\"l" + std::to_string(i) +
             "\"/><child link=\"l" + std::to_string(i + 1) +
             "\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n";
  }
  urdf_case("chain_of_5000_joints", chain + "</robot>\n", {"{D}/arm.urdf", "5000 joints, at most 7"});

  // YAML: one document, plain keys, UTF-8 text, in every kind of YAML file.
  struct YamlUse {
    std::string tag, command, file, base, name_line;
  };
  const std::vector<YamlUse> yamls = {
      {"robot", "fk --robot {D}/f.yaml --joints-deg 0,30,10,0,50,0", "f.yaml",
       source_file("examples/robots/kuka_kr210_r2700.yaml"), "name: \"KUKA KR 210 R2700-class (approximate)\""},
      {"sensor",
       "identify-payload --data {S}/examples/online/payload_poses.csv --sensor-config {D}/f.yaml -o {D}/p.yaml",
       "f.yaml", source_file("examples/online/sensor_3axis.yaml"), "name: \"example 3-axis strain-gauge sensor\""},
      {"case", "case-study --case {D}/f.yaml --quick --seeds 1 --no-progress --out {D}/cs", "f.yaml",
       source_file("data/cases/paper.yaml"),
       "name: \"Loaded circle, IRB 6700-300/2.70, offline vs online compensation (paper, section 3)\""},
  };
  for (const YamlUse& y : yamls) {
    cases.push_back({"yaml_" + y.tag + "_second_document",
                     y.command,
                     {{y.file, y.base + "\n---\nname: second\n"}},
                     {"{D}/" + y.file + ":", "a second YAML document"}});
    cases.push_back({"yaml_" + y.tag + "_list_key",
                     y.command,
                     {{y.file, y.base + "\n? [a, b]\n: 1\n"}},
                     {"{D}/" + y.file + ":", "a key must be a plain name"}});
    // A tag would change the value's meaning for a reader that honours it; deflex refuses tags.
    const std::string tagged = with(y.base, y.name_line, "name: !!str " + y.name_line.substr(6));
    cases.push_back({"yaml_" + y.tag + "_tag",
                     y.command,
                     {{y.file, tagged}},
                     {"{D}/" + y.file + ":" + std::to_string(line_of(tagged, "!!str")) + ":", "YAML tag ('!!str')"}});
    cases.push_back(
        {"yaml_" + y.tag + "_latin1_name",
         y.command,
         {{y.file, with(y.base, y.name_line, y.name_line.substr(0, y.name_line.size() - 1) + "\xE9\"")}},
         {"{D}/" + y.file + ":" + std::to_string(line_of(y.base, y.name_line)) + ":", "field 'name'", "not UTF-8"}});
  }

  cases.push_back({"yaml_robot_latin1_name_json",
                   "fk --robot {D}/f.yaml --joints-deg 0,30,10,0,50,0 --json",
                   {{"f.yaml", with(yamls[0].base, "(approximate)", "(approximate \xE9)")}},
                   {"{D}/f.yaml:", "field 'name'", "not UTF-8"}});

  // Errors of a computation on data name the data's file (they named nothing before).
  std::string unloaded_one_sample = "t_s,x_mm,y_mm,z_mm\n0,1930,0,900\n";
  cases.push_back(
      {"message_iso9283_names_the_run_file",
       "evaluate --unloaded {S}/examples/evaluate/unloaded.csv --loaded {S}/examples/evaluate/loaded_uc.csv "
       "--loaded {D}/short.csv",
       {{"short.csv", unloaded_one_sample}},
       {"run 2", "run 2 = {D}/short.csv"}});
  // Measurements under no load at all, and payload poses all in one orientation.
  std::string no_load =
      "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,dx_mm,dy_mm,dz_mm\n";
  for (int k = 0; k < 12; ++k) {
    no_load += std::to_string(k) + ",30,10,0,50,0,0,0,0,0,0,0,0.1,0.1,0.1\n";
  }
  cases.push_back({"message_identify_names_the_data",
                   "identify --robot builtin --data {D}/m.csv",
                   {{"m.csv", no_load}},
                   {"{D}/m.csv:", "excite no joint"}});
  std::string one_pose = "qw,qx,qy,qz,fx_N,fy_N,fz_N\n";
  for (int k = 0; k < 6; ++k) {
    one_pose += "0,1,0,0,1.5,-0.7,85.5\n";
  }
  cases.push_back({"message_payload_names_the_data",
                   "identify-payload --data {D}/pl.csv -o {D}/p.yaml",
                   {{"pl.csv", one_pose}},
                   {"{D}/pl.csv:", "do not excite"}});

  // Values past their documented range, in every option that takes joints, wrenches, positions.
  for (int j = 0; j < 6; ++j) {
    std::string joints = "0,30,10,0,50,0";
    std::vector<std::string> v{"0", "30", "10", "0", "50", "0"};
    v[static_cast<std::size_t>(j)] = j % 2 == 0 ? "3601" : "-1e5";
    joints = v[0] + "," + v[1] + "," + v[2] + "," + v[3] + "," + v[4] + "," + v[5];
    cases.push_back({"range_fk_joint_" + std::to_string(j + 1),
                     "fk --joints-deg " + joints,
                     {},
                     {"option --joints-deg", "value " + std::to_string(j + 1), "outside -3600..3600 deg"}});
    cases.push_back({"range_deflect_joint_" + std::to_string(j + 1),
                     "deflect --joints-deg " + joints + " --wrench 0,0,-1,0,0,0",
                     {},
                     {"option --joints-deg", "outside -3600..3600 deg"}});
  }
  const char* const components[6] = {"Fx", "Fy", "Fz", "Mx", "My", "Mz"};
  for (int k = 0; k < 6; ++k) {
    for (const char* value : {"1.1e6", "-1e7"}) {
      std::vector<std::string> w(6, "0");
      w[static_cast<std::size_t>(k)] = value;
      cases.push_back({std::string("range_wrench_") + components[k] + (value[0] == '-' ? "_negative" : "_positive"),
                       "deflect --joints-deg 0,30,10,0,50,0 --wrench " + w[0] + "," + w[1] + "," + w[2] + "," + w[3] +
                           "," + w[4] + "," + w[5],
                       {},
                       {"option --wrench", components[k], k < 3 ? "N is outside" : "Nm is outside"}});
    }
  }
  const std::vector<std::tuple<std::string, std::string, std::vector<std::string>>> options = {
      {"ik_position", "ik --position-mm 2e5,0,900 --quaternion-wxyz 0,0,1,0", {"--position-mm", "mm is outside"}},
      {"ik_quaternion", "ik --position-mm 1900,0,900 --quaternion-wxyz 0,0,2,0", {"--quaternion-wxyz", "outside"}},
      {"ik_seed",
       "ik --position-mm 1900,0,900 --quaternion-wxyz 0,0,1,0 --seed-deg 0,0,0,0,4000,0",
       {"--seed-deg", "outside -3600..3600 deg"}},
      {"offline_seed",
       "offline --circle default --force constant:fz_N=-1 --seed-deg 1e6,0,0,0,0,0 -o {D}/o.csv",
       {"--seed-deg", "outside"}},
      {"offline_orientation",
       "offline --circle default --force constant:fz_N=-1 --orientation-wxyz 5,0,0,0 -o {D}/o.csv",
       {"--orientation-wxyz", "outside"}},
      {"plan_region",
       "plan-calibration --robot builtin --region-mm 1300,2e6,-400,400,500,1100 --load-N 800 -o {D}/p.csv",
       {"--region-mm", "outside"}},
      {"plan_spin",
       "plan-calibration --robot builtin --region-mm 1300,1900,-400,400,500,1100 --load-N 800 --spin-deg "
       "0,1e5 -o {D}/p.csv",
       {"--spin-deg", "outside"}},
      {"circle_points_1e8",
       "offline --circle points=100000000 --force constant:fz_N=1 -o {D}/o.csv",
       {"key 'points'", "3..1000000"}},
      {"circle_points_just_over",
       "offline --circle points=1000001 --force constant:fz_N=1 -o {D}/o.csv",
       {"key 'points'", "3..1000000"}},
      {"fix_stiffness_out_of_range",
       "identify --robot {S}/examples/robots/kuka_kr210_r2700.yaml --data "
       "{S}/examples/identify/kr210_synthetic_measurements.csv --fix-stiffness-Nm-per-rad 2=1e11",
       {"--fix-stiffness-Nm-per-rad", "outside"}},
      // Keys given twice in one option spec: refused, never "the last one wins".
      {"repeat_fix_stiffness",
       "identify --robot {S}/examples/robots/kuka_kr210_r2700.yaml --data "
       "{S}/examples/identify/kr210_synthetic_measurements.csv --fix-stiffness-Nm-per-rad 2=1e6,2=2e6",
       {"--fix-stiffness-Nm-per-rad", "joint 2 is given twice"}},
      {"repeat_circle_key",
       "offline --circle points=5,points=6 --force constant:fz_N=1 -o {D}/o.csv",
       {"key 'points' given twice"}},
      {"repeat_force_key",
       "offline --circle default --force constant:fz_N=1,fz_N=2 -o {D}/o.csv",
       {"key 'fz_N' given twice"}},
      {"repeat_line_key",
       "offline --line 'start_mm=1500;0;1000,end_mm=1600;0;1000,start_mm=1400;0;1000' --force constant:fz_N=1 -o "
       "{D}/o.csv",
       {"key 'start_mm' given twice"}},
  };
  for (const auto& [tag, args, says] : options) {
    cases.push_back({"range_" + tag, args, {}, says});
  }
  add_message_cases(cases);
  return cases;
}

}  // namespace deflex::test
