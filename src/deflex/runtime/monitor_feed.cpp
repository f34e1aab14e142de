// The live monitor's data (see monitor_feed.hpp).
#include "deflex/runtime/monitor_feed.hpp"

#include <cmath>
#include <vector>

#include <fmt/format.h>

namespace deflex::runtime {
namespace {

void json_number(std::string& out, double v) {
  if (std::isfinite(v)) {
    fmt::format_to(std::back_inserter(out), "{:.6g}", v);
  } else {
    out += "null";
  }
}

// A JSON string's content: quotes and backslashes escaped, control characters left out.
std::string json_text(const std::string& text) {
  std::string out;
  for (char ch : text) {
    if (ch == '"' || ch == '\\') out += '\\';
    if (static_cast<unsigned char>(ch) >= 0x20) out += ch;
  }
  return out;
}

}  // namespace

MonitorRow monitor_row(const SessionEntry& e) {
  const LinkCycleRecord& r = e.record;
  const LinkCounters& c = e.counters;
  MonitorRow row;
  row.t_s = e.kind == SessionEntry::Kind::kCycle ? r.t_s : e.t_s;
  row.program_t_s = r.program_time_s;
  row.sequence = r.sequence;
  row.status = static_cast<int>(r.status);
  for (int k = 0; k < 6; ++k) row.wrench[k] = r.wrench_base[k];
  for (int k = 0; k < 3; ++k) row.raw_force[k] = r.wrench_measured_base[k];
  for (int j = 0; j < r.dtheta.size() && j < kMaxJoints; ++j) row.dtheta_deg[j] = rad_to_deg(r.dtheta[j]);
  for (int k = 0; k < 3; ++k) row.tcp_mm[k] = r.tcp_correction_m[k] * 1e3;
  row.delay_ms = r.delay_s * 1e3;
  row.answer_ms = r.answer_s * 1e3;
  row.arrival_ms = r.arrival.arrival_delay_s * 1e3;
  row.jitter_ms = r.arrival.jitter_s * 1e3;
  row.missed = c.missed;
  row.duplicates = c.duplicate;
  row.superseded = c.superseded;
  row.rejected = c.rejected();
  row.restarts = c.restarts;
  row.late = c.late;
  row.controller_late = c.controller_late;
  row.silences = c.silences;
  row.guard_trips = c.guard_trips;
  return row;
}

MonitorFeed::MonitorFeed(MonitorSetup setup) : setup_(std::move(setup)) {}

void MonitorFeed::add(const MonitorRow& row) {
  const std::lock_guard lock(mutex_);
  rows_.push_back(row);
  if (!setup_.recorded) {
    while (rows_.size() > 1 && rows_.front().t_s < row.t_s - setup_.window_s) {
      rows_.pop_front();
      ++first_index_;
    }
  }
}

void MonitorFeed::add(const SessionEntry& entry) {
  if (entry.kind != SessionEntry::Kind::kCycle) return;
  add(monitor_row(entry));
}

void MonitorFeed::set_state(const std::string& state, const std::string& stop_reason) {
  const std::lock_guard lock(mutex_);
  state_ = state;
  stop_reason_ = stop_reason;
}

std::uint64_t MonitorFeed::rows_added() const {
  const std::lock_guard lock(mutex_);
  return first_index_ + rows_.size();
}

std::string MonitorFeed::json(std::uint64_t since) const {
  std::vector<MonitorRow> rows;
  std::uint64_t next = 0;
  std::string state, stop;
  {
    // Copy under the lock, format outside it: the writer waits for a copy at most.
    const std::lock_guard lock(mutex_);
    const std::uint64_t from = std::max(since, first_index_);
    next = first_index_ + rows_.size();
    if (from < next) rows.assign(rows_.begin() + static_cast<std::ptrdiff_t>(from - first_index_), rows_.end());
    state = state_;
    stop = stop_reason_;
  }
  std::string out;
  out.reserve(512 + rows.size() * 420);
  fmt::format_to(std::back_inserter(out),
                 "{{\"link\":\"{}\",\"joints\":{},\"joint_bound_deg\":{},\"tcp_bound_mm\":{},\"program_duration_s\":{},"
                 "\"window_s\":{},\"recorded\":{},\"next\":{},\"state\":\"{}\",\"stop_reason\":\"{}\",\"rows\":{{",
                 json_text(setup_.link), setup_.joints, setup_.joint_bound_deg, setup_.tcp_bound_mm,
                 setup_.program_duration_s, setup_.window_s, setup_.recorded ? "true" : "false", next, json_text(state),
                 json_text(stop));
  auto column = [&](const char* name, auto get, bool first = false) {
    if (!first) out += ',';
    fmt::format_to(std::back_inserter(out), "\"{}\":[", name);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (i > 0) out += ',';
      json_number(out, static_cast<double>(get(rows[i])));
    }
    out += ']';
  };
  column(
      "t", [](const MonitorRow& r) { return r.t_s; }, true);
  column("pt", [](const MonitorRow& r) { return r.program_t_s; });
  column("seq", [](const MonitorRow& r) { return static_cast<double>(r.sequence); });
  column("st", [](const MonitorRow& r) { return r.status; });
  static const char* kWrench[6] = {"fx", "fy", "fz", "mx", "my", "mz"};
  for (int k = 0; k < 6; ++k) column(kWrench[k], [k](const MonitorRow& r) { return r.wrench[k]; });
  static const char* kRaw[3] = {"rfx", "rfy", "rfz"};
  for (int k = 0; k < 3; ++k) column(kRaw[k], [k](const MonitorRow& r) { return r.raw_force[k]; });
  for (int j = 0; j < setup_.joints && j < kMaxJoints; ++j) {
    const std::string name = fmt::format("d{}", j + 1);
    column(name.c_str(), [j](const MonitorRow& r) { return r.dtheta_deg[j]; });
  }
  static const char* kTcp[3] = {"cx", "cy", "cz"};
  for (int k = 0; k < 3; ++k) column(kTcp[k], [k](const MonitorRow& r) { return r.tcp_mm[k]; });
  column("delay", [](const MonitorRow& r) { return r.delay_ms; });
  column("answer", [](const MonitorRow& r) { return r.answer_ms; });
  column("arrival", [](const MonitorRow& r) { return r.arrival_ms; });
  column("jitter", [](const MonitorRow& r) { return r.jitter_ms; });
  column("missed", [](const MonitorRow& r) { return static_cast<double>(r.missed); });
  column("duplicates", [](const MonitorRow& r) { return static_cast<double>(r.duplicates); });
  column("superseded", [](const MonitorRow& r) { return static_cast<double>(r.superseded); });
  column("rejected", [](const MonitorRow& r) { return static_cast<double>(r.rejected); });
  column("restarts", [](const MonitorRow& r) { return static_cast<double>(r.restarts); });
  column("late", [](const MonitorRow& r) { return static_cast<double>(r.late); });
  column("controller_late", [](const MonitorRow& r) { return static_cast<double>(r.controller_late); });
  column("silences", [](const MonitorRow& r) { return static_cast<double>(r.silences); });
  column("guard_trips", [](const MonitorRow& r) { return static_cast<double>(r.guard_trips); });
  out += "}}";
  return out;
}

}  // namespace deflex::runtime
