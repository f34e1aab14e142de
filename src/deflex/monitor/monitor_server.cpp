// The live monitor's server (see monitor_server.hpp).
#include "deflex/monitor/monitor_server.hpp"

#include <arpa/inet.h>

#include <chrono>
#include <thread>

#include <fmt/format.h>
#include <httplib.h>

#include "deflex/monitor/detail/bounded_http_server.hpp"

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {
extern const char* const kMonitorPageHtml;
extern const char* const kDygraphsJs;
extern const char* const kDygraphsCss;
}  // namespace deflex

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

MonitorServer::MonitorServer(std::shared_ptr<const runtime::MonitorFeed> feed, const MonitorAddress& address,
                             const MonitorLimits& limits)
    : feed_(std::move(feed)), host_(address.host), server_(std::make_unique<detail::BoundedHttpServer>(limits)) {
  const auto page = std::make_shared<const std::string>(monitor_page());
  server_->Get("/", [page](const httplib::Request&, httplib::Response& res) {
    res.set_content(*page, "text/html; charset=utf-8");
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
  port_ = server_->bind_exclusive(host, address.port);
  if (port_ <= 0) {
    throw InputError(fmt::format(
        "option --monitor: cannot listen on {}:{} (in use, by another session's monitor too, or not an address of "
        "this host)",
        host, address.port));
  }
  thread_ = std::thread([this] { server_->listen_lowered(); });
  // Until the server runs, stop() would not reach it (and the destructor's join would wait forever).
  for (int i = 0; i < 2000 && !server_->is_running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

MonitorServer::~MonitorServer() {
  server_->stop_all();
  if (thread_.joinable()) thread_.join();
}

std::string MonitorServer::url() const { return fmt::format("http://{}:{}/", host_, port_); }

std::uint64_t MonitorServer::refused() const { return server_->refused(); }

std::string monitor_page() {
  static const std::string page = [] {
    std::string p = kMonitorPageHtml;
    const auto put = [&p](const std::string& marker, const std::string& text) {
      const auto at = p.find(marker);
      if (at != std::string::npos) p.replace(at, marker.size(), text);
    };
    put("<!--DEFLEX_DYGRAPHS_CSS-->", std::string("<style>\n") + kDygraphsCss + "\n</style>");
    put("<!--DEFLEX_DYGRAPHS_JS-->", std::string("<script>\n") + kDygraphsJs + "\n</script>");
    return p;
  }();
  return page;
}

std::string monitor_report(const runtime::MonitorFeed& feed, const std::string& title) {
  std::string page = monitor_page();
  std::string data = feed.json(0, static_cast<std::size_t>(-1));
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
