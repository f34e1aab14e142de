// The simulated KUKA controller's RSI side against hand-written answers: it sends a <Rob> every cycle
// with an IPOC that grows by the cycle in ms; it takes only an answer of its SENTYPE, from the sensor,
// carrying the awaited IPOC, before the next cycle; everything else counts late, and at the Timeout
// count RSI, the program and the arm stop. AK values are whole offsets (the same answer a hundred
// times moves the axes once), clamped per axis, applied after the dead time on top of the program.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "deflex/cell/rsi_controller.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/transport/memory_network.hpp"

namespace deflex::cell {
namespace {

const DatagramAddress kSensor{0x7f000001, 49152};
const DatagramAddress kController{0x7f000002, 49153};
const DatagramAddress kStranger{0x7f000003, 49152};

JointVector start_deg() {
  JointVector q(6);
  q << 0, 20, 10, 0, 60, 0;
  return q;
}

std::string sen(std::uint64_t ipoc, double a1, const std::string& type = "ImFree") {
  return "<Sen Type=\"" + type + "\"><AK A1=\"" + std::to_string(a1) +
         "\" A2=\"0\" A3=\"0\" A4=\"0\" A5=\"0\" A6=\"-0.05\"/><IPOC>" + std::to_string(ipoc) + "</IPOC></Sen>";
}

struct Stand {
  ManualClock clock;
  MemoryNetwork network{clock};
  MemoryTransport& sensor = network.add_endpoint(kSensor, 0.0002);
  MemoryTransport& controller_port = network.add_endpoint(kController, 0.0002);
  MemoryTransport& stranger = network.add_endpoint(kStranger, 0.0002);
  RobotModel robot = builtin_irb6700();
  std::shared_ptr<const JointTrajectory> program;
  RsiControllerConfig config;
  std::unique_ptr<RsiController> controller;
  double t = 0.0;
  RsiRobotMessage last;
  unsigned char buf[4096];

