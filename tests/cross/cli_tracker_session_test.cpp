// A real tracker session through the program: the study's example runs exported in a tracker's frame
// and on its clock, `deflex register` from named points, `deflex evaluate --tracker-frame --align-to`
// giving the base-frame figures and the clock offset set; and each bad tracker file refused with exit 2
// naming the file and line.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "deflex/model/types.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;
using test::run_cli;

const std::string kTrackerExamples = std::string(DEFLEX_SOURCE_DIR) + "/examples/evaluate/";

struct TrackerSession {
  fs::path dir = fs::temp_directory_path() / ("deflex_tracker_session_" + std::to_string(::getpid()));
  Pose base_T_tracker = Pose::Identity();
  TrackerSession() {
    fs::create_directories(dir);
    base_T_tracker.linear() = Eigen::AngleAxisd(-2.1, Vector3(0.1, 0.2, 1.0).normalized()).toRotationMatrix();
    base_T_tracker.translation() = Vector3(4.1, -2.3, 0.35);
  }
  ~TrackerSession() { fs::remove_all(dir); }
  // A base-frame CSV of the examples as an SA export in the tracker's frame (metres), stamped on a
  // clock `clock_s` ahead of the file's and running `drift` fast, 3 um noise.
  std::string export_run(const std::string& name, double clock_s, std::uint32_t seed, double drift = 0.0) const {
    std::ifstream in(kTrackerExamples + name);
    std::string line;
    std::getline(in, line);
    const fs::path out_path = dir / (name + ".txt");
    std::ofstream out(out_path);
    out << "// SA Version: 2023.1\n// Working Frame: AT960 Tracker\n// Units: Meters\n"
           "// Columns: Target X Y Z Time\n";
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 3e-6);
    int k = 0;
    while (std::getline(in, line)) {
      double t, x, y, z;
      char c;
      std::istringstream(line) >> t >> c >> x >> c >> y >> c >> z;
      const Vector3 p = base_T_tracker.inverse() * (Vector3(x, y, z) * 1e-3) + Vector3(n(rng), n(rng), n(rng));
      out << fmt::format("P{} {:.12f} {:.12f} {:.12f} {:.6f}\n", ++k, p.x(), p.y(), p.z(), clock_s + t * (1.0 + drift));
    }
    return out_path.string();
  }
  void write(const std::string& name, const std::string& text) const { std::ofstream(dir / name) << text; }
  [[nodiscard]] std::string path(const std::string& name) const { return (dir / name).string(); }
};

