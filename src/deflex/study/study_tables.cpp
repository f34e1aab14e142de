// Case-study results as JSON, terminal tables beside the paper's, Markdown and CSV.
#include "deflex/study/study_tables.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {
namespace {

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json speed_map(const std::map<int, double>& m) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [speed, v] : m) {
    j[std::to_string(speed)] = number(v);
  }
  return j;
}

nlohmann::json numbers(const std::vector<double>& v) {
  nlohmann::json j = nlohmann::json::array();
  for (const double x : v) j.push_back(number(x));
  return j;
}

nlohmann::json speed_lists(const std::map<int, std::vector<double>>& m) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [speed, v] : m) j[std::to_string(speed)] = numbers(v);
  return j;
}

nlohmann::json spread_json(const Spread& s) {
  return {{"mean", number(s.mean)}, {"sd", number(s.sd)}, {"min", number(s.min)}, {"max", number(s.max)}, {"n", s.n}};
}

double mean_of(const std::vector<double>& v) { return spread_of(v).mean; }

// A results.json key naming a TCP speed in whole mm/s.
int speed_key(const std::string& key, const std::string& where) {
  const auto v = parse_int64(key);
  if (!v || *v < 0 || *v > 1000000) {
    throw DataError(fmt::format("{}: key '{}' is not a speed in mm/s", where, key));
  }
  return static_cast<int>(*v);
}

// The table number a setup gets: the paper's own numbers for its two, then 3, 4, ... in order.
std::vector<std::string> table_titles(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  std::vector<std::string> titles;
  int next = 3;
  for (const auto& s : study.setups) {
    if (s.setup == "offline") {
      titles.push_back("Table 1 (offline compensation)");
    } else if (s.setup == "online") {
      titles.push_back("Table 2 (online compensation, force sensor mounted)");
    } else if (!s.paper_table.empty()) {
      const PaperTable* pt = paper.table_for(s.paper_table);
      titles.push_back(fmt::format("Table {} ({}: {}; beside the paper's {})", next++, s.setup,
                                   s.paper_label.empty() ? "beyond the paper" : s.paper_label,
                                   pt != nullptr ? pt->caption.substr(0, pt->caption.find('.')) : s.paper_table));
    } else {
      titles.push_back(fmt::format("Table {} ({}, beyond the paper)", next++, s.setup));
    }
  }
  return titles;
}

// Compensation of a paper row: 1 - mean C / UC, as the paper's 67% and 69-80% are stated.
double paper_compensation(const PaperRow& r) {
  double sum = 0.0;
  for (const auto& [v, c] : r.c_mm) {
    sum += c;
  }
  return r.c_mm.empty() ? kNaN : compensation_ratio(r.uc_mm, sum / static_cast<double>(r.c_mm.size()));
}

std::string mm(double v) { return std::isfinite(v) ? fmt::format("{:.3f}", v) : "n/a"; }

// "0.152" for one seed, "0.152 ±0.012" (the sample standard deviation over the seeds) for several.
std::string mm_spread(const Spread& s) {
  if (s.n <= 1) return mm(s.mean);
  return fmt::format("{} ±{:.3f}", mm(s.mean), s.sd);
}
std::string percent_spread(const Spread& s) {
  if (s.n <= 1) return percent_text(s.mean);
  return fmt::format("{} ±{:.0f}", percent_text(s.mean), 100.0 * s.sd);
}
std::string paper_mm(double v) { return std::isfinite(v) ? fmt::format("{:.2f}", v) : ""; }

std::string cell_with_paper(const std::string& ours, const std::string& paper) {
  return paper.empty() ? ours : fmt::format("{} ({})", ours, paper);
}

struct Row {
  std::vector<std::string> cells;
};

struct Grid {
  std::vector<std::string> header;
  std::vector<Row> rows;
};

// One setup's table: load, UC, C per speed, compensation; "ours (paper)" where the paper has it.
Grid setup_grid(const SetupResult& s, const std::vector<int>& speeds, const PaperTable* paper) {
  Grid g;
  g.header.push_back("load");
  g.header.push_back("UC mm");
  for (std::size_t i = 0; i < speeds.size(); ++i) {
    g.header.push_back(fmt::format("C{} {} mm/s", i + 1, speeds[i]));
  }
  g.header.push_back("compensation %");
  for (const auto& l : s.loads) {
    const PaperRow* pr = paper != nullptr ? paper->row_for(l.load_N) : nullptr;
    Row r;
    r.cells.push_back(fmt::format("{:g} N", l.load_N));
    r.cells.push_back(cell_with_paper(mm_spread(l.uc_mean_spread()), pr != nullptr ? paper_mm(pr->uc_mm) : ""));
    for (const int v : speeds) {
      const double pc = pr != nullptr ? value_at_speed(pr->c_mm, v) : kNaN;
      r.cells.push_back(cell_with_paper(mm_spread(l.c_spread(v)), paper_mm(pc)));
    }
    const Spread comp = printed_compensation_spread(l, speeds);
    r.cells.push_back(
        cell_with_paper(percent_spread(comp), pr != nullptr ? percent_text(paper_compensation(*pr)) : ""));
    g.rows.push_back(r);
  }
  return g;
}

