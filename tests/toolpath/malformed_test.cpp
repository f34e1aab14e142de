// Every kind of malformed toolpath, one table: each must be refused with a DataError naming the file,
// the line and the word or record; and random garbage never crashes a reader.
#include <filesystem>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"
#include "deflex/toolpath/toolpath_reader.hpp"
#include "support/error_of.hpp"
#include "toolpath/toolpath_test_util.hpp"

namespace deflex::test {
namespace {

struct Malformed {
  const char* name;
  std::string program;
  std::string expect;  // a fragment of the message, file and line included
};

const std::string kG = "G21 G90 G17\nS10000 M3\nF1000\nG0 X0 Y0 Z0\n";  // four good lines

std::vector<Malformed> gcode_cases() {
  return {
      {"canned cycle", kG + "G81 X0 Y0 Z-5 R1\n", "t.nc:5: word 'G81': canned cycles"},
      {"unknown letter", kG + "G1 X10 E5\n", "t.nc:5: word 'E5': 'E' is not a word deflex reads"},
      {"parameter", kG + "#1=5\n", "t.nc:5: '#1=5': a parameter"},
      {"expression", kG + "G1 X[1+2]\n", "t.nc:5: 'X[1+2]': the letter 'X' without a number"},
      {"nan", kG + "G1 Xnan\n", "t.nc:5: word 'Xnan': not a word deflex reads"},
      {"huge coordinate", kG + "G1 X200000\n", "t.nc:5: word 'X200000': a coordinate of 200 m"},
      {"huge inch coordinate", "G20\nS100 M3\nF10\nG0 X0 Y0 Z0\nG1 X5000\n",
       "t.nc:5: word 'X5000': a coordinate of 127 m"},
      {"feed zero", "S100 M3\nG0 X0 Y0 Z0\nG1 X10 F0\n", "t.nc:3: word 'F0': a cutting move (G1) at feed 0"},
      {"feed never", "S100 M3\nG0 X0 Y0 Z0\nG1 X10\n", "t.nc:3: word 'F': a cutting move (G1) with no feed"},
      {"feed huge", kG + "G1 X1 F200000\n", "t.nc:5: word 'F200000': a feed of 200000 mm/min"},
      {"feed negative", kG + "F-5\n", "t.nc:5: word 'F-5': a feed of -5 mm/min"},
      {"spindle stopped", kG + "M5\nG1 X10\n",
       "t.nc:6: word 'M5': a cutting move (G1) with the spindle stopped (M5 "
       "on line 5)"},
      {"spindle never", "F100\nS100\nG0 X0 Y0 Z0\nG2 X1 Y1 R1\n", "t.nc:4: word 'M3': a cutting move (G2) before any"},
      {"spindle speed zero", kG + "S0\nG1 X10\n", "t.nc:6: word 'S': a cutting move (G1) at spindle speed 0"},
      {"spindle speed huge", kG + "S200000\n", "t.nc:5: word 'S200000': a spindle speed outside"},
      {"inverse time", kG + "G93\n", "t.nc:5: word 'G93': inverse-time"},
      {"per revolution", kG + "G95\n", "t.nc:5: word 'G95'"},
      {"cutter compensation", kG + "G41 D1\n", "t.nc:5: word 'G41': cutter radius compensation"},
      {"home", kG + "G28 Z0\n", "t.nc:5: word 'G28'"},
      {"machine coordinates", kG + "G53 G0 Z0\n", "t.nc:5: word 'G53'"},
      {"unknown G", kG + "G15\n", "t.nc:5: word 'G15': a G code deflex does not read"},
      {"G with decimals", kG + "G1.5 X1\n", "t.nc:5: word 'G1.5': a G code deflex does not read"},
      {"unknown M", kG + "M98 P100\n", "t.nc:5: word 'M98': an M code"},
      {"two X", kG + "G1 X10 X20\n", "t.nc:5: word 'X20': a second 'X' in one block"},
      {"two motions", kG + "G0 G1 X1\n", "t.nc:5: word 'G1': a second motion G code"},
      {"two spindle M", kG + "M3 M5\n", "t.nc:5: word 'M5': a second spindle M code"},
      {"open comment", kG + "G1 X1 (no end\n", "t.nc:5: '(no end': a comment '(' without its ')'"},
      {"block delete", kG + "/G1 X1\n", "t.nc:5: '/G1 X1': a block-delete"},
      {"K in G17", kG + "G2 X10 Y0 I5 J0 K1\n", "t.nc:5: word 'K1': K is not an arc offset in the G17 plane"},
      {"J in G18", kG + "G18 G2 X10 Z0 I5 J1\n", "t.nc:5: word 'J1': J is not an arc offset in the G18 plane"},
      {"R zero", kG + "G2 X10 Y0 R0\n", "t.nc:5: word 'R0': an arc of radius 0"},
      {"R huge", kG + "G2 X10 Y0 R-200000\n", "t.nc:5: word 'R-200000': an arc radius beyond 100 m"},
      {"R and I", kG + "G2 X10 Y0 R5 I5\n", "t.nc:5: word 'R5': an arc by R and by I, J, K at once"},
      {"R end at start", kG + "G2 X0 Y0 R10\n", "t.nc:5: word 'R10': an arc by R whose end is its start"},
      {"arc without centre", kG + "G2 X10 Y0\n", "t.nc:5: word 'G2': an arc with neither"},
      {"zero radius", kG + "G2 X0 Y0 I0 J0\n", "t.nc:5: word 'I0': the arc's centre is at its start point"},
      {"R on a line", kG + "G1 X1 R5\n", "t.nc:5: word 'R5': R belongs to an arc"},
      {"I on a line", kG + "G1 X1 I5\n", "t.nc:5: word 'I5': I, J, K belong to an arc"},
      {"no motion mode", "S100 M3\nX10 Y0 Z0\n", "t.nc:2: word 'X10': a coordinate with no motion mode"},
      {"cancelled motion", kG + "G80\nX10\n", "t.nc:6: word 'X10': a coordinate with no motion mode"},
      {"cut before position", "S100 M3\nF100\nG1 X10\n",
       "t.nc:3: word 'G1': a cutting move before the position is "
       "known on X, Y, Z"},
      {"cut before z", "S100 M3\nF100\nG0 X0 Y0\nG1 X10\n", "known on Z"},
      {"incremental unknown", "G91 G0 X10\n", "t.nc:1: word 'X10': an incremental move (G91) on an axis whose"},
      {"vector without TRAORI", kG + "G1 X1 A3=0 B3=0 C3=1\n",
       "t.nc:5: word 'A3=0': A3= B3= C3= give the tool axis "
       "under TRAORI"},
      {"vector incomplete", kG + "TRAORI\nG1 X1 A3=0 B3=0\n",
       "t.nc:6: word 'A3=0': a tool-axis vector needs all three"},
      {"vector zero", kG + "TRAORI\nG1 X1 A3=0 B3=0 C3=0\n", "t.nc:6: word 'A3=0': a tool-axis vector of length 0"},
      {"vector and angles", kG + "TRAORI\nG1 X1 A30 A3=0 B3=0 C3=1\n", "t.nc:6: word 'A30': rotary angles"},
      {"axis half turn", kG + "TRAORI\nG1 X1 A3=0 B3=0 C3=-1\n", "t.nc:6: word 'G1': the tool axis turns half a turn"},
      {"index 2", kG + "G1 X1 A2=5\n", "t.nc:5: 'A2=5': an address with an index other than 3"},
      {"IJK vector incomplete", kG + "G43.5 H1\nG1 X1 I0 J0\n", "t.nc:6: word 'I0': a tool-axis vector (G43.5) needs"},
      {"angle huge", kG + "G1 A4000\n", "t.nc:5: word 'A4000': a rotary angle outside"},
      {"assignment", kG + "G1 X=10\n", "t.nc:5: 'X=10': 'X=' assigns a value"},
      {"double sign", kG + "G1 X--5\n", "t.nc:5: 'X--5': the letter 'X' without a number"},
      {"work offset change", "G54\n" + kG + "G55\n",
       "t.nc:6: word 'G55': the program changes work offset from G54 "
       "(line 1)"},
      {"motion after end", kG + "M30\nG0 X5\n",
       "t.nc:6: word 'G0': a motion after the program's end (M2/M30 on line "
       "5)"},
      {"P without G4", kG + "G1 X1 P2\n", "t.nc:5: word 'P2': P is read only as G4's dwell time"},
      {"dwell that moves", kG + "G4 P1 Y3\n", "t.nc:5: word 'G4': G4 (dwell) takes its time"},
      {"tool fraction", kG + "T1.5\n", "t.nc:5: word 'T1.5': a tool number is a whole number"},
      {"N fraction", kG + "N1.5 G0 X1\n", "t.nc:5: word 'N1.5': a block or program number"},
      {"G70 ISO", kG + "G70\n", "t.nc:5: word 'G70': G70/G71 are inch/mm on a Siemens control"},
      {"Siemens cycle", kG + "CYCLE800(1,\"TC1\")\n", "t.nc:5: word 'CYCLE800': not a word deflex reads"},
      {"Siemens tool name", kG + "T=\"MILL10\"\n", "t.nc:5: 'T=\"MILL10\"': 'T=' assigns a value"},
      {"unknown keyword", kG + "ORIMKS\n", "t.nc:5: word 'ORIMKS': not a word deflex reads"},
      {"garbage byte", kG + "G1 X1 \x01\n", "t.nc:5: '?': not a G-code word"},
      {"NUL byte", kG + std::string("G1 X1\0\n", 7), "t.nc:5: a NUL byte"},
      {"long line", kG + std::string(70000, ' ') + "\n", "t.nc:5: a line longer than 65536 bytes"},
      {"empty program", "%\n(nothing)\n%\n", "t.nc: no motion to a known position"},
      {"only unknown rapids", "G0 X1 Y2\n", "t.nc: no motion to a known position"},
  };
}

TEST(MalformedToolpaths, GcodeRefusedNamingFileLineAndWord) {
  for (const Malformed& c : gcode_cases()) {
    std::string message = "no error";
    try {
      (void)gcode_points(c.program);
    } catch (const DataError& e) {
      message = e.what();
    } catch (const std::exception& e) {
      message = std::string("not a DataError: ") + e.what();
    }
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.name << ": " << message;
  }
}

const std::string kA = "SPINDL/RPM,1000,CLW\nFEDRAT/MMPM,100\nGOTO/0,0,0\n";  // three good lines

std::vector<Malformed> apt_cases() {
  return {
      {"two coordinates", kA + "GOTO/1,2\n", "t.apt:4: record 'GOTO': takes x, y, z or x, y, z, i, j, k, not 2"},
      {"not a number", kA + "GOTO/1,2,abc\n", "t.apt:4: record 'GOTO', argument 3 'ABC': 'ABC' is not a number"},
      {"nan", kA + "GOTO/1,2,nan\n", "argument 3 'NAN': 'NAN' is not a finite number"},
      {"huge", kA + "GOTO/200000,0,0\n", "t.apt:4: record 'GOTO', argument 1 '200000': a coordinate of 200 m"},
      {"beyond 1e12", kA + "GOTO/1e300,0,0\n", "argument 1 '1E300': a value beyond 1e12"},
      {"axis not unit", kA + "GOTO/1,2,3,0,0,2\n",
       "t.apt:4: record 'GOTO', argument 4 '0': the tool axis (0, 0, 2) "
       "has length 2"},
      {"axis half turn", kA + "GOTO/1,2,3,0,0,-1\n", "t.apt:4: record 'GOTO': the tool axis turns half a turn"},
      {"feed per rev", kA + "FEDRAT/MMPR,0.1\n", "t.apt:4: record 'FEDRAT', argument 1 'MMPR': a feed per revolution"},
      {"feed unit", kA + "FEDRAT/100,FPM\n", "argument 2 'FPM': not a feed unit"},
      {"feed huge", kA + "FEDRAT/200000\n", "t.apt:4: record 'FEDRAT': a feed of 200000 mm/min"},
      {"feed none", "SPINDL/1000\nGOTO/0,0,0\n",
       "t.apt:2: record 'GOTO': a cutting move (GOTO without RAPID) with "
       "no feed"},
      {"feed zero", "SPINDL/1000\nFEDRAT/0\nGOTO/0,0,0\n",
       "t.apt:3: record 'GOTO': a cutting move (GOTO without "
       "RAPID) at feed 0 (FEDRAT on line 2)"},
      {"spindle never", "FEDRAT/100\nGOTO/0,0,0\n", "t.apt:2: record 'GOTO': a cutting move before any SPINDL"},
      {"spindle off", kA + "SPINDL/OFF\nGOTO/1,0,0\n",
       "t.apt:5: record 'GOTO': a cutting move with the spindle "
       "stopped (SPINDL/OFF on line 4)"},
      {"spindle zero", "SPINDL/0\nFEDRAT/100\nGOTO/0,0,0\n",
       "t.apt:3: record 'GOTO': a cutting move at spindle "
       "speed 0"},
      {"surface speed", kA + "SPINDL/SMM,200\n", "t.apt:4: record 'SPINDL', argument 1 'SMM': a surface speed"},
      {"cycle", kA + "CYCLE/DRILL,RAPTO,3,FEDTO,-33,MMPM,250\n", "t.apt:4: record 'CYCLE': canned cycles"},
      {"cutcom", kA + "CUTCOM/LEFT\n", "t.apt:4: record 'CUTCOM': cutter radius compensation"},
      {"unknown record", kA + "MOVARC/0,0,0,0,0,1,5,ANGLE,90\n", "t.apt:4: record 'MOVARC': not a CL record"},
      {"insert", kA + "INSERT/G1 X5\n", "t.apt:4: record 'INSERT': not a CL record"},
      {"gohome", kA + "GOHOME\n", "t.apt:4: record 'GOHOME'"},
      {"circle interrupted", kA + "CIRCLE/0,10,0,0,0,1,10\nFEDRAT/50\nGOTO/10,10,0\n",
       "t.apt:5: record 'FEDRAT': "
       "comes between the CIRCLE of "
       "line 4 and its GOTO"},
      {"circle at end", kA + "CIRCLE/0,10,0,0,0,1,10\n", "t.apt:4: record 'CIRCLE': no GOTO follows it"},
      {"circle radius", kA + "CIRCLE/0,10,0,0,0,1,12\nGOTO/10,10,0\n",
       "t.apt:5: record 'GOTO': the arc starts 10.0000 "
       "mm from the centre of the CIRCLE of line 4, "
       "whose radius is 12.0000 mm"},
      {"circle end off", kA + "CIRCLE/0,10,0,0,0,1,10\nGOTO/10,11,0\n", "t.apt:5: record 'GOTO': the arc's end is"},
      {"circle after rapid", kA + "RAPID\nCIRCLE/0,10,0,0,0,1,10\n", "t.apt:5: record 'CIRCLE': an arc after RAPID"},
      {"circle too few", kA + "CIRCLE/0,10,0,0,0,1\n", "t.apt:4: record 'CIRCLE': takes 7 to 11 arguments, not 6"},
      {"circle no start", "SPINDL/1000\nFEDRAT/100\nCIRCLE/0,10,0,0,0,1,10\nGOTO/10,10,0\n",
       "t.apt:4: record 'GOTO': "
       "the CIRCLE of line 3 has "
       "no start"},
      {"continued past end", kA + "GOTO/1,2,$\n", "t.apt:4: the record continues ('$') past the end of the file"},
      {"empty argument", kA + "GOTO/1,,3\n", "t.apt:4: record 'GOTO': an empty argument"},
      {"units", kA + "UNITS/FEET\n", "t.apt:4: record 'UNITS', argument 1 'FEET': neither MM nor INCHES"},
      {"after fini", kA + "FINI\nGOTO/1,0,0\n", "t.apt:5: record 'GOTO': a record after FINI"},
      {"cutter zero", kA + "CUTTER/0\n", "t.apt:4: record 'CUTTER', argument 1 '0': a cutter diameter outside"},
      {"corner radius", kA + "CUTTER/10,6\n", "t.apt:4: record 'CUTTER', argument 2 '6': a corner radius outside"},
      {"tldata drill", kA + "TLDATA/DRILL,10,118\n", "t.apt:4: record 'TLDATA': only TLDATA/MILL"},
      {"tool fraction", kA + "LOADTL/1.5\n", "t.apt:4: record 'LOADTL', argument 1 '1.5': a tool number"},
      {"multax", kA + "MULTAX/MAYBE\n", "t.apt:4: record 'MULTAX', argument 1 'MAYBE': neither ON nor OFF"},
      {"rapid args", kA + "RAPID/5\n", "t.apt:4: record 'RAPID': takes 0 arguments, not 1"},
      {"empty", "$$ nothing\nPARTNO X\n", "t.apt: no GOTO"},
  };
}

TEST(MalformedToolpaths, AptRefusedNamingFileLineAndRecord) {
  for (const Malformed& c : apt_cases()) {
    std::string message = "no error";
    try {
      (void)apt_points(c.program);
    } catch (const DataError& e) {
      message = e.what();
    } catch (const std::exception& e) {
      message = std::string("not a DataError: ") + e.what();
    }
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.name << ": " << message;
  }
}

TEST(MalformedToolpaths, OptionsOutOfRangeAreInputErrors) {
  ToolpathOptions o;
  o.chord_tolerance_m = 0.0;
  EXPECT_NE(error_of([&] { (void)gcode_points("G0 X0 Y0 Z0\n", o); }).find("chord_tolerance_m"), std::string::npos);
  o = {};
  o.arc_radius_tolerance_m = std::nan("");
  EXPECT_THROW((void)apt_points("GOTO/0,0,0\n", o), InputError);
  o = {};
  o.max_linear_step_m = 1e-9;
  EXPECT_THROW((void)gcode_points("G0 X0 Y0 Z0\n", o), InputError);
}

TEST(MalformedToolpaths, ABlockOfTooManyPointsIsRefused) {
  ToolpathOptions o;
  o.max_linear_step_m = 1e-5;  // 99 m in steps of 0.01 mm: 9.9 million points
  const std::string e = error_of([&] { (void)gcode_points(kG + "G1 X99000\n", o); });
  EXPECT_NE(e.find("t.nc:5: a linear move would become 9900000 points, more than the 1000000"), std::string::npos) << e;
}

TEST(MalformedToolpaths, UnknownExtensionIsRefusedWithTheList) {
  const std::string e = error_of([] { (void)open_toolpath("part.mpf"); });
  EXPECT_NE(e.find("part.mpf: the toolpath's extension '.mpf'"), std::string::npos) << e;
  EXPECT_NE(e.find(".nc, .gcode, .tap"), std::string::npos) << e;
  EXPECT_NE(e.find(".apt, .cls"), std::string::npos) << e;
  EXPECT_THROW((void)open_toolpath("noextension"), InputError);
}

TEST(MalformedToolpaths, MissingFileAndFolderAreRefusedByTheInputLayer) {
  EXPECT_NE(error_of([] { (void)read_toolpath("/nonexistent/dir/part.nc"); }).find("does not exist"),
            std::string::npos);
  const std::string dir = ::testing::TempDir() + "folder.nc";
  std::filesystem::create_directories(dir);
  EXPECT_NE(error_of([&] { (void)read_toolpath(dir); }).find("a directory"), std::string::npos);
}

/// A line of random bytes drawn mostly from G-code's and APT's alphabets.
std::string garbage_line(std::mt19937& rng) {
  static const std::string kAlphabet = "GMXYZABCIJKRFSTNOPHD0123456789.-+ ()/;%=,$#[]EQUVWL\t3GOTO/CIRCLE/FEDRAT";
  std::uniform_int_distribution<std::size_t> length(0, 40), pick(0, kAlphabet.size() - 1), byte(0, 255);
  std::string line;
  const std::size_t n = length(rng);
  for (std::size_t i = 0; i < n; ++i) {
    line += (i % 13 == 12) ? static_cast<char>(byte(rng)) : kAlphabet[pick(rng)];
  }
  return line;
}

TEST(MalformedToolpaths, RandomGarbageNeverCrashesEitherReader) {
  std::mt19937 rng(2024);
  std::uniform_int_distribution<int> lines(1, 8);
  int refused = 0, read = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string program = i % 2 == 0 ? "S100 M3\nF100\nG0 X0 Y0 Z0\n" : "SPINDL/100\nFEDRAT/100\nGOTO/0,0,0\n";
    const int n = lines(rng);
    for (int k = 0; k < n; ++k) program += garbage_line(rng) + (k % 3 == 0 ? "\r\n" : "\n");
    try {
      const auto p = i % 2 == 0 ? gcode_points(program) : apt_points(program);
      for (const auto& q : p) {
        ASSERT_TRUE(q.position_m.allFinite() && q.tool_axis.allFinite()) << program;
        ASSERT_NEAR(q.tool_axis.norm(), 1.0, 1e-9) << program;
        ASSERT_LE(q.position_m.cwiseAbs().maxCoeff(), 100.0) << program;
      }
      ++read;
    } catch (const DataError&) {
      ++refused;
    }
  }
  EXPECT_GT(refused, 1000);
  EXPECT_GT(read, 100);
}

}  // namespace
}  // namespace deflex::test