TEST(CliTrackerSession, RegisteredAndAlignedRunsGiveTheBaseFrameFigures) {
  TrackerSession s;
  // Six named points measured in both frames (tracker in m, base in mm), 5 um noise on the tracker side.
  std::string base = "// Working Frame: Robot Base\n// Units: Millimeters\n";
  const std::vector<Vector3> pts{{1.5, -0.5, 0.5}, {2.2, -0.4, 0.7}, {1.8, 0.6, 0.4},
                                 {2.0, 0.0, 1.5},  {1.6, 0.3, 1.2},  {2.5, 0.5, 0.9}};
  for (std::size_t i = 0; i < pts.size(); ++i) {
    base += fmt::format("R{} {:.9f} {:.9f} {:.9f}\n", i + 1, pts[i].x() * 1e3, pts[i].y() * 1e3, pts[i].z() * 1e3);
  }
  std::string tracker = "// Working Frame: AT960 Tracker\n// Units: Meters\n";
  for (std::size_t i = pts.size(); i-- > 0;) {  // the other order: pairs are made by name
    const Vector3 t = s.base_T_tracker.inverse() * pts[i] + Vector3(5e-6, -4e-6, 3e-6) * (i % 2 == 0 ? 1 : -1);
    tracker += fmt::format("R{},{:.12f},{:.12f},{:.12f}\n", i + 1, t.x(), t.y(), t.z());
  }
  s.write("base.txt", base);
  s.write("tracker.txt", tracker);
  const auto reg = run_cli("register --tracker " + s.path("tracker.txt") + " --base " + s.path("base.txt") + " -o " +
                           s.path("frame.yaml") + " --json");
  ASSERT_EQ(reg.exit_code, 0) << reg.err;
  const auto rdoc = nlohmann::json::parse(reg.out);
  EXPECT_EQ(rdoc["tracker_frame"], "AT960 Tracker");
  EXPECT_LT(rdoc["rms_mm"].get<double>(), 0.02);
  EXPECT_NEAR(rdoc["position_mm"][0].get<double>(), 4100.0, 0.05);

  const std::string unloaded = s.export_run("unloaded.csv", 812.25, 1);
  const std::string loaded = s.export_run("loaded_uc.csv", 903.5, 2);
  const auto base_run = run_cli("evaluate --split-laps --json --unloaded " + kTrackerExamples +
                                "unloaded.csv --loaded " + kTrackerExamples + "loaded_uc.csv");
  ASSERT_EQ(base_run.exit_code, 0) << base_run.err;
  const auto tracker_run =
      run_cli("evaluate --split-laps --json --tracker-frame " + s.path("frame.yaml") + " --unloaded " + unloaded +
              " --loaded " + loaded + " --align-to " + kTrackerExamples + "unloaded.csv");
  ASSERT_EQ(tracker_run.exit_code, 0) << tracker_run.err;
  const auto b = nlohmann::json::parse(base_run.out), t = nlohmann::json::parse(tracker_run.out);
  EXPECT_NEAR(t["mean_deformation_mm"].get<double>(), b["mean_deformation_mm"].get<double>(), 0.005);
  // The unloaded example itself is the command here, so its run aligns exactly: offset = -clock.
  const auto& runs = t["alignment"]["runs"];
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_NEAR(runs[0]["offset_s"].get<double>(), -812.25, 0.02);  // one sample of the 50 Hz example is 0.02 s
  EXPECT_NEAR(runs[1]["offset_s"].get<double>(), -903.5, 0.02);
  EXPECT_GT(t["time_synchronous_mm"]["mean"].get<double>(), 0.3);  // the 625 N deflection, seen in time
  // The frame the figures were moved with, and how well it was registered.
  EXPECT_NEAR(t["registration"]["rms_mm"].get<double>(), rdoc["rms_mm"].get<double>(), 1e-6);
  EXPECT_EQ(t["registration"]["tracker_frame"], "AT960 Tracker");
  EXPECT_EQ(t["registration"]["rms_limit_mm"].get<double>(), 1.0);
}

