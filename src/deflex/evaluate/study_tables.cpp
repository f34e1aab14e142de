// Case-study results as JSON, terminal tables beside the paper's, Markdown and CSV.
#include "deflex/evaluate/study_tables.hpp"

#include <cmath>
#include <fstream>
#include <limits>

#include <fmt/format.h>

#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/model/errors.hpp"

namespace deflex {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json speed_map(const std::map<int, double>& m) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [speed, v] : m) {
    j[std::to_string(speed)] = number(v);
  }
  return j;
}

// The table number a setup gets: the paper's own numbers for its two, then 3, 4, ... in order.
std::vector<std::string> table_titles(const StudyResult& study) {
  std::vector<std::string> titles;
  int next = 3;
  for (const auto& s : study.setups) {
    if (s.setup == "offline") {
      titles.push_back("Table 1 (offline compensation)");
    } else if (s.setup == "online") {
      titles.push_back("Table 2 (online compensation, force sensor mounted)");
    } else {
      titles.push_back(fmt::format("Table {} ({}, beyond the paper)", next++, s.setup));
    }
  }
  return titles;
}

double mean_over(const std::map<int, double>& m, const std::vector<int>& speeds) {
  double sum = 0.0;
  int n = 0;
  for (const int v : speeds) {
    const double x = value_at_speed(m, v);
    if (std::isfinite(x)) {
      sum += x;
      ++n;
    }
  }
  return n > 0 ? sum / n : kNaN;
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
  g.header.push_back("compensation");
  for (const auto& l : s.loads) {
    const PaperRow* pr = paper != nullptr ? paper->row_for(l.load_N) : nullptr;
    Row r;
    r.cells.push_back(fmt::format("{:g} N", l.load_N));
    r.cells.push_back(cell_with_paper(mm(l.uc_mean_mm()), pr != nullptr ? paper_mm(pr->uc_mm) : ""));
    for (const int v : speeds) {
      const double pc = pr != nullptr ? value_at_speed(pr->c_mm, v) : kNaN;
      r.cells.push_back(cell_with_paper(mm(value_at_speed(l.c_mm, v)), paper_mm(pc)));
    }
    r.cells.push_back(cell_with_paper(percent_text(mean_over(l.compensation, speeds)),
                                      pr != nullptr ? percent_text(paper_compensation(*pr)) : ""));
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
    std::size_t used = 0;
    int speed = 0;
    try {
      speed = std::stoi(key, &used);
    } catch (const std::logic_error&) {
      used = 0;
    }
    if (used != key.size() || key.empty()) {
      throw DataError(fmt::format("{}: key '{}' is not a speed in mm/s", where, key));
    }
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

std::string percent_text(double fraction) {
  if (!std::isfinite(fraction)) {
    return "n/a";
  }
  const double p = std::round(fraction * 100.0);
  return fmt::format("{:.0f}%", p == 0.0 ? 0.0 : p);
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

void LoadResult::fill_compensation() {
  for (const auto& [v, c] : c_mm) {
    const auto it = uc_mm.find(v);
    if (it != uc_mm.end()) {
      compensation[v] = compensation_ratio(it->second, c);
    }
  }
}

nlohmann::json study_to_json(const StudyResult& study) {
  nlohmann::json setups = nlohmann::json::array();
  for (const auto& s : study.setups) {
    nlohmann::json loads = nlohmann::json::array();
    for (const auto& l : s.loads) {
      nlohmann::json jl{{"load_N", l.load_N},
                        {"uc_mm", speed_map(l.uc_mm)},
                        {"c_mm", speed_map(l.c_mm)},
                        {"compensation", speed_map(l.compensation)}};
      const std::pair<const char*, const std::map<int, double>*> optional[] = {
          {"uc_std_mm", &l.uc_std_mm},
          {"c_std_mm", &l.c_std_mm},
          {"uc_max_mm", &l.uc_max_mm},
          {"c_max_mm", &l.c_max_mm},
          {"iso_accuracy_uc_mm", &l.iso_accuracy_uc_mm},
          {"iso_accuracy_c_mm", &l.iso_accuracy_c_mm},
          {"iso_repeatability_mm", &l.iso_repeatability_mm},
          {"uc_sync_mm", &l.uc_sync_mm},
          {"c_sync_mm", &l.c_sync_mm}};
      for (const auto& [key, m] : optional) {
        if (!m->empty()) {
          jl[key] = speed_map(*m);
        }
      }
      loads.push_back(jl);
    }
    nlohmann::json js{{"setup", s.setup}, {"loads", loads}};
    if (!s.description.empty()) {
      js["description"] = s.description;
    }
    setups.push_back(js);
  }
  nlohmann::json doc{{"setups", setups}, {"speeds_mm_s", study_speeds_mm_s(study)}};
  if (!study.speed_sweep.empty()) {
    nlohmann::json sweep = nlohmann::json::array();
    for (const auto& p : study.speed_sweep) {
      sweep.push_back({{"setup", p.setup},
                       {"load_N", p.load_N},
                       {"speed_mm_s", p.speed_mm_s},
                       {"uc_mm", number(p.uc_mm)},
                       {"c_mm", number(p.c_mm)},
                       {"compensation", number(p.compensation)}});
    }
    doc["speed_sweep"] = sweep;
  }
  if (!study.case_name.empty()) {
    doc["case"] = study.case_name;
  }
  doc["seed"] = study.seed;
  if (study.wall_time_s > 0.0) {
    doc["wall_time_s"] = study.wall_time_s;
  }
  nlohmann::json paper = nlohmann::json::object();
  for (const auto& t : paper_reference().tables) {
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& r : t.rows) {
      rows.push_back({{"load_N", r.load_N}, {"uc_mm", r.uc_mm}, {"c_mm", speed_map(r.c_mm)}});
    }
    paper[t.setup] = rows;
  }
  doc["paper"] = paper;
  return doc;
}

StudyResult study_from_json(const nlohmann::json& doc, const std::string& source) {
  StudyResult study;
  if (!doc.is_object() || !doc.contains("setups") || !doc.at("setups").is_array()) {
    throw DataError(fmt::format("{}: missing array 'setups'", source));
  }
  std::size_t si = 0;
  for (const auto& js : doc.at("setups")) {
    const std::string where = fmt::format("{}: setups[{}]", source, si++);
    if (!js.is_object() || !js.contains("setup") || !js.at("setup").is_string()) {
      throw DataError(fmt::format("{}: missing string field 'setup'", where));
    }
    SetupResult s;
    s.setup = js.at("setup").get<std::string>();
    if (js.contains("description") && js.at("description").is_string()) {
      s.description = js.at("description").get<std::string>();
    }
    if (!js.contains("loads") || !js.at("loads").is_array()) {
      throw DataError(fmt::format("{}: missing array 'loads'", where));
    }
    std::size_t li = 0;
    for (const auto& jl : js.at("loads")) {
      const std::string lw = fmt::format("{}.loads[{}]", where, li++);
      LoadResult l;
      l.load_N = read_number(jl, "load_N", lw);
      const std::pair<const char*, std::map<int, double>*> maps[] = {
          {"uc_mm", &l.uc_mm},
          {"c_mm", &l.c_mm},
          {"compensation", &l.compensation},
          {"uc_std_mm", &l.uc_std_mm},
          {"c_std_mm", &l.c_std_mm},
          {"uc_max_mm", &l.uc_max_mm},
          {"c_max_mm", &l.c_max_mm},
          {"iso_accuracy_uc_mm", &l.iso_accuracy_uc_mm},
          {"iso_accuracy_c_mm", &l.iso_accuracy_c_mm},
          {"iso_repeatability_mm", &l.iso_repeatability_mm},
          {"uc_sync_mm", &l.uc_sync_mm},
          {"c_sync_mm", &l.c_sync_mm}};
      for (const auto& [key, m] : maps) {
        if (jl.contains(key)) {
          *m = read_speed_map(jl.at(key), lw + "." + key);
        } else if (std::string(key) == "uc_mm" || std::string(key) == "c_mm") {
          throw DataError(fmt::format("{}: missing field '{}'", lw, key));
        }
      }
      s.loads.push_back(l);
    }
    study.setups.push_back(s);
  }
  if (doc.contains("speeds_mm_s")) {
    for (const auto& v : doc.at("speeds_mm_s")) {
      if (!v.is_number_integer()) {
        throw DataError(fmt::format("{}: speeds_mm_s: not an integer speed in mm/s", source));
      }
      study.speeds_mm_s.push_back(v.get<int>());
    }
  }
  if (doc.contains("speed_sweep")) {
    std::size_t pi = 0;
    for (const auto& jp : doc.at("speed_sweep")) {
      const std::string pw = fmt::format("{}: speed_sweep[{}]", source, pi++);
      SweepPoint p;
      if (!jp.contains("setup") || !jp.at("setup").is_string()) {
        throw DataError(fmt::format("{}: missing string field 'setup'", pw));
      }
      p.setup = jp.at("setup").get<std::string>();
      p.load_N = read_number(jp, "load_N", pw);
      p.speed_mm_s = read_number(jp, "speed_mm_s", pw);
      p.uc_mm = jp.contains("uc_mm") && jp.at("uc_mm").is_null() ? kNaN : read_number(jp, "uc_mm", pw);
      p.c_mm = jp.contains("c_mm") && jp.at("c_mm").is_null() ? kNaN : read_number(jp, "c_mm", pw);
      p.compensation = compensation_ratio(p.uc_mm, p.c_mm);
      study.speed_sweep.push_back(p);
    }
  }
  if (doc.contains("case") && doc.at("case").is_string()) {
    study.case_name = doc.at("case").get<std::string>();
  }
  if (doc.contains("seed") && doc.at("seed").is_number_unsigned()) {
    study.seed = doc.at("seed").get<std::uint64_t>();
  }
  if (doc.contains("wall_time_s") && doc.at("wall_time_s").is_number()) {
    study.wall_time_s = doc.at("wall_time_s").get<double>();
  }
  return study;
}

std::string study_tables_text(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  const std::vector<int> speeds = study_speeds_mm_s(study);
  const auto titles = table_titles(study);
  std::string out;
  for (std::size_t si = 0; si < study.setups.size(); ++si) {
    const SetupResult& s = study.setups[si];
    const PaperTable* pt = paper.table_for(s.setup);
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
    if (pt != nullptr) {
      std::string diffs;
      for (const auto& l : s.loads) {
        const PaperRow* pr = pt->row_for(l.load_N);
        if (pr != nullptr && std::isfinite(l.uc_mean_mm())) {
          diffs += fmt::format("{}{:g} N {:+.0f}%", diffs.empty() ? "" : ", ", l.load_N,
                               (l.uc_mean_mm() / pr->uc_mm - 1.0) * 100.0);
        }
      }
      if (!diffs.empty()) {
        out += fmt::format("  UC against the paper's: {}\n", diffs);
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
    const PaperTable* pt = paper.table_for(s.setup);
    const Grid g = setup_grid(s, speeds, pt);
    out += fmt::format("### {}\n\nMean distance from the unloaded path in mm{}.", titles[si],
                       pt != nullptr ? "; ours (the paper's in brackets)" : "");
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
    out += "\n";
  }
  return out;
}

void write_study_csv(const StudyResult& study, const std::string& path) {
  // Written directly rather than with CsvWriter: the first column is text (the setup's name).
  std::ofstream f(path);
  if (!f) {
    throw Error(fmt::format("{}: cannot write the file", path));
  }
  const PaperFigures paper = paper_reference();
  auto cell = [](double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string(); };
  f << "setup,load_N,speed_mm_s,uc_mm,c_mm,compensation,uc_std_mm,c_std_mm,uc_max_mm,c_max_mm,"
       "iso_accuracy_uc_mm,iso_accuracy_c_mm,iso_repeatability_mm,uc_sync_mm,c_sync_mm,paper_uc_mm,paper_c_mm\n";
  for (const auto& s : study.setups) {
    const PaperTable* pt = paper.table_for(s.setup);
    for (const auto& l : s.loads) {
      const PaperRow* pr = pt != nullptr ? pt->row_for(l.load_N) : nullptr;
      for (const int v : study_speeds_mm_s(study)) {
        const auto at = [&](const std::map<int, double>& m) { return cell(value_at_speed(m, v)); };
        f << fmt::format("{},{:g},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", s.setup, l.load_N, v, at(l.uc_mm),
                         at(l.c_mm), at(l.compensation), at(l.uc_std_mm), at(l.c_std_mm), at(l.uc_max_mm),
                         at(l.c_max_mm), at(l.iso_accuracy_uc_mm), at(l.iso_accuracy_c_mm), at(l.iso_repeatability_mm),
                         at(l.uc_sync_mm), at(l.c_sync_mm), cell(pr != nullptr ? pr->uc_mm : kNaN),
                         pr != nullptr ? at(pr->c_mm) : std::string());
      }
    }
  }
  if (!f) {
    throw Error(fmt::format("{}: write failed", path));
  }
}

}  // namespace deflex
