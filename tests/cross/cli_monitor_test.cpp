// The live monitor page, as a commissioning engineer uses it: `deflex online --monitor` against the
// ABB EGM stand-in in real time, the page opened in headless Chromium, and the values the rendered
// page shows read back and held against the cycle log's row of the same controller sequence number;
// the charts' axes (ticks evenly spaced, units named, the latency axis never below zero), the bound and
// threshold lines and the status timeline read from the rendered page and the data it was given; a
// stalled browser, slowloris and idle clients that never hold up an ordinary request; a second session
// on a busy port refused before it starts; the page for a recorded log and its static report with its
// header and summary whole (link, stop reason, late answers as the session's summary counted them); and
// bad addresses, ports and logs refused with exit 2 before anything runs.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <thread>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cross/cli_child.hpp"
#include "cross/cli_runner.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/cell/rsi_controller.hpp"
#include "deflex/monitor/monitor_server.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/runtime/cycle_log.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/transport/udp_transport.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;
using test::Child;
using test::kDeflex;
using test::spawn;

// The monitor's port from the start-up line "monitor on http://127.0.0.1:PORT/".
int monitor_port_of(const Child& c) {
  const std::string key = "monitor on http://127.0.0.1:";
  for (int i = 0; i < 500; ++i) {
    const std::string text = test::slurp(c.stderr_path);
    const auto at = text.find(key);
    if (at != std::string::npos) return std::atoi(text.c_str() + at + key.size());
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return -1;
}

int monitor_egm_port(const Child& c) { return test::port_of(c, "EGM on 127.0.0.1:"); }

// A connection to the monitor; a read that waits 30 s is a failure, not a hung test.
int connect_to(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  timeval tv{30, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// One HTTP/1.0 request; the whole answer (status line, headers, body).
std::string http_request(int port, const std::string& request) {
  const int fd = connect_to(port);
  if (fd < 0) return "";
  const std::string req = request + " HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
  (void)!::write(fd, req.data(), req.size());
  std::string out;
  char buf[65536];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) out.append(buf, static_cast<std::size_t>(n));
  ::close(fd);
  return out;
}

std::string chromium() {
  for (const char* p : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"}) {
    if (fs::exists(p)) return p;
  }
  return "";
}

// The text of the element with this id in a DOM dump ("" when absent).
std::string dom_text(const std::string& dom, const std::string& id) {
  const std::regex re("id=\"" + id + "\"[^>]*>([^<]*)<");
  std::smatch m;
  return std::regex_search(dom, m, re) ? m[1].str() : "";
}

// Chromium's DOM of `url` after its script ran (`budget_ms` of the page's time); "" when it did not end.
std::string browse(const std::string& url, const std::string& dom_path, int budget_ms = 1500) {
  const std::string browser = chromium();
  (void)std::system(
      ("timeout 120 " + browser +
       " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
       "--disable-background-networking --disable-component-update --disable-sync --virtual-time-budget=" +
       std::to_string(budget_ms) + " --window-size=1400,1900 --dump-dom " + url + " > " + dom_path + " 2>/dev/null")
          .c_str());
  return test::slurp(dom_path);
}

// The part of the DOM from the element with id `from` to the one with id `to`.
std::string dom_between(const std::string& dom, const std::string& from, const std::string& to) {
  const auto a = dom.find("id=\"" + from + "\"");
  const auto b = dom.find("id=\"" + to + "\"", a == std::string::npos ? 0 : a);
  if (a == std::string::npos || b == std::string::npos) return "";
  return dom.substr(a, b - a);
}

// The tick labels of one axis ("x" or "y") of the chart drawn in `part` of the DOM, as numbers.
std::vector<double> ticks(const std::string& part, const std::string& axis) {
  const std::regex re("dygraph-axis-label-" + axis + "\">([^<]*)<");
  std::vector<double> out;
  for (auto it = std::sregex_iterator(part.begin(), part.end(), re); it != std::sregex_iterator(); ++it) {
    out.push_back(std::stod((*it)[1].str()));
  }
  return out;
}

// Ticks an engineer can read a value off: at least three, in order, evenly spaced.
void expect_readable_axis(const std::vector<double>& t, const std::string& what) {
  ASSERT_GE(t.size(), 3u) << what;
  const double step = t[1] - t[0];
  EXPECT_GT(step, 0.0) << what;
  for (std::size_t i = 1; i < t.size(); ++i) EXPECT_NEAR(t[i] - t[i - 1], step, 1e-6 * std::abs(step) + 1e-9) << what;
}

// The attribute `name` of every element of `part` that has one.
std::vector<std::string> attributes(const std::string& part, const std::string& name) {
  const std::regex re(name + "=\"([^\"]*)\"");
  std::vector<std::string> out;
  for (auto it = std::sregex_iterator(part.begin(), part.end(), re); it != std::sregex_iterator(); ++it) {
    out.push_back((*it)[1].str());
  }
  return out;
}

struct MonitorRun {
  std::string dir, program_path, log;
  JointTrajectory program;
  explicit MonitorRun(const std::string& name)
      : dir(::testing::TempDir() + "/" + name),
        program_path((fs::create_directories(dir), test::nominal_program(dir))),
        log(dir + "/log.csv"),
        program(JointTrajectory::read_csv(program_path, builtin_irb6700())) {}
  std::vector<std::string> args(const std::vector<std::string>& extra) const {
    std::vector<std::string> a{kDeflex,
                               "online",
                               "--link",
                               "egm-joint",
                               "--program",
                               program_path,
                               "--egm-port",
                               "0",
                               "--force-source",
                               "csv:" + test::kForceReplay,
                               "--loop",
                               "--log",
                               log,
                               "--max-joint-correction-deg",
                               "0.5",
                               "--status-interval-s",
                               "0.5"};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }
};

void drive(Child& deflex, const JointTrajectory& program, double seconds,
           cell::EgmPositionGuidanceController** out = nullptr) {
  const int port = monitor_egm_port(deflex);
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  UdpTransport transport("127.0.0.1", 0);
  cell::ControllerConfig cc;
  cell::EgmPositionGuidanceController controller(cc, program.points().front(), transport,
                                                 make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  test::run_in_real_time(controller, seconds);
  EXPECT_FALSE(controller.counters().timed_out);
  EXPECT_GT(controller.counters().targets, 200u);
  (void)out;
}

TEST(CliMonitor, TheRenderedPageShowsTheCycleLogsValues) {
  const std::string browser = chromium();
  if (browser.empty()) GTEST_SKIP() << "no chromium (scripts/install-deps.sh installs it)";
  MonitorRun run("cli_monitor_live");
  Child deflex;
  spawn(deflex, run.args({"--monitor", "0", "--monitor-window-s", "10"}), run.dir + "/stderr.txt");
  const int port = monitor_port_of(deflex);
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  // The controller runs in real time until the browser has read the page (and taken its picture).
  const int egm_port = monitor_egm_port(deflex);
  ASSERT_GT(egm_port, 0) << test::slurp(deflex.stderr_path);
  std::atomic<bool> browser_done{false};
  bool timed_out = true;
  std::uint64_t targets = 0;
  std::thread controller_thread([&] {
    UdpTransport transport("127.0.0.1", 0);
    cell::ControllerConfig cc;
    cell::EgmPositionGuidanceController controller(
        cc, run.program.points().front(), transport,
        make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(egm_port)));
    const auto start = std::chrono::steady_clock::now();
    auto next = start;
    for (;;) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if ((browser_done.load() && t > 2.0) || t > 60.0) break;
      controller.tick(t);
      next += std::chrono::milliseconds(4);
      std::this_thread::sleep_until(next);
    }
    timed_out = controller.counters().timed_out;
    targets = controller.counters().targets;
  });
  // The browser opens the page while the session runs; its script asks /data for rows and draws.
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
  const std::string dom = browse(url, run.dir + "/dom.html");
  if (const char* shot = std::getenv("DEFLEX_MONITOR_SCREENSHOT")) {  // the picture in docs/online.md
    (void)std::system(("timeout 120 " + browser +
                       " --headless --no-sandbox --disable-gpu --hide-scrollbars --virtual-time-budget=1500 "
                       "--window-size=1400,1640 --screenshot=" +
                       std::string(shot) + " " + url + " >/dev/null 2>&1")
                          .c_str());
  }
  browser_done = true;
  controller_thread.join();
  EXPECT_FALSE(timed_out);
  EXPECT_GT(targets, 200u);
  EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);
  EXPECT_EQ(dom_text(dom, "v-conn"), "") << "the page lost its connection to the running session";
  EXPECT_EQ(dom_text(dom, "v-state"), "running");
  const std::string seq_text = dom_text(dom, "v-seq");
  ASSERT_FALSE(seq_text.empty() || seq_text == "-") << dom.substr(0, 2000);
  EXPECT_EQ(dom_text(dom, "v-link"), "egm-joint");
  EXPECT_EQ(dom_text(dom, "v-period"), "4 ms");
  const double seq = std::stod(seq_text);
  const CsvTable log = CsvTable::read_file(run.log);
  std::size_t row = log.rows();
  for (std::size_t r = 0; r < log.rows(); ++r) {
    if (log.at(r, "sequence") == seq) row = r;
  }
  ASSERT_LT(row, log.rows()) << "sequence " << seq << " is not in the log";
  // Force (N, 3 decimals on the page), correction (deg, 6 decimals), counts.
  EXPECT_NEAR(std::stod(dom_text(dom, "v-fz")), log.at(row, "fz_N"), 2e-3);
  EXPECT_NEAR(std::stod(dom_text(dom, "v-fx")), log.at(row, "fx_N"), 2e-3);
  EXPECT_NEAR(std::stod(dom_text(dom, "v-rfz")), log.at(row, "meas_fz_N"), 2e-3);
  for (int j = 1; j <= 6; ++j) {
    EXPECT_NEAR(std::stod(dom_text(dom, "v-d" + std::to_string(j))), log.at(row, "dtheta" + std::to_string(j) + "_deg"),
                2e-6)
        << "joint " << j;
  }
  EXPECT_GT(std::abs(log.at(row, "fz_N")), 1.0);  // a real force, not two zeros
  const std::pair<const char*, const char*> counts[] = {{"delayed", "late"},
                                                        {"rejected", "rejected"},
                                                        {"restarts", "restarts"},
                                                        {"guard_trips", "guard_trips"},
                                                        {"duplicates", "duplicates"}};
  for (const auto& [id, column] : counts)
    EXPECT_EQ(std::stod(dom_text(dom, std::string("v-") + id)), log.at(row, column)) << id;
  // Late answers with the summary's meaning, counted here from the log: answered, above the 4 ms cycle.
  double late = 0.0;
  for (std::size_t r = 0; r <= row; ++r) late += log.at(r, "replied") == 1.0 && log.at(r, "answer_ms") > 4.0 ? 1 : 0;
  EXPECT_EQ(std::stod(dom_text(dom, "v-late-count")), late);
  EXPECT_NE(dom_text(dom, "v-jbound").find("0.500"), std::string::npos) << dom_text(dom, "v-jbound");
  // The axes: ticks on both axes of every chart, evenly spaced, the time ticks within the last 10 s
  // shown, units named, the joint chart's range taking in the corrections the log holds for that span.
  const double t_row = log.at(row, "t_s");
  for (const auto& [chart, after, unit] :
       std::vector<std::tuple<std::string, std::string, std::string>>{{"c-force", "lines-force", "force (N)"},
                                                                      {"c-moment", "lines-moment", "moment (Nm)"},
                                                                      {"c-joint", "lines-joint", "correction (deg)"},
                                                                      {"c-tcp", "lines-tcp", "TCP correction (mm)"},
                                                                      {"c-latency", "lines-latency", "time (ms)"}}) {
    const std::string part = dom_between(dom, chart, after);
    ASSERT_FALSE(part.empty()) << chart << " is not on the page";
    expect_readable_axis(ticks(part, "y"), chart + " y");
    const auto x = ticks(part, "x");
    expect_readable_axis(x, chart + " x");
    for (double v : x) {
      EXPECT_GE(v, t_row - 10.0 - 1e-9) << chart;
      EXPECT_LE(v, t_row + 1e-9) << chart;
    }
    EXPECT_NE(part.find(">" + unit + "<"), std::string::npos) << chart << ": no axis title '" << unit << "'";
  }
  EXPECT_GE(ticks(dom_between(dom, "c-latency", "lines-latency"), "y").front(), 0.0) << "a negative time axis";
  {
    const auto y = ticks(dom_between(dom, "c-joint", "lines-joint"), "y");
    double largest = 0.0;
    for (std::size_t r = 0; r <= row; ++r) {
      if (log.at(r, "t_s") < t_row - 10.0) continue;
      for (int j = 1; j <= 6; ++j) largest = std::max(largest, log.at(r, "dtheta" + std::to_string(j) + "_deg"));
    }
    EXPECT_LE(largest, y.back() + (y[1] - y[0])) << "the joint chart's range does not take in the largest correction";
    EXPECT_LT(y.back(), 0.5) << "the corrections are drawn against the 0.5 deg bound, not at their own scale";
  }
  // The bound and the threshold lines the charts draw, as the page lists them under each chart.
  EXPECT_EQ(attributes(dom_between(dom, "lines-joint", "joint-vals"), "data-y"), std::vector<std::string>{"0.5"});
  EXPECT_EQ(attributes(dom_between(dom, "lines-latency", "v-answer"), "data-y"), std::vector<std::string>{"4"});
  EXPECT_EQ(attributes(dom_between(dom, "lines-tcp", "v-cx"), "data-y").size(), 1u);
  // The status timeline: its time axis, and the session's start on it.
  expect_readable_axis(ticks(dom_between(dom, "c-timeline", "timeline-key"), "x"), "timeline x");
  const std::string events = dom_between(dom, "events", "card-force");
  EXPECT_NE(events.find("data-kind=\"state\""), std::string::npos) << events;
  EXPECT_NE(events.find("state: running"), std::string::npos) << events;
  // A 6-component sensor: the moment chart is shown.
  EXPECT_EQ(dom.find("id=\"card-moment\" hidden"), std::string::npos);
}

