// Force samples from deflex force datagrams (see datagram_force_source.hpp).
#include "deflex/sensors/datagram_force_source.hpp"

#include <array>
#include <cmath>

namespace deflex {

SequenceRules force_sequence_rules() {
  SequenceRules r;
  r.bits = 32;
  r.max_ahead = 100;
  r.restart_max = 16;
  r.confirm = 3;
  return r;
}

ForceSourceStats DatagramForceSource::stats() const noexcept {
  ForceSourceStats s;
  s.received = counters_.received;
  s.accepted = counters_.accepted;
  s.malformed = counters_.malformed + counters_.far_ahead;
  s.out_of_order = counters_.out_of_order;
  s.restarts = counters_.restarts;
  return s;
}

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
    if (static_cast<std::size_t>(n) > buf.size() ||
        !decode_force_datagram(buf.data(), static_cast<std::size_t>(n), d)) {
      ++counters_.malformed;
      continue;
    }
    switch (sequence_.observe(d.sequence)) {
      case SequenceVerdict::kDuplicate:
      case SequenceVerdict::kOutOfOrder:
        ++counters_.out_of_order;
        continue;
      case SequenceVerdict::kFarAhead:
        ++counters_.far_ahead;
        continue;
      case SequenceVerdict::kRestart:
        ++counters_.restarts;
        break;
      case SequenceVerdict::kFirst:
      case SequenceVerdict::kNext:
        break;
    }
    ++counters_.accepted;
    out.t_s = d.t_s;
    out.wrench_sensor = d.wrench_sensor;
    out.valid = std::isfinite(d.t_s) && d.wrench_sensor.allFinite();
    return true;
  }
  return false;
}

}  // namespace deflex
