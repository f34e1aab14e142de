// The case study's self-contained HTML report and its files.
#include "deflex/report/html_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/study/paper_figures.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

const char* const kCss = R"(
body { font-family: Helvetica, Arial, sans-serif; color: #222; max-width: 1060px; margin: 24px auto; padding: 0 16px; line-height: 1.45; }
h1 { font-size: 26px; margin-bottom: 4px; }
h2 { font-size: 20px; border-bottom: 2px solid #4C78A8; padding-bottom: 3px; margin-top: 34px; }
h3 { font-size: 16px; margin-bottom: 6px; }
.sub { color: #666; margin-top: 0; }
table { border-collapse: collapse; margin: 8px 0 16px 0; font-size: 14px; }
th, td { border: 1px solid #d0d0d0; padding: 4px 10px; text-align: right; white-space: nowrap; }
th { white-space: normal; }
th { background: #eef2f7; }
td.l, th.l { text-align: left; }
td.l { white-space: normal; min-width: 6em; }
.paper { color: #777; font-size: 12px; }
.sd { color: #555; font-size: 12px; }
.good { color: #2e7d32; } .bad { color: #c62828; }
.bar { display: inline-block; height: 10px; background: #4C78A8; vertical-align: middle; }
.fig { margin: 10px 0 22px 0; }
.fig svg { max-width: 100%; height: auto; }
.pair { display: flex; flex-wrap: wrap; gap: 20px; }
.pair svg { flex: 0 0 auto; }
.note { background: #fff8e1; border-left: 4px solid #f0b429; padding: 8px 12px; margin: 8px 0; }
pre { background: #f6f6f6; padding: 10px; overflow-x: auto; font-size: 12px; }
.caption { color: #555; font-size: 13px; }
)";

std::string esc(const std::string& s) { return xml_escape(s); }

std::string mm(double v) { return std::isfinite(v) ? fmt::format("{:.3f}", v) : "n/a"; }

// "0.152 ±0.012" with the spread small and grey; just the mean for one seed.
std::string mm_spread(const Spread& s) {
  if (s.n <= 1) {
    return mm(s.mean);
  }
  return fmt::format("{} <span class=\"sd\">&#177;{:.3f}</span>", mm(s.mean), s.sd);
}

std::string percent_spread(const Spread& s) {
  if (s.n <= 1) {
    return percent_text(s.mean);
  }
  return fmt::format("{} <span class=\"sd\">&#177;{:.0f}</span>", percent_text(s.mean), s.sd * 100.0);
}

std::string with_paper(const std::string& ours, double paper_value, int decimals = 2) {
  if (!std::isfinite(paper_value)) {
    return ours;
  }
  return fmt::format("{} <span class=\"paper\">({:.{}f})</span>", ours, paper_value, decimals);
}

std::string seeds_text(const StudyResult& study) {
  if (study.seeds.size() <= 1) {
    return fmt::format("seed {}", study.seeds.empty() ? study.seed : study.seeds.front());
  }
  std::string list;
  for (std::size_t i = 0; i < study.seeds.size(); ++i) {
    list += fmt::format("{}{}", i == 0 ? "" : ", ", study.seeds[i]);
  }
  return fmt::format("{} seeds ({})", study.seeds.size(), list);
}

// The setups compared with a paper table of another name, in a sentence ("" when none).
std::string paper_link_sentence(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  std::string out;
  for (const auto& s : study.setups) {
    const PaperTable* pt = paper.table_for(s.paper_table);
    if (s.paper_table.empty() || paper.table_for(s.setup) != nullptr || pt == nullptr) continue;
    out += fmt::format(
        " The setup {}, {}, is set beside the paper's {}, as is the setup {}: the paper measured that "
        "table over such a link.",
        esc(s.setup), esc(s.paper_label), esc(pt->caption.substr(0, pt->caption.find('.'))), esc(s.paper_table));
  }
  return out;
}

std::string results_tables(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  const std::vector<int> speeds = study_speeds_mm_s(study);
  std::string h;
  int next = 3;
  for (const auto& s : study.setups) {
    const PaperTable* pt = paper_table_of(paper, s);
    std::string title;
    if (s.setup == "offline") {
      title = "Table 1: offline compensation";
    } else if (s.setup == "online") {
      title = "Table 2: online compensation (force sensor mounted)";
    } else if (pt != nullptr) {
      title = fmt::format("Table {}: {}, {}, beside the paper's {}", next++, s.setup,
                          s.paper_label.empty() ? "compared with the paper" : s.paper_label,
                          pt->caption.substr(0, pt->caption.find('.')));
    } else {
      title = fmt::format("Table {}: {} (beyond the paper)", next++, s.setup);
    }
    h += fmt::format("<h3>{}</h3>\n", esc(title));
    if (!s.description.empty()) {
      h += fmt::format("<p class=\"caption\">{}</p>\n", esc(s.description));
    }
    h += "<table>\n<tr><th class=\"l\">load</th><th>UC (mm)</th>";
    for (std::size_t i = 0; i < speeds.size(); ++i) {
      h += fmt::format("<th>C{} at {} mm/s (mm)</th>", i + 1, speeds[i]);
    }
    for (const int v : speeds) {
      h += fmt::format("<th>comp. {} mm/s (%)</th>", v);
    }
    h += pt != nullptr ? "<th>UC vs paper (%)</th><th>C vs paper, mean over speeds (%)</th></tr>\n" : "</tr>\n";
    for (const auto& l : s.loads) {
      const PaperRow* pr = pt != nullptr ? pt->row_for(l.load_N) : nullptr;
      h += fmt::format("<tr><td class=\"l\">{:g} N</td><td>{}</td>", l.load_N,
                       with_paper(mm_spread(l.uc_mean_spread()), pr != nullptr ? pr->uc_mm : kNaN));
      for (const int v : speeds) {
        h += fmt::format("<td>{}</td>",
                         with_paper(mm_spread(l.c_spread(v)), pr != nullptr ? value_at_speed(pr->c_mm, v) : kNaN));
      }
      for (const int v : speeds) {
        const double paper_comp = pr != nullptr ? compensation_ratio(pr->uc_mm, value_at_speed(pr->c_mm, v))
                                                : kNaN;  // its UC: the speeds' mean
        // Ours the same way, from the figures printed in this row.
        const std::string ours = percent_text(printed_compensation(l, v));
        h += fmt::format("<td>{}</td>", std::isfinite(paper_comp) ? fmt::format("{} <span class=\"paper\">({})</span>",
                                                                                ours, percent_text(paper_comp))
                                                                  : ours);
      }
      if (pt != nullptr) {
        // Both from the printed figures of this row, so a reader's own division gives the same.
        const double uc_rel = pr != nullptr ? uc_over_paper(l, *pr) - 1.0 : kNaN;
        const double c_rel = pr != nullptr ? c_over_paper(l, *pr) - 1.0 : kNaN;
        for (const auto& [rel, target] : {std::pair{uc_rel, kUcTarget}, std::pair{c_rel, kCTarget}}) {
          if (std::isfinite(rel)) {
            h += fmt::format("<td class=\"{}\">{}</td>", std::abs(rel) <= target ? "good" : "bad",
                             signed_percent_text(rel));
          } else {
            h += "<td>n/a</td>";
          }
        }
      }
      h += "</tr>\n";
    }
    h += "</table>\n";
  }
  h += fmt::format(
      "<p class=\"caption\">Mean distance of the loaded runs' tracker points from the unloaded laps' mean path at the "
      "same speed (the paper's metric), in mm: the mean over {}{}; the paper's figures in brackets (grey). UC is the "
      "mean over the speeds, as in the paper. Compensation = 1 - C/UC with that UC, ours and the paper's alike, "
      "and every percentage here is computed from the figures as printed beside it. \"UC vs paper\" is green "
      "within {} and \"C vs paper\" (C summed over the paper's speeds against the paper's sum) within {}: the "
      "fidelity targets.{}</p>\n",
      seeds_text(study), study.seed_count() > 1 ? ", &#177; the sample standard deviation over the seeds" : "",
      percent_text(kUcTarget), percent_text(kCTarget), paper_link_sentence(study));
  return h;
}

// The time-synchronous error beside the nearest-point one, every setup in one table.
std::string sync_table(const StudyResult& study) {
  const std::vector<int> speeds = study_speeds_mm_s(study);
  std::string rows;
  for (const auto& s : study.setups) {
    for (const auto& l : s.loads) {
      if (l.c_sync_mm.empty() && l.uc_sync_mm.empty()) {
        continue;
      }
      double uc_sync = 0.0;
      int n = 0;
      for (const int v : speeds) {
        const double x = value_at_speed(l.uc_sync_mm, v);
        if (std::isfinite(x)) {
          uc_sync += x;
          ++n;
        }
      }
      rows += fmt::format("<tr><td class=\"l\">{}</td><td>{:g} N</td><td>{}</td><td>{}</td>", esc(s.setup), l.load_N,
                          mm(l.uc_mean_mm()), n > 0 ? mm(uc_sync / n) : "n/a");
      for (const int v : speeds) {
        const auto it = l.c_sync_mm_by_seed.find(v);
        const Spread sync = it != l.c_sync_mm_by_seed.end() && !it->second.empty()
                                ? spread_of(it->second)
                                : spread_of({value_at_speed(l.c_sync_mm, v)});
        rows += fmt::format("<td>{}</td><td>{}</td>", mm_spread(l.c_spread(v)), mm_spread(sync));
      }
      rows += "</tr>\n";
    }
  }
  if (rows.empty()) {
    return "";
  }
  std::string h =
      "<h3 id=\"sync\">Time-synchronous error beside the paper's nearest-point metric</h3>\n"
      "<p class=\"caption\">The time-synchronous error is the mean distance between each loaded tracker point and "
      "the unloaded run's position at the same time since the start of motion, so it counts lag along the path, "
      "which the nearest-point distance (a path followed late but on the line scores 0) does not. Means over the "
      "seeds; &#177; the standard deviation over them.</p>\n"
      "<table>\n<tr><th class=\"l\">setup</th><th>load</th><th>UC nearest-point (mm)</th>"
      "<th>UC time-sync. (mm)</th>";
  for (const int v : speeds) {
    h += fmt::format("<th>C {0} mm/s nearest-point (mm)</th><th>C {0} mm/s time-sync. (mm)</th>", v);
  }
  return h + "</tr>\n" + rows + "</table>\n<p class=\"caption\">UC columns: the mean over the speeds.</p>\n";
}

// What each online setup's controller link did, and the compensation that setup reached at its
// highest load: each controller's timing shows in the last columns.
std::string links_table(const std::vector<study::LinkSummary>& links) {
  if (links.empty()) {
    return "";
  }
  std::string h =
      "<h2 id=\"links\">Controller links</h2>\n<p class=\"caption\">Every online setup runs deflex's deployable link "
      "code over the cell's network against a simulated controller with that controller's own cycle, dead time, "
      "lag and limits. Cycles, rejected datagrams, guard trips and the largest correction are over the setup's "
      "compensated runs; the delay is the link's own measurement (the mean over those runs); UC and C are the "
      "setup's figures at its highest load (means over the speeds and seeds), the compensation 1 - C/UC from "
      "them as printed.</p>\n<table>\n<tr><th class=\"l\">setup</th><th class=\"l\">link</th><th>cycles "
      "answered</th><th>datagrams rejected</th><th>guard trips</th><th>largest correction (mrad)</th><th>bound "
      "(mrad)</th><th>largest at the TCP (mm)</th><th>measured delay (ms)</th><th>load</th><th>UC (mm)</th><th>C "
      "(mm)</th><th>compensation</th><th class=\"l\">the controller counted</th></tr>\n";
  for (const auto& l : links) {
    h += fmt::format(
        "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.1f}"
        "</td><td>{}</td><td>{}</td><td>{:g} N</td><td>{}</td><td>{}</td><td>{}</td><td class=\"l\">{}</td></tr>\n",
        esc(l.setup), esc(l.link), l.cycles, l.rejected, l.guard_trips,
        l.joint_commands ? fmt::format("{:.3f}", l.max_command_deviation_rad * 1e3) : std::string("(TCP offsets)"),
        l.bound_rad * 1e3, mm(l.max_tcp_correction_m * 1e3),
        std::isfinite(l.measured_delay_s) ? fmt::format("{:.0f}", l.measured_delay_s * 1e3) : "n/a", l.load_n,
        mm(l.uc_mm), mm(l.c_mm), percent_text(l.compensation), esc(l.controller_note));
  }
  return h + "</table>\n";
}

std::string compensation_table(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  const std::vector<int> speeds = study_speeds_mm_s(study);
  std::string h = "<table>\n<tr><th class=\"l\">setup</th><th>load</th><th>ours, mean over the speeds (%)</th>";
  if (study.seed_count() > 1) {
    h += "<th>seeds: min to max (%)</th>";
  }
  for (const int v : speeds) {
    h += fmt::format("<th>ours at {} mm/s (%)</th>", v);
  }
  h += "<th>the paper's, mean over the speeds (%)</th><th class=\"l\">the paper's at ";
  for (std::size_t i = 0; i < speeds.size(); ++i) {
    h += fmt::format("{}{}", i == 0 ? "" : " / ", speeds[i]);
  }
  h += " mm/s (%)</th></tr>\n";
  for (const auto& s : study.setups) {
    const PaperTable* pt = paper_table_of(paper, s);
    for (const auto& l : s.loads) {
      const PaperRow* pr = pt != nullptr ? pt->row_for(l.load_N) : nullptr;
      // As the results tables print it, from their printed figures.
      const Spread comp = printed_compensation_spread(l, speeds);
      h += fmt::format("<tr><td class=\"l\">{}</td><td>{:g} N</td><td>{}</td>", esc(s.setup), l.load_N,
                       percent_spread(comp));
      if (study.seed_count() > 1) {
        h += fmt::format("<td>{} to {}</td>", percent_text(comp.min), percent_text(comp.max));
      }
      for (const int v : speeds) {
        h += fmt::format("<td>{}</td>", percent_text(printed_compensation(l, v)));
      }
      if (pr != nullptr) {
        std::string per_speed;
        for (std::size_t i = 0; i < speeds.size(); ++i) {
          per_speed += fmt::format("{}{}", i == 0 ? "" : " / ",
                                   percent_text(compensation_ratio(pr->uc_mm, value_at_speed(pr->c_mm, speeds[i]))));
        }
        h += fmt::format("<td>{}</td><td class=\"l\">{}</td>", percent_text(pr->mean_compensation()), per_speed);
      } else {
        h += "<td>-</td><td class=\"l\">-</td>";
      }
      h += "</tr>\n";
    }
  }
  return h + "</table>\n";
}

std::string iso_table(const StudyResult& study) {
  const std::vector<int> speeds = study_speeds_mm_s(study);
  std::string rows;
  for (const auto& s : study.setups) {
    for (const auto& l : s.loads) {
      for (const int v : speeds) {
        const double a_uc = value_at_speed(l.iso_accuracy_uc_mm, v);
        const double a_c = value_at_speed(l.iso_accuracy_c_mm, v);
        const double rt = value_at_speed(l.iso_repeatability_mm, v);
        if (!std::isfinite(a_uc) && !std::isfinite(a_c) && !std::isfinite(rt)) {
          continue;
        }
        rows += fmt::format(
            "<tr><td class=\"l\">{}</td><td>{:g} N</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
            "<td>{}</td></tr>\n",
            esc(s.setup), l.load_N, v, mm(value_at_speed(l.uc_mm, v)), mm(a_uc), mm(value_at_speed(l.c_mm, v)), mm(a_c),
            mm(rt));
      }
    }
  }
  if (rows.empty()) {
    return "";
  }
  return fmt::format(
             "<h2 id=\"iso\">ISO 9283 path accuracy and repeatability</h2>\n"
             "<p class=\"caption\">ISO 9283:1998, 7.2, positions only, with the mean of the unloaded laps at the same "
             "speed as the reference path (not the commanded path). 81 planes normal to the reference at equal arc "
             "length; in each, the crossing points of every lap of the loaded run (clockwise and anticlockwise laps "
             "together; planes some lap does not cross are left out). AT<sub>p</sub>: the largest distance from the "
             "laps' barycentre to the reference point, for the uncompensated (UC) and the compensated (C) runs. "
             "RT<sub>p</sub>: the path repeatability of the compensated run's laps, the largest l&#772; + 3 "
             "S<sub>l</sub> of the crossing points about their barycentre. Beside them our nearest-point mean "
             "distance (the paper's metric) of the same runs. Every figure is the mean over {}.</p>\n",
             seeds_text(study)) +
         "<table>\n<tr><th class=\"l\">setup</th><th>load</th><th>speed (mm/s)</th><th>UC mean distance (mm)</th>"
         "<th>UC AT<sub>p</sub> (mm)</th><th>C mean distance (mm)</th><th>C AT<sub>p</sub> (mm)</th>"
         "<th>C RT<sub>p</sub> (mm)</th></tr>\n" +
         rows + "</table>\n";
}

// The table's own figure (mean over the seeds) for a budget's setup, load and speed.
const LoadResult* load_of(const StudyResult& study, const std::string& setup, double load_N) {
  for (const auto& s : study.setups) {
    if (s.setup != setup) {
      continue;
    }
    for (const auto& l : s.loads) {
      if (std::abs(l.load_N - load_N) < 0.5) {
        return &l;
      }
    }
  }
  return nullptr;
}

// ", while switching every effect off at once lowers C by 78%" ("" when that run is missing).
std::string all_off_text(const ErrorBudget& b) {
  const double s = one_at_a_time_sensitivity(as_printed(b.residual_mm_all), as_printed(b.residual_mm_all_off));
  if (!std::isfinite(s)) return "";
  return fmt::format(", while switching every effect off at once {} C by {}", s >= 0.0 ? "lowers" : "raises",
                     percent_text(std::abs(s)));
}

std::string budget_tables(const StudyResult& study) {
  const std::vector<ErrorBudget>& budgets = study.error_budgets;
  if (budgets.empty()) {
    return "";
  }
  std::string h =
      "<h2 id=\"budget\">Error budget: one effect at a time</h2>\n<p class=\"caption\">Each effect of the simulated "
      "cell that the compensators' model lacks, its size, and the compensated residual C when that effect alone is "
      "switched off (a cell built without it, calibrated anew, running the same runs with the same seeds). The "
      "sensitivity is (C with every effect - C without it) / C with every effect: how much C falls when that one "
      "effect is gone. It is not a share of the residual, and the effects' sensitivities do not add up to 100%: "
      "effects interact (one can hide or offset another, so switching it off can even raise C), the calibration "
      "absorbs part of each effect and absorbs it differently when another is gone, and C does not grow linearly "
      "with the effects. C with every effect off at once (its own calibration too) shows what is left when none "
      "of them is there. The run with every effect on is one seed's, the very run the tables average with the "
      "other seeds'; the table's mean over the seeds is given beside it, and the two differ by that seed's "
      "scatter. Every percentage is computed from the figures as printed (3 decimals).</p>\n";
  for (const auto& b : budgets) {
    std::string origin;
    if (b.seed != 0 || b.laps > 0) {
      origin = fmt::format(" (seed {}{})", b.seed, b.laps > 0 ? fmt::format(", {} laps a run", b.laps) : "");
    }
    std::string table_mean;
    if (const LoadResult* l = load_of(study, b.setup, b.load_N); l != nullptr) {
      const int v = static_cast<int>(std::lround(b.speed_mm_s));
      const Spread s = l->c_spread(v);
      if (std::isfinite(s.mean)) {
        table_mean = s.n > 1 ? fmt::format("; the table's C over {} seeds: {} mm (seeds {} to {})", s.n, mm(s.mean),
                                           mm(s.min), mm(s.max))
                             : fmt::format("; the table's C: {} mm", mm(s.mean));
      }
    }
    h += fmt::format("<h3>{}, {:g} N, {:g} mm/s{}: C {} mm with every effect on{}{}</h3>\n", esc(b.setup), b.load_N,
                     b.speed_mm_s, origin, mm(b.residual_mm_all),
                     b.uc_mm > 0.0 ? fmt::format(" (UC {} mm)", mm(b.uc_mm)) : "", table_mean);
    h += "<div class=\"fig\">\n" + svg_error_budget(b) + "</div>\n";
    h += "<table>\n<tr><th class=\"l\">effect</th><th class=\"l\">size</th><th>C without it alone (mm)</th>"
         "<th>sensitivity, one effect at a time: (C<sub>every effect</sub> - C<sub>without it</sub>) / "
         "C<sub>every effect</sub> (%)</th></tr>\n";
    double sum = 0.0;
    int n = 0;
    for (const auto& e : b.entries) {
      const double sensitivity = printed_sensitivity(b, e);
      if (std::isfinite(sensitivity)) {
        sum += whole_percent(sensitivity);
        ++n;
      }
      h += fmt::format("<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td></tr>\n", esc(e.effect),
                       esc(e.size), mm(e.residual_mm_without_it), percent_text(sensitivity));
    }
    h += fmt::format("<tr><td class=\"l\"><b>every effect on</b></td><td class=\"l\"></td><td>{}</td><td></td></tr>\n",
                     mm(b.residual_mm_all));
    if (std::isfinite(b.residual_mm_all_off)) {
      h += fmt::format(
          "<tr><td class=\"l\"><b>every effect off at once</b></td><td class=\"l\">its own calibration</td>"
          "<td>{}</td><td>{}</td></tr>\n",
          mm(b.residual_mm_all_off),
          percent_text(one_at_a_time_sensitivity(as_printed(b.residual_mm_all), as_printed(b.residual_mm_all_off))));
    }
    h += "</table>\n";
    if (n > 0) {
      h += fmt::format(
          "<p class=\"caption\">The {} sensitivities above add up to {:.0f}%{}: they are not shares of one "
          "residual.</p>\n",
          n, sum, all_off_text(b));
    }
  }
  return h;
}

bool any_setup(const StudyResult& study, bool with_paper) {
  return std::any_of(study.setups.begin(), study.setups.end(),
                     [&](const SetupResult& s) { return paper_has_setup(s) == with_paper; });
}

// The paper's compensation per table, from its own figures: ": offline 67% at every load, online 69%
// to 80%, rising with the load" (each row's 1 - mean C / UC).
std::string paper_compensation_text() {
  std::string out;
  for (const auto& t : paper_reference().tables) {
    std::vector<std::string> per_row;
    double lo = kNaN, hi = kNaN;
    bool rising = true;
    double last = -1.0;
    for (const auto& r : t.rows) {
      const double p = whole_percent(r.mean_compensation());
      lo = std::isfinite(lo) ? std::min(lo, p) : p;
      hi = std::isfinite(hi) ? std::max(hi, p) : p;
      rising = rising && p > last;
      last = p;
    }
    if (!std::isfinite(lo)) continue;
    const std::string range = lo == hi
                                  ? fmt::format("{:.0f}% at every load", lo)
                                  : fmt::format("{:.0f}% to {:.0f}%{}", lo, hi, rising ? ", rising with the load" : "");
    out += fmt::format("{} {} {}", out.empty() ? ":" : ";", esc(t.setup), range);
  }
  return out;
}

std::string figures_html(const StudyResult& study) {
  auto whiskers_of = [&](const char* what) {
    return study.seed_count() > 1
               ? fmt::format("{}: the mean over {}; whiskers: the range (min to max) over the seeds.", what,
                             seeds_text(study))
               : std::string("One seed: no whiskers.");
  };
  const std::string whiskers = whiskers_of("Bars");
  std::string h;
  const bool paper_setups = any_setup(study, true), other_setups = any_setup(study, false);
  h += "<h2 id=\"figure5\">Figure 5: mean deformation after compensation</h2>\n";
  h += "<div class=\"fig\">\n" + svg_figure5(study, paper_setups ? SetupSelection::kPaper : SetupSelection::kAll) +
       "</div>\n";
  h += "<p class=\"caption\">Upper panel: our residual after compensation (C) per load and speed; lower panel: the "
       "uncompensated deviation (UC, pale), the mean over the speeds as in the paper. Outlined bars: the paper's "
       "values (Tables 1 and 2) beside ours." +
       paper_link_sentence(study) + " " + whiskers + "</p>\n";
  if (paper_setups && other_setups) {
    h += "<div class=\"fig\">\n" + svg_figure5(study, SetupSelection::kBeyondPaper) + "</div>\n";
    h +=
        "<p class=\"caption\">The same, on the same axes, for the setups the paper did not run. " + whiskers + "</p>\n";
  }
  h += "<h2 id=\"compensation\">Compensation per load</h2>\n";
  h += "<p class=\"caption\">The figure the paper quotes" + paper_compensation_text() +
       ". Ours and the paper's alike: 1 - (C averaged over the speeds) / UC (the mean over the speeds), from the "
       "figures as the tables print them; whiskers: the same per seed. " +
       whiskers + "</p>\n";
  h += "<div class=\"fig\">\n" + svg_compensation(study) + "</div>\n";
  h += compensation_table(study);
  if (paper_setups) {
    h += "<div class=\"fig\">\n" + svg_trends(study) + "</div>\n";
    h += "<p class=\"caption\">The trends against load: C/UC per load (left axis; compensation 1 - C/UC on the "
         "right), ours (solid) beside the paper's (dashed), one panel per table of the paper. The notes compare "
         "them row by row. " +
         whiskers_of("Ours") + "</p>\n";
  }
  if (paper_setups) {
    h += "<h2 id=\"parity\">Parity with the paper</h2>\n<div class=\"fig\">\n" + svg_parity(study) + "</div>\n";
    h += "<p class=\"caption\">Every figure of the paper's Tables 1 and 2 against ours: C per load and speed "
         "(dots) and UC per load (squares, the mean over the speeds). Log axes, so equal ratios are equal "
         "distances. Shaded: within " +
         percent_text(kCTarget) +
         " of the paper's (the fidelity target for C, judged per load on the mean over the speeds); dashed: " +
         percent_text(kUcTarget) + " either side (the target for UC)." + paper_link_sentence(study) + " " +
         whiskers_of("Ours") + "</p>\n";
  }
  return h;
}

// The document's head, its title and the line under it naming the case, the seeds and the run time.
std::string html_head(const ReportContent& content) {
  const StudyResult& study = content.study;
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n";
  h += fmt::format("<title>{}</title>\n<style>{}</style>\n</head>\n<body>\n", esc(content.title), kCss);
  h += fmt::format("<h1>{}</h1>\n", esc(content.title));
  std::string sub = "Generated by deflex";
  if (!study.case_name.empty()) {
    sub += fmt::format(" &#183; case {}", esc(study.case_name));
  }
  sub += " &#183; " + seeds_text(study);
  if (study.wall_time_s > 0.0) {
    sub += fmt::format(" &#183; {:.1f} s wall time", study.wall_time_s);
  }
  h += fmt::format(
      "<p class=\"sub\">{}. Reference: the paper's Tables 1 and 2 and Figure 5 "
      "(offline and online compliance compensation of an ABB IRB6700 on a loaded circle).</p>\n",
      sub);
  return h;
}

// The setup in words and the case file as given.
std::string html_setup(const ReportContent& content) {
  std::string h;
  if (!content.setup_paragraphs.empty()) {
    h += "<h2 id=\"setup\">Setup</h2>\n";
    for (const auto& p : content.setup_paragraphs) {
      h += fmt::format("<p>{}</p>\n", esc(p));
    }
  }
  if (!content.case_text.empty()) {
    h += fmt::format("<details><summary>Case file</summary>\n<pre>{}</pre>\n</details>\n", esc(content.case_text));
  }
  return h;
}

// Each path plot's four figures, then one caption for them all.
std::string html_paths(const ReportContent& content) {
  std::string h;
  if (!content.path_plots.empty()) {
    h += "<h2 id=\"paths\">Paths, laps and directions</h2>\n";
    for (const auto& p : content.path_plots) {
      if (!p.title.empty()) {
        h += fmt::format("<h3>{}</h3>\n", esc(p.title));
      }
      h += "<div class=\"fig pair\">\n" + svg_path_plot(p) + svg_polar_deviation(p) + "</div>\n";
      h += "<div class=\"fig\">\n" + svg_lap_overlay(p) + "</div>\n";
      h += "<div class=\"fig\">\n" + svg_signed_error(p) + "</div>\n";
    }
    h += "<p class=\"caption\">Left: the last lap of the uncompensated (UC) and compensated (C) runs in the plane of "
         "the reference (the unloaded laps' mean path), each point drawn at its nearest reference point plus its "
         "magnified deviation; the arrowheads show the direction of travel. Right: the distance from the reference "
         "around the circle, drawn outward from the ring that stands for 0 mm, with rings labelled in mm; every lap "
         "of a direction averaged in 5 deg sectors. Below: every lap of each run, clockwise and anticlockwise in "
         "their own colours, against the angle about the circle's centre (0 deg: the base's +x direction from the "
         "centre; angles grow anticlockwise seen from above), with an arrowhead in each lap's direction of travel. "
         "Last: the compensated run's signed error, its deviation from the reference along the direction the "
         "uncompensated run deviated at the same angle (that run's laps of the same direction of travel, averaged "
         "in 5 deg sectors): above 0 under-compensated (still deflected the way the load pushes), below 0 "
         "over-compensated, which the distances above cannot tell apart. All from the first seed's runs.</p>\n";
  }
  return h;
}

std::string html_sweep(const StudyResult& study) {
  std::string h;
  if (!study.speed_sweep.empty()) {
    h += "<h2 id=\"sweep\">Speed sweep</h2>\n<div class=\"fig\">\n" + svg_speed_sweep(study) + "</div>\n";
    h +=
        "<p class=\"caption\">Beyond the paper's 10-50 mm/s (shaded): how each strategy's compensation holds up "
        "as the TCP speed grows and the compensation cycle and delay start to matter. The time-synchronous panel "
        "shows the lag the nearest-point metric does not see. " +
        std::string(study.seed_count() > 1 ? "Points: the mean over the seeds; whiskers: min to max over them. " : "") +
        "Each panel's range is fitted to its data; points at one speed are drawn side by side.</p>\n";
  }
  return h;
}

std::string html_notes(const ReportContent& content) {
  std::string h;
  if (!content.notes.empty()) {
    h += "<h2 id=\"notes\">Notes</h2>\n";
    for (const auto& n : content.notes) {
      h += fmt::format("<div class=\"note\">{}</div>\n", esc(n));
    }
  }
  return h;
}

// How every figure of the report is computed.
std::string html_method(const StudyResult& study) {
  std::string h;
  h += fmt::format(
      "<h2 id=\"method\">How the figures are computed</h2>\n<ul>\n"
      "<li>Reference path: the unloaded run at the same speed, its laps (clockwise and anticlockwise, as many as "
      "the protocol runs) averaged into one closed path: the samples binned by their angle about the centre (3600 "
      "sectors) "
      "and each sector's positions averaged. Measuring to every unloaded sample instead would bias the distance low "
      "by the unloaded trace's own noise.</li>\n"
      "<li>Mean deformation (the paper's figure, \"nearest-point\"): for every tracker point of a loaded run, the "
      "distance to the nearest point of the reference polyline; the mean over all points of all laps. It sees only "
      "the deviation across the path.</li>\n"
      "<li>Time-synchronous error: for every tracker point of a loaded run, the distance to the unloaded run's "
      "position at the same time since the start of motion (interpolated); the mean over the points. It sees lag "
      "and lead along the path too, so it judges latency and the predictive strategy.</li>\n"
      "<li>Compensation = 1 - C/UC with UC the mean over the speeds (the paper's UC column), ours and the paper's "
      "alike, computed from the figures as the tables print them (results.json and tables.csv keep 1 - C/UC at "
      "each speed with that speed's UC, unrounded).</li>\n"
      "<li>Seeds: {}. Each seed is its own cell (true robot, sensor, calibration) and its own runs; tables and "
      "figures give the mean over the seeds; the tables add &#177; the sample standard deviation, the figures "
      "whiskers from the smallest to the largest seed's value. The path, polar, lap and signed-error figures show "
      "the first seed's runs at each setup's highest load and the protocol's first speed (each figure's title "
      "names them); the error budget uses the first seed's table runs.</li>\n"
      "<li>ISO 9283 path accuracy AT<sub>p</sub> and repeatability RT<sub>p</sub>: section 7.2 of the standard, "
      "positions only, against the same reference (see docs/evaluation.md).</li>\n</ul>\n",
      seeds_text(study));
  return h;
}

}  // namespace

std::string html_report(const ReportContent& content) {
  const StudyResult& study = content.study;
  std::string h = html_head(content);
  h += html_setup(content);
  h += "<h2 id=\"results\">Results beside the paper</h2>\n";
  h += results_tables(study);
  h += sync_table(study);
  h += figures_html(study);
  h += iso_table(study);
  h += links_table(content.links);
  h += html_paths(content);
  h += budget_tables(study);
  h += html_sweep(study);
  h += html_notes(content);
  h += html_method(study);
  h += "</body>\n</html>\n";
  return h;
}

void write_report(const ReportContent& content, const std::string& out_dir, OutputTransaction& outputs) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) {
    throw Error(fmt::format("{}: cannot create the directory: {}", out_dir, ec.message()));
  }
  const std::filesystem::path dir(out_dir);
  const auto write_text = [&](const std::string& name, const std::string& text) {
    outputs.add((dir / name).string(), "report file").write(text);
  };
  const StudyResult& study = content.study;
  write_text("report.html", html_report(content));
  const bool paper_setups = any_setup(study, true);
  write_text("figure5.svg", svg_figure5(study, paper_setups ? SetupSelection::kPaper : SetupSelection::kAll));
  if (paper_setups && any_setup(study, false)) {
    write_text("figure5_beyond.svg", svg_figure5(study, SetupSelection::kBeyondPaper));
  }
  write_text("compensation.svg", svg_compensation(study));
  if (paper_setups) {
    write_text("trends.svg", svg_trends(study));
    write_text("parity.svg", svg_parity(study));
  }
  if (!study.speed_sweep.empty()) {
    write_text("speed_sweep.svg", svg_speed_sweep(study));
  }
  for (std::size_t i = 0; i < content.path_plots.size(); ++i) {
    const PathPlot& p = content.path_plots[i];
    write_text(fmt::format("path_{}.svg", i + 1), svg_path_plot(p));
    write_text(fmt::format("polar_{}.svg", i + 1), svg_polar_deviation(p));
    write_text(fmt::format("laps_{}.svg", i + 1), svg_lap_overlay(p));
    write_text(fmt::format("signed_{}.svg", i + 1), svg_signed_error(p));
  }
  for (std::size_t i = 0; i < study.error_budgets.size(); ++i) {
    write_text(fmt::format("budget_{}.svg", i + 1), svg_error_budget(study.error_budgets[i]));
  }
  write_text("tables.md", study_tables_markdown(study));
  write_text("tables.csv", study_csv_text(study));
  if (!study.speed_sweep.empty()) write_text("sweep.csv", sweep_csv_text(study));
  if (!study.error_budgets.empty()) write_text("error_budget.csv", error_budget_csv_text(study));
  write_text("results.json", study_to_json(study).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

void write_report(const ReportContent& content, const std::string& out_dir) {
  OutputTransaction outputs;
  write_report(content, out_dir, outputs);
  outputs.commit();
}

}  // namespace deflex
