// The machining study's HTML report (see machining_report.hpp).
#include "deflex/report/machining_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

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

struct Series {
  std::string label, colour;
  std::vector<double> x, y;
  bool dashed = false;
};

// A line chart of several series: x in mm, y in the unit named by `y_label`, a legend on the right.
std::string line_chart(const std::string& title, const std::string& x_label, const std::string& y_label,
                       const std::vector<Series>& series) {
  constexpr double kW = 1000.0, kH = 300.0, kLeft = 70.0, kRight = 200.0, kTop = 34.0, kBottom = 46.0;
  double x0 = INFINITY, x1 = -INFINITY, y0 = 0.0, y1 = 0.0;
  for (const Series& s : series) {
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
  for (const Series& s : series) {
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
    std::vector<Series> series;
    for (const MachiningRun* r : runs) {
      if (w >= r->walls.size()) continue;
      Series s{study::to_string(r->strategy), strategy_colour(r->strategy), {}, {}};
      for (std::size_t i = 0; i < r->walls[w].along_m.size(); ++i) {
        s.x.push_back(r->walls[w].along_m[i] * 1e3);
        s.y.push_back(r->walls[w].deviation_m[i] * 1e6);
      }
      series.push_back(std::move(s));
    }
    html += line_chart(fmt::format("{}, {:g} mm/min, seed 1: deviation from the nominal wall (mid-depth row)",
                                   runs.front()->walls[w].name, feed),
                       "along the wall, mm", "deviation, um (> 0 material left)", series);
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
    std::vector<Series> force{{"true (offline run)", "#1e8449", x_mm, t.true_force_n},
                              {"predicted, fitted coefficients", "#2471a3", x_mm, t.predicted_force_n, true}};
    html += line_chart(fmt::format("{}, {:g} mm/min: the in-plane cutting force", t.name, feed), "tool tip x, mm",
                       "force, N", force);
    std::vector<Series> defl;
    for (const MachiningRun* r : runs) {
      if (p >= r->passes.size()) continue;
      Series s{study::to_string(r->strategy), strategy_colour(r->strategy), {}, {}};
      for (std::size_t i = 0; i < r->passes[p].x_m.size(); ++i) {
        s.x.push_back(r->passes[p].x_m[i] * 1e3);
        s.y.push_back(r->passes[p].deflection_m[i] * 1e6);
      }
      defl.push_back(std::move(s));
    }
    html += line_chart(fmt::format("{}, {:g} mm/min: the true tool's distance from the programmed path", t.name, feed),
                       "tool tip x, mm", "distance, um", defl);
  }
  return html;
}

}  // namespace

std::string machining_report_html(const study::MachiningStudyOutput& out) {
  std::string h =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>deflex machining study</title>\n"
      "<style>body{font-family:sans-serif;max-width:1040px;margin:20px auto;color:#222}"
      "pre{font-size:11px;background:#f6f6f6;padding:8px;overflow-x:auto}h2{margin-top:32px}"
      "svg{display:block;margin:10px 0}</style></head><body>\n<h1>deflex machining study</h1>\n";
  for (const std::string& p : out.setup_paragraphs) h += "<p>" + escape(p) + "</p>\n";
  h += "<h2>Part errors</h2>\n<pre>" + escape(study::machining_table_text(out)) + "</pre>\n";
  h += "<h2>Cutting coefficients</h2>\n<pre>" + escape(study::machining_fit_text(out)) + "</pre>\n";
  for (double feed : out.feeds_mm_min) {
    h += fmt::format("<h2>Walls as probed, {:g} mm/min</h2>\n", feed) + wall_charts(out, feed);
    h += fmt::format("<h2>Force and deflection along the passes, {:g} mm/min</h2>\n", feed) + pass_charts(out, feed);
  }
  h += "</body></html>\n";
  return h;
}

}  // namespace deflex
