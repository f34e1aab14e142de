// Programs read as strictly as the controller loads them: every malformed declaration, instruction
// or value fails naming the file, the line and the field; line ends LF, CR LF and CR alone; an empty
// program or one without a target is an error; a KRL program needs its .dat. And RAPID's ConfJ\Off
// and ConfL\Off: from where they stand, a target takes the configuration nearest the previous
// target's (checked against every IK solution of the pose, chosen here), the default stays strict.
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/offline/program_compensation.hpp"
#include "deflex/text/errors.hpp"
#include "offline/program_fixtures.hpp"

namespace deflex {
namespace {

using namespace program_fixtures;
using test::error_of;

const char* const kExt = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]";

std::string robtarget(const std::string& name, const std::string& value) {
  return "  CONST robtarget " + name + ":=" + value + ";\n";
}

const std::string kMoveP1 = "    MoveL p1, v100, fine, tool0;\n";

TEST(RapidStrictness, MalformedDeclarationsNameTheLineAndTheField) {
  expect_error(module(robtarget("p1", "[[1600,0,1200],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09]]"), kMoveP1),
               {"t.mod:2", "robtarget 'p1'", "field 'extax'", "5 values", "an extjoint has 6"});
  expect_error(module(robtarget("p1", std::string("[[1600,0,1200],[nan,0,1,0],[0,0,0,0],") + kExt + "]"), kMoveP1),
               {"t.mod:2", "field 'rot.q1'", "'nan' is not a number"});
  expect_error(module(robtarget("p1", std::string("[[1600,0,1200,5],[0,0,1,0],[0,0,0,0],") + kExt + "]"), kMoveP1),
               {"t.mod:2", "field 'trans'", "4 values, a pos has 3"});
  expect_error(module(robtarget("p1", std::string("[[1600,0,1200],[0,0,1,0],[0,0,0],") + kExt + "]"), kMoveP1),
               {"t.mod:2", "field 'robconf'", "3 values, a confdata has 4"});
  expect_error(module(std::string("  CONST jointtarget j1:=[[0,10,10,0,60],") + kExt + "];\n",
                      "    MoveAbsJ j1, v100, fine, tool0;\n"),
               {"t.mod:2", "jointtarget 'j1'", "field 'robax'", "5 values"});
  expect_error(
      module(std::string("  PERS tooldata tGun:=[TRUE,[[0,0,200],[1,0,0,0]],[nan,[0,0,100],[1,0,0,0],0,0,0]];\n") +
                 robtarget("p1", kP1),
             "    MoveL p1, v100, fine, tGun;\n"),
      {"t.mod:2", "tooldata 'tGun'", "field 'tload.mass'"});
  // A name declared twice where the controller sees both, a value of the wrong type, an index past the end.
  expect_error(module(robtarget("p1", kP1) + robtarget("p1", kP2), kMoveP1), {"t.mod:3", "declared twice", "line 2"});
  expect_error(module("  CONST num p1:=3;\n", kMoveP1), {"t.mod:4", "'p1' is a num (line 2), not a robtarget"});
  expect_error(module(std::string("  CONST robtarget path{2}:=[") + kP1 + "," + kP2 + "];\n",
                      "    MoveL path{3}, v100, fine, tool0;\n"),
               {"t.mod:4", "index 3 is outside path{2}"});
  expect_error(module(std::string("  CONST robtarget path{3}:=[") + kP1 + "," + kP2 + "];\n", kMoveP1),
               {"t.mod:2", "2 values for 3 elements"});
}

TEST(RapidStrictness, MalformedInstructionsAndOptionsFail) {
  const std::string data = robtarget("p1", kP1);
  expect_error(module(data, "    MoveL Offs(p1,0,0), v100, fine, tool0;\n"),
               {"t.mod:4", "Offs takes 4 arguments", "3 given"});
  expect_error(module(data, "    MoveL Offs(p1,0,0,10\\Rz:=5), v100, fine, tool0;\n"),
               {"t.mod:4", "Offs takes no optional argument"});
  expect_error(module(data, "    MoveL RelTool(p1,0,0,10\\Rq:=5), v100, fine, tool0;\n"),
               {"t.mod:4", "RelTool: unknown optional argument '\\Rq'"});
  expect_error(module(data, "    ConfL;\n" + kMoveP1), {"t.mod:4", "ConfL takes one switch"});
  ProgramOptions quaternion;
  quaternion.tooldata = {"tGun=[TRUE,[[0,0,200],[3,0,0,0]],[5,[0,0,100],[1,0,0,0],0,0,0]]"};
  expect_error(module(data, "    MoveL p1, v100, fine, tGun;\n"),
               {"option --tooldata 'tGun=", "quaternion", "not of unit length"}, quaternion);
  ProgramOptions twice;
  twice.tooldata = {"tGun=[TRUE,[[0,0,200],[1,0,0,0]],[5,[0,0,100],[1,0,0,0],0,0,0]]",
                    "tGun=[TRUE,[[0,0,300],[1,0,0,0]],[5,[0,0,100],[1,0,0,0],0,0,0]]"};
  expect_error(module(data, "    MoveL p1, v100, fine, tGun;\n"), {"option --tooldata", "'tGun' is given twice"},
               twice);
}

TEST(RapidStrictness, EmptyProgramsAndProgramsWithoutATargetAreErrors) {
  expect_error("", {"t.mod: the program is empty"});
  expect_error("  ! only a comment\n", {"t.mod: the program is empty"});
  expect_error("PROC main()\nENDPROC\n", {"t.mod:1", "not a RAPID module"});
  expect_error(module("", "    WaitTime 1;\n"), {"t.mod: no motion instruction"});
  expect_error(module("", "    MoveL CRobT(), v100, fine, tool0;\n"),
               {"t.mod: none of its motion targets can be compensated", "t.mod:3", "CRobT() is computed at run time"});
}

TEST(RapidStrictness, LfCrLfAndCrAloneReadAlikeAndKeepTheirLineEnds) {
  const std::string lf = module(robtarget("p1", kP1) + "  ! p1 is used twice, by different tools\n",
                                "    MoveL p1, v100, fine, tool0;\n    MoveL p1, v100, fine, tGun;\n");
  ProgramOptions gun;
  gun.tooldata = {"tGun=[TRUE,[[0,0,200],[1,0,0,0]],[5,[0,0,100],[1,0,0,0],0,0,0]]"};
  const ProgramCompensation a = rapid(lf, gun);
  ASSERT_EQ(a.targets.size(), 2u);
  for (const std::string eol : {"\r\n", "\r"}) {
    std::string text;
    for (const char c : lf) {
      text += c == '\n' ? eol : std::string(1, c);
    }
    const ProgramCompensation b = rapid(text, gun);
    ASSERT_EQ(b.targets.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
      EXPECT_EQ(b.targets[k].line, a.targets[k].line);
      EXPECT_EQ(b.targets[k].action, a.targets[k].action);
      EXPECT_DOUBLE_EQ(b.targets[k].correction_m, a.targets[k].correction_m);
    }
    // The copies are new lines with the module's own line end; every line end is the file's.
    std::string expected;
    for (const char c : a.outputs[0].text) {
      expected += c == '\n' ? eol : std::string(1, c);
    }
    EXPECT_EQ(b.outputs[0].text, expected);
  }
}

// --- ConfJ\Off and ConfL\Off ---------------------------------------------------------------------

// A target 1.6 m ahead with confdata of another cell: cf1 -2 (joint 1 in [-180, -90) deg) has no
// solution there.
const std::string kForeign = std::string("[[1600,100,1200],[0,0,1,0],[-2,0,-1,1],") + kExt + "]";
const std::string kHome = std::string("  CONST jointtarget jHome:=[[5,20,25,0,45,0],") + kExt + "];\n";

/// The configuration of the IK solution of `pose` nearest `seed` (largest joint difference),
/// chosen here among all of them.
ArmConfiguration nearest_configuration(const Pose& pose, const JointVector& seed) {
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  const std::vector<IkResult> all = all_ik_solutions(m, ws, pose, {});
  EXPECT_GE(all.size(), 2u);
  const IkResult* best = nullptr;
  double best_distance = 1e9;
  for (const IkResult& r : all) {
    const double d = (r.q - seed).cwiseAbs().maxCoeff();
    if (d < best_distance) {
      best_distance = d;
      best = &r;
    }
  }
  return best->configuration;
}

TEST(RapidConfOff, FromWhereItStandsATargetTakesTheConfigurationNearestThePreviousOne) {
  const std::string data = kHome + robtarget("pFar", kForeign);
  const std::string strict =
      module(data, "    MoveAbsJ jHome, v100, fine, tool0;\n    MoveL pFar, v100, fine, tool0;\n");
  expect_error(strict, {"t.mod:6", "MoveL pFar", "configuration_unavailable", "[-2,0,-1,1]"});
  // ConfJ governs MoveJ only: a MoveL still checks its configuration.
  expect_error(
      module(data, "    MoveAbsJ jHome, v100, fine, tool0;\n    ConfJ\\Off;\n    MoveL pFar, v100, fine, tool0;\n"),
      {"t.mod:7", "configuration_unavailable"});
  const ProgramCompensation r = rapid(
      module(data, "    MoveAbsJ jHome, v100, fine, tool0;\n    ConfL\\Off;\n    MoveL pFar, v100, fine, tool0;\n"));
  ASSERT_EQ(r.targets.size(), 2u);
  EXPECT_EQ(r.targets[0].configuration_note, "");
  EXPECT_EQ(r.targets[1].configuration_note, "ConfL\\Off (line 6): the configuration nearest the previous target's");
  // The confdata written is that of the solution nearest jHome, found here from all solutions.
  Pose pose = Pose::Identity();
  pose.linear() = Eigen::Quaterniond(0, 0, 1, 0).toRotationMatrix();
  pose.translation() = Vector3(1.6, 0.1, 1.2);
  JointVector home(6);
  home << deg_to_rad(5), deg_to_rad(20), deg_to_rad(25), 0, deg_to_rad(45), 0;
  const ArmConfiguration c = nearest_configuration(pose, home);
  const std::string conf = fmt::format("[{},{},{},{}]", c.cf1, c.cf4, c.cf6, c.cfx);
  EXPECT_NE(r.outputs[0].text.find(conf + "," + kExt + "];"), std::string::npos) << r.outputs[0].text;
  // ConfL\On restores the check from where it stands.
  expect_error(module(data,
                      "    MoveAbsJ jHome, v100, fine, tool0;\n    ConfL\\Off;\n    MoveL pFar, v100, fine, tool0;\n"
                      "    ConfL\\On;\n    MoveL pFar, v100, fine, tool0;\n"),
               {"t.mod:9", "configuration_unavailable"});
  // The first target has no previous one: its own confdata decides, and the note says so.
  const ProgramCompensation first =
      rapid(module(robtarget("p1", kP1), "    ConfJ\\Off;\n    MoveJ p1, v100, fine, tool0;\n"));
  EXPECT_EQ(first.targets.at(0).configuration_note,
            "ConfJ\\Off (line 4), no earlier target and no --seed-deg: its own confdata");
}

// A migrated module's first MoveJ under ConfJ\Off with confdata of another cell: the controller takes
// the configuration nearest the arm, so with the arm's joints at the start (--seed-deg) deflex does
// too; without them it cannot, and names the option that gives them.
TEST(RapidConfOff, TheFirstTargetTakesTheConfigurationNearestTheArmAtTheStart) {
  const std::string text = module(robtarget("pFar", kForeign), "    ConfJ\\Off;\n    MoveJ pFar, v100, fine, tool0;\n");
  expect_error(text, {"t.mod:5", "MoveJ pFar", "configuration_unavailable", "under ConfJ\\Off (line 4) the controller",
                      "--seed-deg"});
  JointVector home(6);
  home << deg_to_rad(5), deg_to_rad(20), deg_to_rad(25), 0, deg_to_rad(45), 0;
  ProgramOptions o;
  o.start_q = home;
  const ProgramCompensation r = rapid(text, o);
  ASSERT_EQ(r.targets.size(), 1u);
  EXPECT_EQ(r.targets[0].configuration_note,
            "ConfJ\\Off (line 4): the configuration nearest --seed-deg (the arm at the start)");
  Pose pose = Pose::Identity();
  pose.linear() = Eigen::Quaterniond(0, 0, 1, 0).toRotationMatrix();
  pose.translation() = Vector3(1.6, 0.1, 1.2);
  const ArmConfiguration c = nearest_configuration(pose, home);
  EXPECT_NE(r.outputs[0].text.find(fmt::format("[{},{},{},{}],", c.cf1, c.cf4, c.cf6, c.cfx) + kExt + "];"),
            std::string::npos)
      << r.outputs[0].text;
  // With ConfJ\On the target's own confdata decides, whatever the start.
  expect_error(module(robtarget("pFar", kForeign), "    MoveJ pFar, v100, fine, tool0;\n"),
               {"t.mod:4", "configuration_unavailable"}, o);
}

// Array elements are numbered from 1: Edge{0} and Edge{-1} stop the controller (they are not an array
// used whole, nor computed at run time); Edge{1} and Edge{N} are the ends.
TEST(RapidStrictness, AnIndexOutsideOneToNIsAnError) {
  const std::string data = "  CONST robtarget Edge{2}:=[" + std::string(kP1) + "," + kP2 + "];\n";
  for (const char* index : {"0", "-1", "3", "+0"}) {
    expect_error(module(data, std::string("    MoveL Edge{") + index + "}, v100, fine, tool0;\n"),
                 {"t.mod:4", "is outside Edge{"});
  }
  EXPECT_EQ(rapid(module(data, "    MoveL Edge{1}, v100, fine, tool0;\n    MoveL Edge{+2}, v100, fine, tool0;\n"))
                .targets.size(),
            2u);
  // A variable index is the program's business: listed, left unchanged.
  const ProgramCompensation listed = rapid(module(
      data + "  VAR num i:=1;\n", "    MoveL Edge{i}, v100, fine, tool0;\n    MoveL Edge{1}, v100, fine, tool0;\n"));
  ASSERT_EQ(listed.unresolved.size(), 1u);
  EXPECT_NE(listed.unresolved[0].reason.find("variable index"), std::string::npos);
}

// Every routine ends with its own ENDPROC (ENDFUNC, ENDTRAP) before the next begins or the module ends.
TEST(RapidStrictness, ARoutineWithoutItsEndIsAnError) {
  const std::string data = robtarget("p1", kP1);
  expect_error("MODULE T\n" + data + "  PROC main()\n    MoveL p1, v100, fine, tool0;\nENDMODULE\n",
               {"t.mod:3", "PROC has no ENDPROC before ENDMODULE (line 5)"});
  expect_error("MODULE T\n" + data +
                   "  PROC main()\n    MoveL p1, v100, fine, tool0;\n  PROC other()\n  ENDPROC\n"
                   "ENDMODULE\n",
               {"t.mod:5", "PROC begins inside the PROC of line 3: its ENDPROC is missing"});
  expect_error(module(data, "    MoveL p1, v100, fine, tool0;\n  ENDFUNC\n"), {"t.mod:5", "ENDFUNC ends the PROC"});
  expect_error("MODULE T\n" + data + "  ENDPROC\nENDMODULE\n", {"t.mod:3", "ENDPROC without a routine"});
}

// --- KRL -----------------------------------------------------------------------------------------

std::string dat_with(const std::string& from, const std::string& to) {
  std::string d = kDat;
  d.replace(d.find(from), from.size(), to);
  return d;
}

void expect_krl_error(const std::string& src, const std::string& dat, const std::vector<std::string>& fragments) {
  ProgramOptions o;
  o.tooldata = {"TOOL_DATA[1]={X 250,Y 0,Z 0,A 0,B 0,C 0}"};
  const std::string msg = error_of([&] { (void)krl(src, dat, o); });
  for (const auto& f : fragments) {
    EXPECT_NE(msg.find(f), std::string::npos) << "'" << msg << "' lacks '" << f << "'";
  }
}

const std::string kPtpXp1 = "DEF dxt()\nFDAT_ACT=FP1\nPTP XP1\nEND\n";

TEST(KrlStrictness, MalformedDataListsNameTheLineAndTheComponent) {
  expect_krl_error(kPtpXp1, dat_with("X 1800.0", "X nan"), {"p.dat:2", "E6POS 'XP1'", "component 'X'", "not a number"});
  expect_krl_error(kPtpXp1, dat_with("Y -300.0,", ""),
                   {"p.src:3", "the point 'XP1'", "p.dat line 2", "does not give every component"});
  expect_krl_error(kPtpXp1, dat_with("E1 0.0}", "E1 0.0"), {"p.dat:2", "E6POS 'XP1'", "not an aggregate"});
  expect_krl_error(kPtpXp1, dat_with("DECL FDAT", "DECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0}\nDECL FDAT"),
                   {"p.dat:3", "'XP1' is declared twice", "line 2"});
  expect_krl_error(kPtpXp1, dat_with("E1 0.0", "Q 0.0"), {"p.dat:2", "E6POS has no component 'Q'"});
  expect_krl_error(kPtpXp1, dat_with("S 2,", "S 2,S 3,"), {"p.dat:2", "component 'S' is given twice"});
  expect_krl_error(kPtpXp1, dat_with("DEFDAT dxt\n", ""), {"p.dat", "not a KRL data list"});
  expect_krl_error("DEF dxt()\nFDAT_ACT=FP1\nLIN {X 1800,Y -300,Z 600,A 20,B 75,C 15,S 2,T x}\nEND\n", kDat,
                   {"p.src:3", "component 'T'", "not a number"});
  expect_krl_error("DEF dxt()\nFDAT_ACT=FP1\nPTP FP1\nEND\n", kDat, {"p.src:3", "'FP1' is a FDAT", "not a point"});
  expect_krl_error("DEF dxt()\nFDAT_ACT=FP1\nEND\n", kDat, {"p.src: no motion instruction"});
  expect_krl_error("", kDat, {"p.src: the program is empty"});
}

// Declarations where the controller takes them: a DEF's before its first statement, the data list's
// between DEFDAT and ENDDAT. INTERRUPT DECL is a statement, and fine anywhere.
TEST(KrlStrictness, DeclarationsAfterAStatementOrOutsideTheDataListAreErrors) {
  expect_krl_error("DEF dxt()\nFDAT_ACT=FP1\nPTP XP1\nDECL INT n\nEND\n", kDat,
                   {"p.src:4", "a declaration after the routine's first statement (line 2)"});
  expect_krl_error("DEF dxt()\nFDAT_ACT=FP1\nPTP XP1\nE6POS pMore\nEND\n", kDat, {"p.src:4", "a declaration after"});
  expect_krl_error(kPtpXp1, std::string(kDat) + "DECL INT late=1\n", {"p.dat:8", "after ENDDAT (line 7)"});
  expect_krl_error(kPtpXp1, "DECL INT early=1\n" + std::string(kDat), {"p.dat:1", "a declaration before DEFDAT"});
  ProgramOptions o;
  o.tooldata = {"TOOL_DATA[1]={X 250,Y 0,Z 0,A 0,B 0,C 0}"};
  EXPECT_EQ(krl("DEF dxt()\nDECL INT n\nINT m\nINTERRUPT DECL 3 WHEN $STOPMESS==TRUE DO IR_STOPM ( )\nFDAT_ACT=FP1\n"
                "INTERRUPT DECL 4 WHEN $STOPMESS==TRUE DO IR_STOPM ( )\nPTP XP1\nEND\nDEF sub()\nDECL INT k\nEND\n",
                kDat, o)
                .targets.size(),
            1u);
}

// A point without Status and Turn as the first target: the configuration is the arm's at the start,
// given by --seed-deg; without it the target is listed, and the list says which option gives it.
TEST(KrlStrictness, AFirstPointWithoutStatusAndTurnTakesTheStartJoints) {
  const std::string dat = dat_with(",S 2,T 10,E1 0.0}", ",E1 0.0}");
  ProgramOptions o;
  o.tooldata = {"TOOL_DATA[1]={X 250,Y 0,Z 0,A 0,B 0,C 0}"};
  const std::string msg = error_of([&] { (void)krl(kPtpXp1, dat, o); });
  EXPECT_NE(msg.find("--seed-deg"), std::string::npos) << msg;
  // The arm at the start: 2 degrees a joint from the solution with the point's own Status 2, Turn 10
  // (found here: KRL's frame R = Rz(A) Ry(B) Rx(C), the tool 250 mm along the flange's x).
  const RobotModel arm = load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/kuka_kr210_r3100_2_flange.yaml");
  Pose tool = Pose::Identity();
  tool.translation() = Vector3(0.25, 0, 0);
  const RobotModel with_tool = arm.with_tool(tool);
  Pose target = Pose::Identity();
  target.linear() =
      (Eigen::AngleAxisd(deg_to_rad(20), Vector3::UnitZ()) * Eigen::AngleAxisd(deg_to_rad(75), Vector3::UnitY()) *
       Eigen::AngleAxisd(deg_to_rad(15), Vector3::UnitX()))
          .toRotationMatrix();
  target.translation() = Vector3(1.8, -0.3, 0.6);
  Workspace ws(with_tool);
  IkRequest req;
  req.kuka_configuration = KukaConfiguration{2, 10};
  const IkResult own = inverse_kinematics(with_tool, ws, target, req);
  ASSERT_TRUE(own.ok()) << own.message;
  o.start_q = JointVector(own.q.array() + deg_to_rad(2.0));
  const ProgramCompensation r = krl(kPtpXp1, dat, o);
  ASSERT_EQ(r.targets.size(), 1u);
  EXPECT_EQ(r.targets[0].configuration_note,
            "no Status and Turn: the configuration of --seed-deg (the arm at the start)");
  // The same solution as the point with its Status and Turn: the same correction.
  ProgramOptions plain;
  plain.tooldata = o.tooldata;
  EXPECT_NEAR(r.targets[0].correction_m, krl(kPtpXp1, kDat, plain).targets.at(0).correction_m, 1e-12);
}

TEST(KrlStrictness, AProgramWithoutItsDataListNamesTheMissingFile) {
  const std::string dir = ::testing::TempDir() + "/deflex_krl_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/p.src") << kPtpXp1;
  const RobotModel m = load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/kuka_kr210_r3100_2_flange.yaml");
  const std::string missing = error_of([&] { (void)compensate_program(m, kPush, dir + "/p.src", dir + "/out.src"); });
  EXPECT_NE(missing.find(dir + "/p.src: its data list " + dir + "/p.dat does not exist"), std::string::npos) << missing;
  std::filesystem::create_directories(dir + "/p.dat");
  const std::string folder = error_of([&] { (void)compensate_program(m, kPush, dir + "/p.src", dir + "/out.src"); });
  EXPECT_NE(folder.find(dir + "/p.dat: is a directory"), std::string::npos) << folder;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace deflex
