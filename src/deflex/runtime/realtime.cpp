// Real-time execution (see realtime.hpp).
#include "deflex/runtime/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex::runtime {

void RealtimeOptions::validate() const {
  if (!enabled) return;
  const int lo = sched_get_priority_min(SCHED_FIFO), hi = sched_get_priority_max(SCHED_FIFO);
  if (priority < lo || priority > hi) {
    throw InputError(fmt::format("option --rt-priority: SCHED_FIFO priorities are {}..{} (got {})", lo, hi, priority));
  }
  if (cpu < -1 || cpu >= CPU_SETSIZE) {
    throw InputError(fmt::format("option --rt-cpu: a CPU number 0..{} (got {})", CPU_SETSIZE - 1, cpu));
  }
}

int allowed_cpu_count() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return 0;
  return CPU_COUNT(&set);
}

namespace {

std::string rlimit_text(int resource) {
  rlimit r{};
  if (getrlimit(resource, &r) != 0) return "unknown";
  return r.rlim_cur == RLIM_INFINITY ? std::string("unlimited") : std::to_string(r.rlim_cur);
}

std::string allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return "unknown";
  std::string out;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (!CPU_ISSET(c, &set)) continue;
    if (!out.empty()) out += ',';
    out += fmt::format("{}", c);
  }
  return out;
}

}  // namespace

RealtimeGrant make_current_thread_realtime(const RealtimeOptions& o) {
  o.validate();
  RealtimeGrant g;
  if (!o.enabled) {
    g.text = "not real-time (ordinary scheduling; --realtime to ask for SCHED_FIFO)";
    return g;
  }
  if (o.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(o.cpu, &set);
    const int err = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (err != 0) {
      throw InputError(
          fmt::format("option --rt-cpu: CPU {} is not available to this process ({}; the CPUs it may use: "
                      "{})",
                      o.cpu, std::strerror(err), allowed_cpus()));
    }
    g.pinned = true;
  }
  sched_param p{};
  p.sched_priority = o.priority;
  const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
  if (err != 0) {
    throw InputError(fmt::format(
        "option --realtime: the system refused SCHED_FIFO priority {} ({}): it needs the CAP_SYS_NICE capability or a "
        "real-time priority limit of at least {} (now {}: `ulimit -r`; grant it in /etc/security/limits.conf, e.g. "
        "'@realtime - rtprio 95', and log in again), docs/online.md \"Real-time setup\"",
        o.priority, std::strerror(err), o.priority, rlimit_text(RLIMIT_RTPRIO)));
  }
  g.scheduler = true;
  if (o.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
      const int e = errno;
      // Undo the scheduling class, so a refused start does not leave a real-time thread behind.
      sched_param normal{};
      pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal);
      throw InputError(fmt::format(
          "option --realtime: the system refused to lock the process's memory ({}): it needs the CAP_IPC_LOCK "
          "capability or a locked-memory limit large enough for deflex (now {} bytes: `ulimit -l` shows KiB; grant it "
          "in "
          "/etc/security/limits.conf, e.g. '@realtime - memlock unlimited'), or --rt-no-mlock",
          std::strerror(e), rlimit_text(RLIMIT_MEMLOCK)));
    }
    g.locked = true;
  }
  g.text = fmt::format("SCHED_FIFO priority {}{}{}", o.priority, g.pinned ? fmt::format(" on CPU {}", o.cpu) : "",
                       g.locked ? ", memory locked" : ", memory not locked");
  return g;
}

}  // namespace deflex::runtime
