// deflex's KUKA RSI axis-correction link against the simulated KUKA controller (rsi_harness.hpp), with
// the invariants of the EGM links: every answer within the bound, a constant force gives a constant
// whole offset equal to the model's correction computed here independently (no drift over 100,000
// cycles), zero force gives exactly zero, and the controller never counts an answer late. Bad, foreign
// and stray documents are counted and never answered (checked on the raw wire, the answers read by
// libxml2); a new RSI session starts from zero correction; the cycle allocates nothing, over the
// in-memory network and over UDP.
#include <gtest/gtest.h>

#include "support/poses.hpp"

#include <string>

#include "deflex/online/online_strategy.hpp"
#include "deflex/transport/udp_transport.hpp"
#include "links/rsi_harness.hpp"
#include "support/allocation_guard.hpp"
#include "wire/libxml2_reader.hpp"

namespace deflex {
namespace {

using test::RsiBench;

using test::pose_deg;

TEST(RsiLink, ConstantForceGivesAConstantWholeOffsetOver100000Cycles) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  RsiBench bench(test::hold_program(test::bench_robot(), q0, 1000.0));
  const Vector3 f_base(150.0, -250.0, -300.0);
  const JointVector expected = test::model_correction(bench.robot, q0, f_base);
  const double bound = bench.compensator.config().max_joint_correction_rad;
  ASSERT_LT(expected.cwiseAbs().maxCoeff(), bound);
  JointVector at_10k;
  double largest = 0.0;
  for (int k = 1; k <= 100000; ++k) {
    // The sensor turns with the arm: its reading is the base-frame force seen at the arm's pose.
    if (k > 1) bench.force.reading = test::reading_at(bench.robot, bench.arm(), f_base);
    ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered) << "cycle " << k;
    largest = std::max(largest, bench.link.last_cycle().dtheta.cwiseAbs().maxCoeff());
    if (k == 10000) at_10k = bench.controller->applied_offset_rad();
  }
  const JointVector at_100k = bench.controller->applied_offset_rad();
  // The controller's axes are offset by -dtheta of the model at the program's pose (AK has 1e-6 deg
  // steps; the controller sends its axes with 1e-4 deg steps).
  EXPECT_LT((at_100k + expected).cwiseAbs().maxCoeff(), deg_to_rad(2e-6));
  EXPECT_EQ(at_100k, at_10k);
  EXPECT_LE(largest, bound);
  EXPECT_EQ(bench.controller->counters().late, 0u);
  EXPECT_EQ(bench.controller->counters().clamped, 0u);
  EXPECT_TRUE(bench.controller->running());
  EXPECT_EQ(bench.link.counters().replies, 100000u);
  EXPECT_EQ(bench.link.counters().guard_trips, 0u);
  EXPECT_EQ(bench.link.counters().rejected(), 0u);
}

TEST(RsiLink, ZeroForceAnswersExactlyZeroWhileTheProgramMoves) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  RsiBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(10, -5, 8, 20, -10, 30), 8.0));
  bench.force.reading = Vector6::Zero();
  for (int k = 0; k < 2000; ++k) {
    ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered);
    EXPECT_EQ(bench.link.last_cycle().dtheta, JointVector::Zero(6));
  }
  EXPECT_EQ(bench.controller->applied_offset_rad(), JointVector::Zero(6));
  // The program moved underneath: the link's nominal is the controller's setpoint, not a program of its own.
  EXPECT_GT((bench.link.last_cycle().q_nominal - q0).cwiseAbs().maxCoeff(), deg_to_rad(5.0));
}

