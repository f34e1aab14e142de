// The case study's self-contained HTML report and its files.
#include "deflex/report/html_report.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "deflex/evaluate/paper_figures.hpp"
#include "deflex/model/errors.hpp"

namespace deflex {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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
.paper { color: #777; font-size: 12px; }
.good { color: #2e7d32; } .bad { color: #c62828; }
.bar { display: inline-block; height: 10px; background: #4C78A8; vertical-align: middle; }
.fig { margin: 10px 0 22px 0; }
.fig svg { max-width: 100%; height: auto; }
.note { background: #fff8e1; border-left: 4px solid #f0b429; padding: 8px 12px; margin: 8px 0; }
pre { background: #f6f6f6; padding: 10px; overflow-x: auto; font-size: 12px; }
.caption { color: #555; font-size: 13px; }
)";

std::string esc(const std::string& s) { return xml_escape(s); }

std::string mm(double v) { return std::isfinite(v) ? fmt::format("{:.3f}", v) : "n/a"; }

std::string with_paper(const std::string& ours, double paper_value, int decimals = 2) {
  if (!std::isfinite(paper_value)) {
    return ours;
  }
  return fmt::format("{} <span class=\"paper\">({:.{}f})</span>", ours, paper_value, decimals);
}

std::string results_tables(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  const std::vector<int> speeds = study_speeds_mm_s(study);
  std::string h;
  int next = 3;
  for (const auto& s : study.setups) {
    const PaperTable* pt = paper.table_for(s.setup);
    std::string title;
    if (s.setup == "offline") {
      title = "Table 1: offline compensation";
    } else if (s.setup == "online") {
      title = "Table 2: online compensation (force sensor mounted)";
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
      h += fmt::format("<th>comp. {} mm/s</th>", v);
    }
    h += pt != nullptr ? "<th>UC vs paper</th></tr>\n" : "</tr>\n";
    for (const auto& l : s.loads) {
      const PaperRow* pr = pt != nullptr ? pt->row_for(l.load_N) : nullptr;
      h += fmt::format("<tr><td class=\"l\">{:g} N</td><td>{}</td>", l.load_N,
                       with_paper(mm(l.uc_mean_mm()), pr != nullptr ? pr->uc_mm : kNaN));
      for (const int v : speeds) {
        h += fmt::format("<td>{}</td>", with_paper(mm(value_at_speed(l.c_mm, v)),
                                                   pr != nullptr ? value_at_speed(pr->c_mm, v) : kNaN));
      }
      for (const int v : speeds) {
        const double paper_comp =
            pr != nullptr ? 1.0 - value_at_speed(pr->c_mm, v) / pr->uc_mm : kNaN;  // the paper's UC is the speeds' mean
        const std::string ours = percent_text(value_at_speed(l.compensation, v));
        h += fmt::format("<td>{}</td>", std::isfinite(paper_comp)
                                            ? fmt::format("{} <span class=\"paper\">({:.0f}%)</span>", ours,
                                                          paper_comp * 100.0)
                                            : ours);
      }
      if (pt != nullptr) {
        if (pr != nullptr && std::isfinite(l.uc_mean_mm())) {
          const double rel = l.uc_mean_mm() / pr->uc_mm - 1.0;
          h += fmt::format("<td class=\"{}\">{:+.0f}%</td>", std::abs(rel) <= 0.25 ? "good" : "bad", rel * 100.0);
        } else {
          h += "<td>n/a</td>";
        }
      }
      h += "</tr>\n";
    }
    h += "</table>\n";
  }
  h += "<p class=\"caption\">Mean distance of the loaded path's tracker points from the unloaded path at the same "
       "speed, in mm; the paper's figures in brackets (grey). UC is the mean over the speeds, as in the paper. "
       "Compensation = 1 - C/UC: ours with UC at the same speed, the paper's with its mean UC. "
       "\"UC vs paper\" is green within 25%.</p>\n";
  return h;
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
  return "<h2 id=\"iso\">ISO 9283 path accuracy and repeatability</h2>\n"
         "<p class=\"caption\">AT<sub>p</sub>: largest distance, over 81 planes normal to the unloaded path, "
         "between the barycentre of the runs' crossing points and the unloaded path; RT<sub>p</sub>: largest "
         "l&#772; + 3 S<sub>l</sub> of the crossing points about their barycentre (ISO 9283:1998, 7.2). The "
         "paper's mean distance beside them.</p>\n"
         "<table>\n<tr><th class=\"l\">setup</th><th>load</th><th>speed (mm/s)</th><th>UC mean (mm)</th>"
         "<th>UC AT<sub>p</sub> (mm)</th><th>C mean (mm)</th><th>C AT<sub>p</sub> (mm)</th>"
         "<th>C RT<sub>p</sub> (mm)</th></tr>\n" +
         rows + "</table>\n";
}

std::string budget_tables(const std::vector<ErrorBudget>& budgets) {
  if (budgets.empty()) {
    return "";
  }
  std::string h =
      "<h2 id=\"budget\">Error budget</h2>\n<p class=\"caption\">Each effect of the simulated cell that the compensators' model "
      "lacks, its size, and the compensated residual when that effect alone is switched off. Its share is "
      "(residual with all effects - residual without it) / residual with all effects; shares need not add up to "
      "100% (effects interact, and tracker noise stays in every run).</p>\n";
  for (const auto& b : budgets) {
    h += fmt::format("<h3>{}, {:g} N, {:g} mm/s: residual {} mm with every effect on{}</h3>\n", esc(b.setup),
                     b.load_N, b.speed_mm_s, mm(b.residual_mm_all),
                     b.uc_mm > 0.0 ? fmt::format(" (UC {} mm)", mm(b.uc_mm)) : "");
    h += "<table>\n<tr><th class=\"l\">effect</th><th class=\"l\">size</th><th>residual without it (mm)</th>"
         "<th>share of the residual</th><th class=\"l\"></th></tr>\n";
    for (const auto& e : b.entries) {
      const double share = e.share_of_residual;
      const double w = std::isfinite(share) ? std::clamp(share, 0.0, 1.0) * 160.0 : 0.0;
      h += fmt::format(
          "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td>"
          "<td class=\"l\"><span class=\"bar\" style=\"width:{:.0f}px\"></span></td></tr>\n",
          esc(e.effect), esc(e.size), mm(e.residual_mm_without_it), percent_text(share), w);
    }
    h += "</table>\n";
  }
  return h;
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  if (!f) {
    throw Error(fmt::format("{}: cannot write the file", path));
  }
  f << text;
  if (!f) {
    throw Error(fmt::format("{}: write failed", path));
  }
}

}  // namespace

std::string html_report(const ReportContent& content) {
  const StudyResult& study = content.study;
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n";
  h += fmt::format("<title>{}</title>\n<style>{}</style>\n</head>\n<body>\n", esc(content.title), kCss);
  h += fmt::format("<h1>{}</h1>\n", esc(content.title));
  std::string sub = "Generated by deflex";
  if (!study.case_name.empty()) {
    sub += fmt::format(" &#183; case {}", esc(study.case_name));
  }
  sub += fmt::format(" &#183; seed {}", study.seed);
  if (study.wall_time_s > 0.0) {
    sub += fmt::format(" &#183; {:.1f} s wall time", study.wall_time_s);
  }
  h += fmt::format("<p class=\"sub\">{}. Reference: the paper's Tables 1 and 2 and Figure 5 "
                   "(offline and online compliance compensation of an ABB IRB6700 on a loaded circle).</p>\n",
                   sub);
  if (!content.setup_paragraphs.empty()) {
    h += "<h2 id=\"setup\">Setup</h2>\n";
    for (const auto& p : content.setup_paragraphs) {
      h += fmt::format("<p>{}</p>\n", esc(p));
    }
  }
  if (!content.case_text.empty()) {
    h += fmt::format("<details><summary>Case file</summary>\n<pre>{}</pre>\n</details>\n", esc(content.case_text));
  }
  h += "<h2 id=\"results\">Results beside the paper</h2>\n";
  h += results_tables(study);
  h += "<h2 id=\"figure5\">Figure 5: mean deformation after compensation</h2>\n";
  h += "<div class=\"fig\">\n" + svg_figure5(study) + "</div>\n";
  h += "<p class=\"caption\">Bars: our residual after compensation per load and speed; black markers: the "
       "paper's values; grey labels above each group: the uncompensated deviation (the paper's in brackets).</p>\n";
  h += iso_table(study);
  if (!content.path_plots.empty()) {
    h += "<h2 id=\"paths\">Path plots</h2>\n";
    for (const auto& p : content.path_plots) {
      h += "<div class=\"fig\">\n" + svg_path_plot(p) + "</div>\n";
    }
    h += "<p class=\"caption\">Left: the paths in the plane of best fit of the unloaded path, each loaded point "
         "drawn at its nearest unloaded point plus the magnified deviation. Right: the distance of each loaded "
         "point from the unloaded path at true scale.</p>\n";
  }
  h += budget_tables(study.error_budgets);
  if (!study.speed_sweep.empty()) {
    h += "<h2 id=\"sweep\">Speed sweep</h2>\n<div class=\"fig\">\n" + svg_speed_sweep(study) + "</div>\n";
    h += "<p class=\"caption\">Beyond the paper's 10-50 mm/s (shaded): how each strategy's compensation holds up "
         "as the TCP speed grows and the compensation cycle and delay start to matter.</p>\n";
  }
  if (!content.notes.empty()) {
    h += "<h2 id=\"notes\">Notes</h2>\n";
    for (const auto& n : content.notes) {
      h += fmt::format("<div class=\"note\">{}</div>\n", esc(n));
    }
  }
  h += "<h2 id=\"method\">How the figures are computed</h2>\n<ul>\n"
       "<li>Mean deformation (the paper's figure): for every tracker point of a loaded run, the distance to the "
       "nearest point of the unloaded path's polyline at the same speed; the mean over all points of all laps.</li>\n"
       "<li>Compensation = 1 - C/UC.</li>\n"
       "<li>ISO 9283 path accuracy AT<sub>p</sub> and repeatability RT<sub>p</sub>: section 7.2 of the standard, "
       "positions only (see docs/evaluation.md).</li>\n</ul>\n";
  h += "</body>\n</html>\n";
  return h;
}

void write_report(const ReportContent& content, const std::string& out_dir) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) {
    throw Error(fmt::format("{}: cannot create the directory: {}", out_dir, ec.message()));
  }
  const std::filesystem::path dir(out_dir);
  write_text((dir / "report.html").string(), html_report(content));
  write_text((dir / "figure5.svg").string(), svg_figure5(content.study));
  if (!content.study.speed_sweep.empty()) {
    write_text((dir / "speed_sweep.svg").string(), svg_speed_sweep(content.study));
  }
  for (std::size_t i = 0; i < content.path_plots.size(); ++i) {
    write_text((dir / fmt::format("path_{}.svg", i + 1)).string(), svg_path_plot(content.path_plots[i]));
  }
  write_text((dir / "tables.md").string(), study_tables_markdown(content.study));
  write_study_csv(content.study, (dir / "tables.csv").string());
  if (!content.study.speed_sweep.empty()) write_sweep_csv(content.study, (dir / "sweep.csv").string());
  if (!content.study.error_budgets.empty()) write_error_budget_csv(content.study, (dir / "error_budget.csv").string());
  write_text((dir / "results.json").string(), study_to_json(content.study).dump(2) + "\n");
}

}  // namespace deflex
