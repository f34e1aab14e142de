// The live monitor: a local web page of an online session's forces, corrections, bounds, link health
// and status timeline, served by cpp-httplib on threads of its own. Two routes, both GET: "/" the page
// (one self-contained file: its script, styles and charting library, dygraphs, inline; nothing fetched
// from elsewhere) and "/data?since=N" the rows since N as JSON (monitor_feed.hpp). Everything else is
// 404; nothing the server receives changes the session, and it writes no file. The server's limits
// (MonitorLimits) bound what any number of clients can take: connections, threads, time per request.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "deflex/runtime/monitor_feed.hpp"

namespace deflex::monitor {

namespace detail {
class BoundedHttpServer;
}

/// What the page's server gives any number of clients together. Its threads run at SCHED_IDLE (only on
/// a CPU nothing else wants): however hard the page is used, the session's loop keeps its CPU.
struct MonitorLimits {
  int threads = 8;                       ///< requests served at once
  int max_connections = 64;              ///< sockets open at once (served and waiting); more: 503
  double request_deadline_s = 2.0;       ///< from the connection to the request's last byte
  double answer_deadline_s = 5.0;        ///< from then to the answer's last byte
  std::size_t max_request_bytes = 8192;  ///< the request line and headers (the routes take no body)
};

struct MonitorAddress {
  std::string host = "127.0.0.1";
  int port = 0;  ///< 0: any free port
};

/// "[ADDR:]PORT" (127.0.0.1 when no address is given). An address other than loopback is refused
/// unless `allow_remote` (the page shows the cell's data to anyone who can reach the port). Throws
/// InputError naming `option`.
MonitorAddress parse_monitor_address(const std::string& text, bool allow_remote, const std::string& option);

/// Thread safety: it serves from threads of its own, which only read the feed's published snapshots;
/// the object is made and destroyed on one thread, and port() and url() are immutable.
class MonitorServer {
 public:
  /// Binds now, for this process alone (InputError naming the address when it cannot: in use, by
  /// another session too, or not this host's), serves on threads of its own from then on: one request
  /// a connection, each within the limits' deadlines. Destroying it ends every connection at once.
  MonitorServer(std::shared_ptr<const runtime::MonitorFeed> feed, const MonitorAddress& address,
                const MonitorLimits& limits = {});
  ~MonitorServer();
  MonitorServer(const MonitorServer&) = delete;
  MonitorServer& operator=(const MonitorServer&) = delete;

  [[nodiscard]] int port() const { return port_; }
  /// "http://127.0.0.1:8080/"
  [[nodiscard]] std::string url() const;
  /// Connections answered 503 because max_connections were open.
  [[nodiscard]] std::uint64_t refused() const;

 private:
  std::shared_ptr<const runtime::MonitorFeed> feed_;
  std::string host_;
  int port_ = 0;
  std::unique_ptr<detail::BoundedHttpServer> server_;
  std::thread thread_;
};

/// The page as served (it asks /data for new rows ten times a second), dygraphs inline.
[[nodiscard]] std::string monitor_page();
/// The page with all of the feed's rows written into it: a static file for a commissioning report
/// (no server, no polling; the charts zoom through the whole run).
[[nodiscard]] std::string monitor_report(const runtime::MonitorFeed& feed, const std::string& title);

}  // namespace deflex::monitor
