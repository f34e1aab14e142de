// End to end over loopback UDP: a controller-side peer exchanges real EGM packets with the sensor
// endpoint (in its own thread, callback style, and single-threaded through poll()). Corrections are
// checked against the lumped model computed here with a finite-difference Jacobian; bad packets,
// duplicates, restarts, reply addressing, the watchdog and allocation-free cycles are checked too.
#include <atomic>
#include <cmath>
#include <thread>

#include <gtest/gtest.h>

#include "deflex/egm/egm_robot_peer.hpp"
#include "deflex/egm/egm_sensor_endpoint.hpp"
#include "deflex/model/csv_table.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/online/udp_force_source.hpp"
#include "online/fd_jacobian.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

// A force source the test can switch on and off; one sample a call when on (atomic: the endpoint
// may run in another thread).
class SwitchableForce final : public ForceSource {
 public:
  explicit SwitchableForce(const Vector6& w) : w_(w) {}
  bool latest(ForceSample& out) noexcept override {
    if (!on.load() || served_) {
      served_ = false;
      return false;
    }
    served_ = true;
    out.t_s = 0.0;
    out.wrench_sensor = w_;
    out.valid = true;
    return true;
  }
  std::atomic<bool> on{true};

 private:
  Vector6 w_;
  bool served_ = false;
};

class EgmEndToEnd : public ::testing::Test {
 protected:
  RobotModel robot = [] {
    Pose tool = Pose::Identity();
    tool.translation() = Vector3(0.0, 0.0, 0.35);
    return builtin_irb6700().with_tool(tool);
  }();
  SensorConfig sensor = [] {
    SensorConfig c;
    c.components = 6;
    c.sample_rate_hz = 250.0;
    return c;
  }();
  OnlineConfig cfg = [] {
    OnlineConfig c;
    c.max_correction_rate_rad_s = 10.0;
    c.watchdog_s = 0.03;
    return c;
  }();
  JointVector q_deg = [] {
    JointVector q(6);
    q << 5, 25, -5, 20, 35, -15;
    return q;
  }();
  JointVector q_rad() const { return q_deg * (kPi / 180.0); }

  // The reading of a sensor at the flange when force f_base acts at the TCP.
  Vector6 reading(const Vector3& f_base) const {
    Workspace ws(robot);
    forward_kinematics(robot, ws, q_rad());
    const Matrix3 R = ws.base_T_flange.linear();
    Vector6 w;
    w.head<3>() = R.transpose() * f_base;
    w.tail<3>() = robot.flange_T_wap().translation().cross(Vector3(w.head<3>()));
    return w;
  }
  JointVector expected_command_deg(const Vector3& f_base) const {
    Wrench W;
    W << f_base, Vector3::Zero();
    JointVector d = test::fd_wap_jacobian(robot, q_rad()).transpose() * W;
    for (int i = 0; i < 6; ++i) {
      d[i] /= robot.stiffness()[i];
    }
    return (q_rad() - d) * (180.0 / kPi);
  }
  EgmRobotMessage message(std::uint32_t seq) const {
    EgmRobotMessage m;
    m.seqno = seq;
    m.tm_ms = seq * 4;
    m.feedback_joints_deg = q_deg;
    m.planned_joints_deg = q_deg;
    return m;
  }
};

TEST_F(EgmEndToEnd, ThreadedEndpointAnswersWithTheModelsCorrection) {
  OnlineCompensator comp(robot, sensor, cfg);
  EgmEndpointConfig ec;
  ec.port = 0;
  EgmSensorEndpoint endpoint(comp, ec);
  UdpForceSource forces(0);
  endpoint.set_force_source(&forces);
  std::atomic<bool> stop{false};
  std::uint64_t callbacks = 0;
  std::thread server([&] {
    endpoint.run(stop, [&](const EgmCycleRecord&) {
      ++callbacks;
      return true;
    });
  });

  const Vector3 f_base(200.0, -350.0, -600.0);
  const Vector6 w_sensor = reading(f_base);
  EgmRobotPeer controller("127.0.0.1", endpoint.port());
  // The sensor's DAQ streams over UDP in the documented format.
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  const sockaddr_in force_to = make_address("127.0.0.1", forces.port());
  std::array<unsigned char, kForceDatagramBytes> dgram{};
  EgmSensorMessage reply;
  int replies = 0;
  for (std::uint32_t k = 1; k <= 40; ++k) {
    ForceSample s;
    s.t_s = 0.004 * k;
    s.wrench_sensor = w_sensor;
    encode_force_datagram(s, k, dgram);
    ::sendto(fd, dgram.data(), dgram.size(), 0, reinterpret_cast<const sockaddr*>(&force_to), sizeof(force_to));
    ASSERT_TRUE(controller.send(message(k)));
    if (controller.receive(reply, 2.0)) {
      ++replies;
    }
  }
  ::close(fd);
  stop = true;
  server.join();
  EXPECT_EQ(replies, 40);
  EXPECT_EQ(callbacks, 40u);
  const JointVector expected = expected_command_deg(f_base);
  const JointVector correction_deg = q_deg - expected;
  ASSERT_GT(correction_deg.norm(), 1e-3);  // a visible correction (about 0.01 deg)
  EXPECT_LT((reply.planned_joints_deg - expected).norm(), 1e-7 * correction_deg.norm() + 1e-12)
      << reply.planned_joints_deg.transpose() << "\n"
      << expected.transpose();
  EXPECT_EQ(endpoint.counters().replies, 40u);
  EXPECT_EQ(endpoint.counters().rejected(), 0u);
  EXPECT_EQ(forces.counters().accepted, 40u);
}

