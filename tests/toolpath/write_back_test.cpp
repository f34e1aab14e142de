// The compensated G-code: lines that are not motions byte for byte, motion lines as written here by
// hand, round trips (read, write with a known correction, read again) within the number format's
// resolution, and every refusal leaving nothing behind.
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"
#include "deflex/toolpath/gcode_write_back.hpp"
#include "support/error_of.hpp"
#include "toolpath/toolpath_test_util.hpp"

namespace deflex::test {
namespace {

namespace fs = std::filesystem;

std::string scratch(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / "deflex_write_back";
  fs::create_directories(dir);
  return (dir / name).string();
}

void put(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<ToolpathPoint> read_file(const std::string& path, const ToolpathOptions& o = {}) {
  GcodeReader r(path, o);
  std::vector<ToolpathPoint> v;
  ToolpathPoint p;
  while (r.next(p)) v.push_back(p);
  return v;
}

/// Writes the compensated program with every point moved by `shift_m`.
void write_shifted(const std::string& src, const std::string& out, const Vector3& shift_m,
                   const ToolpathOptions& o = {}) {
  GcodeWriteBack wb(src, out, o);
  for (const ToolpathPoint& p : read_file(src, o)) wb.add(p, p.position_m + shift_m);
  wb.finish();
}

/// Splits text into lines with their endings.
std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at < text.size()) {
    std::size_t end = text.find_first_of("\r\n", at);
    if (end == std::string::npos) {
      out.push_back(text.substr(at));
      break;
    }
    end += (text[end] == '\r' && end + 1 < text.size() && text[end + 1] == '\n') ? 2 : 1;
    out.push_back(text.substr(at, end - at));
    at = end;
  }
  return out;
}

const std::string kProgram =
    "%\r\n"                       // 1 (a CRLF line among LF ones)
    "O0001 (WRITE BACK TEST)\n"   // 2
    "N10 G21 G90 G17 G94\n"       // 3
    "N20 T1 M6\n"                 // 4
    "N30 S15000 M3\n"             // 5
    "N40 G0 X-5. Y-5.\n"          // 6: no point (Z unknown): kept as it is
    "N50 G43 Z10. H1\n"           // 7
    "N60 G1 Z-2.5 F800.\n"        // 8
    "\n"                          // 9
    "N70 X30. F2000.\n"           // 10
    "N80 G3 X40. Y5. I0. J10.\n"  // 11
    "N90 G1 Y30.\n"               // 12
    "N100 G2 X30. Y40. R10.\n"    // 13
    "N110 G91 G1 X-10.\n"         // 14
    "N120 Y-5. (incremental)\n"   // 15
    "N130 G90 G0 Z10.\n"          // 16
    "N140 M5\n"                   // 17
    "N150 M30\n"                  // 18
    "%";                          // 19: no ending

TEST(GcodeWriteBack, LinesThatAreNotMotionsAreKeptByteForByte) {
  const std::string src = scratch("keep.nc"), out = scratch("keep_out.nc");
  put(src, kProgram);
  const auto points = read_file(src);
  write_shifted(src, out, Vector3::Zero());
  const std::vector<std::string> in = lines_of(kProgram);
  const std::vector<std::string> written = lines_of(slurp(out));
  // How many lines each source line became: its points for a motion line, else 1.
  std::vector<std::size_t> count(in.size() + 1, 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (i == 0 || points[i].segment != points[i - 1].segment) count[points[i].line] = 0;
    ++count[points[i].line];
  }
  std::size_t at = 0;
  for (std::size_t n = 1; n <= in.size(); ++n) {
    const bool motion = std::any_of(points.begin(), points.end(), [&](const ToolpathPoint& p) { return p.line == n; });
    ASSERT_LT(at, written.size());
    if (!motion) {
      EXPECT_EQ(written[at], in[n - 1]) << "source line " << n;
    }
    at += count[n];
  }
  EXPECT_EQ(at, written.size());
}

TEST(GcodeWriteBack, MotionLinesAreRewrittenAsWrittenHereByHand) {
  const std::string src = scratch("hand.nc"), out = scratch("hand_out.nc");
  put(src, kProgram);
  write_shifted(src, out, Vector3::Zero());
  const std::string text = slurp(out);
  const auto has = [&](const std::string& line) { return text.find(line) != std::string::npos; };
  EXPECT_TRUE(has("\nN40 G0 X-5. Y-5.\n")) << text;                    // before the position is known
  EXPECT_TRUE(has("\nN50 G43 X-5.000 Y-5.000 Z10.000 H1\n")) << text;  // G0 is still modal in the output
  EXPECT_TRUE(has("\nN60 G1 X-5.000 Y-5.000 Z-2.500 F800.\n")) << text;
  EXPECT_TRUE(has("\nN70 X30.000 Y-5.000 Z-2.500 F2000.\n")) << text;
  // G3 becomes G1 on its first chord; I and J go with it; the other chords follow on lines of their own.
  EXPECT_TRUE(has("\nN80 G1 X")) << text;
  EXPECT_FALSE(has("I0.")) << text;
  EXPECT_TRUE(has("\nX40.000 Y5.000 Z-2.500\nN90 G1 X40.000 Y30.000 Z-2.500\n")) << text;
  EXPECT_TRUE(has("\nX30.000 Y40.000 Z-2.500\nN110 G90 G1 X20.000 Y40.000 Z-2.500\n")) << text;  // G91 -> G90
  EXPECT_TRUE(has("\nN120 X20.000 Y35.000 Z-2.500 (incremental)\n")) << text;
  EXPECT_TRUE(has("\nN130 G90 G0 X20.000 Y35.000 Z10.000\n")) << text;
  EXPECT_TRUE(text.size() > 2 && text.substr(text.size() - 2) == "\n%") << text;
}

TEST(GcodeWriteBack, RoundTripWithAKnownCorrectionWithinTheNumberFormat) {
  const std::string src = scratch("round.nc"), out = scratch("round_out.nc"), zero = scratch("round_zero.nc");
  put(src, kProgram);
  const auto original = read_file(src);
  const Vector3 shift = mm(0.1234, -0.2, 0.05);
  write_shifted(src, out, shift);
  write_shifted(src, zero, Vector3::Zero());
  for (const auto& [file, d] : {std::pair{out, shift}, std::pair{zero, Vector3(Vector3::Zero())}}) {
    const auto again = read_file(file);
    ASSERT_EQ(again.size(), original.size()) << file;
    for (std::size_t i = 0; i < original.size(); ++i) {
      // Three decimals in mm: within half a micrometre.
      EXPECT_LE((again[i].position_m - (original[i].position_m + d)).cwiseAbs().maxCoeff(), 0.5e-6 + 1e-12) << i;
      EXPECT_EQ(again[i].feed_m_s, original[i].feed_m_s) << i;
      EXPECT_EQ(again[i].spindle, original[i].spindle) << i;
      EXPECT_EQ(again[i].spindle_rpm, original[i].spindle_rpm) << i;
      EXPECT_EQ(again[i].tool, original[i].tool) << i;
      const bool rapid = original[i].motion == MotionKind::kRapid;
      EXPECT_EQ(again[i].motion, rapid ? MotionKind::kRapid : MotionKind::kLinear) << i;
    }
  }
}

TEST(GcodeWriteBack, InchProgramsAreWrittenInInchesWithFourDecimals) {
  const std::string src = scratch("inch.nc"), out = scratch("inch_out.nc");
  put(src, "G20 G90\nS100 M3\nF10\nG0 X1 Y1 Z1\nG1 X2.5\n");
  write_shifted(src, out, mm(0.0254, 0, 0));  // a thousandth of an inch
  EXPECT_EQ(slurp(out), "G20 G90\nS100 M3\nF10\nG0 X1.0010 Y1.0000 Z1.0000\nG1 X2.5010 Y1.0000 Z1.0000\n");
}

TEST(GcodeWriteBack, CompactLinesStayCompactAndToolAxisWordsFollowTheChords) {
  const std::string src = scratch("five.nc"), out = scratch("five_out.nc");
  put(src, "TRAORI\nS100M3\nF100\nG0X0Y0Z0A3=0B3=0C3=1\nG1X10A3=0B3=0.6C3=0.8\n");
  ToolpathOptions o;
  o.max_linear_step_m = 0.005;
  write_shifted(src, out, Vector3::Zero(), o);
  const std::string mid = "A3=0.000000B3=0.316228C3=0.948683";  // the bisector of +z and (0, 0.6, 0.8)
  EXPECT_EQ(slurp(out), "TRAORI\nS100M3\nF100\nG0X0.000Y0.000Z0.000A3=0B3=0C3=1\nG1X5.000Y0.000Z0.000" + mid +
                            "\nX10.000Y0.000Z0.000A3=0.000000B3=0.600000C3=0.800000\n");
  const auto again = read_file(out, o);
  const auto original = read_file(src, o);
  ASSERT_EQ(again.size(), original.size());
  for (std::size_t i = 0; i < again.size(); ++i) {
    EXPECT_LE((again[i].tool_axis - original[i].tool_axis).norm(), 1e-6) << i;
  }
}

TEST(GcodeWriteBack, ByteOrderMarkAndCarriageReturnEndingsAreKept) {
  const std::string src = scratch("bom.nc"), out = scratch("bom_out.nc");
  put(src, "\xEF\xBB\xBF(BOM)\rS100 M3\rG0 X1 Y2 Z3\r");
  write_shifted(src, out, Vector3::Zero());
  EXPECT_EQ(slurp(out), "\xEF\xBB\xBF(BOM)\rS100 M3\rG0 X1.000 Y2.000 Z3.000\r");
}

TEST(GcodeWriteBack, RefusesToOverwriteItsSourceWhateverTheSpelling) {
  const std::string src = scratch("self.nc");
  put(src, kProgram);
  const std::string e = error_of([&] { GcodeWriteBack wb(src, src); });
  EXPECT_NE(e.find("would overwrite the program it is made from"), std::string::npos) << e;
  const std::string other = (fs::path(src).parent_path() / "." / "self.nc").string();
  EXPECT_THROW(GcodeWriteBack(src, other), InputError);
  const std::string link = scratch("self_link.nc");
  fs::remove(link);
  fs::create_symlink(src, link);
  EXPECT_THROW(GcodeWriteBack(src, link), InputError);
  EXPECT_EQ(slurp(src), kProgram);
}

TEST(GcodeWriteBack, PointsThatDoNotFollowTheProgramAreRefusedAndNothingIsWritten) {
  const std::string src = scratch("strict.nc"), out = scratch("strict_out.nc");
  put(src, kProgram);
  fs::remove(out);
  const auto points = read_file(src);
  {
    GcodeWriteBack wb(src, out);
    wb.add(points[0], points[0].position_m);
    const std::string e = error_of([&] { wb.add(points[2], points[2].position_m); });
    EXPECT_NE(e.find("do not follow the program: its next point is on line 8"), std::string::npos) << e;
  }
  EXPECT_FALSE(fs::exists(out));
  {
    GcodeWriteBack wb(src, out);
    for (std::size_t i = 0; i + 1 < points.size(); ++i) wb.add(points[i], points[i].position_m);
    const std::string e = error_of([&] { wb.finish(); });
    EXPECT_NE(e.find("the compensated points end before the program's motion"), std::string::npos) << e;
  }
  EXPECT_FALSE(fs::exists(out));
  {
    GcodeWriteBack wb(src, out);
    EXPECT_THROW(wb.add(points[0], Vector3(kNaN, 0, 0)), InputError);
  }
  EXPECT_FALSE(fs::exists(out));
  // With other options the points differ: refused, not silently misplaced.
  {
    ToolpathOptions fine;
    fine.chord_tolerance_m = 1e-6;
    GcodeWriteBack wb(src, out, fine);
    std::string e;
    for (const auto& p : points) {
      e = error_of([&] { wb.add(p, p.position_m); });
      if (e != "no error") break;
    }
    EXPECT_NE(e.find("do not follow the program"), std::string::npos) << e;
  }
  EXPECT_FALSE(fs::exists(out));
}

TEST(GcodeWriteBack, AptSourceIsRefused) {
  const std::string src = scratch("part.apt");
  put(src, "SPINDL/100\nFEDRAT/100\nGOTO/0,0,0\n");
  EXPECT_NE(error_of([&] { GcodeWriteBack wb(src, scratch("part_out.nc")); }).find("APT/CL data"), std::string::npos);
}

}  // namespace
}  // namespace deflex::test
