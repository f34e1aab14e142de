// The shipped RAPID module and KRL program (examples/programs) through `deflex offline --program-in`:
// every line that holds no target comes out byte for byte (CR LF included), the only new lines are
// compensated copies, and every target the motions reach is what the model says: the test reads
// both programs with its own regular expressions, solves each input target with the model's IK,
// builds q_cmd = q_des - K^-1 J^T W with J by central differences of FK and the tool-frame force
// it gave on the command line, and compares FK(q_cmd) with the output target.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;
using test::run_cli;
using test::slurp;

const std::string kExamples = std::string(DEFLEX_SOURCE_DIR) + "/examples/programs/";

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t nl = text.find('\n', at);
    const std::size_t end = nl == std::string::npos ? text.size() : nl + 1;
    out.push_back(text.substr(at, end - at));  // the line end included: CR LF must survive too
    at = end;
  }
  return out;
}

std::vector<double> numbers_in(const std::string& s) {
  std::vector<double> out;
  static const std::regex number(R"([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)");
  for (auto it = std::sregex_iterator(s.begin(), s.end(), number); it != std::sregex_iterator(); ++it) {
    out.push_back(std::stod(it->str()));
  }
  return out;
}

/// Splits at depth-0 commas.
std::vector<std::string> split_args(const std::string& s) {
  std::vector<std::string> out;
  int depth = 0;
  std::string cur;
  for (char c : s) {
    depth += (c == '(' || c == '[' || c == '{') ? 1 : (c == ')' || c == ']' || c == '}') ? -1 : 0;
    if (c == ',' && depth == 0) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

/// Walks input and output line by line: equal lines pass, output lines matching `is_copy` are
/// insertions, any other difference must be a line `is_target_line` accepts. Returns the pairs.
std::vector<std::pair<std::string, std::string>> compare_lines(
    const std::string& in, const std::string& out, const std::function<bool(const std::string&)>& is_copy,
    const std::function<bool(const std::string&)>& is_target_line, int& inserted) {
  const auto a = lines_of(in);
  const auto b = lines_of(out);
  std::vector<std::pair<std::string, std::string>> changed;
  std::size_t i = 0, o = 0;
  inserted = 0;
  while (i < a.size() && o < b.size()) {
    if (a[i] == b[o]) {
      ++i, ++o;
    } else if (is_copy(b[o])) {
      ++inserted, ++o;
    } else {
      EXPECT_TRUE(is_target_line(a[i])) << "a line without a target changed:\n  in:  " << a[i] << "  out: " << b[o];
      EXPECT_EQ(a[i].substr(a[i].size() - 2), b[o].substr(b[o].size() - 2)) << "line end changed: " << a[i];
      changed.emplace_back(a[i], b[o]);
      ++i, ++o;
    }
  }
  while (o < b.size() && is_copy(b[o])) {
    ++inserted, ++o;
  }
  EXPECT_EQ(i, a.size());
  EXPECT_EQ(o, b.size());
  return changed;
}

/// q_des - K^-1 J(q_des)^T W, J of the TCP by central differences of FK, W the tool-frame wrench
/// rotated by the TCP orientation at q_des.
JointVector expected_command(const RobotModel& m, const JointVector& q_des, const Wrench& wrench_tool) {
  Workspace ws(m);
  const Pose at = tcp_pose(m, ws, q_des);
  Wrench w;
  w.head<3>() = at.linear() * wrench_tool.head<3>();
  w.tail<3>() = at.linear() * wrench_tool.tail<3>();
  Eigen::Matrix<double, 6, 6> J;
  const double h = 1e-6;
  for (int j = 0; j < 6; ++j) {
    JointVector qp = q_des, qm = q_des;
    qp[j] += h;
    qm[j] -= h;
    const Pose a = tcp_pose(m, ws, qm);
    const Pose b = tcp_pose(m, ws, qp);
    J.col(j).head<3>() = (b.translation() - a.translation()) / (2 * h);
    const Eigen::AngleAxisd d(b.linear() * a.linear().transpose());
    J.col(j).tail<3>() = d.angle() * d.axis() / (2 * h);
  }
  JointVector q = q_des;
  const Eigen::Matrix<double, 6, 1> tau = J.transpose() * w;
  for (int j = 0; j < 6; ++j) {
    q[j] -= tau[j] / m.stiffness()[j];
  }
  return q;
}

// ---------------------------------------------------------------------------------------------
// RAPID: the test's own reading of the module.

struct RapidTarget {
  Vector3 p_mm = Vector3::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  std::array<int, 4> conf{};
  std::array<double, 6> joints{};
  bool joint = false;
};

Pose pose_mm(const Vector3& p_mm, const Eigen::Quaterniond& q) {
  Pose p = Pose::Identity();
  p.translation() = p_mm * 1e-3;
  p.linear() = q.normalized().toRotationMatrix();
  return p;
}

RapidTarget rapid_literal(const std::string& s) {
  const auto v = numbers_in(s);
  RapidTarget t;
  if (v.size() == 12) {  // jointtarget
    t.joint = true;
    std::copy(v.begin(), v.begin() + 6, t.joints.begin());
    return t;
  }
  EXPECT_EQ(v.size(), 17u) << s;
  t.p_mm = Vector3(v[0], v[1], v[2]);
  t.q = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
  for (int i = 0; i < 4; ++i) {
    t.conf[static_cast<std::size_t>(i)] = static_cast<int>(v[7 + static_cast<std::size_t>(i)]);
  }
  return t;
}

/// name (or name{i}) -> literal, from the module's declarations.
std::map<std::string, RapidTarget> rapid_declarations(const std::string& text) {
  std::map<std::string, RapidTarget> out;
  static const std::regex decl(R"((?:CONST|PERS|VAR) (?:robtarget|jointtarget) (\w+)(\{(\d+)\})?:=)");
  static const std::regex literal(R"(\[\[[^\]]*\](?:,\[[^\]]*\]){1,3}\])");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), decl); it != std::sregex_iterator(); ++it) {
    const std::string name = (*it)[1];
    const int n = (*it)[3].matched ? std::stoi((*it)[3]) : 0;
    auto from = text.begin() + (it->position() + it->length());
    for (int k = 0; k < std::max(n, 1); ++k) {
      std::smatch m;
      if (!std::regex_search(from, text.end(), m, literal)) {
        ADD_FAILURE() << "no literal after " << name;
        return out;
      }
      out[n == 0 ? name : name + "{" + std::to_string(k + 1) + "}"] = rapid_literal(m.str());
      from = m.suffix().first;
    }
  }
  return out;
}

