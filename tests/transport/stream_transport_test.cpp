// The stream transports: the in-memory connection (delivery by the clock after the latency, in order,
// reads that split and join writes, partial writes when the window is full, the end of a connection
// seen by the peer only after what was sent before it, no allocation once built) and TCP over
// loopback (connect, accept, partial reads, the peer's close, a refused connection named).
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"
#include "deflex/transport/memory_stream.hpp"
#include "deflex/transport/tcp_stream.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

using Bytes = std::vector<unsigned char>;

Bytes counting(std::size_t n, unsigned char from = 0) {
  Bytes b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<unsigned char>(from + i);
  return b;
}

TEST(MemoryStream, DeliversBytesInOrderAfterTheLatencySplittingAndJoiningWrites) {
  ManualClock clock;
  MemoryStreamPair pair(clock, 0.002, 1000);
  StreamTransport& a = pair.client();
  StreamTransport& b = pair.server();
  const Bytes first = counting(10), second = counting(7, 10);
  EXPECT_EQ(a.write(first.data(), first.size()), 10);
  clock.set(0.001);
  EXPECT_EQ(a.write(second.data(), second.size()), 7);
  unsigned char buf[64];
  EXPECT_FALSE(b.wait_readable(1.0));  // nothing has arrived; simulated transports never wait
  EXPECT_EQ(b.read(buf, sizeof(buf)), 0);
  clock.set(0.002);  // the first write has arrived, the second not yet
  EXPECT_TRUE(b.wait_readable(0.0));
  EXPECT_EQ(b.read(buf, 4), 4);  // a read may split a write
  EXPECT_EQ(b.read(buf + 4, sizeof(buf) - 4), 6);
  EXPECT_EQ(Bytes(buf, buf + 10), first);
  EXPECT_EQ(b.read(buf, sizeof(buf)), 0);
  clock.set(0.0031);
  const Bytes third = counting(3, 17);
  EXPECT_EQ(a.write(third.data(), third.size()), 3);
  clock.set(0.01);  // both later writes have arrived: one read joins them
  EXPECT_EQ(b.read(buf, sizeof(buf)), 10);
  EXPECT_EQ(Bytes(buf, buf + 10), counting(10, 10));
  // And the other way.
  EXPECT_EQ(b.write(first.data(), 5), 5);
  clock.set(0.012);
  EXPECT_EQ(a.read(buf, sizeof(buf)), 5);
  EXPECT_THROW(MemoryStreamPair(clock, -1.0), InputError);
  EXPECT_THROW(MemoryStreamPair(clock, 0.0, 0), InputError);
}

TEST(MemoryStream, AFullWindowTakesPartOfAWriteAndTheRestLater) {
  ManualClock clock;
  MemoryStreamPair pair(clock, 0.0, 16);
  const Bytes data = counting(40);
  EXPECT_EQ(pair.client().write(data.data(), data.size()), 16);  // the window holds 16 unread bytes
  EXPECT_EQ(pair.client().write(data.data() + 16, 24), 0);
  EXPECT_EQ(pair.client().unread_by_peer(), 16u);
  unsigned char buf[64];
  EXPECT_EQ(pair.server().read(buf, 10), 10);
  EXPECT_EQ(pair.client().write(data.data() + 16, 24), 10);
  EXPECT_EQ(pair.server().read(buf + 10, sizeof(buf) - 10), 16);
  EXPECT_EQ(pair.client().write(data.data() + 26, 14), 14);
  EXPECT_EQ(pair.server().read(buf + 26, sizeof(buf) - 26), 14);
  EXPECT_EQ(Bytes(buf, buf + 40), data);  // the ring wrapped around, in order
}

