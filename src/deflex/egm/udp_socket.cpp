// IPv4 UDP socket for the EGM link (see udp_socket.hpp).
#include "deflex/egm/udp_socket.hpp"

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

sockaddr_in make_address(const std::string& address, std::uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (::inet_pton(AF_INET, address.c_str(), &a.sin_addr) != 1) {
    throw InputError(fmt::format("'{}' is not an IPv4 address", address));
  }
  return a;
}

UdpSocket::UdpSocket(const std::string& address, std::uint16_t port) {
  const sockaddr_in addr = make_address(address, port);
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    throw Error(fmt::format("cannot create a UDP socket: {}", std::strerror(errno)));
  }
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    const int err = errno;
    ::close(fd_);
    throw Error(fmt::format("cannot bind UDP {}:{}: {}", address, port, std::strerror(err)));
  }
  sockaddr_in bound{};
  socklen_t len = sizeof(bound);
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&bound), &len);
  port_ = ntohs(bound.sin_port);
}

UdpSocket::~UdpSocket() {
  if (fd_ >= 0) {
    ::close(fd_);
  }
}

bool UdpSocket::wait_readable(double timeout_s) noexcept {
  pollfd p{fd_, POLLIN, 0};
  // NaN and negative: no wait. Beyond INT_MAX ms (24.8 days, or infinite): INT_MAX, since the cast
  // of a larger double to int is undefined (in practice INT_MIN, which poll() takes as "forever").
  constexpr double kMaxMs = std::numeric_limits<int>::max();
  const double ms_wanted = std::ceil(timeout_s * 1000.0);
  const int ms = !(ms_wanted > 0.0) ? 0 : ms_wanted >= kMaxMs ? std::numeric_limits<int>::max()
                                                               : static_cast<int>(ms_wanted);
  return ::poll(&p, 1, ms) > 0 && (p.revents & POLLIN) != 0;
}

long UdpSocket::receive(unsigned char* buffer, std::size_t capacity, sockaddr_in& from) noexcept {
  socklen_t len = sizeof(from);
  const ssize_t n =
      ::recvfrom(fd_, buffer, capacity, MSG_DONTWAIT | MSG_TRUNC, reinterpret_cast<sockaddr*>(&from), &len);
  return n < 0 ? -1 : static_cast<long>(n);
}

bool UdpSocket::send_to(const unsigned char* data, std::size_t size, const sockaddr_in& to) noexcept {
  return ::sendto(fd_, data, size, 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to)) ==
         static_cast<ssize_t>(size);
}

}  // namespace deflex
