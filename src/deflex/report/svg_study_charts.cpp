// SVG charts of a whole study: Figure 5, compensation per load, the parity plot and the speed sweep.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/report/detail/svg_canvas.hpp"
#include "deflex/report/detail/svg_chart_parts.hpp"
#include "deflex/report/svg_charts.hpp"

namespace deflex {
namespace {

using svg::Canvas;
using svg::kMinFont;
using svg::Scale;

bool selected(const SetupResult& setup, SetupSelection which) {
  switch (which) {
    case SetupSelection::kPaper:
      return paper_has_setup(setup);
    case SetupSelection::kBeyondPaper:
      return !paper_has_setup(setup);
    case SetupSelection::kAll:
      return true;
  }
  return true;
}

std::string whisker_note(const StudyResult& study) {
  const std::size_t n = study.seed_count();
  return n > 1 ? fmt::format("whiskers: min to max over {} seeds", n) : "one seed: no whiskers";
}

// A bar from the baseline up to `value` (nothing for NaN), with attributes a reader (or a test) can
// check the drawing against.
void value_bar(Canvas& c, const Scale& y, double x, double w, double value, const std::string& fill,
               const std::string& attrs) {
  if (!std::isfinite(value)) {
    return;
  }
  // From zero (or the axis end nearest it), up or down to the value.
  const double base = y(std::clamp(0.0, y.d0, y.d1)), end = y(std::clamp(value, y.d0, y.d1));
  c.rect(x, std::min(base, end), w, std::abs(base - end), fill, attrs);
}

// The paper's value as an outlined bar.
void paper_bar(Canvas& c, const Scale& y, double x, double w, double value) {
  if (!std::isfinite(value)) {
    return;
  }
  const double base = y(std::clamp(0.0, y.d0, y.d1)), end = y(std::clamp(value, y.d0, y.d1));
  c.rect(x, std::min(base, end), w, std::abs(base - end), "white",
         fmt::format(R"(stroke="{}" stroke-width="1.3" data-paper="{:.6g}")", svg::kPaperColour, value));
}

void spread_whisker(Canvas& c, const Scale& y, double x, const Spread& s) {
  if (s.n > 1 && std::isfinite(s.min) && std::isfinite(s.max)) {
    svg::whisker(c, x, y(std::max(s.min, y.d0)), y(std::min(s.max, y.d1)), "#333", 6.0);
  }
}

std::string spread_text(const Spread& s, double scale, const char* unit, int decimals) {
  if (!std::isfinite(s.mean)) {
    return "n/a";
  }
  std::string t = fmt::format("{:.{}f}{}", s.mean * scale, decimals, unit);
  if (s.n > 1) {
    t += fmt::format(" (seeds {:.{}f} to {:.{}f})", s.min * scale, decimals, s.max * scale, decimals);
  }
  return t;
}

struct Group {
  std::size_t setup;
  const LoadResult* load;
  const PaperRow* paper;
};

std::vector<Group> groups_of(const StudyResult& study, SetupSelection which, const PaperFigures& paper) {
  std::vector<Group> groups;
  for (std::size_t si = 0; si < study.setups.size(); ++si) {
    if (!selected(study.setups[si], which)) {
      continue;
    }
    const PaperTable* pt = paper_table_of(paper, study.setups[si]);
    for (const auto& l : study.setups[si].loads) {
      groups.push_back({si, &l, pt != nullptr ? pt->row_for(l.load_N) : nullptr});
    }
  }
  return groups;
}

// Load labels under the groups, setup names under those and dashed separators between setups.
void group_labels(Canvas& c, const StudyResult& study, const std::vector<Group>& groups, double left, double group_w,
                  double sep_top, double labels_y) {
  std::size_t setup_start = 0;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const double xc = left + group_w * (static_cast<double>(g) + 0.5);
    c.text(xc, labels_y, fmt::format("{:g} N", groups[g].load->load_N), 12.0, "middle");
    const bool last_of_setup = g + 1 == groups.size() || groups[g + 1].setup != groups[g].setup;
    if (last_of_setup) {
      const double x_first = left + group_w * static_cast<double>(setup_start);
      const double x_last = left + group_w * static_cast<double>(g + 1);
      const SetupResult& setup = study.setups[groups[g].setup];
      c.text((x_first + x_last) / 2.0, labels_y + 20.0, svg::short_setup_name(setup.setup), 13.0, "middle",
             R"(font-weight="bold")");
      // A setup compared with a paper table of another name says so under its name (two lines when
      // one is wider than its groups).
      if (!setup.paper_label.empty()) {
        const double span = x_last - x_first;
        const auto cut = setup.paper_label.find(" (");
        if (svg::text_width(setup.paper_label, kMinFont) <= span - 6.0 || cut == std::string::npos) {
          c.text((x_first + x_last) / 2.0, labels_y + 35.0, setup.paper_label, kMinFont, "middle",
                 R"(class="paper-label" fill="#444")");
        } else {
          c.text((x_first + x_last) / 2.0, labels_y + 35.0, setup.paper_label.substr(0, cut), kMinFont, "middle",
                 R"(class="paper-label" fill="#444")");
          c.text((x_first + x_last) / 2.0, labels_y + 48.0, setup.paper_label.substr(cut + 1), kMinFont, "middle",
                 R"(class="paper-label" fill="#444")");
        }
      }
      if (g + 1 != groups.size()) {
        c.line(x_last, sep_top, x_last, labels_y + 26.0, "#999", 1.0, R"(stroke-dasharray="4 4")");
      }
      setup_start = g + 1;
    }
  }
}

}  // namespace

bool paper_has_setup(const std::string& setup) { return paper_reference().table_for(setup) != nullptr; }

bool paper_has_setup(const SetupResult& setup) { return paper_table_of(paper_reference(), setup) != nullptr; }

namespace {

// Every setup's C and UC figures (ours and the paper's), so the figure of the paper's setups and the
// one of the others share their scales and can be compared bar for bar.
void fig5_values(const StudyResult& study, const PaperFigures& paper, const std::vector<int>& speeds,
                 std::vector<double>& c_values, std::vector<double>& uc_values) {
  for (const auto& g : groups_of(study, SetupSelection::kAll, paper)) {
    for (const int v : speeds) {
      const Spread s = g.load->c_spread(v);
      c_values.insert(c_values.end(), {s.mean, s.max});
      if (g.paper != nullptr) {
        c_values.push_back(value_at_speed(g.paper->c_mm, v));
      }
    }
    const Spread u = g.load->uc_mean_spread();
    uc_values.insert(uc_values.end(), {u.mean, u.max});
    if (g.paper != nullptr) {
      uc_values.push_back(g.paper->uc_mm);
    }
  }
}

// The legend, two rows: a colour a speed (and the paper's if shown), then UC and the whisker note.
void fig5_legend(Canvas& c, const StudyResult& study, const std::vector<int>& speeds, const std::vector<Group>& groups,
                 double left) {
  const bool any_paper = std::any_of(groups.begin(), groups.end(), [](const Group& g) { return g.paper != nullptr; });
  double lx = left;
  for (std::size_t k = 0; k < speeds.size(); ++k) {
    lx = svg::legend_entry(c, lx, 50.0, "bar", svg::colour(k), fmt::format("C at {} mm/s", speeds[k]));
  }
  if (any_paper) {
    svg::legend_entry(c, lx, 50.0, "hollow", svg::kPaperColour, "the paper's (Tables 1, 2)");
  }
  lx = svg::legend_entry(c, left, 72.0, "bar", svg::pale(svg::kUcColour), "UC, uncompensated: mean over the speeds");
  c.text(lx, 72.0, whisker_note(study), 12.0, "start", R"(fill="#444")");
}

// C of one load at each speed: our bar with its whisker, the paper's beside it.
void fig5_c_bars(Canvas& c, const std::string& setup, const Group& group, const std::vector<int>& speeds,
                 const Scale& yc, double xc, double slot_w) {
  const LoadResult& l = *group.load;
  const bool with_paper = group.paper != nullptr;
  const double n_speeds = static_cast<double>(speeds.size());
  const double ours_w = with_paper ? slot_w * 0.56 : slot_w * 0.8;
  const double paper_w = slot_w * 0.3;
  for (std::size_t k = 0; k < speeds.size(); ++k) {
    const double x0 = xc + (static_cast<double>(k) - n_speeds / 2.0) * slot_w + slot_w * 0.05;
    const Spread s = l.c_spread(speeds[k]);
    const double pv = with_paper ? value_at_speed(group.paper->c_mm, speeds[k]) : kNaN;
    c.group_begin(fmt::format("{} {:g} N, C at {} mm/s: {}{}", setup, l.load_N, speeds[k],
                              spread_text(s, 1.0, " mm", 3),
                              std::isfinite(pv) ? fmt::format("; the paper's {:.2f} mm", pv) : ""));
    value_bar(c, yc, x0, ours_w, s.mean, svg::colour(k),
              fmt::format(R"(data-value="{:.6g}" data-min="{:.6g}" data-max="{:.6g}")", s.mean, s.min, s.max));
    spread_whisker(c, yc, x0 + ours_w / 2.0, s);
    if (with_paper) {
      paper_bar(c, yc, x0 + ours_w + 1.5, paper_w, pv);
    }
    c.group_end();
  }
}

// UC of one load: one pale bar (the paper's UC is the mean over the speeds), the paper's beside it.
void fig5_uc_bar(Canvas& c, const std::string& setup, const Group& group, const Scale& yu, double xc, double group_w) {
  const LoadResult& l = *group.load;
  const bool with_paper = group.paper != nullptr;
  const Spread u = l.uc_mean_spread();
  const double uc_w = std::min(48.0, group_w * 0.34);
  const double uc_paper_w = uc_w * 0.55;
  const double x0 = xc - (with_paper ? (uc_w + 1.5 + uc_paper_w) : uc_w) / 2.0;
  c.group_begin(fmt::format("{} {:g} N, UC (mean over the speeds): {}{}", setup, l.load_N,
                            spread_text(u, 1.0, " mm", 3),
                            with_paper ? fmt::format("; the paper's {:.2f} mm", group.paper->uc_mm) : ""));
  value_bar(c, yu, x0, uc_w, u.mean, svg::pale(svg::kUcColour),
            fmt::format(R"(data-uc="{:.6g}" data-min="{:.6g}" data-max="{:.6g}")", u.mean, u.min, u.max));
  spread_whisker(c, yu, x0 + uc_w / 2.0, u);
  if (with_paper) {
    paper_bar(c, yu, x0 + uc_w + 1.5, uc_paper_w, group.paper->uc_mm);
  }
  c.group_end();
}

}  // namespace

std::string svg_figure5(const StudyResult& study, SetupSelection which) {
  const std::vector<int> speeds = study_speeds_mm_s(study);
  const PaperFigures paper = paper_reference();
  const std::vector<Group> groups = groups_of(study, which, paper);
  const double width = svg::kMaxWidth, height = 668.0;
  const double left = 84.0, right = 16.0;
  Canvas c(width, height);
  c.title(which == SetupSelection::kBeyondPaper
              ? "Mean deformation after compensation: the setups beyond the paper"
              : "Mean deformation after compensation (the paper's Figure 5, ours beside the paper's)");
  if (groups.empty() || speeds.empty()) {
    c.text(width / 2.0, height / 2.0, "no results to plot", 14.0, "middle");
    return c.str();
  }
  std::vector<double> c_values, uc_values;
  fig5_values(study, paper, speeds, c_values, uc_values);
  const double c_top = 96.0, c_bottom = 386.0, uc_top = 420.0, uc_bottom = 548.0;
  const svg::Range cr = svg::fitted_range(c_values, true, 0.05);
  const svg::Range ur = svg::fitted_range(uc_values, true, 0.05);
  const Scale yc{cr.lo, cr.hi, c_bottom, c_top};
  const Scale yu{ur.lo, ur.hi, uc_bottom, uc_top};
  svg::value_axis(c, yc, left, width - right, "C, after compensation (mm)", 1.0, 56.0);
  svg::value_axis(c, yu, left, width - right, "UC, before (mm)", 1.0, 56.0);
  fig5_legend(c, study, speeds, groups, left);

  const double plot_w = width - left - right;
  const double group_w = plot_w / static_cast<double>(groups.size());
  const double slot_w = std::min(64.0, group_w * 0.86 / static_cast<double>(speeds.size()));
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const double xc = left + group_w * (static_cast<double>(g) + 0.5);
    const std::string& setup = study.setups[groups[g].setup].setup;
    fig5_c_bars(c, setup, groups[g], speeds, yc, xc, slot_w);
    fig5_uc_bar(c, setup, groups[g], yu, xc, group_w);
  }
  c.line(left, yc(yc.d0), width - right, yc(yc.d0), "#444", 1.0);
  c.line(left, yu(yu.d0), width - right, yu(yu.d0), "#444", 1.0);
  group_labels(c, study, groups, left, group_w, c_top, uc_bottom + 20.0);
  c.text(left + plot_w / 2.0, height - 14.0,
         "load |F| (N), per strategy setup; mean distance from the unloaded laps' mean path (mm)", 12.0, "middle");
  return c.str();
}

std::string svg_compensation(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  const std::vector<Group> groups = groups_of(study, SetupSelection::kAll, paper);
  const double width = svg::kMaxWidth, height = 430.0;
  const double left = 84.0, right = 16.0, top = 82.0, bottom = 330.0;
  Canvas c(width, height);
  c.title("Compensation 1 - C/UC per load (the figure the paper quotes)");
  if (groups.empty()) {
    c.text(width / 2.0, height / 2.0, "no results to plot", 14.0, "middle");
    return c.str();
  }
  const std::vector<int> speeds = study_speeds_mm_s(study);
  std::vector<double> values{0.0, 1.0};
  bool any_paper = false;
  for (const auto& g : groups) {
    const Spread s = printed_compensation_spread(*g.load, speeds);
    values.insert(values.end(), {s.mean, s.min});
    any_paper = any_paper || g.paper != nullptr;
  }
  double min_value = 0.0;
  for (const double v : values) {
    if (std::isfinite(v)) {
      min_value = std::min(min_value, v);
    }
  }
  const double lo = std::floor(min_value * 10.0) / 10.0;
  const Scale y{lo, 1.0, bottom, top};
  svg::value_axis(c, y, left, width - right, "compensation 1 - C/UC (%)", 100.0, 50.0);
  double lx = left;
  lx = svg::legend_entry(c, lx, 52.0, "bar", svg::colour(0), "ours, mean over the speeds (colour: setup)");
  if (any_paper) {
    lx = svg::legend_entry(c, lx, 52.0, "hollow", svg::kPaperColour, "the paper's");
  }
  c.text(lx, 52.0, whisker_note(study), 12.0, "start", R"(fill="#444")");
  const double plot_w = width - left - right;
  const double group_w = plot_w / static_cast<double>(groups.size());
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const double xc = left + group_w * (static_cast<double>(g) + 0.5);
    const LoadResult& l = *groups[g].load;
    const bool with_paper = groups[g].paper != nullptr;
    const double ours_w = std::min(30.0, group_w * (with_paper ? 0.4 : 0.5));
    const double paper_w = ours_w * 0.6;
    const double x0 = xc - (with_paper ? ours_w + 1.5 + paper_w : ours_w) / 2.0;
    // As the tables print it: from the printed figures, 1 - mean C / UC, the paper's own way.
    const Spread s = printed_compensation_spread(l, speeds);
    const double pc = with_paper ? groups[g].paper->mean_compensation() : kNaN;
    const std::string& setup = study.setups[groups[g].setup].setup;
    c.group_begin(fmt::format("{} {:g} N: compensation {}{}", setup, l.load_N, spread_text(s, 100.0, "%", 0),
                              std::isfinite(pc) ? fmt::format("; the paper's {}", percent_text(pc)) : ""));
    value_bar(c, y, x0, ours_w, s.mean, svg::colour(groups[g].setup),
              fmt::format(R"(data-value="{:.6g}" data-min="{:.6g}" data-max="{:.6g}")", s.mean, s.min, s.max));
    spread_whisker(c, y, x0 + ours_w / 2.0, s);
    if (with_paper) {
      paper_bar(c, y, x0 + ours_w + 1.5, paper_w, pc);
    }
    if (std::isfinite(s.mean)) {
      const double label_at = std::isfinite(s.max) && s.n > 1 ? std::max(s.max, s.mean) : s.mean;
      c.text(x0 + ours_w / 2.0, y(label_at) - 5.0, percent_text(s.mean), kMinFont, "middle");
    }
    c.group_end();
  }
  c.line(left, y(0.0), width - right, y(0.0), "#444", 1.0);
  group_labels(c, study, groups, left, group_w, top, bottom + 20.0);
  c.text(left + plot_w / 2.0, height - 12.0,
         "load |F| (N), per strategy setup; 1 - (mean C over the speeds) / UC, from the tables' printed figures", 12.0,
         "middle");
  return c.str();
}

namespace {

// "Table 2" from the paper table's caption ("Table 2. Online compensation ...").
std::string table_name(const PaperTable& t) { return t.caption.substr(0, t.caption.find('.')); }

// One panel of the trends figure: C/UC against load for the setups compared with one paper table,
// ours (solid, whiskers over the seeds) and the paper's (dashed, hollow), with compensation on the
// right axis.
void trend_panel(Canvas& c, const StudyResult& study, const PaperTable& table, double left, double right,
                 const Scale& y) {
  const PaperFigures paper = paper_reference();
  const std::vector<int> speeds = study_speeds_mm_s(study);
  const double lo = table.rows.front().load_N, hi = table.rows.back().load_N;
  const double pad = hi > lo ? 0.08 * (hi - lo) : 50.0;
  const Scale x{lo - pad, hi + pad, left, right};
  svg::value_axis(c, y, left, right, "C/UC (C: mean over the speeds)", 1.0, 46.0);
  for (const double t : svg::nice_ticks(y.d0, y.d1, 6)) {
    c.text(right + 6.0, y(t) + 4.0, fmt::format("{:.0f}%", 100.0 * (1.0 - t)), kMinFont);
  }
  c.text(right + 4.0, y.p1 - 8.0, "compensation", kMinFont);
  svg::position_axis(c, x, y.p0, "load |F| (N)");
  c.text((left + right) / 2.0, y.p1 - 22.0, table_name(table) + ": " + table.setup, 13.0, "middle");
  std::vector<double> theirs;
  for (const auto& r : table.rows) theirs.insert(theirs.end(), {x(r.load_N), y(1.0 - r.mean_compensation())});
  c.group_begin(table_name(table) + " of the paper: C/UC per load");
  c.polyline(theirs, svg::kPaperColour, 1.8, R"(stroke-dasharray="6 4")");
  for (std::size_t i = 0; i + 1 < theirs.size(); i += 2) {
    const PaperRow& r = table.rows[i / 2];
    c.circle(theirs[i], theirs[i + 1], 4.5, "white",
             fmt::format(R"(stroke="{}" stroke-width="1.6" data-load="{:g}" data-paper="{:.6g}")", svg::kPaperColour,
                         r.load_N, 1.0 - r.mean_compensation()));
  }
  c.group_end();
  for (std::size_t k = 0; k < study.setups.size(); ++k) {
    const SetupResult& s = study.setups[k];
    if (paper_table_of(paper, s) == nullptr || paper_table_of(paper, s)->caption != table.caption) continue;
    std::vector<double> ours;
    c.group_begin(s.setup + ": C/UC per load, ours");
    for (const auto& l : s.loads) {
      const Spread sp = printed_compensation_spread(l, speeds);
      if (!std::isfinite(sp.mean)) continue;
      ours.insert(ours.end(), {x(l.load_N), y(1.0 - sp.mean)});
      if (sp.n > 1) svg::whisker(c, x(l.load_N), y(1.0 - sp.max), y(1.0 - sp.min), svg::colour(k), 5.0);
      c.circle(x(l.load_N), y(1.0 - sp.mean), 4.0, svg::colour(k),
               fmt::format(R"(data-load="{:g}" data-value="{:.6g}")", l.load_N, 1.0 - sp.mean));
    }
    c.polyline(ours, svg::colour(k), 2.0);
    c.group_end();
  }
}

}  // namespace

std::string svg_trends(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  const double width = svg::kMaxWidth, height = 425.0, top = 110.0, bottom = 370.0;
  Canvas c(width, height);
  c.title("Trends against load: C/UC and compensation, ours beside the paper's");
  std::vector<const PaperTable*> tables;
  double y_hi = 0.4;
  for (const auto& s : study.setups) {
    const PaperTable* pt = paper_table_of(paper, s);
    if (pt == nullptr || pt->rows.empty()) continue;
    if (std::find(tables.begin(), tables.end(), pt) == tables.end()) tables.push_back(pt);
    for (const auto& l : s.loads) {
      const Spread sp = printed_compensation_spread(l, study_speeds_mm_s(study));
      if (std::isfinite(sp.min)) y_hi = std::max(y_hi, 1.0 - sp.min);
    }
  }
  if (tables.empty()) {
    c.text(width / 2.0, height / 2.0, "no setup the paper ran", 14.0, "middle");
    return c.str();
  }
  const Scale y{0.0, svg::nice_ceiling(y_hi * 1.05), bottom, top};
  double lx = 84.0;
  for (std::size_t k = 0; k < study.setups.size(); ++k) {
    if (paper_table_of(paper, study.setups[k]) == nullptr) continue;
    lx = svg::legend_entry(c, lx, 52.0, "line", svg::colour(k), "ours: " + study.setups[k].setup);
  }
  lx = svg::legend_entry(c, lx, 52.0, "dash", svg::kPaperColour, "the paper's");
  c.text(84.0, 72.0, whisker_note(study), 12.0, "start", R"(fill="#444")");
  const double panel_w = (width - 20.0) / static_cast<double>(tables.size());
  for (std::size_t i = 0; i < tables.size(); ++i) {
    const double left = 10.0 + panel_w * static_cast<double>(i) + 64.0;
    trend_panel(c, study, *tables[i], left, left + panel_w - 150.0, y);
  }
  return c.str();
}

namespace {

/// One figure of the paper's tables beside ours, for the parity plot.
struct ParityPoint {
  std::string setup;
  std::size_t setup_index;
  double load_N;
  int speed;  // 0 for UC
  double paper;
  Spread ours;
  std::string label;  // the setup's paper_label: how it is compared with a table of another name
  std::string table;  // then the paper's table it is compared with ("Table 2")
};

/// Every load of the study the paper's tables have: UC, then C at each of the paper's speeds.
std::vector<ParityPoint> parity_points(const StudyResult& study, const PaperFigures& paper) {
  std::vector<ParityPoint> points;
  for (std::size_t si = 0; si < study.setups.size(); ++si) {
    const SetupResult& setup = study.setups[si];
    const PaperTable* pt = paper_table_of(paper, setup);
    if (pt == nullptr) {
      continue;
    }
    for (const auto& l : setup.loads) {
      const PaperRow* pr = pt->row_for(l.load_N);
      if (pr == nullptr) {
        continue;
      }
      const std::string table = setup.paper_table.empty() ? std::string() : table_name(*pt);
      points.push_back({setup.setup, si, l.load_N, 0, pr->uc_mm, l.uc_mean_spread(), setup.paper_label, table});
      for (const auto& [v, pc] : pr->c_mm) {
        points.push_back({setup.setup, si, l.load_N, v, pc, l.c_spread(v), setup.paper_label, table});
      }
    }
  }
  return points;
}

/// The parity plot's square (left, top and side, px) and its data range, log scaled alike on both axes.
struct ParityFrame {
  double pl, pt, ps;
  double d0, d1;
  svg::LogScale xs, ys;
};

/// The frame at (pl, pt) of side ps for positive values from `lo` to `hi`.
ParityFrame parity_frame(double lo, double hi, double pl, double pt, double ps) {
  // Ends on 1, 2 or 5 x 10^k with a margin, so every tick is labelled and no point sits on the frame.
  const double d0 = svg::nice_floor(lo / 1.2);
  double d1 = d0;
  while (d1 < hi * 1.2) {
    d1 = svg::nice_floor(d1 * 2.6);  // 1 -> 2 -> 5 -> 10
  }
  return {pl, pt, ps, d0, d1, svg::LogScale{d0, d1, pl, pl + ps}, svg::LogScale{d0, d1, pt + ps, pt}};
}

/// The grid, the ticks, the frame and the axis titles.
void parity_axes(Canvas& c, const ParityFrame& f) {
  const double pl = f.pl, pt = f.pt, ps = f.ps;
  for (const double t : svg::log_ticks(f.d0, f.d1)) {
    const std::string label = fmt::format("{:g}", t);
    c.line(f.xs(t), pt, f.xs(t), pt + ps, "#e3e3e3", 1.0);
    c.line(pl, f.ys(t), pl + ps, f.ys(t), "#e3e3e3", 1.0);
    c.text(f.xs(t), pt + ps + 18.0, label, kMinFont, "middle", R"(class="x-tick")");
    c.text(pl - 6.0, f.ys(t) + 4.0, label, kMinFont, "end", R"(class="y-tick")");
  }
  c.rect(pl, pt, ps, ps, "none", R"(stroke="#444")");
  c.text(pl + ps / 2.0, pt + ps + 38.0, "the paper's mean distance (mm, log scale)", 12.0, "middle");
  const double ymid = pt + ps / 2.0;
  c.text(pl - 50.0, ymid, "ours, mean over the seeds (mm, log scale)", 12.0, "middle",
         fmt::format(R"svg(transform="rotate(-90 {:.2f} {:.2f})")svg", pl - 50.0, ymid));
}

/// The bands, clipped to the plot: C's target shaded, UC's dashed, y = x solid.
void parity_bands(Canvas& c, const ParityFrame& f) {
  const svg::LogScale& xs = f.xs;
  const svg::LogScale& ys = f.ys;
  c.raw(fmt::format(
      R"(<clipPath id="deflex-parity-area"><rect x="{:.2f}" y="{:.2f}" width="{:.2f}" height="{:.2f}"/></clipPath>)"
      "\n<g clip-path=\"url(#deflex-parity-area)\">\n",
      f.pl, f.pt, f.ps, f.ps));
  const double e0 = f.d0 / 2.0, e1 = f.d1 * 2.0;  // beyond the plot, clipped
  const double lo = 1.0 - kCTarget, hi = 1.0 + kCTarget;
  c.polygon({xs(e0), ys(e0 * lo), xs(e1), ys(e1 * lo), xs(e1), ys(e1 * hi), xs(e0), ys(e0 * hi)}, "#dcefd8");
  for (const double k : {1.0 - kUcTarget, 1.0 + kUcTarget}) {
    c.line(xs(e0), ys(e0 * k), xs(e1), ys(e1 * k), "#2e7d32", 1.2, R"(stroke-dasharray="5 4")");
  }
  c.line(xs(e0), ys(e0), xs(e1), ys(e1), "#444", 1.3);
  c.raw("</g>\n");
}

/// How many of the C and the UC points were drawn, and how many of each are within their target.
struct ParityCounts {
  int c_in = 0, c_n = 0, uc_in = 0, uc_n = 0;
};

/// A marker for each point with both values positive (C a dot, UC a square), with its seeds' whisker.
ParityCounts parity_markers(Canvas& c, const ParityFrame& f, const std::vector<ParityPoint>& points) {
  ParityCounts n;
  for (const auto& p : points) {
    if (!std::isfinite(p.ours.mean) || !(p.ours.mean > 0.0) || !(p.paper > 0.0)) {
      continue;
    }
    // From the figure as printed beside it (3 decimals), so the tooltip's percentage is the reader's.
    const double ratio = as_printed(p.ours.mean) / p.paper;
    const std::string col = svg::colour(p.setup_index);
    const double x = f.xs(p.paper), yv = f.ys(p.ours.mean);
    const std::string what = p.speed == 0 ? "UC" : fmt::format("C at {} mm/s", p.speed);
    c.group_begin(fmt::format("{}{} {:g} N, {}: ours {} against the paper's {:.2f} mm ({})", p.setup,
                              p.label.empty() ? "" : " (" + p.label + ")", p.load_N, what,
                              spread_text(p.ours, 1.0, " mm", 3), p.paper, signed_percent_text(ratio - 1.0)));
    if (p.ours.n > 1 && std::isfinite(p.ours.min) && p.ours.min > 0.0) {
      svg::whisker(c, x, f.ys(p.ours.min), f.ys(p.ours.max), col, 5.0);
    }
    const std::string data = fmt::format(R"(data-paper="{:.6g}" data-ours="{:.6g}")", p.paper, p.ours.mean);
    if (p.speed == 0) {
      c.rect(x - 5.0, yv - 5.0, 10.0, 10.0, "white", fmt::format(R"(stroke="{}" stroke-width="2" {})", col, data));
      ++n.uc_n;
      n.uc_in += std::abs(ratio - 1.0) <= kUcTarget ? 1 : 0;
    } else {
      c.circle(x, yv, 4.5, col, fmt::format(R"(stroke="white" stroke-width="0.8" {})", data));
      ++n.c_n;
      n.c_in += std::abs(ratio - 1.0) <= kCTarget ? 1 : 0;
    }
    c.group_end();
  }
  return n;
}

/// The legend (the setups' colours, the markers, the lines and bands) from (rx, ry) down; ry ends below it.
void parity_legend(Canvas& c, const StudyResult& study, const std::vector<ParityPoint>& points, double rx, double& ry) {
  std::map<std::size_t, const ParityPoint*> setups;
  for (const auto& p : points) {
    setups.emplace(p.setup_index, &p);
  }
  for (const auto& [si, p] : setups) {
    svg::legend_entry(
        c, rx, ry, "dot", svg::colour(si),
        svg::short_setup_name(p->setup) + (p->table.empty() ? "" : fmt::format(": against the paper's {}", p->table)));
    if (!p->label.empty()) {
      ry += 16.0;
      c.text(rx + 24.0, ry, p->label, 12.0, "start", R"(class="paper-label" fill="#444")");
    }
    ry += 20.0;
  }
  c.circle(rx + 8.0, ry - 4.0, 4.5, "#666");
  c.text(rx + 24.0, ry, "C at one load and speed", 12.0);
  ry += 20.0;
  c.rect(rx + 3.0, ry - 9.0, 10.0, 10.0, "white", R"(stroke="#666" stroke-width="2")");
  c.text(rx + 24.0, ry, "UC at one load (mean over the speeds)", 12.0);
  ry += 20.0;
  svg::legend_entry(c, rx, ry, "line", "#444", "y = x: ours equal to the paper's");
  ry += 20.0;
  svg::legend_entry(c, rx, ry, "band", "#dcefd8",
                    fmt::format("within {} of the paper's (the target for C)", percent_text(kCTarget)));
  ry += 20.0;
  svg::legend_entry(c, rx, ry, "dash", "#2e7d32",
                    fmt::format("{} either side (the target for UC)", percent_text(kUcTarget)));
  ry += 20.0;
  c.text(rx, ry, whisker_note(study), 12.0, "start", R"(fill="#444")");
}

/// The counts against the targets and, per setup and load, ours over the paper's (C as the mean over
/// the speeds, and UC) from (rx, ry) down, as many loads as fit above the chart's `height`.
void parity_summary(Canvas& c, const StudyResult& study, const PaperFigures& paper, const ParityCounts& n, double rx,
                    double ry, double height) {
  c.text(rx, ry, "Against the targets", 13.0, "start", R"(font-weight="bold")");
  ry += 20.0;
  c.text(rx, ry, fmt::format("C per load and speed within {}: {} of {}", percent_text(kCTarget), n.c_in, n.c_n), 12.0);
  ry += 18.0;
  c.text(rx, ry, fmt::format("UC per load within {}: {} of {}", percent_text(kUcTarget), n.uc_in, n.uc_n), 12.0);
  ry += 24.0;
  // Per setup and load: C as the issue judges it (mean over the speeds), and UC.
  c.text(rx, ry, "ours / the paper's, per load:", 12.0, "start", R"(fill="#444")");
  ry += 18.0;
  for (std::size_t si = 0; si < study.setups.size(); ++si) {
    const PaperTable* table = paper_table_of(paper, study.setups[si]);
    if (table == nullptr) {
      continue;
    }
    for (const auto& l : study.setups[si].loads) {
      const PaperRow* pr = table->row_for(l.load_N);
      if (pr == nullptr || ry > height - 10.0) {
        continue;
      }
      // The tables' "vs paper" figures: from our printed figures.
      const double c_ratio = c_over_paper(l, *pr);
      const double uc_ratio = uc_over_paper(l, *pr);
      const bool c_ok = std::abs(c_ratio - 1.0) <= kCTarget, uc_ok = std::abs(uc_ratio - 1.0) <= kUcTarget;
      c.text(rx, ry,
             fmt::format("{} {:g} N: C \u00d7{:.2f} {}, UC \u00d7{:.2f} {}", study.setups[si].setup, l.load_N, c_ratio,
                         c_ok ? "(in)" : "(out)", uc_ratio, uc_ok ? "(in)" : "(out)"),
             12.0, "start", c_ok && uc_ok ? R"(fill="#2e7d32")" : R"(fill="#c62828")");
      ry += 18.0;
    }
  }
}

}  // namespace

std::string svg_parity(const StudyResult& study) {
  const PaperFigures paper = paper_reference();
  const std::vector<ParityPoint> points = parity_points(study, paper);
  const double width = svg::kMaxWidth, height = 600.0;
  const double pl = 96.0, pt = 70.0, ps = 430.0;
  Canvas c(width, height);
  c.title("Parity: ours against the paper's Tables 1 and 2");
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const auto& p : points) {
    for (const double v : {p.paper, p.ours.mean, p.ours.min, p.ours.max}) {
      if (std::isfinite(v) && v > 0.0) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    }
  }
  if (!(hi > 0.0)) {
    c.text(width / 2.0, height / 2.0, "no figure of the paper's to compare with", 14.0, "middle");
    return c.str();
  }
  const ParityFrame frame = parity_frame(lo, hi, pl, pt, ps);
  parity_axes(c, frame);
  parity_bands(c, frame);
  const ParityCounts counts = parity_markers(c, frame, points);
  // Legend and a summary at the right.
  const double rx = pl + ps + 50.0;
  double ry = pt + 10.0;
  parity_legend(c, study, points, rx, ry);
  parity_summary(c, study, paper, counts, rx, ry + 34.0, height);
  return c.str();
}

namespace {

// One series of the speed sweep: a setup under one load, its points in order of speed.
struct SweepSeries {
  std::string setup;
  double load_N;
  std::vector<const SweepPoint*> points;
};

// One series per setup and load, in order of first appearance; `max_speed` gets the fastest point.
std::vector<SweepSeries> sweep_series(const StudyResult& study, double& max_speed) {
  std::vector<SweepSeries> series;
  max_speed = 0.0;
  for (const auto& p : study.speed_sweep) {
    auto it = std::find_if(series.begin(), series.end(),
                           [&](const SweepSeries& s) { return s.setup == p.setup && s.load_N == p.load_N; });
    if (it == series.end()) {
      series.push_back({p.setup, p.load_N, {}});
      it = series.end() - 1;
    }
    it->points.push_back(&p);
    if (std::isfinite(p.speed_mm_s)) {
      max_speed = std::max(max_speed, p.speed_mm_s);
    }
  }
  return series;
}

// The four figures of a point, one a panel.
struct SweepQuantity {
  const char* label;
  double scale_to_label;
  bool from_zero;
};
constexpr SweepQuantity kSweepQuantities[] = {{"compensation 1 - C/UC (%)", 100.0, false},
                                              {"C, nearest-point (mm)", 1.0, false},
                                              {"C, time-synchronous (mm)", 1.0, false},
                                              {"UC, nearest-point (mm)", 1.0, false}};

// Quantity `q` of a point: its mean and its seeds' values.
Spread sweep_values(const SweepPoint& p, int q) {
  std::vector<double> seeds;
  double mean = kNaN;
  switch (q) {
    case 0:
      mean = p.compensation;
      for (std::size_t k = 0; k < p.c_mm_by_seed.size() && k < p.uc_mm_by_seed.size(); ++k) {
        seeds.push_back(compensation_ratio(p.uc_mm_by_seed[k], p.c_mm_by_seed[k]));
      }
      break;
    case 1:
      mean = p.c_mm;
      seeds = p.c_mm_by_seed;
      break;
    case 2:
      mean = p.c_sync_mm;
      seeds = p.c_sync_mm_by_seed;
      break;
    default:
      mean = p.uc_mm;
      seeds = p.uc_mm_by_seed;
  }
  Spread s = spread_of(seeds);
  s.mean = mean;
  return s;
}

// How each series is drawn: a colour per setup, a dash per load within its setup.
struct SweepStyle {
  std::vector<std::string> colour;
  std::vector<std::string> dash;
};

SweepStyle sweep_style(const std::vector<SweepSeries>& series) {
  const char* const dashes[] = {"", R"(stroke-dasharray="6 3")", R"(stroke-dasharray="2 3")",
                                R"(stroke-dasharray="8 3 2 3")"};
  std::map<std::string, std::size_t> setup_colour;
  for (const auto& s : series) {
    setup_colour.emplace(s.setup, setup_colour.size());
  }
  std::map<std::string, std::size_t> load_rank;
  SweepStyle style;
  for (const auto& s : series) {
    style.dash.emplace_back(dashes[load_rank[s.setup]++ % 4]);
    style.colour.push_back(svg::colour(setup_colour[s.setup]));
  }
  return style;
}

// The legend, wrapped into rows across the chart; returns the baseline of its last row.
double sweep_legend(Canvas& c, const StudyResult& study, const std::vector<SweepSeries>& series,
                    const SweepStyle& style, double width) {
  double lx = 90.0, ly = 52.0;
  auto next_entry = [&](double w) {
    if (lx + w > width - 16.0) {
      lx = 90.0;
      ly += 20.0;
    }
  };
  for (std::size_t si = 0; si < series.size(); ++si) {
    const std::string label = fmt::format("{} {:g} N", series[si].setup, series[si].load_N);
    next_entry(24.0 + svg::text_width(label, 12.0) + 18.0);
    c.line(lx, ly - 4.0, lx + 18.0, ly - 4.0, style.colour[si], 2.0, style.dash[si]);
    c.circle(lx + 9.0, ly - 4.0, 3.0, style.colour[si]);
    c.text(lx + 24.0, ly, label, 12.0);
    lx += 24.0 + svg::text_width(label, 12.0) + 18.0;
  }
  const std::string band_label = "the paper's speeds, 10-50 mm/s";
  next_entry(24.0 + svg::text_width(band_label, 12.0) + 18.0);
  lx = svg::legend_entry(c, lx, ly, "band", "#ececec", band_label);
  next_entry(svg::text_width(whisker_note(study), 12.0));
  c.text(lx, ly, whisker_note(study), 12.0, "start", R"(fill="#444")");
  return ly;
}

// Quantity `q` of every series against speed: a whisker per point over seeds, the means joined.
void sweep_marks(Canvas& c, const std::vector<SweepSeries>& series, const SweepStyle& style, int q, const Scale& x,
                 const Scale& y) {
  for (std::size_t si = 0; si < series.size(); ++si) {
    const std::string& col = style.colour[si];
    // Side by side, so whiskers at the same speed do not hide each other.
    const double dodge = (static_cast<double>(si) - (static_cast<double>(series.size()) - 1.0) / 2.0) * 3.0;
    std::vector<double> xy;
    for (const auto* p : series[si].points) {
      const Spread s = sweep_values(*p, q);
      if (!std::isfinite(s.mean) || !std::isfinite(p->speed_mm_s)) {
        continue;
      }
      const double px = x(p->speed_mm_s) + dodge;
      if (s.n > 1) {
        svg::whisker(c, px, y(s.min), y(s.max), col, 5.0);
      }
      c.circle(px, y(s.mean), 3.0, col, fmt::format(R"(data-value="{:.6g}")", s.mean));
      xy.push_back(px);
      xy.push_back(y(s.mean));
    }
    if (xy.size() >= 4) {
      c.polyline(xy, col, 2.0, style.dash[si]);
    }
  }
}

// One panel: the paper's speed band, both axes fitted to quantity `q` over the whole sweep, the marks.
void sweep_panel(Canvas& c, const StudyResult& study, const std::vector<SweepSeries>& series, const SweepStyle& style,
                 int q, const Scale& x, double top, double panel_h) {
  std::vector<double> all;
  for (const auto& p : study.speed_sweep) {
    const Spread s = sweep_values(p, q);
    all.insert(all.end(), {s.mean, s.min, s.max});
  }
  svg::Range r = svg::fitted_range(all, kSweepQuantities[q].from_zero, 0.08);
  if (q == 0) {
    r.hi = std::min(r.hi, 1.0);  // compensation cannot pass 100%
  }
  const Scale y{r.lo, r.hi, top + panel_h, top};
  const double band_lo = x(std::min(10.0, x.d1)), band_hi = x(std::min(50.0, x.d1));
  c.rect(band_lo, top, band_hi - band_lo, panel_h, "#ececec");
  svg::value_axis(c, y, x.p0, x.p1, kSweepQuantities[q].label, kSweepQuantities[q].scale_to_label, 50.0);
  svg::position_axis(c, x, top + panel_h, "TCP speed (mm/s)");
  sweep_marks(c, series, style, q, x, y);
}

}  // namespace

std::string svg_speed_sweep(const StudyResult& study) {
  const double width = svg::kMaxWidth, height = 680.0;
  Canvas c(width, height);
  c.title("Speed sweep: compensation, residual and lag against TCP speed");
  if (study.speed_sweep.empty()) {
    c.text(width / 2.0, height / 2.0, "no speed sweep in this study", 14.0, "middle");
    return c.str();
  }
  double max_speed = 0.0;
  const std::vector<SweepSeries> series = sweep_series(study, max_speed);
  const SweepStyle style = sweep_style(series);
  // Legend rows first: the panels start below however many rows it takes.
  const double top0 = sweep_legend(c, study, series, style, width) + 36.0;
  const double panel_h = (height - top0 - 2.0 * 56.0) / 2.0;
  const double xs_left[] = {90.0, 600.0};
  const double panel_w = 400.0;
  const double x_max = svg::nice_ceiling(max_speed);
  for (int q = 0; q < 4; ++q) {
    const double x_left = xs_left[q % 2];
    const int row = q / 2;  // the panel's row
    const double top = top0 + row * (panel_h + 56.0);
    sweep_panel(c, study, series, style, q, Scale{0.0, x_max, x_left, x_left + panel_w}, top, panel_h);
  }
  return c.str();
}

}  // namespace deflex
