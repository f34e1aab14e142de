// The runtime session itself: its loop allocates nothing with every report on (the cycle log, the
// fault dump, a log sink: all on the reporter's side of a lock-free ring); options that cannot work
// are refused before anything runs, naming the option; the exit codes are the documented table
// (docs/online.md, "Faults and exit codes", read here from the file).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/poses.hpp"

#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/text/errors.hpp"
#include "links/link_harness.hpp"
#include "support/allocation_guard.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

using test::pose_deg;

TEST(Session, ThePollDoesNotAllocateWithTheLogTheDumpASinkAndTheMonitorOn) {
  const RobotModel robot = test::bench_robot();
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(robot, q0, pose_deg(8, -3, 4, 10, -5, 12), 10.0);
  ManualClock clock;
  MemoryNetwork network(clock);
  MemoryTransport& deflex_port = network.add_endpoint(test::kSensorAddress, 0.0002);
  MemoryTransport& controller_port = network.add_endpoint(test::kControllerAddress, 0.0002);
  const std::string dir = ::testing::TempDir() + "/session_alloc";
  fs::create_directories(dir);
  runtime::SessionConfig c;
  c.link = runtime::LinkKind::kEgmJoint;
  c.online = test::bench_online();
  c.log_path = dir + "/log.csv";
  c.fault_dump_path = dir + "/dump.csv";
  c.status_interval_s = 0.1;
  c.monitor = true;  // the live page's feed: filled by the reporter, never by the loop
  std::size_t lines = 0;
  test::ConstantForce force;
  force.reading = test::reading_at(robot, q0, Vector3(0, 0, -500));
  runtime::Session session(c, robot, test::bench_sensor(), program, nullptr, &force, clock, {&deflex_port},
                           [&lines](runtime::LogLevel, const std::string&) { ++lines; });
  cell::ControllerConfig cc;
  cell::EgmPositionGuidanceController controller(cc, q0, controller_port, test::kSensorAddress);
  double t = 0.0;
  const auto tick = [&](bool guarded) {
    t += 0.004;
    clock.set(t);
    controller.tick(t);
    clock.set(t + 0.0002);
    std::size_t allocations = 0;
    {
      std::optional<test::AllocationGuard> guard;
      if (guarded) guard.emplace();
      while (session.poll(0.0) != LinkPollResult::kIdle) {
      }
      if (guard) allocations = guard->allocations();
    }
    session.service();  // the reporter's work, outside the loop
    return allocations;
  };
  for (int k = 0; k < 300; ++k) tick(false);  // warm: every buffer at its size
  std::size_t allocations = 0;
  for (int k = 0; k < 500; ++k) allocations += tick(true);
  EXPECT_EQ(allocations, 0u);
  const runtime::SessionSummary& s = session.finish();
  EXPECT_EQ(s.exit_code, 0);
  EXPECT_EQ(s.log_dropped, 0u);
  EXPECT_GT(lines, 10u);  // status lines reached the sink
  std::ifstream log(c.log_path);
  std::size_t rows = 0;
  std::string header;
  std::vector<std::string> comments;
  for (std::string line; std::getline(log, line);) {
    if (line.rfind('#', 0) == 0) {
      comments.push_back(line);
    } else if (rows++ == 0) {
      header = line;
    }
  }
  EXPECT_EQ(rows, 1 + s.cycles);  // the header and every cycle
  // Every row carries the bounds, so deflex monitor --log draws them from the log alone; the first
  // line names the link, the cycle and the sensor, the last why the session ended.
  EXPECT_NE(header.find(",joint_bound_deg,tcp_bound_mm"), std::string::npos) << header;
  ASSERT_GE(comments.size(), 2u);
  EXPECT_EQ(comments[0], fmt::format("# deflex cycle log: link=egm-joint period_ms=4 force_components={} "
                                     "force_fault_N={:g}",
                                     test::bench_sensor().components, test::bench_sensor().fault_threshold_N));
  EXPECT_EQ(comments.back(), "# stop: " + s.reason_text);
  // Between them, the settings the session ran with, one a line, in the option's unit: every one that
  // applies to egm-joint, none of another link's.
  const std::vector<std::string> settings(comments.begin() + 1, comments.end() - 1);
  const auto has = [&settings](const std::string& line) {
    return std::find(settings.begin(), settings.end(), line) != settings.end();
  };
  EXPECT_TRUE(has("# setting: --period-ms=4"));
  EXPECT_TRUE(has(fmt::format("# setting: --max-joint-correction-deg={:.6g}",
                              c.online.max_joint_correction_rad * 180.0 / 3.14159265358979323846)));
  EXPECT_TRUE(has("# setting: --status-interval-s=0.1"));
  EXPECT_TRUE(has("# setting: --jacobian-at=nominal") || has("# setting: --jacobian-at=feedback"));
  for (const std::string& line : settings) {
    EXPECT_EQ(line.rfind("# setting: --", 0), 0u) << line;
    EXPECT_EQ(line.find("--rsi-"), std::string::npos) << line;
    EXPECT_EQ(line.find("--fanuc-"), std::string::npos) << line;
  }
  ASSERT_TRUE(session.monitor_feed());
  EXPECT_EQ(session.monitor_feed()->rows_added(), s.cycles);  // every cycle reached the page's feed
}