struct RapidMotion {
  std::string instruction;
  std::vector<std::string> targets;  // as written
};

std::vector<RapidMotion> rapid_motions(const std::string& text) {
  std::vector<RapidMotion> out;
  static const std::regex motion(R"(\b(MoveL|MoveJ|MoveC|MoveAbsJ) ([^;]*);)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), motion); it != std::sregex_iterator(); ++it) {
    RapidMotion m;
    m.instruction = (*it)[1];
    const auto args = split_args((*it)[2]);
    const std::size_t n = m.instruction == "MoveC" ? 2 : 1;
    for (std::size_t k = 0; k < n; ++k) {
      // Optional arguments (\NoEOffs, \ID) start at a depth-0 backslash; RelTool's \Rz is inside ().
      int depth = 0;
      std::size_t cut = args[k].size();
      for (std::size_t c = 0; c < args[k].size() && cut == args[k].size(); ++c) {
        depth += args[k][c] == '(' ? 1 : args[k][c] == ')' ? -1 : 0;
        cut = depth == 0 && args[k][c] == '\\' ? c : cut;
      }
      m.targets.push_back(args[k].substr(0, cut));
    }
    out.push_back(m);
  }
  return out;
}

/// The target a motion argument reaches, in the work object, with Offs and RelTool applied.
bool rapid_reach(const std::string& arg, const std::map<std::string, RapidTarget>& decls, RapidTarget& out) {
  std::smatch m;
  static const std::regex offs(R"(Offs\((\w+(?:\{\d+\})?),([^,]+),([^,]+),([^,)]+)\))");
  static const std::regex reltool(R"(RelTool\((\w+(?:\{\d+\})?),([^,]+),([^,]+),([^,\\)]+)\\Rz:=([^)]+)\))");
  const auto num = [](const std::string& s) { return s == "nApproach" ? 50.0 : std::stod(s); };
  if (std::regex_match(arg, m, offs)) {
    if (decls.count(m[1]) == 0) {
      return false;
    }
    out = decls.at(m[1]);
    out.p_mm += Vector3(num(m[2]), num(m[3]), num(m[4]));
    return true;
  }
  if (std::regex_match(arg, m, reltool)) {
    out = decls.at(m[1]);
    const Matrix3 R = out.q.toRotationMatrix();
    out.p_mm += R * Vector3(num(m[2]), num(m[3]), num(m[4]));
    out.q = Eigen::Quaterniond(R * Eigen::AngleAxisd(deg_to_rad(num(m[5])), Vector3::UnitZ()).toRotationMatrix());
    return true;
  }
  if (!arg.empty() && arg[0] == '[') {
    out = rapid_literal(arg);
    return true;
  }
  if (decls.count(arg) == 0) {
    return false;
  }
  out = decls.at(arg);
  return true;
}