TEST_F(EgmEndToEnd, JointsBeyondTheRobotsLimitsAreNeverAnswered) {
  OnlineCompensator comp(robot, sensor, cfg);
  EgmEndpointConfig ec;
  ec.port = 0;
  EgmSensorEndpoint endpoint(comp, ec);
  SwitchableForce force(reading(Vector3(0, 0, -500)));
  endpoint.set_force_source(&force);
  EgmRobotPeer controller("127.0.0.1", endpoint.port());
  EgmSensorMessage reply;
  // Finite but impossible joints: planned joint 2 at 1e6 deg; feedback joint 1 at 200 deg (limit 170).
  EgmRobotMessage absurd = message(20);
  absurd.planned_joints_deg[1] = 1e6;
  ASSERT_TRUE(controller.send(absurd));
  EXPECT_NE(endpoint.poll(0.5), EgmPollResult::kReplied);
  EXPECT_FALSE(controller.receive(reply, 0.02));
  EgmRobotMessage beyond = message(21);
  beyond.feedback_joints_deg[0] = 200.0;
  ASSERT_TRUE(controller.send(beyond));
  EXPECT_NE(endpoint.poll(0.5), EgmPollResult::kReplied);
  EXPECT_FALSE(controller.receive(reply, 0.02));
  EXPECT_EQ(endpoint.counters().out_of_limits, 2u);
  // A packet within the limits is answered as usual.
  ASSERT_TRUE(controller.send(message(22)));
  EXPECT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  EXPECT_TRUE(controller.receive(reply, 1.0));
}

TEST_F(EgmEndToEnd, BadPacketsAreCountedAndNeverAnswered) {
  OnlineCompensator comp(robot, sensor, cfg);
  EgmEndpointConfig ec;
  ec.port = 0;
  EgmSensorEndpoint endpoint(comp, ec);
  SwitchableForce force(reading(Vector3(0, 0, -500)));
  endpoint.set_force_source(&force);
  EgmRobotPeer controller("127.0.0.1", endpoint.port());
  EgmSensorMessage reply;

  const auto expect_silence = [&](const char* what) {
    EXPECT_NE(endpoint.poll(0.5), EgmPollResult::kReplied) << what;
    EXPECT_FALSE(controller.receive(reply, 0.02)) << what;
  };
  ASSERT_TRUE(controller.send(message(10)));
  ASSERT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  ASSERT_TRUE(controller.receive(reply, 1.0));

  const unsigned char garbage[] = {0xFF, 0xFF, 0xFF, 0x07, 0x00, 0x13};
  controller.send_raw(garbage, sizeof(garbage));
  expect_silence("garbage");
  unsigned char buf[1024];
  const std::size_t n = controller.encode(message(11), buf, sizeof(buf));
  controller.send_raw(buf, n / 2);
  expect_silence("truncated");
  std::vector<unsigned char> big(3000, 0x08);
  controller.send_raw(big.data(), big.size());
  expect_silence("oversized");
  EgmRobotMessage nan_msg = message(12);
  nan_msg.planned_joints_deg[3] = std::nan("");
  controller.send(nan_msg);
  expect_silence("NaN joints");
  EgmRobotMessage five = message(13);
  five.feedback_joints_deg = five.feedback_joints_deg.head(5).eval();
  controller.send(five);
  expect_silence("five joints");
  controller.send(message(10));
  expect_silence("duplicate");
  controller.send(message(9));
  expect_silence("out of order");
  controller.send_raw(buf, 0);
  expect_silence("empty");

  const EgmCounters& c = endpoint.counters();
  EXPECT_EQ(c.malformed, 1u);
  EXPECT_EQ(c.truncated, 1u);
  EXPECT_EQ(c.oversized, 1u);
  EXPECT_EQ(c.non_finite, 1u);
  EXPECT_EQ(c.missing_joints, 1u);
  EXPECT_EQ(c.duplicate, 1u);
  EXPECT_EQ(c.out_of_order, 1u);
  EXPECT_EQ(c.empty, 1u);
  EXPECT_EQ(c.replies, 1u);

  // The endpoint is still alive and answers the next good packet.
  controller.send(message(14));
  EXPECT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  EXPECT_TRUE(controller.receive(reply, 1.0));
}

