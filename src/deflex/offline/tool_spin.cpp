// The spindle's free angle along a toolpath: the spin reference, and the choice for stiffness.
#include "deflex/offline/tool_spin.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "deflex/model/opw_ik.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/key_value_spec.hpp"

namespace deflex {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Costed per step of the grid the angle takes between two stages (m, against sums of deflections of
// about 1e-4 m a point): breaks ties towards holding the angle, never outweighs a deflection.
constexpr double kChangePenalty = 1e-12;
// The workpiece's x counts as along the tool axis when it lies within this of it (sin of ~8 deg).
constexpr double kReferenceMinSine = 0.14;

Vector3 unit_normal_part(const Vector3& v, const Vector3& axis) {
  const Vector3 n = v - axis.dot(v) * axis;
  return n / n.norm();
}

double wrap_angle(double a) { return std::remainder(a, 2.0 * kPi); }

}  // namespace

Matrix3 tcp_rotation(const Vector3& tool_axis, const Vector3& reference_x, double spin_rad) {
  const Vector3 z = -tool_axis;
  const Vector3 y0 = z.cross(reference_x);
  const double c = std::cos(spin_rad), s = std::sin(spin_rad);
  Matrix3 r;
  r.col(0) = c * reference_x + s * y0;
  r.col(1) = z.cross(Vector3(r.col(0)));
  r.col(2) = z;
  return r;
}

const Vector3& SpinReference::next(const Vector3& tool_axis) {
  if (!started_) {
    const Vector3 x = Vector3::UnitX();
    const bool along = x.cross(tool_axis).norm() < kReferenceMinSine;
    x_ = unit_normal_part(along ? Vector3::UnitY() : x, tool_axis);
    started_ = true;
  } else {
    // The smallest rotation taking the last axis to this one, applied to the reference; then made
    // exactly normal to the axis again (rounding).
    const Vector3 k = axis_.cross(tool_axis);
    const double c = axis_.dot(tool_axis), s = k.norm();
    if (s > 1e-15) {
      const Vector3 u = k / s;
      x_ = c * x_ + s * u.cross(x_) + (1.0 - c) * u.dot(x_) * u;
    }
    x_ = unit_normal_part(x_, tool_axis);
  }
  axis_ = tool_axis;
  return x_;
}

ToolSpinOptions parse_tool_spin_spec(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string kind = trim_blanks(spec.substr(0, colon));
  const std::string body = colon == std::string::npos ? "" : spec.substr(colon + 1);
  ToolSpinOptions o;
  if (kind == "fixed") {
    const KeyValueSpec check(spec, "deg=" + body, {"deg"});
    const double deg = check.number("deg", 0.0);
    if (trim_blanks(body).empty() || !(std::abs(deg) <= 360.0)) {
      check.fail("give the spin angle in degrees, -360..360: fixed:DEG");
    }
    o.optimize = false;
    o.fixed_rad = deg_to_rad(deg);
    return o;
  }
  if (kind != "optimize") {
    throw InputError(
        fmt::format("tool spin '{}': use optimize[:step_deg=..,rate_deg_per_mm=..,...] or fixed:DEG", spec));
  }
  const KeyValueSpec keys(spec, body,
                          {"step_deg", "rate_deg_per_mm", "limit_margin_deg", "singularity_floor", "lag_stages"});
  const auto in = [&](const char* key, double fallback, double lo, double hi, const char* unit) {
    const double v = keys.number(key, fallback);
    if (!(v >= lo && v <= hi))
      keys.fail(fmt::format("key '{}': {:g}{} is outside {:g}..{:g}{}", key, v, unit, lo, hi, unit));
    return v;
  };
  const double step = in("step_deg", 10.0, 2.0, 60.0, " deg");
  if (std::abs(360.0 / step - std::round(360.0 / step)) > 1e-9) {
    keys.fail(fmt::format("key 'step_deg': {:g} deg does not divide 360 deg", step));
  }
  o.grid_step_rad = deg_to_rad(step);
  o.max_rate_rad_per_m = deg_to_rad(in("rate_deg_per_mm", 1.0, 0.01, 100.0, " deg/mm")) * 1e3;
  o.joint_limit_margin_rad = deg_to_rad(in("limit_margin_deg", 5.0, 0.0, 30.0, " deg"));
  o.singularity_floor = in("singularity_floor", 0.1, 0.0, 0.5, "");
  o.lag_stages = static_cast<std::size_t>(keys.integer("lag_stages", 50));
  if (o.lag_stages < 1 || o.lag_stages > 1000) keys.fail("key 'lag_stages': must be 1..1000");
  return o;
}

std::string describe_tool_spin(const ToolSpinOptions& o) {
  if (!o.optimize) return fmt::format("fixed at {:g} deg", rad_to_deg(o.fixed_rad));
  return fmt::format(
      "optimised for stiffness: candidates every {:g} deg, at most {:g} deg per mm of path, {:g} deg from the joint "
      "limits, singularity floor {:g}, decided {} stages ({:g} mm) behind",
      rad_to_deg(o.grid_step_rad), rad_to_deg(o.max_rate_rad_per_m) * 1e-3, rad_to_deg(o.joint_limit_margin_rad),
      o.singularity_floor, o.lag_stages, o.stage_spacing_m() * 1e3 * static_cast<double>(o.lag_stages));
}

struct ToolSpinPlanner::Impl {
  // The planner's own types: nested, since Impl (a member of a class in a header) may not hold types of
  // the anonymous namespace.
  using Compliance36 = Eigen::Matrix<double, 3, 6>;

