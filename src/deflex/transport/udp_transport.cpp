// IPv4 UDP datagram transport (see udp_transport.hpp).
#include "deflex/transport/udp_transport.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

sockaddr_in to_sockaddr(const DatagramAddress& a) {
  sockaddr_in s{};
  s.sin_family = AF_INET;
  s.sin_port = htons(a.port);
  s.sin_addr.s_addr = htonl(a.ipv4);
  return s;
}

}  // namespace

DatagramAddress make_datagram_address(const std::string& ipv4, std::uint16_t port) {
  in_addr a{};
  if (::inet_pton(AF_INET, ipv4.c_str(), &a) != 1) {
    throw InputError(fmt::format("'{}' is not an IPv4 address", ipv4));
  }
  return DatagramAddress{ntohl(a.s_addr), port};
}

std::string to_string(const DatagramAddress& address) {
  return fmt::format("{}.{}.{}.{}:{}", (address.ipv4 >> 24) & 0xff, (address.ipv4 >> 16) & 0xff,
                     (address.ipv4 >> 8) & 0xff, address.ipv4 & 0xff, address.port);
}

UdpTransport::UdpTransport(const std::string& address, std::uint16_t port) {
  const sockaddr_in addr = to_sockaddr(make_datagram_address(address, port));
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    throw Error(fmt::format("cannot create a UDP socket: {}", std::strerror(errno)));
  }
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    const int err = errno;
    ::close(fd_);
    throw Error(fmt::format("cannot bind UDP {}:{}: {}", address, port, std::strerror(err)));
  }
  // The kernel's receive time stamp of every datagram (CLOCK_REALTIME): a link's answer time then
  // includes the time the datagram waited for the program to be scheduled.
  const int on = 1;
  stamped_ = ::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof(on)) == 0;
  sockaddr_in bound{};
  socklen_t len = sizeof(bound);
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&bound), &len);
  local_ = DatagramAddress{ntohl(bound.sin_addr.s_addr), ntohs(bound.sin_port)};
}

UdpTransport::~UdpTransport() {
  if (fd_ >= 0) {
    ::close(fd_);
  }
}

bool UdpTransport::wait_readable(double timeout_s) noexcept {
  pollfd p{fd_, POLLIN, 0};
  // NaN and negative: no wait. Beyond INT_MAX ms (24.8 days, or infinite): INT_MAX, since the cast
  // of a larger double to int is undefined (in practice INT_MIN, which poll() takes as "forever").
  constexpr double kMaxMs = std::numeric_limits<int>::max();
  const double ms_wanted = std::ceil(timeout_s * 1000.0);
  const int ms = !(ms_wanted > 0.0)    ? 0
                 : ms_wanted >= kMaxMs ? std::numeric_limits<int>::max()
                                       : static_cast<int>(ms_wanted);
  return ::poll(&p, 1, ms) > 0 && (p.revents & POLLIN) != 0;
}

long UdpTransport::receive(unsigned char* buffer, std::size_t capacity, DatagramAddress& from) noexcept {
  sockaddr_in s{};
  iovec iov{buffer, capacity};
  alignas(cmsghdr) unsigned char control[CMSG_SPACE(sizeof(timespec))];
  msghdr m{};
  m.msg_name = &s;
  m.msg_namelen = sizeof(s);
  m.msg_iov = &iov;
  m.msg_iovlen = 1;
  m.msg_control = control;
  m.msg_controllen = sizeof(control);
  const ssize_t n = ::recvmsg(fd_, &m, MSG_DONTWAIT | MSG_TRUNC);
  if (n < 0) {
    return -1;
  }
  receipt_ns_ = -1;
  for (cmsghdr* c = CMSG_FIRSTHDR(&m); c != nullptr; c = CMSG_NXTHDR(&m, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec ts{};
      std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
      receipt_ns_ = static_cast<long long>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
    }
  }
  from = DatagramAddress{ntohl(s.sin_addr.s_addr), ntohs(s.sin_port)};
  return static_cast<long>(n);
}

double UdpTransport::since_receipt_s() const noexcept {
  if (receipt_ns_ < 0) return std::numeric_limits<double>::quiet_NaN();
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  const long long now_ns = static_cast<long long>(now.tv_sec) * 1000000000LL + now.tv_nsec;
  return static_cast<double>(now_ns - receipt_ns_) * 1e-9;
}

bool UdpTransport::send_to(const unsigned char* data, std::size_t size, const DatagramAddress& to) noexcept {
  const sockaddr_in s = to_sockaddr(to);
  return ::sendto(fd_, data, size, 0, reinterpret_cast<const sockaddr*>(&s), sizeof(s)) == static_cast<ssize_t>(size);
}

}  // namespace deflex