// Calendar stamps (1.7e9 s) on a clock 50 ppm fast: offset_s and drift_ppm alone cannot rebuild the
// mapping (50 ppm of 1.7e9 s is 85000 s); with reference_t_s, the tracker time they refer to, the
// first and the last sample come back to the program's 0 s and end within a sample of the 50 Hz file.
TEST(CliTrackerSession, TheAlignmentGivesEverythingToRebuildTheTimeMapping) {
  TrackerSession s;
  Pose identity = Pose::Identity();
  s.base_T_tracker = identity;
  const double clock_s = 1.7e9, drift = 50e-6;
  const std::string run = s.export_run("unloaded.csv", clock_s, 3, drift);
  const auto r = run_cli("evaluate --json --fit-drift --unloaded " + run + " --loaded " + run + " --align-to " +
                         kTrackerExamples + "unloaded.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto a = nlohmann::json::parse(r.out)["alignment"]["runs"][0];
  const double offset = a["offset_s"].get<double>(), ppm = a["drift_ppm"].get<double>();
  const double reference = a["reference_t_s"].get<double>();
  const auto program_time = [&](double tracker_t) { return tracker_t + offset + ppm * 1e-6 * (tracker_t - reference); };
  // The example file's first and last stamps, as the exporter wrote them on the tracker's clock.
  std::ifstream in(kTrackerExamples + "unloaded.csv");
  std::string line, last;
  std::getline(in, line);
  while (std::getline(in, line)) last = line;
  const double t_end = std::stod(last.substr(0, last.find(',')));
  EXPECT_NEAR(program_time(clock_s), 0.0, 0.02);
  EXPECT_NEAR(program_time(clock_s + t_end * (1.0 + drift)), t_end, 0.02);
  EXPECT_NEAR(ppm, -50.0, 5.0);  // a tracker clock 50 ppm fast: program time runs 50 ppm slower
  EXPECT_GT(reference, clock_s);
  EXPECT_LT(reference, clock_s + t_end * (1.0 + drift));
  // In text the uncertainty has two significant digits, however small (not "+- 0.0000 s").
  const auto text =
      run_cli("evaluate --unloaded " + run + " --loaded " + run + " --align-to " + kTrackerExamples + "unloaded.csv");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  const auto at = text.out.find(" +- ");
  ASSERT_NE(at, std::string::npos) << text.out;
  const std::string digits = text.out.substr(at + 4, text.out.find(" s", at + 4) - at - 4);
  const auto first = digits.find_first_of("123456789");
  ASSERT_NE(first, std::string::npos) << text.out;
  EXPECT_EQ(digits.size() - first, 2u) << digits;
}

// SA on Windows exports in Windows-1252: a working frame "Caf\xE9 \xB0" (e-acute, the degree sign)
// registered and then evaluated with the tracker's own files. The frame file held U+FFFD and
// evaluate refused the files it came from; now both sides read the same UTF-8 name.
TEST(CliTrackerSession, AWindows1252FrameNameRegistersAndEvaluates) {
  TrackerSession s;
  const std::string session = kTrackerExamples + "session/";
  const auto cp1252 = [&](const std::string& name) {
    std::ifstream in(session + name, std::ios::binary);
    std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::string from = "AT960 Tracker";
    text.replace(text.find(from), from.size(), "Caf\xE9 \xB0");
    s.write(name, text);
    return s.path(name);
  };
  const auto reg = run_cli("register --tracker " + cp1252("tracker_points.txt") + " --base " + session +
                           "base_points.txt -o " + s.path("frame.yaml"));
  ASSERT_EQ(reg.exit_code, 0) << reg.err;
  std::ifstream frame(s.path("frame.yaml"));
  const std::string yaml{std::istreambuf_iterator<char>(frame), std::istreambuf_iterator<char>()};
  EXPECT_NE(yaml.find("tracker_frame: \"Caf\xC3\xA9 \xC2\xB0\""), std::string::npos) << yaml;
  const auto ev = run_cli("evaluate --json --tracker-frame " + s.path("frame.yaml") + " --unloaded " +
                          cp1252("unloaded.sa.txt") + " --loaded " + cp1252("loaded_uc.sa.txt"));
  ASSERT_EQ(ev.exit_code, 0) << ev.err;
  EXPECT_EQ(nlohmann::json::parse(ev.out)["registration"]["tracker_frame"], "Caf\xC3\xA9 \xC2\xB0");
}

TEST(CliTrackerSession, BadFilesExitTwoNamingFileAndLine) {
  TrackerSession s;
  s.write("nounit.txt", "// Working Frame: T\nP1 1 2 3\nP2 1 2 3\n");
  s.write("ok.txt", "// Working Frame: T\n// Units: mm\n// Columns: target x y z time\nP1 1 2 3 0\nP2 1 2 3 0\n");
  s.write("line.txt", "// Units: mm\nA 0 0 0\nB 1 1 1\nC 2 2 2\n");
  s.write("frame.yaml",
          "tracker_frame: \"Other\"\nbase_T_tracker:\n  position: [0, 0, 0]\n  quaternion_wxyz: [1, 0, 0, 0]\n");
  auto expect_refused = [](const test::CliRun& r, const std::string& text) {
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(text), std::string::npos) << r.err;
  };
  expect_refused(run_cli("evaluate --unloaded " + s.path("nounit.txt") + " --loaded " + s.path("nounit.txt")),
                 "nounit.txt: the header names no length unit");
  // Duplicate time stamps where a time-based metric is asked for.
  expect_refused(run_cli("evaluate --unloaded " + s.path("ok.txt") + " --loaded " + s.path("ok.txt") + " --align-to " +
                         kTrackerExamples + "unloaded.csv"),
                 "ok.txt:5: time stamp 0 s repeats line 4's");
  // A frame file for another tracker frame.
  expect_refused(run_cli("evaluate --unloaded " + s.path("ok.txt") + " --loaded " + s.path("ok.txt") +
                         " --tracker-frame " + s.path("frame.yaml")),
                 "ok.txt:1: the working frame is 'T', not the expected 'Other'");
  // Collinear registration points.
  expect_refused(run_cli("register --tracker " + s.path("line.txt") + " --base " + s.path("line.txt") + " -o " +
                         s.path("out.yaml")),
                 "line.txt: registration: the points lie on one line");
  EXPECT_FALSE(fs::exists(s.path("out.yaml")));
}

}  // namespace
}  // namespace deflex
