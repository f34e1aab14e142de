// The RDT force source against a test sensor on the in-memory network (rdt_test_sensor.hpp, written
// from the manuals and independent of deflex's RDT code), on a manual clock: every record handed on
// at 7 kHz read at 250 Hz, buffered datagrams, loss, duplicates, reorder, faulty records, a stall, a
// sensor that never answers, a stolen stream, a sensor restart, stop, a reader that fell behind,
// sequence wrap, the requests' bytes, and an allocation-free cycle.
#include "deflex/sensors/rdt_force_source.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "deflex/text/errors.hpp"
#include "deflex/transport/clock.hpp"
#include "deflex/transport/memory_network.hpp"
#include "sensors/rdt_test_sensor.hpp"
#include "support/allocation_guard.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using test::RdtTestSensor;

// 1,000,000 counts per N and 100,000 counts per Nm: the test sensor's default counts
// {1000000, -2000000, 3000000, 40000, -50000, 60000} are 1, -2, 3 N and 0.4, -0.5, 0.6 Nm.
RdtCalibration test_calibration(double rate_hz) { return test::test_rdt_calibration(rate_hz); }

struct Bench {
  explicit Bench(double rate_hz, RdtStreamSettings settings = {}, RdtCalibration calibration = {})
      : sensor(network, make_datagram_address("10.0.0.2", 49152), rate_hz),
        mine(network.add_endpoint(make_datagram_address("10.0.0.1", 5000))),
        source(mine, clock, sensor.address(),
               calibration.counts_per_force > 0 ? calibration : test_calibration(rate_hz), settings) {}

  // Runs `seconds` of cycles of `period_s`: the clock moves, the sensor sends what is due, the
  // source is drained as a compensator drains it (until it returns false).
  void run(double seconds, double period_s = 0.004, bool read = true) {
    const auto cycles = static_cast<long>(std::lround(seconds / period_s));
    for (long i = 0; i < cycles; ++i) {
      ++cycle;
      clock.set(static_cast<double>(cycle) * period_s);
      sensor.tick(clock.now_s());
      if (!read) continue;
      ForceSample s;
      while (source.latest(s)) got.push_back(s);
    }
  }

  ManualClock clock;
  long cycle = 0;
  MemoryNetwork network{clock, 2048, 8192};
  RdtTestSensor sensor;
  MemoryTransport& mine;
  RdtForceSource source;
  std::vector<ForceSample> got;
};

void expect_increasing_times(const std::vector<ForceSample>& got) {
  for (std::size_t i = 1; i < got.size(); ++i) {
    ASSERT_GT(got[i].t_s, got[i - 1].t_s) << "sample " << i;
  }
}

TEST(RdtForceSource, EveryRecordOfA7kHzStreamReadAt250HzIsHandedOnOnceInOrder) {
  Bench b(7000.0);
  ASSERT_TRUE(b.source.start());
  b.run(1.0);
  ASSERT_GT(b.sensor.sent_records, 6900u);
  EXPECT_EQ(b.got.size(), b.sensor.sent_records);  // none decimated, none left behind
  for (std::size_t i = 1; i < b.got.size(); ++i) {
    ASSERT_NEAR(b.got[i].t_s - b.got[i - 1].t_s, 1.0 / 7000.0, 1e-12) << i;
  }
  const ForceSample& s = b.got.back();
  EXPECT_TRUE(s.valid);
  EXPECT_DOUBLE_EQ(s.wrench_sensor(0), 1.0);
  EXPECT_DOUBLE_EQ(s.wrench_sensor(1), -2.0);
  EXPECT_DOUBLE_EQ(s.wrench_sensor(2), 3.0);
  EXPECT_DOUBLE_EQ(s.wrench_sensor(3), 0.4);
  EXPECT_DOUBLE_EQ(s.wrench_sensor(4), -0.5);
  EXPECT_DOUBLE_EQ(s.wrench_sensor(5), 0.6);
  const ForceSourceStats st = b.source.stats();
  EXPECT_EQ(st.received, b.got.size());
  EXPECT_EQ(st.accepted, b.got.size());
  EXPECT_EQ(st.lost + st.duplicates + st.out_of_order + st.malformed + st.faulty + st.restarts, 0u);
  EXPECT_EQ(b.source.state(), RdtStreamState::kStreaming);
  EXPECT_EQ(b.source.sample_rate_hz(), 7000.0);
}

