// Offline compensation of a 100,000-point path on the built-in IRB6700, in memory, beside its anchor:
// the loop an integrator writes with the bare OPW closed form (bench/opw_anchor.hpp: the branch
// nearest the previous point) and Orocos KDL's FK and Jacobian solvers, doing the same work a point:
// the IK of the pose, the process wrench, dtheta = K^-1 J^T W at the desired joints, the command
// q_desired - dtheta and its FK, and with prediction the two fixed points q = q_x + K^-1 J(q)^T W (the
// uncompensated deflection, the residual) with their FK; results into a buffer the caller keeps.
// Checked against deflex before timing. deflex a point: path IK (limits, turns, FK check, step
// bound) plus compensate_path, its results into a fresh OfflineResult (each call) or into one it is
// given again (compensate_path(..., out)). Targets: the compensation at most the anchor's time a
// point; 100,000 points under 100 ms.
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <vector>

#include <benchmark/benchmark.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "model/kdl_chain.hpp"
#include "opw_anchor.hpp"

namespace {

using namespace deflex;

constexpr int kPoints = 100000;
constexpr double kFixedPointTolRad = 1e-13;  // deflex's certification of a fixed point

struct LongPath {
  RobotModel model = builtin_irb6700();
  std::vector<Pose> poses;
  JointPath path;
  LdbbForceModel force{Vector3(1.5, 0.0, 0.9), 625.0, true};
  LongPath() {
    CirclePath c = default_circle();
    c.points = kPoints;
    poses = sample_circle(c, Eigen::Quaterniond(0, 0, 1, 0));
    path = solve_path_ik(model, poses, IkRequest{});
  }
};

const LongPath& long_path() {
  static const LongPath p;
  return p;
}

/// What the anchor keeps a point (its own buffer, allocated once).
struct AnchorPoint {
  std::array<double, 6> q_desired{}, q_command{};
  KDL::Frame tcp_command;
  Wrench wrench = Wrench::Zero();
  KDL::Frame deflected, residual;  // the arm's TCP loaded at q_desired and at q_command
};

/// The anchor: bare OPW (nearest branch to the previous point), then KDL for every FK and Jacobian.
class Anchor {
 public:
  explicit Anchor(const LongPath& p)
      : p_(p),
        chain_(test::kdl_chain_from_dh(p.model)),
        fk_(chain_),
        jac_(chain_),
        q_(6),
        J_(6),
        points_(p.poses.size()) {
    for (int i = 0; i < 6; ++i) c_[i] = p.model.compliance()[i];
  }
  Anchor(const Anchor&) = delete;
  Anchor& operator=(const Anchor&) = delete;

  void run(bool predict) {
    const OpwGeometry& g = *p_.model.opw();
    std::array<double, 6> previous{};
    for (int i = 0; i < 6; ++i) previous[static_cast<std::size_t>(i)] = p_.path.q[0][i];
    bench::OpwAnchorSolutions branches{};
    for (std::size_t k = 0; k < p_.poses.size(); ++k) {
      AnchorPoint& pt = points_[k];
      bench::opw_anchor_ik(g, g.opw_T_base * p_.poses[k] * g.tcp_T_end, branches);
      previous = branches[nearest(branches, previous)];
      pt.q_desired = previous;
      pt.wrench = p_.force.wrench_at(k, p_.poses[k]);
      const Vector6 dtheta = step(pt.q_desired, pt.wrench);
      for (std::size_t i = 0; i < 6; ++i) pt.q_command[i] = pt.q_desired[i] - dtheta[static_cast<int>(i)];
      fk_.JntToCart(joints(pt.q_command), pt.tcp_command);
      if (predict) {
        pt.deflected = loaded_tcp(pt.q_desired, pt.wrench);
        pt.residual = loaded_tcp(pt.q_command, pt.wrench);
      }
    }
  }

  [[nodiscard]] const std::vector<AnchorPoint>& points() const { return points_; }

 private:
  static std::size_t nearest(const bench::OpwAnchorSolutions& q, const std::array<double, 6>& previous) {
    std::size_t best = 0;
    double best_step = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < 8; ++b) {
      double s = 0.0;
      for (std::size_t i = 0; i < 6; ++i) s = std::max(s, std::abs(q[b][i] - previous[i]));
      if (s < best_step) {  // NaN (an unreachable branch) never wins
        best_step = s;
        best = b;
      }
    }
    return best;
  }

  const KDL::JntArray& joints(const std::array<double, 6>& q) {
    for (unsigned i = 0; i < 6; ++i) q_(i) = q[i];
    return q_;
  }

  /// K^-1 J(q)^T W, J by KDL (the TCP is the wrench's point on this robot).
  Vector6 step(const std::array<double, 6>& q, const Wrench& w) {
    jac_.JntToJac(joints(q), J_);
    return c_.cwiseProduct(J_.data.transpose() * w);
  }

