// The monitor's HTTP server with its limits (see bounded_http_server.hpp).
#include "deflex/monitor/detail/bounded_http_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <thread>
#include <vector>

namespace deflex::monitor::detail {
namespace {

using Clock = std::chrono::steady_clock;

// How the pool tells the server about the connection it hands over: cpp-httplib passes the server
// only the socket, so the accept time (the start of the connection's deadlines) and whether the
// connection is over the cap travel beside it, on the thread that runs the job.
thread_local Clock::time_point t_accepted{};
thread_local bool t_refuse = false;

// A thread that must never take a CPU from the session: SCHED_IDLE (any thread may lower itself to
// it), else the lowest nice value.
void lower_this_thread() {
  sched_param p{};
  if (pthread_setschedparam(pthread_self(), SCHED_IDLE, &p) != 0) {
    (void)setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 19);
  }
}

// cpp-httplib's task queue: a fixed number of low-priority threads and a cap on the connections
// open at once (waiting or served); a connection over the cap is handed back at once to be refused.
class IdleThreadPool final : public httplib::TaskQueue {
 public:
  IdleThreadPool(int threads, int max_connections) : max_connections_(static_cast<std::size_t>(max_connections)) {
    for (int k = 0; k < threads; ++k) threads_.emplace_back([this] { work(); });
  }
  ~IdleThreadPool() override = default;
  IdleThreadPool(const IdleThreadPool&) = delete;
  IdleThreadPool& operator=(const IdleThreadPool&) = delete;

  void enqueue(std::function<void()> fn) override {
    const auto now = Clock::now();
    {
      const std::lock_guard lock(mutex_);
      if (jobs_.size() + busy_ < max_connections_) {
        jobs_.push_back({std::move(fn), now});
        cv_.notify_one();
        return;
      }
    }
    // Over the cap: the job runs here, on the accepting thread, and only refuses (a 503 written
    // without waiting, the socket closed).
    t_refuse = true;
    fn();
    t_refuse = false;
  }

  void shutdown() override {
    {
      const std::lock_guard lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    for (auto& t : threads_) t.join();
  }

 private:
  struct Job {
    std::function<void()> fn;
    Clock::time_point accepted;
  };

  void work() {
    lower_this_thread();
    for (;;) {
      Job job;
      {
        std::unique_lock lock(mutex_);
        cv_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
        if (jobs_.empty()) return;  // stopping, and every waiting socket was closed
        job = std::move(jobs_.front());
        jobs_.pop_front();
        ++busy_;
      }
      t_accepted = job.accepted;
      job.fn();
      const std::lock_guard lock(mutex_);
      --busy_;
    }
  }

  std::size_t max_connections_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;
  std::size_t busy_ = 0;
  bool stop_ = false;
  std::vector<std::thread> threads_;
};

// The most one send() copies into the kernel: a large answer handed over whole keeps a CPU in the
// kernel's network code for milliseconds, where the thread's low priority does not count.
constexpr std::size_t kSendChunk = 16384;

// A connection's bytes with deadlines: every read waits at most until the request's deadline, every
// write until the answer's, and no more than `max_read` bytes are taken. Reads are buffered (the
// request parser asks for one byte at a time).
class DeadlineStream final : public httplib::Stream {
 public:
  DeadlineStream(int fd, Clock::time_point read_by, Clock::time_point write_by, std::size_t max_read,
                 const std::atomic<bool>& stopping)
      : fd_(fd), read_by_(read_by), write_by_(write_by), max_read_(max_read), stopping_(stopping) {}

  bool is_readable() const override { return pos_ < len_ || wait(POLLIN, read_by_); }
  bool is_writable() const override { return wait(POLLOUT, write_by_); }

  ssize_t read(char* ptr, size_t size) override {
    if (pos_ == len_) {
      if (taken_ >= max_read_ || !wait(POLLIN, read_by_)) return -1;
      const ssize_t n = ::recv(fd_, buf_, std::min(sizeof buf_, max_read_ - taken_), MSG_DONTWAIT);
      if (n <= 0) return n == 0 ? 0 : -1;
      pos_ = 0;
      len_ = static_cast<std::size_t>(n);
      taken_ += len_;
    }
    const std::size_t k = std::min(size, len_ - pos_);
    std::memcpy(ptr, buf_ + pos_, k);
    pos_ += k;
    return static_cast<ssize_t>(k);
  }

