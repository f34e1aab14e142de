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

// "# deflex cycle log: link=rsi period_ms=4 force_components=3 force_fault_N=2000" into the setup (a log written before
// the line existed: the link is not known, nor the cycle its answers are late against).
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

}  // namespace

std::shared_ptr<runtime::MonitorFeed> read_cycle_log_feed(const std::string& path) {
  const std::string text = read_input_file(path, InputKind::kCsvTable);
  runtime::MonitorSetup setup;
  setup.recorded = true;
  setup.source = path;
  setup.link = "not in the log";
  setup.force_components = 0;
  std::string stop_reason;
  std::map<std::string, std::size_t> col;
  std::vector<std::string> header;
  std::shared_ptr<runtime::MonitorFeed> feed;
  std::size_t pos = 0;
  int line_no = 0;
  double last_t = -1e300;
  std::uint64_t missed = 0;
  auto need = [&](const std::string& name) {
    const auto it = col.find(name);
    if (it == col.end()) throw DataError(fmt::format("{}: not a deflex cycle log: no column '{}'", path, name));
    return it->second;
  };
  struct Columns {
    std::size_t t, pt, seq, st, w[6], raw[3], d[kMaxJoints], c[3], delay, answer, arrival, jitter, missed_before, dup,
        sup, rej, rst, late, clate, sil, guard;
    std::size_t replied = kNoColumn;
  } c{};
  while (pos < text.size()) {
    auto end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (trim_view(line).empty()) continue;
    if (line[0] == '#') {
      if (header.empty() &&
          line.substr(0, std::string_view(runtime::kCycleLogPreamble).size()) == runtime::kCycleLogPreamble) {
        read_preamble(line, setup);
      } else if (line.substr(0, std::string_view(runtime::kCycleLogStop).size()) == runtime::kCycleLogStop) {
        stop_reason = std::string(line.substr(std::string_view(runtime::kCycleLogStop).size()));
      }
      continue;
    }
    const auto cells = cells_of(line);
    if (header.empty()) {
      for (std::size_t i = 0; i < cells.size(); ++i) {
        header.emplace_back(cells[i]);
        col[header.back()] = i;
      }
      c.t = need("t_s");
      c.pt = need("program_t_s");
      c.seq = need("sequence");
      c.st = need("status");
      const char* wrench[6] = {"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"};
      for (int k = 0; k < 6; ++k) c.w[k] = need(wrench[k]);
      const char* raw[3] = {"meas_fx_N", "meas_fy_N", "meas_fz_N"};
      for (int k = 0; k < 3; ++k) c.raw[k] = need(raw[k]);
      int joints = 0;
      while (joints < kMaxJoints && col.count(fmt::format("dtheta{}_deg", joints + 1)) != 0) {
        c.d[joints] = col.at(fmt::format("dtheta{}_deg", joints + 1));
        ++joints;
      }
      if (joints == 0) throw DataError(fmt::format("{}: not a deflex cycle log: no column 'dtheta1_deg'", path));
      setup.joints = joints;
      const char* corr[3] = {"corr_x_mm", "corr_y_mm", "corr_z_mm"};
      for (int k = 0; k < 3; ++k) c.c[k] = need(corr[k]);
      c.delay = need("delay_ms");
      c.answer = need("answer_ms");
      c.arrival = need("arrival_delay_ms");
      c.jitter = need("jitter_ms");
      c.missed_before = need("missed_before");
      c.dup = need("duplicates");
      c.sup = need("superseded");
      c.rej = need("rejected");
      c.rst = need("restarts");
      c.late = need("late");
      c.clate = need("controller_late");
      c.sil = need("silences");
      c.guard = need("guard_trips");
      if (col.count("replied") != 0) c.replied = col.at("replied");
      continue;
    }
    if (cells.size() != header.size()) {
      throw DataError(fmt::format("{}:{}: {} cells where the header has {} (a truncated or damaged log)", path, line_no,
                                  cells.size(), header.size()));
    }
    auto value = [&](std::size_t i) {
      if (cells[i].empty()) return kNaN;
      const auto v = parse_double(cells[i]);
      if (!v) throw DataError(fmt::format("{}:{}: column '{}': {}", path, line_no, header[i], not_a_number(cells[i])));
      return *v;
    };
    auto count = [&](std::size_t i) {
      const double v = value(i);
      if (!(v >= 0.0) || v != std::floor(v)) {
        throw DataError(fmt::format("{}:{}: column '{}': '{}' is not a count", path, line_no, header[i], cells[i]));
      }
      return static_cast<std::uint64_t>(v);
    };
    if (!feed) {
      // The bounds are in every row of a log written since they were added (older logs: not drawn).
      if (col.count("joint_bound_deg") != 0) setup.joint_bound_deg = value(col.at("joint_bound_deg"));
      if (col.count("tcp_bound_mm") != 0) setup.tcp_bound_mm = value(col.at("tcp_bound_mm"));
      if (!std::isfinite(setup.joint_bound_deg)) setup.joint_bound_deg = 0.0;
      if (!std::isfinite(setup.tcp_bound_mm)) setup.tcp_bound_mm = 0.0;
      feed = std::make_shared<runtime::MonitorFeed>(setup);
    }
    runtime::MonitorRow r;
    r.t_s = value(c.t);
    if (!std::isfinite(r.t_s))
      throw DataError(fmt::format("{}:{}: column 't_s': a cycle without a time", path, line_no));
    if (r.t_s < last_t) {
      throw DataError(
          fmt::format("{}:{}: column 't_s': time goes back ({} s after {} s)", path, line_no, r.t_s, last_t));
    }
    last_t = r.t_s;
    r.program_t_s = value(c.pt);
    r.sequence = count(c.seq);
    r.status = static_cast<int>(value(c.st));
    r.replied = c.replied == kNoColumn || value(c.replied) != 0.0;
    for (int k = 0; k < 6; ++k) r.wrench[k] = value(c.w[k]);
    for (int k = 0; k < 3; ++k) r.raw_force[k] = value(c.raw[k]);
    for (int j = 0; j < setup.joints; ++j) r.dtheta_deg[j] = value(c.d[j]);
    for (int k = 0; k < 3; ++k) r.tcp_mm[k] = value(c.c[k]);
    r.delay_ms = value(c.delay);
    r.answer_ms = value(c.answer);
    r.arrival_ms = value(c.arrival);
    r.jitter_ms = value(c.jitter);
    missed += count(c.missed_before);
    r.missed = missed;
    r.duplicates = count(c.dup);
    r.superseded = count(c.sup);
    r.rejected = count(c.rej);
    r.restarts = count(c.rst);
    r.late = count(c.late);
    r.controller_late = count(c.clate);
    r.silences = count(c.sil);
    r.guard_trips = count(c.guard);
    feed->add(r);
  }
  if (header.empty()) throw DataError(fmt::format("{}: no header row: not a deflex cycle log", path));
  if (!feed) throw DataError(fmt::format("{}: no cycles (only the header)", path));
  feed->set_state("recorded", stop_reason);
  return feed;
}

}  // namespace deflex::monitor
