// The live monitor page, as a commissioning engineer uses it: `deflex online --monitor` against the
// ABB EGM stand-in in real time, the page opened in headless Chromium, and the values the rendered
// page shows read back and held against the cycle log's row of the same controller sequence number;
// a stalled browser that never reads; the page for a recorded log and its static report; and bad
// addresses, ports and logs refused with exit 2 before anything runs.
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

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cross/cli_child.hpp"
#include "cross/cli_runner.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/monitor/monitor_server.hpp"
#include "deflex/paths/joint_trajectory.hpp"
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

int connect_to(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
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
  // The browser opens the page while the session runs; its script polls /data and draws.
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
  const std::string dom_path = run.dir + "/dom.html";
  (void)std::system((browser + " --headless --no-sandbox --disable-gpu --virtual-time-budget=1500 --dump-dom " + url +
                     " > " + dom_path + " 2>/dev/null")
                        .c_str());
  if (const char* shot = std::getenv("DEFLEX_MONITOR_SCREENSHOT")) {  // the picture in docs/online.md
    (void)std::system((browser +
                       " --headless --no-sandbox --disable-gpu --hide-scrollbars --virtual-time-budget=1500 "
                       "--window-size=1400,900 --screenshot=" +
                       std::string(shot) + " " + url + " >/dev/null 2>&1")
                          .c_str());
  }
  browser_done = true;
  controller_thread.join();
  EXPECT_FALSE(timed_out);
  EXPECT_GT(targets, 200u);
  EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);
  const std::string dom = test::slurp(dom_path);
  EXPECT_EQ(dom_text(dom, "v-conn"), "") << "the page lost its connection to the running session";
  EXPECT_EQ(dom_text(dom, "v-state"), "running");
  const std::string seq_text = dom_text(dom, "v-seq");
  ASSERT_FALSE(seq_text.empty() || seq_text == "-") << dom.substr(0, 2000);
  EXPECT_EQ(dom_text(dom, "v-link"), "egm-joint");
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
  for (const char* k : {"late", "rejected", "restarts", "guard_trips", "duplicates"}) {
    EXPECT_EQ(std::stod(dom_text(dom, std::string("v-") + k)), log.at(row, k)) << k;
  }
  EXPECT_NE(dom_text(dom, "v-jbound").find("0.500"), std::string::npos) << dom_text(dom, "v-jbound");
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
  EXPECT_EQ(page.find("http://"), std::string::npos) << "the page fetches nothing from elsewhere";
  EXPECT_EQ(page.find("https://"), std::string::npos);
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
    spawn(deflex, run.args({"--log-report"}), run.dir + "/stderr.txt");
    drive(deflex, run.program, 2.0);
    EXPECT_EQ(deflex.stop(), 0) << test::slurp(deflex.stderr_path);
  }
  const std::string report = run.dir + "/log.html";
  ASSERT_TRUE(fs::exists(report)) << test::slurp(run.dir + "/stderr.txt");
  const std::string html = test::slurp(report);
  EXPECT_NE(html.find("window.DEFLEX_STATIC"), std::string::npos);
  EXPECT_NE(html.find("\"recorded\":true"), std::string::npos);
  EXPECT_NE(html.find("\"joint_bound_deg\":0.5"), std::string::npos);
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
  std::string text = test::slurp(run.log);
  std::ofstream(run.dir + "/cut.csv") << text.substr(0, text.size() - 40);
  r = test::run_cli("monitor --log " + run.dir + "/cut.csv --report " + run.dir + "/x.html");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("cut.csv:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(run.dir + "/x.html"));
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
