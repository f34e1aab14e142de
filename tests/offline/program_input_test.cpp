// Existing programs in: what resolves, what is listed and left alone, what is copied, and every
// kind of bad input failing with the file, the line and the name (and nothing written).
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <unistd.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/force/wrench_table_model.hpp"
#include "deflex/offline/detail/krl_program.hpp"
#include "deflex/offline/detail/program_text.hpp"
#include "deflex/offline/detail/rapid_program.hpp"
#include "deflex/offline/program_compensation.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "offline/program_fixtures.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using namespace program_fixtures;
using test::error_of;

TEST(RapidProgram, SingleUseTargetsAreEditedInPlaceAndNothingElseChanges) {
  const std::string in = module(std::string("  CONST robtarget p1:=") + kP1 + ";\n  ! keep: p1\n",
                                "    MoveL p1, v100, fine, tool0;  ! comment\n    WaitTime 1;\n");
  const ProgramCompensation r = rapid(in);
  ASSERT_EQ(r.targets.size(), 1u);
  EXPECT_EQ(r.targets[0].action, "edited in place");
  EXPECT_EQ(r.targets[0].line, 5);
  EXPECT_GT(r.targets[0].correction_m, 1e-5);
  const std::string& out = r.outputs.at(0).text;
  EXPECT_EQ(out.size() - out.find("  ! keep: p1"), in.size() - in.find("  ! keep: p1"));  // tail untouched
  EXPECT_EQ(out.substr(out.find("  ! keep")), in.substr(in.find("  ! keep")));
  EXPECT_EQ(out.substr(0, 31), in.substr(0, 31));  // "MODULE T\n  CONST robtarget p1:=[["
}

TEST(RapidProgram, OptionalArgumentsAnywhereTheInstructionAllowsThem) {
  const std::string in =
      module(std::string("  CONST robtarget p1:=") + kP1 + ";\n",
             "    MoveL \\Conc, p1 \\ID:=10, v100 \\V:=500, fine \\Inpos:=inpos50, tool0 \\WObj:=wobj0;\n");
  const ProgramCompensation r = rapid(in);
  ASSERT_EQ(r.targets.size(), 1u);
  EXPECT_EQ(r.targets[0].target, "p1");
  EXPECT_EQ(r.targets[0].action, "edited in place");
}

TEST(RapidProgram, TargetsReferencedElsewhereOrUsedDifferentlyGetCopies) {
  // p1 is also read by an assignment: in place would change p2's run-time value, so a copy.
  const std::string in = module(std::string("  CONST robtarget p1:=") + kP1 + ";\n  VAR robtarget p2;\n",
                                "    p2:=p1;\n    MoveL p1, v100, fine, tool0;\n    MoveL p2, v100, fine, tool0;\n");
  const ProgramCompensation r = rapid(in);
  ASSERT_EQ(r.targets.size(), 1u);
  EXPECT_EQ(r.targets[0].action, "copy p1_c1");
  ASSERT_EQ(r.unresolved.size(), 1u);
  EXPECT_EQ(r.unresolved[0].line, 7);
  EXPECT_NE(r.unresolved[0].reason.find("assigned while the program runs"), std::string::npos);
  const std::string& out = r.outputs.at(0).text;
  EXPECT_NE(out.find(std::string("  CONST robtarget p1:=") + kP1 + ";\n  CONST robtarget p1_c1:=[["), std::string::npos)
      << out;
  EXPECT_NE(out.find("    p2:=p1;\n    MoveL p1_c1, v100"), std::string::npos) << out;
}

