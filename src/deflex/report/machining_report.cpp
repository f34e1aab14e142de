// The machining study's HTML report (see machining_report.hpp).
#include "deflex/report/machining_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "deflex/report/detail/svg_canvas.hpp"

namespace deflex {
namespace {

using study::MachiningRun;
using study::MachiningStrategy;

const char* strategy_colour(MachiningStrategy s) {
  switch (s) {
    case MachiningStrategy::kUncompensated:
      return "#c0392b";
    case MachiningStrategy::kOffline:
      return "#2471a3";
    case MachiningStrategy::kOnline:
      return "#1e8449";
    case MachiningStrategy::kHybrid:
      return "#7d3c98";
  }
  return "#000";
}

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '&')
      o += "&amp;";
    else
      o += c;
  }
  return o;
}

struct ChartSeries {
  std::string label, colour;
  std::vector<double> x, y;
  bool dashed = false;
};

// A line chart of several series: x in mm, y in the unit named by `y_label`, a legend on the right.
std::string line_chart(const std::string& title, const std::string& x_label, const std::string& y_label,
                       const std::vector<ChartSeries>& series) {
  constexpr double kW = 1000.0, kH = 300.0, kLeft = 70.0, kRight = 200.0, kTop = 34.0, kBottom = 46.0;
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = 0.0, y1 = 0.0;
  for (const ChartSeries& s : series) {
    for (double v : s.x) x0 = std::min(x0, v), x1 = std::max(x1, v);
    for (double v : s.y) y0 = std::min(y0, v), y1 = std::max(y1, v);
  }
  if (!(x1 > x0)) x0 = 0.0, x1 = 1.0;
  if (!(y1 > y0)) y1 = y0 + 1.0;
  const double pad = 0.05 * (y1 - y0);
  y0 -= pad;
  y1 += pad;
  svg::Canvas c(kW, kH);
  c.title(title);
  const svg::Scale sx{x0, x1, kLeft, kW - kRight}, sy{y0, y1, kH - kBottom, kTop};
  const std::vector<double> xt = svg::nice_ticks(x0, x1), yt = svg::nice_ticks(y0, y1, 5);
  for (double v : yt) {
    c.line(kLeft, sy(v), kW - kRight, sy(v), "#ddd");
    c.text(kLeft - 6, sy(v) + 4, svg::tick_label(v, yt.size() > 1 ? yt[1] - yt[0] : 1.0), 11, "end");
  }
  for (double v : xt)
    c.text(sx(v), kH - kBottom + 16, svg::tick_label(v, xt.size() > 1 ? xt[1] - xt[0] : 1.0), 11, "middle");
  if (y0 < 0.0 && y1 > 0.0) c.line(kLeft, sy(0.0), kW - kRight, sy(0.0), "#888");
  c.line(kLeft, kH - kBottom, kW - kRight, kH - kBottom, "#444");
  c.line(kLeft, kTop, kLeft, kH - kBottom, "#444");
  c.text((kLeft + kW - kRight) / 2, kH - 8, x_label, 12, "middle");
  c.text(14, (kTop + kH - kBottom) / 2, y_label, 12, "middle",
         fmt::format("transform=\"rotate(-90 14 {})\"", (kTop + kH - kBottom) / 2));
  double ly = kTop + 10;
  for (const ChartSeries& s : series) {
    std::vector<double> xy;
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      xy.push_back(sx(s.x[i]));
      xy.push_back(sy(s.y[i]));
    }
    const std::string extra = s.dashed ? "stroke-dasharray=\"6 4\"" : "";
    c.polyline(xy, s.colour, 1.8, extra);
    c.line(kW - kRight + 12, ly, kW - kRight + 36, ly, s.colour, 2.0, extra);
    c.text(kW - kRight + 42, ly + 4, s.label, 11);
    ly += 18;
  }
  return c.str();
}

// Runs of the first seed at one feed, in the strategies' order.
std::vector<const MachiningRun*> first_seed_runs(const study::MachiningStudyOutput& out, double feed) {
  std::vector<const MachiningRun*> r;
  for (const MachiningRun& run : out.runs) {
    if (run.seed_index == 0 && run.feed_mm_min == feed) r.push_back(&run);
  }
  return r;
}

