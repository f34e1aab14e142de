// The monitor's HTTP server with its limits. cpp-httplib parses requests and routes them; this class
// owns everything a client could use to hold the server up or share its port:
// - the port is this server's alone: cpp-httplib sets SO_REUSEPORT by default, which lets a second
//   process listen on the same port and take half its connections; here only SO_REUSEADDR (on Linux
//   it lets a restarted session bind over connections still in TIME_WAIT, never beside a listener);
// - a few threads at SCHED_IDLE serve the requests (they run only on a CPU nothing else wants, so
//   they can never take one from the session's loop or its reporter);
// - at most `max_connections` sockets are open at once (served or waiting); one more is answered 503
//   and closed at once by the accepting thread;
// - one request a connection, read within a deadline from the connection's accept (a client that
//   drips its request byte by byte is cut off when its time is up) and answered within another;
// - on stop every open connection is shut at once, so stopping never waits for a client.
#pragma once

// Eigen (through monitor_server.hpp) before cpp-httplib: httplib.h brings in <resolv.h>, whose `_res`
// macro breaks Eigen's parameters of that name.
#include "deflex/monitor/monitor_server.hpp"

#include <httplib.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <set>
#include <string>

namespace deflex::monitor::detail {

/// Thread safety: configure (routes, bind) on one thread before listen_after_bind(); stop_all() and
/// refused() from any thread.
class BoundedHttpServer final : public httplib::Server {
 public:
  explicit BoundedHttpServer(const MonitorLimits& limits);
  ~BoundedHttpServer() override;
  BoundedHttpServer(const BoundedHttpServer&) = delete;
  BoundedHttpServer& operator=(const BoundedHttpServer&) = delete;

  /// Binds `host`:`port` (0: any free port) for this server alone: the port bound, or -1.
  int bind_exclusive(const std::string& host, int port);
  /// Accepts and serves until stop_all(), on the calling thread lowered as the serving threads are.
  bool listen_lowered();
  /// Stops accepting and shuts every open connection (their threads end at once).
  void stop_all();
  /// Connections answered 503 because `max_connections` were open.
  [[nodiscard]] std::uint64_t refused() const { return refused_.load(); }
  [[nodiscard]] const MonitorLimits& limits() const { return limits_; }

 private:
  bool process_and_close_socket(socket_t sock) override;
  void refuse(socket_t sock);
  bool track(socket_t sock);
  void untrack(socket_t sock);

  MonitorLimits limits_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> refused_{0};
  std::mutex open_mutex_;
  std::set<socket_t> open_;
};

}  // namespace deflex::monitor::detail
