// A synthetic case study with the shape of the paper's (two setups, three loads, three speeds, a
// hybrid row and a speed sweep) and synthetic circle traces, to exercise the report.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>

#include "deflex/report/html_report.hpp"

namespace deflex::test {

/// Three seeds' values around `mean`: mean * (1 - f, 1 + 0.2 f, 1 + 0.8 f). Their mean is `mean`;
/// their range, mean * (1 - f) to mean * (1 + 0.8 f), is not mean +- their standard deviation
/// (0.917 mean f), so a figure that drew one for the other would show it.
inline std::vector<double> three_seeds(double mean, double f) {
  return {mean * (1.0 - f), mean * (1.0 + 0.2 * f), mean * (1.0 + 0.8 * f)};
}

inline StudyResult synthetic_study() {
  StudyResult s;
  s.case_name = "synthetic";
  s.seed = 11;
  s.seeds = {11, 12, 13};
  s.speeds_mm_s = {10, 30, 50};
  const double offline_loads[] = {125, 375, 625};
  const double online_loads[] = {150, 400, 650};
  const char* const names[] = {"offline", "online", "hybrid"};
  for (int k = 0; k < 3; ++k) {
    SetupResult su;
    su.setup = names[k];
    su.description = k == 0 ? "force model only, no sensor" : k == 1 ? "force sensor, 100 ms cycle" : "model + sensor";
    for (int i = 0; i < 3; ++i) {
      LoadResult l;
      l.load_N = k == 0 ? offline_loads[i] : online_loads[i];
      for (const int v : {10, 30, 50}) {
        const double uc = (k == 0 ? 0.00098 : 0.0017) * l.load_N * (1.0 + 0.002 * v);
        l.uc_mm[v] = uc;
        l.c_mm[v] = uc * (k == 0 ? 0.34 : k == 1 ? 0.27 - 0.02 * i : 0.12);
        // Per seed: C spreads 10-20%, UC 4%; the lag the time-synchronous error sees grows with speed.
        l.uc_mm_by_seed[v] = three_seeds(uc, 0.04);
        l.c_mm_by_seed[v] = three_seeds(l.c_mm[v], 0.1 + 0.002 * v);
        l.uc_sync_mm[v] = uc * 1.05;
        l.c_sync_mm[v] = l.c_mm[v] + 0.004 * v;
        l.uc_sync_mm_by_seed[v] = three_seeds(l.uc_sync_mm[v], 0.04);
        l.c_sync_mm_by_seed[v] = three_seeds(l.c_sync_mm[v], 0.1);
        l.iso_accuracy_uc_mm[v] = uc * 1.4;
        l.iso_accuracy_c_mm[v] = l.c_mm[v] * 1.5;
        l.iso_repeatability_mm[v] = 0.03;
      }
      l.fill_compensation();
      su.loads.push_back(l);
    }
    s.setups.push_back(su);
  }
  for (const double v : {10.0, 30.0, 50.0, 100.0, 150.0, 200.0}) {
    const double uc = 1.12 + 0.0004 * v;  // the UC rises a little with speed (servo lag)
    const double c_on = 0.24 + 0.0025 * v;
    const double c_lat = 0.22 + 0.0004 * v;
    for (const auto& [name, c] : {std::pair<const char*, double>{"online", c_on}, {"online-latency-comp", c_lat}}) {
      SweepPoint p;
      p.setup = name;
      p.load_N = 650;
      p.speed_mm_s = v;
      p.uc_mm = uc;
      p.c_mm = c;
      p.compensation = 1.0 - c / uc;
      p.c_sync_mm = c + 0.003 * v;
      p.uc_mm_by_seed = three_seeds(uc, 0.03);
      p.c_mm_by_seed = three_seeds(c, 0.12);
      p.c_sync_mm_by_seed = three_seeds(p.c_sync_mm, 0.08);
      s.speed_sweep.push_back(p);
    }
  }
  return s;
}

/// Unloaded circle (r 100 mm, centre (1.8, 0, 1.0) m) and loaded paths deflected by a field that
/// turns with the TCP (as the LDBB's bar does): UC by `uc_mm`, C by `c_mm`, plus tracker noise.
inline PathPlot synthetic_path_plot(double uc_mm, double c_mm, unsigned seed) {
  PathPlot p;
  p.title = "online, 650 N, 30 mm/s";
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 5e-6);
  const Vector3 centre(1.8, 0.0, 1.0);
  const int n = 6000;
  for (int i = 0; i <= n; ++i) {
    const double a = 2.0 * kPi * i / n;
    const Vector3 radial(std::cos(a), std::sin(a), 0.0);
    const Vector3 on = centre + 0.1 * radial;
    const Vector3 field = (0.8 * radial + Vector3(0.2, 0.1, 0.55) * std::cos(a - 0.4)).normalized();
    const Vector3 jitter(noise(rng), noise(rng), noise(rng));
    p.unloaded.push_back({i * 1e-3, on + jitter});
    p.uc.push_back({i * 1e-3, on + uc_mm * 1e-3 * field * (0.8 + 0.2 * std::sin(2 * a)) + jitter});
    p.c.push_back({i * 1e-3, on + c_mm * 1e-3 * field * (0.5 + 0.5 * std::sin(3 * a)) + jitter});
  }
  // The reference (the unloaded laps' mean: here the noise-free circle) and the laps: the traces
  // above run anticlockwise (the angle grows); the same points reversed make a clockwise lap.
  for (int i = 0; i <= n; i += 4) {
    const double a = 2.0 * kPi * i / n;
    p.unloaded_mean.push_back({i * 1e-3, centre + 0.1 * Vector3(std::cos(a), std::sin(a), 0.0)});
  }
  auto reversed = [](TrackerTrace t) {
    std::reverse(t.begin(), t.end());
    return t;
  };
  p.uc_laps = {{p.uc, false}, {reversed(p.uc), true}};
  p.c_laps = {{p.c, false}, {reversed(p.c), true}};
  return p;
}

