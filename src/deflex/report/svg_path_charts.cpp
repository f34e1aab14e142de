// SVG charts of one setup's runs: the path plot with magnified deviations, the per-lap deviation
// against the angle on the circle, and the polar deviation plot. Distances are taken, as the
// study's figures are, to the nearest point of the reference: the unloaded laps' mean path.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/report/detail/svg_canvas.hpp"
#include "deflex/report/detail/svg_chart_parts.hpp"
#include "deflex/report/svg_charts.hpp"

namespace deflex {
namespace {

using svg::Canvas;
using svg::kMinFont;
using svg::Scale;

TrackerTrace finite_only(const TrackerTrace& t) {
  TrackerTrace out;
  out.reserve(t.size());
  for (const auto& s : t) {
    if (s.p_m.allFinite()) {
      out.push_back(s);
    }
  }
  return out;
}

// The reference the distances are taken to and the frame the angle is measured in.
struct Reference {
  TrackerTrace path;  // finite samples; a closed path is closed (its first sample repeated)
  bool is_mean = false;
  PathPlane plane;
  bool closed = false;
  bool horizontal = false;  // the plane's normal within 10 deg of the base z: u, v are +x, +y
  double size_m = 0.0;
  std::optional<PolylineIndex> index;
};

// nullopt when neither the unloaded mean nor the unloaded lap has 2 finite samples.
std::optional<Reference> reference_of(const PathPlot& plot) {
  Reference r;
  r.path = finite_only(plot.unloaded_mean);
  r.is_mean = r.path.size() >= 2;
  if (!r.is_mean) {
    r.path = finite_only(plot.unloaded);
  }
  if (r.path.size() < 2) {
    return std::nullopt;
  }
  r.plane = best_fit_plane(r.path);
  double lo_u = HUGE_VAL, hi_u = -HUGE_VAL, lo_v = HUGE_VAL, hi_v = -HUGE_VAL;
  for (const auto& s : r.path) {
    const Vector3 d = s.p_m - r.plane.centroid_m;
    lo_u = std::min(lo_u, d.dot(r.plane.u));
    hi_u = std::max(hi_u, d.dot(r.plane.u));
    lo_v = std::min(lo_v, d.dot(r.plane.v));
    hi_v = std::max(hi_v, d.dot(r.plane.v));
  }
  r.size_m = std::max(hi_u - lo_u, hi_v - lo_v);
  const double gap = (r.path.front().p_m - r.path.back().p_m).norm();
  r.closed = gap < 0.1 * r.size_m;
  // A thinned closed path can lose its repeated first sample; without it a point near the seam
  // would find its nearest neighbour a whole gap away.
  if (r.closed && gap > 0.0) {
    r.path.push_back(r.path.front());
  }
  r.horizontal = std::abs(r.plane.normal.z()) > std::cos(deg_to_rad(10.0));
  r.index.emplace(r.path);
  return r;
}

// Angle about the reference's centre in its plane, 0..360 deg, anticlockwise seen from the side
// the normal points to (from above).
double angle_deg(const Reference& r, const Vector3& p) {
  const Vector3 d = p - r.plane.centroid_m;
  const double a = rad_to_deg(std::atan2(d.dot(r.plane.v), d.dot(r.plane.u)));
  return a < 0.0 ? a + 360.0 : a;
}

// Clockwise seen from above: the sign of the area swept about the centre.
bool turns_clockwise(const TrackerTrace& t, const Reference& r) {
  double area = 0.0;
  for (std::size_t k = 0; k + 1 < t.size(); ++k) {
    area += (t[k].p_m - r.plane.centroid_m).cross(t[k + 1].p_m - r.plane.centroid_m).dot(r.plane.normal);
  }
  return area < 0.0;
}

struct LapDeviation {
  bool clockwise = false;
  std::vector<double> angle_deg, distance_mm;
  Vector3 first = Vector3::Zero();
};

std::vector<LapDeviation> lap_deviations(const std::vector<DirectedLap>& laps, const TrackerTrace& last_lap,
                                         const Reference& ref) {
  std::vector<DirectedLap> use = laps;
  if (use.empty() && last_lap.size() >= 2) {  // no per-lap data: the last lap, its direction from the trace
    use.push_back({last_lap, turns_clockwise(finite_only(last_lap), ref)});
  }
  std::vector<LapDeviation> out;
  for (const auto& lap : use) {
    LapDeviation d;
    d.clockwise = lap.clockwise;
    for (const auto& s : lap.trace) {
      if (!s.p_m.allFinite()) {
        continue;
      }
      d.angle_deg.push_back(angle_deg(ref, s.p_m));
      d.distance_mm.push_back(ref.index->nearest(s.p_m).distance_m * 1e3);
    }
    if (!d.distance_mm.empty()) {
      out.push_back(std::move(d));
    }
  }
  return out;
}

double mean_of(const std::vector<LapDeviation>& laps, int clockwise /* -1: any */) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& l : laps) {
    if (clockwise >= 0 && l.clockwise != (clockwise == 1)) {
      continue;
    }
    for (const double d : l.distance_mm) {
      sum += d;
      ++n;
    }
  }
  return n > 0 ? sum / static_cast<double>(n) : kNaN;
}

int count_of(const std::vector<LapDeviation>& laps, bool clockwise) {
  return static_cast<int>(
      std::count_if(laps.begin(), laps.end(), [&](const auto& l) { return l.clockwise == clockwise; }));
}

constexpr int kSectors = 72;  // 5 deg each