TEST(ProgramRoundTrip, RobotStudioModuleChangesOnlyItsTargetsAndMatchesTheModel) {
  const std::string out_dir = (fs::temp_directory_path() / ("deflex_rapid_" + std::to_string(::getpid()))).string();
  fs::create_directories(out_dir);
  const std::string in = kExamples + "deburr_housing.mod";
  const std::string out = out_dir + "/deburr_housing.mod";
  const auto r =
      run_cli("offline --program-in " + in + " --force 'tool:fz_N=-150,fx_N=40' --program-out " + out + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["language"], "RAPID");
  ASSERT_EQ(doc["unresolved"].size(), 1u);
  EXPECT_NE(doc["unresolved"][0]["reason"].get<std::string>().find("assigned while the program runs"),
            std::string::npos);
  EXPECT_EQ(doc["targets"].size(), 12u);

  const std::string a = slurp(in);
  const std::string b = slurp(out);
  int inserted = 0;
  const auto changed = compare_lines(
      a, b, [](const std::string& l) { return std::regex_search(l, std::regex(R"(CONST robtarget \w+_c\d+:=\[\[)")); },
      [](const std::string& l) {
        return std::regex_search(l, std::regex(R"(robtarget|jointtarget|^\s*\[\[|\b(MoveL|MoveJ|MoveC|MoveAbsJ) )"));
      },
      inserted);
  EXPECT_EQ(inserted, 2);  // Target_10: once directly, twice through Offs (one copy for both)
  EXPECT_GE(changed.size(), 10u);

  // Every motion of the output against the model, paired with the input's in order.
  const RobotModel base = builtin_irb6700();
  const Pose tool = pose_mm(Vector3(40, 0, 220), Eigen::Quaterniond(0.965926, 0, 0.258819, 0));
  const Pose wobj = pose_mm(Vector3(1400, -300, 600), Eigen::Quaterniond(0.996195, 0, 0, 0.0871557));
  const RobotModel m = base.with_tool(tool);
  Wrench wrench_tool;
  wrench_tool << 40, 0, -150, 0, 0, 0;
  const auto din = rapid_declarations(a);
  const auto dout = rapid_declarations(b);
  const auto min = rapid_motions(a);
  const auto mout = rapid_motions(b);
  ASSERT_EQ(min.size(), mout.size());
  Workspace ws(m);
  int checked = 0;
  for (std::size_t i = 0; i < min.size(); ++i) {
    for (std::size_t k = 0; k < min[i].targets.size(); ++k) {
      RapidTarget t_in, t_out;
      if (!rapid_reach(min[i].targets[k], din, t_in)) {
        EXPECT_EQ(min[i].targets[k], mout[i].targets[k]) << "an unresolved target must stay as it was";
        continue;
      }
      ASSERT_TRUE(rapid_reach(mout[i].targets[k], dout, t_out)) << mout[i].targets[k];
      JointVector q_des(6);
      if (t_in.joint) {
        for (int j = 0; j < 6; ++j) {
          q_des[j] = deg_to_rad(t_in.joints[static_cast<std::size_t>(j)]);
        }
      } else {
        IkRequest req;
        req.configuration = ArmConfiguration{t_in.conf[0], t_in.conf[1], t_in.conf[2], t_in.conf[3]};
        const IkResult ik = inverse_kinematics(m, ws, wobj * pose_mm(t_in.p_mm, t_in.q), req);
        ASSERT_TRUE(ik.ok()) << ik.message;
        q_des = ik.q;
      }
      const JointVector q_cmd = expected_command(m, q_des, wrench_tool);
      if (t_in.joint) {
        for (int j = 0; j < 6; ++j) {
          EXPECT_NEAR(t_out.joints[static_cast<std::size_t>(j)], rad_to_deg(q_cmd[j]), 6e-5) << min[i].targets[k];
        }
      } else {
        const Pose want = wobj.inverse() * tcp_pose(m, ws, q_cmd);
        EXPECT_LT((t_out.p_mm - want.translation() * 1e3).norm(), 1e-4) << mout[i].targets[k];
        EXPECT_LT(Eigen::AngleAxisd(want.linear() * t_out.q.normalized().toRotationMatrix().transpose()).angle(), 5e-8)
            << mout[i].targets[k];
        const ArmConfiguration c = arm_configuration(m, ws, q_cmd);
        EXPECT_EQ((std::array<int, 4>{c.cf1, c.cf4, c.cf6, c.cfx}), t_out.conf) << mout[i].targets[k];
        // The compensation is real: the target moved by about the predicted deflection (0.1-0.3 mm).
        EXPECT_GT((t_out.p_mm - t_in.p_mm).norm(), 0.05) << mout[i].targets[k];
      }
      ++checked;
    }
  }
  EXPECT_EQ(checked, 12);
  fs::remove_all(out_dir);
}

