// The RDT force source over real UDP on loopback against the Python stand-in sensor
// (examples/online/rdt_sensor_standin.py): the calibration fetched from its HTTP page in non-SI
// units, every record with the stand-in's scheduled loss, duplicates, reorder, saturation and status
// bits counted exactly as the stand-in reports them, buffered mode, a stall, a stolen stream, a
// restart, the sensor's own bias beside deflex's tare, and a sensor that never answers. Pass or fail
// never depends on timing: the counts are compared with the stand-in's own, and where real time
// decides how often something happens (re-requests) only "at least once" is asserted.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "cross/cli_child.hpp"
#include "deflex/sensors/rdt_force_source.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/wire/rdt.hpp"
#include "sensors/rdt_test_sensor.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using test::Child;

const std::string kStandin = std::string(DEFLEX_SOURCE_DIR) + "/examples/online/rdt_sensor_standin.py";

struct Standin {
  Child child;
  int rdt_port = -1;
  int http_port = -1;

  explicit Standin(std::vector<std::string> args) {
    std::vector<std::string> argv{"/usr/bin/env", "python3", kStandin, "--port", "0", "--http-port", "0"};
    argv.insert(argv.end(), args.begin(), args.end());
    const std::string log = ::testing::TempDir() + "/rdt_standin_" + std::to_string(::getpid()) + "_" +
                            ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".err";
    test::spawn(child, argv, log);
    rdt_port = test::port_of(child, "RDT on 127.0.0.1:");
    http_port = test::port_of(child, "HTTP on 127.0.0.1:");
  }
  /// Stops it (SIGINT) and returns the summary it printed.
  nlohmann::json summary() {
    child.stop();
    const std::string text = test::slurp(child.stderr_path);
    const auto at = text.find("summary: ");
    if (at == std::string::npos) return nlohmann::json::object();
    return nlohmann::json::parse(text.substr(at + 9, text.find('\n', at) - at - 9));
  }
  [[nodiscard]] DatagramAddress address() const {
    return make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(rdt_port));
  }
  [[nodiscard]] std::string page() const { return "http://127.0.0.1:" + std::to_string(http_port) + "/netftapi2.xml"; }
};

/// A source on the stand-in, its calibration fetched from the stand-in's page, started.
std::unique_ptr<RdtUdpForceSource> connect(const Standin& sensor, const RdtStreamSettings& settings = {}) {
  RdtSourceOptions options;
  options.endpoint = "127.0.0.1:" + std::to_string(sensor.rdt_port);
  options.calibration.spec = sensor.page();
  options.stream = settings;
  options.bind_address = "127.0.0.1";
  return open_rdt_force_source(options);
}

/// Reads until `done` or `limit_s` of wall time, into `got`.
template <class Done>
void read_until(RdtUdpForceSource& source, std::vector<ForceSample>& got, double limit_s, Done done) {
  const auto start = std::chrono::steady_clock::now();
  ForceSample s;
  while (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < limit_s && !done()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    while (source.latest(s)) got.push_back(s);
  }
}