// Mean distance (mm) of one direction's laps in each 5 deg sector of the angle; NaN where no sample
// fell; empty when the direction has no sample at all.
std::vector<double> sector_means(const std::vector<LapDeviation>& laps, bool clockwise) {
  std::vector<double> sum(kSectors, 0.0);
  std::vector<int> n(kSectors, 0);
  for (const auto& lap : laps) {
    if (lap.clockwise != clockwise) {
      continue;
    }
    for (std::size_t i = 0; i < lap.angle_deg.size(); ++i) {
      const auto s = static_cast<std::size_t>(
          std::clamp(static_cast<int>(lap.angle_deg[i] / (360.0 / kSectors)), 0, kSectors - 1));
      sum[s] += lap.distance_mm[i];
      ++n[s];
    }
  }
  if (std::all_of(n.begin(), n.end(), [](int k) { return k == 0; })) {
    return {};
  }
  std::vector<double> mean(kSectors, kNaN);
  for (std::size_t s = 0; s < mean.size(); ++s) {
    if (n[s] > 0) {
      mean[s] = sum[s] / n[s];
    }
  }
  return mean;
}

double sector_centre_deg(std::size_t s) { return (static_cast<double>(s) + 0.5) * 360.0 / kSectors; }

// A filled arrowhead at (x, y) pointing along (dx, dy) in pixels.
void arrowhead(Canvas& c, double x, double y, double dx, double dy, const std::string& col, double size = 9.0) {
  const double n = std::hypot(dx, dy);
  if (!(n > 0.0)) {
    return;
  }
  const double ux = dx / n, uy = dy / n;
  c.polygon({x + ux * size * 0.6, y + uy * size * 0.6, x - ux * size * 0.4 - uy * size * 0.45,
             y - uy * size * 0.4 + ux * size * 0.45, x - ux * size * 0.4 + uy * size * 0.45,
             y - uy * size * 0.4 - ux * size * 0.45},
            col, R"(class="travel-arrow" stroke="white" stroke-width="1" stroke-linejoin="round")");
}

std::string direction_name(bool clockwise) { return clockwise ? "clockwise" : "anticlockwise"; }
std::string direction_colour(bool clockwise) { return clockwise ? svg::kClockwiseColour : svg::kAnticlockwiseColour; }
std::string direction_mean_colour(bool clockwise) { return clockwise ? "#8F3B00" : "#2E1A4F"; }
std::string direction_dash(bool clockwise) { return clockwise ? "" : R"(stroke-dasharray="6 3")"; }

// The base direction an angle on a horizontal circle points to (seen from above).
std::string compass(int deg) {
  switch (deg) {
    case 0:
      return "+x";
    case 90:
      return "+y";
    case 180:
      return "-x";
    case 270:
      return "-y";
    default:
      return "";
  }
}

