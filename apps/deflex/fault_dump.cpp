// `deflex online --fault-dump` (see fault_dump.hpp).
#include "fault_dump.hpp"

#include <cstdio>

#include <fmt/format.h>

#include "deflex/link/link_history.hpp"
#include "deflex/model/errors.hpp"

namespace deflex::cli {

FaultDump::FaultDump(std::string path, double quiet_s, std::shared_ptr<spdlog::logger> log)
    : path_(std::move(path)), quiet_s_(quiet_s), log_(std::move(log)) {
  // Checked now: an unwritable path must not end a run at its first fault.
  if (!path_.empty()) {
    std::FILE* probe = std::fopen(path_.c_str(), "a");
    if (probe == nullptr) throw Error(fmt::format("{}: cannot write the fault dump", path_));
    std::fclose(probe);
  }
}

FaultDump::~FaultDump() {
  if (writer_.joinable()) writer_.join();
}

void FaultDump::on_cycle(double now_s, ControllerLink& link) {
  const bool fault = link.fault_pending();
  link.clear_fault();
  if (in_episode_ && !fault && now_s - last_fault_s_ > quiet_s_) end_episode(now_s);
  if (!fault) return;
  ++faulted_total_;
  last_fault_s_ = now_s;
  if (in_episode_) {
    ++faulted_;
    return;
  }
  in_episode_ = true;
  began_s_ = now_s;
  faulted_ = 1;
  ++episodes_;
  const LinkCycleRecord& r = link.last_cycle();
  log_->warn("fault episode {} began: status {}, |F| {:.1f} N{}", episodes_, to_string(r.status),
             r.wrench_measured_base.head<3>().norm(),
             r.replied ? "" : " (that message was not answered)");
  if (!path_.empty()) write(link);
}

void FaultDump::end_episode(double now_s) {
  in_episode_ = false;
  log_->info("fault episode {} ended: {} faulted cycles over {:.2f} s", episodes_, faulted_, last_fault_s_ - began_s_);
  (void)now_s;
}

void FaultDump::finish(double now_s) {
  if (in_episode_) end_episode(now_s);
  if (writer_.joinable()) writer_.join();
}

void FaultDump::write(const ControllerLink& link) {
  if (writing_.load()) {
    log_->warn("fault episode {}: the previous dump is still being written; this episode's is skipped", episodes_);
    return;
  }
  const LinkHistory* ring = link.history();
  if (ring == nullptr) {  // a link without a ring to copy: written here, once per episode all the same
    try {
      link.write_history_csv(path_);
      log_->warn("fault episode {}: last cycles written to {}", episodes_, path_);
    } catch (const Error& e) {
      log_->error("fault episode {}: {}", episodes_, e.what());
    }
    return;
  }
  if (writer_.joinable()) writer_.join();
  auto copy = std::make_shared<const LinkHistory>(*ring);  // between polls: the ring is not being written
  writing_ = true;
  writer_ = std::thread([this, copy, episode = episodes_] {
    try {
      copy->write_csv(path_);
      log_->warn("fault episode {}: last {} cycles written to {}", episode, copy->size(), path_);
    } catch (const Error& e) {
      log_->error("fault episode {}: {}", episode, e.what());
    }
    writing_ = false;
  });
}

}  // namespace deflex::cli