TEST(RdtForceSource, BufferedDatagramsOfFortyRecordsAreUnpackedInOrder) {
  RdtStreamSettings settings;
  settings.buffered = true;
  Bench b(7000.0, settings);
  b.sensor.buffer = 40;
  b.source.start();
  b.run(1.0);
  ASSERT_GT(b.sensor.datagrams, 170u);
  EXPECT_EQ(b.got.size(), 40 * b.sensor.datagrams);
  expect_increasing_times(b.got);
  EXPECT_EQ(b.source.counters().datagrams, b.sensor.datagrams);
  EXPECT_EQ(b.source.stats().lost, 0u);
  ASSERT_FALSE(b.sensor.requests.empty());
  EXPECT_EQ(b.sensor.requests[0].bytes, (std::array<unsigned char, 8>{0x12, 0x34, 0x00, 0x03, 0, 0, 0, 0}));
}

TEST(RdtForceSource, LossDuplicatesAndReorderAreCountedAndNeverHandedOnTwice) {
  Bench b(1000.0);
  b.sensor.drop = {10, 11};
  b.sensor.duplicate = {20};
  b.sensor.swap_with_next = {30};  // record 31 goes out before record 30
  b.source.start();
  b.run(0.2);
  const RdtCounters& c = b.source.counters();
  EXPECT_EQ(c.lost, 2u);  // 10 and 11; 30 came, late
  EXPECT_EQ(c.duplicates, 1u);
  EXPECT_EQ(c.out_of_order, 1u);
  EXPECT_EQ(b.got.size(), b.sensor.produced - 3);  // 10, 11 never sent; 30 too late to hand on
  expect_increasing_times(b.got);
  // Record 12 follows record 9 by three sample periods of the sensor's own clock.
  EXPECT_NEAR(b.got[10].t_s - b.got[9].t_s, 3e-3, 1e-12);
}

TEST(RdtForceSource, AStatusBitOrASaturatedAxisGivesAnInvalidSample) {
  Bench b(1000.0);
  b.sensor.flag = {5};
  b.sensor.saturate = {7};
  b.source.start();
  b.run(0.05);
  ASSERT_GT(b.got.size(), 8u);
  for (std::size_t i = 0; i < b.got.size(); ++i) {
    EXPECT_EQ(b.got[i].valid, i != 5 && i != 7) << i;
  }
  EXPECT_EQ(b.source.counters().faulty, 2u);
  EXPECT_EQ(b.source.counters().saturated, 1u);
  EXPECT_EQ(b.source.counters().last_status, 0x00010000u);
  EXPECT_EQ(b.source.stats().faulty, 2u);
}

TEST(RdtForceSource, AStalledStreamIsRequestedAgainWithBackOff) {
  Bench b(1000.0);
  b.source.start();
  b.run(0.2);
  b.sensor.quiet = true;  // the network goes quiet for 1 s: records and requests are lost
  const std::uint64_t before = b.sensor.produced;
  b.run(0.15);
  EXPECT_EQ(b.source.state(), RdtStreamState::kStalled);
  b.run(0.85);
  const std::uint64_t lost_in_stall = b.sensor.produced - before;
  b.sensor.quiet = false;
  b.run(0.3);
  // Stall seen 0.1 s after the last record; requests then after 0.1, 0.2, 0.4 s more (the next, 0.8 s
  // later, is not due before the records come back).
  EXPECT_EQ(b.source.counters().re_requests, 4u);
  EXPECT_EQ(b.source.state(), RdtStreamState::kStreaming);
  // The sensor kept its numbering (our requests were lost): the gap is loss.
  EXPECT_EQ(b.source.counters().lost, lost_in_stall);
  EXPECT_EQ(b.source.stats().restarts, 4u);
  expect_increasing_times(b.got);
}