TEST(CliMonitor, AStalledBrowserNeverDelaysTheController) {
  MonitorRun run("cli_monitor_stalled");
  Child deflex;
  spawn(deflex, run.args({"--monitor", "0", "--json"}), run.dir + "/stderr.txt", run.dir + "/stdout.json");
  const int port = monitor_port_of(deflex);
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  // One client connects and sends nothing; one asks for the data and never reads a byte of it; one
  // sends half a request.
  const int silent = connect_to(port);
  const int no_reader = connect_to(port);
  const int half = connect_to(port);
  ASSERT_GE(silent, 0);
  const int small = 1024;
  setsockopt(no_reader, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  const std::string req = "GET /data?since=0 HTTP/1.1\r\nHost: x\r\n\r\n";
  for (int i = 0; i < 50; ++i) (void)!::write(no_reader, req.data(), req.size());
  (void)!::write(half, "GET /da", 7);
  drive(deflex, run.program, 3.0);
  // The server still answers a well-behaved client.
  const std::string answer = http_request(port, "GET /data?since=0");
  EXPECT_NE(answer.find("200"), std::string::npos) << answer.substr(0, 200);
  EXPECT_NE(answer.find("\"link\":\"egm-joint\""), std::string::npos);
  EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);
  for (int fd : {silent, no_reader, half}) ::close(fd);
  // The session's own timing counters: the answers were not held up (a late answer is one slower
  // than the controller's cycle; a busy test machine makes a few, a blocked reporter would make most).
  const auto doc = nlohmann::json::parse(test::slurp(run.dir + "/stdout.json"));
  const double answers = doc["answers"].get<double>();
  EXPECT_GT(answers, 200.0);
  EXPECT_LT(doc["timing"]["late_answers"].get<double>(), 0.01 * answers) << doc["timing"].dump();
}