  /// Why a candidate angle is out at a stage.
  enum class Reason : int { kUnreachable, kConfiguration, kLimits, kSingular, kCount };

  struct Candidate {
    Compliance36 a = Compliance36::Zero();  // translational deflection per wrench about the TCP: J_p K^-1 J^T T
    bool feasible = false;
  };

  struct Stage {
    double s = 0.0;  // effective path length, m
    bool stay_only = false;
    std::size_t line = 0;
    std::vector<Candidate> c;
    std::vector<std::int8_t> back;  // the best predecessor's grid offset (-1, 0, 1) of each state
    int decided = -1;
  };

  struct Held {
    SpinPoint p;
    double s = 0.0;
  };

  const RobotModel& model;
  ToolSpinOptions o;
  IkRequest first;
  int grid = 1;
  std::vector<double> angles;  // rad, -pi..pi
  std::vector<int> order;      // the grid by |angle|: ties go to the smaller spin
  Workspace ws;
  Jacobian j_tcp, j_wap;
  OpwSolutions solutions;
  ArmConfiguration configuration;
  bool have_configuration = false;
  unsigned arm = kOpwAllArms;
  std::vector<JointVector> seed;
  std::vector<bool> seeded;
  JointVector first_q;
  std::vector<JointVector> first_stage_q;  // the first stage's solutions, until it is decided
  std::deque<Stage> stages;
  std::size_t stage_base = 0;  // index of stages.front()
  std::size_t decided = 0;     // stages decided: 0..decided-1
  std::deque<Held> points;     // not emitted yet
  std::size_t costed = 0;      // points at the front of `points` already costed into a stage
  std::deque<double> ready;
  std::vector<double> d, d_next, s0, s1, norms;
  std::vector<int> root;
  Eigen::Matrix<double, Eigen::Dynamic, 6> stacked;  // every candidate's compliance, 3 rows each
  Eigen::VectorXd deflections;
  std::array<std::size_t, static_cast<std::size_t>(Reason::kCount)> reasons{};
  std::optional<Held> last;
  double last_stage_s = 0.0;
  ToolSpinStats stats;