std::map<int, double> read_speed_map(const nlohmann::json& j, const std::string& where) {
  std::map<int, double> m;
  if (!j.is_object()) {
    throw DataError(fmt::format("{}: must be an object keyed by speed in mm/s", where));
  }
  for (const auto& [key, value] : j.items()) {
    const int speed = speed_key(key, where);
    if (value.is_null()) {
      m[speed] = kNaN;
    } else if (value.is_number()) {
      m[speed] = value.get<double>();
    } else {
      throw DataError(fmt::format("{}.\"{}\": not a number", where, key));
    }
  }
  return m;
}

std::vector<double> read_numbers(const nlohmann::json& j, const std::string& where) {
  if (!j.is_array()) throw DataError(fmt::format("{}: must be an array of numbers", where));
  std::vector<double> out;
  for (const auto& v : j) {
    if (v.is_null()) {
      out.push_back(kNaN);
    } else if (v.is_number()) {
      out.push_back(v.get<double>());
    } else {
      throw DataError(fmt::format("{}: not a number", where));
    }
  }
  return out;
}

std::map<int, std::vector<double>> read_speed_lists(const nlohmann::json& j, const std::string& where) {
  std::map<int, std::vector<double>> m;
  if (!j.is_object()) throw DataError(fmt::format("{}: must be an object keyed by speed in mm/s", where));
  for (const auto& [key, value] : j.items()) {
    const int speed = speed_key(key, where);
    m[speed] = read_numbers(value, fmt::format("{}.\"{}\"", where, key));
  }
  return m;
}

double read_number(const nlohmann::json& j, const char* key, const std::string& where, bool required = true) {
  if (!j.contains(key)) {
    if (required) {
      throw DataError(fmt::format("{}: missing field '{}'", where, key));
    }
    return 0.0;
  }
  if (!j.at(key).is_number()) {
    throw DataError(fmt::format("{}.{}: not a number", where, key));
  }
  return j.at(key).get<double>();
}

// One entry of results.json's "error_budget" (`bw` names it in errors); each sensitivity
// recomputed from the residuals.
ErrorBudget read_error_budget(const nlohmann::json& jb, const std::string& bw) {
  ErrorBudget b;
  if (!jb.contains("setup") || !jb.at("setup").is_string()) {
    throw DataError(fmt::format("{}: missing string field 'setup'", bw));
  }
  b.setup = jb.at("setup").get<std::string>();
  b.load_N = read_number(jb, "load_N", bw);
  b.speed_mm_s = read_number(jb, "speed_mm_s", bw);
  b.residual_mm_all = jb.contains("residual_mm_all") && jb.at("residual_mm_all").is_null()
                          ? kNaN
                          : read_number(jb, "residual_mm_all", bw);
  b.uc_mm = jb.contains("uc_mm") && jb.at("uc_mm").is_null() ? kNaN : read_number(jb, "uc_mm", bw, false);
  if (jb.contains("residual_mm_all_off") && !jb.at("residual_mm_all_off").is_null()) {
    b.residual_mm_all_off = read_number(jb, "residual_mm_all_off", bw);
  }
  if (jb.contains("seed")) {
    if (!jb.at("seed").is_number_unsigned()) throw DataError(fmt::format("{}: seed: not a seed", bw));
    b.seed = jb.at("seed").get<std::uint64_t>();
  }
  if (jb.contains("laps")) {
    const double laps = read_number(jb, "laps", bw);
    if (laps < 0 || laps > 1e6 || laps != std::floor(laps))
      throw DataError(fmt::format("{}: laps: not a lap count", bw));
    b.laps = static_cast<int>(laps);
  }
  if (jb.contains("entries")) {
    std::size_t ei = 0;
    for (const auto& je : jb.at("entries")) {
      const std::string ew = fmt::format("{}.entries[{}]", bw, ei++);
      ErrorBudgetEntry e;
      if (!je.contains("effect") || !je.at("effect").is_string()) {
        throw DataError(fmt::format("{}: missing string field 'effect'", ew));
      }
      e.effect = je.at("effect").get<std::string>();
      e.size = je.contains("size") && je.at("size").is_string() ? je.at("size").get<std::string>() : "";
      e.residual_mm_without_it = je.contains("residual_mm_without_it") && je.at("residual_mm_without_it").is_null()
                                     ? kNaN
                                     : read_number(je, "residual_mm_without_it", ew);
      e.sensitivity = one_at_a_time_sensitivity(b.residual_mm_all, e.residual_mm_without_it);
      b.entries.push_back(e);
    }
  }
  return b;
}

}  // namespace

std::vector<int> study_speeds_mm_s(const StudyResult& study) {
  if (!study.speeds_mm_s.empty()) {
    return study.speeds_mm_s;
  }
  std::map<int, bool> seen;
  for (const auto& s : study.setups) {
    for (const auto& l : s.loads) {
      for (const auto& [v, c] : l.c_mm) {
        seen[v] = true;
      }
    }
  }
  std::vector<int> out;
  for (const auto& [v, b] : seen) {
    out.push_back(v);
  }
  return out;
}

double value_at_speed(const std::map<int, double>& m, int speed_mm_s) {
  const auto it = m.find(speed_mm_s);
  return it == m.end() ? kNaN : it->second;
}

