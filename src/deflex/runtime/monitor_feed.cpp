// The live monitor's data (see monitor_feed.hpp).
#include "deflex/runtime/monitor_feed.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "deflex/runtime/session_settings.hpp"

namespace deflex::runtime {

// Rows in fixed blocks: the writer fills a block's rows in order and readers read only the rows below
// the count their snapshot was published with, so no row is written while it can be read.
struct MonitorFeed::Block {
  static constexpr std::size_t kRows = 256;
  explicit Block(std::uint64_t first_index) : first(first_index), rows(new MonitorRow[kRows]) {}
  std::uint64_t first;
  std::unique_ptr<MonitorRow[]> rows;
};

struct MonitorFeed::Snapshot {
  std::vector<std::shared_ptr<Block>> blocks;
  std::uint64_t first = 0, next = 0;
  std::string state, stop_reason;
  std::shared_ptr<const std::vector<MonitorEvent>> events;
};

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

// The settings as the page lists them: each with its unit and help (range and links included) from the
// settings table, found by the option; one the table does not know (a log from another version of
// deflex) keeps its option and value alone.
std::string settings_json(const std::vector<ShownSetting>& settings) {
  std::string out = "\"settings\":[";
  for (std::size_t i = 0; i < settings.size(); ++i) {
    const ShownSetting& shown = settings[i];
    const SessionSetting* s = find_session_setting(shown.option);
    std::string unit, key, help;
    if (s != nullptr) {
      unit = std::string(s->option_unit.empty() ? s->unit : s->option_unit);
      key = std::string(s->key);
      help = option_help(*s);
    }
    fmt::format_to(std::back_inserter(out),
                   "{}{{\"option\":\"{}\",\"key\":\"{}\",\"value\":\"{}\",\"unit\":\"{}\",\"help\":\"{}\"}}",
                   i > 0 ? "," : "", json_text(shown.option), json_text(key), json_text(shown.value), json_text(unit),
                   json_text(help));
  }
  out += "],";
  return out;
}

// The counters whose every increase is a mark on the timeline.
struct CountedEvent {
  std::uint64_t MonitorRow::*count;
  const char* kind;
  const char* text;
};
constexpr CountedEvent kCountedEvents[] = {
    {&MonitorRow::guard_trips, "guard trip", "the command guard held a command that broke its bounds"},
    {&MonitorRow::restarts, "restart", "the controller started a new session"},
    {&MonitorRow::silences, "silence", "the controller was silent; the link rode through"},
    {&MonitorRow::rejected, "rejected", "messages refused (not usable)"},
};

}  // namespace

const char* monitor_status_name(int status) {
  switch (status) {
    case 0:
      return "ok";
    case 1:
      return "no force yet";
    case 2:
      return "stale force";
    case 3:
      return "force fault";
    case 4:
      return "held";
    case -1:
      return "invalid input";
    default:
      return "unknown";
  }
}

