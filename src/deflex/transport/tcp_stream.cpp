// TCP stream transport (see tcp_stream.hpp) and the wait on two streams (stream_transport.hpp).
#include "deflex/transport/tcp_stream.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

std::string address_text(const sockaddr_in& a) {
  char text[INET_ADDRSTRLEN] = {};
  ::inet_ntop(AF_INET, &a.sin_addr, text, sizeof(text));
  return fmt::format("{}:{}", text, ntohs(a.sin_port));
}

void set_nodelay(int fd) {
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
}

}  // namespace

int poll_timeout_ms(double timeout_s) noexcept {
  constexpr double kMaxMs = std::numeric_limits<int>::max();
  const double ms_wanted = std::ceil(timeout_s * 1000.0);
  if (!(ms_wanted > 0.0)) return 0;
  return ms_wanted >= kMaxMs ? std::numeric_limits<int>::max() : static_cast<int>(ms_wanted);
}

bool wait_readable_any(StreamTransport& a, StreamTransport& b, double timeout_s) noexcept {
  const int fa = a.descriptor(), fb = b.descriptor();
  if (fa < 0 || fb < 0) {
    const bool ra = a.wait_readable(0.0);
    const bool rb = b.wait_readable(0.0);
    return ra || rb;
  }
  pollfd p[2] = {{fa, POLLIN, 0}, {fb, POLLIN, 0}};
  return ::poll(p, 2, poll_timeout_ms(timeout_s)) > 0 &&
         ((p[0].revents | p[1].revents) & (POLLIN | POLLHUP | POLLERR)) != 0;
}

TcpStream::TcpStream(int fd, std::string peer) : fd_(fd), peer_(std::move(peer)) { set_nodelay(fd_); }

TcpStream::~TcpStream() {
  if (fd_ >= 0) ::close(fd_);
}

std::unique_ptr<TcpStream> TcpStream::connect(const std::string& host, std::uint16_t port, double timeout_s) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int gai = ::getaddrinfo(host.c_str(), nullptr, &hints, &found);
  if (gai != 0 || found == nullptr) {
    throw Error(fmt::format("cannot connect to {}:{}: unknown host ({})", host, port, ::gai_strerror(gai)));
  }
  sockaddr_in addr = *reinterpret_cast<const sockaddr_in*>(found->ai_addr);
  ::freeaddrinfo(found);
  addr.sin_port = htons(port);
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) throw Error(fmt::format("cannot create a TCP socket: {}", std::strerror(errno)));
  int err = 0;
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    err = errno;
    if (err == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      const int ready = ::poll(&p, 1, poll_timeout_ms(timeout_s));
      if (ready <= 0) {
        ::close(fd);
        throw Error(fmt::format("cannot connect to {}:{}: no answer within {:g} s (is the server program running?)",
                                host, port, timeout_s));
      }
      socklen_t len = sizeof(err);
      ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
    }
  }
  if (err != 0) {
    ::close(fd);
    throw Error(fmt::format("cannot connect to {}:{}: {}", host, port, std::strerror(err)));
  }
  return std::unique_ptr<TcpStream>(new TcpStream(fd, address_text(addr)));
}

bool TcpStream::wait_readable(double timeout_s) noexcept {
  if (fd_ < 0 || ended_) return true;
  pollfd p{fd_, POLLIN, 0};
  return ::poll(&p, 1, poll_timeout_ms(timeout_s)) > 0 && (p.revents & (POLLIN | POLLHUP | POLLERR)) != 0;
}

long TcpStream::read(unsigned char* buffer, std::size_t capacity) noexcept {
  if (fd_ < 0 || ended_) return kClosed;
  if (capacity == 0) return 0;
  const ssize_t n = ::recv(fd_, buffer, capacity, MSG_DONTWAIT);
  if (n > 0) return static_cast<long>(n);
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return 0;
  ended_ = true;  // 0: the peer closed; < 0: reset or another error
  return kClosed;
}

long TcpStream::write(const unsigned char* data, std::size_t size) noexcept {
  if (fd_ < 0 || ended_) return kClosed;
  if (size == 0) return 0;
  const ssize_t n = ::send(fd_, data, size, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n >= 0) return static_cast<long>(n);
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return 0;
  ended_ = true;
  return kClosed;
}

void TcpStream::close() noexcept {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

TcpListener::TcpListener(const std::string& address, std::uint16_t port) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (::inet_pton(AF_INET, address.c_str(), &addr.sin_addr) != 1) {
    throw InputError(fmt::format("'{}' is not an IPv4 address", address));
  }
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw Error(fmt::format("cannot create a TCP socket: {}", std::strerror(errno)));
  const int one = 1;
  ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0 || ::listen(fd_, 4) != 0) {
    const int err = errno;
    ::close(fd_);
    throw Error(fmt::format("cannot listen on TCP {}:{}: {}", address, port, std::strerror(err)));
  }
  sockaddr_in bound{};
  socklen_t len = sizeof(bound);
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&bound), &len);
  port_ = ntohs(bound.sin_port);
}

TcpListener::~TcpListener() {
  if (fd_ >= 0) ::close(fd_);
}

std::unique_ptr<TcpStream> TcpListener::accept(double timeout_s) {
  pollfd p{fd_, POLLIN, 0};
  if (::poll(&p, 1, poll_timeout_ms(timeout_s)) <= 0) return nullptr;
  sockaddr_in peer{};
  socklen_t len = sizeof(peer);
  const int fd = ::accept4(fd_, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) return nullptr;
  return std::unique_ptr<TcpStream>(new TcpStream(fd, address_text(peer)));
}

}  // namespace deflex