double whole_percent(double fraction) {
  if (!std::isfinite(fraction)) return kNaN;
  // Halves away from zero as a reader rounds them: 1 - 0.051 / 0.120 is 57.5 %, so 58 %, though it
  // comes out a hair under 0.575 in binary. Figures printed to 3 or 4 digits never lie within the
  // nudge of a half unless they are on it.
  const double p = fraction * 100.0;
  return std::round(p + std::copysign(1e-9 * std::max(1.0, std::abs(p)), p));
}

std::string percent_text(double fraction) {
  if (!std::isfinite(fraction)) {
    return "n/a";
  }
  const double p = whole_percent(fraction);
  return fmt::format("{:.0f}%", p == 0.0 ? 0.0 : p);
}

std::string signed_percent_text(double fraction) {
  if (!std::isfinite(fraction)) return "n/a";
  const double p = whole_percent(fraction);
  return p == 0.0 ? "0%" : fmt::format("{:+.0f}%", p);
}

const PaperTable* paper_table_of(const PaperFigures& paper, const SetupResult& setup) {
  if (const PaperTable* own = paper.table_for(setup.setup)) return own;
  return setup.paper_table.empty() ? nullptr : paper.table_for(setup.paper_table);
}

double as_printed(double value, int decimals) {
  if (!std::isfinite(value)) return kNaN;
  // The very text the tables print, read back: the same rounding as the printing, ties included.
  return std::strtod(fmt::format("{:.{}f}", value, decimals).c_str(), nullptr);
}

double printed_compensation(const LoadResult& load, int speed_mm_s) {
  return compensation_ratio(as_printed(load.uc_mean_spread().mean), as_printed(load.c_spread(speed_mm_s).mean));
}

Spread printed_compensation_spread(const LoadResult& load, const std::vector<int>& speeds) {
  double c_sum = 0.0;
  int n = 0;
  for (const int v : speeds) {
    const double c = as_printed(load.c_spread(v).mean);
    if (std::isfinite(c)) {
      c_sum += c;
      ++n;
    }
  }
  const double mean = n > 0 ? compensation_ratio(as_printed(load.uc_mean_spread().mean), c_sum / n) : kNaN;
  // Per seed the same quantity, for the spread: 1 - (that seed's C over the speeds) / (its UC).
  std::vector<double> per_seed;
  const int seeds = load.seeds();
  if (seeds > 1 && !load.uc_mm_by_seed.empty()) {
    for (int k = 0; k < seeds; ++k) {
      const auto at = [k](const std::vector<double>& list) {
        return static_cast<std::size_t>(k) < list.size() ? list[static_cast<std::size_t>(k)] : kNaN;
      };
      std::vector<double> uc, c;
      for (const auto& [v, list] : load.uc_mm_by_seed) uc.push_back(at(list));
      for (const int v : speeds) {
        const auto it = load.c_mm_by_seed.find(v);
        if (it != load.c_mm_by_seed.end()) c.push_back(at(it->second));
      }
      per_seed.push_back(compensation_ratio(spread_of(uc).mean, spread_of(c).mean));
    }
  }
  Spread s = per_seed.empty() ? spread_of({mean}) : spread_of(per_seed);
  s.mean = mean;
  if (per_seed.empty()) {
    s.min = s.max = mean;
  }
  return s;
}

double printed_sensitivity(const ErrorBudget& budget, const ErrorBudgetEntry& entry) {
  return one_at_a_time_sensitivity(as_printed(budget.residual_mm_all), as_printed(entry.residual_mm_without_it));
}

double uc_over_paper(const LoadResult& load, const PaperRow& paper) {
  const double ours = as_printed(load.uc_mean_spread().mean);
  return paper.uc_mm > 0.0 && std::isfinite(ours) ? ours / paper.uc_mm : kNaN;
}

double c_over_paper(const LoadResult& load, const PaperRow& paper) {
  double ours = 0.0, theirs = 0.0;
  int n = 0;
  for (const auto& [v, pc] : paper.c_mm) {
    const double o = as_printed(load.c_spread(v).mean);
    if (std::isfinite(o) && std::isfinite(pc)) {
      ours += o;
      theirs += pc;
      ++n;
    }
  }
  return n > 0 && theirs > 0.0 ? ours / theirs : kNaN;
}

double LoadResult::uc_mean_mm() const {
  if (uc_mm.empty()) {
    return kNaN;
  }
  double sum = 0.0;
  for (const auto& [v, x] : uc_mm) {
    sum += x;
  }
  return sum / static_cast<double>(uc_mm.size());
}

Spread spread_of(const std::vector<double>& values) {
  Spread s;
  double sum = 0.0;
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    sum += v;
    s.min = s.n == 0 ? v : std::min(s.min, v);
    s.max = s.n == 0 ? v : std::max(s.max, v);
    ++s.n;
  }
  if (s.n == 0) return s;
  s.mean = sum / s.n;
  if (s.n > 1) {
    double var = 0.0;
    for (const double v : values) {
      if (std::isfinite(v)) var += (v - s.mean) * (v - s.mean);
    }
    s.sd = std::sqrt(var / (s.n - 1));
  }
  return s;
}