TEST(RsiLink, MovingUnderForceEveryAnswerStaysWithinTheBoundAndNoneIsLate) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  RsiBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(12, -6, 9, 15, -12, 25), 10.0));
  const Vector3 f_base(0.0, 0.0, -650.0);
  double worst = 0.0;
  for (int k = 1; k <= 3000; ++k) {
    bench.force.reading = test::reading_at(bench.robot, bench.arm().size() ? bench.arm() : q0, f_base);
    ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered);
    worst = std::max(worst, bench.controller->applied_offset_rad().cwiseAbs().maxCoeff());
    const LinkCycleRecord& r = bench.link.last_cycle();
    // What went on the wire is the whole offset -dtheta, rounded to the answer's 6 decimals of a degree.
    EXPECT_LE((r.q_command - (r.q_nominal - r.dtheta)).cwiseAbs().maxCoeff(), deg_to_rad(0.5e-6) * (1 + 1e-9));
  }
  EXPECT_LE(worst, bench.compensator.config().max_joint_correction_rad * (1 + 1e-6));
  EXPECT_GT(worst, 1e-5);
  EXPECT_EQ(bench.controller->counters().late, 0u);
  EXPECT_EQ(bench.controller->counters().clamped, 0u);
  // The model's correction at the program's pose now (the correction ramps with the arm, so compare
  // where the force and the pose have been still for the filter: the end of the sweep).
  for (int k = 0; k < 500; ++k) {
    bench.force.reading = test::reading_at(bench.robot, bench.arm(), f_base);
    bench.tick();
  }
  const JointVector expected = test::model_correction(bench.robot, bench.link.last_cycle().q_nominal, f_base);
  EXPECT_LT((bench.link.last_cycle().dtheta - expected).cwiseAbs().maxCoeff(), 1e-8);
}

// A raw controller endpoint: what the link answers, read back byte for byte.
struct RawWire {
  ManualClock clock;
  MemoryNetwork network{clock, 8192};
  MemoryTransport& sensor = network.add_endpoint(test::kSensorAddress, 0.0);
  MemoryTransport& controller = network.add_endpoint(test::kControllerAddress, 0.0);
  MemoryTransport& stranger = network.add_endpoint(test::kStrangerAddress, 0.0);
  RobotModel robot = test::bench_robot();
  OnlineCompensator compensator{robot, test::bench_sensor(), test::bench_online()};
  OnlineStrategy strategy{robot, StrategyKind::kOnline, nullptr};
  test::ConstantForce force;
  RsiLink link{compensator, strategy, sensor, clock};
  double t = 0.0;

  RawWire() { link.read_force_from(&force); }

  /// Sends `doc` from `from`, lets the link poll, returns what came back to `from` (empty: nothing).
  std::string exchange(const std::string& doc, MemoryTransport* from = nullptr) {
    MemoryTransport& port = from != nullptr ? *from : controller;
    t += 0.004;
    clock.set(t);
    EXPECT_TRUE(port.send_to(reinterpret_cast<const unsigned char*>(doc.data()), doc.size(), test::kSensorAddress));
    while (link.poll(0.0) != LinkPollResult::kIdle) {
    }
    unsigned char buf[4096];
    DatagramAddress who;
    const long n = port.receive(buf, sizeof(buf), who);
    return n < 0 ? std::string() : std::string(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(n));
  }
};

std::string rob(std::uint64_t ipoc, const std::string& a1 = "0", const std::string& type = "KUKA") {
  return "<Rob Type=\"" + type + "\"><AIPos A1=\"" + a1 + "\" A2=\"20\" A3=\"10\" A4=\"0\" A5=\"60\" A6=\"0\"/>" +
         "<ASPos A1=\"0\" A2=\"20\" A3=\"10\" A4=\"0\" A5=\"60\" A6=\"0\"/><Delay D=\"0\"/><IPOC>" +
         std::to_string(ipoc) + "</IPOC></Rob>";
}

