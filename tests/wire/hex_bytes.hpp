// Datagrams written by hand in tests: "00 00 00 01  3F 80 00 00" -> bytes, so a test states the wire
// image it expects from the protocol's tables, independently of the codec's own byte helpers.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace deflex::test {

using Bytes = std::vector<unsigned char>;

/// Hex pairs, any whitespace between them; throws std::invalid_argument on anything else.
inline Bytes hex(std::string_view text) {
  Bytes out;
  int high = -1;
  for (const char c : text) {
    if (c == ' ' || c == '\n' || c == '\t') continue;
    int v = -1;
    if (c >= '0' && c <= '9') v = c - '0';
    if (c >= 'A' && c <= 'F') v = c - 'A' + 10;
    if (c >= 'a' && c <= 'f') v = c - 'a' + 10;
    if (v < 0) throw std::invalid_argument("not a hex digit in a test's bytes");
    if (high < 0) {
      high = v;
    } else {
      out.push_back(static_cast<unsigned char>(high * 16 + v));
      high = -1;
    }
  }
  if (high >= 0) throw std::invalid_argument("odd number of hex digits in a test's bytes");
  return out;
}

/// `bytes` with `n` zero bytes appended.
inline Bytes zeros_after(Bytes bytes, std::size_t n) {
  bytes.insert(bytes.end(), n, 0);
  return bytes;
}

}  // namespace deflex::test
