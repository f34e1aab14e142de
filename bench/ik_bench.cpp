// Inverse kinematics of the built-in IRB6700, each figure beside its anchor in the same run:
//  - every branch of a pose: deflex's opw_solutions() (2*pi turn nearest a seed inside the joint
//    limits, FK check, ABB and KUKA configuration, no heap allocation) against the bare 8-branch
//    closed form of the OPW paper written here (opw_anchor.hpp: no limits, no turns, no FK check),
//    on the same 1000 poses (the anchor gets them already in its canonical frame);
//  - one solution chosen by a seed: deflex's inverse_kinematics() against KDL's numerical solver;
//  - path IK a point: deflex's PathIkSolver along a 10,000-point circle against a loop that runs
//    the anchor on every point and keeps the branch nearest the previous point.
// Before timing, the anchor's solutions are checked against deflex's (the program aborts if they
// differ), so both sides compute the same answers.
// Run: build/bench/ik_bench --benchmark_min_time=0.5 --benchmark_repetitions=5
//      --benchmark_report_aggregates_only=true
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <vector>

#include <benchmark/benchmark.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>

#include "bench_robot.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/model/opw_ik.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/path_spec.hpp"
#include "model/kdl_chain.hpp"
#include "opw_anchor.hpp"

namespace {

using namespace deflex;

constexpr int kPathPoints = 10000;

const RobotModel& robot() { return bench::irb6700(); }

const std::vector<JointVector>& configurations() {
  static const std::vector<JointVector> qs = bench::random_configurations(1000);
  return qs;
}

[[noreturn]] void disagree(const char* what, std::size_t index) {
  std::fprintf(stderr, "ik_bench: the anchor and deflex disagree (%s, pose %zu)\n", what, index);
  std::abort();
}

/// a - b brought into (-pi, pi].
double wrapped(double a, double b) { return std::remainder(a - b, 2.0 * kPi); }

/// True when some 2*pi turn of every joint of the anchor's `q` lies inside the model's limits.
bool fits_some_turn(const std::array<double, 6>& q) {
  for (int i = 0; i < 6; ++i) {
    const double lo = robot().lower_limits()[i];
    const double hi = robot().upper_limits()[i];
    const double x = q[static_cast<std::size_t>(i)];
    if (!std::isfinite(x)) {
      return false;
    }
    const double t = x - 2.0 * kPi * std::floor((x - lo + 1e-9) / (2.0 * kPi));  // lowest turn >= lo
    if (t > hi + 1e-9) {
      return false;
    }
  }
  return true;
}

bool same_modulo_turns(const std::array<double, 6>& anchor, const JointVector& q) {
  for (int i = 0; i < 6; ++i) {
    if (!(std::abs(wrapped(anchor[static_cast<std::size_t>(i)], q[i])) < 1e-9)) {
      return false;
    }
  }
  return true;
}

/// The targets, in the robot's base frame and in the anchor's canonical frame.
struct Targets {
  std::vector<Pose> base_T_tcp;
  std::vector<Pose> opw_T_end;
};

Pose canonical(const Pose& base_T_tcp) {
  const OpwGeometry& g = *robot().opw();
  return g.opw_T_base * base_T_tcp * g.tcp_T_end;
}

/// Every solution deflex finds is one of the anchor's, and every anchor solution with a turn of
/// each joint inside the limits is one of deflex's.
void check_every_branch(const Targets& t) {
  for (std::size_t k = 0; k < t.base_T_tcp.size(); ++k) {
    OpwSolutions ours;
    opw_solutions(robot(), t.base_T_tcp[k], &configurations()[k], ours);
    bench::OpwAnchorSolutions theirs{};
    bench::opw_anchor_ik(*robot().opw(), t.opw_T_end[k], theirs);
    int fitting = 0;
    for (const auto& a : theirs) {
      if (!fits_some_turn(a)) {
        continue;
      }
      ++fitting;
      bool found = false;
      for (int s = 0; s < ours.count; ++s) {
        found = found || same_modulo_turns(a, ours.solution[static_cast<std::size_t>(s)].q);
      }
      if (!found) {
        disagree("an anchor branch deflex does not give", k);
      }
    }
    if (fitting != ours.count) {
      disagree("number of branches inside the limits", k);
    }
  }
}

const Targets& targets() {
  static const Targets t = [] {
    Targets out;
    Workspace ws(robot());
    for (const auto& q : configurations()) {
      out.base_T_tcp.push_back(tcp_pose(robot(), ws, q));
      out.opw_T_end.push_back(canonical(out.base_T_tcp.back()));
    }
    check_every_branch(out);
    return out;
  }();
  return t;
}

// The hot-path IK: every solution of one pose (up to 8 branches), each joint at the 2*pi turn
// nearest the seed inside the joint limits, every solution checked by FK, ABB and KUKA
// configuration, no heap allocation.
void BM_Deflex_OpwAllSolutions(benchmark::State& state) {
  const Targets& t = targets();
  const auto& qs = configurations();
  OpwSolutions solutions;
  std::size_t i = 0;
  int found = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % t.base_T_tcp.size();
    opw_solutions(robot(), t.base_T_tcp[k], &qs[k], solutions);
    found += solutions.count;
    benchmark::DoNotOptimize(solutions.solution[0].q.data());
  }
  state.counters["solutions_per_pose"] = benchmark::Counter(found, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_Deflex_OpwAllSolutions);

// The anchor: the paper's 8 branches of the same poses, bare.
void BM_Anchor_OpwBare8(benchmark::State& state) {
  const Targets& t = targets();
  const OpwGeometry& g = *robot().opw();
  bench::OpwAnchorSolutions q{};
  std::size_t i = 0;
  for (auto _ : state) {
    bench::opw_anchor_ik(g, t.opw_T_end[i++ % t.opw_T_end.size()], q);
    benchmark::DoNotOptimize(q.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Anchor_OpwBare8);

// One solution, chosen by a seed (the nearest of those inside the limits), with its FK error from
// the model's own FK: the general entry point.
void BM_Deflex_AnalyticIK(benchmark::State& state) {
  const Targets& t = targets();
  Workspace ws(robot());
  std::size_t i = 0;
  IkRequest req;
  for (auto _ : state) {
    const std::size_t k = i++ % t.base_T_tcp.size();
    req.seed = configurations()[k];
    const IkResult r = inverse_kinematics(robot(), ws, t.base_T_tcp[k], req);
    benchmark::DoNotOptimize(r.q.data());
  }
}
BENCHMARK(BM_Deflex_AnalyticIK);

// KDL's numerical IK (Levenberg-Marquardt) from a seed 0.05 rad off the answer on every joint, as
// along a path: one solution, no limits.
void BM_KDL_NumericIK(benchmark::State& state) {
  const KDL::Chain chain = test::kdl_chain_from_dh(robot());
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainIkSolverPos_LMA ik(chain, 1e-10, 500, 1e-15);
  std::vector<KDL::Frame> kdl_targets;
  std::vector<KDL::JntArray> seeds;
  for (const JointVector& q : configurations()) {
    KDL::JntArray k(6);
    for (unsigned j = 0; j < 6; ++j) {
      k(j) = q[static_cast<int>(j)];
    }
    KDL::Frame f;
    fk.JntToCart(k, f);
    kdl_targets.push_back(f);
    for (unsigned j = 0; j < 6; ++j) {
      k(j) += 0.05;
    }
    seeds.push_back(k);
  }
  KDL::JntArray out(6);
  std::size_t i = 0;
  int failed = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % kdl_targets.size();
    failed += ik.CartToJnt(seeds[k], kdl_targets[k], out) < 0 ? 1 : 0;
    benchmark::DoNotOptimize(out.data.data());
  }
  state.counters["failed"] = failed;
}
BENCHMARK(BM_KDL_NumericIK);

/// The reference circle with 10,000 points, tool down, its joints from deflex's path IK, and the
/// same poses in the anchor's canonical frame.
struct CircleRun {
  std::vector<Pose> base_T_tcp;
  std::vector<Pose> opw_T_end;
  JointPath path;
};

/// The anchor's path loop: every branch of each point, then the one nearest (largest joint
/// difference) the previous point's joints. Returns the index of the chosen branch.
std::size_t nearest_branch(const bench::OpwAnchorSolutions& q, const std::array<double, 6>& previous) {
  std::size_t best = 0;
  double best_step = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < 8; ++b) {
    double step = 0.0;
    for (std::size_t i = 0; i < 6; ++i) {
      step = std::max(step, std::abs(q[b][i] - previous[i]));
    }
    if (step < best_step) {  // NaN (an unreachable branch) never wins
      best_step = step;
      best = b;
    }
  }
  return best;
}

const CircleRun& circle() {
  static const CircleRun c = [] {
    CircleRun out;
    CirclePath spec = default_circle();
    spec.points = kPathPoints;
    out.base_T_tcp = sample_circle(spec, Eigen::Quaterniond(0, 0, 1, 0));
    for (const Pose& p : out.base_T_tcp) {
      out.opw_T_end.push_back(canonical(p));
    }
    out.path = solve_path_ik(robot(), out.base_T_tcp, IkRequest{});
    // The anchor's loop, started from deflex's first point, must follow the same joints.
    std::array<double, 6> previous{};
    for (int i = 0; i < 6; ++i) {
      previous[static_cast<std::size_t>(i)] = out.path.q[0][i];
    }
    bench::OpwAnchorSolutions q{};
    for (std::size_t k = 0; k < out.opw_T_end.size(); ++k) {
      bench::opw_anchor_ik(*robot().opw(), out.opw_T_end[k], q);
      previous = q[nearest_branch(q, previous)];
      for (int i = 0; i < 6; ++i) {
        if (!(std::abs(previous[static_cast<std::size_t>(i)] - out.path.q[k][i]) < 1e-9)) {
          disagree("the path's joints", k);
        }
      }
    }
    return out;
  }();
  return c;
}

// deflex's path IK a point: PathIkSolver::next (the solution nearest the previous point with the
// first point's configuration, inside the limits, FK-checked, step bound checked) round the circle.
void BM_Deflex_PathIkPoint(benchmark::State& state) {
  const CircleRun& c = circle();
  PathIkSolver solver(robot(), IkRequest{});
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(solver.next(c.base_T_tcp[i++ % c.base_T_tcp.size()]).data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Deflex_PathIkPoint);

// The anchor's path loop a point: all 8 bare branches, the nearest to the previous point kept.
void BM_Anchor_OpwNearestPathPoint(benchmark::State& state) {
  const CircleRun& c = circle();
  const OpwGeometry& g = *robot().opw();
  std::array<double, 6> previous{};
  for (int i = 0; i < 6; ++i) {
    previous[static_cast<std::size_t>(i)] = c.path.q[0][i];
  }
  bench::OpwAnchorSolutions q{};
  std::size_t i = 0;
  for (auto _ : state) {
    bench::opw_anchor_ik(g, c.opw_T_end[i++ % c.opw_T_end.size()], q);
    previous = q[nearest_branch(q, previous)];
    benchmark::DoNotOptimize(previous.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Anchor_OpwNearestPathPoint);

}  // namespace

BENCHMARK_MAIN();