TEST(RsiLink, BadForeignAndStrayDocumentsAreCountedAndNeverAnswered) {
  RawWire w;
  // A good document is answered with its IPOC echoed and a <Sen> of the configured Type.
  const std::string first = w.exchange(rob(4000));
  const auto answer = test::libxml2_read(first);
  ASSERT_TRUE(answer.well_formed) << first;
  EXPECT_EQ(answer.root.name, "Sen");
  EXPECT_EQ(answer.root.attributes.at("Type"), "ImFree");
  ASSERT_EQ(answer.children.size(), 2u);
  EXPECT_EQ(answer.children[0].name, "AK");
  EXPECT_EQ(answer.children[0].attributes.size(), 6u);
  EXPECT_EQ(answer.children[1].text, "4000");

  const std::string good = rob(4004);
  const std::vector<std::pair<std::string, std::uint64_t LinkCounters::*>> bad = {
      {good.substr(0, good.size() - 3), &LinkCounters::truncated},
      {"<Rob Type=\"KUKA\"><AIPos A1=\"0\" A1=\"1\"/></Rob>", &LinkCounters::malformed},
      {"", &LinkCounters::empty},
      {rob(4004, "0", "ABB"), &LinkCounters::foreign_document},
      {"<Sen Type=\"ImFree\"><AK A1=\"0\"/><IPOC>4004</IPOC></Sen>", &LinkCounters::foreign_document},
      {rob(4004, "1e999"), &LinkCounters::non_finite},
      {rob(4004, "400"), &LinkCounters::out_of_limits},
      {std::string(5000, ' ') + good, &LinkCounters::oversized},
      {rob(4000 + 100000), &LinkCounters::far_ahead},
      {"<Rob Type=\"KUKA\"><AIPos A1=\"0\" A2=\"20\" A3=\"10\" A4=\"0\" A5=\"60\" A6=\"0\"/><IPOC>99999999999999999999"
       "</IPOC></Rob>",
       &LinkCounters::sequence_out_of_range},
      {rob(4000), &LinkCounters::duplicate},
      {rob(3996), &LinkCounters::out_of_order},
      {"<Rob Type=\"KUKA\"><IPOC>4004</IPOC></Rob>", &LinkCounters::missing_joints},
      {"<Rob Type=\"KUKA\"><AIPos A1=\"0\" A2=\"20\" A3=\"10\" A4=\"0\" A5=\"60\" A6=\"0\"/></Rob>",
       &LinkCounters::missing_header},
  };
  for (const auto& [doc, counter] : bad) {
    const std::uint64_t before = w.link.counters().*counter;
    EXPECT_EQ(w.exchange(doc), "") << doc.substr(0, 200);
    EXPECT_EQ(w.link.counters().*counter, before + 1) << doc.substr(0, 200);
  }
  // Another sender, with a perfectly good next document: never answered while the controller talks.
  EXPECT_EQ(w.exchange(rob(4004), &w.stranger), "");
  EXPECT_EQ(w.link.counters().foreign_sender, 1u);
  // The controller's next document is answered: none of the above moved the link.
  const auto next = test::libxml2_read(w.exchange(rob(4004)));
  ASSERT_TRUE(next.well_formed);
  EXPECT_EQ(next.children[1].text, "4004");
  EXPECT_EQ(w.link.counters().replies, 2u);
  EXPECT_EQ(w.link.counters().restarts, 0u);
}

TEST(RsiLink, AStrayIpocFarAheadDoesNotCaptureTheLink) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  RsiBench bench(test::hold_program(test::bench_robot(), q0, 100.0));
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  for (int k = 0; k < 200; ++k) bench.tick();
  // A stray from the controller's own address, 100,000 ms ahead, just before its next cycle.
  const std::string stray = rob(bench.controller->last_ipoc() + 100000);
  ASSERT_TRUE(bench.controller_port.send_to(reinterpret_cast<const unsigned char*>(stray.data()), stray.size(),
                                            test::kSensorAddress));
  for (int k = 0; k < 200; ++k) ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered);
  EXPECT_EQ(bench.link.counters().far_ahead, 1u);
  EXPECT_EQ(bench.link.counters().out_of_order, 0u);
  EXPECT_EQ(bench.controller->counters().late, 0u);  // every real cycle was answered in time
}

TEST(RsiLink, TheControllersLateCountComesBackInTheDiagnostics) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  RsiBench bench(test::hold_program(test::bench_robot(), q0, 100.0));
  for (int k = 0; k < 50; ++k) bench.tick();
  for (int k = 0; k < 7; ++k) bench.tick(false);  // deflex misses 7 cycles (a stalled machine)
  for (int k = 0; k < 3; ++k) bench.tick();
  EXPECT_EQ(bench.controller->counters().late, 7u);
  EXPECT_EQ(bench.link.counters().controller_late, 7u);
  // 8 documents waited in the socket: the newest was answered, the 7 older ones superseded, and
  // the arrival delay of the waiting ones was seen.
  EXPECT_EQ(bench.link.counters().superseded, 7u);
  EXPECT_GT(bench.link.counters().max_arrival_delay_s, 6 * 0.004);
  EXPECT_GE(bench.link.counters().late, 6u);
  EXPECT_EQ(bench.link.counters().missed, 0u);
}