TEST(RdtForceSource, ASensorThatNeverAnswersIsANamedStateWithBackOff) {
  ManualClock clock;
  MemoryNetwork network(clock);
  MemoryTransport& mine = network.add_endpoint(make_datagram_address("10.0.0.1", 5000));
  RdtForceSource source(mine, clock, make_datagram_address("10.0.0.2", 49152), test_calibration(1000.0));
  EXPECT_EQ(source.state(), RdtStreamState::kIdle);
  source.start();
  ForceSample s;
  for (int i = 1; i <= 1250; ++i) {  // 5 s in 4 ms cycles
    clock.set(0.004 * i);
    EXPECT_FALSE(source.latest(s));
    if (i == 200) {
      EXPECT_EQ(source.state(), RdtStreamState::kRequested);
    }
  }
  EXPECT_EQ(source.state(), RdtStreamState::kNoAnswer);
  // Requested again at 1 s (the answer timeout), then after 0.1, 0.2, 0.4, 0.8, 1.6 s; the next,
  // 2 s (the most) later, falls after 5 s.
  EXPECT_EQ(source.counters().re_requests, 6u);
  EXPECT_EQ(source.counters().requests, 7u);
  EXPECT_EQ(network.counters().dropped_no_route, 7u);
}

TEST(RdtForceSource, AStolenStreamIsTakenBackAndCounted) {
  Bench b(1000.0);
  MemoryTransport& thief = b.network.add_endpoint(make_datagram_address("10.0.0.3", 6000));
  b.source.start();
  b.run(0.2);
  const std::array<unsigned char, 8> start{0x12, 0x34, 0x00, 0x02, 0, 0, 0, 0};
  thief.send_to(start.data(), start.size(), b.sensor.address());
  b.run(0.3);
  std::array<unsigned char, 2048> buf{};
  DatagramAddress from;
  int stolen = 0;
  while (thief.receive(buf.data(), buf.size(), from) >= 0) ++stolen;
  EXPECT_GT(stolen, 50);                               // the sensor answered the last requester
  EXPECT_EQ(b.sensor.target, b.mine.local_address());  // and we asked it back
  EXPECT_EQ(b.source.counters().re_requests, 1u);
  EXPECT_EQ(b.source.counters().sequence_restarts, 0u);  // the restart at 1 was our own request's
  // What the thief got, the sensor's counter tells: at least the 0.1 s before we asked again.
  EXPECT_GE(b.source.counters().unseen, 100u);
  EXPECT_LE(b.source.counters().unseen, static_cast<std::uint64_t>(stolen) + 8);
  EXPECT_EQ(b.source.state(), RdtStreamState::kStreaming);
  expect_increasing_times(b.got);
}

TEST(RdtForceSource, AStreamRequestedAgainEarlyLosesNoRecord) {
  Bench b(1000.0);
  b.source.start();
  b.run(0.012);  // a few records, numbers still small
  ASSERT_GT(b.got.size(), 3u);
  b.sensor.streaming = false;  // the stream stops without a word
  b.run(0.5);
  EXPECT_EQ(b.source.counters().re_requests, 1u);
  EXPECT_EQ(b.got.size(), b.sensor.sent_records);  // the new stream's 1, 2, 3 are not "late"
  EXPECT_EQ(b.source.counters().out_of_order + b.source.counters().far_ahead, 0u);
  EXPECT_EQ(b.source.counters().sequence_restarts, 0u);
  EXPECT_GT(b.source.counters().unseen, 90u);  // the 0.1 s of silence, by the sensor's counter
}

TEST(RdtForceSource, ASequenceThatRestartsWithoutOurRequestIsCounted) {
  Bench b(1000.0);
  b.source.start();
  b.run(0.2);
  b.sensor.renumber();
  b.run(0.2);
  EXPECT_EQ(b.source.counters().sequence_restarts, 1u);
  EXPECT_EQ(b.got.size(), b.sensor.sent_records);
  EXPECT_EQ(b.source.stats().restarts, 1u);
}

TEST(RdtForceSource, ASensorThatRestartsIsFollowedAndItsTimeKeepsIncreasing) {
  Bench b(1000.0);
  b.sensor.ft_start = 5000000;  // powered up long ago
  b.source.start();
  b.run(0.3);
  b.sensor.quiet = true;  // off for 2 s
  b.run(2.0);
  b.sensor.quiet = false;
  b.sensor.power_cycle(b.clock.now_s());  // back, counting from 0, not streaming until asked
  b.run(3.0);
  EXPECT_EQ(b.source.state(), RdtStreamState::kStreaming);
  EXPECT_EQ(b.source.counters().ft_restarts, 1u);
  EXPECT_GT(b.got.size(), 1500u);
  expect_increasing_times(b.got);
}

