// The controller's side of EGM, for the end-to-end tests and the simulated cell: sends EgmRobot
// messages (feedback and planned joints) to the sensor's address and receives its EgmSensor reply
// (the joints to go to). Not a model of ABB's controller: only its link.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "deflex/egm/egm_codec.hpp"
#include "deflex/egm/udp_socket.hpp"

namespace deflex {

class EgmRobotPeer {
 public:
  /// `joints`: how many joints the messages carry. Binds an ephemeral local port on `local_address`.
  /// Throws Error / InputError.
  EgmRobotPeer(const std::string& sensor_host, std::uint16_t sensor_port, int joints = 6,
               const std::string& local_address = "127.0.0.1");

  /// Sends one EgmRobot message. Never allocates; false on a send error or non-encodable message.
  bool send(const EgmRobotMessage& msg) noexcept;
  /// Sends arbitrary bytes (tests of malformed packets).
  bool send_raw(const unsigned char* data, std::size_t size) noexcept;
  /// Waits up to timeout_s for a reply; false on timeout or an undecodable reply.
  bool receive(EgmSensorMessage& out, double timeout_s) noexcept;

  /// Encodes without sending (tests build truncated packets from it).
  std::size_t encode(const EgmRobotMessage& msg, unsigned char* out, std::size_t capacity) noexcept {
    return codec_.encode_robot(msg, out, capacity);
  }
  [[nodiscard]] std::uint16_t local_port() const { return socket_.port(); }

 private:
  UdpSocket socket_;
  sockaddr_in sensor_{};
  EgmCodec codec_;
  std::vector<unsigned char> buf_;
};

}  // namespace deflex
