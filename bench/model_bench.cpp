// Model hot paths against KDL on the same 1000 IRB6700 configurations:
// FK, FK + Jacobian, the full deflection (FK + J + dtheta = K^-1 J^T W), and inverse kinematics
// (every analytic solution of a pose against KDL's numerical Levenberg-Marquardt solver).
// Run: build/bench/model_bench --benchmark_min_time=1
#include <vector>

#include <benchmark/benchmark.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "bench_robot.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/model/opw_ik.hpp"
#include "deflex/model/robot_io.hpp"
#include "model/kdl_chain.hpp"

namespace {

using namespace deflex;

const RobotModel& robot() { return bench::irb6700(); }

const std::vector<JointVector>& configurations() {
  static const std::vector<JointVector> qs = bench::random_configurations(1000);
  return qs;
}

std::vector<KDL::JntArray> kdl_configurations() {
  std::vector<KDL::JntArray> out;
  for (const auto& q : configurations()) {
    KDL::JntArray k(6);
    for (int i = 0; i < 6; ++i) {
      k(static_cast<unsigned>(i)) = q[i];
    }
    out.push_back(k);
  }
  return out;
}

void BM_Deflex_FK(benchmark::State& state) {
  Workspace ws(robot());
  const auto& qs = configurations();
  std::size_t i = 0;
  for (auto _ : state) {
    forward_kinematics(robot(), ws, qs[i++ % qs.size()]);
    benchmark::DoNotOptimize(ws.base_T_tcp);
  }
}
BENCHMARK(BM_Deflex_FK);

void BM_KDL_FK(benchmark::State& state) {
  const KDL::Chain chain = test::kdl_chain_from_dh(robot());
  KDL::ChainFkSolverPos_recursive fk(chain);
  const auto qs = kdl_configurations();
  KDL::Frame f;
  std::size_t i = 0;
  for (auto _ : state) {
    fk.JntToCart(qs[i++ % qs.size()], f);
    benchmark::DoNotOptimize(f);
  }
}
BENCHMARK(BM_KDL_FK);

void BM_Deflex_FK_Jacobian(benchmark::State& state) {
  Workspace ws(robot());
  Jacobian J(6, 6);
  const auto& qs = configurations();
  std::size_t i = 0;
  for (auto _ : state) {
    jacobian(robot(), ws, qs[i++ % qs.size()], EndPoint::kTcp, J);
    benchmark::DoNotOptimize(J.data());
    benchmark::DoNotOptimize(ws.base_T_tcp);
  }
}
BENCHMARK(BM_Deflex_FK_Jacobian);

void BM_KDL_FK_Jacobian(benchmark::State& state) {
  const KDL::Chain chain = test::kdl_chain_from_dh(robot());
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainJntToJacSolver jac(chain);
  const auto qs = kdl_configurations();
  KDL::Frame f;
  KDL::Jacobian J(6);
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& q = qs[i++ % qs.size()];
    fk.JntToCart(q, f);
    jac.JntToJac(q, J);
    benchmark::DoNotOptimize(f);
    benchmark::DoNotOptimize(J.data.data());
  }
}
BENCHMARK(BM_KDL_FK_Jacobian);

void BM_Deflex_FullDeflection(benchmark::State& state) {
  Workspace ws(robot());
  JointVector dtheta(6);
  Wrench w;
  w << 400.0, -300.0, -650.0, 0.0, 0.0, 0.0;
  const auto& qs = configurations();
  std::size_t i = 0;
  for (auto _ : state) {
    joint_deflection(robot(), ws, qs[i++ % qs.size()], w, dtheta);
    benchmark::DoNotOptimize(dtheta.data());
  }
}
BENCHMARK(BM_Deflex_FullDeflection);