TEST_F(EgmEndToEnd, RestartIsRecognisedAndRepliesGoToTheSender) {
  OnlineCompensator comp(robot, sensor, cfg);
  EgmEndpointConfig ec;
  ec.port = 0;
  EgmSensorEndpoint endpoint(comp, ec);
  EgmRobotPeer a("127.0.0.1", endpoint.port());
  EgmRobotPeer b("127.0.0.1", endpoint.port());
  ASSERT_NE(a.local_port(), b.local_port());
  EgmSensorMessage reply;
  for (std::uint32_t k = 100; k < 110; ++k) {
    a.send(message(k));
    ASSERT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
    ASSERT_TRUE(a.receive(reply, 1.0));
  }
  // The controller restarts (from another port, as a restarted process would): seqno 1 again.
  b.send(message(1));
  EXPECT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  EXPECT_TRUE(b.receive(reply, 1.0));
  EXPECT_FALSE(a.receive(reply, 0.02));
  EXPECT_EQ(endpoint.counters().restarts, 1u);
  EXPECT_EQ(endpoint.counters().out_of_order, 0u);
  b.send(message(2));
  EXPECT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  EXPECT_TRUE(b.receive(reply, 1.0));
}

TEST_F(EgmEndToEnd, StaleForceRampsTheCorrectionToZero) {
  OnlineCompensator comp(robot, sensor, cfg);
  EgmEndpointConfig ec;
  ec.port = 0;
  EgmSensorEndpoint endpoint(comp, ec);
  SwitchableForce force(reading(Vector3(0, 300, -800)));
  endpoint.set_force_source(&force);
  EgmRobotPeer controller("127.0.0.1", endpoint.port());
  EgmSensorMessage reply;
  std::uint32_t seq = 1;
  for (int k = 0; k < 10; ++k, ++seq) {
    controller.send(message(seq));
    ASSERT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
    ASSERT_TRUE(controller.receive(reply, 1.0));
  }
  const double loaded = (reply.planned_joints_deg - q_deg).norm();
  ASSERT_GT(loaded, 1e-3);
  force.on = false;
  double previous = loaded;
  bool reached_zero = false;
  // Real time passes between cycles (4 ms, like EGM); the bound on cycles only stops a broken build.
  for (int k = 0; k < 500 && !reached_zero; ++k, ++seq) {
    std::this_thread::sleep_for(std::chrono::milliseconds(4));
    controller.send(message(seq));
    ASSERT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
    ASSERT_TRUE(controller.receive(reply, 1.0));
    const double now = (reply.planned_joints_deg - q_deg).norm();
    EXPECT_LE(now, previous + 1e-10);  // never grows while the force is stale
    previous = now;
    reached_zero = now < 1e-10;  // zero correction, up to the deg -> rad -> deg round trip
  }
  EXPECT_TRUE(reached_zero);
  EXPECT_EQ(endpoint.last_cycle().status, CycleStatus::kStaleForce);
}