TEST(RdtStandin, CalibrationFromItsPageAndEveryFaultCountedAsItReports) {
  Standin sensor({"--rate",          "1000",   "--force-unit",        "lbf",  "--counts-per-force", "100",
                  "--torque-unit",   "lbf-in", "--counts-per-torque", "1000", "--wrench",           "10,0,-20,5,0,0",
                  "--max-records",   "2000",   "--drop-every",        "50",   "--duplicate-every",  "70",
                  "--reorder-every", "97",     "--saturate-every",    "101",  "--status-every",     "103"});
  ASSERT_GT(sensor.rdt_port, 0);
  RdtCalibrationOptions options;
  options.spec = sensor.page();
  const RdtCalibration cal = resolve_rdt_calibration(options, "127.0.0.1");
  EXPECT_EQ(cal.force_unit, "lbf");
  EXPECT_EQ(cal.rate_hz, 1000.0);
  RdtStreamSettings settings;
  settings.stall_timeout_s = 1.0;  // a slow machine's hiccup is not a stall here
  RdtUdpForceSource source(sensor.address(), cal, settings, "127.0.0.1");
  source.start();
  std::vector<ForceSample> got;
  std::uint64_t last = 0;
  int quiet = 0;
  // Until the stand-in has sent its 2000 records and gone silent.
  read_until(source, got, 20.0, [&] {
    const std::uint64_t now = source.source().counters().records;
    quiet = now == last ? quiet + 1 : 0;
    last = now;
    return now >= 2000 && quiet > 100;
  });
  const nlohmann::json s = sensor.summary();
  ASSERT_EQ(s.value("sent", 0), 2000) << s.dump();
  const RdtCounters& c = source.source().counters();
  EXPECT_EQ(c.records, 2000u + s.value("duplicated", 0u));
  EXPECT_EQ(c.lost, s.value("dropped", 0u));
  EXPECT_EQ(c.duplicates, s.value("duplicated", 0u));
  EXPECT_EQ(c.out_of_order, s.value("reordered", 0u));
  EXPECT_EQ(c.faulty, s.value("saturated", 0u) + s.value("flagged", 0u));
  EXPECT_EQ(c.saturated, s.value("saturated", 0u));
  EXPECT_EQ(got.size(), 2000u - s.value("reordered", 0u));
  EXPECT_GT(s.value("dropped", 0), 30);
  EXPECT_GT(s.value("duplicated", 0), 20);
  EXPECT_GT(s.value("reordered", 0), 15);
  // 10 lbf, -20 lbf, 5 lbf-in in SI (1 lbf = 4.4482216152605 N, 1 lbf-in = 0.1129848290276167 Nm).
  const ForceSample& v = got.front().valid ? got.front() : got[1];
  EXPECT_NEAR(v.wrench_sensor(0), 44.482216152605, 1e-9);
  EXPECT_NEAR(v.wrench_sensor(2), -88.96443230521, 1e-9);
  EXPECT_NEAR(v.wrench_sensor(3), 0.5649241451380835, 1e-12);
  for (std::size_t i = 1; i < got.size(); ++i) ASSERT_GT(got[i].t_s, got[i - 1].t_s);
}

TEST(RdtStandin, BufferedStreamingOfFortyRecordsADatagramAt7kHz) {
  Standin sensor({"--rate", "7000", "--buffer", "40", "--max-records", "7000"});
  RdtStreamSettings settings;
  settings.buffered = true;
  settings.stall_timeout_s = 1.0;
  auto connected = connect(sensor, settings);
  RdtUdpForceSource& source = *connected;
  std::vector<ForceSample> got;
  read_until(source, got, 20.0, [&] { return got.size() >= 7000; });
  ASSERT_EQ(got.size(), 7000u);
  EXPECT_EQ(source.source().counters().datagrams, 7000u / 40u);
  EXPECT_EQ(source.stats().lost, 0u);
  for (std::size_t i = 1; i < got.size(); ++i) ASSERT_NEAR(got[i].t_s - got[i - 1].t_s, 1.0 / 7000.0, 1e-12);
  EXPECT_NEAR(got.back().wrench_sensor(2), -50.0, 1e-12);
  (void)sensor.summary();
}

TEST(RdtStandin, AStallAndAStolenStreamAreRecoveredFrom) {
  Standin sensor({"--rate", "1000", "--stall-at", "0.8", "--stall-s", "0.6"});
  auto connected = connect(sensor);
  RdtUdpForceSource& source = *connected;
  std::vector<ForceSample> got;
  // Through the stall (the stand-in's 0.8 s to 1.4 s) and back.
  read_until(source, got, 10.0, [&] {
    return source.source().counters().re_requests > 0 && source.source().state() == RdtStreamState::kStreaming &&
           got.size() > 2000;
  });
  EXPECT_GE(source.source().counters().re_requests, 1u);
  ASSERT_EQ(source.source().state(), RdtStreamState::kStreaming);

  // Another program asks for the stream: the sensor answers it, we see silence and ask again.
  const int thief = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(sensor.rdt_port));
  to.sin_addr.s_addr = htonl(0x7F000001);
  const unsigned char start[8] = {0x12, 0x34, 0x00, 0x02, 0, 0, 0, 0};
  ::sendto(thief, start, sizeof start, 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  const std::uint64_t before = source.source().counters().re_requests;
  const std::size_t had = got.size();
  read_until(source, got, 10.0, [&] {
    return source.source().counters().re_requests > before && source.source().state() == RdtStreamState::kStreaming &&
           got.size() > had + 500;
  });
  unsigned char buf[64];
  const long stolen = ::recv(thief, buf, sizeof buf, MSG_DONTWAIT);
  ::close(thief);
  EXPECT_EQ(stolen, 36);  // the thief got the stream for a while
  EXPECT_GT(source.source().counters().re_requests, before);
  EXPECT_EQ(source.source().state(), RdtStreamState::kStreaming);
  for (std::size_t i = 1; i < got.size(); ++i) ASSERT_GT(got[i].t_s, got[i - 1].t_s);
  const nlohmann::json s = sensor.summary();
  EXPECT_GE(s.value("clients", 0), 2);
  EXPECT_GT(s.value("stall_lost", 0), 0);
}