int LoadResult::seeds() const {
  std::size_t n = 0;
  for (const auto& [v, list] : c_mm_by_seed) n = std::max(n, list.size());
  return static_cast<int>(std::max<std::size_t>(n, 1));
}

void LoadResult::fill_means() {
  const std::pair<std::map<int, std::vector<double>>*, std::map<int, double>*> pairs[] = {
      {&uc_mm_by_seed, &uc_mm},
      {&c_mm_by_seed, &c_mm},
      {&uc_sync_mm_by_seed, &uc_sync_mm},
      {&c_sync_mm_by_seed, &c_sync_mm}};
  for (const auto& [by_seed, mean] : pairs) {
    for (const auto& [v, list] : *by_seed) (*mean)[v] = mean_of(list);
  }
  fill_compensation();
}

Spread LoadResult::c_spread(int speed_mm_s) const {
  const auto it = c_mm_by_seed.find(speed_mm_s);
  if (it != c_mm_by_seed.end() && !it->second.empty()) return spread_of(it->second);
  return spread_of({value_at_speed(c_mm, speed_mm_s)});
}

Spread LoadResult::uc_mean_spread() const {
  // Per seed: UC averaged over the speeds (the paper's UC column), then spread over the seeds.
  const int n = seeds();
  if (n <= 1 || uc_mm_by_seed.empty()) return spread_of({uc_mean_mm()});
  std::vector<double> per_seed;
  for (int k = 0; k < n; ++k) {
    double sum = 0.0;
    int count = 0;
    for (const auto& [v, list] : uc_mm_by_seed) {
      if (static_cast<std::size_t>(k) < list.size() && std::isfinite(list[static_cast<std::size_t>(k)])) {
        sum += list[static_cast<std::size_t>(k)];
        ++count;
      }
    }
    per_seed.push_back(count > 0 ? sum / count : kNaN);
  }
  return spread_of(per_seed);
}

Spread LoadResult::compensation_spread() const {
  const int n = seeds();
  if (n <= 1 || uc_mm_by_seed.empty() || c_mm_by_seed.empty()) {
    std::vector<double> all;
    for (const auto& [v, c] : compensation) all.push_back(c);
    return spread_of({spread_of(all).mean});
  }
  std::vector<double> per_seed;
  for (int k = 0; k < n; ++k) {
    double sum = 0.0;
    int count = 0;
    for (const auto& [v, list] : c_mm_by_seed) {
      const auto uc = uc_mm_by_seed.find(v);
      if (uc == uc_mm_by_seed.end() || static_cast<std::size_t>(k) >= list.size() ||
          static_cast<std::size_t>(k) >= uc->second.size()) {
        continue;
      }
      const double r = compensation_ratio(uc->second[static_cast<std::size_t>(k)], list[static_cast<std::size_t>(k)]);
      if (std::isfinite(r)) {
        sum += r;
        ++count;
      }
    }
    per_seed.push_back(count > 0 ? sum / count : kNaN);
  }
  return spread_of(per_seed);
}

void LoadResult::fill_compensation() {
  for (const auto& [v, c] : c_mm) {
    const auto it = uc_mm.find(v);
    if (it != uc_mm.end()) {
      compensation[v] = compensation_ratio(it->second, c);
    }
  }
}

