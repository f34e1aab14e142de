// Both EGM links over real loopback UDP sockets (the transport a cell uses), single-threaded: the
// controller stand-in's socket and deflex's are both polled here. The receive-compute-reply cycle
// allocates nothing on UDP either, and the answers reach the controller.
#include <gtest/gtest.h>

#include "deflex/transport/udp_transport.hpp"
#include "links/link_harness.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

JointVector start_pose() {
  JointVector q(6);
  q << 0.0, 0.35, 0.17, 0.0, 1.05, 0.0;
  return q;
}

template <class Controller, class Link>
void exchange(Controller& controller, Link& link, ManualClock& clock, int warm, int counted, std::size_t& allocations,
              int& answered) {
  double t = 0.0;
  for (int k = 0; k < warm + counted; ++k) {
    t += 0.004;
    clock.set(t);
    controller.tick(t);
    // The datagram is on its way through the kernel: wait for it (bounded) before the timed poll.
    LinkPollResult r = LinkPollResult::kIdle;
    if (k < warm) {
      r = link.poll(0.5);
    } else {
      test::AllocationGuard guard;
      r = link.poll(0.5);
      allocations += guard.allocations();
    }
    if (r == LinkPollResult::kAnswered) ++answered;
  }
}

TEST(UdpLinks, EgmJointCycleOverUdpDoesNotAllocateAndIsAnswered) {
  const RobotModel robot = test::bench_robot();
  ManualClock clock;
  UdpTransport deflex_socket("127.0.0.1", 0), controller_socket("127.0.0.1", 0);
  OnlineCompensator comp(robot, test::bench_sensor(), test::bench_online());
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  test::ConstantForce force;
  force.reading = test::reading_at(robot, start_pose(), Vector3(0, 0, -400));
  EgmJointLink link(comp, strategy, test::hold_program(robot, start_pose(), 100.0), deflex_socket, clock);
  link.read_force_from(&force);
  cell::EgmPositionGuidanceController controller(cell::ControllerConfig{}, start_pose(), controller_socket,
                                                 deflex_socket.local_address());
  std::size_t allocations = 0;
  int answered = 0;
  exchange(controller, link, clock, 100, 300, allocations, answered);
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(answered, 400);
  EXPECT_GT(controller.counters().targets, 390u);
}

TEST(UdpLinks, EgmPathCycleOverUdpDoesNotAllocateAndIsAnswered) {
  const RobotModel robot = test::bench_robot();
  ManualClock clock;
  UdpTransport deflex_socket("127.0.0.1", 0), controller_socket("127.0.0.1", 0);
  OnlineCompensator comp(robot, test::bench_sensor(), test::bench_online());
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  test::ConstantForce force;
  force.reading = test::reading_at(robot, start_pose(), Vector3(0, 0, -400));
  EgmPathLink link(comp, strategy, deflex_socket, clock);
  link.read_force_from(&force);
  cell::ControllerConfig cc;
  cc.path_corr_period_s = 0.004;
  cell::EgmPathCorrectionController controller(cc, robot, test::hold_program(robot, start_pose(), 100.0),
                                               controller_socket, deflex_socket.local_address());
  std::size_t allocations = 0;
  int answered = 0;
  exchange(controller, link, clock, 100, 300, allocations, answered);
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(answered, 400);
  EXPECT_GT(controller.counters().targets, 390u);
}

}  // namespace
}  // namespace deflex