// ---------------------------------------------------------------------------------------------
// KRL.

struct KrlPoint {
  std::map<std::string, double> c;  // X, Y, Z, A, B, C, S, T or A1..A6
};

KrlPoint krl_aggregate(const std::string& s) {
  KrlPoint p;
  static const std::regex comp(R"(([A-Z][A-Z0-9]*) ('B[01]+'|[-+]?[0-9.]+))");
  for (auto it = std::sregex_iterator(s.begin(), s.end(), comp); it != std::sregex_iterator(); ++it) {
    const std::string v = (*it)[2];
    p.c[(*it)[1]] = v[0] == '\'' ? static_cast<double>(std::stoi(v.substr(2, v.size() - 3), nullptr, 2)) : std::stod(v);
  }
  return p;
}

std::map<std::string, KrlPoint> krl_points(const std::string& dat) {
  std::map<std::string, KrlPoint> out;
  static const std::regex decl(R"(DECL E6POS (\w+)=(\{[^}]*\}))");
  for (auto it = std::sregex_iterator(dat.begin(), dat.end(), decl); it != std::sregex_iterator(); ++it) {
    out[(*it)[1]] = krl_aggregate((*it)[2]);
  }
  return out;
}

Pose krl_frame(double x, double y, double z, double a, double b, double c) {
  Pose p = Pose::Identity();
  p.translation() = Vector3(x, y, z) * 1e-3;
  p.linear() = (Eigen::AngleAxisd(deg_to_rad(a), Vector3::UnitZ()) *
                Eigen::AngleAxisd(deg_to_rad(b), Vector3::UnitY()) * Eigen::AngleAxisd(deg_to_rad(c), Vector3::UnitX()))
                   .toRotationMatrix();
  return p;
}

