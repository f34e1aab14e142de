// `deflex monitor --log online.csv`: the live monitor's page for a recorded session (scrub through it),
// served locally or written as one static HTML file.
#include <atomic>
#include <chrono>
#include <csignal>
#include <iostream>
#include <memory>
#include <thread>

#include <fmt/format.h>

#include "command.hpp"
#include "deflex/monitor/cycle_log_reader.hpp"
#include "deflex/monitor/monitor_server.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::cli {
namespace {

std::atomic<bool> g_monitor_stop{false};
void on_monitor_signal(int /*signal*/) { g_monitor_stop = true; }

struct MonitorOpts {
  std::string log, address = "127.0.0.1:8080", report;
  bool remote = false;
  double duration_s = 0.0;
};

void setup_monitor(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<MonitorOpts>();
  sub.add_option("--log", o->log, "A cycle log written by deflex online --log")->required();
  sub.add_option("--monitor", o->address,
                 "Serve the page at [ADDR:]PORT (default 127.0.0.1:8080; port 0: any free one)")
      ->capture_default_str();
  sub.add_flag("--monitor-remote", o->remote, "Allow an address other hosts can reach");
  sub.add_option("--report", o->report,
                 "Write the page with the whole log in it to this HTML file instead of serving it");
  sub.add_option("--duration-s", o->duration_s, "Serve this long, then exit (0: until Ctrl-C)");
  sub.callback([o, &exit_code] {
    const monitor::MonitorAddress address = monitor::parse_monitor_address(o->address, o->remote, "--monitor");
    const auto feed = monitor::read_cycle_log_feed(o->log);
    if (!o->report.empty()) {
      write_output_file(o->report, monitor::monitor_report(*feed, "deflex monitor: " + o->log), "option --report");
      std::cerr << fmt::format("deflex monitor: {} cycles of {} drawn into {}\n", feed->rows_added(), o->log,
                               o->report);
      exit_code = 0;
      return;
    }
    monitor::MonitorServer server(feed, address);
    std::cerr << fmt::format("deflex monitor: {} cycles of {} on {} (Ctrl-C to stop)\n", feed->rows_added(), o->log,
                             server.url());
    g_monitor_stop = false;
    std::signal(SIGINT, on_monitor_signal);
    std::signal(SIGTERM, on_monitor_signal);
    const auto start = std::chrono::steady_clock::now();
    while (!g_monitor_stop.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (o->duration_s > 0.0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >= o->duration_s) {
        break;
      }
    }
    exit_code = 0;
  });
}

}  // namespace

DEFLEX_COMMAND("monitor",
               "The live monitor's page for a recorded cycle log (deflex online --log): served locally, or written "
               "as one HTML file with --report",
               setup_monitor, 72);

}  // namespace deflex::cli
