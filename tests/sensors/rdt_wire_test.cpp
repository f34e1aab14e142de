// RDT requests and records against bytes written out by hand from the manuals' layout (ATI 9620-05
// section 10, 9610-05 section 12.1): big-endian, 8-byte requests with header 0x1234, 36-byte records,
// 1..40 records a datagram, both sequence numbers wrapping at 2^32, int32 counts at their limits.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "deflex/wire/rdt.hpp"

namespace deflex {
namespace {

// rdt_sequence 1, ft_sequence 0xFFFFFFFF (the last before the wrap), status 0x80010000,
// Fx -1, Fy INT32_MAX, Fz INT32_MIN, Tx 1000000, Ty -1000000, Tz 0x01020304.
const std::array<unsigned char, 36> kRecord{
    0x00, 0x00, 0x00, 0x01,  // rdt_sequence
    0xFF, 0xFF, 0xFF, 0xFF,  // ft_sequence
    0x80, 0x01, 0x00, 0x00,  // status
    0xFF, 0xFF, 0xFF, 0xFF,  // Fx = -1
    0x7F, 0xFF, 0xFF, 0xFF,  // Fy = 2147483647
    0x80, 0x00, 0x00, 0x00,  // Fz = -2147483648
    0x00, 0x0F, 0x42, 0x40,  // Tx = 1000000
    0xFF, 0xF0, 0xBD, 0xC0,  // Ty = -1000000
    0x01, 0x02, 0x03, 0x04,  // Tz = 16909060
};

TEST(RdtWire, RequestBytesAreBigEndianWithTheHeaderFirst) {
  std::array<unsigned char, 8> out{};
  encode_rdt_request({kRdtRequestHeader, static_cast<std::uint16_t>(RdtCommand::kStartRealTime), 0}, out);
  EXPECT_EQ(out, (std::array<unsigned char, 8>{0x12, 0x34, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00}));
  encode_rdt_request({kRdtRequestHeader, static_cast<std::uint16_t>(RdtCommand::kStartBuffered), 0x01020304}, out);
  EXPECT_EQ(out, (std::array<unsigned char, 8>{0x12, 0x34, 0x00, 0x03, 0x01, 0x02, 0x03, 0x04}));
  encode_rdt_request({kRdtRequestHeader, static_cast<std::uint16_t>(RdtCommand::kSetSoftwareBias), 255}, out);
  EXPECT_EQ(out, (std::array<unsigned char, 8>{0x12, 0x34, 0x00, 0x42, 0x00, 0x00, 0x00, 0xFF}));
  encode_rdt_request({kRdtRequestHeader, static_cast<std::uint16_t>(RdtCommand::kStop), 0}, out);
  EXPECT_EQ(out, (std::array<unsigned char, 8>{0x12, 0x34, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}));
}

TEST(RdtWire, RequestDecodingRefusesAWrongHeaderOrSize) {
  const std::array<unsigned char, 9> bytes{0x12, 0x34, 0x00, 0x82, 0x00, 0x00, 0x00, 0x02, 0x00};
  RdtRequest r;
  ASSERT_TRUE(decode_rdt_request(bytes.data(), 8, r));
  EXPECT_EQ(r.command, 0x0082);
  EXPECT_EQ(r.sample_count, 2u);
  EXPECT_FALSE(decode_rdt_request(bytes.data(), 9, r));                                        // one byte too many
  EXPECT_FALSE(decode_rdt_request(bytes.data(), 7, r));                                        // one too few
  const std::array<unsigned char, 8> swapped{0x34, 0x12, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00};  // little-endian
  EXPECT_FALSE(decode_rdt_request(swapped.data(), 8, r));
  EXPECT_EQ(r.header, 0x3412);
}

TEST(RdtWire, RecordFieldsComeOutOfTheManualsByteOrder) {
  RdtRecord r;
  decode_rdt_record(kRecord.data(), r);
  EXPECT_EQ(r.rdt_sequence, 1u);
  EXPECT_EQ(r.ft_sequence, 4294967295u);
  EXPECT_EQ(r.status, 0x80010000u);
  EXPECT_EQ(r.counts[0], -1);
  EXPECT_EQ(r.counts[1], 2147483647);
  EXPECT_EQ(r.counts[2], -2147483647 - 1);
  EXPECT_EQ(r.counts[3], 1000000);
  EXPECT_EQ(r.counts[4], -1000000);
  EXPECT_EQ(r.counts[5], 16909060);
  EXPECT_TRUE(rdt_counts_saturated(r));
}

TEST(RdtWire, EncodingARecordGivesTheSameBytes) {
  RdtRecord r;
  r.rdt_sequence = 1;
  r.ft_sequence = 0xFFFFFFFFu;
  r.status = 0x80010000u;
  r.counts = {-1, 2147483647, -2147483647 - 1, 1000000, -1000000, 16909060};
  std::array<unsigned char, 36> out{};
  encode_rdt_record(r, out.data());
  EXPECT_EQ(out, kRecord);
}

TEST(RdtWire, SaturationIsEitherInt32Limit) {
  RdtRecord r;
  r.counts = {0, 0, 0, 0, 0, std::numeric_limits<std::int32_t>::max() - 1};
  EXPECT_FALSE(rdt_counts_saturated(r));  // one count short of the limit is a measurement
  r.counts[5] = std::numeric_limits<std::int32_t>::max();
  EXPECT_TRUE(rdt_counts_saturated(r));
  r.counts[5] = 0;
  r.counts[0] = std::numeric_limits<std::int32_t>::min();
  EXPECT_TRUE(rdt_counts_saturated(r));
}

TEST(RdtWire, BufferedDatagramsHoldOneToFortyWholeRecords) {
  EXPECT_EQ(rdt_record_count(36), 1u);
  EXPECT_EQ(rdt_record_count(72), 2u);
  EXPECT_EQ(rdt_record_count(360), 10u);
  EXPECT_EQ(rdt_record_count(1440), 40u);
  EXPECT_EQ(rdt_record_count(0), 0u);
  EXPECT_EQ(rdt_record_count(8), 0u);     // a request, not records
  EXPECT_EQ(rdt_record_count(35), 0u);    // a record cut short
  EXPECT_EQ(rdt_record_count(37), 0u);    // a record with a byte too many
  EXPECT_EQ(rdt_record_count(64), 0u);    // deflex's own DFXF datagram on the wrong port
  EXPECT_EQ(rdt_record_count(1476), 0u);  // 41 records: more than the sensor's largest buffer
}

TEST(RdtWire, RecordsOfABufferedDatagramFollowEachOtherAcrossTheWrap) {
  // Three records back to back, rdt_sequence 0xFFFFFFFE, 0xFFFFFFFF, 0 (the wrap), by hand.
  std::vector<unsigned char> d(3 * 36, 0);
  const std::array<std::array<unsigned char, 4>, 3> seq{
      {{0xFF, 0xFF, 0xFF, 0xFE}, {0xFF, 0xFF, 0xFF, 0xFF}, {0, 0, 0, 0}}};
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t b = 0; b < 4; ++b) d[i * 36 + b] = seq[i][b];
    d[i * 36 + 15] = static_cast<unsigned char>(i + 1);  // Fx = 1, 2, 3
  }
  ASSERT_EQ(rdt_record_count(d.size()), 3u);
  RdtRecord r;
  decode_rdt_record(d.data() + 72, r);
  EXPECT_EQ(r.rdt_sequence, 0u);
  EXPECT_EQ(r.counts[0], 3);
  decode_rdt_record(d.data() + 36, r);
  EXPECT_EQ(r.rdt_sequence, 0xFFFFFFFFu);
  EXPECT_EQ(r.counts[0], 2);
}

}  // namespace
}  // namespace deflex
