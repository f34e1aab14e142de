// SVG charts of a case study: Figure 5, path plots and the speed sweep.
#include "deflex/report/svg_charts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/report/svg_canvas.hpp"

namespace deflex {
namespace {

using svg::Canvas;
using svg::Scale;

const char* const kPalette[] = {"#4C78A8", "#F58518", "#54A24B", "#B279A2", "#E45756", "#72B7B2", "#9D755D"};
constexpr std::size_t kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);
const char* const kUnloadedColour = "#888888";
const char* const kUcColour = "#D62728";
const char* const kCColour = "#1F77B4";

std::string colour(std::size_t i) { return kPalette[i % kPaletteSize]; }

std::string short_setup_name(const std::string& setup) {
  if (setup == "offline") {
    return "offline (OFF)";
  }
  if (setup == "online") {
    return "online (ON)";
  }
  return setup;
}

// Horizontal grid, ticks and labels of a value axis, and the axis title rotated along it.
void value_axis(Canvas& c, const Scale& y, double x_left, double x_right, double step_hint_max, const std::string& label,
                double scale_to_label = 1.0) {
  const auto ticks = svg::nice_ticks(y.d0, y.d1, 6);
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : step_hint_max;
  for (const double t : ticks) {
    c.line(x_left, y(t), x_right, y(t), "#e3e3e3", 1.0);
    c.text(x_left - 6.0, y(t) + 4.0, svg::tick_label(t * scale_to_label, step * scale_to_label), 11.0, "end");
  }
  c.line(x_left, y.p0, x_left, y.p1, "#444", 1.0);
  const double mid = (y.p0 + y.p1) / 2.0;
  c.text(x_left - 48.0, mid, label, 12.0, "middle",
         fmt::format(R"svg(transform="rotate(-90 {:.2f} {:.2f})")svg", x_left - 48.0, mid));
}

void position_axis(Canvas& c, const Scale& x, double y_bottom, const std::string& label) {
  const auto ticks = svg::nice_ticks(x.d0, x.d1, 6);
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0;
  c.line(x.p0, y_bottom, x.p1, y_bottom, "#444", 1.0);
  for (const double t : ticks) {
    c.line(x(t), y_bottom, x(t), y_bottom + 5.0, "#444", 1.0);
    c.text(x(t), y_bottom + 18.0, svg::tick_label(t, step), 11.0, "middle");
  }
  c.text((x.p0 + x.p1) / 2.0, y_bottom + 36.0, label, 12.0, "middle");
}

// A legend entry: a swatch (bar, line or marker) and its text; returns the x after it.
double legend_entry(Canvas& c, double x, double y, const std::string& kind, const std::string& col,
                    const std::string& label) {
  if (kind == "bar") {
    c.rect(x, y - 10.0, 14.0, 12.0, col);
  } else if (kind == "marker") {
    c.line(x - 2.0, y - 4.0, x + 16.0, y - 4.0, col, 2.5);
    c.circle(x + 7.0, y - 4.0, 3.0, "white", fmt::format(R"(stroke="{}" stroke-width="1.5")", col));
  } else if (kind == "dash") {
    c.line(x, y - 4.0, x + 18.0, y - 4.0, col, 2.0, R"(stroke-dasharray="5 3")");
  } else {
    c.line(x, y - 4.0, x + 18.0, y - 4.0, col, 2.0);
  }
  c.text(x + 22.0, y, label, 12.0);
  return x + 22.0 + 7.0 * static_cast<double>(label.size()) + 18.0;
}

double nice_floor(double v) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    return 1.0;
  }
  const double mag = std::pow(10.0, std::floor(std::log10(v)));
  for (const double m : {5.0, 2.0, 1.0}) {
    if (m * mag <= v) {
      return m * mag;
    }
  }
  return mag;
}

}  // namespace

std::string xml_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    switch (ch) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += ch;
    }
  }
  return out;
}

