// Payload (mass, centre of gravity) and bias identification from static poses.
#include "deflex/identify/payload_identification.hpp"

#include <cmath>

#include <fmt/format.h>
#include <Eigen/Dense>

#include "deflex/model/kinematics.hpp"
#include "deflex/model/linear_algebra.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

namespace {

Matrix3 skew(const Vector3& v) {
  Matrix3 s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

struct Solved {
  Eigen::VectorXd x;
  double rms = 0.0;
  double condition = 0.0;
};

Solved solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, const char* what) {
  const Svd svd(A);
  const Eigen::VectorXd& s = svd.values();
  Solved r;
  r.condition = s(s.size() - 1) > 0.0 ? s(0) / s(s.size() - 1) : std::numeric_limits<double>::infinity();
  if (!(r.condition < 1e8)) {
    throw InputError(
        fmt::format("payload identification: the poses do not excite every {} unknown (condition number {:.3g}); "
                    "use orientations that turn the sensor about at least two different axes",
                    what, r.condition));
  }
  r.x = svd.solve(b);
  r.rms = std::sqrt((A * r.x - b).squaredNorm() / static_cast<double>(b.size()));
  return r;
}

}  // namespace

PayloadEstimate identify_payload(const std::vector<PayloadObservation>& poses, bool use_moments,
                                 const Vector3& gravity_base_m_s2) {
  const auto m = static_cast<Eigen::Index>(poses.size());
  if (m < 3) {
    throw InputError(fmt::format("payload identification needs at least 3 static poses (got {})", m));
  }
  if (!gravity_base_m_s2.allFinite() || gravity_base_m_s2.norm() < 1e-6) {
    throw InputError("payload identification: gravity vector must be finite and non-zero");
  }
  Eigen::MatrixXd Af(3 * m, 4), At(3 * m, 6);
  Eigen::VectorXd bf(3 * m), bt(3 * m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const PayloadObservation& o = poses[static_cast<std::size_t>(i)];
    if (!o.base_R_sensor.allFinite() || !o.wrench_sensor.allFinite()) {
      throw InputError(fmt::format("payload identification: pose {} has non-finite values", i + 1));
    }
    const Vector3 g_sensor = o.base_R_sensor.transpose() * gravity_base_m_s2;
    Af.block<3, 1>(3 * i, 0) = g_sensor;
    Af.block<3, 3>(3 * i, 1).setIdentity();
    bf.segment<3>(3 * i) = o.wrench_sensor.head<3>();
    At.block<3, 3>(3 * i, 0) = -skew(g_sensor);
    At.block<3, 3>(3 * i, 3).setIdentity();
    bt.segment<3>(3 * i) = o.wrench_sensor.tail<3>();
  }
  PayloadEstimate e;
  e.poses = static_cast<int>(m);
  const Solved f = solve(Af, bf, "force");
  e.mass_kg = f.x(0);
  e.bias_sensor.head<3>() = f.x.segment<3>(1);
  e.force_residual_rms_N = f.rms;
  e.force_condition_number = f.condition;
  if (e.mass_kg < 0.0) {
    throw InputError(
        fmt::format("payload identification: the mass comes out negative ({:.4g} kg): check the force sign and the "
                    "orientation columns",
                    e.mass_kg));
  }
  if (use_moments) {
    const Solved t = solve(At, bt, "moment");
    e.moments_used = true;
    const Vector3 mc = t.x.head<3>();
    e.cog_sensor_m = e.mass_kg > 1e-9 ? Vector3(mc / e.mass_kg) : Vector3::Zero();
    e.bias_sensor.tail<3>() = t.x.tail<3>();
    e.moment_residual_rms_Nm = t.rms;
    e.moment_condition_number = t.condition;
  }
  return e;
}

std::vector<PayloadObservation> read_payload_observations(const std::string& csv_path, const RobotModel* model,
                                                          const Pose& flange_T_sensor, const Matrix6& crosstalk,
                                                          bool& has_moments) {
  const CsvTable t = CsvTable::read_file(csv_path);
  t.require({"fx_N", "fy_N", "fz_N"});
  has_moments = t.has("mx_Nm") || t.has("my_Nm") || t.has("mz_Nm");
  if (has_moments) {
    t.require({"mx_Nm", "my_Nm", "mz_Nm"});
  }
  const bool quaternion = t.has("qw");
  if (!quaternion && !t.has("q1_deg")) {
    throw DataError(csv_path +
                    ": no orientation columns: give the sensor orientation as qw,qx,qy,qz (base_R_sensor) "
                    "or the robot joints as q1_deg..qN_deg");
  }
  if (quaternion) {
    t.require({"qw", "qx", "qy", "qz"});
  } else {
    if (model == nullptr) {
      throw DataError(csv_path + ": orientation columns missing: give qw,qx,qy,qz or joints q1_deg..qN_deg");
    }
    std::vector<std::string> cols;
    for (int j = 1; j <= model->dof(); ++j) {
      cols.push_back(fmt::format("q{}_deg", j));
    }
    t.require(cols);
  }
  std::unique_ptr<Workspace> ws;
  if (!quaternion) {
    ws = std::make_unique<Workspace>(*model);
  }
  std::vector<PayloadObservation> out;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    PayloadObservation o;
    Vector6 raw = Vector6::Zero();
    raw << t.at(r, "fx_N"), t.at(r, "fy_N"), t.at(r, "fz_N"), 0.0, 0.0, 0.0;
    if (has_moments) {
      raw.tail<3>() << t.at(r, "mx_Nm"), t.at(r, "my_Nm"), t.at(r, "mz_Nm");
    }
    o.wrench_sensor = crosstalk * raw;
    if (!has_moments) {
      o.wrench_sensor.tail<3>().setZero();
    }
    if (quaternion) {
      Eigen::Quaterniond q(t.at(r, "qw"), t.at(r, "qx"), t.at(r, "qy"), t.at(r, "qz"));
      if (std::abs(q.norm() - 1.0) > 1e-3) {
        t.fail(r, "qw", fmt::format("quaternion is not unit (norm {:.6f})", q.norm()));
      }
      o.base_R_sensor = q.normalized().toRotationMatrix();
    } else {
      JointVector q(model->dof());
      for (int j = 0; j < model->dof(); ++j) {
        q[j] = deg_to_rad(t.at(r, fmt::format("q{}_deg", j + 1)));
      }
      forward_kinematics(*model, *ws, q);
      o.base_R_sensor = ws->base_T_flange.linear() * flange_T_sensor.linear();
    }
    out.push_back(o);
  }
  // Checked here as well as in identify_payload(), so that the message names the file.
  if (out.size() < 3) {
    throw DataError(fmt::format("{}: {} static pose{}; payload identification needs at least 3", csv_path, out.size(),
                                out.size() == 1 ? "" : "s"));
  }
  return out;
}

}  // namespace deflex