TEST(CliMonitor, OnlyThePageAndItsDataAreServed) {
  MonitorRun run("cli_monitor_routes");
  Child deflex;
  spawn(deflex, run.args({"--monitor", "0"}), run.dir + "/stderr.txt");
  const int port = monitor_port_of(deflex);
  ASSERT_GT(port, 0);
  const std::string page = http_request(port, "GET /");
  EXPECT_NE(page.find("200"), std::string::npos);
  EXPECT_NE(page.find("deflex online monitor"), std::string::npos);
  // The page fetches nothing from elsewhere: no element loads a file (dygraphs is inline), no style
  // imports one, and its script asks this server alone. (The library's licence comment names a web
  // address; nothing loads it.)
  const std::regex loads(
      R"re(((src|href)\s*=\s*["']?|url\(\s*["']?)(https?:)?//|<script[^>]*src|<link|@import|sourceMappingURL)re");
  std::smatch m;
  EXPECT_FALSE(std::regex_search(page, m, loads)) << m.str();
  EXPECT_NE(page.find("Dygraph"), std::string::npos) << "the charting library is not in the page";
  const std::regex fetched(R"(fetch\(([^)]*)\))");
  for (auto it = std::sregex_iterator(page.begin(), page.end(), fetched); it != std::sregex_iterator(); ++it) {
    EXPECT_EQ((*it)[1].str().rfind("`/data?", 0), 0u) << (*it)[0].str();
  }
  EXPECT_NE(http_request(port, "GET /data").find("\"rows\""), std::string::npos);
  EXPECT_NE(http_request(port, "GET /etc/passwd").find("404"), std::string::npos);
  EXPECT_NE(http_request(port, "GET /data/../x").find("404"), std::string::npos);
  const std::string post = http_request(port, "POST /data");
  EXPECT_EQ(post.find("200"), std::string::npos) << post.substr(0, 100);
  EXPECT_NE(http_request(port, "GET /data?since=-4").find("400"), std::string::npos);
  EXPECT_EQ(deflex.stop(), 0);
}

