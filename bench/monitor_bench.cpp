// The live monitor page against the loop's timing: a KUKA RSI session (real UDP on loopback, the
// session's loop on its own thread, its reporter, the monitor's server on its feed) answering an RSI
// controller stand-in ticked every 4 ms in real time, for 5,000 cycles; once with the page used as
// meant (one browser asking for new rows ten times a second) and once abused besides: 30 idle
// event-stream clients (a request for an event stream, then nothing, again whenever dropped), 10
// slowloris connections (a header byte every 100 ms, reopened when dropped) and a flood (2 threads
// asking for the whole window as fast as they can). Reported: the session's late answers (answers
// later than the 4 ms cycle) and answer time p50/p99/max, the controller's own count of late answers,
// the browser's requests answered, the connections refused at the cap, what the flood was served.
// Three processes, as on a cell: deflex (this one), the controller stand-in and the page's clients,
// so neither the controller nor the clients share deflex's heap or locks. The stand-in runs at
// SCHED_FIFO where that is allowed (a controller has its own real-time computer; here it shares two
// cores with everything, and would otherwise count its own late wake-ups). deflex's loop runs both as
// an ordinary thread (its worst case: every process on the machine competes with it) and at
// SCHED_FIFO as `deflex online --realtime` runs it (skipped where real time is refused).
//   build/bench/monitor_bench --benchmark_repetitions=3
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>

#include "deflex/cell/rsi_controller.hpp"
#include "deflex/monitor/monitor_server.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/transport/clock.hpp"
#include "deflex/transport/udp_transport.hpp"

namespace deflex {
namespace {

constexpr int kCycles = 5000;

// A force source with a new sample every other call, like a DAQ faster than the RSI cycle.
class ConstantForce final : public ForceSource {
 public:
  bool latest(ForceSample& out) noexcept override {
    served_ = !served_;
    if (!served_) return false;
    out.t_s += 0.002;
    out.wrench_sensor << 50.0, -120.0, -400.0, 2.0, 1.0, -0.5;
    return true;
  }

 private:
  bool served_ = false;
};

int connect_to(int port, double recv_timeout_s) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  timeval tv{static_cast<time_t>(recv_timeout_s), static_cast<suseconds_t>(std::fmod(recv_timeout_s, 1.0) * 1e6)};
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

// One request; the whole answer ("" when none came).
std::string request(int port, const std::string& target, double timeout_s) {
  const int fd = connect_to(port, timeout_s);
  if (fd < 0) return "";
  const std::string req = "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  (void)!::send(fd, req.data(), req.size(), MSG_NOSIGNAL);
  std::string out;
  char buf[65536];
  for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0;) out.append(buf, static_cast<std::size_t>(n));
  ::close(fd);
  return out;
}

bool closed_by_peer(int fd) {
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, 0) <= 0) return false;
  char c;
  return ::recv(fd, &c, 1, MSG_DONTWAIT | MSG_PEEK) == 0 || (p.revents & (POLLHUP | POLLERR)) != 0;
}

// The abusive clients, until `stop`.
struct Abuse {
  std::vector<std::thread> threads;
  std::atomic<bool> stop{false};
  std::atomic<int> flood_answers{0};
  std::atomic<std::size_t> flood_bytes{0};

  void start(int port) {
    threads.emplace_back([this, port] { idle_event_streams(port, 30); });
    threads.emplace_back([this, port] { slowloris(port, 10); });
    for (int k = 0; k < 2; ++k) {
      threads.emplace_back([this, port] {
        while (!stop.load()) {
          const std::string a = request(port, "/data?since=0", 5.0);
          if (a.rfind("HTTP/1.1 200", 0) == 0) ++flood_answers;
          flood_bytes += a.size();
        }
      });
    }
  }
  void end() {
    stop = true;
    for (auto& t : threads) t.join();
  }