TEST(ProgramRoundTrip, KrlProgramChangesOnlyItsPointsAndMatchesTheModel) {
  const std::string out_dir = (fs::temp_directory_path() / ("deflex_krl_" + std::to_string(::getpid()))).string();
  fs::create_directories(out_dir);
  const std::string robot = std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/kuka_kr210_r3100_2_flange.yaml";
  const auto r = run_cli("offline --robot " + robot + " --program-in " + kExamples + "deburr_bracket.src" +
                         " --force tool:fx_N=-150 --tooldata 'TOOL_DATA[1]={X 250,Y 0,Z 0,A 0,B 0,C 0}'"
                         " --tooldata 'TOOL_DATA[2]={X 320,Y 0,Z 40,A 0,B -10,C 0}'"
                         " --wobjdata 'BASE_DATA[1]={X 1800,Y -300,Z 500,A 0,B 0,C 0}' --program-out " +
                         out_dir + "/deburr_bracket.src --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["targets"].size(), 8u);
  EXPECT_EQ(doc["unresolved"].size(), 4u);  // XHOME twice, LIN_REL, the point assigned at run time

  const std::string src_in = slurp(kExamples + "deburr_bracket.src");
  const std::string dat_in = slurp(kExamples + "deburr_bracket.dat");
  const std::string src_out = slurp(out_dir + "/deburr_bracket.src");
  const std::string dat_out = slurp(out_dir + "/deburr_bracket.dat");
  int inserted = 0;
  const auto motion_line = [](const std::string& l) { return std::regex_search(l, std::regex(R"(^(PTP|LIN|CIRC) )")); };
  const auto src_changed = compare_lines(
      src_in, src_out, [](const std::string&) { return false; }, motion_line, inserted);
  EXPECT_EQ(inserted, 0);
  const auto dat_changed = compare_lines(
      dat_in, dat_out,
      [](const std::string& l) { return std::regex_search(l, std::regex(R"(^DECL E6POS \w+_C\d+=)")); },
      [](const std::string& l) { return std::regex_search(l, std::regex(R"(^DECL E6POS )")); }, inserted);
  EXPECT_EQ(inserted, 2);  // XP2 with tool 1 and with tool 2

  // Every PTP/LIN/CIRC in order, with the tool the FDAT before it names.
  const RobotModel base_model = load_robot(robot);
  const std::map<int, Pose> tools = {{1, krl_frame(250, 0, 0, 0, 0, 0)}, {2, krl_frame(320, 0, 40, 0, -10, 0)}};
  const Pose base = krl_frame(1800, -300, 500, 0, 0, 0);
  const auto pin = krl_points(dat_in);
  const auto pout = krl_points(dat_out);
  Wrench wrench_tool;
  wrench_tool << -150, 0, 0, 0, 0, 0;
  const auto lin = lines_of(src_in);
  const auto lout = lines_of(src_out);
  ASSERT_EQ(lin.size(), lout.size());
  int tool_no = 0;
  int checked = 0;
  for (std::size_t i = 0; i < lin.size(); ++i) {
    std::smatch m;
    if (std::regex_search(lin[i], m, std::regex(R"(^FDAT_ACT=FP(\d+))"))) {
      tool_no = m[1] == "8" ? 2 : 1;
      continue;
    }
    if (!std::regex_search(lin[i], m, std::regex(R"(^(PTP|LIN|CIRC) +(.*?)\s*(C_DIS)?\s*$)"))) {
      continue;
    }
    const auto targets_in = split_args(m[2]);
    std::smatch mo;
    ASSERT_TRUE(std::regex_search(lout[i], mo, std::regex(R"(^(PTP|LIN|CIRC) +(.*?)\s*(C_DIS)?\s*$)")));
    const auto targets_out = split_args(mo[2]);
    for (std::size_t k = 0; k < targets_in.size(); ++k) {
      std::string tin = targets_in[k], tout = targets_out[k];
      tin.erase(0, tin.find_first_not_of(' '));
      tout.erase(0, tout.find_first_not_of(' '));
      if (tin[0] != '{' && pin.count(tin) == 0) {
        EXPECT_EQ(tin, tout) << "an unresolved target must stay as it was";
        continue;
      }
      if (tin == "XP9") {
        EXPECT_EQ(tout, "XP9");  // assigned at run time: left alone
        continue;
      }
      const RobotModel mt = base_model.with_tool(tools.at(std::max(tool_no, 1)));
      Workspace ws(mt);
      const KrlPoint a = tin[0] == '{' ? krl_aggregate(tin) : pin.at(tin);
      const KrlPoint b = tout[0] == '{' ? krl_aggregate(tout) : pout.at(tout);
      JointVector q_des(6);
      const char* const axes[6] = {"A1", "A2", "A3", "A4", "A5", "A6"};
      if (a.c.count("A1") != 0) {
        for (int j = 0; j < 6; ++j) {
          q_des[j] = deg_to_rad(a.c.at(axes[j]));
        }
        const JointVector q_cmd = expected_command(mt, q_des, wrench_tool);
        for (int j = 0; j < 6; ++j) {
          EXPECT_NEAR(b.c.at(axes[j]), rad_to_deg(q_cmd[j]), 6e-5) << tout;
        }
        ++checked;
        continue;
      }
      IkRequest req;
      req.kuka_configuration = KukaConfiguration{static_cast<int>(a.c.at("S")), static_cast<int>(a.c.at("T"))};
      const Pose target =
          base * krl_frame(a.c.at("X"), a.c.at("Y"), a.c.at("Z"), a.c.at("A"), a.c.at("B"), a.c.at("C"));
      const IkResult ik = inverse_kinematics(mt, ws, target, req);
      ASSERT_TRUE(ik.ok()) << ik.message;
      const JointVector q_cmd = expected_command(mt, ik.q, wrench_tool);
      const Pose want = base.inverse() * tcp_pose(mt, ws, q_cmd);
      const Pose got = krl_frame(b.c.at("X"), b.c.at("Y"), b.c.at("Z"), b.c.at("A"), b.c.at("B"), b.c.at("C"));
      EXPECT_LT((got.translation() - want.translation()).norm() * 1e3, 1e-4) << tout;
      EXPECT_LT(Eigen::AngleAxisd(want.linear() * got.linear().transpose()).angle(), 3e-6) << tout;  // 1e-4 deg digits
      const KukaConfiguration st = kuka_configuration(mt, ws, q_cmd);
      EXPECT_EQ(static_cast<int>(b.c.at("S")), st.status) << tout;
      EXPECT_EQ(static_cast<int>(b.c.at("T")), st.turn) << tout;
      const Pose in_point = krl_frame(a.c.at("X"), a.c.at("Y"), a.c.at("Z"), a.c.at("A"), a.c.at("B"), a.c.at("C"));
      EXPECT_GT((got.translation() - in_point.translation()).norm() * 1e3, 0.05) << tout;  // really compensated
      ++checked;
    }
  }
  EXPECT_EQ(checked, 8);
  EXPECT_FALSE(src_changed.empty());
  EXPECT_FALSE(dat_changed.empty());
  fs::remove_all(out_dir);
}

/// The IK solution of `pose` nearest `seed` (largest joint difference), chosen here among all.
JointVector nearest_solution(const RobotModel& m, const Pose& pose, const JointVector& seed) {
  Workspace ws(m);
  const std::vector<IkResult> all = all_ik_solutions(m, ws, pose, {});
  EXPECT_FALSE(all.empty());
  JointVector best = all.front().q;
  for (const IkResult& r : all) {
    if ((r.q - seed).cwiseAbs().maxCoeff() < (best - seed).cwiseAbs().maxCoeff()) {
      best = r.q;
    }
  }
  return best;
}

// A module taught on another cell (examples/programs/migrated_pocket.mod): its confdata fit no
// solution of this robot. With ConfJ\Off and ConfL\Off every Cartesian target is solved as the
// controller does, nearest the previous target's joints (chosen here among all IK solutions), and
// compensated as the model says (J by central differences); without them the first is refused.
TEST(ProgramRoundTrip, MigratedModuleWithConfOffIsCompensatedNearestThePreviousTarget) {
  const std::string out_dir = (fs::temp_directory_path() / ("deflex_migrated_" + std::to_string(::getpid()))).string();
  fs::create_directories(out_dir);
  const std::string in = kExamples + "migrated_pocket.mod";
  const auto r =
      run_cli("offline --program-in " + in + " --force tool:fz_N=-300 --program-out " + out_dir + "/out.mod --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["targets"].size(), 9u);
  EXPECT_EQ(doc["unresolved"].size(), 0u);
  int noted = 0;
  for (const auto& t : doc["targets"]) {
    const std::string note = t["configuration"];
    noted += note.find("nearest the previous target's") != std::string::npos ? 1 : 0;
  }
  EXPECT_EQ(noted, 7);  // every MoveJ and MoveL; not the two MoveAbsJ

  const std::string a = slurp(in);
  const std::string b = slurp(out_dir + "/out.mod");
  const auto din = rapid_declarations(a);
  const auto dout = rapid_declarations(b);
  const auto min = rapid_motions(a);
  const auto mout = rapid_motions(b);
  ASSERT_EQ(min.size(), mout.size());
  const RobotModel m = builtin_irb6700().with_tool(pose_mm(Vector3(0, 0, 250), Eigen::Quaterniond::Identity()));
  const Pose wobj = pose_mm(Vector3(1300, -200, 500), Eigen::Quaterniond::Identity());
  Wrench wrench_tool;
  wrench_tool << 0, 0, -300, 0, 0, 0;
  Workspace ws(m);
  JointVector previous;
  for (std::size_t i = 0; i < min.size(); ++i) {
    RapidTarget t_in, t_out;
    ASSERT_TRUE(rapid_reach(min[i].targets[0], din, t_in));
    ASSERT_TRUE(rapid_reach(mout[i].targets[0], dout, t_out));
    JointVector q_des(6);
    if (t_in.joint) {
      for (int j = 0; j < 6; ++j) {
        q_des[j] = deg_to_rad(t_in.joints[static_cast<std::size_t>(j)]);
      }
    } else {
      ASSERT_EQ(previous.size(), 6) << "a Cartesian target before any joint target";
      q_des = nearest_solution(m, wobj * pose_mm(t_in.p_mm, t_in.q), previous);
      const ArmConfiguration own = arm_configuration(m, ws, q_des);
      EXPECT_NE((std::array<int, 4>{own.cf1, own.cf4, own.cf6, own.cfx}), t_in.conf) << "not a migrated target";
    }
    const JointVector q_cmd = expected_command(m, q_des, wrench_tool);
    if (t_in.joint) {
      for (int j = 0; j < 6; ++j) {
        EXPECT_NEAR(t_out.joints[static_cast<std::size_t>(j)], rad_to_deg(q_cmd[j]), 6e-5) << min[i].targets[0];
      }
    } else {
      const Pose want = wobj.inverse() * tcp_pose(m, ws, q_cmd);
      EXPECT_LT((t_out.p_mm - want.translation() * 1e3).norm(), 1e-4) << mout[i].targets[0];
      EXPECT_LT(Eigen::AngleAxisd(want.linear() * t_out.q.normalized().toRotationMatrix().transpose()).angle(), 5e-8)
          << mout[i].targets[0];
      const ArmConfiguration c = arm_configuration(m, ws, q_cmd);
      EXPECT_EQ((std::array<int, 4>{c.cf1, c.cf4, c.cf6, c.cfx}), t_out.conf) << "the confdata of this robot";
      EXPECT_GT((t_out.p_mm - t_in.p_mm).norm(), 0.1) << mout[i].targets[0];
    }
    previous = q_des;
  }

  // Without ConfJ\Off and ConfL\Off the controller stops at the first Cartesian target, and so does deflex.
  std::string strict = a;
  for (const char* conf : {"ConfJ\\Off;", "ConfL\\Off;"}) {
    strict.replace(strict.find(conf), std::string(conf).size(), std::string(conf).substr(0, 6) + "On; ");
  }
  std::ofstream(out_dir + "/strict.mod", std::ios::binary) << strict;
  const auto refused = run_cli("offline --program-in " + out_dir + "/strict.mod --force tool:fz_N=-300 --program-out " +
                               out_dir + "/strict_out.mod");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("strict.mod:41: MoveJ pApproach: configuration_unavailable"), std::string::npos)
      << refused.err;
  EXPECT_FALSE(fs::exists(out_dir + "/strict_out.mod"));
  fs::remove_all(out_dir);
}

TEST(ProgramCli, BadInputExitsWithTwoAndWritesNothing) {
  const std::string dir = (fs::temp_directory_path() / ("deflex_badprog_" + std::to_string(::getpid()))).string();
  fs::create_directories(dir);
  // The shipped module with one motion given an argument RAPID does not have.
  std::string text = slurp(kExamples + "deburr_housing.mod");
  const std::string from = "MoveL Target_20,vDeburr,zDeburr,tDeburr";
  text.replace(text.find(from), from.size(), from + "\\Speed:=3");
  std::ofstream(dir + "/bad.mod", std::ios::binary) << text;
  auto r = run_cli("offline --program-in " + dir + "/bad.mod --force tool:fz_N=-150 --program-out " + dir + "/out.mod");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.mod:47: MoveL: unknown optional argument '\\Speed'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/out.mod"));
  // The tool declared elsewhere and not given.
  r = run_cli("offline --robot " + std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/kuka_kr210_r3100_2_flange.yaml" +
              " --program-in " + kExamples + "deburr_bracket.src --force tool:fx_N=-150 --program-out " + dir +
              "/out.src");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("deburr_bracket.src:33: $TOOL is TOOL_DATA[1] here"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/out.src"));
  EXPECT_FALSE(fs::exists(dir + "/out.dat"));
  // A path and a program at once.
  r = run_cli("offline --circle --program-in " + kExamples + "deburr_housing.mod --force tool:fz_N=-1 --program-out " +
              dir + "/o.mod");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("give no --circle"), std::string::npos) << r.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace deflex
