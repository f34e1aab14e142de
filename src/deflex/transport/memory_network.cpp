// In-memory datagram network (see memory_network.hpp).
#include "deflex/transport/memory_network.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

MemoryTransport::MemoryTransport(MemoryNetwork& network, const DatagramAddress& address, double latency_s,
                                 std::size_t depth, std::size_t max_bytes)
    : network_(network), address_(address), latency_s_(latency_s), slots_(depth) {
  for (Slot& s : slots_) {
    s.bytes.assign(max_bytes, 0);
  }
}

bool MemoryTransport::wait_readable(double /*timeout_s*/) noexcept {
  return count_ > 0 && slots_[head_].deliver_at_s <= network_.clock().now_s();
}

long MemoryTransport::receive(unsigned char* buffer, std::size_t capacity, DatagramAddress& from) noexcept {
  if (!wait_readable(0.0)) {
    return -1;
  }
  const Slot& s = slots_[head_];
  std::memcpy(buffer, s.bytes.data(), std::min(capacity, s.size));
  from = s.from;
  receipt_s_ = s.deliver_at_s;
  const auto size = static_cast<long>(s.size);
  head_ = (head_ + 1) % slots_.size();
  --count_;
  ++network_.counters_.delivered;
  return size;
}

double MemoryTransport::since_receipt_s() const noexcept { return network_.clock().now_s() - receipt_s_; }

bool MemoryTransport::send_to(const unsigned char* data, std::size_t size, const DatagramAddress& to) noexcept {
  return network_.route(data, size, address_, to, latency_s_);
}

bool MemoryTransport::enqueue(const unsigned char* data, std::size_t size, const DatagramAddress& from,
                              double deliver_at_s) noexcept {
  if (count_ == slots_.size()) {
    return false;
  }
  Slot& s = slots_[(head_ + count_) % slots_.size()];
  std::memcpy(s.bytes.data(), data, size);
  s.size = size;
  s.from = from;
  s.deliver_at_s = deliver_at_s;
  ++count_;
  return true;
}

MemoryNetwork::MemoryNetwork(const Clock& clock, std::size_t max_datagram_bytes, std::size_t queue_depth)
    : clock_(clock), max_bytes_(max_datagram_bytes), depth_(queue_depth) {
  if (max_bytes_ == 0 || max_bytes_ > 65507 || depth_ == 0 || depth_ > 1'000'000) {
    throw InputError("memory network: datagram size must be 1..65507 bytes and the queue depth 1..1000000");
  }
}

MemoryTransport& MemoryNetwork::add_endpoint(const DatagramAddress& address, double latency_s) {
  if (!std::isfinite(latency_s) || latency_s < 0.0) {
    throw InputError(fmt::format("memory network: latency of {} must be finite and >= 0 s", to_string(address)));
  }
  for (const auto& e : endpoints_) {
    if (e->local_address() == address) {
      throw InputError(fmt::format("memory network: address {} is taken", to_string(address)));
    }
  }
  endpoints_.push_back(
      std::unique_ptr<MemoryTransport>(new MemoryTransport(*this, address, latency_s, depth_, max_bytes_)));
  return *endpoints_.back();
}

void MemoryNetwork::add_outage(double from_s, double to_s, const DatagramAddress& address) {
  if (!std::isfinite(from_s) || !std::isfinite(to_s) || !(to_s > from_s)) {
    throw InputError("memory network: an outage needs a finite start before its end");
  }
  outages_.push_back(Outage{from_s, to_s, address});
}

bool MemoryNetwork::route(const unsigned char* data, std::size_t size, const DatagramAddress& from,
                          const DatagramAddress& to, double latency_s) noexcept {
  if (size > max_bytes_) {
    ++counters_.dropped_oversized;
    return false;
  }
  const double now = clock_.now_s();
  for (const Outage& o : outages_) {
    if (now >= o.from_s && now < o.to_s && (o.address == DatagramAddress{} || o.address == from || o.address == to)) {
      ++counters_.dropped_outage;  // the cable is out: sent, and lost
      return true;
    }
  }
  for (Reordering& r : reorderings_) {
    if (now < r.from_s || !(r.from == from) || (r.count == 0 && r.held.empty())) continue;
    if (r.count > 0) {  // held back: the next datagram overtakes it
      --r.count;
      r.held.push_back(Held{std::vector<unsigned char>(data, data + size), from, to, latency_s});
      return true;
    }
    const bool routed = deliver(data, size, from, to, latency_s);
    for (const Held& h : r.held) (void)deliver(h.bytes.data(), h.bytes.size(), h.from, h.to, h.latency_s);
    r.held.clear();
    return routed;
  }
  return deliver(data, size, from, to, latency_s);
}

void MemoryNetwork::add_reordering(double from_s, int count, const DatagramAddress& from) {
  if (count < 1 || !std::isfinite(from_s)) throw InputError("memory network: a reordering needs a count >= 1");
  reorderings_.push_back(Reordering{from_s, count, from, {}});
}

bool MemoryNetwork::deliver(const unsigned char* data, std::size_t size, const DatagramAddress& from,
                            const DatagramAddress& to, double latency_s) noexcept {
  for (const auto& e : endpoints_) {
    if (e->local_address() == to) {
      // Like UDP, a datagram the receiver has no room for is lost after it was sent: the sender
      // learns nothing.
      if (!e->enqueue(data, size, from, clock_.now_s() + latency_s)) {
        ++counters_.dropped_full;
      }
      return true;
    }
  }
  ++counters_.dropped_no_route;  // sent into the void, as UDP to a port nobody listens on
  return true;
}

}  // namespace deflex
