// The controller side of the EGM link (see egm_robot_peer.hpp).
#include "deflex/egm/egm_robot_peer.hpp"

#include <chrono>

namespace deflex {

EgmRobotPeer::EgmRobotPeer(const std::string& sensor_host, std::uint16_t sensor_port, int joints,
                           const std::string& local_address)
    : socket_(local_address, 0), sensor_(make_address(sensor_host, sensor_port)), codec_(joints), buf_(2048, 0) {}

bool EgmRobotPeer::send(const EgmRobotMessage& msg) noexcept {
  const std::size_t n = codec_.encode_robot(msg, buf_.data(), buf_.size());
  return n > 0 && socket_.send_to(buf_.data(), n, sensor_);
}

bool EgmRobotPeer::send_raw(const unsigned char* data, std::size_t size) noexcept {
  return socket_.send_to(data, size, sensor_);
}

bool EgmRobotPeer::receive(EgmSensorMessage& out, double timeout_s) noexcept {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left < 0.0 || !socket_.wait_readable(left)) {
      return false;
    }
    sockaddr_in from{};
    const long n = socket_.receive(buf_.data(), buf_.size(), from);
    if (n < 0) {
      continue;
    }
    return static_cast<std::size_t>(n) <= buf_.size() && codec_.decode_sensor(buf_.data(), static_cast<std::size_t>(n), out);
  }
}

}  // namespace deflex