MonitorRow monitor_row(const SessionEntry& e) {
  const LinkCycleRecord& r = e.record;
  const LinkCounters& c = e.counters;
  MonitorRow row;
  row.t_s = e.kind == SessionEntry::Kind::kCycle ? r.t_s : e.t_s;
  row.program_t_s = r.program_time_s;
  row.sequence = r.sequence;
  row.status = static_cast<int>(r.status);
  row.replied = r.replied;
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

MonitorFeed::MonitorFeed(MonitorSetup setup)
    : setup_(std::move(setup)), settings_json_(settings_json(setup_.settings)) {
  auto empty = std::make_shared<Snapshot>();
  empty->state = state_;
  empty->events = std::make_shared<const std::vector<MonitorEvent>>();
  published_ = std::move(empty);
}

MonitorFeed::~MonitorFeed() = default;

void MonitorFeed::add_event(double t_s, const char* kind, std::string text) {
  for (auto it = events_.rbegin(); it != events_.rend(); ++it) {
    if (it->kind != kind || it->text != text) continue;
    if (t_s - it->last_t_s < MonitorEvent::kMergeS) {
      ++it->count;
      it->last_t_s = t_s;
      events_changed_ = true;
      return;
    }
    break;
  }
  if (events_.size() >= kMaxEvents) events_.erase(events_.begin());
  events_.push_back({t_s, t_s, kind, std::move(text), 1});
  events_changed_ = true;
}

void MonitorFeed::note_events(const MonitorRow& row) {
  // A compensator status that holds the correction back, from the cycle it began.
  const bool began = !have_last_ || row.status != last_.status;
  if (began && row.status != 0 && row.status != 1) {
    add_event(row.t_s, monitor_status_name(row.status),
              fmt::format("the compensator: {}", monitor_status_name(row.status)));
  }
  if (!have_last_) return;
  for (const CountedEvent& c : kCountedEvents) {
    if (row.*c.count > last_.*c.count) add_event(row.t_s, c.kind, c.text);
  }
}

void MonitorFeed::add(MonitorRow row) {
  if (row.replied) {
    ++answers_;
    if (setup_.period_s > 0.0 && row.answer_ms > setup_.period_s * 1e3) ++late_answers_;
  }
  row.answers = answers_;
  row.late_answers = late_answers_;
  note_events(row);
  last_ = row;
  have_last_ = true;
  if (blocks_.empty() || next_ - blocks_.back()->first == Block::kRows) {
    blocks_.push_back(std::make_shared<Block>(next_));
  }
  blocks_.back()->rows[next_ - blocks_.back()->first] = row;
  ++next_;
  dirty_ = true;
  if (!setup_.recorded) {
    // The window: rows older than window_s before this one go, and the blocks that held only them.
    const auto row_at = [this](std::uint64_t i) -> const MonitorRow& {
      const auto b =
          std::upper_bound(blocks_.begin(), blocks_.end(), i,
                           [](std::uint64_t v, const std::shared_ptr<Block>& blk) { return v < blk->first; });
      return (*(b - 1))->rows[i - (*(b - 1))->first];
    };
    while (first_ + 1 < next_ && row_at(first_).t_s < row.t_s - setup_.window_s) ++first_;
    while (blocks_.size() > 1 && blocks_[1]->first <= first_) blocks_.erase(blocks_.begin());
    if (row.t_s - published_t_s_ >= 0.05 || next_ - published_next_ >= 64) publish(false);
  }
}

void MonitorFeed::add(const SessionEntry& entry) {
  if (entry.kind == SessionEntry::Kind::kCycle) {
    add(monitor_row(entry));
  } else if (!setup_.recorded) {
    publish(false);  // the controller is silent: the last rows go out now, not with the next one
  }
}

void MonitorFeed::set_state(const std::string& state, const std::string& stop_reason) {
  // The stop on the timeline at the last cycle, with its reason (a recorded log's too).
  const double t = have_last_ ? last_.t_s : 0.0;
  if (!stop_reason.empty() && stop_reason != stop_reason_) {
    add_event(t, "stop", stop_reason);
  } else if (state != state_ && state == "ended") {
    add_event(t, "stop", "the session ended");
  } else if (state != state_ && state != "recorded") {
    add_event(t, "state", state);
  }
  state_ = state;
  stop_reason_ = stop_reason;
  dirty_ = true;
  publish(state == "ended" || state == "recorded");
}

void MonitorFeed::flush() { publish(true); }

void MonitorFeed::publish(bool wait) {
  if (!dirty_) return;
  auto snap = std::make_shared<Snapshot>();
  snap->blocks = blocks_;
  snap->first = first_;
  snap->next = next_;
  snap->state = state_;
  snap->stop_reason = stop_reason_;
  if (events_changed_ || !events_published_) {
    events_published_ = std::make_shared<const std::vector<MonitorEvent>>(events_);
    events_changed_ = false;
  }
  snap->events = events_published_;
  std::shared_ptr<const Snapshot> old;
  {
    std::unique_lock lock(mutex_, std::defer_lock);
    if (wait) {
      lock.lock();
    } else if (!lock.try_lock()) {
      return;  // a reader holds it: the next row publishes
    }
    old = std::exchange(published_, std::move(snap));
  }
  dirty_ = false;
  published_next_ = next_;
  published_t_s_ = have_last_ ? last_.t_s : published_t_s_;
}

std::uint64_t MonitorFeed::rows_added() const {
  const std::lock_guard lock(mutex_);
  return published_->next;
}

namespace {

void json_events(std::string& out, const std::vector<MonitorEvent>& events) {
  out += "\"events\":[";
  for (std::size_t i = 0; i < events.size(); ++i) {
    const MonitorEvent& e = events[i];
    if (i > 0) out += ',';
    out += "{\"t\":";
    json_number(out, e.t_s);
    out += ",\"last_t\":";
    json_number(out, e.last_t_s);
    fmt::format_to(std::back_inserter(out), ",\"kind\":\"{}\",\"text\":\"{}\",\"count\":{}}}", json_text(e.kind),
                   json_text(e.text), e.count);
  }
  out += "],";
}

}  // namespace

namespace {

// The rows as columns, {"t":[...],"fz":[...],...} (units as MonitorRow's).
void json_rows(std::string& out, const std::vector<const MonitorRow*>& rows, int joints) {
  out += "\"rows\":{";
  auto column = [&](const char* name, auto get) {
    if (out.back() != '{') out += ',';
    fmt::format_to(std::back_inserter(out), "\"{}\":[", name);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (i > 0) out += ',';
      json_number(out, static_cast<double>(get(*rows[i])));
    }
    out += ']';
  };
  column("t", [](const MonitorRow& r) { return r.t_s; });
  column("pt", [](const MonitorRow& r) { return r.program_t_s; });
  column("seq", [](const MonitorRow& r) { return static_cast<double>(r.sequence); });
  column("st", [](const MonitorRow& r) { return r.status; });
  static const char* kWrench[6] = {"fx", "fy", "fz", "mx", "my", "mz"};
  for (int k = 0; k < 6; ++k) column(kWrench[k], [k](const MonitorRow& r) { return r.wrench[k]; });
  static const char* kRaw[3] = {"rfx", "rfy", "rfz"};
  for (int k = 0; k < 3; ++k) column(kRaw[k], [k](const MonitorRow& r) { return r.raw_force[k]; });
  for (int j = 0; j < joints && j < kMaxJoints; ++j) {
    const std::string name = fmt::format("d{}", j + 1);
    column(name.c_str(), [j](const MonitorRow& r) { return r.dtheta_deg[j]; });
  }
  static const char* kTcp[3] = {"cx", "cy", "cz"};
  for (int k = 0; k < 3; ++k) column(kTcp[k], [k](const MonitorRow& r) { return r.tcp_mm[k]; });
  column("delay", [](const MonitorRow& r) { return r.delay_ms; });
  column("answer", [](const MonitorRow& r) { return r.replied ? r.answer_ms : std::nan(""); });
  column("arrival", [](const MonitorRow& r) { return r.arrival_ms; });
  column("jitter", [](const MonitorRow& r) { return r.jitter_ms; });
  const std::pair<const char*, std::uint64_t MonitorRow::*> counts[] = {
      {"missed", &MonitorRow::missed},
      {"duplicates", &MonitorRow::duplicates},
      {"superseded", &MonitorRow::superseded},
      {"rejected", &MonitorRow::rejected},
      {"restarts", &MonitorRow::restarts},
      {"late", &MonitorRow::late},
      {"controller_late", &MonitorRow::controller_late},
      {"silences", &MonitorRow::silences},
      {"guard_trips", &MonitorRow::guard_trips},
      {"answers", &MonitorRow::answers},
      {"late_answers", &MonitorRow::late_answers}};
  for (const auto& count : counts) {
    const auto member = count.second;
    column(count.first, [member](const MonitorRow& r) { return static_cast<double>(r.*member); });
  }
  out += '}';
}

}  // namespace

