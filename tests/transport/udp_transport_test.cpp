// The datagram transports: UDP (the wait's timeout at its edges: NaN, negative, beyond an int of
// milliseconds; the true size of a datagram larger than the buffer) and the in-memory network
// (delivery by the clock, in order, lost when a queue is full, no allocation once built).
#include <chrono>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"

#include "deflex/transport/memory_network.hpp"
#include "deflex/transport/udp_transport.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

TEST(UdpTransport, WaitTimeoutEdgesNeitherBlockForeverNorOverflow) {
  UdpTransport socket("127.0.0.1", 0);
  const auto start = std::chrono::steady_clock::now();
  // Nothing sent: a NaN or negative timeout is "do not wait", not an endless poll() (a NaN cast to
  // int was INT_MIN, which poll() takes as "wait forever").
  EXPECT_FALSE(socket.wait_readable(std::nan("")));
  EXPECT_FALSE(socket.wait_readable(-1.0));
  EXPECT_FALSE(socket.wait_readable(-std::numeric_limits<double>::infinity()));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);

  // A datagram waiting: any timeout, even one beyond INT_MAX ms or infinite, returns at once.
  const unsigned char payload[100] = {1, 2, 3};
  ASSERT_TRUE(socket.send_to(payload, sizeof(payload), make_datagram_address("127.0.0.1", socket.port())));
  EXPECT_TRUE(socket.wait_readable(1e12));
  EXPECT_TRUE(socket.wait_readable(std::numeric_limits<double>::infinity()));
  unsigned char small[10];
  DatagramAddress from;
  EXPECT_EQ(socket.receive(small, sizeof(small), from), 100);  // the full size, so oversize is seen
  EXPECT_EQ(small[2], 3);
  EXPECT_EQ(from.port, socket.port());
  EXPECT_EQ(to_string(from), fmt::format("127.0.0.1:{}", socket.port()));
  EXPECT_EQ(socket.receive(small, sizeof(small), from), -1);  // nothing left
  EXPECT_THROW((void)make_datagram_address("300.1.2.3", 1), InputError);
  EXPECT_THROW(UdpTransport("not-an-address", 0), InputError);
}

TEST(MemoryNetwork, DeliversInOrderAfterTheLatencyByTheClock) {
  ManualClock clock;
  MemoryNetwork net(clock, 64, 4);
  const DatagramAddress a{1, 10}, b{2, 20};
  MemoryTransport& ta = net.add_endpoint(a, 0.003);
  MemoryTransport& tb = net.add_endpoint(b, 0.0);
  EXPECT_THROW(net.add_endpoint(a), InputError);
  unsigned char msg[3] = {7, 8, 9};
  ASSERT_TRUE(ta.send_to(msg, 3, b));
  msg[0] = 6;
  ASSERT_TRUE(ta.send_to(msg, 3, b));
  unsigned char buf[8];
  DatagramAddress from;
  EXPECT_FALSE(tb.wait_readable(10.0));  // not yet arrived: nothing waits in simulated time
  EXPECT_EQ(tb.receive(buf, sizeof(buf), from), -1);
  clock.set(0.003);
  EXPECT_TRUE(tb.wait_readable(0.0));
  EXPECT_EQ(tb.receive(buf, sizeof(buf), from), 3);
  EXPECT_EQ(buf[0], 7);  // in the order sent
  EXPECT_EQ(from, a);
  EXPECT_EQ(tb.receive(buf, 2, from), 3);  // cut, but the full size is told
  EXPECT_EQ(buf[0], 6);
  EXPECT_EQ(tb.receive(buf, sizeof(buf), from), -1);
  // A full queue loses the datagram (the sender is not told, as with UDP); oversized ones fail.
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(ta.send_to(msg, 3, b));
  EXPECT_EQ(net.counters().dropped_full, 2u);
  unsigned char big[65] = {};
  EXPECT_FALSE(ta.send_to(big, sizeof(big), b));
  EXPECT_TRUE(ta.send_to(msg, 3, DatagramAddress{3, 30}));  // nobody there
  EXPECT_EQ(net.counters().dropped_no_route, 1u);
  // Sending and receiving never allocate.
  clock.set(1.0);
  while (tb.receive(buf, sizeof(buf), from) >= 0) {
  }
  std::size_t allocations = 0;
  long got = 0;
  {
    test::AllocationGuard guard;
    const bool sent = ta.send_to(msg, 3, b);
    clock.set(1.003);
    got = sent ? tb.receive(buf, sizeof(buf), from) : -2;
    allocations = guard.allocations();
  }
  EXPECT_EQ(got, 3);
  EXPECT_EQ(allocations, 0u);
}

}  // namespace
}  // namespace deflex