std::string svg_figure5(const StudyResult& study) {
  const std::vector<int> speeds = study_speeds_mm_s(study);
  const PaperFigures paper = paper_reference();
  struct Group {
    std::size_t setup;
    const LoadResult* load;
    const PaperRow* paper;
  };
  std::vector<Group> groups;
  double top_value = 0.0;
  for (std::size_t si = 0; si < study.setups.size(); ++si) {
    const PaperTable* pt = paper.table_for(study.setups[si].setup);
    for (const auto& l : study.setups[si].loads) {
      const PaperRow* pr = pt != nullptr ? pt->row_for(l.load_N) : nullptr;
      groups.push_back({si, &l, pr});
      for (const int v : speeds) {
        const double c = value_at_speed(l.c_mm, v);
        if (std::isfinite(c)) {
          top_value = std::max(top_value, c);
        }
        if (pr != nullptr) {
          const double pc = value_at_speed(pr->c_mm, v);
          if (std::isfinite(pc)) {
            top_value = std::max(top_value, pc);
          }
        }
      }
    }
  }
  const double n_speeds = static_cast<double>(std::max<std::size_t>(1, speeds.size()));
  const double width = std::max(760.0, 110.0 + static_cast<double>(groups.size()) * (n_speeds * 22.0 + 34.0));
  const double height = 470.0;
  const double left = 84.0, right = 20.0, top = 70.0, bottom = 96.0;
  Canvas c(width, height);
  c.title("Mean deformation after compensation (the paper's Figure 5)");
  if (groups.empty() || speeds.empty()) {
    c.text(width / 2.0, height / 2.0, "no results to plot", 14.0, "middle");
    return c.str();
  }
  // Head-room above the tallest bar for the UC labels.
  const Scale y{0.0, svg::nice_ceiling(top_value * 1.3), height - bottom, top};
  value_axis(c, y, left, width - right, 0.1, "mean distance from the unloaded path, C (mm)");
  const double plot_w = width - left - right;
  const double group_w = plot_w / static_cast<double>(groups.size());
  const double bar_w = std::min(26.0, group_w * 0.75 / n_speeds);
  double lx = left;
  for (std::size_t k = 0; k < speeds.size(); ++k) {
    lx = legend_entry(c, lx, 52.0, "bar", colour(k), fmt::format("C at {} mm/s", speeds[k]));
  }
  lx = legend_entry(c, lx, 52.0, "marker", "#111", "paper (Tables 1, 2)");
  c.text(lx, 52.0, "UC: uncompensated, mean over speeds (mm)", 12.0, "start", R"(fill="#666")");

  std::size_t setup_start = 0;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const double xc = left + group_w * (static_cast<double>(g) + 0.5);
    const LoadResult& l = *groups[g].load;
    for (std::size_t k = 0; k < speeds.size(); ++k) {
      const double x0 = xc + (static_cast<double>(k) - n_speeds / 2.0) * bar_w;
      const double v = value_at_speed(l.c_mm, speeds[k]);
      if (std::isfinite(v)) {
        c.rect(x0 + 1.0, y(v), bar_w - 2.0, y(0.0) - y(v), colour(k),
               fmt::format(R"(data-value="{:.6g}")", v));
      }
      if (groups[g].paper != nullptr) {
        const double pv = value_at_speed(groups[g].paper->c_mm, speeds[k]);
        if (std::isfinite(pv)) {
          c.line(x0 - 1.0, y(pv), x0 + bar_w + 1.0, y(pv), "#111", 2.5);
          c.circle(x0 + bar_w / 2.0, y(pv), 3.0, "white", R"(stroke="#111" stroke-width="1.5")");
        }
      }
    }
    const double uc = l.uc_mean_mm();
    std::string uc_text = std::isfinite(uc) ? fmt::format("UC {:.2f}", uc) : "UC n/a";
    if (groups[g].paper != nullptr) {
      uc_text += fmt::format(" ({:.2f})", groups[g].paper->uc_mm);
    }
    c.text(xc, top + 14.0, uc_text, 10.5, "middle", R"(fill="#666")");
    c.text(xc, height - bottom + 18.0, fmt::format("{:g} N", l.load_N), 12.0, "middle");
    const bool last_of_setup = g + 1 == groups.size() || groups[g + 1].setup != groups[g].setup;
    if (last_of_setup) {
      const double x_first = left + group_w * static_cast<double>(setup_start);
      const double x_last = left + group_w * static_cast<double>(g + 1);
      c.text((x_first + x_last) / 2.0, height - bottom + 40.0, short_setup_name(study.setups[groups[g].setup].setup),
             13.0, "middle", R"(font-weight="bold")");
      if (g + 1 != groups.size()) {
        c.line(x_last, top, x_last, height - bottom + 46.0, "#999", 1.0, R"(stroke-dasharray="4 4")");
      }
      setup_start = g + 1;
    }
  }
  c.line(left, y(0.0), width - right, y(0.0), "#444", 1.0);
  c.text(left + plot_w / 2.0, height - 16.0, "load |F| (N), per strategy setup; bars: our simulated cell", 12.0,
         "middle");
  return c.str();
}

std::string svg_path_plot(const PathPlot& plot) {
  if (plot.unloaded.size() < 2) {
    throw InputError(fmt::format("path plot '{}': the unloaded path needs at least 2 samples", plot.title));
  }
  // Drawn in the plane of best fit of the unloaded path, axes following the base frame.
  const PathPlane plane = best_fit_plane(plot.unloaded);
  const Vector3& centroid = plane.centroid_m;
  const Vector3& u = plane.u;
  const Vector3& v = plane.v;

  const PolylineIndex index(plot.unloaded);
  struct Dev {
    Vector3 on_path;
    Vector3 d;
    double position;
  };
  // Position along the path: the angle about the centroid for a closed path (a circle), else the
  // coordinate along u.
  double extent_u_lo = std::numeric_limits<double>::infinity(), extent_u_hi = -extent_u_lo;
  double extent_v_lo = extent_u_lo, extent_v_hi = -extent_u_lo;
  for (const auto& s : plot.unloaded) {
    const Vector3 r = s.p_m - centroid;
    extent_u_lo = std::min(extent_u_lo, r.dot(u));
    extent_u_hi = std::max(extent_u_hi, r.dot(u));
    extent_v_lo = std::min(extent_v_lo, r.dot(v));
    extent_v_hi = std::max(extent_v_hi, r.dot(v));
  }
  const double size = std::max(extent_u_hi - extent_u_lo, extent_v_hi - extent_v_lo);
  const bool closed = (plot.unloaded.front().p_m - plot.unloaded.back().p_m).norm() < 0.1 * size;
  auto position_of = [&](const Vector3& p) {
    const Vector3 r = p - centroid;
    if (closed) {
      double a = rad_to_deg(std::atan2(r.dot(v), r.dot(u)));
      return a < 0.0 ? a + 360.0 : a;
    }
    return r.dot(u) * 1e3;
  };
  auto deviations = [&](const TrackerTrace& t) {
    std::vector<Dev> out;
    const std::size_t stride = std::max<std::size_t>(1, (t.size() + 1499) / 1500);
    for (std::size_t i = 0; i < t.size(); i += stride) {
      const auto near = index.nearest(t[i].p_m);
      out.push_back({near.point_m, t[i].p_m - near.point_m, position_of(near.point_m)});
    }
    return out;
  };
  const std::vector<Dev> uc = deviations(plot.uc);
  const std::vector<Dev> cc = deviations(plot.c);
  double max_dev = 0.0;
  for (const auto* set : {&uc, &cc}) {
    for (const auto& d : *set) {
      max_dev = std::max(max_dev, d.d.norm());
    }
  }
  const double mag = plot.magnification > 0.0 ? plot.magnification
                     : max_dev > 0.0             ? nice_floor(0.12 * size / max_dev)
                                                 : 1.0;
  auto mean_dev = [](const std::vector<Dev>& ds) {
    double s = 0.0;
    for (const auto& d : ds) {
      s += d.d.norm();
    }
    return ds.empty() ? std::numeric_limits<double>::quiet_NaN() : s / static_cast<double>(ds.size());
  };

  const double width = 1000.0, height = 540.0;
  Canvas c(width, height);
  c.title(plot.title.empty() ? "Paths: unloaded, loaded uncompensated (UC) and compensated (C)" : plot.title);
  double lx = 70.0;
  lx = legend_entry(c, lx, 50.0, "line", kUnloadedColour, "unloaded");
  auto mean_text = [&](const char* name, const std::vector<Dev>& ds) {
    const double m = mean_dev(ds);
    return std::isfinite(m) ? fmt::format("{} (mean {:.3f} mm)", name, m * 1e3) : fmt::format("{} (no data)", name);
  };
  lx = legend_entry(c, lx, 50.0, "line", kUcColour, mean_text("UC", uc));
  legend_entry(c, lx, 50.0, "line", kCColour, mean_text("C", cc));

  // Left panel: the path in its plane, equal scales, deviations magnified.
  const double pl = 80.0, pt = 80.0, pw = 400.0, ph = 400.0;
  const double half = 0.5 * size * 1.25 + 1e-9;
  const double mid_u = 0.5 * (extent_u_lo + extent_u_hi), mid_v = 0.5 * (extent_v_lo + extent_v_hi);
  const Scale xs{(mid_u - half) * 1e3, (mid_u + half) * 1e3, pl, pl + pw};
  const Scale ys{(mid_v - half) * 1e3, (mid_v + half) * 1e3, pt + ph, pt};
  c.rect(pl, pt, pw, ph, "none", R"(stroke="#ccc")");
  value_axis(c, ys, pl, pl + pw, 10.0, "v (mm, in the path's plane)");
  position_axis(c, xs, pt + ph, "u (mm, in the path's plane, about its centre)");
  auto draw_path = [&](const std::vector<Vector3>& pts, const std::string& col, double w) {
    std::vector<double> xy;
    for (const auto& p : pts) {
      const Vector3 r = p - centroid;
      xy.push_back(xs(r.dot(u) * 1e3));
      xy.push_back(ys(r.dot(v) * 1e3));
    }
    c.polyline(xy, col, w);
  };
  {
    std::vector<Vector3> pts;
    const std::size_t stride = std::max<std::size_t>(1, (plot.unloaded.size() + 1499) / 1500);
    for (std::size_t i = 0; i < plot.unloaded.size(); i += stride) {
      pts.push_back(plot.unloaded[i].p_m);
    }
    pts.push_back(plot.unloaded.back().p_m);
    draw_path(pts, kUnloadedColour, 4.5);  // wide, so it shows beside a C path lying on it
  }
  for (const auto& [set, col] : {std::pair{&uc, kUcColour}, std::pair{&cc, kCColour}}) {
    std::vector<Vector3> pts;
    for (const auto& d : *set) {
      pts.push_back(d.on_path + mag * d.d);
    }
    draw_path(pts, col, 1.3);
  }
  c.text(pl + 8.0, pt + 18.0, fmt::format("deviations magnified x{:g}", mag), 12.0, "start",
         R"(font-weight="bold")");
  c.text(pl + 8.0, pt + 34.0, "(projected on the plane: out-of-plane part not shown)", 10.5, "start",
         R"(fill="#666")");

  // Right panel: distance from the unloaded path along the path, true scale.
  const double ql = 590.0, qt = 80.0, qw = 380.0, qh = 400.0;
  double pos_lo = 0.0, pos_hi = 360.0;
  if (!closed) {
    pos_lo = extent_u_lo * 1e3;
    pos_hi = extent_u_hi * 1e3;
  }
  const Scale px{pos_lo, pos_hi, ql, ql + qw};
  const Scale py{0.0, svg::nice_ceiling(max_dev * 1e3 * 1.1), qt + qh, qt};
  value_axis(c, py, ql, ql + qw, 0.1, "distance from the unloaded path (mm)");
  position_axis(c, px, qt + qh, closed ? "position on the path: angle about its centre (deg)" : "position along u (mm)");
  for (const auto& [set, col] : {std::pair{&uc, kUcColour}, std::pair{&cc, kCColour}}) {
    // Break the line where the position wraps (a new lap) or jumps.
    std::vector<double> xy;
    for (std::size_t i = 0; i < set->size(); ++i) {
      const Dev& d = (*set)[i];
      if (i > 0 && std::abs(d.position - (*set)[i - 1].position) > 0.2 * (pos_hi - pos_lo)) {
        c.polyline(xy, col, 1.0);
        xy.clear();
      }
      xy.push_back(px(d.position));
      xy.push_back(py(d.d.norm() * 1e3));
    }
    if (!xy.empty()) {
      c.polyline(xy, col, 1.0);
    }
  }
  return c.str();
}

std::string svg_speed_sweep(const StudyResult& study) {
  const double width = 1000.0, height = 440.0;
  Canvas c(width, height);
  c.title("Speed sweep: compensation and residual against TCP speed");
  if (study.speed_sweep.empty()) {
    c.text(width / 2.0, height / 2.0, "no speed sweep in this study", 14.0, "middle");
    return c.str();
  }
  // One series per setup and load, in order of first appearance.
  struct Series {
    std::string setup;
    double load_N;
    std::vector<const SweepPoint*> points;
  };
  std::vector<Series> series;
  double max_speed = 0.0, max_c = 0.0, min_comp = 0.0;
  for (const auto& p : study.speed_sweep) {
    auto it = std::find_if(series.begin(), series.end(),
                           [&](const Series& s) { return s.setup == p.setup && s.load_N == p.load_N; });
    if (it == series.end()) {
      series.push_back({p.setup, p.load_N, {}});
      it = series.end() - 1;
    }
    it->points.push_back(&p);
    max_speed = std::max(max_speed, p.speed_mm_s);
    if (std::isfinite(p.c_mm)) {
      max_c = std::max(max_c, p.c_mm);
    }
    if (std::isfinite(p.compensation)) {
      min_comp = std::min(min_comp, p.compensation);
    }
  }
  std::map<std::string, std::size_t> setup_colour;
  for (const auto& s : series) {
    setup_colour.emplace(s.setup, setup_colour.size());
  }
  const double top = 86.0, plot_h = 290.0;
  const Scale x1{0.0, svg::nice_ceiling(max_speed), 80.0, 470.0};
  const Scale x2{0.0, svg::nice_ceiling(max_speed), 580.0, 970.0};
  const Scale y1{std::floor(min_comp * 10.0) / 10.0, 1.0, top + plot_h, top};
  const Scale y2{0.0, svg::nice_ceiling(max_c * 1.1), top + plot_h, top};
  for (const auto* xs : {&x1, &x2}) {
    const double band_lo = (*xs)(10.0), band_hi = (*xs)(50.0);
    c.rect(band_lo, top, band_hi - band_lo, plot_h, "#f1f1f1");
    c.text((band_lo + band_hi) / 2.0, top + 14.0, "paper's speeds", 10.5, "middle", R"(fill="#777")");
  }
  value_axis(c, y1, x1.p0, x1.p1, 0.1, "compensation 1 - C/UC (%)", 100.0);
  value_axis(c, y2, x2.p0, x2.p1, 0.1, "residual after compensation, C (mm)");
  position_axis(c, x1, top + plot_h, "TCP speed (mm/s)");
  position_axis(c, x2, top + plot_h, "TCP speed (mm/s)");
  const char* const dashes[] = {"", R"(stroke-dasharray="6 3")", R"(stroke-dasharray="2 3")", R"(stroke-dasharray="8 3 2 3")"};
  std::map<std::string, std::size_t> load_rank;
  double lx = 80.0, ly = 50.0;
  for (const auto& s : series) {
    const std::size_t rank = load_rank[s.setup]++;
    const std::string col = colour(setup_colour[s.setup]);
    const std::string dash = dashes[rank % 4];
    std::vector<double> a, b;
    for (const auto* p : s.points) {
      if (std::isfinite(p->compensation)) {
        a.push_back(x1(p->speed_mm_s));
        a.push_back(y1(p->compensation));
        c.circle(x1(p->speed_mm_s), y1(p->compensation), 3.0, col);
      }
      if (std::isfinite(p->c_mm)) {
        b.push_back(x2(p->speed_mm_s));
        b.push_back(y2(p->c_mm));
        c.circle(x2(p->speed_mm_s), y2(p->c_mm), 3.0, col);
      }
    }
    c.polyline(a, col, 2.0, dash);
    c.polyline(b, col, 2.0, dash);
    const std::string label = fmt::format("{} {:g} N", s.setup, s.load_N);
    if (lx + 40.0 + 7.0 * static_cast<double>(label.size()) > width - 20.0) {
      lx = 80.0;
      ly += 18.0;
    }
    c.line(lx, ly - 4.0, lx + 22.0, ly - 4.0, col, 2.0, dash);
    c.text(lx + 27.0, ly, label, 12.0);
    lx += 27.0 + 7.0 * static_cast<double>(label.size()) + 22.0;
  }
  return c.str();
}

}  // namespace deflex