TEST(RdtForceSource, StopEndsTheStreamAndIsNotRequestedAgain) {
  Bench b(1000.0);
  b.source.start();
  b.run(0.1);
  ASSERT_TRUE(b.source.stop());
  b.run(0.01);
  const std::size_t n = b.got.size();
  b.run(2.0);
  EXPECT_EQ(b.got.size(), n);
  EXPECT_FALSE(b.sensor.streaming);
  EXPECT_EQ(b.sensor.requests.back().bytes, (std::array<unsigned char, 8>{0x12, 0x34, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(b.source.state(), RdtStreamState::kIdle);
  EXPECT_EQ(b.source.counters().re_requests, 0u);
}

TEST(RdtForceSource, AReaderThatFellBehindGetsTheNewestRecordsAndCountsTheRest) {
  RdtStreamSettings settings;
  settings.buffered = true;
  settings.queue_s = 0.25;
  Bench b(7000.0, settings);
  b.sensor.buffer = 40;
  b.source.start();
  b.run(1.0, 0.004, false);  // nobody reads for a second
  ForceSample s;
  std::vector<ForceSample> got;
  while (b.source.latest(s)) got.push_back(s);
  EXPECT_EQ(got.size(), 1750u);  // 0.25 s at 7 kHz: what the queue keeps
  EXPECT_EQ(b.source.counters().dropped_behind, 40 * b.sensor.datagrams - 1750);
  EXPECT_EQ(b.source.counters().lost, 0u);  // dropped by us, not lost on the wire
  expect_increasing_times(got);
}

TEST(RdtForceSource, BothSequencesWrapAt2To32) {
  Bench b(1000.0);
  b.sensor.rdt_start = 0xFFFFFFF0u;
  b.sensor.ft_start = 0xFFFFFF00u;
  b.source.start();
  b.run(0.5);
  ASSERT_GT(b.got.size(), 450u);
  for (std::size_t i = 1; i < b.got.size(); ++i) {
    ASSERT_NEAR(b.got[i].t_s - b.got[i - 1].t_s, 1e-3, 1e-12) << i;
  }
  const ForceSourceStats st = b.source.stats();
  EXPECT_EQ(st.lost + st.duplicates + st.out_of_order + st.restarts, 0u);
}

TEST(RdtForceSource, TimeFollowsTheSensorsInternalCounterAtAnyStep) {
  Bench b(1000.0);
  b.sensor.ft_step = 7;  // a 7 kHz sensor streaming every 7th sample
  b.source.start();
  b.run(0.2);
  ASSERT_GT(b.got.size(), 100u);
  for (std::size_t i = 1; i < b.got.size(); ++i) {
    ASSERT_NEAR(b.got[i].t_s - b.got[i - 1].t_s, 1e-3, 1e-12) << i;
  }
}

TEST(RdtForceSource, MalformedAndForeignDatagramsAreCountedAndIgnored) {
  Bench b(1000.0);
  MemoryTransport& same_host = b.network.add_endpoint(make_datagram_address("10.0.0.2", 7777));
  MemoryTransport& stranger = b.network.add_endpoint(make_datagram_address("10.0.0.9", 49152));
  b.source.start();
  b.run(0.05);
  const std::vector<unsigned char> dfxf(64, 0x44), short_record(35, 0), long_record(37, 0), forty_one(41 * 36, 0),
      record(36, 0);
  for (const auto* d : {&dfxf, &short_record, &long_record, &forty_one}) {
    same_host.send_to(d->data(), d->size(), b.mine.local_address());
  }
  stranger.send_to(record.data(), record.size(), b.mine.local_address());
  const std::size_t n = b.got.size();
  const std::uint64_t sent = b.sensor.sent_records;
  b.run(0.05);
  EXPECT_EQ(b.source.counters().malformed, 4u);
  EXPECT_EQ(b.source.counters().foreign, 1u);
  EXPECT_EQ(b.source.stats().malformed, 4u);
  EXPECT_EQ(b.got.size() - n, b.sensor.sent_records - sent);  // the stream went on untouched
  EXPECT_EQ(b.source.stats().lost, 0u);
}

// Starts the stream, asks for the sensor's bias, and returns what the sensor received.
std::vector<std::array<unsigned char, 8>> start_and_bias(Bench& b) {
  b.source.start();
  b.source.request_sensor_bias();
  b.run(0.004);
  std::vector<std::array<unsigned char, 8>> out;
  for (const auto& r : b.sensor.requests) out.push_back(r.bytes);
  return out;
}

using Bytes = std::vector<std::array<unsigned char, 8>>;

TEST(RdtForceSource, RequestsAndBiasAreTheManualsBytes) {
  Bench ati(1000.0);
  EXPECT_EQ(start_and_bias(ati), (Bytes{{0x12, 0x34, 0x00, 0x02, 0, 0, 0, 0}, {0x12, 0x34, 0x00, 0x42, 0, 0, 0, 0}}));

  // OnRobot's Compute Box: the rate first (1000 / 2 = 500 Hz), then the stream; bias "on" is 0xFF.
  Bench hex(500.0, {}, onrobot_hex_calibration(500.0));
  EXPECT_EQ(start_and_bias(hex), (Bytes{{0x12, 0x34, 0x00, 0x82, 0, 0, 0, 2},
                                        {0x12, 0x34, 0x00, 0x02, 0, 0, 0, 0},
                                        {0x12, 0x34, 0x00, 0x42, 0, 0, 0, 0xFF}}));
  hex.run(0.1);
  ASSERT_FALSE(hex.got.empty());
  EXPECT_DOUBLE_EQ(hex.got.back().wrench_sensor(0), 100.0);  // 1000000 counts / 10000
  EXPECT_DOUBLE_EQ(hex.got.back().wrench_sensor(3), 0.4);    // 40000 counts / 100000
}

TEST(RdtForceSource, NoCalibrationNoSource) {
  ManualClock clock;
  MemoryNetwork network(clock);
  MemoryTransport& mine = network.add_endpoint(make_datagram_address("10.0.0.1", 5000));
  const std::string e = test::error_of(
      [&] { RdtForceSource s(mine, clock, make_datagram_address("10.0.0.2", 49152), RdtCalibration{}); });
  EXPECT_NE(e.find("counts per force (cfgcpf)"), std::string::npos) << e;
  RdtStreamSettings bad;
  bad.retry_max_s = 0.01;  // below retry_min_s
  const std::string s = test::error_of(
      [&] { RdtForceSource x(mine, clock, make_datagram_address("10.0.0.2", 49152), test_calibration(1000.0), bad); });
  EXPECT_NE(s.find("retry_max_s"), std::string::npos) << s;
}

TEST(RdtForceSource, ParsesTheEndpointOfAnRdtForceSource) {
  EXPECT_EQ(parse_rdt_endpoint("192.168.1.1"), make_datagram_address("192.168.1.1", 49152));
  EXPECT_EQ(parse_rdt_endpoint("127.0.0.1:50000"), make_datagram_address("127.0.0.1", 50000));
  EXPECT_NE(test::error_of([] { (void)parse_rdt_endpoint("127.0.0.1:0"); }).find("port must be 1..65535"),
            std::string::npos);
  EXPECT_NE(test::error_of([] { (void)parse_rdt_endpoint(":49152"); }).find("IPv4 address"), std::string::npos);
  EXPECT_NE(test::error_of([] { (void)parse_rdt_endpoint("sensor.local"); }), "no error");
}

TEST(RdtForceSource, TheCycleNeverAllocatesThroughLossStallAndRestart) {
  RdtStreamSettings settings;
  settings.buffered = true;
  Bench b(7000.0, settings);
  b.sensor.buffer = 20;
  b.sensor.drop = {100, 101, 500};
  b.sensor.duplicate = {900};
  b.sensor.swap_with_next = {1500};
  b.sensor.flag = {2000};
  b.source.start();
  std::size_t allocations = 0;
  std::size_t handed = 0;
  for (int i = 1; i <= 500; ++i) {  // 2 s in 4 ms cycles
    b.clock.set(0.004 * i);
    b.sensor.quiet = i > 200 && i < 300;  // a stall with re-requests in the middle
    b.sensor.tick(b.clock.now_s());       // the sensor allocates; it is not on our cycle
    test::AllocationGuard guard;
    ForceSample s;
    while (b.source.latest(s)) ++handed;
    (void)b.source.stats();
    allocations += guard.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(handed, 10000u);
  EXPECT_GE(b.source.counters().re_requests, 1u);
}

}  // namespace
}  // namespace deflex