std::string wall_charts(const study::MachiningStudyOutput& out, double feed) {
  const std::vector<const MachiningRun*> runs = first_seed_runs(out, feed);
  if (runs.empty() || runs.front()->walls.empty()) return "";
  std::string html;
  for (std::size_t w = 0; w < runs.front()->walls.size(); ++w) {
    std::vector<ChartSeries> series;
    for (const MachiningRun* r : runs) {
      if (w >= r->walls.size()) continue;
      ChartSeries s{study::to_string(r->strategy), strategy_colour(r->strategy), {}, {}};
      for (std::size_t i = 0; i < r->walls[w].along_m.size(); ++i) {
        s.x.push_back(r->walls[w].along_m[i] * 1e3);
        s.y.push_back(r->walls[w].deviation_m[i] * 1e6);
      }
      series.push_back(std::move(s));
    }
    html += line_chart(fmt::format("{}, {:g} mm/min, seed 1: deviation from the nominal wall (mid-depth row)",
                                   runs.front()->walls[w].name, feed),
                       "along the wall, mm", "deviation, µm (> 0: material left)", series);
  }
  return html;
}

std::string pass_charts(const study::MachiningStudyOutput& out, double feed) {
  const std::vector<const MachiningRun*> runs = first_seed_runs(out, feed);
  std::string html;
  const MachiningRun* offline = nullptr;
  const MachiningRun* uncomp = nullptr;
  for (const MachiningRun* r : runs) {
    if (r->strategy == MachiningStrategy::kOffline) offline = r;
    if (r->strategy == MachiningStrategy::kUncompensated) uncomp = r;
  }
  if (offline == nullptr || uncomp == nullptr) return html;
  for (std::size_t p = 0; p < offline->passes.size(); ++p) {
    const study::PassTrace& t = offline->passes[p];
    std::vector<double> x_mm;
    for (double x : t.x_m) x_mm.push_back(x * 1e3);
    std::vector<ChartSeries> force{{"true (offline run)", "#1e8449", x_mm, t.true_force_n},
                                   {"predicted, fitted coefficients", "#2471a3", x_mm, t.predicted_force_n, true}};
    html += line_chart(fmt::format("{}, {:g} mm/min: the in-plane cutting force", t.name, feed), "tool tip x, mm",
                       "force, N", force);
    std::vector<ChartSeries> defl;
    for (const MachiningRun* r : runs) {
      if (p >= r->passes.size()) continue;
      ChartSeries s{study::to_string(r->strategy), strategy_colour(r->strategy), {}, {}};
      for (std::size_t i = 0; i < r->passes[p].x_m.size(); ++i) {
        s.x.push_back(r->passes[p].x_m[i] * 1e3);
        s.y.push_back(r->passes[p].deflection_m[i] * 1e6);
      }
      defl.push_back(std::move(s));
    }
    html += line_chart(fmt::format("{}, {:g} mm/min: the true tool's distance from the programmed path", t.name, feed),
                       "tool tip x, mm", "distance, µm", defl);
  }
  return html;
}

// The part errors as an HTML table: a row per strategy and feed, mean and spread over the seeds.
std::string error_table(const study::MachiningStudyOutput& out) {
  struct Col {
    const char* head;
    study::Spread study::MachiningRow::*cell;
  };
  const Col cols[] = {{"climb wall", &study::MachiningRow::climb_mean},
                      {"climb P-V", &study::MachiningRow::climb_pv},
                      {"conv. wall", &study::MachiningRow::conventional_mean},
                      {"conv. P-V", &study::MachiningRow::conventional_pv},
                      {"contour wall", &study::MachiningRow::contour_mean},
                      {"contour P-V", &study::MachiningRow::contour_pv},
                      {"pocket floor flatness", &study::MachiningRow::pocket_flatness},
                      {"pocket width", &study::MachiningRow::pocket_width},
                      {"slot width", &study::MachiningRow::slot_width}};
  std::string h = "<table><tr><th>strategy</th><th>feed, mm/min</th>";
  for (const Col& c : cols) h += fmt::format("<th>{}, &micro;m</th>", c.head);
  h += "</tr>\n";
  for (const study::MachiningRow& r : out.rows) {
    h += fmt::format("<tr><td style=\"color:{}\"><b>{}</b></td><td>{:g}</td>", strategy_colour(r.strategy),
                     study::to_string(r.strategy), r.feed_mm_min);
    for (const Col& c : cols) {
      const study::Spread& v = r.*c.cell;
      h += fmt::format("<td>{:+.1f} <small>&plusmn; {:.1f}</small></td>", v.mean * 1e6, v.sd * 1e6);
    }
    h += "</tr>\n";
  }
  return h + "</table>\n";
}

