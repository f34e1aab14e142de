// The case study's report content and honest notes (case_report.hpp).
#include "deflex/report/case_report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "deflex/evaluate/path_metrics.hpp"

namespace deflex::study {
namespace {

// A YAML key or value without the blanks, a flow mapping's braces and comma, or a list item's "- ".
std::string trim(const std::string& s) {
  auto b = s.find_first_not_of(" \t{");
  if (b != std::string::npos && s.compare(b, 2, "- ") == 0) b = s.find_first_not_of(" \t{", b + 2);
  const auto e = s.find_last_not_of(" \t,}");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

// "ahead of", "behind" or "level with", from whole percents as printed.
std::string order_word(double a, double b) {
  const double pa = whole_percent(a), pb = whole_percent(b);
  return pa > pb ? "ahead of" : pa < pb ? "behind" : "level with";
}

// The paper's table name ("Table 2") from its caption.
std::string table_name(const PaperTable& t) { return t.caption.substr(0, t.caption.find('.')); }

// A signed percentage outside a target, with one decimal where whole percents would print the target
// itself (-35.2 % outside 35 % must not read "-35%").
std::string beside_target_text(double fraction, double target) {
  return std::round(std::abs(fraction) * 100.0) == std::round(target * 100.0)
             ? fmt::format("{:+.1f}%", fraction * 100.0)
             : signed_percent_text(fraction);
}

// "falls", "rises" or "stays level" for C/UC from the first to the last load, as printed (two decimals).
std::string trend_word(double first, double last) {
  const double a = std::round(first * 100.0), b = std::round(last * 100.0);
  return b < a - 2.0 ? "falls" : b > a + 2.0 ? "rises" : "stays level";
}

// One setup's compensation against the paper's at each load (whole percents as the tables print
// them, the difference in points) and C/UC from its first load to its last, ours and the paper's.
std::string compensation_rows_note(const SetupResult& s, const PaperTable& pt, const std::vector<int>& speeds) {
  std::string rows;
  double ours_first = kNaN, ours_last = kNaN, paper_first = kNaN, paper_last = kNaN, load_first = 0.0, load_last = 0.0;
  for (const auto& l : s.loads) {
    const PaperRow* pr = pt.row_for(l.load_N);
    if (pr == nullptr) continue;
    const double ours = printed_compensation_spread(l, speeds).mean, theirs = pr->mean_compensation();
    if (!std::isfinite(ours) || !std::isfinite(theirs)) continue;
    const double points = whole_percent(ours) - whole_percent(theirs);
    rows += fmt::format("{}{:g} N {} against {} ({:+.0f} points)", rows.empty() ? "" : "; ", l.load_N,
                        percent_text(ours), percent_text(theirs), points);
    if (!std::isfinite(ours_first)) {
      ours_first = 1.0 - ours;
      paper_first = 1.0 - theirs;
      load_first = l.load_N;
    }
    ours_last = 1.0 - ours;
    paper_last = 1.0 - theirs;
    load_last = l.load_N;
  }
  if (rows.empty()) return fmt::format("{}: no load of the paper's {} to compare.", s.setup, table_name(pt));
  return fmt::format(
      "{} against the paper's {}, compensation row by row (ours against the paper's): {}. C/UC from {:g} N to {:g} "
      "N: ours {:.2f} to {:.2f} ({}), the paper's {:.2f} to {:.2f} ({}).",
      s.setup, table_name(pt), rows, load_first, load_last, ours_first, ours_last, trend_word(ours_first, ours_last),
      paper_first, paper_last, trend_word(paper_first, paper_last));
}

}  // namespace

std::vector<std::string> tuned_values(const std::string& case_text) {
  std::vector<std::string> out;
  std::istringstream in(case_text);
  std::string line, section;
  while (std::getline(in, line)) {
    const auto hash = line.find('#');
    const std::string body = line.substr(0, hash);
    const auto colon = body.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = trim(body.substr(0, colon));
    if (!line.empty() && !std::isspace(static_cast<unsigned char>(line[0]))) section = key;
    if (hash == std::string::npos) continue;
    std::string comment = trim(line.substr(hash + 1));
    std::string lower = comment;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char ch) { return std::tolower(ch); });
    if (lower.rfind("tuned", 0) != 0) continue;  // the case file's own mark: "# tuned: why"
    const std::string value = trim(body.substr(colon + 1));
    std::string name = section;
    if (name.empty() || section == key) {
      name = key;
    } else {
      name.append(".").append(key);
    }
    out.push_back(value.empty() ? fmt::format("{} ({})", name, comment)
                                : fmt::format("{} = {} ({})", name, value, comment));
  }
  return out;
}

