// deflex's force-sample datagram (see force_datagram.hpp).
#include "deflex/wire/force_datagram.hpp"

#include <bit>
#include <cstring>

namespace deflex {

static_assert(std::endian::native == std::endian::little, "the datagram format is little-endian");

namespace {
constexpr unsigned char kMagic[4] = {'D', 'F', 'X', 'F'};
}

void encode_force_datagram(const ForceDatagram& sample, std::array<unsigned char, kForceDatagramBytes>& out) noexcept {
  std::memcpy(out.data(), kMagic, 4);
  std::memcpy(out.data() + 4, &sample.sequence, 4);
  std::memcpy(out.data() + 8, &sample.t_s, 8);
  for (int i = 0; i < 6; ++i) {
    const double v = sample.wrench_sensor[i];
    std::memcpy(out.data() + 16 + 8 * static_cast<std::size_t>(i), &v, 8);
  }
}

bool decode_force_datagram(const unsigned char* data, std::size_t size, ForceDatagram& out) noexcept {
  if (size != kForceDatagramBytes || std::memcmp(data, kMagic, 4) != 0) {
    return false;
  }
  std::memcpy(&out.sequence, data + 4, 4);
  std::memcpy(&out.t_s, data + 8, 8);
  for (int i = 0; i < 6; ++i) {
    double v = 0.0;
    std::memcpy(&v, data + 16 + 8 * static_cast<std::size_t>(i), 8);
    out.wrench_sensor[i] = v;
  }
  return true;
}

}  // namespace deflex
