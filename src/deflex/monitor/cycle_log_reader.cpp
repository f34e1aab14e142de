// A cycle log read back for the monitor (see cycle_log_reader.hpp).
#include "deflex/monitor/cycle_log_reader.hpp"

#include <cmath>
#include <map>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "deflex/runtime/cycle_log.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex::monitor {
namespace {

constexpr std::size_t kNoColumn = static_cast<std::size_t>(-1);

std::vector<std::string_view> cells_of(std::string_view line) {
  std::vector<std::string_view> out;
  for_each_csv_cell(line, [&out](std::string_view cell) { out.push_back(cell); });
  return out;
}

// "# deflex cycle log: link=rsi period_ms=4 force_components=3 force_fault_N=2000" into the setup (a log
// written before the line existed: the link is not known, nor the cycle its answers are late against).
void read_preamble(std::string_view line, runtime::MonitorSetup& setup) {
  line.remove_prefix(std::string_view(runtime::kCycleLogPreamble).size());
  std::size_t at = 0;
  while (at < line.size()) {
    const std::size_t end = std::min(line.find(' ', at), line.size());
    const std::string_view word = line.substr(at, end - at);
    at = end + 1;
    const auto eq = word.find('=');
    if (eq == std::string_view::npos) continue;
    const std::string_view key = word.substr(0, eq), value = word.substr(eq + 1);
    if (key == "link") {
      setup.link = std::string(value);
    } else if (key == "period_ms") {
      const auto v = parse_double(value);
      if (v && *v > 0.0 && std::isfinite(*v)) setup.period_s = *v * 1e-3;
    } else if (key == "force_fault_N") {
      const auto v = parse_double(value);
      if (v && *v > 0.0 && std::isfinite(*v)) setup.force_fault_n = *v;
    } else if (key == "force_components") {
      const auto v = parse_int64(value);
      if (v && (*v == 3 || *v == 6)) setup.force_components = static_cast<int>(*v);
    }
  }
}

// The log's columns, by index into a row's cells.
struct Columns {
  std::size_t t, pt, seq, st, w[6], raw[3], d[kMaxJoints], c[3], delay, answer, arrival, jitter, missed_before, dup,
      sup, rej, rst, late, clate, sil, guard;
  std::size_t replied = kNoColumn;  // a log written before the column existed: every cycle answered
};

// One log read line by line: its first and last comment lines, the header, the rows into the feed.
class LogReader {
 public:
  explicit LogReader(std::string path) : path_(std::move(path)) {
    setup_.recorded = true;
    setup_.source = path_;
    setup_.link = "not in the log";
    setup_.force_components = 0;
  }

  void line(std::string_view line, int line_no) {
    line_no_ = line_no;
    if (line[0] == '#') {
      comment(line);
    } else if (header_.empty()) {
      header(cells_of(line));
    } else {
      row(cells_of(line));
    }
  }

  std::shared_ptr<runtime::MonitorFeed> finish() {
    if (header_.empty()) throw DataError(fmt::format("{}: no header row: not a deflex cycle log", path_));
    if (!feed_) throw DataError(fmt::format("{}: no cycles (only the header)", path_));
    feed_->set_state("recorded", stop_reason_);
    return feed_;
  }

 private:
  void comment(std::string_view line) {
    const std::string_view preamble = runtime::kCycleLogPreamble, stop = runtime::kCycleLogStop;
    const std::string_view setting = runtime::kCycleLogSetting;
    if (header_.empty() && line.substr(0, preamble.size()) == preamble) {
      read_preamble(line, setup_);
    } else if (header_.empty() && line.substr(0, setting.size()) == setting) {
      // "# setting: --option=value": the value is the rest of the line (a path may hold '=').
      const std::string_view rest = line.substr(setting.size());
      const std::size_t eq = rest.find('=');
      if (eq != std::string_view::npos && eq > 0) {
        setup_.settings.push_back({std::string(rest.substr(0, eq)), std::string(rest.substr(eq + 1))});
      }
    } else if (line.substr(0, stop.size()) == stop) {
      stop_reason_ = std::string(line.substr(stop.size()));
    }
  }

  std::size_t need(const std::string& name) const {
    const auto it = col_.find(name);
    if (it == col_.end()) throw DataError(fmt::format("{}: not a deflex cycle log: no column '{}'", path_, name));
    return it->second;
  }

  void header(const std::vector<std::string_view>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) {
      header_.emplace_back(cells[i]);
      col_[header_.back()] = i;
    }
    Columns& c = c_;
    c.t = need("t_s");
    c.pt = need("program_t_s");
    c.seq = need("sequence");
    c.st = need("status");
    const char* wrench[6] = {"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"};
    for (int k = 0; k < 6; ++k) c.w[k] = need(wrench[k]);
    const char* raw[3] = {"meas_fx_N", "meas_fy_N", "meas_fz_N"};
    for (int k = 0; k < 3; ++k) c.raw[k] = need(raw[k]);
    int joints = 0;
    while (joints < kMaxJoints && col_.count(fmt::format("dtheta{}_deg", joints + 1)) != 0) {
      c.d[joints] = col_.at(fmt::format("dtheta{}_deg", joints + 1));
      ++joints;
    }
    if (joints == 0) throw DataError(fmt::format("{}: not a deflex cycle log: no column 'dtheta1_deg'", path_));
    setup_.joints = joints;
    const char* corr[3] = {"corr_x_mm", "corr_y_mm", "corr_z_mm"};
    for (int k = 0; k < 3; ++k) c.c[k] = need(corr[k]);
    const std::pair<std::size_t Columns::*, const char*> named[] = {{&Columns::delay, "delay_ms"},
                                                                    {&Columns::answer, "answer_ms"},
                                                                    {&Columns::arrival, "arrival_delay_ms"},
                                                                    {&Columns::jitter, "jitter_ms"},
                                                                    {&Columns::missed_before, "missed_before"},
                                                                    {&Columns::dup, "duplicates"},
                                                                    {&Columns::sup, "superseded"},
                                                                    {&Columns::rej, "rejected"},
                                                                    {&Columns::rst, "restarts"},
                                                                    {&Columns::late, "late"},
                                                                    {&Columns::clate, "controller_late"},
                                                                    {&Columns::sil, "silences"},
                                                                    {&Columns::guard, "guard_trips"}};
    for (const auto& n : named) c.*(n.first) = need(n.second);
    if (col_.count("replied") != 0) c.replied = col_.at("replied");
  }