TEST(RapidProgram, ATableForceGivesEachUseItsOwnCopy) {
  const std::string path = ::testing::TempDir() + "/deflex_table_" + std::to_string(::getpid()) + ".csv";
  std::ofstream(path) << "fx_N,fy_N,fz_N\n0,0,-200\n0,0,-600\n";
  const WrenchTableModel table = WrenchTableModel::read_file(path);
  const std::string in = module(std::string("  CONST robtarget p1:=") + kP1 + ";\n",
                                "    MoveL p1, v100, fine, tool0;\n    MoveL p1, v100, fine, tool0;\n");
  const ProgramCompensation r = rapid(in, {}, table);
  ASSERT_EQ(r.targets.size(), 2u);
  EXPECT_EQ(r.targets[0].action, "copy p1_c1");
  EXPECT_EQ(r.targets[1].action, "copy p1_c2");
  EXPECT_NEAR(r.targets[1].correction_m / r.targets[0].correction_m, 3.0, 1e-3);  // linear in the load
  // Three motion targets need three rows.
  const std::string three =
      module(std::string("  CONST robtarget p1:=") + kP1 + ";\n",
             "    MoveL p1,v100,fine,tool0;\n    MoveL p1,v100,fine,tool0;\n    MoveL p1,v100,fine,tool0;\n");
  EXPECT_NE(error_of([&] { (void)rapid(three, {}, table); }).find("has 2 points"), std::string::npos);
  std::filesystem::remove(path);
}

TEST(RapidProgram, ToolsAndWorkObjectsFromTheModuleOrTheCommandLine) {
  const std::string body = "    MoveL p1, v100, fine, tSpindle\\WObj:=wTable;\n";
  const std::string data = std::string("  CONST robtarget p1:=") +
                           "[[400,0,600],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];\n";
  expect_error(module(data, body), {"t.mod:4", "MoveL", "tooldata 'tSpindle'", "--tooldata tSpindle=[...]"});
  ProgramOptions o;
  o.tooldata = {"tSpindle=[TRUE,[[0,0,200],[1,0,0,0]],[5,[0,0,100],[1,0,0,0],0,0,0]]"};
  expect_error(module(data, body), {"t.mod:4", "wobjdata 'wTable'", "--wobjdata wTable=[...]"}, o);
  o.wobjdata = {"wTable=[FALSE,TRUE,\"\",[[1200,0,400],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]"};
  const ProgramCompensation r = rapid(module(data, body), o);
  ASSERT_EQ(r.targets.size(), 1u);
  // A stationary tool cannot be compensated statically: listed, left alone (the motion with tool0
  // after it is compensated; a program with nothing to compensate is an error that lists why).
  ProgramOptions s = o;
  s.tooldata = {"tSpindle=[FALSE,[[0,0,200],[1,0,0,0]],[5,[0,0,100],[1,0,0,0],0,0,0]]"};
  const ProgramCompensation st = rapid(
      module(std::string("  CONST robtarget p2:=") + kP1 + ";\n" + data, body + "    MoveL p2,v100,fine,tool0;\n"), s);
  EXPECT_EQ(st.targets.size(), 1u);
  ASSERT_EQ(st.unresolved.size(), 1u);
  EXPECT_NE(st.unresolved[0].reason.find("stationary"), std::string::npos);
  expect_error(module(data, body), {"t.mod: none of its motion targets can be compensated", "t.mod:4", "stationary"},
               s);
  // Bad command-line values name the option.
  ProgramOptions bad;
  bad.tooldata = {"tSpindle=[TRUE,[[0,0,200]]]"};
  expect_error(module(data, body), {"option --tooldata", "tSpindle", "a tooldata has 3"}, bad);
}

TEST(RapidProgram, BadMotionsFailNamingTheFileLineAndName) {
  const std::string data = std::string("  CONST robtarget p1:=") + kP1 + ";\n";
  expect_error(module(data, "    MoveL p1, v100, fine, tool0\\Foo:=3;\n"),
               {"t.mod:4", "MoveL", "unknown optional argument '\\Foo'"});
  expect_error(module(data, "    MoveL p1, v100, tool0;\n"), {"t.mod:4", "MoveL", "4 arguments", "3 given"});
  expect_error(module(data, "    MoveC p1, v100, fine, tool0;\n"), {"t.mod:4", "MoveC", "5 arguments"});
  // Out of reach: 4 m ahead.
  expect_error(
      module("  CONST robtarget far:=[[4000,0,1000],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];\n",
             "    MoveL far, v100, fine, tool0;\n"),
      {"t.mod:4", "MoveL far", "unreachable"});
  // The wrist stretched straight (joint 5 at zero): a singularity.
  // All joints at zero: tool0 at (1782.5, 0, 2125) mm turned 90 deg about y (the datasheet pose).
  expect_error(module("  CONST robtarget ps:=[[1782.5,0,2125],[0.70710678118654752,0,0.70710678118654752,0],[0,0,0,0],"
                      "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];\n",
                      "    MoveL ps, v100, fine, tool0;\n"),
               {"t.mod:4", "MoveL ps", "wrist singularity"});
  // A confdata the pose cannot take.
  expect_error(
      module("  CONST robtarget pc:=[[1600,0,1200],[0,0,1,0],[2,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];\n",
             "    MoveL pc, v100, fine, tool0;\n"),
      {"t.mod:4", "MoveL pc", "configuration"});
  expect_error(
      module("  CONST robtarget pq:=[[1600,0,1200],[0,0,3,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];\n",
             "    MoveL pq, v100, fine, tool0;\n"),
      {"t.mod:4", "unit quaternion"});
  expect_error("MODULE T\n  CONST string s:=\"open;\n", {"t.mod:2", "string not closed"});
}

