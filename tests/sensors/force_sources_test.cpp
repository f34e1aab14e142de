// Force inputs: the UDP sample stream (format round trip, bad datagrams, ordering) over loopback and
// the CSV replay (timing by a manual clock, looping, bad files).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "deflex/sensors/detail/csv_force_replay.hpp"
#include "deflex/sensors/detail/udp_force_source.hpp"
#include "deflex/text/errors.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

class Sender {
 public:
  explicit Sender(std::uint16_t port) : fd_(::socket(AF_INET, SOCK_DGRAM, 0)) {
    to_.sin_family = AF_INET;
    to_.sin_port = htons(port);
    to_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  }
  ~Sender() { ::close(fd_); }
  void send(const void* data, std::size_t n) {
    ASSERT_EQ(::sendto(fd_, data, n, 0, reinterpret_cast<const sockaddr*>(&to_), sizeof(to_)), static_cast<ssize_t>(n));
  }

 private:
  int fd_;
  sockaddr_in to_{};
};

// Polls until `count` samples arrived (loopback delivery is immediate in practice; bounded wait).
int receive(UdpForceSource& src, std::vector<ForceSample>& got, std::size_t count) {
  ForceSample s;
  for (int i = 0; i < 2000 && got.size() < count; ++i) {
    while (src.latest(s)) {
      got.push_back(s);
    }
    if (got.size() < count) {
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
  }
  return static_cast<int>(got.size());
}

TEST(UdpForceSource, DecodesTheDocumentedFormatAndDropsBadDatagrams) {
  UdpForceSource src(0);
  ASSERT_NE(src.port(), 0);
  Sender tx(src.port());
  // A datagram built by hand from the documented layout, not by encode_force_datagram().
  unsigned char hand[64] = {'D', 'F', 'X', 'F', 5, 0, 0, 0};
  const double values[7] = {1.25, 10.0, -20.0, 30.0, 0.5, -0.25, 0.125};
  std::memcpy(hand + 8, values, sizeof(values));
  tx.send(hand, 64);
  tx.send("garbage", 7);  // wrong size
  unsigned char wrong_magic[64] = {'X'};
  tx.send(wrong_magic, 64);
  tx.send(hand, 64);  // duplicate sequence 5
  std::array<unsigned char, kForceDatagramBytes> enc{};
  ForceDatagram s;
  s.sequence = 6;
  s.t_s = 1.5;
  s.wrench_sensor << 1, 2, 3, 4, 5, 6;
  encode_force_datagram(s, enc);
  tx.send(enc.data(), enc.size());
  unsigned char big[200] = {'D', 'F', 'X', 'F'};
  tx.send(big, sizeof(big));  // oversized
  std::vector<ForceSample> got;
  ASSERT_EQ(receive(src, got, 2), 2);
  EXPECT_EQ(got[0].t_s, 1.25);
  EXPECT_EQ(got[0].wrench_sensor[1], -20.0);
  EXPECT_EQ(got[0].wrench_sensor[5], 0.125);
  EXPECT_TRUE(got[0].valid);
  EXPECT_EQ(got[1].wrench_sensor[5], 6.0);
  // Let the oversized one arrive, then check the counters.
  ForceSample extra;
  for (int i = 0; i < 200 && src.counters().received < 6; ++i) {
    (void)src.latest(extra);
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  EXPECT_EQ(src.counters().malformed, 3u);
  EXPECT_EQ(src.counters().out_of_order, 1u);
  EXPECT_EQ(src.counters().accepted, 2u);
}

TEST(UdpForceSource, NonFiniteValuesArriveFlaggedInvalidAndPollingDoesNotAllocate) {
  UdpForceSource src(0);
  Sender tx(src.port());
  std::array<unsigned char, kForceDatagramBytes> enc{};
  ForceDatagram s;
  s.sequence = 1;
  s.wrench_sensor[2] = std::nan("");
  encode_force_datagram(s, enc);
  tx.send(enc.data(), enc.size());
  std::vector<ForceSample> got;
  got.reserve(4);
  ASSERT_EQ(receive(src, got, 1), 1);
  EXPECT_FALSE(got[0].valid);
  test::AllocationGuard guard;
  ForceSample out;
  for (int i = 0; i < 100; ++i) {
    (void)src.latest(out);
  }
  EXPECT_EQ(guard.allocations(), 0u);
}

TEST(UdpForceSource, ARestartedSenderIsAcceptedAgain) {
  UdpForceSource src(0);
  Sender tx(src.port());
  std::array<unsigned char, kForceDatagramBytes> enc{};
  ForceDatagram s;
  for (std::uint32_t seq : {500u, 501u, 1u, 2u}) {
    s.t_s = seq;
    s.sequence = seq;
    encode_force_datagram(s, enc);
    tx.send(enc.data(), enc.size());
  }
  std::vector<ForceSample> got;
  ASSERT_EQ(receive(src, got, 4), 4);
  EXPECT_EQ(got[2].t_s, 1.0);
  EXPECT_EQ(src.counters().out_of_order, 0u);
}

TEST(CsvForceReplay, ReplaysByTheClockAndLoops) {
  const std::string path = ::testing::TempDir() + "/replay.csv";
  std::ofstream(path)
      << "t_s,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm\n10.0,1,0,0,0,0,0.5\n10.1,2,0,0,0,0,0\n10.2,3,0,0,0,0,0\n";
  CsvForceReplay r(path, true);
  ForceSample s;
  r.advance_to(0.0);
  ASSERT_TRUE(r.latest(s));
  EXPECT_EQ(s.wrench_sensor[0], 1.0);
  EXPECT_EQ(s.wrench_sensor[5], 0.5);
  EXPECT_FALSE(r.latest(s));
  r.advance_to(0.25);
  ASSERT_TRUE(r.latest(s));
  ASSERT_TRUE(r.latest(s));
  EXPECT_EQ(s.wrench_sensor[0], 3.0);
  EXPECT_FALSE(r.latest(s));
  r.advance_to(0.31);  // the second lap starts one sample period after the last sample
  ASSERT_TRUE(r.latest(s));
  EXPECT_EQ(s.wrench_sensor[0], 1.0);
  EXPECT_NEAR(s.t_s, 10.3, 1e-12);
}

TEST(CsvForceReplay, BadFilesNameTheLine) {
  const std::string path = ::testing::TempDir() + "/replay_bad.csv";
  std::ofstream(path) << "t_s,fx_N,fy_N,fz_N\n0.0,1,2,3\n0.0,1,2,3\n";
  try {
    CsvForceReplay r(path);
    ADD_FAILURE() << "non-increasing time accepted";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find(":3"), std::string::npos) << e.what();
  }
  std::ofstream(path) << "t_s,fx_N,fz_N\n0.0,1,3\n";
  EXPECT_THROW(CsvForceReplay{path}, DataError);
}

}  // namespace
}  // namespace deflex