std::string fit_table(const study::MachiningStudyOutput& out) {
  std::string h = "<table><tr><th></th>";
  for (const char* k : kCoefficientKeys) h += fmt::format("<th>{}</th>", k);
  h += "</tr>\n";
  auto row = [&](const std::string& name, const CuttingCoefficients& k) {
    h += "<tr><td>" + escape(name) + "</td>";
    for (int i = 0; i < 6; ++i) h += fmt::format("<td>{:.1f}</td>", coefficient_in_user_units(k, i));
    h += "</tr>\n";
  };
  row("published Al7075-T6", out.published);
  for (const study::MachiningFit& f : out.fits) {
    row(fmt::format("seed {}: fitted from {} slot cuts", f.seed_index + 1, f.fit.cuts), f.fit.k);
    row(fmt::format("seed {}: the cell's truth (runout {:.1f} um)", f.seed_index + 1, f.truth_runout_m * 1e6), f.truth);
  }
  return h + "</table>\n";
}

}  // namespace

std::string machining_report_html(const study::MachiningStudyOutput& out) {
  std::string h =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>deflex machining study</title>\n"
      "<style>body{font-family:sans-serif;max-width:1040px;margin:20px auto;color:#222;line-height:1.4}"
      "table{border-collapse:collapse;font-size:12px;margin:8px 0}td,th{border:1px solid #ccc;padding:3px 6px;"
      "text-align:right;white-space:nowrap}th{background:#f0f0f0;white-space:normal}td:first-child,th:first-child{text-"
      "align:left}h2{margin-top:32px}"
      "svg{display:block;margin:10px 0}.note{color:#555;font-size:13px}</style></head><body>\n"
      "<h1>deflex machining study</h1>\n";
  for (const std::string& p : out.setup_paragraphs) h += "<p>" + escape(p) + "</p>\n";
  h += fmt::format(
      "<h2>Part errors</h2>\n<p class=\"note\">Over {} seed{}: mean &plusmn; standard deviation. A wall's figure is "
      "its mean deviation from the nominal plane along its outward normal (&gt; 0: material left, the tool pushed "
      "away; &lt; 0: a gouge); P-V its profile's peak to valley; the floor's flatness is the range about its "
      "least-squares plane; widths are measured &minus; nominal. Probe noise {:g} &micro;m per point.</p>\n",
      out.seeds, out.seeds == 1 ? "" : "s", out.probe_noise_m * 1e6);
  h += error_table(out);
  h += "<h2>Cutting coefficients</h2>\n<p class=\"note\">The offline and hybrid strategies use the fitted set "
       "(N/mm&sup2;, N/mm); the truth is shown for the comparison only.</p>\n" +
       fit_table(out);
  for (double feed : out.feeds_mm_min) {
    h += fmt::format("<h2>Walls as probed, {:g} mm/min</h2>\n", feed) + wall_charts(out, feed);
  }
  for (double feed : out.feeds_mm_min) {
    h += fmt::format(
             "<h2>Force and deflection along the passes, {:g} mm/min</h2>\n<p class=\"note\">The force the offline "
             "model predicted from the fitted coefficients on the nominal stock, against the cell's true force in "
             "the offline run; and each strategy's true tool tip's distance from the programmed path in the plane of "
             "the cut (seed 1).</p>\n",
             feed) +
         pass_charts(out, feed);
  }
  h += "</body></html>\n";
  return h;
}

}  // namespace deflex