namespace {

// A load's per-speed figures, one row each, read and written by the same table: its key in the saved
// study, the field, and whether a saved study must have it (required), always has it (written even
// when empty) or has it only when measured.
enum class Presence { kRequired, kAlways, kWhenMeasured };
struct LoadMapField {
  const char* key;
  std::map<int, double> LoadResult::*field;
  Presence presence;
};
constexpr LoadMapField kLoadMaps[] = {
    {"uc_mm", &LoadResult::uc_mm, Presence::kRequired},
    {"c_mm", &LoadResult::c_mm, Presence::kRequired},
    {"compensation", &LoadResult::compensation, Presence::kAlways},
    {"uc_std_mm", &LoadResult::uc_std_mm, Presence::kWhenMeasured},
    {"c_std_mm", &LoadResult::c_std_mm, Presence::kWhenMeasured},
    {"uc_max_mm", &LoadResult::uc_max_mm, Presence::kWhenMeasured},
    {"c_max_mm", &LoadResult::c_max_mm, Presence::kWhenMeasured},
    {"iso_accuracy_uc_mm", &LoadResult::iso_accuracy_uc_mm, Presence::kWhenMeasured},
    {"iso_accuracy_c_mm", &LoadResult::iso_accuracy_c_mm, Presence::kWhenMeasured},
    {"iso_repeatability_mm", &LoadResult::iso_repeatability_mm, Presence::kWhenMeasured},
    {"uc_sync_mm", &LoadResult::uc_sync_mm, Presence::kWhenMeasured},
    {"c_sync_mm", &LoadResult::c_sync_mm, Presence::kWhenMeasured},
};
// Its per-seed lists (written when measured).
struct LoadSeedField {
  const char* key;
  std::map<int, std::vector<double>> LoadResult::*field;
};
constexpr LoadSeedField kLoadSeedLists[] = {
    {"uc_mm_by_seed", &LoadResult::uc_mm_by_seed},
    {"c_mm_by_seed", &LoadResult::c_mm_by_seed},
    {"uc_sync_mm_by_seed", &LoadResult::uc_sync_mm_by_seed},
    {"c_sync_mm_by_seed", &LoadResult::c_sync_mm_by_seed},
};
// A sweep point's per-seed lists.
struct SweepSeedField {
  const char* key;
  std::vector<double> SweepPoint::*field;
};
constexpr SweepSeedField kSweepSeedLists[] = {
    {"uc_mm_by_seed", &SweepPoint::uc_mm_by_seed},
    {"c_mm_by_seed", &SweepPoint::c_mm_by_seed},
    {"c_sync_mm_by_seed", &SweepPoint::c_sync_mm_by_seed},
};

nlohmann::json load_to_json(const LoadResult& l) {
  nlohmann::json jl{{"load_N", l.load_N}};
  for (const LoadMapField& f : kLoadMaps) {
    const std::map<int, double>& m = l.*f.field;
    if (f.presence != Presence::kWhenMeasured || !m.empty()) jl[f.key] = speed_map(m);
  }
  for (const LoadSeedField& f : kLoadSeedLists) {
    if (!(l.*f.field).empty()) jl[f.key] = speed_lists(l.*f.field);
  }
  nlohmann::json c_spread = nlohmann::json::object();
  for (const auto& [v, c] : l.c_mm) c_spread[std::to_string(v)] = spread_json(l.c_spread(v));
  jl["spread"] = {{"uc_mm", spread_json(l.uc_mean_spread())},
                  {"c_mm", c_spread},
                  {"compensation", spread_json(l.compensation_spread())}};
  return jl;
}

nlohmann::json setup_to_json(const SetupResult& s) {
  nlohmann::json loads = nlohmann::json::array();
  for (const auto& l : s.loads) loads.push_back(load_to_json(l));
  nlohmann::json js{{"setup", s.setup}, {"loads", loads}};
  if (!s.description.empty()) js["description"] = s.description;
  if (!s.paper_table.empty()) {
    js["paper_table"] = s.paper_table;
    js["paper_label"] = s.paper_label;
  }
  return js;
}

nlohmann::json sweep_to_json(const std::vector<SweepPoint>& points) {
  nlohmann::json sweep = nlohmann::json::array();
  for (const auto& p : points) {
    nlohmann::json jp{{"setup", p.setup},
                      {"load_N", p.load_N},
                      {"speed_mm_s", p.speed_mm_s},
                      {"uc_mm", number(p.uc_mm)},
                      {"c_mm", number(p.c_mm)},
                      {"compensation", number(p.compensation)},
                      {"c_sync_mm", number(p.c_sync_mm)}};
    if (!p.c_mm_by_seed.empty()) {
      for (const SweepSeedField& f : kSweepSeedLists) jp[f.key] = numbers(p.*f.field);
    }
    sweep.push_back(jp);
  }
  return sweep;
}

nlohmann::json budgets_to_json(const std::vector<ErrorBudget>& budgets) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& b : budgets) {
    nlohmann::json entries = nlohmann::json::array();
    for (const auto& e : b.entries) {
      entries.push_back({{"effect", e.effect},
                         {"size", e.size},
                         {"residual_mm_without_it", number(e.residual_mm_without_it)},
                         {"sensitivity_one_at_a_time", number(e.sensitivity)}});
    }
    out.push_back({{"setup", b.setup},
                   {"load_N", b.load_N},
                   {"speed_mm_s", b.speed_mm_s},
                   {"residual_mm_all", number(b.residual_mm_all)},
                   {"residual_mm_all_off", number(b.residual_mm_all_off)},
                   {"uc_mm", number(b.uc_mm)},
                   {"seed", b.seed},
                   {"laps", b.laps},
                   {"entries", entries}});
  }
  return out;
}

// The paper's tables beside ours, so a saved study is read with what it is compared against.
nlohmann::json paper_to_json() {
  nlohmann::json paper = nlohmann::json::object();
  for (const auto& t : paper_reference().tables) {
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& r : t.rows) {
      rows.push_back({{"load_N", r.load_N}, {"uc_mm", r.uc_mm}, {"c_mm", speed_map(r.c_mm)}});
    }
    paper[t.setup] = rows;
  }
  return paper;
}

LoadResult load_from_json(const nlohmann::json& jl, const std::string& lw) {
  LoadResult l;
  l.load_N = read_number(jl, "load_N", lw);
  for (const LoadMapField& f : kLoadMaps) {
    if (jl.contains(f.key)) {
      l.*f.field = read_speed_map(jl.at(f.key), lw + "." + f.key);
    } else if (f.presence == Presence::kRequired) {
      throw DataError(fmt::format("{}: missing field '{}'", lw, f.key));
    }
  }
  for (const LoadSeedField& f : kLoadSeedLists) {
    if (jl.contains(f.key)) l.*f.field = read_speed_lists(jl.at(f.key), lw + "." + f.key);
  }
  return l;
}