TEST(RdtStandin, ARestartedSensorIsRequestedAgainAndItsCounterRestartIsCounted) {
  Standin sensor({"--rate", "1000", "--ft-start", "0x10000000", "--restart-at", "0.5", "--restart-s", "0.5"});
  auto connected = connect(sensor);
  RdtUdpForceSource& source = *connected;
  std::vector<ForceSample> got;
  read_until(source, got, 15.0, [&] {
    return source.source().counters().ft_restarts > 0 && source.source().state() == RdtStreamState::kStreaming &&
           got.size() > 1000;
  });
  EXPECT_EQ(source.source().counters().ft_restarts, 1u);
  EXPECT_GE(source.source().counters().re_requests, 1u);
  for (std::size_t i = 1; i < got.size(); ++i) ASSERT_GT(got[i].t_s, got[i - 1].t_s);
  EXPECT_EQ(sensor.summary().value("restarts", 0), 1);
}

TEST(RdtStandin, TheSensorsOwnBiasAndDeflexsTareAreApart) {
  Standin sensor({"--rate", "1000", "--wrench", "3,-4,-50,0.5,0,0", "--noise", "0.05"});
  auto connected = connect(sensor);
  RdtUdpForceSource& source = *connected;
  // deflex's tare: the offset is taken out here; the sensor still reads the load.
  TareSettings tare;
  tare.window_s = 0.2;
  const TareResult& r = source.tare(tare);
  EXPECT_NEAR(r.offset_sensor(2), -50.0, 0.05);
  EXPECT_NEAR(r.offset_sensor(0), 3.0, 0.05);
  std::vector<ForceSample> got;
  read_until(source, got, 10.0, [&] { return got.size() > 100; });
  ASSERT_GT(got.size(), 100u);
  EXPECT_NEAR(got.back().wrench_sensor(2), 0.0, 0.5);
  // The sensor's own bias (0x0042) zeroes its reading for every client; deflex's tare, already taken,
  // now removes a load that is no longer in the reading: the two must not be stacked.
  source.source().request_sensor_bias();
  got.clear();
  read_until(source, got, 10.0, [&] { return got.size() > 300; });
  ASSERT_GT(got.size(), 300u);
  EXPECT_NEAR(got.back().wrench_sensor(2), 50.0, 0.5);
  EXPECT_EQ(sensor.summary().value("biases", 0), 1);
}

TEST(RdtStandin, ASensorThatNeverAnswersIsAClearErrorAtStart) {
  const RdtCalibration cal = test::test_rdt_calibration(1000.0);
  RdtStreamSettings settings;
  settings.answer_timeout_s = 0.3;
  // A port nobody listens on: the request goes out, nothing comes back.
  const int probe = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in any{};
  any.sin_family = AF_INET;
  any.sin_addr.s_addr = htonl(0x7F000001);
  ::bind(probe, reinterpret_cast<const sockaddr*>(&any), sizeof any);
  socklen_t len = sizeof any;
  ::getsockname(probe, reinterpret_cast<sockaddr*>(&any), &len);
  const auto port = ntohs(any.sin_port);
  RdtUdpForceSource source(make_datagram_address("127.0.0.1", port), cal, settings, "127.0.0.1");
  const std::string e = test::error_of([&] { source.start(); });
  ::close(probe);
  EXPECT_NE(e.find("rdt sensor 127.0.0.1:" + std::to_string(port) + ": no record within 0.3 s"), std::string::npos)
      << e;
  EXPECT_EQ(source.source().state(), RdtStreamState::kNoAnswer);
}

TEST(RdtStandin, AnRdtSourceWithoutACalibrationDoesNotStart) {
  RdtSourceOptions options;
  options.endpoint = "127.0.0.1";
  const std::string e = test::error_of([&] { (void)open_rdt_force_source(options); });
  EXPECT_NE(e.find("an rdt force source needs the sensor's calibration"), std::string::npos) << e;
  options.endpoint = "127.0.0.1:99999";
  EXPECT_NE(test::error_of([&] { (void)open_rdt_force_source(options); }).find("port must be 1..65535"),
            std::string::npos);
}

}  // namespace
}  // namespace deflex