TEST(RapidProgram, RunTimeConstructsAreListedAndLeftUnchanged) {
  const std::string in = module(std::string("  CONST robtarget p1:=") + kP1 + ";\n  VAR num dz:=10;\n",
                                "    dz:=dz+5;\n"
                                "    MoveL CRobT(), v100, fine, tool0;\n"
                                "    MoveL Offs(p1,0,0,dz), v100, fine, tool0;\n"
                                "    TriggL p1, v100, trig1, fine, tool0;\n"
                                "    MoveJ p1, v100, fine, tool0;\n");
  const ProgramCompensation r = rapid(in);
  ASSERT_EQ(r.unresolved.size(), 3u);
  EXPECT_EQ(r.unresolved[0].line, 6);
  EXPECT_NE(r.unresolved[0].reason.find("run time"), std::string::npos);
  EXPECT_EQ(r.unresolved[1].line, 7);  // the program changes dz: its value is not known before it runs
  EXPECT_EQ(r.unresolved[2].line, 8);
  EXPECT_NE(r.unresolved[2].reason.find("TriggL"), std::string::npos);
  ASSERT_EQ(r.targets.size(), 1u);
  EXPECT_EQ(r.targets[0].action, "copy p1_c1");  // TriggL and Offs still read the original p1
  const std::string& out = r.outputs.at(0).text;
  EXPECT_NE(
      out.find("    MoveL CRobT(), v100, fine, tool0;\n    MoveL Offs(p1,0,0,dz), v100, fine, tool0;\n    TriggL p1,"),
      std::string::npos);
}