std::vector<std::string> honest_notes(const CaseConfig& /*config*/, const StudyResult& study,
                                      const std::string& case_text) {
  std::vector<std::string> notes;
  const PaperFigures paper = paper_reference();
  const std::vector<int> speeds = study_speeds_mm_s(study);
  // Where the figures come from, and what the case file itself says was tuned (read from it, so the
  // note cannot outlive a change of the case).
  std::string origin =
      "These figures come from deflex's simulated cell, not from a robot. The cell's sizes are in the case file; "
      "docs/error-budget.md gives their sources.";
  if (!case_text.empty()) {
    const std::vector<std::string> tuned = tuned_values(case_text);
    if (tuned.empty()) {
      origin += " The case file marks no value as tuned to the paper's figures.";
    } else {
      origin += fmt::format(" The case file marks {} value{} as tuned:", tuned.size(), tuned.size() == 1 ? "" : "s");
      for (std::size_t i = 0; i < tuned.size(); ++i) origin += (i == 0 ? " " : "; ") + tuned[i];
      origin += ".";
    }
  }
  notes.push_back(origin);
  // Per load, where our printed figures leave the fidelity targets.
  for (const auto& s : study.setups) {
    const PaperTable* pt = paper_table_of(paper, s);
    if (pt == nullptr) continue;
    for (const auto& l : s.loads) {
      const PaperRow* pr = pt->row_for(l.load_N);
      if (pr == nullptr) continue;
      const double uc = uc_over_paper(l, *pr), c = c_over_paper(l, *pr);
      std::vector<std::string> outside;
      if (std::isfinite(uc) && std::abs(uc - 1.0) > kUcTarget) {
        outside.push_back(fmt::format("UC {:.3f} mm against the paper's {:.2f} mm, {} (target: within {})",
                                      as_printed(l.uc_mean_spread().mean), pr->uc_mm,
                                      beside_target_text(uc - 1.0, kUcTarget), percent_text(kUcTarget)));
      }
      if (std::isfinite(c) && std::abs(c - 1.0) > kCTarget) {
        outside.push_back(fmt::format("C over the paper's speeds {} against the paper's (target: within {})",
                                      beside_target_text(c - 1.0, kCTarget), percent_text(kCTarget)));
      }
      if (outside.empty()) continue;
      std::string text = fmt::format("{} {:g} N against the paper's {}: ", s.setup, l.load_N, table_name(*pt));
      for (std::size_t i = 0; i < outside.size(); ++i) text += (i == 0 ? "" : "; ") + outside[i];
      notes.push_back(text + ".");
    }
  }
  // Compensation against the paper's, row by row (never pooled over the loads: a range of ours that
  // overlaps the paper's can hide a gap at every row), then the trend of C/UC over the loads.
  for (const auto& s : study.setups) {
    const PaperTable* pt = paper_table_of(paper, s);
    if (pt != nullptr) notes.push_back(compensation_rows_note(s, *pt, speeds));
  }
  // The paper's headline, online ahead of offline at the highest load, checked on our figures and
  // on the paper's alike rather than asserted.
  const SetupResult* offline = nullptr;
  for (const auto& s : study.setups) {
    if (s.setup == "offline" && !s.loads.empty()) offline = &s;
  }
  const PaperTable* paper_offline = paper.table_for("offline");
  const PaperTable* paper_online = paper.table_for("online");
  if (offline != nullptr && paper_offline != nullptr && paper_online != nullptr && !paper_offline->rows.empty() &&
      !paper_online->rows.empty()) {
    const double ours_off = printed_compensation_spread(offline->loads.back(), speeds).mean;
    const double paper_off = paper_offline->rows.back().mean_compensation();
    for (const auto& s : study.setups) {
      const bool online = s.setup == "online" || s.paper_table == "online";
      if (!online || s.loads.empty() || !std::isfinite(ours_off)) continue;
      const double ours_on = printed_compensation_spread(s.loads.back(), speeds).mean;
      const double paper_on = paper_online->rows.back().mean_compensation();
      if (!std::isfinite(ours_on)) continue;
      const bool same = order_word(ours_on, ours_off) == order_word(paper_on, paper_off);
      notes.push_back(fmt::format(
          "At the highest load {} compensates {} and offline {}: {} {} offline. In the paper online compensates {} and "
          "offline {}: online {} offline. {}",
          s.setup, percent_text(ours_on), percent_text(ours_off), s.setup, order_word(ours_on, ours_off),
          percent_text(paper_on), percent_text(paper_off), order_word(paper_on, paper_off),
          same ? "The same order as the paper's." : "Not the paper's order."));
    }
  }
  return notes;
}

ReportContent case_report(const CaseConfig& config, const CaseStudyOutput& output, const std::string& case_text) {
  ReportContent report;
  report.title = "deflex case study: " + config.name;
  report.setup_paragraphs = output.setup_paragraphs;
  report.study = output.study;
  for (const auto& p : output.plots) {
    PathPlot plot;
    plot.title = p.title;
    plot.unloaded = p.unloaded;
    plot.uc = p.uc;
    plot.c = p.c;
    plot.unloaded_mean = p.unloaded_mean;
    plot.uc_laps = p.uc_laps;
    plot.c_laps = p.c_laps;
    report.path_plots.push_back(std::move(plot));
  }
  report.notes = honest_notes(config, output.study, case_text);
  report.case_text = case_text;
  report.links = output.links;
  return report;
}

}  // namespace deflex::study
