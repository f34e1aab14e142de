// Ring of a link's last cycles (see link_history.hpp).
#include "deflex/link/link_history.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdio>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

const char* to_string(LinkState s) {
  switch (s) {
    case LinkState::kWaiting: return "waiting";
    case LinkState::kRunning: return "running";
    case LinkState::kFinished: return "finished";
    case LinkState::kRefused: return "refused";
    case LinkState::kStopped: return "stopped";
  }
  return "unknown";
}

const char* to_string(LinkStopCause c) {
  switch (c) {
    case LinkStopCause::kNone: return "not stopped";
    case LinkStopCause::kRequested: return "stop requested";
    case LinkStopCause::kProtocol: return "protocol error";
    case LinkStopCause::kConnection: return "connection lost";
    case LinkStopCause::kController: return "controller refused or faulted";
    case LinkStopCause::kSafety: return "safety check";
  }
  return "unknown";
}

LinkHistory::LinkHistory(std::size_t cycles, int joints) : joints_(joints) {
  blank_.q_nominal = blank_.q_feedback = blank_.q_command = blank_.dtheta = JointVector::Zero(joints);
  ring_.assign(std::max<std::size_t>(cycles, 1), blank_);
}

void LinkHistory::record(const LinkCycleRecord& r) noexcept {
  ring_[head_] = r;
  head_ = (head_ + 1) % ring_.size();
  count_ = std::min(count_ + 1, ring_.size());
}

void LinkHistory::write_csv(const std::string& path) const {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    throw Error(fmt::format("{}: cannot write the link's cycle history", path));
  }
  std::string header = "t_s,program_t_s,sequence,status,replied";
  for (const char* name : {"q_nominal", "q_feedback", "q_command", "dtheta"}) {
    for (int j = 1; j <= joints_; ++j) {
      header += fmt::format(",{}{}_deg", name, j);
    }
  }
  header += ",corr_x_mm,corr_y_mm,corr_z_mm,rot_uncorrected_mrad,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,"
            "meas_fx_N,meas_fy_N,meas_fz_N,delay_ms,compute_ms,arrival_delay_ms,jitter_ms,missed_before\n";
  std::fputs(header.c_str(), f);
  const std::size_t size = ring_.size();
  const std::size_t first = (head_ + size - count_) % size;
  for (std::size_t k = 0; k < count_; ++k) {
    const LinkCycleRecord& r = ring_[(first + k) % size];
    std::fprintf(f, "%.6f,%.6f,%" PRIu64 ",%d,%d", r.t_s, r.program_time_s, r.sequence, static_cast<int>(r.status),
                 r.replied ? 1 : 0);
    for (const JointVector* q : {&r.q_nominal, &r.q_feedback, &r.q_command, &r.dtheta}) {
      for (int j = 0; j < q->size(); ++j) {
        std::fprintf(f, ",%.10g", rad_to_deg((*q)[j]));
      }
    }
    std::fprintf(f, ",%.6f,%.6f,%.6f,%.6f", r.tcp_correction_m.x() * 1e3, r.tcp_correction_m.y() * 1e3,
                 r.tcp_correction_m.z() * 1e3, r.rotation_uncorrected_rad * 1e3);
    for (int j = 0; j < 6; ++j) {
      std::fprintf(f, ",%.6g", r.wrench_base[j]);
    }
    for (int j = 0; j < 3; ++j) {
      std::fprintf(f, ",%.6g", r.wrench_measured_base[j]);
    }
    std::fprintf(f, ",%.3f,%.4f,%.3f,%.3f,%" PRIu64 "\n", r.delay_s * 1e3, r.compute_s * 1e3,
                 r.arrival.arrival_delay_s * 1e3, r.arrival.jitter_s * 1e3, r.arrival.missed_before);
  }
  const bool ok = std::ferror(f) == 0;
  if (std::fclose(f) != 0 || !ok) {
    throw Error(fmt::format("{}: write failed", path));
  }
}

}  // namespace deflex
