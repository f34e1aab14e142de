// A test RDT sensor on the in-memory network, written from the manuals and independent of deflex's
// RDT code: it reads requests and writes records byte by byte itself. It answers the last requester,
// restarts rdt_sequence at 1 for each request, counts ft_sequence from its power-up (not reset by a
// request), packs `buffer` records a datagram in buffered mode, stops on 0x0000, and can drop,
// duplicate, swap, flag, saturate or withhold records, go quiet (a stall) and power-cycle.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <set>
#include <vector>

#include "deflex/sensors/rdt_calibration.hpp"
#include "deflex/transport/memory_network.hpp"

namespace deflex::test {

/// A calibration for tests: `counts_per_force` counts a newton, `counts_per_torque` a newton-metre.
inline RdtCalibration test_rdt_calibration(double rate_hz, double counts_per_force = 1000000.0,
                                           double counts_per_torque = 100000.0) {
  RdtCalibration c;
  c.source = "test";
  c.counts_per_force = counts_per_force;
  c.counts_per_torque = counts_per_torque;
  c.force_unit = "N";
  c.torque_unit = "Nm";
  c.rate_hz = rate_hz;
  return c;
}

class RdtTestSensor {
 public:
  RdtTestSensor(MemoryNetwork& network, const DatagramAddress& address, double rate_hz)
      : endpoint_(network.add_endpoint(address)), rate_hz_(rate_hz) {}

  // What it measures: counts of internal sample i (default: a constant).
  std::function<std::array<std::int32_t, 6>(std::uint64_t)> counts_of = [](std::uint64_t) {
    return std::array<std::int32_t, 6>{1000000, -2000000, 3000000, 40000, -50000, 60000};
  };
  int buffer = 10;              // records a datagram in buffered mode
  std::uint32_t ft_step = 1;    // ft_sequence counts a record (internal rate / RDT rate)
  std::uint32_t ft_start = 0;   // ft_sequence at power-up
  std::uint32_t rdt_start = 1;  // the manuals: 1 (a test may start near the wrap)
  // Faults, by the index of the record among all records produced for a client (0, 1, ...).
  std::set<std::uint64_t> drop, duplicate, swap_with_next, saturate;
  std::set<std::uint64_t> flag;  // status word set
  std::uint32_t status_word = 0x00010000;
  bool quiet = false;  // the network is cut: records and requests are lost

  // What it was asked.
  struct Request {
    std::array<unsigned char, 8> bytes{};
    DatagramAddress from;
  };
  std::vector<Request> requests;
  std::uint64_t produced = 0, sent_records = 0, datagrams = 0, requests_ignored = 0;
  DatagramAddress target;
  bool streaming = false;

  [[nodiscard]] DatagramAddress address() const { return endpoint_.local_address(); }

  /// Reads requests and sends every record due by `now_s` (the network's clock).
  void tick(double now_s) {
    std::array<unsigned char, 64> in{};
    DatagramAddress from;
    long n = 0;
    while ((n = endpoint_.receive(in.data(), in.size(), from)) >= 0) {
      if (quiet) continue;
      handle(in.data(), static_cast<std::size_t>(n), from, now_s);
    }
    const auto due = static_cast<std::uint64_t>(std::floor((now_s - power_up_s_) * rate_hz_ + 1e-9));
    while (streaming && next_sample_ <= due) {
      emit(next_sample_++);
    }
    if (!streaming) next_sample_ = due + 1;
  }

  /// Numbers the next record rdt_start again, with no request (as if another program had asked).
  void renumber() { rdt_ = rdt_start; }

  /// A power cycle: forgets the client, stops streaming, the ft counter starts again from 0.
  void power_cycle(double now_s) {
    streaming = false;
    ft_start = 0;
    power_up_s_ = now_s;
    next_sample_ = 0;
    pending_.clear();
  }

 private:
  static void put_be32(std::vector<unsigned char>& out, std::uint32_t v) {
    out.push_back(static_cast<unsigned char>(v >> 24));
    out.push_back(static_cast<unsigned char>(v >> 16));
    out.push_back(static_cast<unsigned char>(v >> 8));
    out.push_back(static_cast<unsigned char>(v));
  }

  void handle(const unsigned char* b, std::size_t n, const DatagramAddress& from, double now_s) {
    if (n != 8 || b[0] != 0x12 || b[1] != 0x34) {
      ++requests_ignored;
      return;
    }
    Request r;
    for (std::size_t i = 0; i < 8; ++i) r.bytes[i] = b[i];
    r.from = from;
    requests.push_back(r);
    const unsigned command = static_cast<unsigned>(b[2]) << 8 | b[3];
    if (command == 0x0002 || command == 0x0003) {
      target = from;  // the last requester takes the stream
      streaming = true;
      buffered_ = command == 0x0003;
      rdt_ = rdt_start;
      pending_.clear();
      next_sample_ = static_cast<std::uint64_t>(std::floor((now_s - power_up_s_) * rate_hz_ + 1e-9)) + 1;
    } else if (command == 0x0000) {
      streaming = false;
      pending_.clear();
    }
  }

  void emit(std::uint64_t sample) {
    const std::uint64_t k = produced++;
    std::array<std::int32_t, 6> c = counts_of(sample);
    if (saturate.count(k) != 0) c[2] = 2147483647;
    std::vector<unsigned char> rec;
    put_be32(rec, rdt_++);
    put_be32(rec, static_cast<std::uint32_t>(ft_start + sample * ft_step));
    put_be32(rec, flag.count(k) != 0 ? status_word : 0u);
    for (const std::int32_t v : c) put_be32(rec, static_cast<std::uint32_t>(v));
    if (drop.count(k) != 0 || quiet) return;
    ++sent_records;
    pending_.insert(pending_.end(), rec.begin(), rec.end());
    const std::size_t per = buffered_ ? static_cast<std::size_t>(buffer) : 1;
    if (pending_.size() < per * 36) return;
    std::vector<unsigned char> datagram;
    datagram.swap(pending_);
    if (swap_with_next.count(k) != 0) {
      held_ = datagram;
      return;
    }
    send(datagram);
    if (duplicate.count(k) != 0) send(datagram);
    if (!held_.empty()) {
      send(held_);
      held_.clear();
    }
  }

  void send(const std::vector<unsigned char>& d) {
    ++datagrams;
    endpoint_.send_to(d.data(), d.size(), target);
  }

  MemoryTransport& endpoint_;
  double rate_hz_;
  double power_up_s_ = 0.0;
  std::uint64_t next_sample_ = 0;
  std::uint32_t rdt_ = 1;
  bool buffered_ = false;
  std::vector<unsigned char> pending_, held_;
};

}  // namespace deflex::test