TEST(MemoryStream, ThePeerReadsWhatWasSentBeforeACloseThenSeesItClosed) {
  ManualClock clock;
  MemoryStreamPair pair(clock, 0.005, 100);
  const Bytes data = counting(8);
  ASSERT_EQ(pair.server().write(data.data(), data.size()), 8);
  pair.server().close();
  EXPECT_FALSE(pair.server().is_open());
  EXPECT_EQ(pair.server().read(nullptr, 0), StreamTransport::kClosed);
  EXPECT_EQ(pair.server().write(data.data(), 1), StreamTransport::kClosed);
  unsigned char buf[16];
  EXPECT_EQ(pair.client().read(buf, sizeof(buf)), 0);  // neither the bytes nor the close have arrived
  // Until the close reaches the client, its writes still go (and are lost), as on TCP.
  EXPECT_EQ(pair.client().write(data.data(), 2), 2);
  clock.set(0.005);
  EXPECT_EQ(pair.client().read(buf, sizeof(buf)), 8);
  EXPECT_EQ(pair.client().read(buf, sizeof(buf)), StreamTransport::kClosed);
  EXPECT_TRUE(pair.client().wait_readable(0.0));
  EXPECT_EQ(pair.client().write(data.data(), 2), StreamTransport::kClosed);
  EXPECT_TRUE(pair.client().is_open());  // this end was not closed; the connection is over all the same
}

TEST(MemoryStream, ReadingAndWritingDoNotAllocate) {
  ManualClock clock;
  MemoryStreamPair pair(clock, 0.001, 4096, 256);
  const Bytes data = counting(68);
  unsigned char buf[256];
  test::AllocationGuard guard;
  for (int k = 0; k < 10000; ++k) {
    clock.advance(0.004);
    ASSERT_EQ(pair.client().write(data.data(), data.size()), 68);
    clock.advance(0.001);
    ASSERT_EQ(pair.server().read(buf, sizeof(buf)), 68);
  }
  EXPECT_EQ(guard.allocations(), 0u);
}

TEST(TcpStream, ConnectsOverLoopbackCarriesBytesBothWaysAndSeesThePeerClose) {
  TcpListener listener("127.0.0.1", 0);
  ASSERT_GT(listener.port(), 0);
  auto client = TcpStream::connect("127.0.0.1", listener.port(), 2.0);
  auto server = listener.accept(2.0);
  ASSERT_NE(server, nullptr);
  EXPECT_EQ(client->peer(), "127.0.0.1:" + std::to_string(listener.port()));
  const Bytes data = counting(200);
  EXPECT_EQ(client->write(data.data(), data.size()), 200);
  Bytes got;
  unsigned char buf[64];  // smaller than what was sent: reads take it in pieces
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (got.size() < data.size() && std::chrono::steady_clock::now() < deadline) {
    server->wait_readable(0.1);
    const long n = server->read(buf, sizeof(buf));
    ASSERT_GE(n, 0);
    got.insert(got.end(), buf, buf + n);
  }
  EXPECT_EQ(got, data);
  EXPECT_EQ(server->read(buf, sizeof(buf)), 0);  // nothing waits: no block, no error
  EXPECT_EQ(server->write(data.data(), 3), 3);
  EXPECT_TRUE(wait_readable_any(*server, *client, 2.0));
  EXPECT_EQ(client->read(buf, sizeof(buf)), 3);
  server->close();
  EXPECT_FALSE(server->is_open());
  EXPECT_TRUE(client->wait_readable(2.0));
  EXPECT_EQ(client->read(buf, sizeof(buf)), StreamTransport::kClosed);
  EXPECT_FALSE(client->is_open());
  // Nobody listening (a port that was just free): the error names the address and port.
  auto gone = std::make_unique<TcpListener>("127.0.0.1", 0);
  const std::uint16_t free_port = gone->port();
  gone.reset();
  try {
    (void)TcpStream::connect("127.0.0.1", free_port, 1.0);
    ADD_FAILURE() << "connected to a closed port";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("127.0.0.1:" + std::to_string(free_port)), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)TcpStream::connect("no-such-host.invalid", 11000, 1.0), Error);
  EXPECT_THROW(TcpListener("not-an-address", 0), InputError);
}

TEST(TcpStream, WaitTimeoutEdgesNeitherBlockForeverNorOverflow) {
  EXPECT_EQ(poll_timeout_ms(std::nan("")), 0);
  EXPECT_EQ(poll_timeout_ms(-1.0), 0);
  EXPECT_EQ(poll_timeout_ms(0.0015), 2);
  EXPECT_EQ(poll_timeout_ms(1e12), std::numeric_limits<int>::max());
  EXPECT_EQ(poll_timeout_ms(std::numeric_limits<double>::infinity()), std::numeric_limits<int>::max());
}

}  // namespace
}  // namespace deflex
