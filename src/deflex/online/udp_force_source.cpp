// UDP force-sample stream (format in udp_force_source.hpp and docs/online.md).
#include "deflex/online/udp_force_source.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

static_assert(std::endian::native == std::endian::little, "the datagram format is little-endian");

namespace {
constexpr unsigned char kMagic[4] = {'D', 'F', 'X', 'F'};
}

void encode_force_datagram(const ForceSample& sample, std::uint32_t sequence,
                           std::array<unsigned char, kForceDatagramBytes>& out) noexcept {
  std::memcpy(out.data(), kMagic, 4);
  std::memcpy(out.data() + 4, &sequence, 4);
  std::memcpy(out.data() + 8, &sample.t_s, 8);
  for (int i = 0; i < 6; ++i) {
    const double v = sample.wrench_sensor[i];
    std::memcpy(out.data() + 16 + 8 * i, &v, 8);
  }
}

bool decode_force_datagram(const unsigned char* data, std::size_t size, ForceSample& out,
                           std::uint32_t& sequence) noexcept {
  if (size != kForceDatagramBytes || std::memcmp(data, kMagic, 4) != 0) {
    return false;
  }
  std::memcpy(&sequence, data + 4, 4);
  std::memcpy(&out.t_s, data + 8, 8);
  for (int i = 0; i < 6; ++i) {
    double v = 0.0;
    std::memcpy(&v, data + 16 + 8 * i, 8);
    out.wrench_sensor[i] = v;
  }
  out.valid = std::isfinite(out.t_s) && out.wrench_sensor.allFinite();
  return true;
}

UdpForceSource::UdpForceSource(std::uint16_t port, const std::string& bind_address) {
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    throw Error(fmt::format("force source: cannot create a UDP socket: {}", std::strerror(errno)));
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (::inet_pton(AF_INET, bind_address.c_str(), &addr.sin_addr) != 1) {
    ::close(fd_);
    throw InputError(fmt::format("force source: '{}' is not an IPv4 address", bind_address));
  }
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    const int err = errno;
    ::close(fd_);
    throw Error(fmt::format("force source: cannot bind UDP {}:{}: {}", bind_address, port, std::strerror(err)));
  }
  socklen_t len = sizeof(addr);
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
}

UdpForceSource::~UdpForceSource() {
  if (fd_ >= 0) {
    ::close(fd_);
  }
}

bool UdpForceSource::latest(ForceSample& out) noexcept {
  std::array<unsigned char, 2 * kForceDatagramBytes> buf{};
  // Bounded: a flood must not stall the caller's cycle.
  for (int i = 0; i < 256; ++i) {
    const ssize_t n = ::recv(fd_, buf.data(), buf.size(), MSG_DONTWAIT | MSG_TRUNC);
    if (n < 0) {
      return false;  // EAGAIN: nothing new (or a socket error: also nothing usable)
    }
    ++counters_.received;
    std::uint32_t seq = 0;
    if (static_cast<std::size_t>(n) > buf.size() ||
        !decode_force_datagram(buf.data(), static_cast<std::size_t>(n), out, seq)) {
      ++counters_.malformed;
      continue;
    }
    // Wrap-safe ordering: a sample not newer than the last one is dropped. A restarted sender (a jump
    // back to a small sequence number, or a big backwards jump) is accepted.
    const auto diff = static_cast<std::int32_t>(seq - last_sequence_);
    const bool restarted = diff <= -1000 || (seq <= 16 && last_sequence_ > seq + 16);
    if (have_sequence_ && diff <= 0 && !restarted) {
      ++counters_.out_of_order;
      continue;
    }
    have_sequence_ = true;
    last_sequence_ = seq;
    ++counters_.accepted;
    return true;
  }
  return false;
}

}  // namespace deflex
