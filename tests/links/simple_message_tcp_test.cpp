// The simple message link over real loopback TCP (the transport a cell uses) against the simulated
// RAPID streaming server, single-threaded: both ends' sockets are polled here, on a simulated clock.
// The invariants hold over TCP too (every point within the bound of the nominal, convergence to the
// model's correction under a constant force), the cycle allocates nothing on sockets either, and
// Ctrl-C's STOP_TRAJECTORY reaches the controller.
#include <gtest/gtest.h>

#include "deflex/transport/tcp_stream.hpp"
#include "links/simple_message_bench.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

TEST(SimpleMessageTcp, StreamsOverLoopbackWithinTheBoundConvergesAndDoesNotAllocate) {
  const RobotModel robot = test::bench_robot();
  JointVector q0(6);
  q0 << 0.1, 0.45, 0.05, 0.3, 0.6, -0.2;
  TcpListener motion_server("127.0.0.1", 0), state_server("127.0.0.1", 0);
  auto motion = TcpStream::connect("127.0.0.1", motion_server.port(), 2.0);
  auto state = TcpStream::connect("127.0.0.1", state_server.port(), 2.0);
  auto motion_accepted = motion_server.accept(2.0);
  auto state_accepted = state_server.accept(2.0);
  ASSERT_NE(motion_accepted, nullptr);
  ASSERT_NE(state_accepted, nullptr);

  ManualClock clock;
  OnlineCompensator comp(robot, test::bench_sensor(), test::bench_online_100ms());
  OnlineStrategy strategy(robot, StrategyKind::kOnline, nullptr);
  test::ConstantForce force;
  const Vector3 f_base(100.0, 0.0, -400.0);
  force.reading = test::reading_at(robot, q0, f_base);
  SimpleMessageLink link(comp, strategy, test::hold_program(robot, q0, 1000.0), *motion, *state, clock);
  link.read_force_from(&force);
  cell::SimpleMessageServer server({}, robot, q0, *motion_accepted, *state_accepted);

  const double bound = comp.config().max_joint_correction_rad;
  std::size_t allocations = 0;
  std::uint64_t points = 0;
  double worst = 0.0, t = 0.0;
  for (int k = 0; k < 20000 && points < 150; ++k) {
    t += 0.004;
    clock.set(t);
    server.tick(t);
    force.reading = test::reading_at(robot, server.motion().position(), f_base);
    // The bytes are on their way through the kernel: the first poll may wait for them, briefly.
    for (int i = 0; i < 4; ++i) {
      LinkPollResult r;
      if (k < 500) {
        r = link.poll(i == 0 ? 0.0005 : 0.0);
      } else {
        test::AllocationGuard guard;
        r = link.poll(i == 0 ? 0.0005 : 0.0);
        allocations += guard.allocations();
      }
      ASSERT_NE(r, LinkPollResult::kStopped) << link.stop_reason();
      if (r == LinkPollResult::kIdle) break;
      if (r == LinkPollResult::kAnswered) {
        ++points;
        worst = std::max(worst, (link.last_cycle().q_command - link.last_cycle().q_nominal).cwiseAbs().maxCoeff());
      }
    }
  }
  ASSERT_EQ(points, 150u);
  EXPECT_EQ(allocations, 0u);
  EXPECT_LE(worst, bound);
  const JointVector expected = test::model_correction(robot, q0, f_base);
  EXPECT_LT((link.last_cycle().q_command - (q0 - expected)).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_GE(server.counters().accepted, 149u);

  // Ctrl-C: STOP_TRAJECTORY goes out on the socket and the controller stops.
  link.stop();
  for (int k = 0; k < 200 && server.counters().stops == 0; ++k) {
    t += 0.004;
    clock.set(t);
    motion_accepted->wait_readable(0.002);
    server.tick(t);
  }
  EXPECT_EQ(server.counters().stops, 1u);
}

}  // namespace
}  // namespace deflex