/// A horizontal circle of 100 mm radius around (1.8, 0, 1.0) m, as a lap of `n` samples displaced
/// radially by `radial_mm(angle_rad)`, run anticlockwise (seen from above) or clockwise.
template <class F>
TrackerTrace circle_lap(F radial_mm, bool clockwise, int n = 720) {
  TrackerTrace t;
  const Vector3 centre(1.8, 0.0, 1.0);
  for (int i = 0; i <= n; ++i) {
    const double a = (clockwise ? -1.0 : 1.0) * 2.0 * kPi * i / n + 0.3;  // starts at 17 deg, not at 0
    const Vector3 radial(std::cos(a), std::sin(a), 0.0);
    t.push_back({i * 1e-2, centre + (0.1 + radial_mm(a) * 1e-3) * radial});
  }
  return t;
}

/// Laps with known deviations: UC 2 clockwise laps at 0.5 mm and 2 anticlockwise at 0.3 mm, the
/// first clockwise one with a bump to 0.8 mm around 90 deg; C one lap each way at 0.1 and 0.06 mm.
inline PathPlot synthetic_lap_plot() {
  PathPlot p;
  p.title = "synthetic laps";
  auto constant = [](double mm) { return [mm](double) { return mm; }; };
  p.unloaded_mean = circle_lap(constant(0.0), false, 3600);
  p.unloaded = p.unloaded_mean;
  auto bump = [](double a) {
    const double d = std::remainder(a - kPi / 2.0, 2.0 * kPi);
    return 0.5 + 0.3 * std::exp(-d * d / (2.0 * 0.05 * 0.05));
  };
  p.uc_laps = {{circle_lap(bump, true), true},
               {circle_lap(constant(0.5), true), true},
               {circle_lap(constant(0.3), false), false},
               {circle_lap(constant(0.3), false), false}};
  p.c_laps = {{circle_lap(constant(0.1), true), true}, {circle_lap(constant(0.06), false), false}};
  p.uc = p.uc_laps.back().trace;
  p.c = p.c_laps.back().trace;
  return p;
}

inline ReportContent synthetic_report() {
  ReportContent r;
  r.title = "deflex case study (synthetic data for the report's tests)";
  r.setup_paragraphs = {"Synthetic figures shaped like the paper's: not a simulation result.",
                        "Robot: ABB IRB 6700; circle of 100 mm radius; LDBB loads 125-650 N & speeds 10-50 mm/s."};
  r.study = synthetic_study();
  r.path_plots.push_back(synthetic_path_plot(1.1, 0.22, 3));
  ErrorBudget b;
  b.setup = "online";
  b.load_N = 650;
  b.speed_mm_s = 30;
  b.residual_mm_all = 0.20;
  b.uc_mm = 1.1;
  b.entries = {{"force sensor compliance <unmodelled>", "40 N/mm", 0.12, one_at_a_time_sensitivity(0.20, 0.12)},
               {"lost motion", "0.02 mrad per joint", 0.17, one_at_a_time_sensitivity(0.20, 0.17)},
               {"tracker noise", "5 um 1-sigma", 0.195, one_at_a_time_sensitivity(0.20, 0.195)},
               {"LDBB ripple", "1 % at 2 Hz", 0.2004, one_at_a_time_sensitivity(0.20, 0.2004)}};
  b.residual_mm_all_off = 0.05;
  r.study.error_budgets.push_back(b);
  r.notes = {"Our online UC at 150 N is 14% above the paper's: the sensor compliance is a guess."};
  r.case_text = "case: synthetic\nseed: 11\n";
  return r;
}

}  // namespace deflex::test
