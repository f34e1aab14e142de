// Model hot paths against KDL on the same 1000 IRB6700 configurations:
// FK, FK + Jacobian and the full deflection (FK + J + dtheta = K^-1 J^T W). Inverse kinematics is
// in ik_bench.cpp.
// Run: build/bench/model_bench --benchmark_min_time=1
#include <vector>

#include <benchmark/benchmark.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "bench_robot.hpp"
#include "deflex/model/compliance.hpp"
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

}  // namespace

BENCHMARK_MAIN();
