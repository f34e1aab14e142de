// Protobuf's wire format written by hand, for tests that build EGM packets from the field numbers
// (independent of protoc's generated code): varints, length-delimited fields, little-endian doubles.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

namespace deflex::test {

using Bytes = std::vector<unsigned char>;

inline void varint(Bytes& b, std::uint64_t v) {
  while (v >= 0x80) {
    b.push_back(static_cast<unsigned char>(v | 0x80));
    v >>= 7;
  }
  b.push_back(static_cast<unsigned char>(v));
}

/// Field `field` of wire type 2 holding `body`.
inline void len_field(Bytes& b, int field, const Bytes& body) {
  varint(b, static_cast<std::uint64_t>(field << 3 | 2));
  varint(b, body.size());
  b.insert(b.end(), body.begin(), body.end());
}

/// Field `field` of wire type 1 (a double).
inline void double_field(Bytes& b, int field, double v) {
  varint(b, static_cast<std::uint64_t>(field << 3 | 1));
  unsigned char raw[8];
  std::memcpy(raw, &v, 8);
  b.insert(b.end(), raw, raw + 8);
}

/// Field `field` of wire type 0 (a varint).
inline void varint_field(Bytes& b, int field, std::uint64_t v) {
  varint(b, static_cast<std::uint64_t>(field << 3));
  varint(b, v);
}

}  // namespace deflex::test
