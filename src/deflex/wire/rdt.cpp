// RDT requests and records, big-endian, byte by byte (see rdt.hpp).
#include "deflex/wire/rdt.hpp"

#include <limits>

#include "deflex/wire/detail/byte_order.hpp"

namespace deflex {
namespace {

// Big-endian fields through the wire module's byte helpers.
constexpr wire_bytes::Order kBe = wire_bytes::Order::kBig;
std::uint32_t read_be32(const unsigned char* p) noexcept { return wire_bytes::load_u32(kBe, p); }
std::uint16_t read_be16(const unsigned char* p) noexcept { return wire_bytes::load_u16(kBe, p); }
void write_be32(std::uint32_t v, unsigned char* p) noexcept { wire_bytes::store_u32(kBe, v, p); }
void write_be16(std::uint16_t v, unsigned char* p) noexcept { wire_bytes::store_u16(kBe, v, p); }

}  // namespace

bool rdt_counts_saturated(const RdtRecord& record) noexcept {
  for (const std::int32_t c : record.counts) {
    if (c == std::numeric_limits<std::int32_t>::max() || c == std::numeric_limits<std::int32_t>::min()) {
      return true;
    }
  }
  return false;
}

void encode_rdt_request(const RdtRequest& request, std::array<unsigned char, kRdtRequestBytes>& out) noexcept {
  write_be16(request.header, out.data());
  write_be16(request.command, out.data() + 2);
  write_be32(request.sample_count, out.data() + 4);
}

bool decode_rdt_request(const unsigned char* data, std::size_t size, RdtRequest& out) noexcept {
  out = RdtRequest{};
  if (size < kRdtRequestBytes) {
    return false;
  }
  out.header = read_be16(data);
  out.command = read_be16(data + 2);
  out.sample_count = read_be32(data + 4);
  return size == kRdtRequestBytes && out.header == kRdtRequestHeader;
}

void encode_rdt_record(const RdtRecord& record, unsigned char* out) noexcept {
  write_be32(record.rdt_sequence, out);
  write_be32(record.ft_sequence, out + 4);
  write_be32(record.status, out + 8);
  for (std::size_t i = 0; i < 6; ++i) {
    // Two's complement on the wire: the int32 goes out as the uint32 of the same bits.
    write_be32(static_cast<std::uint32_t>(record.counts[i]), out + 12 + 4 * i);
  }
}

void decode_rdt_record(const unsigned char* data, RdtRecord& out) noexcept {
  out.rdt_sequence = read_be32(data);
  out.ft_sequence = read_be32(data + 4);
  out.status = read_be32(data + 8);
  for (std::size_t i = 0; i < 6; ++i) {
    // uint32 -> int32 of the same bits (well defined since C++20).
    out.counts[i] = static_cast<std::int32_t>(read_be32(data + 12 + 4 * i));
  }
}

std::size_t rdt_record_count(std::size_t size) noexcept {
  if (size == 0 || size % kRdtRecordBytes != 0 || size > kRdtMaxDatagramBytes) {
    return 0;
  }
  return size / kRdtRecordBytes;
}

}  // namespace deflex
