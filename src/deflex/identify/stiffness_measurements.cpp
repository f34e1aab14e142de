// Reading and writing the compliance-calibration measurement CSV.
#include "deflex/identify/stiffness_measurements.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/model/csv_table.hpp"
#include "deflex/model/errors.hpp"

namespace deflex {
namespace {

// A quantity that may be given in one of two units: returns the column and its factor to SI.
struct UnitColumn {
  std::string name;
  double to_si = 1.0;
};

std::optional<UnitColumn> find_column(const CsvTable& t, const std::string& stem, const std::string& unit_a,
                                      double factor_a, const std::string& unit_b, double factor_b) {
  const std::string a = stem + "_" + unit_a;
  const std::string b = stem + "_" + unit_b;
  if (t.has(a) && t.has(b)) {
    throw DataError(fmt::format("{}: both columns '{}' and '{}' are present; keep one", t.source(), a, b));
  }
  if (t.has(a)) {
    return UnitColumn{a, factor_a};
  }
  if (t.has(b)) {
    return UnitColumn{b, factor_b};
  }
  return std::nullopt;
}

}  // namespace

std::vector<StiffnessMeasurement> read_stiffness_measurements(const std::string& csv_path) {
  const CsvTable t = CsvTable::read_file(csv_path);
  std::vector<UnitColumn> q_cols;
  for (int j = 1; j <= kMaxJoints; ++j) {
    const auto c = find_column(t, fmt::format("q{}", j), "deg", kPi / 180.0, "rad", 1.0);
    if (!c) {
      break;
    }
    q_cols.push_back(*c);
  }
  if (q_cols.empty()) {
    throw DataError(fmt::format("{}: no joint columns (expected q1_deg, q2_deg, ...; have: {})", csv_path,
                                fmt::join(t.columns(), ", ")));
  }
  t.require({"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"});
  std::vector<UnitColumn> d_cols;
  for (const char* axis : {"dx", "dy", "dz"}) {
    const auto c = find_column(t, axis, "mm", 1e-3, "m", 1.0);
    if (!c) {
      throw DataError(fmt::format("{}: missing column '{}_mm' (TCP displacement, loaded minus unloaded; have: {})",
                                  csv_path, axis, fmt::join(t.columns(), ", ")));
    }
    d_cols.push_back(*c);
  }
  const int rot_count = static_cast<int>(t.has("drx_rad")) + static_cast<int>(t.has("dry_rad")) +
                        static_cast<int>(t.has("drz_rad"));
  if (rot_count != 0 && rot_count != 3) {
    throw DataError(fmt::format("{}: give all three of drx_rad, dry_rad, drz_rad or none", csv_path));
  }
  const bool has_weight = t.has("weight");
  if (t.rows() == 0) {
    throw DataError(fmt::format("{}: no measurement rows", csv_path));
  }

  std::vector<StiffnessMeasurement> out;
  out.reserve(t.rows());
  const char* const wrench_cols[6] = {"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"};
  for (std::size_t r = 0; r < t.rows(); ++r) {
    StiffnessMeasurement m;
    m.line = t.line_of(r);
    m.q.resize(static_cast<Eigen::Index>(q_cols.size()));
    for (std::size_t j = 0; j < q_cols.size(); ++j) {
      const double v = t.at(r, q_cols[j].name) * q_cols[j].to_si;
      if (std::abs(v) > 4.0 * kPi) {
        t.fail(r, q_cols[j].name, "joint value beyond +-720 deg; check the unit");
      }
      m.q[static_cast<Eigen::Index>(j)] = v;
    }
    for (int k = 0; k < 6; ++k) {
      m.wrench_base[k] = t.at(r, wrench_cols[k]);
    }
    for (int k = 0; k < 3; ++k) {
      const UnitColumn& c = d_cols[static_cast<std::size_t>(k)];
      const double v = t.at(r, c.name) * c.to_si;
      if (std::abs(v) > 0.1) {
        t.fail(r, c.name, "displacement beyond 100 mm is not an elastic deflection; check the unit");
      }
      m.dp_m[k] = v;
    }
    if (rot_count == 3) {
      const Vector3 d(t.at(r, "drx_rad"), t.at(r, "dry_rad"), t.at(r, "drz_rad"));
      if (d.norm() > 0.1) {
        t.fail(r, "drx_rad", "orientation change beyond 0.1 rad is not an elastic deflection; check the unit");
      }
      m.drot_rad = d;
    }
    if (has_weight) {
      m.weight = t.at(r, "weight");
      if (!(m.weight > 0.0)) {
        t.fail(r, "weight", "weight must be > 0 (leave a row out to drop it)");
      }
    }
    out.push_back(std::move(m));
  }
  return out;
}

void write_stiffness_measurements(const std::string& csv_path, const std::vector<StiffnessMeasurement>& data,
                                  const std::vector<std::string>& comments) {
  const Eigen::Index n = data.empty() ? 0 : data.front().q.size();
  bool all_rot = !data.empty();
  for (const auto& m : data) {
    all_rot = all_rot && m.drot_rad.has_value();
    if (m.q.size() != n) {
      throw InputError("write_stiffness_measurements: measurements have different joint counts");
    }
  }
  std::vector<std::string> cols;
  for (Eigen::Index j = 1; j <= n; ++j) {
    cols.push_back(fmt::format("q{}_deg", j));
  }
  for (const char* c : {"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm", "dx_mm", "dy_mm", "dz_mm"}) {
    cols.emplace_back(c);
  }
  if (all_rot) {
    for (const char* c : {"drx_rad", "dry_rad", "drz_rad"}) {
      cols.emplace_back(c);
    }
  }
  cols.emplace_back("weight");
  CsvWriter w(csv_path, cols);
  for (const auto& c : comments) {
    w.comment(c);
  }
  std::vector<double> row;
  for (const auto& m : data) {
    row.clear();
    for (Eigen::Index j = 0; j < n; ++j) {
      row.push_back(rad_to_deg(m.q[j]));
    }
    for (int k = 0; k < 6; ++k) {
      row.push_back(m.wrench_base[k]);
    }
    for (int k = 0; k < 3; ++k) {
      row.push_back(m.dp_m[k] * 1e3);
    }
    if (all_rot) {
      for (int k = 0; k < 3; ++k) {
        row.push_back((*m.drot_rad)[k]);
      }
    }
    row.push_back(m.weight);
    w.row(row);
  }
  w.finish();
}

}  // namespace deflex
