// The EGM link's UDP socket: the wait's timeout at its edges (NaN, negative, beyond an int of
// milliseconds) and the true size of a datagram larger than the buffer.
#include <chrono>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "deflex/egm/udp_socket.hpp"

namespace deflex {
namespace {

TEST(UdpSocket, WaitTimeoutEdgesNeitherBlockForeverNorOverflow) {
  UdpSocket socket("127.0.0.1", 0);
  const auto start = std::chrono::steady_clock::now();
  // Nothing sent: a NaN or negative timeout is "do not wait", not an endless poll() (a NaN cast to
  // int was INT_MIN, which poll() takes as "wait forever").
  EXPECT_FALSE(socket.wait_readable(std::nan("")));
  EXPECT_FALSE(socket.wait_readable(-1.0));
  EXPECT_FALSE(socket.wait_readable(-std::numeric_limits<double>::infinity()));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);

  // A datagram waiting: any timeout, even one beyond INT_MAX ms or infinite, returns at once.
  const unsigned char payload[100] = {1, 2, 3};
  ASSERT_TRUE(socket.send_to(payload, sizeof(payload), make_address("127.0.0.1", socket.port())));
  EXPECT_TRUE(socket.wait_readable(1e12));
  EXPECT_TRUE(socket.wait_readable(std::numeric_limits<double>::infinity()));
  unsigned char small[10];
  sockaddr_in from{};
  EXPECT_EQ(socket.receive(small, sizeof(small), from), 100);  // the full size, so oversize is seen
  EXPECT_EQ(small[2], 3);
  EXPECT_EQ(ntohs(from.sin_port), socket.port());
  EXPECT_EQ(socket.receive(small, sizeof(small), from), -1);  // nothing left
}

}  // namespace
}  // namespace deflex