SetupResult setup_from_json(const nlohmann::json& js, const std::string& where) {
  if (!js.is_object() || !js.contains("setup") || !js.at("setup").is_string()) {
    throw DataError(fmt::format("{}: missing string field 'setup'", where));
  }
  SetupResult s;
  s.setup = js.at("setup").get<std::string>();
  if (js.contains("description") && js.at("description").is_string()) {
    s.description = js.at("description").get<std::string>();
  }
  const std::pair<const char*, std::string*> text_fields[] = {{"paper_table", &s.paper_table},
                                                              {"paper_label", &s.paper_label}};
  for (const auto& [key, field] : text_fields) {
    if (!js.contains(key)) continue;
    if (!js.at(key).is_string()) throw DataError(fmt::format("{}.{}: not a string", where, key));
    *field = js.at(key).get<std::string>();
  }
  if (!js.contains("loads") || !js.at("loads").is_array()) {
    throw DataError(fmt::format("{}: missing array 'loads'", where));
  }
  std::size_t li = 0;
  for (const auto& jl : js.at("loads")) s.loads.push_back(load_from_json(jl, fmt::format("{}.loads[{}]", where, li++)));
  return s;
}

// A number that may be saved as null (not measured).
double read_number_or_nan(const nlohmann::json& j, const char* key, const std::string& where) {
  return j.contains(key) && j.at(key).is_null() ? kNaN : read_number(j, key, where);
}

SweepPoint sweep_point_from_json(const nlohmann::json& jp, const std::string& pw) {
  SweepPoint p;
  if (!jp.contains("setup") || !jp.at("setup").is_string()) {
    throw DataError(fmt::format("{}: missing string field 'setup'", pw));
  }
  p.setup = jp.at("setup").get<std::string>();
  p.load_N = read_number(jp, "load_N", pw);
  p.speed_mm_s = read_number(jp, "speed_mm_s", pw);
  p.uc_mm = read_number_or_nan(jp, "uc_mm", pw);
  p.c_mm = read_number_or_nan(jp, "c_mm", pw);
  p.compensation = compensation_ratio(p.uc_mm, p.c_mm);
  if (jp.contains("c_sync_mm")) p.c_sync_mm = read_number_or_nan(jp, "c_sync_mm", pw);
  for (const SweepSeedField& f : kSweepSeedLists) {
    if (jp.contains(f.key)) p.*f.field = read_numbers(jp.at(f.key), pw + "." + f.key);
  }
  return p;
}

// The study's own fields beside its setups: the speeds, the case, the seeds, the wall time.
void read_study_fields(const nlohmann::json& doc, const std::string& source, StudyResult& study) {
  if (doc.contains("speeds_mm_s")) {
    for (const auto& v : doc.at("speeds_mm_s")) {
      if (!v.is_number_integer()) {
        throw DataError(fmt::format("{}: speeds_mm_s: not an integer speed in mm/s", source));
      }
      study.speeds_mm_s.push_back(v.get<int>());
    }
  }
  if (doc.contains("case") && doc.at("case").is_string()) study.case_name = doc.at("case").get<std::string>();
  if (doc.contains("seed") && doc.at("seed").is_number_unsigned()) study.seed = doc.at("seed").get<std::uint64_t>();
  if (doc.contains("wall_time_s") && doc.at("wall_time_s").is_number()) {
    study.wall_time_s = doc.at("wall_time_s").get<double>();
  }
  if (doc.contains("seeds")) {
    for (const auto& v : doc.at("seeds")) {
      if (!v.is_number_unsigned()) throw DataError(fmt::format("{}: seeds: not a seed", source));
      study.seeds.push_back(v.get<std::uint64_t>());
    }
  }
}

}  // namespace

nlohmann::json study_to_json(const StudyResult& study) {
  nlohmann::json setups = nlohmann::json::array();
  for (const auto& s : study.setups) setups.push_back(setup_to_json(s));
  nlohmann::json doc{{"setups", setups}, {"speeds_mm_s", study_speeds_mm_s(study)}};
  if (!study.speed_sweep.empty()) doc["speed_sweep"] = sweep_to_json(study.speed_sweep);
  if (!study.error_budgets.empty()) doc["error_budget"] = budgets_to_json(study.error_budgets);
  if (!study.seeds.empty()) doc["seeds"] = study.seeds;
  if (!study.case_name.empty()) doc["case"] = study.case_name;
  doc["seed"] = study.seed;
  if (study.wall_time_s > 0.0) doc["wall_time_s"] = study.wall_time_s;
  doc["paper"] = paper_to_json();
  return doc;
}

StudyResult study_from_json(const nlohmann::json& doc, const std::string& source) {
  StudyResult study;
  if (!doc.is_object() || !doc.contains("setups") || !doc.at("setups").is_array()) {
    throw DataError(fmt::format("{}: missing array 'setups'", source));
  }
  std::size_t si = 0;
  for (const auto& js : doc.at("setups")) {
    study.setups.push_back(setup_from_json(js, fmt::format("{}: setups[{}]", source, si++)));
  }
  read_study_fields(doc, source, study);
  if (doc.contains("speed_sweep")) {
    std::size_t pi = 0;
    for (const auto& jp : doc.at("speed_sweep")) {
      study.speed_sweep.push_back(sweep_point_from_json(jp, fmt::format("{}: speed_sweep[{}]", source, pi++)));
    }
  }
  if (doc.contains("error_budget")) {
    std::size_t bi = 0;
    for (const auto& jb : doc.at("error_budget")) {
      study.error_budgets.push_back(read_error_budget(jb, fmt::format("{}: error_budget[{}]", source, bi++)));
    }
  }
  return study;
}

