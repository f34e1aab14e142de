// The controller-side files `deflex controller-setup` writes, read back independently: the RSI XML
// files by libxml2 (well-formed, and every value the controller takes from them agrees with the
// options deflex runs with: IP, port, SENTYPE, the AXISCORR limits, the wiring ETHERNET -> AXISCORR,
// the Timeout), the KRL and RAPID by small structure checkers written here from the languages' rules
// (blocks closed in order, statements terminated, names declared before use), and the EGM instructions'
// arguments against deflex's port, period, ramp-in and device. Options that cannot work are refused
// with the option named.
#include <algorithm>
#include <cmath>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "deflex/egm/egm_controller_setup.hpp"
#include "deflex/fanuc/fanuc_controller_setup.hpp"
#include "deflex/motoros2/motoros2_controller_setup.hpp"
#include "deflex/rsi/rsi_controller_setup.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/ur/ur_controller_setup.hpp"
#include "deflex/ur/ur_rtde_link.hpp"
#include "wire/libxml2_reader.hpp"

namespace deflex {
namespace {

const ControllerFile& file(const std::vector<ControllerFile>& files, const std::string& suffix) {
  for (const auto& f : files) {
    if (f.name.size() >= suffix.size() && f.name.compare(f.name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      return f;
    }
  }
  throw std::runtime_error("no file ending " + suffix);
}

// ---- RAPID: statements (comments after '!' removed, strings kept), blocks, declarations ----
struct RapidModule {
  std::vector<std::string> problems;
  std::string name;
  std::vector<std::string> statements;  // inside procedures, whitespace-collapsed, without the ';'
  std::vector<std::string> declared;
};

RapidModule read_rapid(const std::string& text) {
  RapidModule m;
  std::string code;
  {
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
      bool in_string = false;
      std::string kept;
      for (const char c : line) {
        if (c == '"') in_string = !in_string;
        if (c == '!' && !in_string) break;
        kept += c;
      }
      if (in_string) m.problems.push_back("unterminated string: " + line);
      code += kept + "\n";
    }
  }
  // Block lines stand alone; every other statement runs to its ';' (it may span lines).
  static const std::regex module_re(R"(^\s*MODULE\s+([A-Za-z][A-Za-z0-9_]{0,31})\s*$)");
  static const std::regex proc_re(R"(^\s*PROC\s+([A-Za-z][A-Za-z0-9_]{0,31})\s*\(\s*\)\s*$)");
  static const std::regex decl_re(
      R"(^(LOCAL\s+)?(VAR|CONST|PERS)\s+([a-z_]+)\s+([A-Za-z][A-Za-z0-9_]{0,31})\s*(:=.*)?$)");
  std::istringstream in(code);
  std::string line, pending;
  std::vector<std::string> blocks;
  std::smatch match;
  while (std::getline(in, line)) {
    const auto b = line.find_first_not_of(" \t");
    if (b == std::string::npos) continue;
    line = line.substr(b, line.find_last_not_of(" \t") - b + 1);
    if (pending.empty() && std::regex_match(line, match, module_re)) {
      if (!blocks.empty()) m.problems.push_back("MODULE inside a block");
      m.name = match[1];
      blocks.push_back("MODULE");
      continue;
    }
    if (pending.empty() && std::regex_match(line, match, proc_re)) {
      if (blocks != std::vector<std::string>{"MODULE"}) m.problems.push_back("PROC outside the module: " + line);
      blocks.push_back("PROC");
      continue;
    }
    if (pending.empty() && (line == "ENDPROC" || line == "ENDMODULE")) {
      const std::string open = line == "ENDPROC" ? "PROC" : "MODULE";
      if (blocks.empty() || blocks.back() != open) m.problems.push_back(line + " closes nothing open");
      if (!blocks.empty()) blocks.pop_back();
      continue;
    }
    pending += (pending.empty() ? "" : " ") + line;
    if (pending.back() != ';') continue;
    std::string statement = std::regex_replace(pending.substr(0, pending.size() - 1), std::regex(R"(\s+)"), " ");
    pending.clear();
    if (std::regex_match(statement, match, decl_re)) {
      if (blocks != std::vector<std::string>{"MODULE"}) m.problems.push_back("declaration inside a procedure");
      m.declared.push_back(match[4]);
      continue;
    }
    if (blocks != std::vector<std::string>{"MODULE", "PROC"}) m.problems.push_back("statement outside a procedure");
    m.statements.push_back(statement);
  }
  if (!pending.empty()) m.problems.push_back("statement without ';': " + pending);
  if (!blocks.empty()) m.problems.push_back("blocks left open");
  return m;
}

// The statement that starts with `instruction`, and its optional arguments \Name[:=value].
struct RapidCall {
  std::string text;
  std::map<std::string, std::string> optional;
};
RapidCall call(const RapidModule& m, const std::string& instruction) {
  for (const auto& s : m.statements) {
    if (s.rfind(instruction + " ", 0) == 0) {
      RapidCall c{s, {}};
      static const std::regex arg(R"(\\([A-Za-z0-9_]+)(:=([^\\;]+))?)");
      for (auto it = std::sregex_iterator(s.begin(), s.end(), arg); it != std::sregex_iterator(); ++it) {
        std::string v = (*it)[3];
        while (!v.empty() && v.back() == ' ') v.pop_back();
        c.optional[(*it)[1]] = v;
      }
      return c;
    }
  }
  ADD_FAILURE() << "no " << instruction;
  return {};
}

EgmSetupOptions egm_options(bool path) {
  EgmSetupOptions o;
  o.path_correction = path;
  o.sensor_ip = "192.168.125.50";
  o.port = 6511;
  o.period_ms = path ? 24.0 : 4.0;
  o.max_joint_correction_deg = 0.3;
  o.ramp_in_s = 2.5;
  return o;
}

// The UdpUc entry: Name, Type, remote address and port.
std::map<std::string, std::string> udpuc(const std::string& cfg) {
  std::map<std::string, std::string> out;
  static const std::regex attr(R"re(-(\w+)\s+("([^"]*)"|(\d+)))re");
  const auto at = cfg.find("COM_TRP:");
  EXPECT_NE(at, std::string::npos);
  const std::string body = cfg.substr(at);
  for (auto it = std::sregex_iterator(body.begin(), body.end(), attr); it != std::sregex_iterator(); ++it) {
    out[(*it)[1]] = (*it)[3].matched ? std::string((*it)[3]) : std::string((*it)[4]);
  }
  return out;
}

TEST(ControllerSetup, EgmJointModuleIsWellFormedAndAgreesWithDeflex) {
  const auto files = egm_controller_setup(egm_options(false));
  const RapidModule m = read_rapid(file(files, ".mod").text);
  EXPECT_TRUE(m.problems.empty()) << ::testing::PrintToString(m.problems);
  EXPECT_EQ(m.name, "DeflexEgm");
  // The command the header names runs deflex bound to the address the controller sends to.
  EXPECT_NE(file(files, ".mod")
                .text.find("deflex online --link egm-joint --bind 192.168.125.50 --egm-port 6511 "
                           "--period-ms 4 --max-joint-correction-deg 0.3"),
            std::string::npos);
  EXPECT_EQ(m.statements.front(), "EGMReset deflex_egm_id");
  const RapidCall setup = call(m, "EGMSetupUC");
  EXPECT_NE(setup.text.find("ROB_1,deflex_egm_id,\"default\",\"DEFLEX\""), std::string::npos) << setup.text;
  EXPECT_TRUE(setup.optional.count("Joint"));
  const RapidCall act = call(m, "EGMActJoint");
  EXPECT_EQ(act.optional.at("SampleRate"), "4");
  for (int j = 1; j <= 6; ++j) EXPECT_EQ(act.optional.at(std::string("J") + std::to_string(j)), "deflex_converged");
  EXPECT_GE(std::stod(act.optional.at("MaxPosDeviation")), 0.3);
  const RapidCall run = call(m, "EGMRunJoint");
  EXPECT_EQ(run.optional.at("RampInTime"), "2.5");
  EXPECT_NE(run.text.find("EGM_STOP_HOLD"), std::string::npos);
  // Every name the instructions use is declared.
  for (const char* name : {"deflex_egm_id", "deflex_converged"}) {
    EXPECT_NE(std::find(m.declared.begin(), m.declared.end(), name), m.declared.end()) << name;
  }
  // The UdpUc device the module names is the one the configuration entry defines, at deflex's address.
  const auto entry = udpuc(file(files, "_udpuc.cfg").text);
  EXPECT_EQ(entry.at("Name"), "DEFLEX");
  EXPECT_EQ(entry.at("Type"), "UDPUC");
  EXPECT_EQ(entry.at("RemoteAdress"), "192.168.125.50");
  EXPECT_EQ(entry.at("RemotePortNumber"), "6511");
}

TEST(ControllerSetup, EgmPathModuleActivatesPathCorrectionInDeflexsFrame) {
  for (const char* frame : {"tool", "flange", "path"}) {
    EgmSetupOptions o = egm_options(true);
    o.path_frame = frame;
    o.tool = "tSpindle";
    const RapidModule m = read_rapid(file(egm_controller_setup(o), ".mod").text);
    EXPECT_TRUE(m.problems.empty()) << frame << ::testing::PrintToString(m.problems);
    const RapidCall setup = call(m, "EGMSetupUC");
    EXPECT_TRUE(setup.optional.count("PathCorr") && setup.optional.count("APTR")) << setup.text;
    const RapidCall act = call(m, "EGMActMove");
    EXPECT_EQ(act.optional.at("SampleRate"), "24");
    const std::string expected_frame = std::string(frame) == "flange" ? "deflex_flange_frame" : "tSpindle.tframe";
    EXPECT_NE(act.text.find("deflex_egm_id," + expected_frame), std::string::npos) << act.text;
    if (std::string(frame) == "flange") {
      EXPECT_NE(std::find(m.declared.begin(), m.declared.end(), "deflex_flange_frame"), m.declared.end());
    }
    EXPECT_EQ(call(m, "EGMStop").text, "EGMStop deflex_egm_id,EGM_STOP_HOLD");
  }
}

RsiSetupOptions rsi_options() {
  RsiSetupOptions o;
  o.sensor_ip = "192.168.1.20";
  o.port = 59152;
  o.sentype = "Deflex";
  o.max_joint_correction_deg = 0.35;
  o.timeout = 60;
  return o;
}

TEST(ControllerSetup, RsiEthernetConfigIsWellFormedAndAgreesWithDeflex) {
  const auto files = rsi_controller_setup(rsi_options());
  const std::string xml = file(files, "_ethernet.xml").text;
  ASSERT_TRUE(test::libxml2_read(xml).well_formed) << xml;
  const auto one = [&](const std::string& name) {
    const auto e = test::libxml2_elements(xml, name);
    EXPECT_EQ(e.size(), 1u) << name;
    return e.empty() ? std::string() : e[0].text;
  };
  EXPECT_EQ(one("IP_NUMBER"), "192.168.1.20");
  EXPECT_EQ(one("PORT"), "59152");
  EXPECT_EQ(one("SENTYPE"), "Deflex");
  EXPECT_EQ(one("ONLYSEND"), "FALSE");
  const auto elements = test::libxml2_elements(xml, "ELEMENT");
  std::vector<std::string> send, receive;
  for (const auto& e : elements) {
    const std::string tag = e.attributes.at("TAG");
    if (tag.rfind("AK.", 0) == 0) {
      receive.push_back(tag);
      EXPECT_EQ(e.attributes.at("INDX"), tag.substr(4)) << tag;  // AK.Ai arrives on output i
      EXPECT_EQ(e.attributes.at("HOLDON"), "1");
      EXPECT_EQ(e.attributes.at("TYPE"), "DOUBLE");
    } else {
      send.push_back(tag);
    }
  }
  EXPECT_EQ(receive, (std::vector<std::string>{"AK.A1", "AK.A2", "AK.A3", "AK.A4", "AK.A5", "AK.A6"}));
  for (const char* needed : {"DEF_AIPos", "DEF_ASPos", "DEF_Delay"}) {
    EXPECT_NE(std::find(send.begin(), send.end(), needed), send.end()) << needed;
  }
}

TEST(ControllerSetup, RsiContextWiresEthernetToAxisCorrWithDeflexsBound) {
  const auto files = rsi_controller_setup(rsi_options());
  const std::string xml = file(files, ".rsi.xml").text;
  ASSERT_TRUE(test::libxml2_read(xml).well_formed) << xml;
  const auto objects = test::libxml2_elements(xml, "RSIObject");
  ASSERT_EQ(objects.size(), 3u);
  // Parameters by object: read each object's own sub-document.
  std::map<std::string, std::map<std::string, std::string>> params;
  std::string object;
  std::vector<std::pair<std::string, std::string>> inputs;
  {
    std::istringstream in(xml);
    std::string line;
    static const std::regex obj(R"re(<RSIObject ObjType="(\w+)")re");
    std::smatch m;
    while (std::getline(in, line)) {
      if (std::regex_search(line, m, obj)) object = m[1];
      if (line.find("<Parameter ") != std::string::npos || line.find("<Input ") != std::string::npos) {
        const auto e = test::libxml2_elements(line, line.find("<Input ") != std::string::npos ? "Input" : "Parameter");
        ASSERT_EQ(e.size(), 1u) << line;
        if (line.find("<Input ") != std::string::npos) {
          EXPECT_EQ(object, "AXISCORR");
          EXPECT_EQ(e[0].attributes.at("OutObjID"), "ETHERNET1");
          inputs.emplace_back(e[0].attributes.at("InIdx"), e[0].attributes.at("OutIdx"));
        } else {
          params[object][e[0].attributes.at("Name")] = e[0].attributes.at("ParamValue");
        }
      }
    }
  }
  EXPECT_EQ(params["ETHERNET"]["ConfigFile"], "deflex_rsi_ethernet.xml");
  EXPECT_EQ(params["ETHERNET"]["Timeout"], "60");
  ASSERT_EQ(inputs.size(), 6u);
  for (int a = 1; a <= 6; ++a) {
    const std::string i = std::to_string(a);
    EXPECT_EQ(inputs[static_cast<std::size_t>(a - 1)], std::make_pair(i, i));
    EXPECT_EQ(std::stod(params["AXISCORR"]["LowerLimA" + i]), -0.35);
    EXPECT_EQ(std::stod(params["AXISCORR"]["UpperLimA" + i]), 0.35);
    EXPECT_GT(std::stod(params["AXISCORRMON"]["MaxA" + i]), 0.35);  // it trips only beyond what AXISCORR passes
  }
}

TEST(ControllerSetup, RsiKrlSwitchesRsiOnInAbsoluteModeAroundTheProgram) {
  const auto files = rsi_controller_setup(rsi_options());
  const std::string krl = file(files, ".src").text;
  // KRL structure: DEF name( ) ... END, IF/ENDIF balanced, the context it creates is the one written.
  std::istringstream in(krl);
  std::string line;
  std::vector<std::string> code;
  while (std::getline(in, line)) {
    const auto semi = line.find(';');
    line = line.substr(0, semi);
    const auto b = line.find_first_not_of(" \t");
    if (b != std::string::npos) code.push_back(line.substr(b, line.find_last_not_of(" \t") - b + 1));
  }
  ASSERT_GE(code.size(), 3u);
  EXPECT_EQ(code.front(), "DEF deflex_rsi( )");
  EXPECT_EQ(code.back(), "END");
  int depth = 0;
  std::vector<std::string> rsi_calls;
  for (const auto& c : code) {
    if (c.rfind("IF ", 0) == 0) ++depth;
    if (c == "ENDIF") --depth;
    EXPECT_GE(depth, 0);
    if (c.find("RSI_") != std::string::npos) rsi_calls.push_back(c);
  }
  EXPECT_EQ(depth, 0);
  ASSERT_EQ(rsi_calls.size(), 3u);
  EXPECT_EQ(rsi_calls[0], "ret = RSI_CREATE(\"deflex_rsi.rsi\", CONTID, TRUE)");
  EXPECT_EQ(rsi_calls[1], "ret = RSI_ON(#ABSOLUTE, #IPO_FAST)");
  EXPECT_EQ(rsi_calls[2], "ret = RSI_OFF()");
  // The command it names runs deflex with the same values, bound to the address the controller sends to.
  EXPECT_NE(krl.find("--bind 192.168.1.20 --rsi-port 59152 --rsi-sentype Deflex --period-ms 4 "
                     "--max-joint-correction-deg 0.35"),
            std::string::npos);
}

TEST(ControllerSetup, OptionsThatCannotWorkAreRefusedNamingTheOption) {
  const auto refuses = [](auto options, const std::string& fragment) {
    try {
      if constexpr (std::is_same_v<decltype(options), RsiSetupOptions>) {
        (void)rsi_controller_setup(options);
      } else {
        (void)egm_controller_setup(options);
      }
      ADD_FAILURE() << "accepted; expected " << fragment;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  RsiSetupOptions r = rsi_options();
  r.sensor_ip = "192.168.1";
  refuses(r, "192.168.1");
  r = rsi_options();
  r.sensor_ip = "0.0.0.0";
  refuses(r, "--sensor-ip");
  r = rsi_options();
  r.timeout = 200;  // 0.8 s of late answers: beyond deflex's 0.5 s restart silence
  refuses(r, "--rsi-timeout");
  r = rsi_options();
  r.sentype = "Im Free";
  refuses(r, "--rsi-sentype");
  r = rsi_options();
  r.period_ms = 8.0;
  refuses(r, "--period-ms");
  r = rsi_options();
  r.max_joint_correction_deg = 0.0;
  refuses(r, "--max-joint-correction-deg");
  EgmSetupOptions e = egm_options(false);
  e.period_ms = 8.0;
  refuses(e, "--period-ms");
  e = egm_options(true);
  e.period_ms = 30.0;
  refuses(e, "--period-ms");
  e = egm_options(true);
  e.path_frame = "world";
  refuses(e, "--path-corr-frame");
  e = egm_options(false);
  e.device = "2fast";
  refuses(e, "--egm-device");
  e = egm_options(false);
  e.max_pos_deviation_deg = 0.1;
  refuses(e, "--max-pos-deviation-deg");
  e = egm_options(false);
  e.program_peak_speed_deg_s = {10, 10, 10, 10, 10, 10};
  e.max_speed_deviation_deg_s = 5.0;  // slower than the program itself
  refuses(e, "--max-speed-deviation-deg-s");
}

TEST(ControllerSetup, EgmSupervisionIsDerivedTightFromDeflexsOwnLimits) {
  // A program whose fastest joint moves at 2 deg/s, deflex's default bound, rate and ramp-in.
  EgmSetupOptions o = egm_options(false);
  o.max_joint_correction_deg = 0.5;
  o.ramp_in_s = 1.0;
  o.max_rate_deg_s = 3.0;
  o.program_peak_speed_deg_s = {2.0, 1.5, 1.0, 0.5, 1.0, 2.0};
  const EgmSupervision s = egm_supervision(o);
  // The fastest deflex's command may move: the program's 2, the blend's 1.5 x 1 deg / 1 s, the rate's 3.
  EXPECT_DOUBLE_EQ(s.fastest_command_deg_s, 2.0 + 1.5 + 3.0);
  EXPECT_EQ(s.max_speed_deviation_deg_s, std::ceil(1.25 * 6.5));
  EXPECT_DOUBLE_EQ(s.max_pos_deviation_deg, 0.5 + 1.0 + 2.0 * 0.1);
  EXPECT_EQ(s.comm_timeout_s, o.stop_silence_s);
  // The jump of a program clock that ran on through a 0.45 s silence (1.13 deg in one 4 ms cycle, the
  // measured defect) is far beyond what the controller now admits: it would stop EGM.
  EXPECT_GT(1.13 / 0.004, 10.0 * s.max_speed_deviation_deg_s);
  // The module carries the values.
  const RapidCall act = call(read_rapid(file(egm_controller_setup(o), ".mod").text), "EGMActJoint");
  EXPECT_EQ(std::stod(act.optional.at("MaxSpeedDeviation")), s.max_speed_deviation_deg_s);
  EXPECT_EQ(std::stod(act.optional.at("MaxPosDeviation")), s.max_pos_deviation_deg);
  const RapidCall setup = call(read_rapid(file(egm_controller_setup(o), ".mod").text), "EGMSetupUC");
  EXPECT_EQ(std::stod(setup.optional.at("CommTimeout")), 3.0);
  // Without a program, the robot's speed limits stand in: looser, and the module says so.
  o.program_peak_speed_deg_s.clear();
  o.robot_max_speed_deg_s = {100, 90, 90, 190, 140, 235};
  const EgmSupervision loose = egm_supervision(o);
  EXPECT_GT(loose.max_speed_deviation_deg_s, 235.0);
  EXPECT_NE(file(egm_controller_setup(o), ".mod").text.find("the robot's joint speed limits"), std::string::npos);
}

}  // namespace
}  // namespace deflex

namespace deflex {
namespace {

// FANUC: the TP program waits in IBGN after moving to the program's start (its joints, in degrees,
// as the .LS position section writes them), and the sheet sets the interval deflex runs at.
TEST(ControllerSetup, FanucTpProgramWaitsInIbgnAtTheProgramsStart) {
  FanucSetupOptions o;
  o.period_ms = 4.0;
  o.version = 3;
  o.start_rad = JointVector(6);
  o.start_rad << deg_to_rad(10.0), deg_to_rad(-20.5), deg_to_rad(30.25), 0.0, deg_to_rad(90.0), deg_to_rad(-179.0);
  o.limits.fill({120.0, 265.0, 1240.0});
  const std::vector<ControllerFile> files = fanuc_controller_setup(o);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].name, "DEFLEXSM.LS");
  const std::string& tp = files[0].text;
  EXPECT_EQ(tp.rfind("/PROG  DEFLEXSM\n", 0), 0u) << tp;
  // The lines in order, numbered: frames, the move to the start, IBGN start then end.
  const std::size_t move = tp.find("   3:  J P[1] 10% FINE ;");
  const std::size_t start = tp.find("   5:  IBGN start[1] ;");
  const std::size_t end = tp.find("   6:  IBGN end[1] ;");
  ASSERT_NE(move, std::string::npos) << tp;
  ASSERT_NE(start, std::string::npos) << tp;
  ASSERT_NE(end, std::string::npos) << tp;
  EXPECT_LT(move, start);
  EXPECT_LT(start, end);
  for (const char* joint : {"J1=    10.000 deg", "J2=   -20.500 deg", "J3=    30.250 deg", "J6=  -179.000 deg"}) {
    EXPECT_NE(tp.find(joint), std::string::npos) << joint << "\n" << tp;
  }
  EXPECT_NE(tp.find("/END\n"), std::string::npos);
  const std::string& sheet = files[1].text;
  EXPECT_NE(sheet.find("$STMO.$COM_INT        = 4 "), std::string::npos) << sheet;
  EXPECT_NE(sheet.find("--fanuc-version 3"), std::string::npos) << sheet;
  EXPECT_NE(sheet.find("jerk 1240 deg/s^3"), std::string::npos) << sheet;
  EXPECT_EQ(sheet.find("S647"), std::string::npos) << "the 1 ms option only for a 1 ms interval";
  o.period_ms = 1.0;
  EXPECT_NE(fanuc_controller_setup(o)[1].text.find("S647"), std::string::npos);
}

TEST(ControllerSetup, FanucOptionsThatCannotWorkAreRefused) {
  const auto refused = [](const FanucSetupOptions& o, const char* words) {
    try {
      (void)fanuc_controller_setup(o);
      ADD_FAILURE() << "expected an InputError naming " << words;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  FanucSetupOptions o;
  o.program_name = "deflex";
  refused(o, "--tp-program");
  o = FanucSetupOptions{};
  o.program_name = "TOOLONGNAME";
  refused(o, "--tp-program");
  o = FanucSetupOptions{};
  o.period_ms = 2.0;
  refused(o, "8, 4 or 1 ms");
  o = FanucSetupOptions{};
  o.version = 2;
  refused(o, "--fanuc-version");
}

// MotoROS2: the configuration keys, read back with a YAML parser, carry deflex's port, its stop silence
// as the controller's timeout and the gap deflex never exceeds; the sheet gives each joint's speed the
// FSU limit must stay above (the figures given, in degrees) and the period deflex runs at.
TEST(ControllerSetup, Motoros2ConfigKeysFollowDeflexsSettings) {
  Motoros2SetupOptions o;
  o.robot_port = 22010;
  o.stop_silence_s = 0.75;
  o.group = 1;
  o.stream_speed_rad_s = JointVector(2);
  o.stream_speed_rad_s << 0.1, 0.25;
  const std::vector<ControllerFile> files = motoros2_controller_setup(o);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].name, "deflex_motoros2_config.yaml");
  const YAML::Node y = YAML::Load(files[0].text);
  EXPECT_EQ(y["rt_listener_udp_port_number"].as<int>(), 22010);
  EXPECT_EQ(y["rt_status_udp_port_number"].as<int>(), 22001);
  EXPECT_EQ(y["rt_status_sleep_period"].as<int>(), 10);
  EXPECT_EQ(y["timeout_for_rt_msg"].as<int>(), 750);
  EXPECT_EQ(y["max_sequence_diff_for_rt_msg"].as<int>(), 1);
  const std::string& sheet = files[1].text;
  EXPECT_NE(sheet.find("joint 1: above 5.730 deg/s"), std::string::npos) << sheet;  // 0.1 rad/s
  EXPECT_NE(sheet.find("joint 2: above 14.324 deg/s"), std::string::npos) << sheet;
  EXPECT_NE(sheet.find("--period-ms must equal it (4 ms here"), std::string::npos) << sheet;
  EXPECT_NE(sheet.find("--motoros2-group 1"), std::string::npos) << sheet;
  EXPECT_NE(sheet.find("timeout_for_rt_msg (750 ms)"), std::string::npos) << sheet;
}

TEST(ControllerSetup, Motoros2OptionsThatCannotWorkAreRefused) {
  const auto refused = [](const Motoros2SetupOptions& o, const char* words) {
    try {
      (void)motoros2_controller_setup(o);
      ADD_FAILURE() << "expected an InputError naming " << words;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  Motoros2SetupOptions o;
  o.period_ms = 4.5;
  refused(o, "--period-ms");
  o = Motoros2SetupOptions{};
  o.robot_port = 70000;
  refused(o, "--robot-port");
  o = Motoros2SetupOptions{};
  o.group = 8;
  refused(o, "--motoros2-group");
  o = Motoros2SetupOptions{};
  o.stop_silence_s = 0.02;  // shorter than two 12 ms resends and a period
  refused(o, "--stop-silence-s");
}

// The registers a URScript text reads or writes through `function(N)`, as RTDE field names `prefix + N`,
// comma separated in the order of first use.
std::string registers_used(const std::string& text, const std::string& function, const std::string& prefix) {
  std::vector<std::string> names;
  for (std::size_t at = text.find(function + "("); at != std::string::npos; at = text.find(function + "(", at + 1)) {
    const std::size_t open = at + function.size() + 1;
    const std::string name = prefix + text.substr(open, text.find_first_of(",)", open) - open);
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

std::string sorted_csv(const std::string& csv) {
  std::vector<std::string> names;
  std::stringstream in(csv);
  for (std::string n; std::getline(in, n, ',');) names.push_back(n);
  std::sort(names.begin(), names.end());
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

// UR: the script reads exactly the input registers deflex's link sets up (its input recipe), writes the
// output register the link reads, arms the watchdog on deflex's counter, calls servoj with the step
// time of the rate, and checks each step against the stream's limit (0.1 rad/s over 2 ms, 1 % over);
// its blocks close; the sheet gives the speed limits in degrees and servoj's delay.
TEST(ControllerSetup, UrScriptUsesTheLinksRegistersAndDeflexsServojSettings) {
  for (const int offset : {24, 0}) {
    SCOPED_TRACE(offset);
    UrSetupOptions o;
    o.register_offset = offset;
    o.lookahead_s = 0.05;
    o.gain = 1000;
    o.stream_speed_rad_s = JointVector::Constant(6, 0.1);
    const std::vector<ControllerFile> files = ur_controller_setup(o);
    ASSERT_EQ(files.size(), 2u);
    EXPECT_EQ(files[0].name, "deflex_servo.script");
    const std::string& script = files[0].text;
    const std::string ints = registers_used(script, "read_input_integer_register", "input_int_register_");
    const std::string doubles = registers_used(script, "read_input_float_register", "input_double_register_");
    EXPECT_EQ(sorted_csv(ints + "," + doubles), sorted_csv(ur_rtde_input_names(offset)));
    EXPECT_NE(ur_rtde_output_names(offset).find(
                  registers_used(script, "write_output_integer_register", "output_int_register_")),
              std::string::npos);
    EXPECT_NE(script.find(fmt::format("rtde_set_watchdog(\"input_int_register_{}\", 10, \"stop\")", offset)),
              std::string::npos)
        << script;
    EXPECT_NE(script.find("servoj(q, 0, 0, 0.002, lookahead, gain)"), std::string::npos) << script;
    EXPECT_NE(script.find("step_max = [0.000202000, 0.000202000"), std::string::npos) << script;
    // Every block (def, while, if) closes with an end.
    std::size_t opened = 0, ends = 0;
    std::stringstream lines(script);
    for (std::string line; std::getline(lines, line);) {
      const std::string t = line.substr(std::min(line.size(), line.find_first_not_of(' ')));
      if (t.rfind("def ", 0) == 0 || t.rfind("while ", 0) == 0 || t.rfind("if ", 0) == 0) ++opened;
      if (t == "end") ++ends;
    }
    EXPECT_EQ(opened, ends) << script;
    const std::string& sheet = files[1].text;
    EXPECT_NE(sheet.find("joint 6: above 5.730 deg/s"), std::string::npos) << sheet;
    EXPECT_NE(sheet.find("about 53.0 ms"), std::string::npos) << sheet;  // 50 + 1 + 2
  }
  UrSetupOptions cb3;
  cb3.period_ms = 8.0;
  EXPECT_NE(ur_controller_setup(cb3)[0].text.find("servoj(q, 0, 0, 0.008, lookahead, gain)"), std::string::npos);
  EXPECT_EQ(ur_controller_setup(cb3)[0].text.find("step_max"), std::string::npos);
}

TEST(ControllerSetup, UrOptionsThatCannotWorkAreRefused) {
  const auto refused = [](const UrSetupOptions& o, const char* words) {
    try {
      (void)ur_controller_setup(o);
      ADD_FAILURE() << "expected an InputError naming " << words;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  UrSetupOptions o;
  o.period_ms = 4.0;
  refused(o, "--period-ms");
  o = UrSetupOptions{};
  o.lookahead_s = 0.25;
  refused(o, "--ur-lookahead-ms");
  o = UrSetupOptions{};
  o.gain = 50;
  refused(o, "--ur-gain");
  o = UrSetupOptions{};
  o.register_offset = 3;
  refused(o, "--ur-register-offset");
}

}  // namespace
}  // namespace deflex
