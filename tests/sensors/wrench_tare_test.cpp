// The software tare: mean and standard deviation over the window against values worked out by hand,
// refusal on motion and on faulty samples, the payload's weight at the tare pose, and the tare inside
// the RDT source (nothing handed on while it collects or after it was refused).
#include "deflex/sensors/wrench_tare.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "deflex/sensors/rdt_force_source.hpp"
#include "deflex/transport/clock.hpp"
#include "deflex/transport/memory_network.hpp"
#include "sensors/rdt_test_sensor.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

ForceSample sample(double fx, double fz, double tx = 0.0, bool valid = true) {
  ForceSample s;
  s.wrench_sensor << fx, 0.0, fz, tx, 0.0, 0.0;
  s.valid = valid;
  return s;
}

TEST(WrenchTare, TheOffsetIsTheWindowsMeanLessTheExpectedWrench) {
  TareSettings settings;
  settings.window_s = 0.01;  // 10 samples at 1 kHz
  settings.expected_wrench_sensor << 0.0, 0.0, -19.62, 0.0, 0.0, 0.0;
  WrenchTare tare;
  tare.start(settings, 1000.0);
  // Fz alternates -20.1 and -19.9: mean -20, sample standard deviation 0.1 sqrt(10/9).
  for (int i = 0; i < 9; ++i) {
    EXPECT_EQ(tare.add(sample(2.0, i % 2 == 0 ? -20.1 : -19.9)), TareState::kCollecting);
  }
  EXPECT_EQ(tare.add(sample(2.0, -19.9)), TareState::kDone);
  const TareResult& r = tare.result();
  EXPECT_EQ(r.samples, 10);
  EXPECT_NEAR(r.mean_sensor(2), -20.0, 1e-12);
  EXPECT_NEAR(r.std_sensor(2), 0.1 * std::sqrt(10.0 / 9.0), 1e-12);
  EXPECT_NEAR(r.std_sensor(0), 0.0, 1e-12);
  EXPECT_NEAR(r.offset_sensor(0), 2.0, 1e-12);
  EXPECT_NEAR(r.offset_sensor(2), -20.0 + 19.62, 1e-12);
  // Applied: at the tare pose the reading becomes the expected weight, which gravity compensation removes.
  const Vector6 w = tare.apply(sample(2.0, -20.0).wrench_sensor);
  EXPECT_NEAR(w(2), -19.62, 1e-12);
  EXPECT_NEAR(w(0), 0.0, 1e-12);
  EXPECT_NE(describe(r, settings).find("tare done: 10 samples"), std::string::npos);
}

TEST(WrenchTare, AReadingThatMovesDuringTheWindowIsRefused) {
  TareSettings settings;
  settings.window_s = 0.1;
  WrenchTare tare;
  tare.start(settings, 1000.0);
  for (int i = 0; i < 100; ++i) {
    tare.add(sample(0.05 * i, 0.0));  // 0 to 5 N: the arm is being pushed
  }
  EXPECT_EQ(tare.result().state, TareState::kRejected);
  EXPECT_NEAR(tare.result().std_sensor(0), 0.05 * std::sqrt(100.0 * 101.0 / 12.0), 1e-9);  // of 0..99 steps
  EXPECT_NE(describe(tare.result(), settings).find("moved during the 0.1 s window"), std::string::npos);
  // Refused: samples pass unchanged through apply(), and the source hands nothing on (below).
  EXPECT_DOUBLE_EQ(tare.apply(sample(3.0, 0.0).wrench_sensor)(0), 3.0);
}

TEST(WrenchTare, ATorqueAxisThatMovesIsRefusedToo) {
  TareSettings settings;
  settings.window_s = 0.004;
  WrenchTare tare;
  tare.start(settings, 1000.0);
  for (double tx : {0.0, 0.2, 0.0, 0.2}) tare.add(sample(0.0, 0.0, tx));
  EXPECT_EQ(tare.result().state, TareState::kRejected);  // std 0.115 Nm > 0.05 Nm
}

TEST(WrenchTare, AFaultySampleInTheWindowRefusesIt) {
  TareSettings settings;
  settings.window_s = 0.005;
  WrenchTare tare;
  tare.start(settings, 1000.0);
  for (int i = 0; i < 5; ++i) tare.add(sample(1.0, 1.0, 0.0, i != 2));
  EXPECT_EQ(tare.result().state, TareState::kRejected);
  EXPECT_EQ(tare.result().faulty, 1);
  EXPECT_NE(describe(tare.result(), settings).find("1 of the 5 samples in the window were faulty"), std::string::npos);
}