  explicit Stand(RsiControllerConfig c = {}, const JointVector& move_deg = JointVector::Zero(6)) : config(c) {
    const JointVector q0 = start_deg() * (kPi / 180.0);
    program = std::make_shared<const JointTrajectory>(
        std::vector<double>{0.0, 10.0}, std::vector<JointVector>{q0, q0 + move_deg * (kPi / 180.0)}, robot, "program");
    controller = std::make_unique<RsiController>(config, robot, program, controller_port, kSensor);
  }
  /// One 4 ms tick; returns true when a <Rob> reached the sensor (decoded into `last`).
  bool tick() {
    clock.set(t);
    controller->tick(t);
    clock.set(t + 0.0003);
    t += 0.004;
    DatagramAddress from;
    bool got = false;
    for (long n; (n = sensor.receive(buf, sizeof(buf), from)) >= 0;) {
      EXPECT_EQ(decode_rsi_robot(buf, static_cast<std::size_t>(n), 6, last), RsiDecodeStatus::kOk);
      got = true;
    }
    return got;
  }
  void answer(const std::string& doc, MemoryTransport* via = nullptr) {
    ASSERT_TRUE((via != nullptr ? *via : sensor)
                    .send_to(reinterpret_cast<const unsigned char*>(doc.data()), doc.size(), kController));
  }
};

TEST(RsiController, SendsEveryCycleWithAGrowingIpocAndTheProgramAsSetpoint) {
  RsiControllerConfig c;
  c.first_ipoc = 4294967290ULL;  // across 2^32: a 64-bit counter
  JointVector move = JointVector::Zero(6);
  move[0] = 10.0;
  Stand s(c, move);
  std::uint64_t previous = 0;
  for (int k = 0; k < 50; ++k) {
    ASSERT_TRUE(s.tick());
    if (k > 0) {
      EXPECT_EQ(s.last.ipoc, previous + 4);
    }
    previous = s.last.ipoc;
    s.answer(sen(s.last.ipoc, 0.0));
  }
  EXPECT_EQ(s.last.ipoc, 4294967290ULL + 49 * 4);
  // The program moves A1 by 10 deg over 10 s: ASPos is the program at the cycle's time.
  JointVector q(6);
  s.program->sample(49 * 0.004, q);
  EXPECT_NEAR(s.last.setpoint_deg[0], rad_to_deg(q[0]), 1e-4);
  EXPECT_GT(s.last.setpoint_deg[0], 0.01);
  EXPECT_EQ(s.last.delay, 0u);
  EXPECT_EQ(s.controller->counters().late, 0u);
}

TEST(RsiController, AbsoluteOffsetsDoNotAccumulateAndAreClampedToTheLimits) {
  Stand s;
  for (int k = 0; k < 100; ++k) {
    ASSERT_TRUE(s.tick());
    s.answer(sen(s.last.ipoc, 0.2));  // the same whole offset, a hundred times
  }
  s.tick();
  EXPECT_NEAR(rad_to_deg(s.controller->applied_offset_rad()[0]), 0.2, 1e-12);
  EXPECT_NEAR(rad_to_deg(s.controller->applied_offset_rad()[5]), -0.05, 1e-12);
  // AIPos = ASPos + offset.
  EXPECT_NEAR(s.last.actual_deg[0] - s.last.setpoint_deg[0], 0.2, 1e-4);
  // Beyond UpperLimA1 (0.5 deg): clamped.
  for (int k = 0; k < 10; ++k) {
    s.answer(sen(s.last.ipoc, 3.0));
    ASSERT_TRUE(s.tick());
  }
  EXPECT_NEAR(rad_to_deg(s.controller->applied_offset_rad()[0]), 0.5, 1e-12);
  EXPECT_EQ(s.controller->counters().clamped, 10u);
  EXPECT_EQ(s.controller->counters().late, 0u);
}

TEST(RsiController, AnythingButTheAwaitedAnswerIsLateAndTheTimeoutStopsRsi) {
  RsiControllerConfig c;
  c.timeout = 6;
  Stand s(c);
  ASSERT_TRUE(s.tick());
  s.answer(sen(s.last.ipoc, 0.1, "Other"));  // another SENTYPE
  ASSERT_TRUE(s.tick());
  s.answer(sen(s.last.ipoc - 4, 0.1));  // the previous cycle's IPOC
  ASSERT_TRUE(s.tick());
  s.answer(sen(s.last.ipoc, 0.1), &s.stranger);  // another sender
  ASSERT_TRUE(s.tick());
  s.answer("<Sen Type=\"ImFree\"><AK A1=\"0.1\"/>");  // unreadable
  ASSERT_TRUE(s.tick());
  EXPECT_EQ(s.last.delay, 4u);      // the controller reports the count in <Delay>
  s.answer(sen(s.last.ipoc, 0.1));  // a good one: taken, but the count stays
  ASSERT_TRUE(s.tick());
  EXPECT_EQ(s.last.delay, 4u);
  EXPECT_EQ(s.controller->counters().answers, 1u);
  ASSERT_TRUE(s.tick());   // no answer: 5
  EXPECT_FALSE(s.tick());  // no answer: 6 = Timeout, RSI stops and sends no more
  EXPECT_EQ(s.controller->counters().stopped, RsiStop::kTimeout);
  const JointVector held = s.controller->tick(s.t);
  for (int k = 0; k < 20; ++k) EXPECT_FALSE(s.tick());
  EXPECT_EQ(s.controller->tick(s.t), held);  // the arm stopped where it was
  EXPECT_EQ(s.controller->counters().late, 6u);
}

TEST(RsiController, AxisCorrMonStopsRsiBeyondMaxA) {
  RsiControllerConfig c;
  c.upper_limit_deg = 2.0;
  c.max_correction_deg = 1.0;
  Stand s(c);
  ASSERT_TRUE(s.tick());
  s.answer(sen(s.last.ipoc, 1.5));
  for (int k = 0; k < 5; ++k) s.tick();
  EXPECT_EQ(s.controller->counters().stopped, RsiStop::kMaxCorrection);
}

}  // namespace
}  // namespace deflex::cell
