// Model hot paths against their anchors on the same 1000 IRB6700 configurations: FK against KDL and
// the OPW closed form (opw_forward, the arm's seven lengths); FK + Jacobian against KDL and a plain
// scalar walk of the same DH table written here (standard sin/cos, one 4x4 DH step a joint as
// textbooks write it); the full deflection (FK + J + dtheta = K^-1 J^T W) against KDL. Every anchor is
// checked against deflex before anything is timed. Inverse kinematics is in ik_bench.cpp.
// Run: build/bench/model_bench --benchmark_min_time=1
#include <array>
#include <cmath>
#include <cstdlib>
#include <vector>

#include <benchmark/benchmark.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "bench_robot.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/opw_geometry.hpp"
#include "deflex/robotfile/robot_io.hpp"
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

// The plain anchor: T_i = T_{i-1} Rz(q_i + offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i) with the C library's
// sin and cos, R and p as scalars, then J from the joint axes and origins. Standard DH only.
struct PlainDhAnchor {
  explicit PlainDhAnchor(const RobotModel& m) : rows(m.description().dh), tool(m.description().flange_T_tcp) {}
  std::vector<DhRow> rows;
  Pose tool;
  double R[3][3], p[3];
  double z[6][3], o[6][3];
  double J[6][6];

  void run(const JointVector& q) {
    double r[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, t[3] = {0, 0, 0};
    for (std::size_t i = 0; i < rows.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        z[i][k] = r[k][2];
        o[i][k] = t[k];
      }
      const double th = q[static_cast<int>(i)] + rows[i].theta_offset_rad;
      const double ct = std::cos(th), st = std::sin(th), ca = std::cos(rows[i].alpha_rad),
                   sa = std::sin(rows[i].alpha_rad);
      // The DH step's rotation and translation, then r <- r * step.
      const double a[3][3] = {{ct, -st * ca, st * sa}, {st, ct * ca, -ct * sa}, {0, sa, ca}};
      const double d[3] = {rows[i].a_m * ct, rows[i].a_m * st, rows[i].d_m};
      double nr[3][3];
      for (int u = 0; u < 3; ++u) {
        t[u] += r[u][0] * d[0] + r[u][1] * d[1] + r[u][2] * d[2];
        for (int v = 0; v < 3; ++v) nr[u][v] = r[u][0] * a[0][v] + r[u][1] * a[1][v] + r[u][2] * a[2][v];
      }
      for (int u = 0; u < 3; ++u) {
        for (int v = 0; v < 3; ++v) r[u][v] = nr[u][v];
      }
    }
    const Vector3 tt = tool.translation();
    for (int u = 0; u < 3; ++u) {
      p[u] = t[u] + r[u][0] * tt[0] + r[u][1] * tt[1] + r[u][2] * tt[2];
      for (int v = 0; v < 3; ++v) R[u][v] = r[u][v];  // the tool has no rotation here
    }
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const double dx = p[0] - o[i][0], dy = p[1] - o[i][1], dz = p[2] - o[i][2];
      J[0][i] = z[i][1] * dz - z[i][2] * dy;
      J[1][i] = z[i][2] * dx - z[i][0] * dz;
      J[2][i] = z[i][0] * dy - z[i][1] * dx;
      J[3][i] = z[i][0];
      J[4][i] = z[i][1];
      J[5][i] = z[i][2];
    }
  }
};

// Aborts unless the anchors give deflex's poses and Jacobians (1e-12) on every configuration.
void check_anchors() {
  static const bool checked = [] {
    Workspace ws(robot());
    Jacobian J(6, 6);
    PlainDhAnchor plain(robot());
    const OpwGeometry& g = *robot().opw();
    for (const auto& q : configurations()) {
      jacobian(robot(), ws, q, EndPoint::kTcp, J);
      plain.run(q);
      for (int u = 0; u < 3; ++u) {
        if (std::abs(plain.p[u] - ws.base_T_tcp.translation()[u]) > 1e-12) std::abort();
        for (int v = 0; v < 3; ++v) {
          if (std::abs(plain.R[u][v] - ws.base_T_tcp.linear()(u, v)) > 1e-12) std::abort();
        }
      }
      for (int u = 0; u < 6; ++u) {
        for (int v = 0; v < 6; ++v) {
          if (std::abs(plain.J[u][v] - J(u, v)) > 1e-12) std::abort();
        }
      }
      std::array<double, 6> theta{};
      for (int i = 0; i < 6; ++i) theta[static_cast<std::size_t>(i)] = g.theta(i, q[i]);
      const Pose flange = g.chain_T_opw * opw_forward(g, theta) * g.end_T_flange;
      if (!flange.isApprox(ws.base_T_flange, 1e-12)) std::abort();
    }
    return true;
  }();
  (void)checked;
}

void BM_Deflex_FK(benchmark::State& state) {
  check_anchors();
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

// The OPW closed form's forward kinematics of the same configurations (canonical angles made once).
void BM_Anchor_OpwClosedFormFK(benchmark::State& state) {
  check_anchors();
  const OpwGeometry& g = *robot().opw();
  std::vector<std::array<double, 6>> thetas;
  for (const auto& q : configurations()) {
    std::array<double, 6> theta{};
    for (int i = 0; i < 6; ++i) theta[static_cast<std::size_t>(i)] = g.theta(i, q[i]);
    thetas.push_back(theta);
  }
  std::size_t i = 0;
  for (auto _ : state) {
    Pose p = opw_forward(g, thetas[i++ % thetas.size()]);
    benchmark::DoNotOptimize(p);
  }
}
BENCHMARK(BM_Anchor_OpwClosedFormFK);

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

void BM_Anchor_PlainDhFK_Jacobian(benchmark::State& state) {
  check_anchors();
  PlainDhAnchor plain(robot());
  const auto& qs = configurations();
  std::size_t i = 0;
  for (auto _ : state) {
    plain.run(qs[i++ % qs.size()]);
    benchmark::DoNotOptimize(plain.J);
    benchmark::DoNotOptimize(plain.p);
  }
}
BENCHMARK(BM_Anchor_PlainDhFK_Jacobian);

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