namespace {

// The time-synchronous (along-path) error of each load: UC (mean over the speeds) and C per speed,
// as rows of text cells; empty when no load carries it.
std::vector<std::vector<std::string>> sync_rows(const SetupResult& s, const std::vector<int>& speeds) {
  std::vector<std::vector<std::string>> rows;
  bool any = false;
  for (const auto& l : s.loads) {
    std::vector<std::string> r{fmt::format("{:g} N", l.load_N)};
    double uc = 0.0;
    int n = 0;
    for (const auto& [v, x] : l.uc_sync_mm) {
      if (std::isfinite(x)) {
        uc += x;
        ++n;
      }
    }
    r.push_back(n > 0 ? fmt::format("{:.3f}", uc / n) : "-");
    for (int v : speeds) {
      const double c = value_at_speed(l.c_sync_mm, v);
      any = any || std::isfinite(c);
      r.push_back(std::isfinite(c) ? fmt::format("{:.3f}", c) : "-");
    }
    rows.push_back(std::move(r));
  }
  if (!any) rows.clear();
  return rows;
}

}  // namespace

std::string study_tables_text(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  const std::vector<int> speeds = study_speeds_mm_s(study);
  const auto titles = table_titles(study);
  std::string out;
  for (std::size_t si = 0; si < study.setups.size(); ++si) {
    const SetupResult& s = study.setups[si];
    const PaperTable* pt = paper_table_of(paper, s);
    const Grid g = setup_grid(s, speeds, pt);
    out += fmt::format("{}: mean distance from the unloaded path, mm{}\n", titles[si],
                       pt != nullptr ? "; ours (paper's)" : "");
    if (!s.description.empty()) {
      out += fmt::format("  {}\n", s.description);
    }
    std::vector<std::size_t> width(g.header.size());
    for (std::size_t c = 0; c < g.header.size(); ++c) {
      width[c] = g.header[c].size();
      for (const auto& r : g.rows) {
        width[c] = std::max(width[c], r.cells[c].size());
      }
    }
    auto line = [&](const std::vector<std::string>& cells) {
      std::string l = " ";
      for (std::size_t c = 0; c < cells.size(); ++c) {
        l += fmt::format(" {:<{}} ", cells[c], width[c]);
      }
      while (!l.empty() && l.back() == ' ') {
        l.pop_back();
      }
      return l + "\n";
    };
    out += line(g.header);
    std::string rule = " ";
    for (const auto w : width) {
      rule.append(1, ' ').append(w, '-').append(1, ' ');
    }
    out += rule.substr(0, rule.size() - 1) + "\n";
    for (const auto& r : g.rows) {
      out += line(r.cells);
    }
    out += "  compensation: 1 - (mean of the printed C columns) / printed UC, as the paper states its own\n";
    if (pt != nullptr) {
      std::string diffs;
      for (const auto& l : s.loads) {
        const PaperRow* pr = pt->row_for(l.load_N);
        if (pr != nullptr && std::isfinite(l.uc_mean_mm())) {
          // From the printed figures, so the reader's own division gives the same percentage.
          diffs += fmt::format("{}{:g} N {}", diffs.empty() ? "" : ", ", l.load_N,
                               signed_percent_text(uc_over_paper(l, *pr) - 1.0));
        }
      }
      if (!diffs.empty()) {
        out += fmt::format("  UC against the paper's: {}\n", diffs);
      }
    }
    const auto sync = sync_rows(s, speeds);
    if (!sync.empty()) {
      out += "  Time-synchronous error (against the unloaded run at the same time: sees lag along the path), mm:\n";
      std::string head = fmt::format("  {:<7} {:>6}", "load", "UC");
      for (int v : speeds) head += fmt::format(" {:>10}", fmt::format("C {} mm/s", v));
      out += head + "\n";
      for (const auto& r : sync) {
        std::string l = fmt::format("  {:<7} {:>6}", r[0], r[1]);
        for (std::size_t c = 2; c < r.size(); ++c) l += fmt::format(" {:>10}", r[c]);
        out += l + "\n";
      }
    }
    out += "\n";
  }
  return out;
}