TEST(RsiLink, ANewSessionStartsFromZeroCorrectionAsTheControllerDoes) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  RsiBench bench(test::hold_program(test::bench_robot(), q0, 100.0));
  const Vector3 f_base(0.0, 0.0, -600.0);
  for (int k = 0; k < 1500; ++k) {
    bench.force.reading = test::reading_at(bench.robot, bench.arm().size() ? bench.arm() : q0, f_base);
    bench.tick();
  }
  const double before = bench.link.last_cycle().dtheta.cwiseAbs().maxCoeff();
  ASSERT_GT(before, 1e-4);
  // RSI is switched off and on again a second later: a new controller session, a new IPOC range.
  bench.t_s += 1.0;
  cell::RsiControllerConfig cc = bench.controller_config;
  cc.first_ipoc = 77000000;
  bench.controller = std::make_unique<cell::RsiController>(cc, bench.robot, bench.program, bench.controller_port,
                                                           test::kSensorAddress);
  ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered);
  EXPECT_EQ(bench.link.counters().restarts, 1u);
  // The first answer of the new session is near zero, not the old correction: it ramps at the rate bound.
  const double first = bench.link.last_cycle().dtheta.cwiseAbs().maxCoeff();
  EXPECT_LE(first, bench.compensator.config().max_correction_rate_rad_s * 0.004 + 1e-12);
  for (int k = 0; k < 1500; ++k) {
    bench.force.reading = test::reading_at(bench.robot, bench.arm(), f_base);
    bench.tick();
  }
  EXPECT_NEAR(bench.link.last_cycle().dtheta.cwiseAbs().maxCoeff(), before, 1e-9);
}

TEST(RsiLink, SteadyStateCycleDoesNotAllocate) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const LdbbForceModel ldbb(Vector3(1.5, 0.0, 0.5), 400.0, true);
  for (StrategyKind kind : {StrategyKind::kOnline, StrategyKind::kHybrid, StrategyKind::kPredictive}) {
    RsiBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(8, -3, 4, 10, -5, 12), 5.0), kind, &ldbb);
    bench.force.reading = test::reading_at(bench.robot, q0, Vector3(50, 0, -400));
    for (int k = 0; k < 300; ++k) bench.tick();
    for (int k = 0; k < 200; ++k) {
      bench.t_s += 0.004;
      bench.clock.set(bench.t_s);
      bench.controller->tick(bench.t_s);
      bench.clock.set(bench.t_s + 0.0002);
      test::AllocationGuard guard;
      const LinkPollResult r = bench.link.poll(0.0);
      EXPECT_EQ(guard.allocations(), 0u) << to_string(kind);
      EXPECT_EQ(r, LinkPollResult::kAnswered);
    }
  }
}

TEST(RsiLink, CycleOverUdpDoesNotAllocateAndIsAnswered) {
  const RobotModel robot = test::bench_robot();
  JointVector q0(6);
  q0 << 0.0, 0.35, 0.17, 0.0, 1.05, 0.0;
  ManualClock clock;
  UdpTransport deflex_socket("127.0.0.1", 0), controller_socket("127.0.0.1", 0);
  OnlineCompensator comp(robot, test::bench_sensor(), test::bench_online());
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  test::ConstantForce force;
  force.reading = test::reading_at(robot, q0, Vector3(0, 0, -400));
  RsiLink link(comp, strategy, deflex_socket, clock);
  link.read_force_from(&force);
  cell::RsiController controller(test::rsi_controller_for(comp.config()), robot, test::hold_program(robot, q0, 100.0),
                                 controller_socket, deflex_socket.local_address());
  std::size_t allocations = 0;
  int answered = 0;
  double t = 0.0;
  for (int k = 0; k < 400; ++k) {
    t += 0.004;
    clock.set(t);
    controller.tick(t);
    // The datagram is on its way through the kernel: wait for it (bounded) before the counted poll.
    test::AllocationGuard guard;
    if (link.poll(0.5) == LinkPollResult::kAnswered) ++answered;
    if (k >= 100) allocations += guard.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(answered, 400);
  controller.tick(t + 0.004 - 1e-9);  // take the last answer (loopback: it is there by now, in practice)
  EXPECT_GT(controller.counters().answers, 390u);
}

}  // namespace
}  // namespace deflex