TEST(Session, OptionsThatCannotWorkAreRefusedNamingThem) {
  const RobotModel robot = test::bench_robot();
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::hold_program(robot, q0, 10.0);
  ManualClock clock;
  MemoryNetwork network(clock);
  MemoryTransport& port = network.add_endpoint(test::kSensorAddress, 0.0);
  const auto refuse = [&](runtime::SessionConfig c, std::shared_ptr<const JointTrajectory> p,
                          const std::string& fragment) {
    const std::string e = test::error_of(
        [&] { runtime::Session s(c, robot, test::bench_sensor(), p, nullptr, nullptr, clock, {&port}); });
    EXPECT_NE(e.find(fragment), std::string::npos) << e;
  };
  runtime::SessionConfig c;
  c.online = test::bench_online();
  c.online.period_s = 0.1;
  c.online.max_correction_rate_rad_s = 0.2;  // 0.02 rad a cycle, beyond the 0.01 rad bound
  refuse(c, program, "rate bound allows 1.146 deg a cycle");
  c.online = test::bench_online();
  c.online.max_tcp_rate_m_s = 5.0;  // 20 mm a cycle, beyond the 5 mm bound
  refuse(c, program, "TCP rate bound allows 20 mm a cycle");
  c.online = test::bench_online();
  refuse(c, nullptr, "option --program: egm-joint streams a nominal program");
  c.link = runtime::LinkKind::kRsi;
  refuse(c, program, "option --program: rsi corrects the controller's own program");
  c.link = runtime::LinkKind::kEgmJoint;
  c.stop_silence_s = -1.0;
  refuse(c, program, "stop silence must be > 0 s");
  c.stop_silence_s.reset();
  c.realtime.enabled = true;
  c.realtime.priority = 0;
  refuse(c, program, "option --rt-priority: SCHED_FIFO priorities are 1..99");
  c.realtime = {};
  c.log_path = "/dev/null/dir/log.csv";  // a missing folder would be made: one under a device cannot
  refuse(c, program, "option --log '/dev/null/dir/log.csv'");
}

TEST(Session, TheExitCodesAreTheDocumentedTable) {
  // docs/online.md: "| 6 | controller-stopped | ..." rows.
  std::ifstream doc(std::string(DEFLEX_SOURCE_DIR) + "/docs/online.md");
  const std::regex row(R"(^\| (\d) \| `([a-z-]+)`)");
  std::map<std::string, int> documented;
  for (std::string line; std::getline(doc, line);) {
    std::smatch m;
    if (std::regex_search(line, m, row)) documented[m[2]] = std::stoi(m[1]);
  }
  for (int r = 1; r <= 10; ++r) {
    const auto reason = static_cast<runtime::StopReason>(r);
    ASSERT_TRUE(documented.count(runtime::to_string(reason))) << runtime::to_string(reason) << " is not in the table";
    EXPECT_EQ(documented[runtime::to_string(reason)], runtime::exit_code(reason)) << runtime::to_string(reason);
  }
  // Only the planned ends exit 0.
  for (int r = 1; r <= 10; ++r) {
    const auto reason = static_cast<runtime::StopReason>(r);
    const bool planned = reason == runtime::StopReason::kProgramEnd || reason == runtime::StopReason::kUserStop ||
                         reason == runtime::StopReason::kDuration;
    EXPECT_EQ(runtime::exit_code(reason) == 0, planned) << runtime::to_string(reason);
  }
}

// A position-guidance session against the cell's EGM controller, stepped: the harness of the tests below.
struct SteppedEgm {
  RobotModel robot = test::bench_robot();
  JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  std::shared_ptr<const JointTrajectory> program = test::sweep_program(robot, q0, pose_deg(8, -3, 4, 10, -5, 12), 10.0);
  ManualClock clock;
  MemoryNetwork network{clock};
  MemoryTransport& deflex_port = network.add_endpoint(test::kSensorAddress, 0.0002);
  MemoryTransport& controller_port = network.add_endpoint(test::kControllerAddress, 0.0002);
  std::vector<std::string> lines;
  std::unique_ptr<runtime::Session> session;
  std::unique_ptr<cell::EgmPositionGuidanceController> controller;
  double t = 0.0;

