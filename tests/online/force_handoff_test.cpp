// A force sensor driver on its own thread hands samples to the cycle through ForceHandoff: every sample
// arrives once, in order, while both threads run at once; a full queue refuses (and counts) rather
// than overwriting; neither side allocates; the cycle takes it as any ForceSource.
#include <thread>

#include <gtest/gtest.h>

#include "deflex/online/force_handoff.hpp"
#include "deflex/online/online_compensator.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

ForceSample handoff_sample(std::uint64_t i) {
  ForceSample s;
  s.t_s = static_cast<double>(i) * 1e-3;
  s.wrench_sensor << static_cast<double>(i), -static_cast<double>(i), 2.0 * static_cast<double>(i), 0.0, 0.0, 0.0;
  return s;
}

TEST(ForceHandoff, EverySampleArrivesOnceInOrderAcrossThreads) {
  constexpr std::uint64_t kSamples = 200000;
  ForceHandoff queue(256);
  std::thread driver([&] {
    for (std::uint64_t i = 0; i < kSamples;) {
      if (queue.push(handoff_sample(i))) {
        ++i;
      } else {
        std::this_thread::yield();  // a driver that waits for room (a real one would count the loss)
      }
    }
  });
  std::uint64_t next = 0;
  ForceSample s;
  bool in_order = true, intact = true;
  while (next < kSamples) {
    if (!queue.latest(s)) {
      std::this_thread::yield();
      continue;
    }
    in_order = in_order && s.t_s == static_cast<double>(next) * 1e-3;
    intact = intact && s.wrench_sensor[0] == static_cast<double>(next) &&
             s.wrench_sensor[2] == 2.0 * static_cast<double>(next);
    ++next;
  }
  driver.join();
  EXPECT_TRUE(in_order);
  EXPECT_TRUE(intact);  // never half a sample: the wrench matches its time stamp
  EXPECT_FALSE(queue.latest(s));
  EXPECT_EQ(queue.stats().accepted, kSamples);
}

TEST(ForceHandoff, AFullQueueRefusesAndCountsNeverOverwrites) {
  ForceHandoff queue(4);
  for (std::uint64_t i = 0; i < 4; ++i) EXPECT_TRUE(queue.push(handoff_sample(i)));
  EXPECT_FALSE(queue.push(handoff_sample(99)));
  EXPECT_EQ(queue.stats().lost, 1u);
  EXPECT_EQ(queue.stats().received, 5u);
  ForceSample s;
  for (std::uint64_t i = 0; i < 4; ++i) {
    ASSERT_TRUE(queue.latest(s));
    EXPECT_EQ(s.t_s, static_cast<double>(i) * 1e-3);  // the oldest four, not the refused one
  }
  EXPECT_THROW(ForceHandoff(0), InputError);
}

TEST(ForceHandoff, NeitherSideAllocatesAndTheCycleDrainsIt) {
  ForceHandoff queue(64);
  OnlineCompensator compensator(builtin_irb6700(), SensorConfig{}, OnlineConfig{});
  CycleInput in;
  in.q_planned = JointVector::Constant(6, 0.3);
  in.q_feedback = in.q_planned;
  std::size_t allocations = 0;
  CycleOutput out;
  for (int k = 0; k < 50; ++k) {
    test::AllocationGuard guard;
    for (int j = 0; j < 4; ++j) (void)queue.push(handoff_sample(static_cast<std::uint64_t>(4 * k + j)));
    in.t_s = 0.004 * k;
    out = compensator.step(in, queue);
    allocations += guard.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(out.samples_used, 4);
  EXPECT_GE(static_cast<int>(out.status), 0);
  EXPECT_EQ(queue.stats().lost, 0u);
}

}  // namespace
}  // namespace deflex
