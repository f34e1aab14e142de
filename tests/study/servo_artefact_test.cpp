// The loaded runs' tracker traces carry no line at the servo's rate or its subharmonics: a force
// that depends on where the arm is, solved a tick behind the arm, rings at half the servo rate
// (period two ticks) once its loop gain passes one, and the tracker sees it. The spectrum is a
// plain DFT written here (Welch: quadratic detrend and Hann window per one-second segment, powers
// averaged over the segments and the three axes), the line's power against the median of the
// spectrum around it, which is the tracker's white noise.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "deflex/study/case_study.hpp"
#include "deflex/study/detail/simulated_run.hpp"

namespace deflex::study {
namespace {

constexpr double kTrackerHz = 1000.0;
constexpr int kSegment = 1000;  // samples: 1 Hz bins

// Power at integer-Hz bins lo..hi of one axis' samples x (Welch over kSegment-sample segments).
std::vector<double> welch_power(const std::vector<double>& x, int lo_hz, int hi_hz) {
  std::vector<double> power(static_cast<std::size_t>(hi_hz - lo_hz + 1), 0.0);
  const std::size_t segments = x.size() / kSegment;
  std::vector<double> y(kSegment);
  for (std::size_t s = 0; s < segments; ++s) {
    // Least-squares quadratic in the centred sample index, removed: the circle's own motion.
    double m[3][4] = {};
    for (int i = 0; i < kSegment; ++i) {
      const double t = (i - 0.5 * (kSegment - 1)) / kSegment;
      const double b[3] = {1.0, t, t * t};
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m[r][c] += b[r] * b[c];
        m[r][3] += b[r] * x[s * kSegment + static_cast<std::size_t>(i)];
      }
    }
    for (int p = 0; p < 3; ++p) {  // Gauss-Jordan on the 3x3 normal equations
      for (int r = 0; r < 3; ++r) {
        if (r == p) continue;
        const double f = m[r][p] / m[p][p];
        for (int c = 0; c < 4; ++c) m[r][c] -= f * m[p][c];
      }
    }
    const double a0 = m[0][3] / m[0][0], a1 = m[1][3] / m[1][1], a2 = m[2][3] / m[2][2];
    for (int i = 0; i < kSegment; ++i) {
      const double t = (i - 0.5 * (kSegment - 1)) / kSegment;
      const double hann = 0.5 - 0.5 * std::cos(2.0 * kPi * i / (kSegment - 1));
      y[static_cast<std::size_t>(i)] =
          hann * (x[s * kSegment + static_cast<std::size_t>(i)] - (a0 + a1 * t + a2 * t * t));
    }
    for (int k = lo_hz; k <= hi_hz; ++k) {
      double re = 0.0, im = 0.0;
      for (int i = 0; i < kSegment; ++i) {
        const double phase = 2.0 * kPi * k * i / kSegment;
        re += y[static_cast<std::size_t>(i)] * std::cos(phase);
        im -= y[static_cast<std::size_t>(i)] * std::sin(phase);
      }
      power[static_cast<std::size_t>(k - lo_hz)] += (re * re + im * im) / static_cast<double>(segments);
    }
  }
  return power;
}

struct Line {
  double peak;   // the largest bin within 1.5 Hz of the line
  double floor;  // the median bin 5-25 Hz either side
};

// The line at f0 (Hz) in the summed spectrum of the three axes of a trace.
Line line_at(const TrackerTrace& trace, double f0) {
  const int lo = static_cast<int>(std::floor(f0)) - 25;
  const int hi = static_cast<int>(std::ceil(f0)) + 25;
  std::vector<double> total(static_cast<std::size_t>(hi - lo + 1), 0.0);
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> x;
    x.reserve(trace.size());
    for (const auto& s : trace) x.push_back(s.p_m[axis]);
    const std::vector<double> p = welch_power(x, lo, hi);
    for (std::size_t i = 0; i < p.size(); ++i) total[i] += p[i];
  }
  Line line{0.0, 0.0};
  std::vector<double> around;
  for (int k = lo; k <= hi; ++k) {
    const double d = std::abs(k - f0);
    const double v = total[static_cast<std::size_t>(k - lo)];
    if (d <= 1.5) line.peak = std::max(line.peak, v);
    if (d >= 5.0) around.push_back(v);
  }
  std::nth_element(around.begin(), around.begin() + static_cast<std::ptrdiff_t>(around.size() / 2), around.end());
  line.floor = around[around.size() / 2];
  return line;
}