  double value(const std::vector<std::string_view>& cells, std::size_t i) const {
    if (cells[i].empty()) return kNaN;
    const auto v = parse_double(cells[i]);
    if (!v) throw DataError(fmt::format("{}:{}: column '{}': {}", path_, line_no_, header_[i], not_a_number(cells[i])));
    return *v;
  }

  std::uint64_t count(const std::vector<std::string_view>& cells, std::size_t i) const {
    const double v = value(cells, i);
    if (!(v >= 0.0) || v != std::floor(v)) {
      throw DataError(fmt::format("{}:{}: column '{}': '{}' is not a count", path_, line_no_, header_[i], cells[i]));
    }
    return static_cast<std::uint64_t>(v);
  }

  // The feed, made at the first row: the bounds are in every row of a log written since they were
  // added (older logs: not drawn).
  void make_feed(const std::vector<std::string_view>& cells) {
    if (col_.count("joint_bound_deg") != 0) setup_.joint_bound_deg = value(cells, col_.at("joint_bound_deg"));
    if (col_.count("tcp_bound_mm") != 0) setup_.tcp_bound_mm = value(cells, col_.at("tcp_bound_mm"));
    if (!std::isfinite(setup_.joint_bound_deg)) setup_.joint_bound_deg = 0.0;
    if (!std::isfinite(setup_.tcp_bound_mm)) setup_.tcp_bound_mm = 0.0;
    feed_ = std::make_shared<runtime::MonitorFeed>(setup_);
  }

  void row(const std::vector<std::string_view>& cells) {
    if (cells.size() != header_.size()) {
      throw DataError(fmt::format("{}:{}: {} cells where the header has {} (a truncated or damaged log)", path_,
                                  line_no_, cells.size(), header_.size()));
    }
    if (!feed_) make_feed(cells);
    const Columns& c = c_;
    const auto v = [&](std::size_t i) { return value(cells, i); };
    const auto n = [&](std::size_t i) { return count(cells, i); };
    runtime::MonitorRow r;
    r.t_s = v(c.t);
    if (!std::isfinite(r.t_s)) {
      throw DataError(fmt::format("{}:{}: column 't_s': a cycle without a time", path_, line_no_));
    }
    if (r.t_s < last_t_) {
      throw DataError(
          fmt::format("{}:{}: column 't_s': time goes back ({} s after {} s)", path_, line_no_, r.t_s, last_t_));
    }
    last_t_ = r.t_s;
    r.program_t_s = v(c.pt);
    r.sequence = n(c.seq);
    r.status = static_cast<int>(v(c.st));
    r.replied = c.replied == kNoColumn || v(c.replied) != 0.0;
    for (int k = 0; k < 6; ++k) r.wrench[k] = v(c.w[k]);
    for (int k = 0; k < 3; ++k) r.raw_force[k] = v(c.raw[k]);
    for (int j = 0; j < setup_.joints; ++j) r.dtheta_deg[j] = v(c.d[j]);
    for (int k = 0; k < 3; ++k) r.tcp_mm[k] = v(c.c[k]);
    r.delay_ms = v(c.delay);
    r.answer_ms = v(c.answer);
    r.arrival_ms = v(c.arrival);
    r.jitter_ms = v(c.jitter);
    missed_ += n(c.missed_before);
    r.missed = missed_;
    r.duplicates = n(c.dup);
    r.superseded = n(c.sup);
    r.rejected = n(c.rej);
    r.restarts = n(c.rst);
    r.late = n(c.late);
    r.controller_late = n(c.clate);
    r.silences = n(c.sil);
    r.guard_trips = n(c.guard);
    feed_->add(r);
  }

  std::string path_;
  runtime::MonitorSetup setup_;
  std::string stop_reason_;
  std::map<std::string, std::size_t> col_;
  std::vector<std::string> header_;
  Columns c_{};
  std::shared_ptr<runtime::MonitorFeed> feed_;
  int line_no_ = 0;
  double last_t_ = -1e300;
  std::uint64_t missed_ = 0;
};

}  // namespace

std::shared_ptr<runtime::MonitorFeed> read_cycle_log_feed(const std::string& path) {
  const std::string text = read_input_file(path, InputKind::kCsvTable);
  LogReader reader(path);
  std::size_t pos = 0;
  int line_no = 0;
  while (pos < text.size()) {
    auto end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (trim_view(line).empty()) continue;
    reader.line(line, line_no);
  }
  return reader.finish();
}

}  // namespace deflex::monitor