  // All of it or -1: the answer's headers go out in single writes.
  ssize_t write(const char* ptr, size_t size) override {
    std::size_t sent = 0;
    while (sent < size) {
      if (!wait(POLLOUT, write_by_)) return -1;
      const ssize_t n = ::send(fd_, ptr + sent, std::min(size - sent, kSendChunk), MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
      if (n <= 0) return -1;
      sent += static_cast<std::size_t>(n);
    }
    return static_cast<ssize_t>(size);
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override { address(::getpeername, ip, port); }
  void get_local_ip_and_port(std::string& ip, int& port) const override { address(::getsockname, ip, port); }
  socket_t socket() const override { return fd_; }

 private:
  bool wait(short events, Clock::time_point by) const {
    for (;;) {
      if (stopping_.load()) return false;
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(by - Clock::now()).count();
      if (left <= 0) return false;
      pollfd p{fd_, events, 0};
      const int r = ::poll(&p, 1, static_cast<int>(std::min<long long>(left, 1000)));
      if (r > 0) return (p.revents & (events | POLLHUP | POLLERR)) != 0;
      if (r < 0 && errno != EINTR) return false;
    }
  }

  template <class Get>
  void address(Get get, std::string& ip, int& port) const {
    sockaddr_in a{};
    socklen_t len = sizeof a;
    ip.clear();
    port = 0;
    if (get(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0 || a.sin_family != AF_INET) return;
    char text[INET_ADDRSTRLEN] = {};
    if (inet_ntop(AF_INET, &a.sin_addr, text, sizeof text) != nullptr) ip = text;
    port = ntohs(a.sin_port);
  }

  int fd_;
  Clock::time_point read_by_, write_by_;
  std::size_t max_read_;
  const std::atomic<bool>& stopping_;
  char buf_[4096] = {};
  std::size_t pos_ = 0, len_ = 0, taken_ = 0;
};

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

BoundedHttpServer::BoundedHttpServer(const MonitorLimits& limits) : limits_(limits) {
  new_task_queue = [this] { return new IdleThreadPool(limits_.threads, limits_.max_connections); };
  // The port for this server alone (see the header): SO_REUSEADDR only, SO_REUSEPORT never.
  set_socket_options([](socket_t sock) {
    const int yes = 1;
    (void)setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  set_payload_max_length(limits_.max_request_bytes);
}

BoundedHttpServer::~BoundedHttpServer() = default;

int BoundedHttpServer::bind_exclusive(const std::string& host, int port) {
  if (port == 0) return bind_to_any_port(host);
  return bind_to_port(host, port) ? port : -1;
}

void BoundedHttpServer::stop_all() {
  stopping_ = true;
  {
    const std::lock_guard lock(open_mutex_);
    for (socket_t s : open_) ::shutdown(s, SHUT_RDWR);
  }
  stop();
}

bool BoundedHttpServer::track(socket_t sock) {
  const std::lock_guard lock(open_mutex_);
  if (stopping_.load()) return false;
  open_.insert(sock);
  return true;
}

void BoundedHttpServer::untrack(socket_t sock) {
  const std::lock_guard lock(open_mutex_);
  open_.erase(sock);
}

void BoundedHttpServer::refuse(socket_t sock) {
  static const std::string kBusy = [] {
    const std::string body = "the monitor is serving as many clients as it takes; try again\n";
    return "HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain\r\nConnection: close\r\nContent-Length: " +
           std::to_string(body.size()) + "\r\n\r\n" + body;
  }();
  (void)::send(sock, kBusy.data(), kBusy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  ++refused_;
}

bool BoundedHttpServer::listen_lowered() {
  lower_this_thread();
  return listen_after_bind();
}

bool BoundedHttpServer::process_and_close_socket(socket_t sock) {
  bool served = false;
  if (t_refuse) {
    refuse(sock);
  } else if (track(sock)) {
    const auto read_by = t_accepted + seconds(limits_.request_deadline_s);
    DeadlineStream stream(sock, read_by, read_by + seconds(limits_.answer_deadline_s), limits_.max_request_bytes,
                          stopping_);
    bool closed = true;
    served = process_request(stream, /*close_connection=*/true, closed, [](httplib::Request&) {});
    untrack(sock);
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  return served;
}

}  // namespace deflex::monitor::detail