  Impl(const RobotModel& m, const ToolSpinOptions& options, const IkRequest& request)
      : model(m), o(options), first(request), ws(m), j_tcp(6, m.dof()), j_wap(6, m.dof()) {
    check_options();
    if (o.optimize) {
      grid = static_cast<int>(std::lround(2.0 * kPi / o.grid_step_rad));
      for (int g = 0; g < grid; ++g) angles.push_back(wrap_angle(g * o.grid_step_rad));
    } else {
      angles.push_back(wrap_angle(o.fixed_rad));
    }
    for (int g = 0; g < grid; ++g) order.push_back(g);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return std::abs(angles[static_cast<std::size_t>(a)]) < std::abs(angles[static_cast<std::size_t>(b)]) - 1e-12;
    });
    seed.assign(static_cast<std::size_t>(grid), JointVector::Zero(m.dof()));
    seeded.assign(static_cast<std::size_t>(grid), false);
    d.assign(static_cast<std::size_t>(grid), kInfinity);
    d_next = s0 = s1 = norms = d;
    root.assign(index(grid), 0);
    stacked.setZero(rows_of(grid), 6);
    deflections.setZero(rows_of(grid));
  }

  void check_options() const {
    const double step = o.grid_step_rad;
    if (!(step >= deg_to_rad(2.0) - 1e-12 && step <= deg_to_rad(60.0) + 1e-12) ||
        std::abs(2.0 * kPi / step - std::round(2.0 * kPi / step)) > 1e-9) {
      throw InputError(fmt::format("tool spin: the grid step must divide 360 deg and be 2..60 deg (got {:g} deg)",
                                   rad_to_deg(step)));
    }
    if (!(o.max_rate_rad_per_m > 0.0) || !std::isfinite(o.max_rate_rad_per_m) || !(o.move_counted_max_m > 0.0) ||
        !(o.joint_limit_margin_rad >= 0.0) || !(o.singularity_floor >= 0.0) || o.lag_stages < 1 ||
        o.max_buffered_points < 2 || !std::isfinite(o.fixed_rad)) {
      throw InputError("tool spin: options out of range (rate, counted move, margin, floor, lag, buffer, angle)");
    }
  }

  [[nodiscard]] std::size_t index(int g) const { return static_cast<std::size_t>(g); }
  /// The first of candidate g's three rows in the stacked compliances.
  [[nodiscard]] static Eigen::Index rows_of(int g) { return 3 * static_cast<Eigen::Index>(g); }
  /// A grid index one step past either end, back on the circle (no division: it runs a few thousand
  /// times a stage).
  [[nodiscard]] int wrap_state(int g) const { return g < 0 ? g + grid : g >= grid ? g - grid : g; }
  [[nodiscard]] Stage& stage(std::size_t k) { return stages[k - stage_base]; }
  [[nodiscard]] std::size_t newest() const { return stage_base + stages.size() - 1; }

  Pose candidate_pose(const Vector3& tip, const Vector3& axis, const Vector3& ref, int g) const {
    Pose t = Pose::Identity();
    t.linear() = tcp_rotation(axis, ref, angles[index(g)]);
    t.translation() = tip;
    return t;
  }

  void choose_configuration(const Held& h) {
    if (first.configuration) {
      configuration = *first.configuration;
    } else {
      IkResult r;
      for (const int g : order) {
        r = inverse_kinematics(model, ws, candidate_pose(h.p.tip_m, h.p.tool_axis, h.p.reference_x, g), first);
        if (r.ok() && r.status == IkStatus::kOk) break;
      }
      if (!r.ok() || r.status != IkStatus::kOk) {
        const std::string angles_text = o.optimize
                                            ? fmt::format("any of the {} spindle angles", grid)
                                            : fmt::format("the spindle angle {:g} deg", rad_to_deg(angles.front()));
        throw InputError(fmt::format("line {}: the arm cannot reach the toolpath's first point at {} ({}: {})",
                                     h.p.line, angles_text, to_string(r.status), r.message));
      }
      configuration = r.configuration;
    }
    have_configuration = true;
    if (const OpwGeometry* geometry = model.opw(); geometry != nullptr && o.singularity_floor >= 1e-6) {
      arm = opw_arm_of_configuration(*geometry, configuration.cfx);
    }
  }

  /// The joints of candidate g at pose t in the path's configuration, nearest the candidate's seed.
  bool solve(const Pose& t, int g, JointVector& q, Reason& why) {
    const JointVector* near = seeded[index(g)] ? &seed[index(g)] : (first.seed ? &*first.seed : nullptr);
    if (model.opw() == nullptr) {
      IkRequest r;
      r.configuration = configuration;
      r.match_quadrants = false;
      if (near != nullptr) r.seed = *near;
      r.near_singular_threshold = std::max(o.singularity_floor, 1e-6);
      const IkResult res = inverse_kinematics(model, ws, t, r);
      why = res.status == IkStatus::kNearSingular         ? Reason::kSingular
            : res.status == IkStatus::kOutsideJointLimits ? Reason::kLimits
                                                          : Reason::kUnreachable;
      if (res.status != IkStatus::kOk) return false;
      q = res.q;
      return true;
    }
    opw_solutions(model, t, near, solutions, std::max(o.singularity_floor, 1e-6), arm);
    int best = -1;
    double best_step = kInfinity;
    for (int k = 0; k < solutions.count; ++k) {
      const OpwSolution& sol = solutions.solution[static_cast<std::size_t>(k)];
      if (sol.configuration.cfx != configuration.cfx) continue;
      double step = 0.0;
      if (near != nullptr) {
        for (int j = 0; j < 6; ++j) step = std::max(step, std::abs(sol.q[j] - (*near)[j]));
      }
      if (step < best_step) {
        best_step = step;
        best = k;
      }
    }
    if (best < 0) {
      why = solutions.status == IkStatus::kUnreachable          ? Reason::kUnreachable
            : solutions.status == IkStatus::kOutsideJointLimits ? Reason::kLimits
                                                                : Reason::kConfiguration;
      return false;
    }
    const OpwSolution& sol = solutions.solution[static_cast<std::size_t>(best)];
    if (sol.singularity != Singularity::kNone) {
      why = Reason::kSingular;
      return false;
    }
    q = sol.q;
    return true;
  }

  /// Candidate g at a stage: feasible, and its compliance.
  void evaluate(const Pose& t, int g, Candidate& out) {
    ++stats.candidate_solves;
    out.feasible = false;
    JointVector q(model.dof());
    Reason why = Reason::kUnreachable;
    if (!solve(t, g, q, why)) {
      ++reasons[static_cast<std::size_t>(why)];
      return;
    }
    const double m = o.joint_limit_margin_rad;
    for (int j = 0; j < model.dof(); ++j) {
      const double lo = model.lower_limits()[j], hi = model.upper_limits()[j];
      if (hi - lo > 2.0 * m && (q[j] < lo + m || q[j] > hi - m)) {
        ++reasons[static_cast<std::size_t>(Reason::kLimits)];
        return;
      }
    }
    seed[index(g)] = q;
    seeded[index(g)] = true;
    forward_kinematics(model, ws, q);
    point_jacobian(ws, ws.base_T_tcp.translation(), j_tcp);
    const Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, kMaxJoints> b =
        j_tcp.topRows<3>() * model.compliance().asDiagonal();
    if (model.wap_is_tcp()) {
      out.a = b * j_tcp.transpose();
    } else {
      point_jacobian(ws, ws.base_T_wap.translation(), j_wap);
      out.a = b * j_wap.transpose();
      // The wrench is about the TCP; the model takes it about the WAP: M_wap = M + (p_tcp - p_wap) x F.
      const Vector3 r = ws.base_T_tcp.translation() - ws.base_T_wap.translation();
      Matrix3 skew;
      skew << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
      out.a.leftCols<3>() += out.a.rightCols<3>() * skew;
    }
    out.feasible = true;
  }

  std::string reasons_text() const {
    static const char* const kNames[] = {"unreachable", "no solution in the path's arm configuration",
                                         "within the margin of a joint limit", "near a singularity"};
    std::string s;
    for (std::size_t k = 0; k < reasons.size(); ++k) {
      if (reasons[k] == 0) continue;
      s += fmt::format("{}{} {}", s.empty() ? "" : ", ", reasons[k], kNames[k]);
    }
    return s;
  }

  /// A new stage at effective length s with the geometry of the point `at` (tip, axis, reference).
  void add_stage(double s, const SpinPoint& at, bool stay_only) {
    Stage st;
    st.s = s;
    st.stay_only = stay_only;
    st.line = at.line;
    st.c.resize(index(grid));
    st.back.assign(index(grid), 0);
    reasons.fill(0);
    bool any = false;
    for (int g = 0; g < grid; ++g) {
      evaluate(candidate_pose(at.tip_m, at.tool_axis, at.reference_x, g), g, st.c[index(g)]);
      any = any || st.c[index(g)].feasible;
    }
    ++stats.stages;
    last_stage_s = s;
    if (!o.optimize) {
      if (!any && stats.margin_violations++ == 0) stats.first_margin_violation_line = at.line;
      return;
    }
    if (!any) {
      throw InputError(fmt::format(
          "line {}: the arm cannot reach the toolpath at any of the {} spindle angles (every {:g} deg) in its arm "
          "configuration [cfx {}] with {:g} deg from the joint limits and singularity floor {:g}: {}",
          at.line, grid, rad_to_deg(o.grid_step_rad), configuration.cfx, rad_to_deg(o.joint_limit_margin_rad),
          o.singularity_floor, reasons_text()));
    }
    if (stages.empty()) {
      for (int g = 0; g < grid; ++g) d[index(g)] = st.c[index(g)].feasible ? 0.0 : kInfinity;
      first_stage_q = seed;
      stages.push_back(std::move(st));
      return;
    }
    cost_interval(stages.back(), st);
    step_dp(stages.back(), st);
    stages.push_back(std::move(st));
    while (newest() >= decided + o.lag_stages) decide(decided);
  }

  /// S0, S1 of the points between the last stage and `next`: sums of each candidate's deflection, and
  /// of it weighted by the point's place u (0..1) in the interval, for the interpolated angle.
  /// The compliance is taken at the interval's middle (the mean of its two stages'): over one stage
  /// spacing it changes by well under a percent, and one product a point serves every candidate.
  void cost_interval(const Stage& prev, const Stage& next) {
    std::fill(s0.begin(), s0.end(), 0.0);
    std::fill(s1.begin(), s1.end(), 0.0);
    for (int g = 0; g < grid; ++g) {
      const Candidate &c0 = prev.c[index(g)], &c1 = next.c[index(g)];
      stacked.middleRows<3>(rows_of(g)) =
          c0.feasible && c1.feasible ? Compliance36(0.5 * (c0.a + c1.a)) : Compliance36::Zero();
    }
    const double length = next.s - prev.s;
    Wrench wrench = Wrench::Constant(std::numeric_limits<double>::quiet_NaN());
    for (; costed < points.size() && points[costed].s <= next.s; ++costed) {
      const Held& h = points[costed];
      if (!h.p.cutting) continue;
      const double u = length > 0.0 ? (h.s - prev.s) / length : 1.0;
      if (h.p.wrench != wrench) {
        wrench = h.p.wrench;
        deflections.noalias() = stacked * wrench;
        for (int g = 0; g < grid; ++g) norms[index(g)] = deflections.segment<3>(rows_of(g)).norm();
      }
      for (int g = 0; g < grid; ++g) {
        s0[index(g)] += norms[index(g)];
        s1[index(g)] += u * norms[index(g)];
      }
    }
  }

  void step_dp(const Stage& prev, Stage& next) {
    bool any = false;
    for (int b = 0; b < grid; ++b) {
      double best = kInfinity;
      std::int8_t back = 0;
      const bool b_ok = prev.c[index(b)].feasible && next.c[index(b)].feasible;
      for (const int offset : {0, -1, 1}) {
        if (!b_ok || (offset != 0 && (next.stay_only || grid < 3))) continue;
        const int a = wrap_state(b + offset);
        if (!(d[index(a)] < kInfinity) || !prev.c[index(a)].feasible || !next.c[index(a)].feasible) continue;
        const double c =
            d[index(a)] + s0[index(a)] - s1[index(a)] + s1[index(b)] + (offset != 0 ? kChangePenalty : 0.0);
        if (c < best) {
          best = c;
          back = static_cast<std::int8_t>(offset);
        }
      }
      d_next[index(b)] = best;
      next.back[index(b)] = back;
      any = any || best < kInfinity;
    }
    if (!any) {
      throw InputError(fmt::format(
          "line {}: no spindle angle reachable from the angles before it within {:g} deg per mm keeps the arm {:g} "
          "deg from its joint limits and above singularity floor {:g}",
          next.line, rad_to_deg(o.max_rate_rad_per_m) * 1e-3, rad_to_deg(o.joint_limit_margin_rad),
          o.singularity_floor));
    }
    std::swap(d, d_next);
  }

  int best_state() const {
    int best = -1;
    for (const int g : order) {
      if (d[index(g)] < kInfinity && (best < 0 || d[index(g)] < d[index(best)])) best = g;
    }
    return best;
  }

  /// The state at stage k of the path ending in each state of the newest stage (all traced at once).
  void ancestors(std::size_t k) {
    for (int g = 0; g < grid; ++g) root[index(g)] = g;
    for (std::size_t j = newest(); j > k; --j) {
      const std::vector<std::int8_t>& back = stage(j).back;
      for (int& r : root) r = wrap_state(r + back[index(r)]);
    }
  }

  /// Decides stage k (every stage before it is decided): the best path's state there; paths through
  /// other states are dropped, and the points up to it get their angles.
  void decide(std::size_t k) {
    ancestors(k);
    const int c = root[index(best_state())];
    for (int g = 0; g < grid; ++g) {
      if (root[index(g)] != c) d[index(g)] = kInfinity;
    }
    Stage& st = stage(k);
    st.decided = c;
    double from = angles[index(c)], turn = 0.0, s_from = st.s, length = 0.0;
    if (k > 0) {
      const Stage& prev = stage(k - 1);
      from = angles[index(prev.decided)];
      turn = -st.back[index(c)] * o.grid_step_rad;
      s_from = prev.s;
      length = st.s - prev.s;
    } else {
      first_q = first_stage_q[index(c)];
      first_stage_q.clear();
    }
    while (!points.empty() && points.front().s <= st.s) {
      const double u = length > 0.0 ? (points.front().s - s_from) / length : 1.0;
      ready.push_back(wrap_angle(from + u * turn));
      points.pop_front();
      costed = costed > 0 ? costed - 1 : 0;
    }
    decided = k + 1;
    while (stage_base + 1 < decided) {
      stages.pop_front();
      ++stage_base;
    }
  }

  void push(const SpinPoint& p) {
    Held h{p, 0.0};
    if (last) h.s = last->s + std::min(p.move_m, o.move_counted_max_m);
    if (!have_configuration) choose_configuration(h);
    if (!last) {
      add_stage(0.0, p, false);
      if (!o.optimize && seeded[0]) first_q = seed[0];
    } else {
      add_stages_up_to(h);
    }
    last = h;
    if (!o.optimize) {
      ready.push_back(wrap_angle(o.fixed_rad));
      return;
    }
    points.push_back(h);
    if (points.size() > o.max_buffered_points) {
      // A stage here, the angle held across it, and everything decided: the buffer empties.
      ++stats.forced_stages;
      add_stage(h.s, p, true);
      while (decided <= newest()) decide(decided);
    }
  }

  /// Stages every stage spacing from the last one up to the point h, on the move from the last point.
  void add_stages_up_to(const Held& h) {
    const double spacing = o.stage_spacing_m();
    while (true) {
      const double s = last_stage_s + spacing;
      if (s > h.s) break;
      const double f = h.s > last->s ? (s - last->s) / (h.s - last->s) : 1.0;
      SpinPoint at = h.p;
      at.tip_m = last->p.tip_m + f * (h.p.tip_m - last->p.tip_m);
      at.tool_axis = (last->p.tool_axis + f * (h.p.tool_axis - last->p.tool_axis)).normalized();
      at.reference_x =
          unit_normal_part(last->p.reference_x + f * (h.p.reference_x - last->p.reference_x), at.tool_axis);
      // Optimised, the points between the last stage and this one are in the buffer (h is not yet).
      add_stage(s, at, false);
    }
  }

  void finish() {
    if (!last) return;
    if (o.optimize) {
      if (!points.empty() && points.back().s > stages.back().s) add_stage(points.back().s, points.back().p, true);
      while (decided <= newest()) decide(decided);
    }
  }
};

ToolSpinPlanner::ToolSpinPlanner(const RobotModel& model, const ToolSpinOptions& options, const IkRequest& first)
    : impl_(std::make_unique<Impl>(model, options, first)) {}

ToolSpinPlanner::~ToolSpinPlanner() = default;

void ToolSpinPlanner::push(const SpinPoint& point) { impl_->push(point); }

void ToolSpinPlanner::finish() { impl_->finish(); }

bool ToolSpinPlanner::pop(double& spin_rad) {
  if (impl_->ready.empty()) return false;
  spin_rad = impl_->ready.front();
  impl_->ready.pop_front();
  return true;
}

IkRequest ToolSpinPlanner::path_request() const {
  IkRequest r = impl_->first;
  r.configuration = impl_->configuration;
  r.match_quadrants = false;
  if (impl_->first_q.size() == impl_->model.dof()) r.seed = impl_->first_q;
  return r;
}

const ToolSpinStats& ToolSpinPlanner::stats() const { return impl_->stats; }

}  // namespace deflex
