// The order of force samples over a datagram transport: a stray sample 999 ahead of the running
// sequence number is dropped on its own (it made deflex drop the real samples after it for about a
// second), a sender that restarts from a small number or jumps for good is followed, duplicates and
// late samples are dropped. Samples are built by hand from the documented 64-byte layout.
#include <cstring>

#include <gtest/gtest.h>

#include "deflex/sensors/datagram_force_source.hpp"
#include "deflex/transport/memory_network.hpp"

namespace deflex {
namespace {

struct Stream {
  ManualClock clock;
  MemoryNetwork network{clock};
  MemoryTransport& deflex_port = network.add_endpoint({0x7f000001, 6600}, 0.0);
  MemoryTransport& daq = network.add_endpoint({0x7f000002, 6601}, 0.0);
  DatagramForceSource source{deflex_port};

  void send(std::uint32_t sequence) {
    unsigned char d[64] = {'D', 'F', 'X', 'F'};
    std::memcpy(d + 4, &sequence, 4);
    const double t = sequence * 1e-3;
    std::memcpy(d + 8, &t, 8);
    ASSERT_TRUE(daq.send_to(d, sizeof(d), deflex_port.local_address()));
  }
  /// The sequence numbers (as their times, in ms) the source hands on.
  std::vector<std::uint32_t> taken() {
    std::vector<std::uint32_t> out;
    ForceSample s;
    while (source.latest(s)) out.push_back(static_cast<std::uint32_t>(std::lround(s.t_s * 1e3)));
    return out;
  }
};

TEST(ForceSequence, AStraySampleFarAheadDoesNotMakeTheRealOnesLate) {
  Stream f;
  for (std::uint32_t s = 1; s <= 100; ++s) f.send(s);
  f.send(100 + 999);  // the stray
  for (std::uint32_t s = 101; s <= 200; ++s) f.send(s);
  const auto got = f.taken();
  ASSERT_EQ(got.size(), 200u);
  EXPECT_EQ(got[100], 101u);
  EXPECT_EQ(got.back(), 200u);
  EXPECT_EQ(f.source.counters().far_ahead, 1u);
  EXPECT_EQ(f.source.counters().out_of_order, 0u);
}

TEST(ForceSequence, ARestartedOrJumpingSenderIsFollowedAndLateSamplesAreDropped) {
  Stream f;
  for (std::uint32_t s : {500u, 501u, 502u, 502u, 501u, 503u}) f.send(s);  // a duplicate and a late one
  for (std::uint32_t s : {3u, 4u}) f.send(s);                              // restarted from a small number
  for (std::uint32_t s : {60000u, 60001u, 60002u, 60003u}) f.send(s);      // a jump for good: 3 to confirm
  const auto got = f.taken();
  EXPECT_EQ(got, (std::vector<std::uint32_t>{500, 501, 502, 503, 3, 4, 60002, 60003}));
  EXPECT_EQ(f.source.counters().out_of_order, 2u);
  EXPECT_EQ(f.source.counters().far_ahead, 2u);
  EXPECT_EQ(f.source.counters().restarts, 2u);
}

}  // namespace
}  // namespace deflex
