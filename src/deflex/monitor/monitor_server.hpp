// The live monitor: a local web page of an online session's forces, corrections, bounds and link
// health, served by cpp-httplib on a thread pool of its own. Two routes, both GET: "/" the page (one
// self-contained file: its script and styles inline, nothing fetched from elsewhere) and "/data?since=N"
// the rows since N as JSON (monitor_feed.hpp). Everything else is 404; nothing the server receives
// changes the session, and it writes no file.
#pragma once

#include <memory>
#include <string>
#include <thread>

#include "deflex/runtime/monitor_feed.hpp"

namespace httplib {
class Server;
}

namespace deflex::monitor {

struct MonitorAddress {
  std::string host = "127.0.0.1";
  int port = 0;  ///< 0: any free port
};

/// "[ADDR:]PORT" (127.0.0.1 when no address is given). An address other than loopback is refused
/// unless `allow_remote` (the page shows the cell's data to anyone who can reach the port). Throws
/// InputError naming `option`.
MonitorAddress parse_monitor_address(const std::string& text, bool allow_remote, const std::string& option);

/// Thread safety: it serves from threads of its own, which only read the feed (MonitorFeed locks);
/// the object is made and destroyed on one thread, and port() and url() are immutable.
class MonitorServer {
 public:
  /// Binds now (InputError naming the address when it cannot: in use, not this host's), serves on
  /// threads of its own from then on. A client that stalls is dropped after 2 s without a byte.
  MonitorServer(std::shared_ptr<const runtime::MonitorFeed> feed, const MonitorAddress& address);
  ~MonitorServer();
  MonitorServer(const MonitorServer&) = delete;
  MonitorServer& operator=(const MonitorServer&) = delete;

  [[nodiscard]] int port() const { return port_; }
  /// "http://127.0.0.1:8080/"
  [[nodiscard]] std::string url() const;

 private:
  std::shared_ptr<const runtime::MonitorFeed> feed_;
  std::string host_;
  int port_ = 0;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
};

/// The page as served (it polls /data).
[[nodiscard]] std::string monitor_page();
/// The page with the feed's rows written into it: a static file for a commissioning report (no
/// server, no polling; the time slider scrubs through the run).
[[nodiscard]] std::string monitor_report(const runtime::MonitorFeed& feed, const std::string& title);

}  // namespace deflex::monitor
