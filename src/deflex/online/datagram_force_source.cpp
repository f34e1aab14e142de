// Force samples from deflex force datagrams (see datagram_force_source.hpp).
#include "deflex/online/datagram_force_source.hpp"

#include <array>
#include <cmath>

namespace deflex {

bool DatagramForceSource::latest(ForceSample& out) noexcept {
  std::array<unsigned char, 2 * kForceDatagramBytes> buf{};
  DatagramAddress from;
  ForceDatagram d;
  // Bounded: a flood must not stall the caller's cycle.
  for (int i = 0; i < 256; ++i) {
    const long n = transport_.receive(buf.data(), buf.size(), from);
    if (n < 0) {
      return false;  // nothing new (or a socket error: also nothing usable)
    }
    ++counters_.received;
    if (static_cast<std::size_t>(n) > buf.size() || !decode_force_datagram(buf.data(), static_cast<std::size_t>(n), d)) {
      ++counters_.malformed;
      continue;
    }
    // Wrap-safe ordering: a sample not newer than the last one is dropped. A restarted sender (a jump
    // back to a small sequence number, or a big backwards jump) is accepted.
    const auto diff = static_cast<std::int32_t>(d.sequence - last_sequence_);
    const bool restarted = diff <= -1000 || (d.sequence <= 16 && last_sequence_ > d.sequence + 16);
    if (have_sequence_ && diff <= 0 && !restarted) {
      ++counters_.out_of_order;
      continue;
    }
    have_sequence_ = true;
    last_sequence_ = d.sequence;
    ++counters_.accepted;
    out.t_s = d.t_s;
    out.wrench_sensor = d.wrench_sensor;
    out.valid = std::isfinite(d.t_s) && d.wrench_sensor.allFinite();
    return true;
  }
  return false;
}

}  // namespace deflex