std::string MonitorFeed::json(std::uint64_t since, std::size_t max_rows) const {
  std::shared_ptr<const Snapshot> snap;
  {
    const std::lock_guard lock(mutex_);
    snap = published_;
  }
  const std::uint64_t from = std::min(std::max(since, snap->first), snap->next);
  const std::uint64_t to = snap->next - from <= max_rows ? snap->next : from + std::max<std::size_t>(max_rows, 1);
  // The rows [from, to) in order, from the snapshot's blocks.
  std::vector<const MonitorRow*> rows;
  rows.reserve(to - from);
  auto b = std::upper_bound(snap->blocks.begin(), snap->blocks.end(), from,
                            [](std::uint64_t v, const std::shared_ptr<Block>& blk) { return v < blk->first; });
  for (std::uint64_t i = from; i < to; ++i) {
    while (b != snap->blocks.end() && (*b)->first <= i) ++b;
    const Block& blk = **(b - 1);
    rows.push_back(&blk.rows[i - blk.first]);
  }
  std::string out;
  out.reserve(1024 + rows.size() * 460);
  fmt::format_to(std::back_inserter(out),
                 "{{\"link\":\"{}\",\"joints\":{},\"force_components\":{},\"period_ms\":{},\"joint_bound_deg\":{},"
                 "\"tcp_bound_mm\":{},\"force_fault_n\":{},\"program_duration_s\":{},\"window_s\":{},\"recorded\":{},"
                 "\"source\":\"{}\",\"first\":{},\"next\":{},\"more\":{},\"state\":\"{}\",\"stop_reason\":\"{}\",",
                 json_text(setup_.link), setup_.joints, setup_.force_components, setup_.period_s * 1e3,
                 setup_.joint_bound_deg, setup_.tcp_bound_mm, setup_.force_fault_n, setup_.program_duration_s,
                 setup_.window_s, setup_.recorded ? "true" : "false", json_text(setup_.source), snap->first, to,
                 to < snap->next ? "true" : "false", json_text(snap->state), json_text(snap->stop_reason));
  out += settings_json_;
  json_events(out, *snap->events);
  json_rows(out, rows, setup_.joints);
  out += '}';
  return out;
}

}  // namespace deflex::runtime
