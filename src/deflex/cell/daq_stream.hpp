// The force sensor's acquisition program on the cell PC (the paper's LabVIEW + NI cDAQ): it streams
// every sample to deflex's force port as a deflex force datagram, with the sensor's own time stamp
// and a sequence number, over the cell's network. The simulated cell feeds deflex exactly the way a
// real DAQ program does: through the wire format, never through deflex's objects.
#pragma once

#include <array>
#include <cstdint>

#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/force_datagram.hpp"

namespace deflex::cell {

/// Thread safety: one thread at a time (the simulation's), with its transport.
class DaqStream {
 public:
  /// `transport` must outlive the stream; samples go to `deflex_force_port`.
  DaqStream(DatagramTransport& transport, const DatagramAddress& deflex_force_port)
      : transport_(transport), to_(deflex_force_port) {}

  /// Sends one 3-component sample (N, sensor frame) taken at the sensor's time t_s.
  void send(double t_s, const Vector3& force_sensor_n) noexcept {
    ForceDatagram d;
    d.sequence = ++sequence_;
    d.t_s = t_s;
    d.wrench_sensor.head<3>() = force_sensor_n;
    encode_force_datagram(d, buffer_);
    if (!transport_.send_to(buffer_.data(), buffer_.size(), to_)) ++send_errors_;
  }
  [[nodiscard]] std::uint32_t sent() const { return sequence_; }
  [[nodiscard]] std::uint64_t send_errors() const { return send_errors_; }

 private:
  DatagramTransport& transport_;
  DatagramAddress to_;
  std::uint32_t sequence_ = 0;
  std::uint64_t send_errors_ = 0;
  std::array<unsigned char, kForceDatagramBytes> buffer_{};
};

}  // namespace deflex::cell