TEST(ProgramEntry, NothingIsWrittenOnErrorAndTheInputIsNeverTheOutput) {
  const std::string dir = ::testing::TempDir() + "/deflex_prog_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/bad.mod") << module(std::string("  CONST robtarget p1:=") + kP1 + ";\n",
                                            "    MoveL p1, v100, fine, tNone;\n");
  const RobotModel m = builtin_irb6700();
  EXPECT_THROW((void)compensate_program(m, kPush, dir + "/bad.mod", dir + "/out.mod"), DataError);
  EXPECT_FALSE(std::filesystem::exists(dir + "/out.mod"));
  EXPECT_NE(
      error_of([&] { (void)compensate_program(m, kPush, dir + "/bad.mod", dir + "/bad.mod"); }).find("another file"),
      std::string::npos);
  EXPECT_NE(error_of([&] {
              (void)compensate_program(m, kPush, dir + "/x.txt", dir + "/y.txt");
            }).find("unknown program type"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// KRL.

TEST(KrlProgram, PointsToolsAndErrors) {
  ProgramOptions o;
  o.tooldata = {"TOOL_DATA[1]={X 250,Y 0,Z 0,A 0,B 0,C 0}"};
  const ProgramCompensation r = krl("DEF dxt()\nFDAT_ACT=FP1\nPTP XP1\nLIN P[1] C_DIS\nEND\n", kDat, o);
  ASSERT_EQ(r.targets.size(), 2u);
  EXPECT_EQ(r.targets[0].action, "edited in place");
  EXPECT_EQ(r.targets[1].action, "edited in place");
  ASSERT_EQ(r.outputs.size(), 2u);
  EXPECT_EQ(r.outputs[1].path, "out.dat");
  EXPECT_EQ(r.outputs[0].text,
            "DEF dxt()\nFDAT_ACT=FP1\nPTP XP1\nLIN P[1] C_DIS\nEND\n");  // nothing to change in the .src
  EXPECT_EQ(r.outputs[1].text.substr(0, 30), std::string(kDat).substr(0, 30));

  const auto fails = [&](const std::string& src, const ProgramOptions& opt, const std::vector<std::string>& fragments) {
    const std::string msg = error_of([&] { (void)krl(src, kDat, opt); });
    for (const auto& f : fragments) {
      EXPECT_NE(msg.find(f), std::string::npos) << "'" << msg << "' lacks '" << f << "'";
    }
  };
  fails("DEF dxt()\nFDAT_ACT=FP1\nLIN XP1 C_FOO\nEND\n", o, {"p.src:3", "LIN", "unknown 'C_FOO'"});
  fails("DEF dxt()\nFDAT_ACT=FP1\nPTP XP1\nEND\n", {},
        {"p.src:3", "$TOOL is TOOL_DATA[1]", "--tooldata \"TOOL_DATA[1]="});
  fails("DEF dxt()\nPTP XP1\nEND\n", o, {"p.src:2", "no $TOOL is set"});
  fails("DEF dxt()\nFDAT_ACT=FP1\nLIN {A1 0,A2 -90,A3 90,A4 0,A5 30,A6 0}\nEND\n", o, {"p.src:3", "PTP only"});
  fails("DEF dxt()\nFDAT_ACT=FP1\nCIRC XP1\nEND\n", o, {"p.src:3", "CIRC", "2 targets"});
  fails("DEF dxt()\n$TOOL=TOOL_DATA[1]\n$BASE=$NULLFRAME\nPTP {X 5000,Y 0,Z 600,A 0,B 90,C 0,S 2,T 2}\nEND\n", o,
        {"p.src:4", "unreachable"});
  // $TOOL from a FRAME the .dat declares: no command line needed.
  const ProgramCompensation from_dat = krl("DEF dxt()\n$TOOL=TSPINDLE\n$BASE=$NULLFRAME\nPTP XP1\nEND\n", kDat, {});
  EXPECT_EQ(from_dat.targets.size(), 1u);
  EXPECT_NEAR(from_dat.targets[0].correction_m, r.targets[0].correction_m, 1e-12);  // the same tool as TOOL_DATA[1]
  // A point without Status/Turn and nothing before it to continue from: the arm's configuration
  // when the program runs decides it, so it is listed.
  const ProgramCompensation nost =
      krl("DEF dxt()\n$TOOL=TOOL_DATA[1]\n$BASE=$NULLFRAME\nLIN {X 1800,Y -300,Z 600,A 20,B 75,C 15}\nPTP XP1\nEND\n",
          kDat, o);
  ASSERT_EQ(nost.unresolved.size(), 1u);
  EXPECT_EQ(nost.unresolved[0].line, 4);
  EXPECT_NE(nost.unresolved[0].reason.find("no Status and Turn"), std::string::npos);
  // After a point with them, it continues from it.
  const ProgramCompensation cont =
      krl("DEF dxt()\n$TOOL=TOOL_DATA[1]\n$BASE=$NULLFRAME\nPTP XP1\nLIN {X 1800,Y -250,Z 600,A 20,B 75,C 15}\nEND\n",
          kDat, o);
  EXPECT_EQ(cont.targets.size(), 2u);
  EXPECT_EQ(cont.targets[1].action, "literal edited");
}

TEST(ProgramText, EditsAndNumbers) {
  EXPECT_EQ(apply_edits("abcdef", {{4, 1, "X"}, {1, 2, ""}, {6, 0, "!"}}), "adXf!");
  EXPECT_THROW((void)apply_edits("abcdef", {{1, 3, "x"}, {2, 1, "y"}}), std::logic_error);
  EXPECT_EQ(program_number(-0.00001, 4), "0");
  EXPECT_EQ(program_number(12.5, 4), "12.5");
  EXPECT_EQ(program_number(1500.0, 4), "1500");
  EXPECT_EQ(program_number(-0.12345678, 4), "-0.1235");
  EXPECT_EQ(line_of("a\nb\nc", 4), 3);
  EXPECT_EQ(line_terminator("x\r\ny"), "\r\n");
}

}  // namespace
}  // namespace deflex
