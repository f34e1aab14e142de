// The live monitor's server (see monitor_server.hpp).
#include "deflex/monitor/monitor_server.hpp"

#include <arpa/inet.h>

#include <chrono>
#include <thread>

#include <fmt/format.h>
#include <httplib.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {
extern const char* const kMonitorPageHtml;
}

namespace deflex::monitor {
namespace {

bool is_loopback(const std::string& host) {
  if (host == "localhost" || host == "::1") return true;
  in_addr a{};
  if (inet_pton(AF_INET, host.c_str(), &a) != 1) return false;
  return (ntohl(a.s_addr) >> 24) == 127;
}

}  // namespace

MonitorAddress parse_monitor_address(const std::string& text, bool allow_remote, const std::string& option) {
  MonitorAddress a;
  std::string port_text = text;
  const auto colon = text.rfind(':');
  if (colon != std::string::npos) {
    a.host = text.substr(0, colon);
    port_text = text.substr(colon + 1);
    if (a.host.empty()) throw InputError(fmt::format("option {} '{}': an empty address before ':'", option, text));
  }
  const auto port = parse_int64(port_text);
  if (!port || *port < 0 || *port > 65535) {
    throw InputError(fmt::format("option {} '{}': the port must be a number 0..65535 ([ADDR:]PORT)", option, text));
  }
  a.port = static_cast<int>(*port);
  in_addr probe{};
  if (a.host != "localhost" && inet_pton(AF_INET, a.host.c_str(), &probe) != 1) {
    throw InputError(fmt::format("option {} '{}': '{}' is not an IPv4 address", option, text, a.host));
  }
  if (!allow_remote && !is_loopback(a.host)) {
    throw InputError(
        fmt::format("option {} '{}': {} is reachable from other hosts; the page shows the cell's data "
                    "to anyone who can reach it: add --monitor-remote to allow that",
                    option, text, a.host));
  }
  return a;
}

MonitorServer::MonitorServer(std::shared_ptr<const runtime::MonitorFeed> feed, const MonitorAddress& address)
    : feed_(std::move(feed)), host_(address.host), server_(std::make_unique<httplib::Server>()) {
  server_->set_read_timeout(2, 0);
  server_->set_write_timeout(2, 0);
  server_->set_keep_alive_timeout(2);
  server_->set_payload_max_length(4096);  // a request carries nothing the server uses
  const std::string page = monitor_page();
  server_->Get("/", [page](const httplib::Request&, httplib::Response& res) {
    res.set_content(page, "text/html; charset=utf-8");
    res.set_header("Cache-Control", "no-store");
  });
  server_->Get("/data", [feed = feed_](const httplib::Request& req, httplib::Response& res) {
    std::uint64_t since = 0;
    if (req.has_param("since")) {
      const auto v = parse_int64(req.get_param_value("since"));
      if (!v || *v < 0) {
        res.status = 400;
        res.set_content("since: a row number >= 0", "text/plain");
        return;
      }
      since = static_cast<std::uint64_t>(*v);
    }
    res.set_content(feed->json(since), "application/json");
    res.set_header("Cache-Control", "no-store");
  });
  const std::string host = address.host == "localhost" ? "127.0.0.1" : address.host;
  if (address.port == 0) {
    port_ = server_->bind_to_any_port(host);
  } else {
    port_ = server_->bind_to_port(host, address.port) ? address.port : -1;
  }
  if (port_ <= 0) {
    throw InputError(fmt::format("option --monitor: cannot listen on {}:{} (in use, or not an address of this host)",
                                 host, address.port));
  }
  thread_ = std::thread([this] { server_->listen_after_bind(); });
  // Until the server runs, stop() would not reach it (and the destructor's join would wait forever).
  for (int i = 0; i < 2000 && !server_->is_running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

MonitorServer::~MonitorServer() {
  server_->stop();
  if (thread_.joinable()) thread_.join();
}

std::string MonitorServer::url() const { return fmt::format("http://{}:{}/", host_, port_); }

std::string monitor_page() { return kMonitorPageHtml; }

std::string monitor_report(const runtime::MonitorFeed& feed, const std::string& title) {
  std::string page = monitor_page();
  std::string data = feed.json(0);
  // Inside a <script> element: "</" would end it.
  std::string safe;
  safe.reserve(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (data[i] == '<') {
      safe += "\\u003c";
    } else {
      safe += data[i];
    }
  }
  // The title as a JavaScript string inside a <script> element.
  std::string escaped_title;
  for (char c : title) {
    if (c == '"' || c == '\\') {
      escaped_title += '\\';
      escaped_title += c;
    } else if (c == '<') {
      escaped_title += "\\u003c";
    } else if (static_cast<unsigned char>(c) >= 0x20) {
      escaped_title += c;
    }
  }
  const std::string marker = "<!--DEFLEX_STATIC_DATA-->";
  const auto at = page.find(marker);
  if (at != std::string::npos) {
    page.replace(
        at, marker.size(),
        fmt::format("<script>window.DEFLEX_STATIC = {};\nwindow.DEFLEX_TITLE = \"{}\";</script>", safe, escaped_title));
  }
  return page;
}

}  // namespace deflex::monitor