// A title and, under it, what the figure is of (the plot's own title: setup, load, speed, seed).
void titles(Canvas& c, const std::string& title, const std::string& of) {
  c.title(title);
  if (!of.empty()) {
    c.text(c.width() / 2.0, 44.0, of, 13.0, "middle", R"(fill="#444")");
  }
}

void no_data(Canvas& c, const std::string& why) { c.text(c.width() / 2.0, c.height() / 2.0, why, 14.0, "middle"); }

// The laps to use: the given ones, else the last lap with its direction from the trace.
std::vector<DirectedLap> laps_or_last(const std::vector<DirectedLap>& laps, const TrackerTrace& last_lap,
                                      const Reference& ref) {
  if (!laps.empty() || last_lap.size() < 2) return laps;
  return {{last_lap, turns_clockwise(finite_only(last_lap), ref)}};
}

std::size_t sector_of(double deg) {
  return static_cast<std::size_t>(std::clamp(static_cast<int>(deg / (360.0 / kSectors)), 0, kSectors - 1));
}

// Per direction of travel (index 1: clockwise) and 5 deg sector, the sum and count of a run's
// deviation vectors from the reference (sample minus its nearest reference point), in m.
struct SectorVectors {
  std::vector<Vector3> sum[2] = {std::vector<Vector3>(kSectors, Vector3::Zero()),
                                 std::vector<Vector3>(kSectors, Vector3::Zero())};
  std::vector<int> n[2] = {std::vector<int>(kSectors, 0), std::vector<int>(kSectors, 0)};
  // The direction's mean in the sector, else the other direction's; zero when neither has a sample.
  [[nodiscard]] Vector3 mean(bool clockwise, std::size_t s) const {
    for (const int d : {clockwise ? 1 : 0, clockwise ? 0 : 1}) {
      if (n[d][s] > 0) return sum[d][s] / n[d][s];
    }
    return Vector3::Zero();
  }
};

SectorVectors sector_vectors(const std::vector<DirectedLap>& laps, const Reference& ref) {
  SectorVectors v;
  for (const auto& lap : laps) {
    const int d = lap.clockwise ? 1 : 0;
    for (const auto& sample : lap.trace) {
      if (!sample.p_m.allFinite()) continue;
      const std::size_t s = sector_of(angle_deg(ref, sample.p_m));
      v.sum[d][s] += sample.p_m - ref.index->nearest(sample.p_m).point_m;
      ++v.n[d][s];
    }
  }
  return v;
}

// The angle axis under a panel: ticks every 45 deg (compass names on a horizontal path), and with
// `grid` a line across the panel every 90 deg.
void angle_axis(Canvas& c, const Scale& x, double top, double bottom, bool horizontal, bool grid) {
  c.line(x.p0, bottom, x.p1, bottom, "#444", 1.0);
  for (int deg = 0; deg <= 360; deg += 45) {
    c.line(x(deg), bottom, x(deg), bottom + 5.0, "#444", 1.0);
    c.text(x(deg), bottom + 18.0, fmt::format("{}", deg), kMinFont, "middle");
    if (horizontal && deg % 90 == 0) {
      c.text(x(deg), bottom + 32.0, compass(deg % 360), kMinFont, "middle", R"(fill="#666")");
    }
    if (grid && deg % 90 == 0) {
      c.line(x(deg), top, x(deg), bottom, deg % 360 == 0 ? "#777" : "#d8d8d8", 1.0,
             deg % 360 == 0 ? "" : R"(stroke-dasharray="3 3")");
    }
  }
  c.text((x.p0 + x.p1) / 2.0, bottom + 50.0, "angle about the circle's centre (deg)", 12.0, "middle");
}

// SVG path data through `steps` sector means (sector k % means.size()), lifting the pen over empty
// (NaN) sectors; `to_px(sector, mean)` places a point.
template <class ToPx>
std::string sector_path(const std::vector<double>& means, std::size_t steps, ToPx to_px) {
  std::string d;
  bool pen = false;
  for (std::size_t k = 0; k < steps; ++k) {
    const std::size_t s = k % means.size();
    if (!std::isfinite(means[s])) {
      pen = false;
      continue;
    }
    const auto [x, y] = to_px(s, means[s]);
    d += fmt::format("{}{:.1f},{:.1f}", pen ? " L" : (d.empty() ? "M" : " M"), x, y);
    pen = true;
  }
  return d;
}

}  // namespace

namespace {

// A tracker sample as drawn on the path plot: its nearest reference point and its deviation from it.
struct PathDeviation {
  Vector3 on_path, d;
};

// A trace's deviations, thinned to at most about 1500.
std::vector<PathDeviation> path_deviations(const TrackerTrace& t, const Reference& ref) {
  std::vector<PathDeviation> out;
  const std::size_t stride = std::max<std::size_t>(1, (t.size() + 1499) / 1500);
  for (std::size_t i = 0; i < t.size(); i += stride) {
    if (t[i].p_m.allFinite()) {
      const auto near = ref.index->nearest(t[i].p_m);
      out.push_back({near.point_m, t[i].p_m - near.point_m});
    }
  }
  return out;
}

std::string path_mean_text(const char* name, const std::vector<PathDeviation>& ds, const TrackerTrace& lap,
                           const Reference& ref) {
  if (ds.empty()) {
    return fmt::format("{} (no data)", name);
  }
  double s = 0.0;
  for (const auto& d : ds) {
    s += d.d.norm();
  }
  const std::string dir = ref.closed ? ", " + direction_name(turns_clockwise(finite_only(lap), ref)) : "";
  return fmt::format("{}, last lap{}: mean {:.3f} mm", name, dir, s / static_cast<double>(ds.size()) * 1e3);
}

// The path's plane mapped to pixels, equal scales, centred on the path.
struct PlaneMap {
  Vector3 centroid, u, v;
  Scale xs, ys;
  double half = 0.0;  // half the span drawn (m)
  [[nodiscard]] std::pair<double, double> operator()(const Vector3& p) const {
    const Vector3 d = p - centroid;
    return std::pair{xs(d.dot(u) * 1e3), ys(d.dot(v) * 1e3)};
  }
};

PlaneMap plane_map(const Reference& ref, double pl, double pt, double pw, double ph) {
  PlaneMap m{ref.plane.centroid_m, ref.plane.u, ref.plane.v, {}, {}};
  double lo_u = HUGE_VAL, hi_u = -HUGE_VAL, lo_v = HUGE_VAL, hi_v = -HUGE_VAL;
  for (const auto& s : ref.path) {
    const Vector3 d = s.p_m - m.centroid;
    lo_u = std::min(lo_u, d.dot(m.u));
    hi_u = std::max(hi_u, d.dot(m.u));
    lo_v = std::min(lo_v, d.dot(m.v));
    hi_v = std::max(hi_v, d.dot(m.v));
  }
  m.half = 0.5 * ref.size_m * 1.3 + 1e-9;
  const double mid_u = 0.5 * (lo_u + hi_u), mid_v = 0.5 * (lo_v + hi_v);
  m.xs = Scale{(mid_u - m.half) * 1e3, (mid_u + m.half) * 1e3, pl, pl + pw};
  m.ys = Scale{(mid_v - m.half) * 1e3, (mid_v + m.half) * 1e3, pt + ph, pt};
  return m;
}

// The reference wide, then each run's deviations magnified, each with an arrowhead for its travel.
void path_plot_lines(Canvas& c, const Reference& ref, const PlaneMap& to_px, const std::vector<PathDeviation>& uc,
                     const std::vector<PathDeviation>& cc, double mag) {
  {
    std::vector<double> xy;
    const std::size_t stride = std::max<std::size_t>(1, (ref.path.size() + 1499) / 1500);
    for (std::size_t i = 0; i < ref.path.size(); i += stride) {
      const auto [x, y] = to_px(ref.path[i].p_m);
      xy.insert(xy.end(), {x, y});
    }
    const auto [x, y] = to_px(ref.path.back().p_m);
    xy.insert(xy.end(), {x, y});
    c.polyline(xy, svg::kUnloadedColour, 4.5);  // wide, so it shows beside a C path lying on it
  }
  for (const auto& [set, col] : {std::pair{&uc, svg::kUcColour}, std::pair{&cc, svg::kCColour}}) {
    std::vector<double> xy;
    for (const auto& d : *set) {
      const auto [x, y] = to_px(d.on_path + mag * d.d);
      xy.insert(xy.end(), {x, y});
    }
    c.polyline(xy, col, 1.3);
    // The direction of travel: an arrowhead a third of the way along.
    if (set->size() >= 8) {
      const std::size_t k = set->size() / 3;
      const auto [x0, y0] = to_px((*set)[k].on_path + mag * (*set)[k].d);
      const auto [x1, y1] = to_px((*set)[k + 3].on_path + mag * (*set)[k + 3].d);
      arrowhead(c, x0, y0, x1 - x0, y1 - y0, col, 11.0);
    }
  }
}

// The centre and the 0 deg ray of the angle the other figures use.
void path_plot_centre(Canvas& c, const Reference& ref, const PlaneMap& to_px, double pw) {
  const auto [cx, cy] = to_px(to_px.centroid);
  c.line(cx - 5.0, cy, cx + 5.0, cy, "#666", 1.0);
  c.line(cx, cy - 5.0, cx, cy + 5.0, "#666", 1.0);
  const double ray = 0.5 * ref.size_m * 0.75 * pw / (2.0 * to_px.half);
  c.line(cx, cy, cx + ray, cy, "#666", 1.0, R"(stroke-dasharray="3 3")");
  c.text(cx + 8.0, cy - 6.0, ref.horizontal ? "0 deg (+x)" : "0 deg (+u)", kMinFont, "start", R"(fill="#444")");
}

// Below the axes, clear of every line: how to read the figure.
void path_plot_notes(Canvas& c, const Reference& ref, double mag, double xc, double y0) {
  c.text(xc, y0, fmt::format("Deviations magnified x{:g}", mag), 12.0, "middle", R"(font-weight="bold")");
  c.text(xc, y0 + 16.0,
         fmt::format("each point drawn from its nearest reference point; seen from {},",
                     ref.horizontal ? "above" : "the plane's normal"),
         12.0, "middle", R"(fill="#555")");
  c.text(xc, y0 + 32.0, "projected on the path's plane (the out-of-plane part is not drawn)", 12.0, "middle",
         R"(fill="#555")");
}

}  // namespace

std::string svg_path_plot(const PathPlot& plot) {
  const double width = 500.0, height = 640.0;
  Canvas c(width, height);
  titles(c, "The last laps, deviations magnified", plot.title);
  const std::optional<Reference> ref = reference_of(plot);
  if (!ref) {
    no_data(c, "no unloaded path to plot (fewer than 2 samples)");
    return c.str();
  }
  const std::vector<PathDeviation> uc = path_deviations(plot.uc, *ref);
  const std::vector<PathDeviation> cc = path_deviations(plot.c, *ref);
  double max_dev = 0.0;
  for (const auto* set : {&uc, &cc}) {
    for (const auto& d : *set) {
      max_dev = std::max(max_dev, d.d.norm());
    }
  }
  const double mag = plot.magnification > 0.0 ? plot.magnification
                     : max_dev > 0.0          ? svg::nice_floor(0.12 * ref->size_m / max_dev)
                                              : 1.0;
  svg::legend_entry(c, 40.0, 72.0, "line", svg::kUnloadedColour,
                    ref->is_mean ? "unloaded, mean of the laps (the reference)" : "unloaded, last lap (the reference)");
  svg::legend_entry(c, 40.0, 92.0, "line", svg::kUcColour, path_mean_text("UC", uc, plot.uc, *ref));
  svg::legend_entry(c, 40.0, 112.0, "line", svg::kCColour, path_mean_text("C", cc, plot.c, *ref));

  // The path in its plane, equal scales, deviations magnified.
  const double pl = 76.0, pt = 130.0, pw = 400.0, ph = 400.0;
  const PlaneMap to_px = plane_map(*ref, pl, pt, pw, ph);
  c.rect(pl, pt, pw, ph, "none", R"(stroke="#ccc")");
  const std::string axis_u = ref->horizontal ? "x" : "u", axis_v = ref->horizontal ? "y" : "v";
  svg::value_axis(c, to_px.ys, pl, pl + pw, fmt::format("{} about the centre (mm)", axis_v), 1.0, 50.0);
  svg::position_axis(c, to_px.xs, pt + ph, fmt::format("{} about the centre (mm)", axis_u));
  path_plot_lines(c, *ref, to_px, uc, cc, mag);
  if (ref->closed) {
    path_plot_centre(c, *ref, to_px, pw);
  }
  path_plot_notes(c, *ref, mag, pl + pw / 2.0, pt + ph + 62.0);
  return c.str();
}

namespace {

// Legend: colour and dash by direction, with the direction of travel on the angle axis; below, the
// direction's mean, which the eye cannot find in six noisy laps.
void lap_overlay_legend(Canvas& c) {
  for (const bool cw : {true, false}) {
    const double lx = cw ? 80.0 : 590.0;
    const std::string label = fmt::format("{} laps: travel {} (angle {})", direction_name(cw),
                                          cw ? "to the left" : "to the right", cw ? "falls" : "grows");
    c.line(lx, 66.0, lx + 18.0, 66.0, direction_colour(cw), 2.0, direction_dash(cw));
    arrowhead(c, lx + (cw ? 2.0 : 16.0), 66.0, cw ? -1.0 : 1.0, 0.0, direction_colour(cw), 11.0);
    c.text(lx + 24.0, 70.0, label, 12.0);
    c.line(lx, 86.0, lx + 18.0, 86.0, direction_mean_colour(cw), 2.6, direction_dash(cw));
    c.text(lx + 24.0, 90.0, fmt::format("{} laps' mean in 5 deg sectors", direction_name(cw)), 12.0);
  }
}

// A panel's name and, under it, each direction's lap count and mean distance.
void lap_panel_heading(Canvas& c, const std::vector<LapDeviation>& laps, const char* name, double left, double top) {
  c.text(left, top - 26.0, name, 13.0, "start", R"(font-weight="bold")");
  std::string summary;
  for (const bool cw : {true, false}) {
    const int n = count_of(laps, cw);
    if (n > 0) {
      summary += fmt::format("{}{} {} lap{}: mean {:.3f} mm", summary.empty() ? "" : "; ", direction_name(cw), n,
                             n == 1 ? "" : "s", mean_of(laps, cw ? 1 : 0));
    }
  }
  c.text(left, top - 9.0, summary.empty() ? "no laps" : summary, 12.0, "start", R"(fill="#444")");
}

struct LapArrow {
  double x, y, dx;
  std::string colour;
};

// The sample of lap `k` of `count` nearest its own share of the angle axis, with the angle travelled
// over the next 3 samples; nullopt when the lap is short or turns too fast there.
std::optional<std::pair<std::size_t, double>> lap_arrow_at(const LapDeviation& lap, std::size_t k, std::size_t count) {
  const std::size_t n = lap.angle_deg.size();
  if (n < 12) {
    return std::nullopt;
  }
  const double target = (static_cast<double>(k) + 0.5) * 360.0 / static_cast<double>(count);
  std::size_t i = 0;
  for (std::size_t j = 1; j + 3 < n; ++j) {
    if (std::abs(std::remainder(lap.angle_deg[j] - target, 360.0)) <
        std::abs(std::remainder(lap.angle_deg[i] - target, 360.0))) {
      i = j;
    }
  }
  double da = lap.angle_deg[i + 3] - lap.angle_deg[i];
  da = std::remainder(da, 360.0);
  if (std::abs(da) < 90.0 && da != 0.0) {
    return std::pair{i, da};
  }
  return std::nullopt;
}

// A line a lap; returns the arrowheads showing each lap's travel, to draw over every line.
std::vector<LapArrow> lap_lines(Canvas& c, const std::vector<LapDeviation>& laps, const char* run, const Scale& x,
                                const Scale& y) {
  std::vector<LapArrow> arrows;
  for (std::size_t k = 0; k < laps.size(); ++k) {
    const LapDeviation& lap = laps[k];
    std::string d;
    for (std::size_t i = 0; i < lap.angle_deg.size(); ++i) {
      const bool wrap = i > 0 && std::abs(lap.angle_deg[i] - lap.angle_deg[i - 1]) > 180.0;
      d += fmt::format("{}{:.1f},{:.1f}", i == 0 || wrap ? (i == 0 ? "M" : " M") : " L", x(lap.angle_deg[i]),
                       y(lap.distance_mm[i]));
    }
    const std::string col = direction_colour(lap.clockwise);
    c.path(d, col, 1.1,
           fmt::format(R"(stroke-opacity="0.85" {} class="lap" data-run="{}" data-direction="{}")",
                       direction_dash(lap.clockwise), run, lap.clockwise ? "cw" : "ccw"));
    // The direction of travel, from the samples themselves: an arrowhead at this lap's own angle
    // (the laps' arrows spread evenly along the axis, so they do not stack).
    if (const auto at = lap_arrow_at(lap, k, laps.size())) {
      arrows.push_back({x(lap.angle_deg[at->first]), y(lap.distance_mm[at->first]), at->second, col});
    }
  }
  return arrows;
}

// One run's panel: heading, axes, its laps, each direction's mean over its laps, the arrowheads.
void lap_panel(Canvas& c, const std::vector<LapDeviation>& laps, const char* name, const char* run, bool horizontal,
               double left, double top) {
  const double panel_h = 266.0, panel_w = 400.0;
  const Scale x{0.0, 360.0, left, left + panel_w};
  double max_d = 0.0;
  for (const auto& lap : laps) {
    for (const double d : lap.distance_mm) {
      max_d = std::max(max_d, d);
    }
  }
  const Scale y{0.0, svg::nice_ceiling(max_d * 1.05), top + panel_h, top};
  lap_panel_heading(c, laps, name, left, top);
  svg::value_axis(c, y, left, left + panel_w, "distance from the reference (mm)", 1.0, 46.0);
  angle_axis(c, x, top, top + panel_h, horizontal, true);
  const std::vector<LapArrow> arrows = lap_lines(c, laps, run, x, y);
  for (const bool cw : {true, false}) {
    const std::vector<double> means = sector_means(laps, cw);
    const std::string d = sector_path(means, means.size(), [&](std::size_t k, double m) {
      return std::pair{x(sector_centre_deg(k)), y(m)};
    });
    if (!d.empty()) {
      c.path(d, direction_mean_colour(cw), 2.6,
             fmt::format(R"({} class="direction-mean" data-run="{}" data-direction="{}")", direction_dash(cw), run,
                         cw ? "cw" : "ccw"));
    }
  }
  // Over every line, outlined in white, so no later lap hides an earlier one's arrow.
  for (const auto& a : arrows) {
    arrowhead(c, a.x, a.y, a.dx, 0.0, a.colour, 13.0);
  }
}

}  // namespace

std::string svg_lap_overlay(const PathPlot& plot) {
  const double width = svg::kMaxWidth, height = 530.0;
  Canvas c(width, height);
  titles(c, "Every lap: distance from the reference against the angle on the circle", plot.title);
  const std::optional<Reference> ref = reference_of(plot);
  if (!ref || !ref->closed) {
    no_data(c, !ref ? "no unloaded path to plot (fewer than 2 samples)" : "the path is not closed: no angle to plot");
    return c.str();
  }
  lap_overlay_legend(c);
  lap_panel(c, lap_deviations(plot.uc_laps, plot.uc, *ref), "UC, uncompensated", "UC", ref->horizontal, 80.0, 140.0);
  lap_panel(c, lap_deviations(plot.c_laps, plot.c, *ref), "C, compensated", "C", ref->horizontal, 590.0, 140.0);
  c.text(width / 2.0, height - 36.0,
         fmt::format("Angle: about the centre of the reference, 0 deg = the base's {} direction from the centre{}, "
                     "growing anticlockwise seen from {}.",
                     ref->horizontal ? "+x" : "+x (projected on the circle's plane)", "",
                     ref->horizontal ? "above" : "the plane's normal (n.z > 0)"),
         12.0, "middle", R"(fill="#444")");
  c.text(width / 2.0, height - 18.0,
         fmt::format("Distance: from each tracker point to the nearest point of the {}; one line per lap.",
                     ref->is_mean ? "unloaded laps' mean path (the study's reference)" : "last unloaded lap"),
         12.0, "middle", R"(fill="#444")");
  return c.str();
}

namespace {

// Each run's laps in one direction averaged in 5 deg sectors.
struct PolarCurve {
  const char* run;
  bool clockwise;
  std::string colour;
  std::vector<double> mean_mm;  // per sector, NaN when empty
};

// The curves of both runs; `max_mm` gets the largest sector mean.
std::vector<PolarCurve> polar_curves(const PathPlot& plot, const Reference& ref, double& max_mm) {
  std::vector<PolarCurve> curves;
  const std::vector<LapDeviation> runs[] = {lap_deviations(plot.uc_laps, plot.uc, ref),
                                            lap_deviations(plot.c_laps, plot.c, ref)};
  max_mm = 0.0;
  for (int r = 0; r < 2; ++r) {
    for (const bool cw : {true, false}) {
      std::vector<double> means = sector_means(runs[r], cw);
      if (means.empty()) {
        continue;
      }
      for (const double m : means) {
        if (std::isfinite(m)) {
          max_mm = std::max(max_mm, m);
        }
      }
      curves.push_back({r == 0 ? "UC" : "C", cw, r == 0 ? svg::kUcColour : svg::kCColour, std::move(means)});
    }
  }
  return curves;
}

// Legend: run by colour, direction by dash. Returns the baseline below the last row.
double polar_legend(Canvas& c, const std::vector<PolarCurve>& curves) {
  double ly = 72.0;
  for (const auto& cv : curves) {
    const std::string label = fmt::format("{}, {} laps (5 deg sector means)", cv.run, direction_name(cv.clockwise));
    c.line(40.0, ly - 4.0, 58.0, ly - 4.0, cv.colour, 2.0, direction_dash(cv.clockwise));
    c.text(64.0, ly, label, 12.0);
    ly += 18.0;
  }
  return ly;
}

// The polar frame: distance drawn outward from the 0 mm ring at r0, rings at a round step, the
// outermost the first at or beyond the largest sector mean.
struct PolarFrame {
  double cx, cy, r0, r_out;
  double ring_step = 1.0, ring_max = 1.0, px_per_mm = 1.0;
  [[nodiscard]] double radius(double mm) const { return r0 + mm * px_per_mm; }
  [[nodiscard]] std::pair<double, double> point(double deg, double mm) const {
    const double a = deg_to_rad(deg);
    return std::pair{cx + radius(mm) * std::cos(a), cy - radius(mm) * std::sin(a)};
  }
};

PolarFrame polar_frame(double cx, double cy, double max_mm) {
  PolarFrame f{cx, cy, 70.0, 165.0};
  const auto steps = svg::nice_ticks(0.0, std::max(max_mm, 1e-6) * 1.02, 3);
  f.ring_step = steps.size() > 1 ? steps[1] - steps[0] : std::max(max_mm, 1e-6);
  f.ring_max = std::max(1.0, std::ceil(max_mm * 1.02 / f.ring_step - 1e-9)) * f.ring_step;
  f.px_per_mm = (f.r_out - f.r0) / f.ring_max;
  return f;
}

// Spokes every 45 deg, labelled outside the outer ring.
void polar_spokes(Canvas& c, const PolarFrame& f, bool horizontal) {
  for (int deg = 0; deg < 360; deg += 45) {
    const auto [x0, y0] = f.point(deg, 0.0);
    const auto [x1, y1] = f.point(deg, f.ring_max);
    c.line(x0, y0, x1, y1, "#e0e0e0", 1.0);
    const double a = deg_to_rad(deg);
    const double lr = f.r_out + 12.0;
    const std::string label =
        horizontal && deg % 90 == 0 ? fmt::format("{} deg ({})", deg, compass(deg)) : fmt::format("{} deg", deg);
    const double tx = f.cx + lr * std::cos(a), ty = f.cy - lr * std::sin(a) + 4.0;
    const std::string anchor = std::abs(std::cos(a)) < 0.3 ? "middle" : std::cos(a) > 0.0 ? "start" : "end";
    c.text(tx, ty, label, kMinFont, anchor, deg == 0 ? R"(font-weight="bold")" : R"(fill="#555")");
  }
}

// Rings: the reference (0 mm) solid, the others dashed. Returns their distances (mm).
std::vector<double> polar_rings(Canvas& c, const PolarFrame& f) {
  std::vector<double> rings;
  for (int k = 0; k * f.ring_step <= f.ring_max * (1.0 + 1e-9); ++k) {
    rings.push_back(k * f.ring_step);
  }
  for (const double mm : rings) {
    c.circle(
        f.cx, f.cy, f.radius(mm), "none",
        fmt::format(R"(stroke="{}" stroke-width="{}" {} class="ring" data-mm="{:.6g}")", mm == 0.0 ? "#888" : "#bbb",
                    mm == 0.0 ? "1.5" : "1", mm == 0.0 ? "" : R"(stroke-dasharray="4 3")", mm));
  }
  return rings;
}

// Where a ring's label goes: the sector between the spokes (over the label's own width) whose nearest
// curve is the most pixels away from the ring; all else equal, nearest 112.5 deg.
double ring_label_deg(const PolarFrame& f, const std::vector<PolarCurve>& curves, double mm, double half_span_deg) {
  double best_deg = 112.5, best_clearance = -1.0;
  for (std::size_t k = 0; k < kSectors; ++k) {
    const double deg = sector_centre_deg(k);
    if (std::abs(std::remainder(deg - 22.5, 45.0)) > 12.5) {
      continue;  // between the spokes, away from their labels
    }
    double clearance = HUGE_VAL;
    for (const auto& cv : curves) {
      for (std::size_t j = 0; j < kSectors; ++j) {
        const double sector_deg = sector_centre_deg(j);
        const double m = cv.mean_mm[j];
        if (std::isfinite(m) && std::abs(std::remainder(sector_deg - deg, 360.0)) <= half_span_deg) {
          clearance = std::min(clearance, std::abs(f.radius(m) - f.radius(mm)));
        }
      }
    }
    const double score = clearance - 1e-3 * std::abs(std::remainder(deg - 112.5, 360.0));
    if (score > best_clearance) {
      best_clearance = score;
      best_deg = deg;
    }
  }
  return best_deg;
}

// Ring labels last, on a white halo, each where the curves keep farthest from it. The 0 mm ring is
// named inside, where no distance is drawn.
void polar_ring_labels(Canvas& c, const PolarFrame& f, const std::vector<PolarCurve>& curves,
                       const std::vector<double>& rings) {
  const std::string halo = R"(stroke="white" stroke-width="3" paint-order="stroke" fill="#333")";
  c.text(f.cx, f.cy - 2.0, "0 mm ring:", kMinFont, "middle", R"(class="ring-label" fill="#555")");
  c.text(f.cx, f.cy + 12.0, "the reference", kMinFont, "middle", R"(class="ring-label" fill="#555")");
  for (const double mm : rings) {
    if (mm == 0.0) {
      continue;
    }
    const std::string label = svg::tick_label(mm, f.ring_step) + " mm";
    const double half_span_deg = rad_to_deg(0.5 * svg::text_width(label, kMinFont) / f.radius(mm)) + 2.5;
    const auto [x, y] = f.point(ring_label_deg(f, curves, mm, half_span_deg), mm);
    c.text(x, y + 4.0, label, kMinFont, "middle", R"(class="ring-label" )" + halo);
  }
}

}  // namespace

std::string svg_polar_deviation(const PathPlot& plot) {
  const double width = 500.0, height = 640.0;
  Canvas c(width, height);
  titles(c, "Distance from the reference around the circle", plot.title);
  const std::optional<Reference> ref = reference_of(plot);
  if (!ref || !ref->closed) {
    no_data(c, !ref ? "no unloaded path to plot (fewer than 2 samples)" : "the path is not closed: no angle to plot");
    return c.str();
  }
  double max_mm = 0.0;
  const std::vector<PolarCurve> curves = polar_curves(plot, *ref, max_mm);
  const double ly = polar_legend(c, curves);
  const PolarFrame f = polar_frame(250.0, std::max(ly + 196.0, 340.0), max_mm);
  polar_spokes(c, f, ref->horizontal);
  const std::vector<double> rings = polar_rings(c, f);
  for (const auto& cv : curves) {
    const std::string d = sector_path(cv.mean_mm, static_cast<std::size_t>(kSectors) + 1,
                                      [&](std::size_t s, double m) { return f.point(sector_centre_deg(s), m); });
    c.path(d, cv.colour, 1.6,
           fmt::format(R"({} class="polar" data-run="{}" data-direction="{}")", direction_dash(cv.clockwise), cv.run,
                       cv.clockwise ? "cw" : "ccw"));
  }
  polar_ring_labels(c, f, curves, rings);
  c.text(f.cx, f.cy + f.r_out + 44.0, "Distance from the reference drawn outward from the 0 mm ring", 12.0, "middle",
         R"(fill="#444")");
  c.text(f.cx, f.cy + f.r_out + 60.0, fmt::format("(1 mm = {:.0f} px); angle as in the per-lap figure", f.px_per_mm),
         12.0, "middle", R"(fill="#444")");
  return c.str();
}

namespace {

// The compensated run's signed error per direction of travel (index 1: clockwise): its sector means
// (NaN where no sample fell), its mean over its samples, and the largest sector mean's size (mm).
struct SignedError {
  std::vector<double> means[2];
  double overall[2] = {kNaN, kNaN};
  double max_abs = 0.0;
};

// Each C sample's deviation projected on the UC laps' mean deviation in its sector and direction.
SignedError signed_error_of(const std::vector<DirectedLap>& c_laps, const SectorVectors& uc, const Reference& ref) {
  std::vector<double> sum[2] = {std::vector<double>(kSectors, 0.0), std::vector<double>(kSectors, 0.0)};
  std::vector<int> n[2] = {std::vector<int>(kSectors, 0), std::vector<int>(kSectors, 0)};
  for (const auto& lap : c_laps) {
    const int d = lap.clockwise ? 1 : 0;
    for (const auto& sample : lap.trace) {
      if (!sample.p_m.allFinite()) continue;
      const std::size_t s = sector_of(angle_deg(ref, sample.p_m));
      const Vector3 along = uc.mean(lap.clockwise, s);
      if (!(along.norm() > 0.0)) continue;
      const Vector3 dev = sample.p_m - ref.index->nearest(sample.p_m).point_m;
      sum[d][s] += dev.dot(along.normalized()) * 1e3;
      ++n[d][s];
    }
  }
  SignedError e;
  for (int d = 0; d < 2; ++d) {
    e.means[d].assign(kSectors, kNaN);
    double total = 0.0;
    int count = 0;
    for (std::size_t s = 0; s < kSectors; ++s) {
      if (n[d][s] == 0) continue;
      e.means[d][s] = sum[d][s] / n[d][s];
      e.max_abs = std::max(e.max_abs, std::abs(e.means[d][s]));
      total += sum[d][s];
      count += n[d][s];
    }
    if (count > 0) e.overall[d] = total / count;
  }
  return e;
}

// The legend, a row a direction with C laps; beside it UC's own size along its direction, for scale.
// Returns the baseline below the last row.
double signed_error_legend(Canvas& c, const SignedError& e, const SectorVectors& uc) {
  double uc_sum = 0.0;
  int uc_n = 0;
  for (int d = 0; d < 2; ++d) {
    for (std::size_t s = 0; s < kSectors; ++s) {
      if (uc.n[d][s] > 0) {
        uc_sum += (uc.sum[d][s] / uc.n[d][s]).norm() * 1e3;
        ++uc_n;
      }
    }
  }
  double ly = 70.0;
  for (const bool cw : {true, false}) {
    const int d = cw ? 1 : 0;
    if (!std::isfinite(e.overall[d])) continue;
    c.line(80.0, ly - 4.0, 98.0, ly - 4.0, direction_colour(cw), 2.4, direction_dash(cw));
    c.text(104.0, ly, fmt::format("C, {} laps (5 deg sector means): mean {:+.3f} mm", direction_name(cw), e.overall[d]),
           12.0);
    ly += 18.0;
  }
  if (uc_n > 0) {
    c.text(590.0, 70.0, fmt::format("for scale: the UC deflection itself, {:.3f} mm on average", uc_sum / uc_n), 12.0,
           "start", R"(fill="#444")");
  }
  return ly;
}

// The value axis about zero, its two halves shaded and named (under- and over-compensated).
void signed_error_frame(Canvas& c, const Scale& x, const Scale& y) {
  const double left = x.p0, right = x.p1, top = y.p1, bottom = y.p0;
  c.rect(left, top, right - left, y(0.0) - top, "#fdecea");
  c.rect(left, y(0.0), right - left, bottom - y(0.0), "#e8f1fb");
  svg::value_axis(c, y, left, right, "C along the UC deflection (mm)", 1.0, 56.0);
  c.line(left, y(0.0), right, y(0.0), "#444", 1.4);
  c.text(left + 8.0, top + 15.0, "+ under-compensated: still deflected the way the load pushes", 12.0, "start",
         R"(fill="#8a1c1c")");
  c.text(left + 8.0, bottom - 8.0, "- over-compensated: pushed past the unloaded path, against the load", 12.0, "start",
         R"(fill="#1c4f8a")");
}

}  // namespace

std::string svg_signed_error(const PathPlot& plot) {
  const double width = svg::kMaxWidth, height = 470.0;
  Canvas c(width, height);
  titles(c, "Signed error of the compensated run along the uncompensated deflection", plot.title);
  const std::optional<Reference> ref = reference_of(plot);
  if (!ref || !ref->closed) {
    no_data(c, !ref ? "no unloaded path to plot (fewer than 2 samples)" : "the path is not closed: no angle to plot");
    return c.str();
  }
  // The direction the load pushed the arm, per direction of travel and sector: the UC laps' mean
  // deviation there. Each C sample's deviation is projected on it.
  const SectorVectors uc = sector_vectors(laps_or_last(plot.uc_laps, plot.uc, *ref), *ref);
  const SignedError e = signed_error_of(laps_or_last(plot.c_laps, plot.c, *ref), uc, *ref);
  if (!std::isfinite(e.overall[0]) && !std::isfinite(e.overall[1])) {
    no_data(c, "no compensated lap with an uncompensated one to compare with");
    return c.str();
  }
  const double ly = signed_error_legend(c, e, uc);
  const double left = 90.0, right = width - 30.0, top = std::max(ly + 14.0, 118.0), bottom = height - 96.0;
  const double r = svg::nice_ceiling(std::max(e.max_abs, 1e-6) * 1.1);
  const Scale x{0.0, 360.0, left, right};
  const Scale y{-r, r, bottom, top};
  signed_error_frame(c, x, y);
  angle_axis(c, x, top, bottom, ref->horizontal, false);
  for (const bool cw : {true, false}) {
    const int d = cw ? 1 : 0;
    if (!std::isfinite(e.overall[d])) continue;
    const std::string path = sector_path(e.means[d], e.means[d].size(), [&](std::size_t s, double m) {
      return std::pair{x(sector_centre_deg(s)), y(m)};
    });
    c.path(path, direction_colour(cw), 2.2,
           fmt::format(R"({} class="signed-error" data-direction="{}" data-mean-mm="{:.6g}")", direction_dash(cw),
                       cw ? "cw" : "ccw", e.overall[d]));
  }
  c.text(width / 2.0, height - 18.0,
         "Each C sample's deviation from the reference projected on the UC laps' mean deviation in its 5 deg sector "
         "(same direction of travel).",
         12.0, "middle", R"(fill="#444")");
  return c.str();
}

}  // namespace deflex