void BM_KDL_FullDeflection(benchmark::State& state) {
  // The same computation with KDL's solvers, for reference: FK, J, then K^-1 J^T W.
  const KDL::Chain chain = test::kdl_chain_from_dh(robot());
  KDL::ChainJntToJacSolver jac(chain);
  const auto qs = kdl_configurations();
  KDL::Jacobian J(6);
  Eigen::Matrix<double, 6, 1> w;
  w << 400.0, -300.0, -650.0, 0.0, 0.0, 0.0;
  Eigen::Matrix<double, 6, 1> c = robot().compliance();
  Eigen::Matrix<double, 6, 1> dtheta;
  std::size_t i = 0;
  for (auto _ : state) {
    jac.JntToJac(qs[i++ % qs.size()], J);
    dtheta = c.cwiseProduct(J.data.transpose() * w);
    benchmark::DoNotOptimize(dtheta.data());
  }
}
BENCHMARK(BM_KDL_FullDeflection);

void BM_Deflex_CompensatedConfiguration(benchmark::State& state) {
  Workspace ws(robot());
  JointVector q_cmd(6);
  Wrench w;
  w << 400.0, -300.0, -650.0, 0.0, 0.0, 0.0;
  const auto& qs = configurations();
  std::size_t i = 0;
  for (auto _ : state) {
    compensated_configuration(robot(), ws, qs[i++ % qs.size()], w, q_cmd);
    benchmark::DoNotOptimize(q_cmd.data());
  }
}
BENCHMARK(BM_Deflex_CompensatedConfiguration);

void BM_Deflex_AnalyticIK(benchmark::State& state) {
  Workspace ws(robot());
  std::vector<Pose> targets;
  for (const auto& q : configurations()) {
    targets.push_back(tcp_pose(robot(), ws, q));
  }
  std::size_t i = 0;
  for (auto _ : state) {
    IkRequest req;
    req.seed = configurations()[i % targets.size()];
    const IkResult r = inverse_kinematics(robot(), ws, targets[i++ % targets.size()], req);
    benchmark::DoNotOptimize(r.q.data());
  }
}
BENCHMARK(BM_Deflex_AnalyticIK);

std::vector<Pose> tcp_targets() {
  Workspace ws(robot());
  std::vector<Pose> targets;
  for (const auto& q : configurations()) {
    targets.push_back(tcp_pose(robot(), ws, q));
  }
  return targets;
}

// The hot-path IK: every solution of one pose (up to 8 branches), each joint at the 2*pi turn
// nearest the seed inside the joint limits, every solution checked by FK, ABB and KUKA
// configuration, no heap allocation.
void BM_Deflex_OpwAllSolutions(benchmark::State& state) {
  const std::vector<Pose> targets = tcp_targets();
  const auto& qs = configurations();
  OpwSolutions solutions;
  std::size_t i = 0;
  int found = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % targets.size();
    opw_solutions(robot(), targets[k], &qs[k], solutions);
    found += solutions.count;
    benchmark::DoNotOptimize(solutions.solution[0].q.data());
  }
  state.counters["solutions_per_pose"] = benchmark::Counter(found, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_Deflex_OpwAllSolutions);

// KDL's numerical IK (Levenberg-Marquardt) from a seed 0.05 rad off the answer on every joint, as
// along a path: one solution, no limits.
void BM_KDL_NumericIK(benchmark::State& state) {
  const KDL::Chain chain = test::kdl_chain_from_dh(robot());
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainIkSolverPos_LMA ik(chain, 1e-10, 500, 1e-15);
  const auto qs = kdl_configurations();
  std::vector<KDL::Frame> targets(qs.size());
  std::vector<KDL::JntArray> seeds;
  for (std::size_t k = 0; k < qs.size(); ++k) {
    fk.JntToCart(qs[k], targets[k]);
    KDL::JntArray seed = qs[k];
    for (unsigned j = 0; j < 6; ++j) {
      seed(j) += 0.05;
    }
    seeds.push_back(seed);
  }
  KDL::JntArray out(6);
  std::size_t i = 0;
  int failed = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % targets.size();
    failed += ik.CartToJnt(seeds[k], targets[k], out) < 0 ? 1 : 0;
    benchmark::DoNotOptimize(out.data.data());
  }
  state.counters["failed"] = failed;
}
BENCHMARK(BM_KDL_NumericIK);

}  // namespace

BENCHMARK_MAIN();