TEST(WrenchTare, BadSettingsAreNamed) {
  WrenchTare tare;
  TareSettings s;
  s.window_s = 0.0;
  EXPECT_NE(test::error_of([&] { tare.start(s, 1000.0); }).find("the window (s)"), std::string::npos);
  s = {};
  s.max_std_force_n = -1.0;
  EXPECT_NE(test::error_of([&] { tare.start(s, 1000.0); }).find("force standard deviation"), std::string::npos);
  s = {};
  EXPECT_NE(test::error_of([&] { tare.start(s, 0.0); }).find("sample rate"), std::string::npos);
}

TEST(WrenchTare, ThePayloadsWeightAsTheSensorReadsIt) {
  // 2 kg, centre of gravity 0.1 m along the sensor's z; the sensor turned +90 deg about base x, so its
  // y axis points down: the weight reads -19.62 N on y and its moment about the sensor origin is
  // c x f = (0, 0, 0.1) x (0, -19.62, 0) = (1.962, 0, 0) Nm.
  Matrix3 base_R_sensor;
  base_R_sensor << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  const Vector6 w = payload_wrench_sensor(2.0, Vector3(0, 0, 0.1), Vector3(0, 0, -9.81), base_R_sensor);
  EXPECT_NEAR(w(0), 0.0, 1e-12);
  EXPECT_NEAR(w(1), -19.62, 1e-12);
  EXPECT_NEAR(w(2), 0.0, 1e-12);
  EXPECT_NEAR(w(3), 1.962, 1e-12);
  EXPECT_NEAR(w(4), 0.0, 1e-12);
  EXPECT_NEAR(w(5), 0.0, 1e-12);
}

RdtCalibration micro_newton_calibration() { return test::test_rdt_calibration(1000.0, 1000000.0, 1000000.0); }

TEST(WrenchTare, InsideTheSourceNothingIsHandedOnUntilTheTareIsDone) {
  ManualClock clock;
  MemoryNetwork network(clock, 2048, 4096);
  test::RdtTestSensor sensor(network, make_datagram_address("10.0.0.2", 49152), 1000.0);
  // 5 N offset on Fz with +-0.1 N of alternating noise.
  sensor.counts_of = [](std::uint64_t i) {
    return std::array<std::int32_t, 6>{0, 0, i % 2 == 0 ? 5100000 : 4900000, 0, 0, 0};
  };
  MemoryTransport& mine = network.add_endpoint(make_datagram_address("10.0.0.1", 5000));
  RdtForceSource source(mine, clock, sensor.address(), micro_newton_calibration());
  source.start();
  TareSettings settings;
  settings.window_s = 0.2;
  source.start_tare(settings);
  std::vector<ForceSample> got;
  ForceSample s;
  for (int i = 1; i <= 150; ++i) {  // 0.6 s
    clock.set(0.004 * i);
    sensor.tick(clock.now_s());
    while (source.latest(s)) got.push_back(s);
    if (source.tare_result().state == TareState::kCollecting) {
      EXPECT_TRUE(got.empty());
    }
  }
  ASSERT_EQ(source.tare_result().state, TareState::kDone);
  EXPECT_NEAR(source.tare_result().offset_sensor(2), 5.0, 1e-9);
  EXPECT_EQ(source.counters().held_by_tare, 200u);
  ASSERT_GT(got.size(), 350u);
  for (const ForceSample& x : got) {
    ASSERT_NEAR(std::abs(x.wrench_sensor(2)), 0.1, 1e-9);  // the offset gone, the noise left
  }
}

TEST(WrenchTare, InsideTheSourceARefusedTareHandsNothingOn) {
  ManualClock clock;
  MemoryNetwork network(clock, 2048, 4096);
  test::RdtTestSensor sensor(network, make_datagram_address("10.0.0.2", 49152), 1000.0);
  sensor.counts_of = [](std::uint64_t i) {  // a 10 N/s ramp: the arm is moving
    return std::array<std::int32_t, 6>{static_cast<std::int32_t>(10000 * i), 0, 0, 0, 0, 0};
  };
  MemoryTransport& mine = network.add_endpoint(make_datagram_address("10.0.0.1", 5000));
  RdtForceSource source(mine, clock, sensor.address(), micro_newton_calibration());
  source.start();
  source.start_tare({});
  ForceSample s;
  int handed = 0;
  for (int i = 1; i <= 250; ++i) {
    clock.set(0.004 * i);
    sensor.tick(clock.now_s());
    while (source.latest(s)) ++handed;
  }
  EXPECT_EQ(source.tare_result().state, TareState::kRejected);
  EXPECT_EQ(handed, 0);
  EXPECT_EQ(source.counters().held_by_tare, source.counters().records);
  source.clear_tare();  // the caller's decision: go on without a tare
  for (int i = 251; i <= 260; ++i) {
    clock.set(0.004 * i);
    sensor.tick(clock.now_s());
    while (source.latest(s)) ++handed;
  }
  EXPECT_GT(handed, 30);
}

}  // namespace
}  // namespace deflex