std::string study_tables_markdown(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  const std::vector<int> speeds = study_speeds_mm_s(study);
  const auto titles = table_titles(study);
  std::string out;
  for (std::size_t si = 0; si < study.setups.size(); ++si) {
    const SetupResult& s = study.setups[si];
    const PaperTable* pt = paper_table_of(paper, s);
    const Grid g = setup_grid(s, speeds, pt);
    out += fmt::format(
        "### {}\n\nMean distance from the unloaded path in mm{}; compensation 1 - (mean of the C columns) / UC, "
        "from the printed figures, as the paper states its own.",
        titles[si], pt != nullptr ? "; ours (the paper's in brackets)" : "");
    if (!s.description.empty()) {
      out += " " + s.description;
    }
    out += "\n\n|";
    for (const auto& h : g.header) {
      out.append(" ").append(h).append(" |");
    }
    out += "\n|";
    for (std::size_t c = 0; c < g.header.size(); ++c) {
      out += c == 0 ? " --- |" : " ---: |";
    }
    out += "\n";
    for (const auto& r : g.rows) {
      out += "|";
      for (const auto& c : r.cells) {
        out.append(" ").append(c).append(" |");
      }
      out += "\n";
    }
    const auto sync = sync_rows(s, speeds);
    if (!sync.empty()) {
      out +=
          "\nTime-synchronous error in mm (against the unloaded run at the same time: it sees lag along the path, "
          "which the nearest-point distance does not).\n\n| load | UC |";
      for (int v : speeds) out += fmt::format(" C {} mm/s |", v);
      out += "\n| --- | ---: |";
      for (std::size_t c = 0; c < speeds.size(); ++c) out += " ---: |";
      out += "\n";
      for (const auto& r : sync) {
        out += "|";
        for (const auto& c : r) out.append(" ").append(c).append(" |");
        out += "\n";
      }
    }
    out += "\n";
  }
  return out;
}

std::string study_csv_text(const StudyResult& study) {
  // Not through CsvWriter: the first column is text (the setup's name).
  std::string f;
  const PaperFigures paper = paper_reference();
  auto cell = [](double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string(); };
  f += "setup,load_N,speed_mm_s,uc_mm,c_mm,compensation,uc_std_mm,c_std_mm,uc_max_mm,c_max_mm,"
       "iso_accuracy_uc_mm,iso_accuracy_c_mm,iso_repeatability_mm,uc_sync_mm,c_sync_mm,seeds,c_mm_seed_sd,"
       "c_mm_seed_min,c_mm_seed_max,paper_uc_mm,paper_c_mm\n";
  for (const auto& s : study.setups) {
    const PaperTable* pt = paper_table_of(paper, s);
    for (const auto& l : s.loads) {
      const PaperRow* pr = pt != nullptr ? pt->row_for(l.load_N) : nullptr;
      for (const int v : study_speeds_mm_s(study)) {
        const auto at = [&](const std::map<int, double>& m) { return cell(value_at_speed(m, v)); };
        const Spread cs = l.c_spread(v);
        f += fmt::format("{},{:g},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", csv_text_cell(s.setup),
                         l.load_N, v, at(l.uc_mm), at(l.c_mm), at(l.compensation), at(l.uc_std_mm), at(l.c_std_mm),
                         at(l.uc_max_mm), at(l.c_max_mm), at(l.iso_accuracy_uc_mm), at(l.iso_accuracy_c_mm),
                         at(l.iso_repeatability_mm), at(l.uc_sync_mm), at(l.c_sync_mm), cs.n, cell(cs.sd), cell(cs.min),
                         cell(cs.max), cell(pr != nullptr ? pr->uc_mm : kNaN),
                         pr != nullptr ? at(pr->c_mm) : std::string());
      }
    }
  }
  return f;
}

std::string sweep_csv_text(const StudyResult& study) {
  std::string f;
  auto cell = [](double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string(); };
  f += "setup,load_N,speed_mm_s,uc_mm,c_mm,compensation,c_sync_mm,seeds,c_mm_seed_sd,c_mm_seed_min,c_mm_seed_max\n";
  for (const auto& p : study.speed_sweep) {
    const Spread cs = p.c_mm_by_seed.empty() ? spread_of({p.c_mm}) : spread_of(p.c_mm_by_seed);
    f += fmt::format("{},{:g},{:g},{},{},{},{},{},{},{},{}\n", csv_text_cell(p.setup), p.load_N, p.speed_mm_s,
                     cell(p.uc_mm), cell(p.c_mm), cell(p.compensation), cell(p.c_sync_mm), cs.n, cell(cs.sd),
                     cell(cs.min), cell(cs.max));
  }
  return f;
}

std::string error_budget_csv_text(const StudyResult& study) {
  std::string f;
  auto cell = [](double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string(); };
  f += "setup,load_N,speed_mm_s,seed,laps,residual_mm_all,residual_mm_all_off,uc_mm,effect,size,"
       "residual_mm_without_it,sensitivity_one_at_a_time\n";
  for (const auto& b : study.error_budgets) {
    for (const auto& e : b.entries) {
      f += fmt::format("{},{:g},{:g},{},{},{},{},{},{},{},{},{}\n", csv_text_cell(b.setup), b.load_N, b.speed_mm_s,
                       b.seed, b.laps, cell(b.residual_mm_all), cell(b.residual_mm_all_off), cell(b.uc_mm),
                       csv_text_cell(e.effect), csv_text_cell(e.size), cell(e.residual_mm_without_it),
                       cell(e.sensitivity));
    }
  }
  return f;
}

void write_study_csv(const StudyResult& study, const std::string& path) {
  write_output_file(path, study_csv_text(study));
}

void write_sweep_csv(const StudyResult& study, const std::string& path) {
  write_output_file(path, sweep_csv_text(study));
}

void write_error_budget_csv(const StudyResult& study, const std::string& path) {
  write_output_file(path, error_budget_csv_text(study));
}

}  // namespace deflex