TEST(CliMonitor, RecordedLogServedAndWrittenAsAReport) {
  MonitorRun run("cli_monitor_recorded");
  {
    Child deflex;
    spawn(deflex, run.args({"--log-report", "--json"}), run.dir + "/stderr.txt", run.dir + "/summary.json");
    drive(deflex, run.program, 2.0);
    EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);
  }
  const std::string report = run.dir + "/log.html";
  ASSERT_TRUE(fs::exists(report)) << test::slurp(run.dir + "/stderr.txt");
  const std::string html = test::slurp(report);
  EXPECT_NE(html.find("window.DEFLEX_STATIC"), std::string::npos);
  EXPECT_NE(html.find("\"recorded\":true"), std::string::npos);
  EXPECT_NE(html.find("\"joint_bound_deg\":0.5"), std::string::npos);
  // The report's header and summary are whole: the link, the cycle, the stop reason as the session's
  // summary gave it, and the late answers as the session counted them (the page counts them again from
  // the log's answer times).
  const auto summary = nlohmann::json::parse(test::slurp(run.dir + "/summary.json"));
  if (!chromium().empty()) {
    const std::string dom = browse("file://" + report, run.dir + "/report_dom.html", 500);
    EXPECT_EQ(dom_text(dom, "v-link"), "egm-joint");
    EXPECT_EQ(dom_text(dom, "v-period"), "4 ms");
    EXPECT_EQ(dom_text(dom, "v-stop"), summary["reason"].get<std::string>());
    EXPECT_EQ(dom_text(dom, "v-late-answers")
                  .rfind(fmt::format("{} of {} answers later than the 4 ms cycle",
                                     summary["timing"]["late_answers"].get<int>(), summary["answers"].get<int>()),
                         0),
              0u)
        << dom_text(dom, "v-late-answers");
    EXPECT_NE(dom_text(dom, "v-answer-stats").find("over the run"), std::string::npos);
    EXPECT_NE(dom.find("<td class=\"opt\">--max-joint-correction-deg</td><td class=\"n\">0.5</td><td>deg</td>"),
              std::string::npos)
        << dom_between(dom, "card-settings", "</details>");
    const std::string events = dom_between(dom, "events", "card-force");
    EXPECT_NE(events.find("data-kind=\"stop\""), std::string::npos) << events;
    for (const auto& [chart, after] : std::vector<std::pair<std::string, std::string>>{
             {"c-force", "lines-force"}, {"c-joint", "lines-joint"}, {"c-latency", "lines-latency"}}) {
      const std::string part = dom_between(dom, chart, after);
      expect_readable_axis(ticks(part, "x"), chart + " x");
      expect_readable_axis(ticks(part, "y"), chart + " y");
    }
  }
  const auto r = test::run_cli("monitor --log " + run.log + " --report " + run.dir + "/again.html");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  Child server;
  spawn(server, {kDeflex, "monitor", "--log", run.log, "--monitor", "127.0.0.1:0", "--duration-s", "5"},
        run.dir + "/monitor_stderr.txt");
  int port = -1;
  for (int i = 0; i < 300 && port < 0; ++i) {
    const std::string text = test::slurp(run.dir + "/monitor_stderr.txt");
    const auto at = text.find("on http://127.0.0.1:");
    if (at != std::string::npos) port = std::atoi(text.c_str() + at + 20);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_GT(port, 0) << test::slurp(run.dir + "/monitor_stderr.txt");
  const std::string data = http_request(port, "GET /data?since=0");
  EXPECT_NE(data.find("\"recorded\":true"), std::string::npos);
  EXPECT_NE(data.find("\"state\":\"recorded\""), std::string::npos);
  // The settings the session ran with came back from the log alone, each described by the settings
  // table: its unit, its key and its help with the range.
  const auto doc = nlohmann::json::parse(data.substr(data.find("\r\n\r\n") + 4));
  const auto setting = [&doc](const std::string& option) {
    for (const auto& s : doc["settings"]) {
      if (s["option"] == option) return s;
    }
    return nlohmann::json();
  };
  const auto bound = setting("--max-joint-correction-deg");
  EXPECT_EQ(bound["value"], "0.5") << bound;
  EXPECT_EQ(bound["unit"], "deg") << bound;
  EXPECT_EQ(bound["key"], "max_joint_correction_rad") << bound;
  EXPECT_NE(bound["help"].get<std::string>().find("[deg; >0..10]"), std::string::npos) << bound;
  EXPECT_EQ(setting("--status-interval-s")["value"], "0.5");
  EXPECT_EQ(setting("--period-ms")["value"], "4");
  EXPECT_EQ(setting("--force-source")["value"], "csv:" + test::kForceReplay);
  EXPECT_TRUE(setting("--rsi-sentype").is_null()) << "an RSI setting shown for an EGM session";
  EXPECT_EQ(server.stop(), 0);
}