  SteppedEgm(const runtime::SessionConfig& c, ForceSource& force) {
    session = std::make_unique<runtime::Session>(
        c, robot, test::bench_sensor(), program, nullptr, &force, clock, runtime::SessionEndpoints{&deflex_port},
        [this](runtime::LogLevel, const std::string& text) { lines.push_back(text); });
    controller = std::make_unique<cell::EgmPositionGuidanceController>(cell::ControllerConfig{}, q0, controller_port,
                                                                       test::kSensorAddress);
  }
  void run_for(double seconds) {
    for (const double end = t + seconds; t < end && !session->ended();) {
      t += 0.004;
      clock.set(t);
      controller->tick(t);
      clock.set(t + 0.0002);
      while (session->poll(0.0) != LinkPollResult::kIdle) {
      }
      session->service();
    }
  }
  [[nodiscard]] bool logged(const std::string& part) const {
    for (const std::string& l : lines) {
      if (l.find(part) != std::string::npos) return true;
    }
    return false;
  }
};

TEST(Session, ACycleLogThatCannotBeWrittenEndsTheSessionWithExit1NamingItAndTheSummary) {
  // /dev/full fails every write with ENOSPC, as a full disk does: before, the reporter's thread threw
  // and the process aborted (exit 134) mid-session with no summary.
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this machine";
  runtime::SessionConfig c;
  c.link = runtime::LinkKind::kEgmJoint;
  c.online = test::bench_online();
  c.log_path = "/dev/full";
  c.status_interval_s = 0.0;
  test::ConstantForce force;
  SteppedEgm b(c, force);
  force.reading = test::reading_at(b.robot, b.q0, Vector3(0, 0, -500));
  b.run_for(5.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, runtime::StopReason::kOutputFailed);
  EXPECT_EQ(s.exit_code, 1);
  EXPECT_NE(s.reason_text.find("/dev/full"), std::string::npos) << s.reason_text;
  EXPECT_NE(s.reason_text.find("standstill"), std::string::npos) << s.reason_text;  // ramped down, then ended
  EXPECT_NE(s.output_error.find("/dev/full"), std::string::npos) << s.output_error;
  EXPECT_EQ(s.text.rfind("deflex online: the egm-joint session ended: output-failed (exit code 1)", 0), 0u) << s.text;
  EXPECT_TRUE(b.logged("/dev/full"));
  EXPECT_GT(s.answers, 100u);  // it ran until the first failed write, and the loop kept answering
}

TEST(Session, AnOutputFailureReportedFromOutsideEndsTheSessionTheSameWay) {
  // The program around the session (the CLI's field log) reports its own file's failure.
  runtime::SessionConfig c;
  c.link = runtime::LinkKind::kEgmJoint;
  c.online = test::bench_online();
  c.status_interval_s = 0.0;
  test::ConstantForce force;
  SteppedEgm b(c, force);
  b.run_for(2.0);
  b.session->report_output_failure("the field log /var/log/cell.log could not be written (No space left on device)");
  b.session->report_output_failure("a second failure is not the reason");
  b.run_for(2.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.exit_code, 1);
  EXPECT_EQ(s.reason_text.rfind("the field log /var/log/cell.log could not be written", 0), 0u) << s.reason_text;
}

// A force source that reports what an RDT sensor reports: samples it flagged faulty, and a stream it had
// to request again.
class FlaggingForce final : public ForceSource {
 public:
  bool latest(ForceSample& out) noexcept override { return inner.latest(out); }
  [[nodiscard]] ForceSourceStats stats() const noexcept override { return s; }
  test::ConstantForce inner;
  ForceSourceStats s;
};

TEST(Session, SensorFaultsAndStreamReRequestsAreNamedInTheLogAndTheSummary) {
  runtime::SessionConfig c;
  c.link = runtime::LinkKind::kEgmJoint;
  c.online = test::bench_online();
  c.status_interval_s = 0.0;
  FlaggingForce force;
  SteppedEgm b(c, force);
  b.run_for(1.0);
  EXPECT_FALSE(b.logged("faulty"));
  force.s.faulty = 3;
  force.s.saturated = 1;
  force.s.last_status = 0x80010000u;
  b.run_for(0.5);
  force.s.re_requests = 2;
  force.s.restarts = 2;
  b.run_for(0.5);
  EXPECT_TRUE(
      b.logged("the force sensor flagged 3 samples faulty so far (1 at its range limits; last status word "
               "0x80010000)"));
  EXPECT_TRUE(b.logged("the force stream stopped or never came: requested again (2 re-requests so far"));
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_NE(s.text.find("3 flagged faulty by the sensor (1 at its range limits, last status word 0x80010000)"),
            std::string::npos)
      << s.text;
  EXPECT_NE(s.text.find("2 stream re-requests"), std::string::npos) << s.text;
  const nlohmann::json j = nlohmann::json::parse(s.json_text);
  EXPECT_EQ(j["force_source"]["re_requests"], 2);
  EXPECT_EQ(j["force_source"]["faulty"], 3);
}

}  // namespace
}  // namespace deflex