// The paper's cell with every effect, one lap at 50 mm/s, one seed.
CaseConfig one_lap_case() {
  CaseConfig c = paper_case();
  c.laps_cw = 1;
  c.laps_ccw = 0;
  c.speeds_m_s = {0.05};
  c.sweep_speeds_m_s.clear();
  c.seeds = 1;
  return c;
}

TEST(ServoArtefact, TheSelfCheckFindsALineOfAFewMicrometresInTheTrackersNoise) {
  // The measure itself: white noise of 5 um alone shows no line; a 3 um sine at 125 Hz added to it
  // stands far out. (Expected peak-to-floor ratio of the sine: A^2 N / (8 sigma^2) per axis, ~45.)
  TrackerTrace clean, ringing;
  std::uint64_t state = 12345;
  auto gauss = [&state] {  // Box-Muller on a 64-bit LCG: an independent noise source
    auto uniform = [&state] {
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      return (static_cast<double>(state >> 11) + 0.5) / 9007199254740992.0;
    };
    const double u1 = uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
  };
  for (int i = 0; i < 16000; ++i) {
    TrackerSample s;
    s.t_s = i / kTrackerHz;
    s.p_m = Vector3(5e-6 * gauss(), 5e-6 * gauss(), 5e-6 * gauss()) + Vector3(0.1 * std::sin(0.3 * s.t_s), 0, 0);
    clean.push_back(s);
    s.p_m.x() += 3e-6 * std::sin(2.0 * kPi * 125.0 * s.t_s);
    ringing.push_back(s);
  }
  const Line quiet = line_at(clean, 125.0);
  const Line loud = line_at(ringing, 125.0);
  EXPECT_LT(quiet.peak, 3.0 * quiet.floor);
  EXPECT_GT(loud.peak, 10.0 * loud.floor);
}

TEST(ServoArtefact, LoadedTracesHaveNoLineAtTheServoRateOrItsSubharmonics) {
  // The servo ticks every 4 ms (250 Hz); a force a tick behind the arm rings at 125 Hz, and longer
  // cycles of ticks at 83.3 and 62.5 Hz. The paper's highest loads, where the bar's seal is the
  // stiffest against the arm's compliance: offline uncompensated at 625 N, and with the sensor
  // mounted uncompensated and compensated online over EGM at 650 N.
  const CaseConfig c = one_lap_case();
  struct Run {
    bool sensor;
    LinkKind link;
    RunKind kind;
    double load_n;
  };
  for (const Run& run : {Run{false, LinkKind::kProgram, RunKind::kUncompensated, 625.0},
                         Run{true, LinkKind::kEgmJoint, RunKind::kUncompensated, 650.0},
                         Run{true, LinkKind::kEgmJoint, RunKind::kCompensated, 650.0}}) {
    const SetupCell cell = build_setup_cell(c, run.sensor);
    RunSpec r;
    r.kind = run.kind;
    r.strategy = Strategy::kOnline;
    if (!run.sensor) r.strategy = Strategy::kOffline;
    r.link = run.link;
    r.load_n = run.load_n;
    r.speed_m_s = 0.05;
    r.laps_cw = 1;
    r.laps_ccw = 0;
    r.seed = 7;
    const RunOutput out = simulate_run(c, cell, r);
    ASSERT_GT(out.trace.size(), static_cast<std::size_t>(10 * kSegment));
    for (const double f0 : {62.5, 250.0 / 3.0, 125.0, 250.0}) {
      const Line line = line_at(out.trace, f0);
      EXPECT_LT(line.peak, 3.0 * line.floor)
          << (run.sensor ? "sensor mounted, " : "no sensor, ") << run.load_n << " N, line at " << f0 << " Hz: peak "
          << line.peak << " against a floor of " << line.floor << " (" << line.peak / line.floor << " times)";
    }
  }
}

}  // namespace
}  // namespace deflex::study