TEST(CliMonitor, BadAddressesPortsAndLogsExitTwo) {
  MonitorRun run("cli_monitor_bad");
  // A port in use: refused before the session starts.
  const int taken = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(taken, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(::listen(taken, 1), 0);
  socklen_t len = sizeof a;
  ::getsockname(taken, reinterpret_cast<sockaddr*>(&a), &len);
  const std::string port = std::to_string(ntohs(a.sin_port));
  auto refused = [&](const std::vector<std::string>& extra, const std::string& text) {
    std::string cmd;
    for (const auto& s : run.args(extra)) cmd += "'" + s + "' ";
    const auto r = test::run_shell(cmd);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(text), std::string::npos) << r.err;
  };
  refused({"--monitor", port}, "cannot listen on 127.0.0.1:" + port);
  ::close(taken);
  refused({"--monitor", "0.0.0.0:0"}, "add --monitor-remote");
  refused({"--monitor", "127.0.0.1:99999"}, "0..65535");
  refused({"--monitor", "not-an-address:80", "--monitor-remote"}, "is not an IPv4 address");
  {
    const auto r = test::run_cli("online --link egm-joint --program " + run.program_path +
                                 " --egm-port 0 --force-source csv:" + test::kForceReplay + " --log-report");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--log-report: needs --log"), std::string::npos) << r.err;
  }
  // Logs that are not whole.
  std::ofstream(run.dir + "/truncated.csv") << "t_s,program_t_s,sequence,status\n0.1,0.1,1\n";
  auto r = test::run_cli("monitor --log " + run.dir + "/truncated.csv --report " + run.dir + "/x.html");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no column"), std::string::npos) << r.err;
  {
    Child deflex;
    spawn(deflex, run.args({}), run.dir + "/stderr.txt");
    drive(deflex, run.program, 1.0);
    EXPECT_EQ(deflex.stop(), 0);
  }
  // A log cut in its last row, as a session that died mid-write leaves it (no stop line).
  std::string text = test::slurp(run.log);
  text = text.substr(0, text.rfind(runtime::kCycleLogStop));
  std::ofstream(run.dir + "/cut.csv") << text.substr(0, text.size() - 40);
  fs::remove(run.dir + "/x.html");
  r = test::run_cli("monitor --log " + run.dir + "/cut.csv --report " + run.dir + "/x.html");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("cut.csv:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(run.dir + "/x.html"));
}

TEST(CliMonitor, AThreeComponentSensorHasNoMomentChartAndTheTimelineMarksItsFault) {
  const std::string dir = ::testing::TempDir() + "/cli_monitor_fault";
  fs::create_directories(dir);
  // 1.5 s at 1 kHz, forces only: a 300 N push with a 200 ms spike above the sensor's 2000 N threshold.
  {
    std::ofstream csv(dir + "/spike.csv");
    csv << "t_s,fx_N,fy_N,fz_N\n";
    for (int i = 0; i < 1500; ++i) {
      const double t = i * 1e-3;
      csv << t << ",0,0," << (t >= 0.3 && t < 0.5 ? -8000.0 : -300.0) << "\n";
    }
  }
  Child deflex;
  spawn(deflex,
        {kDeflex, "online", "--link", "rsi", "--rsi-port", "0", "--force-source", "csv:" + dir + "/spike.csv",
         "--sensor-config", std::string(DEFLEX_SOURCE_DIR) + "/examples/online/sensor_3axis.yaml", "--log",
         dir + "/log.csv", "--log-report"},
        dir + "/stderr.txt");
  const int port = test::port_of(deflex, "RSI on 127.0.0.1:");
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  const RobotModel robot = builtin_irb6700();
  JointVector q(6);
  q << 0, 20, 10, 0, 60, 0;
  q *= kPi / 180.0;
  UdpTransport transport("127.0.0.1", 0);
  cell::RsiController controller(cell::RsiControllerConfig{}, robot,
                                 std::make_shared<const JointTrajectory>(std::vector<double>{0.0, 100.0},
                                                                         std::vector<JointVector>{q, q}, robot, "hold"),
                                 transport, make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  test::run_in_real_time(controller, 2.5);
  EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);
  // The first faulted cycle, from the log.
  const CsvTable log = CsvTable::read_file(dir + "/log.csv");
  double fault_t = -1.0;
  for (std::size_t r = 0; r < log.rows() && fault_t < 0.0; ++r) {
    if (log.at(r, "status") == 3.0) fault_t = log.at(r, "t_s");
  }
  ASSERT_GT(fault_t, 0.0) << "the spike made no force fault";
  const std::string html = test::slurp(dir + "/log.html");
  ASSERT_FALSE(html.empty()) << test::slurp(dir + "/stderr.txt");
  EXPECT_NE(html.find("\"force_components\":3"), std::string::npos);
  EXPECT_NE(html.find("\"link\":\"rsi\""), std::string::npos);
  // The data the page is given: the fault marked at its first cycle, and the stop.
  const auto at = html.find("window.DEFLEX_STATIC = ");
  ASSERT_NE(at, std::string::npos);
  const auto end = html.find(";\nwindow.DEFLEX_TITLE", at);
  const auto data = nlohmann::json::parse(html.substr(at + 23, end - at - 23));
  bool marked = false;
  for (const auto& e : data["events"]) {
    if (e["kind"] == "force fault") {
      EXPECT_NEAR(e["t"].get<double>(), fault_t, 1e-6);
      marked = true;
    }
  }
  EXPECT_TRUE(marked) << data["events"].dump();
  EXPECT_EQ(data["events"].back()["kind"], "stop");
  if (chromium().empty()) GTEST_SKIP() << "no chromium (scripts/install-deps.sh installs it)";
  const std::string dom = browse("file://" + dir + "/log.html", dir + "/dom.html", 500);
  EXPECT_NE(dom.find("id=\"card-moment\" hidden"), std::string::npos) << "a moment chart for a 3-component sensor";
  EXPECT_NE(dom_text(dom, "v-sensor").find("3 components"), std::string::npos) << dom_text(dom, "v-sensor");
  const std::string events = dom_between(dom, "events", "card-force");
  EXPECT_NE(events.find("data-kind=\"force fault\""), std::string::npos) << events;
  // The force chart draws the sensor's 2000 N fault threshold (above the chart or on it).
  EXPECT_EQ(attributes(dom_between(dom, "lines-force", "v-fx"), "data-y"), std::vector<std::string>{"2000"});
}

TEST(CliMonitor, ASecondSessionOnABusyMonitorPortExitsTwoBeforeItStarts) {
  MonitorRun run("cli_monitor_busy");
  {  // a log for `deflex monitor --log`
    Child deflex;
    spawn(deflex, run.args({}), run.dir + "/stderr.txt");
    drive(deflex, run.program, 1.5);
    EXPECT_EQ(deflex.stop(), 0);
  }
  MonitorRun first_run = run, second_run = run;
  first_run.log = run.dir + "/first.csv";
  second_run.log = run.dir + "/second.csv";
  Child first;
  spawn(first, first_run.args({"--monitor", "0"}), run.dir + "/first.txt");
  const int port = monitor_port_of(first);
  ASSERT_GT(port, 0) << test::slurp(first.stderr_path);
  std::string cmd;
  for (const auto& a : second_run.args({"--monitor", std::to_string(port)})) cmd += "'" + a + "' ";
  const auto second = test::run_shell(cmd);
  EXPECT_EQ(second.exit_code, 2) << second.err;
  EXPECT_NE(second.err.find("cannot listen on 127.0.0.1:" + std::to_string(port)), std::string::npos) << second.err;
  EXPECT_EQ(second.err.find("EGM on"), std::string::npos) << "the second session started: " << second.err;
  EXPECT_FALSE(fs::exists(run.dir + "/second.csv"));
  const auto served =
      test::run_cli("monitor --log " + run.log + " --monitor 127.0.0.1:" + std::to_string(port) + " --duration-s 1");
  EXPECT_EQ(served.exit_code, 2) << served.err;
  EXPECT_NE(served.err.find("cannot listen"), std::string::npos) << served.err;
  // The first session's page is its own still.
  EXPECT_NE(http_request(port, "GET /data").find("\"link\":\"egm-joint\""), std::string::npos);
  (void)first.stop();
}

// A listener that lets others share its port (SO_REUSEPORT, as cpp-httplib's own default sets it).
struct SharingListener {
  int fd = -1, port = 0;
  SharingListener() {
    fd = ::socket(AF_INET, SOCK_STREAM, 0);
    const int yes = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    setsockopt(fd, SOL_SOCKET, SO_REUSEPORT, &yes, sizeof yes);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    EXPECT_EQ(::listen(fd, 4), 0);
    socklen_t len = sizeof a;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    port = ntohs(a.sin_port);
  }
  ~SharingListener() { ::close(fd); }
};

TEST(MonitorServer, ItsPortIsItsAloneWhateverTheOtherListenerAllows) {
  runtime::MonitorSetup setup;
  const auto feed = std::make_shared<runtime::MonitorFeed>(setup);
  {
    const SharingListener other;
    EXPECT_THROW(monitor::MonitorServer(feed, {"127.0.0.1", other.port}), InputError);
  }
  monitor::MonitorServer server(feed, {"127.0.0.1", 0});
  EXPECT_THROW(monitor::MonitorServer(feed, {"127.0.0.1", server.port()}), InputError);
  EXPECT_THROW(monitor::MonitorServer(feed, {"0.0.0.0", server.port()}), InputError);
  // And a sharing listener cannot join it.
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  const int yes = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  setsockopt(fd, SOL_SOCKET, SO_REUSEPORT, &yes, sizeof yes);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(server.port()));
  EXPECT_NE(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ::close(fd);
}

// Sends a request's first line and then one header byte at a time, reconnecting whenever the server
// drops it, until `stop`.
void slowloris(int port, const std::atomic<bool>& stop, std::atomic<int>& dropped) {
  int fd = -1;
  while (!stop.load()) {
    if (fd < 0) {
      fd = connect_to(port);
      const std::string start = "GET /data?since=0 HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ";
      if (fd >= 0) (void)!::send(fd, start.data(), start.size(), MSG_NOSIGNAL);
    } else if (::send(fd, "a", 1, MSG_NOSIGNAL) != 1) {
      ::close(fd);
      fd = -1;
      ++dropped;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (fd >= 0) ::close(fd);
}

// `count` clients that ask for an event stream and then say nothing more (their sockets, to close).
std::vector<int> idle_event_streams(int port, int count) {
  std::vector<int> idle;
  for (int k = 0; k < count; ++k) {
    idle.push_back(connect_to(port));
    const std::string req = "GET /events HTTP/1.1\r\nHost: x\r\nAccept: text/event-stream\r\n\r\n";
    (void)!::send(idle.back(), req.data(), req.size(), MSG_NOSIGNAL);
  }
  return idle;
}

TEST(MonitorServer, OrdinaryRequestsAreAllAnsweredWithSlowlorisAndIdleClientsOn) {
  runtime::MonitorSetup setup;
  setup.link = "rsi";
  const auto feed = std::make_shared<runtime::MonitorFeed>(setup);
  runtime::MonitorRow row;
  for (int k = 0; k < 100; ++k) {
    row.t_s = k * 0.004;
    feed->add(row);
  }
  feed->flush();
  monitor::MonitorServer server(feed, {"127.0.0.1", 0});
  std::atomic<bool> stop{false};
  std::atomic<int> dropped{0};
  std::vector<std::thread> abusers;
  for (int k = 0; k < 10; ++k) abusers.emplace_back([&] { slowloris(server.port(), stop, dropped); });
  // Thirty clients that ask for an event stream and then say nothing more.
  const std::vector<int> idle = idle_event_streams(server.port(), 30);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // every slow connection open
  // Twenty ordinary requests at once: every one answered, with the data.
  std::vector<std::string> answers(20);
  std::vector<std::thread> clients;
  for (std::size_t k = 0; k < answers.size(); ++k) {
    clients.emplace_back([&, k] { answers[k] = http_request(server.port(), "GET /data?since=0"); });
  }
  for (auto& c : clients) c.join();
  for (std::size_t k = 0; k < answers.size(); ++k) {
    EXPECT_EQ(answers[k].rfind("HTTP/1.1 200", 0), 0u) << k << ": " << answers[k].substr(0, 200);
    EXPECT_NE(answers[k].find("\"link\":\"rsi\""), std::string::npos) << k;
  }
  // The slow connections are cut at the request deadline (2 s from their connection) and a client sees
  // it at a send after that: keep them going until one is seen, 5 s past the deadline at most (the
  // ordinary requests above can all be answered before the first cut).
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(7);
  while (dropped.load() == 0 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  stop = true;
  for (auto& t : abusers) t.join();
  for (int fd : idle) ::close(fd);
  EXPECT_GT(dropped.load(), 0) << "the server never cut a slowloris connection off";
}

// The fault table's row for an abusive page: while ten slowloris clients, thirty idle event streams
// and two clients asking for the data as fast as they can hold the monitor, the stream on the wire
// keeps both invariants (every step between two targets the controller took within the per-cycle
// limit this test computes from the program, every command within the bound of the nominal) and the
// answers stay in time.
TEST(CliMonitor, AnAbusivePageNeitherDelaysNorStepsTheStream) {
  MonitorRun run("cli_monitor_abusive");
  Child deflex;
  spawn(deflex, run.args({"--monitor", "0", "--json"}), run.dir + "/stderr.txt", run.dir + "/stdout.json");
  const int port = monitor_port_of(deflex);
  ASSERT_GT(port, 0) << test::slurp(deflex.stderr_path);
  const int egm_port = monitor_egm_port(deflex);
  ASSERT_GT(egm_port, 0) << test::slurp(deflex.stderr_path);
  std::atomic<bool> stop{false};
  std::atomic<int> dropped{0};
  std::atomic<long> floods{0};
  std::vector<std::thread> abusers;
  for (int k = 0; k < 10; ++k) abusers.emplace_back([&] { slowloris(port, stop, dropped); });
  for (int k = 0; k < 2; ++k) {
    abusers.emplace_back([&] {
      while (!stop.load()) {
        (void)http_request(port, "GET /data?since=0");
        ++floods;
      }
    });
  }
  const std::vector<int> idle = idle_event_streams(port, 30);
  // The controller in real time, every target it takes recorded (what went on the wire).
  std::vector<JointVector> wire;
  {
    UdpTransport transport("127.0.0.1", 0);
    cell::ControllerConfig cc;
    cell::EgmPositionGuidanceController controller(
        cc, run.program.points().front(), transport,
        make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(egm_port)));
    std::uint64_t taken = 0;
    test::run_in_real_time(controller, 3.0, [&] {
      if (controller.counters().targets == taken) return;
      taken = controller.counters().targets;
      wire.push_back(controller.target());
    });
    EXPECT_FALSE(controller.counters().timed_out);
  }
  stop = true;
  for (auto& t : abusers) t.join();
  for (int fd : idle) ::close(fd);
  EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);
  EXPECT_GT(floods.load(), 10) << "the flood never got an answer";
  ASSERT_GT(wire.size(), 200u);
  // The per-cycle step limit the test computes from the program (test::cli_step_limit_deg), with the
  // float32 rounding of the wire.
  const JointVector limit = test::cli_step_limit_deg(run.program).array() * (kPi / 180.0) + 1e-7;
  double worst = 0.0;
  for (std::size_t k = 1; k < wire.size(); ++k) {
    worst = std::max(worst, ((wire[k] - wire[k - 1]).cwiseAbs().array() / limit.array()).maxCoeff());
  }
  EXPECT_LE(worst, 1.0) << "a step on the wire beyond the per-cycle limit with an abusive page on";
  EXPECT_GT(worst, 0.05) << "the stream never moved: the check above saw nothing";
  const CsvTable log = CsvTable::read_file(run.log);
  double farthest = 0.0;
  for (std::size_t r = 0; r < log.rows(); ++r) {
    for (int j = 1; j <= 6; ++j) {
      const std::string n = std::to_string(j) + "_deg";
      farthest = std::max(farthest, std::abs(log.at(r, "q_command" + n) - log.at(r, "q_nominal" + n)));
    }
  }
  EXPECT_LE(farthest, 0.5 + 1e-9) << "a command beyond the 0.5 deg bound of the nominal";
  const auto doc = nlohmann::json::parse(test::slurp(run.dir + "/stdout.json"));
  const double answers = doc["answers"].get<double>();
  EXPECT_GT(answers, 200.0);
  EXPECT_LT(doc["timing"]["late_answers"].get<double>(), 0.01 * answers) << doc["timing"].dump();
}

TEST(MonitorServer, ConnectionsBeyondItsCapAreRefusedAndItServesAgainAfter) {
  runtime::MonitorSetup setup;
  const auto feed = std::make_shared<runtime::MonitorFeed>(setup);
  monitor::MonitorLimits limits;
  limits.threads = 2;
  limits.max_connections = 10;
  limits.request_deadline_s = 60.0;  // the silent clients below stay open until the test closes them
  monitor::MonitorServer server(feed, {"127.0.0.1", 0}, limits);
  std::vector<int> silent;
  for (int k = 0; k < 25; ++k) silent.push_back(connect_to(server.port()));
  // The fifteen over the cap of ten get a 503 and are closed; the ten others wait, unanswered.
  for (int i = 0; i < 3000 && server.refused() < 15; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(server.refused(), 15u);
  int refused = 0;
  for (int fd : silent) {
    char buf[256];
    const ssize_t n = ::recv(fd, buf, sizeof buf - 1, MSG_DONTWAIT);
    if (n > 0 && std::string(buf, static_cast<std::size_t>(n)).rfind("HTTP/1.1 503", 0) == 0) ++refused;
  }
  EXPECT_EQ(refused, 15);
  for (int fd : silent) ::close(fd);
  // Once they are gone it serves again.
  std::string answer;
  for (int i = 0; i < 50 && answer.rfind("HTTP/1.1 200", 0) != 0; ++i) {
    answer = http_request(server.port(), "GET /data");
    if (answer.rfind("HTTP/1.1 200", 0) != 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(answer.rfind("HTTP/1.1 200", 0), 0u) << answer.substr(0, 200);
}

TEST(MonitorServer, StartsAndStopsAtOnceAndParsesItsAddress) {
  runtime::MonitorSetup setup;
  setup.link = "egm-joint";
  const auto feed = std::make_shared<runtime::MonitorFeed>(setup);
  for (int k = 0; k < 20; ++k) {  // a server destroyed right after it was made never hangs its owner
    monitor::MonitorServer server(feed, {"127.0.0.1", 0});
    EXPECT_GT(server.port(), 0);
  }
  monitor::MonitorServer server(feed, {"127.0.0.1", 0});
  EXPECT_NE(http_request(server.port(), "GET /data").find("\"link\":\"egm-joint\""), std::string::npos);
  const auto a = monitor::parse_monitor_address("8080", false, "--monitor");
  EXPECT_EQ(a.host, "127.0.0.1");
  EXPECT_EQ(a.port, 8080);
  EXPECT_EQ(monitor::parse_monitor_address("127.0.0.2:0", false, "--monitor").host, "127.0.0.2");
  EXPECT_EQ(monitor::parse_monitor_address("192.168.1.5:9000", true, "--monitor").port, 9000);
  EXPECT_THROW(monitor::parse_monitor_address("192.168.1.5:9000", false, "--monitor"), InputError);
  EXPECT_THROW(monitor::parse_monitor_address(":80", false, "--monitor"), InputError);
  EXPECT_THROW(monitor::parse_monitor_address("80x", false, "--monitor"), InputError);
  // An address that is not this host's cannot be bound: refused at once.
  EXPECT_THROW(monitor::MonitorServer(feed, {"192.0.2.1", 0}), InputError);
}

}  // namespace
}  // namespace deflex