TEST_F(EgmEndToEnd, SteadyStateCycleDoesNotAllocateAndHistoryIsWritten) {
  OnlineCompensator comp(robot, sensor, cfg);
  EgmEndpointConfig ec;
  ec.port = 0;
  ec.history_cycles = 16;
  EgmSensorEndpoint endpoint(comp, ec);
  SwitchableForce force(reading(Vector3(100, 0, -400)));
  endpoint.set_force_source(&force);
  EgmRobotPeer controller("127.0.0.1", endpoint.port());
  EgmSensorMessage reply;
  reply.planned_joints_deg = JointVector::Zero(6);
  controller.send(message(1));
  ASSERT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  ASSERT_TRUE(controller.receive(reply, 1.0));
  std::size_t allocations = 0;
  {
    test::AllocationGuard guard;
    for (std::uint32_t k = 2; k < 200; ++k) {
      controller.send(message(k));
      (void)endpoint.poll(1.0);
      (void)controller.receive(reply, 1.0);
    }
    allocations = guard.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(endpoint.counters().replies, 199u);
  const std::string path = ::testing::TempDir() + "/egm_history.csv";
  endpoint.write_history_csv(path);
  const CsvTable t = CsvTable::read_file(path);
  ASSERT_EQ(t.rows(), 16u);
  EXPECT_EQ(t.at(15, "seqno"), 199.0);
  EXPECT_EQ(t.at(0, "seqno"), 184.0);
  EXPECT_NEAR(t.at(15, "q_command1_rad"), deg_to_rad(reply.planned_joints_deg[0]), 1e-11);
}


TEST_F(EgmEndToEnd, OnlyTheNewestOfABurstIsAnsweredAndSilenceMarksARestart) {
  OnlineCompensator comp(robot, sensor, cfg);
  EgmEndpointConfig ec;
  ec.port = 0;
  ec.restart_silence_s = 0.3;  // short, so the test waits little
  EgmSensorEndpoint endpoint(comp, ec);
  EgmRobotPeer controller("127.0.0.1", endpoint.port());
  EgmSensorMessage reply;

  // Three packets before one poll: one answer, carrying the newest packet's planned joints (no
  // force yet, so the command is the planned configuration itself).
  for (std::uint32_t k = 100; k < 103; ++k) {
    EgmRobotMessage m = message(k);
    m.planned_joints_deg[0] += static_cast<double>(k - 100);
    ASSERT_TRUE(controller.send(m));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // all three queued on loopback
  ASSERT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  ASSERT_TRUE(controller.receive(reply, 1.0));
  EXPECT_NEAR(reply.planned_joints_deg[0], q_deg[0] + 2.0, 1e-9);
  EXPECT_FALSE(controller.receive(reply, 0.02));  // exactly one answer
  EXPECT_EQ(endpoint.counters().superseded, 2u);
  EXPECT_EQ(endpoint.last_cycle().seqno, 102u);

  // A step back to 50 right away is a stale packet (not a small number, no silence): ignored.
  controller.send(message(50));
  EXPECT_EQ(endpoint.poll(0.2), EgmPollResult::kRejected);
  EXPECT_FALSE(controller.receive(reply, 0.02));
  EXPECT_EQ(endpoint.counters().out_of_order, 1u);
  EXPECT_EQ(endpoint.counters().restarts, 0u);

  // The same step back after more than restart_silence_s without a packet: a restarted controller.
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  controller.send(message(50));
  EXPECT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  EXPECT_TRUE(controller.receive(reply, 1.0));
  EXPECT_EQ(endpoint.counters().restarts, 1u);
  EXPECT_EQ(endpoint.counters().out_of_order, 1u);
}

TEST_F(EgmEndToEnd, AStrayRestartPacketDoesNotMakeTheControllersCommandJump) {
  OnlineConfig slow = cfg;
  slow.max_correction_rate_rad_s = 5e-4;  // 2e-6 rad in a 4 ms cycle: the correction builds up slowly
  OnlineCompensator comp(robot, sensor, slow);
  EgmEndpointConfig ec;
  ec.port = 0;
  EgmSensorEndpoint endpoint(comp, ec);
  SwitchableForce force(reading(Vector3(0, 300, -800)));
  endpoint.set_force_source(&force);
  EgmRobotPeer controller("127.0.0.1", endpoint.port());
  EgmRobotPeer stray("127.0.0.1", endpoint.port());
  EgmSensorMessage reply;
  std::uint32_t seq = 500;
  for (int k = 0; k < 40; ++k, ++seq) {
    std::this_thread::sleep_for(std::chrono::milliseconds(4));
    controller.send(message(seq));
    ASSERT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
    ASSERT_TRUE(controller.receive(reply, 1.0));
  }
  const JointVector before_deg = reply.planned_joints_deg;
  const double built_up_rad = deg_to_rad((before_deg - q_deg).cwiseAbs().maxCoeff());
  ASSERT_GT(built_up_rad, 2e-5);  // well above what one cycle may change
  const auto t0 = std::chrono::steady_clock::now();

  // Another sender's packet with a small sequence number: taken as a controller restart.
  stray.send(message(1));
  ASSERT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  EXPECT_TRUE(stray.receive(reply, 1.0));
  EXPECT_EQ(endpoint.counters().restarts, 1u);
  // The real controller's next answer differs from its last by no more than the rate bound allows
  // for the time that passed (with a reset, the whole correction vanished in one cycle).
  controller.send(message(seq));
  ASSERT_EQ(endpoint.poll(1.0), EgmPollResult::kReplied);
  ASSERT_TRUE(controller.receive(reply, 1.0));
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double change_rad = deg_to_rad((reply.planned_joints_deg - before_deg).cwiseAbs().maxCoeff());
  EXPECT_LE(change_rad, slow.max_correction_rate_rad_s * (elapsed_s + 0.004) + 1e-12)
      << "built up " << built_up_rad << " rad";
}

}  // namespace
}  // namespace deflex