  /// The TCP of the arm commanded to q_x under w: the fixed point q = q_x + K^-1 J(q)^T W.
  KDL::Frame loaded_tcp(const std::array<double, 6>& q_x, const Wrench& w) {
    std::array<double, 6> q = q_x;
    for (int it = 0; it < 50; ++it) {
      const Vector6 d = step(q, w);
      double change = 0.0;
      for (std::size_t i = 0; i < 6; ++i) {
        const double next = q_x[i] + d[static_cast<int>(i)];
        change = std::max(change, std::abs(next - q[i]));
        q[i] = next;
      }
      if (change < kFixedPointTolRad) break;
    }
    KDL::Frame f;
    fk_.JntToCart(joints(q), f);
    return f;
  }

  const LongPath& p_;
  KDL::Chain chain_;
  KDL::ChainFkSolverPos_recursive fk_;
  KDL::ChainJntToJacSolver jac_;
  KDL::JntArray q_;
  KDL::Jacobian J_;
  Vector6 c_;
  std::vector<AnchorPoint> points_;
};

[[noreturn]] void disagree(const char* what, std::size_t k) {
  std::fprintf(stderr, "offline_bench: the anchor and deflex disagree on %s at point %zu\n", what, k);
  std::exit(1);
}

/// The anchor does what deflex does: the same joints, commands and loaded TCPs, point by point.
void check(Anchor& anchor, const OfflineResult& ours) {
  anchor.run(true);
  for (std::size_t k = 0; k < ours.points.size(); k += 997) {
    const OfflinePoint& o = ours.points[k];
    const AnchorPoint& a = anchor.points()[k];
    for (std::size_t i = 0; i < 6; ++i) {
      if (!(std::abs(a.q_desired[i] - o.q_desired[static_cast<int>(i)]) < 1e-9)) disagree("the path's joints", k);
      if (!(std::abs(a.q_command[i] - o.q_command[static_cast<int>(i)]) < 1e-9)) disagree("the command", k);
    }
    const Vector3 loaded = o.tcp_desired.translation() + o.predicted_deflection.head<3>();
    const Vector3 kdl(a.deflected.p.x(), a.deflected.p.y(), a.deflected.p.z());
    if (!((loaded - kdl).norm() < 1e-9)) disagree("the loaded TCP", k);
    const Vector3 residual(a.residual.p.x(), a.residual.p.y(), a.residual.p.z());
    if (!((o.tcp_desired.translation() + o.predicted_residual.head<3>() - residual).norm() < 1e-9)) {
      disagree("the compensated TCP", k);
    }
  }
}

Anchor& anchor() {
  static Anchor a(long_path());  // in place: KDL's solvers keep a reference to its chain
  static const bool checked = [] {
    const LongPath& p = long_path();
    check(a, compensate_path(p.model, p.path, p.poses, p.force, OfflineOptions{}));
    return true;
  }();
  (void)checked;
  return a;
}

OfflineOptions options_of(const benchmark::State& state) {
  OfflineOptions o;
  o.predict = state.range(0) != 0;
  return o;
}

const char* label_of(const OfflineOptions& o) {
  return o.predict ? "with deflection + residual prediction" : "compensation step only";
}

void BM_PathIk100k(benchmark::State& state) {
  const LongPath& p = long_path();
  for (auto _ : state) {
    benchmark::DoNotOptimize(solve_path_ik(p.model, p.poses, IkRequest{}));
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}

// compensate_path returning a fresh OfflineResult each call (55 MB of points, new pages each time).
void BM_Compensate100k(benchmark::State& state) {
  const LongPath& p = long_path();
  const OfflineOptions options = options_of(state);
  for (auto _ : state) {
    benchmark::DoNotOptimize(compensate_path(p.model, p.path, p.poses, p.force, options));
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
  state.SetLabel(label_of(options));
}

// The same into an OfflineResult the caller keeps and gives again.
void BM_Compensate100kReused(benchmark::State& state) {
  const LongPath& p = long_path();
  const OfflineOptions options = options_of(state);
  OfflineResult out;
  for (auto _ : state) {
    compensate_path(p.model, p.path, p.poses, p.force, options, out);
    benchmark::DoNotOptimize(out.points.data());
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
  state.SetLabel(label_of(options));
}

// The whole in-memory job a point: path IK, then compensation into a kept result.
void BM_OfflineJob100k(benchmark::State& state) {
  const LongPath& p = long_path();
  const OfflineOptions options = options_of(state);
  OfflineResult out;
  for (auto _ : state) {
    const JointPath path = solve_path_ik(p.model, p.poses, IkRequest{});
    compensate_path(p.model, path, p.poses, p.force, options, out);
    benchmark::DoNotOptimize(out.points.data());
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
  state.SetLabel(label_of(options));
}

// The anchor's job a point: bare OPW IK and KDL, into its own kept buffer.
void BM_Anchor_OpwKdlJob100k(benchmark::State& state) {
  Anchor& a = anchor();
  const bool predict = state.range(0) != 0;
  for (auto _ : state) {
    a.run(predict);
    benchmark::DoNotOptimize(a.points().data());
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
  state.SetLabel(predict ? "with deflection + residual prediction" : "compensation step only");
}

}  // namespace

BENCHMARK(BM_PathIk100k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Compensate100k)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Compensate100kReused)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OfflineJob100k)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Anchor_OpwKdlJob100k)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
