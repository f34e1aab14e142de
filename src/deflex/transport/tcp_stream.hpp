// A stream transport over a TCP connection (IPv4): the client side for deflex (the robot program is
// the server: ROS-Industrial's motion and state servers listen on the controller), and a listener for
// the stand-in servers in tests and simulations. Non-blocking once connected; small frames leave at once
// (TCP_NODELAY). Owns its descriptor; only construction, connect and accept throw or allocate.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "deflex/transport/stream_transport.hpp"

namespace deflex {

/// Thread safety: one thread at a time (a read or write that finds the connection over marks it
/// ended).
class TcpStream final : public StreamTransport {
 public:
  /// Connects to `host` (a name or an IPv4 address) at `port`, waiting up to `timeout_s`. Throws Error
  /// naming host:port and why (refused, timed out, unknown host).
  [[nodiscard]] static std::unique_ptr<TcpStream> connect(const std::string& host, std::uint16_t port,
                                                          double timeout_s);
  ~TcpStream() override;
  TcpStream(const TcpStream&) = delete;
  TcpStream& operator=(const TcpStream&) = delete;

  bool wait_readable(double timeout_s) noexcept override;
  long read(unsigned char* buffer, std::size_t capacity) noexcept override;
  long write(const unsigned char* data, std::size_t size) noexcept override;
  void close() noexcept override;
  [[nodiscard]] bool is_open() const noexcept override { return fd_ >= 0 && !ended_; }
  [[nodiscard]] int descriptor() const noexcept override { return fd_; }
  /// "127.0.0.1:11000", the other end.
  [[nodiscard]] const std::string& peer() const { return peer_; }

 private:
  friend class TcpListener;
  TcpStream(int fd, std::string peer);
  int fd_ = -1;
  bool ended_ = false;  // the peer closed or the connection broke
  std::string peer_;
};

/// Thread safety: one thread at a time.
class TcpListener {
 public:
  /// Listens on `address:port` (port 0: ephemeral, read it back with port()). Throws Error naming the
  /// address on failure, InputError when `address` is not IPv4.
  TcpListener(const std::string& address, std::uint16_t port);
  ~TcpListener();
  TcpListener(const TcpListener&) = delete;
  TcpListener& operator=(const TcpListener&) = delete;

  [[nodiscard]] std::uint16_t port() const { return port_; }
  /// Waits up to `timeout_s` for a client; null when none came.
  [[nodiscard]] std::unique_ptr<TcpStream> accept(double timeout_s);

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
};

}  // namespace deflex