  void idle_event_streams(int port, int count) {
    const std::string req = "GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\nAccept: text/event-stream\r\n\r\n";
    std::vector<int> fds(static_cast<std::size_t>(count), -1);
    while (!stop.load()) {
      for (int& fd : fds) {
        if (fd >= 0 && !closed_by_peer(fd)) continue;
        if (fd >= 0) ::close(fd);
        fd = connect_to(port, 1.0);
        if (fd >= 0) (void)!::send(fd, req.data(), req.size(), MSG_NOSIGNAL);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    for (int fd : fds) ::close(fd);
  }

  void slowloris(int port, int count) {
    std::vector<int> fds(static_cast<std::size_t>(count), -1);
    while (!stop.load()) {
      for (int& fd : fds) {
        if (fd >= 0 && !closed_by_peer(fd) && ::send(fd, "X", 1, MSG_NOSIGNAL) == 1) continue;
        if (fd >= 0) ::close(fd);
        fd = connect_to(port, 1.0);
        if (fd >= 0) (void)!::send(fd, "GET /data?since=0 HTTP/1.1\r\nHost: 127.0.0.1\r\nX-", 47, MSG_NOSIGNAL);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    for (int fd : fds) ::close(fd);
  }
};

// The page used as meant: a browser asking for new rows ten times a second.
struct Browser {
  std::thread thread;
  std::atomic<bool> stop{false};
  std::atomic<int> asked{0}, answered{0};
  void start(int port) {
    thread = std::thread([this, port] {
      std::uint64_t next = 0;
      while (!stop.load()) {
        ++asked;
        const std::string a = request(port, "/data?since=" + std::to_string(next), 10.0);
        const auto at = a.find("\"next\":");
        if (a.rfind("HTTP/1.1 200", 0) == 0 && at != std::string::npos) {
          ++answered;
          next = std::stoull(a.substr(at + 7));
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    });
  }
  void end() {
    stop = true;
    thread.join();
  }
};

// A child process running `body`, which reads what it needs from `in` and writes its results to
// `out`; forked while this process has one thread, so the child starts clean.
struct Child {
  pid_t pid = -1;
  int in = -1, out = -1;  // the parent's ends
  explicit Child(const std::function<void(int in, int out)>& body) {
    int down[2], up[2];
    if (::pipe(down) != 0 || ::pipe(up) != 0) std::abort();
    pid = ::fork();
    if (pid == 0) {
      ::close(down[1]);
      ::close(up[0]);
      body(down[0], up[1]);
      std::_Exit(0);
    }
    ::close(down[0]);
    ::close(up[1]);
    in = up[0];
    out = down[1];
  }
  template <class T>
  void send(const T& v) const {
    if (::write(out, &v, sizeof v) != static_cast<ssize_t>(sizeof v)) std::abort();
  }
  template <class T>
  T receive() const {
    T v{};
    if (::read(in, &v, sizeof v) != static_cast<ssize_t>(sizeof v)) std::abort();
    return v;
  }
  ~Child() {
    ::close(in);
    ::close(out);
    ::waitpid(pid, nullptr, 0);
  }
};

template <class T>
T read_pipe(int fd) {
  T v{};
  if (::read(fd, &v, sizeof v) != static_cast<ssize_t>(sizeof v)) std::_Exit(1);
  return v;
}
template <class T>
void write_pipe(int fd, const T& v) {
  if (::write(fd, &v, sizeof v) != static_cast<ssize_t>(sizeof v)) std::_Exit(1);
}

struct StandInResult {
  std::uint64_t late = 0, answers = 0;
  int fifo = 0;
};

// The controller: RSI every 4 ms in real time for kCycles, to the port it is given.
void standin(int in, int out) {
  const int port = read_pipe<int>(in);
  const RobotModel robot = builtin_irb6700();
  JointVector q(6);
  q << 0, 20, 10, 0, 60, 0;
  q *= kPi / 180.0;
  const auto hold = std::make_shared<const JointTrajectory>(std::vector<double>{0.0, 1000.0},
                                                            std::vector<JointVector>{q, q}, robot, "hold");
  UdpTransport transport("127.0.0.1", 0);
  cell::RsiController controller(cell::RsiControllerConfig{}, robot, hold, transport,
                                 make_datagram_address("127.0.0.1", static_cast<std::uint16_t>(port)));
  sched_param fifo{};
  fifo.sched_priority = 10;
  StandInResult r;
  r.fifo = pthread_setschedparam(pthread_self(), SCHED_FIFO, &fifo) == 0 ? 1 : 0;
  const auto t0 = std::chrono::steady_clock::now();
  auto next = t0;
  for (int k = 0; k < kCycles && controller.running(); ++k) {
    controller.tick(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    next += std::chrono::milliseconds(4);
    std::this_thread::sleep_until(next);
  }
  r.late = controller.counters().late;
  r.answers = controller.counters().answers;
  write_pipe(out, r);
}

struct ClientsResult {
  int asked = 0, answered = 0, flood_answers = 0;
  double flood_mb = 0.0;
};

// The page's clients: the browser, and the abuse when asked, until the parent says stop.
void clients(int in, int out) {
  const int port = read_pipe<int>(in);
  const bool abusive = read_pipe<int>(in) != 0;
  Browser browser;
  browser.start(port);
  Abuse abuse;
  if (abusive) abuse.start(port);
  (void)read_pipe<int>(in);  // stop
  if (abusive) abuse.end();
  browser.end();
  ClientsResult r;
  r.asked = browser.asked;
  r.answered = browser.answered;
  r.flood_answers = abuse.flood_answers;
  r.flood_mb = static_cast<double>(abuse.flood_bytes.load()) / 1e6;
  write_pipe(out, r);
}

void run_session(benchmark::State& state, bool abusive, bool realtime) {
  const RobotModel robot = builtin_irb6700();
  for (auto _ : state) {
    const Child controller(standin);
    const Child page(clients);
    runtime::SessionConfig config;
    config.link = runtime::LinkKind::kRsi;
    config.network.rsi_port = 0;
    config.status_interval_s = 0.0;
    config.monitor = true;
    config.realtime.enabled = realtime;
    ConstantForce force;
    SteadyClock clock;
    std::promise<std::pair<int, std::shared_ptr<runtime::MonitorFeed>>> started;
    std::atomic<bool> stop{false};
    runtime::SessionSummary summary;
    std::string refused_realtime;
    // The session on a thread of its own, as `deflex online` runs it on its main thread.
    std::thread loop([&] {
      runtime::Session session(config, robot, SensorConfig{}, nullptr, nullptr, &force, clock);
      const std::string& where = session.where();
      started.set_value({std::stoi(where.substr(where.rfind(':') + 1)), session.monitor_feed()});
      try {
        while (!session.ended()) {
          if (stop.load()) session.request_stop();
          (void)session.run(0.1);
        }
      } catch (const std::exception& e) {  // real time refused (no CAP_SYS_NICE)
        refused_realtime = e.what();
        while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      summary = session.finish();
    });
    const auto [rsi_port, feed] = started.get_future().get();
    StandInResult standin_result;
    ClientsResult clients_result;
    int refused = 0;
    {
      monitor::MonitorServer server(feed, {"127.0.0.1", 0});
      page.send(server.port());
      page.send(abusive ? 1 : 0);
      std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the clients connected
      controller.send(rsi_port);
      standin_result = controller.receive<StandInResult>();
      page.send(0);
      clients_result = page.receive<ClientsResult>();
      refused = static_cast<int>(server.refused());
      stop = true;
      loop.join();
    }
    if (!refused_realtime.empty()) {
      state.SkipWithError(refused_realtime.c_str());
      break;
    }
    const nlohmann::json document = nlohmann::json::parse(summary.json_text);
    const auto& timing = document["timing"];
    const auto number = [](const nlohmann::json& v) { return v.is_number() ? v.get<double>() : 0.0; };
    state.counters["answers"] = static_cast<double>(summary.answers);
    state.counters["late"] = static_cast<double>(summary.late_answers);
    state.counters["answer_p50_ms"] = number(timing["answer_ms"]["p50"]);
    state.counters["answer_p99_ms"] = number(timing["answer_ms"]["p99"]);
    state.counters["answer_max_ms"] = number(timing["answer_ms"]["max"]);
    state.counters["controller_late"] = static_cast<double>(standin_result.late);
    state.counters["superseded"] = static_cast<double>(summary.counters.superseded);
    state.counters["largest_gap_ms"] = number(timing["largest_gap_ms"]);
    state.counters["standin_fifo"] = standin_result.fifo;
    state.counters["page_asked"] = clients_result.asked;
    state.counters["page_answered"] = clients_result.answered;
    state.counters["flood_answers"] = clients_result.flood_answers;
    state.counters["flood_MB"] = clients_result.flood_mb;
    state.counters["refused_503"] = refused;
  }
}

// The loop an ordinary thread (the worst case: every other process on the machine competes with it),
// then at SCHED_FIFO with its memory locked as `deflex online --realtime` runs it on a cell PC.
void BM_RsiAnswersWithThePageInUse(benchmark::State& state) { run_session(state, false, false); }
void BM_RsiAnswersWithThePageAbused(benchmark::State& state) { run_session(state, true, false); }
void BM_RsiAnswersWithThePageInUse_RealTime(benchmark::State& state) { run_session(state, false, true); }
void BM_RsiAnswersWithThePageAbused_RealTime(benchmark::State& state) { run_session(state, true, true); }

BENCHMARK(BM_RsiAnswersWithThePageInUse)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_RsiAnswersWithThePageAbused)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_RsiAnswersWithThePageInUse_RealTime)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_RsiAnswersWithThePageAbused_RealTime)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
}  // namespace deflex

BENCHMARK_MAIN();
