// Reading and writing the compliance-calibration measurement CSV.
#include "deflex/identify/stiffness_measurements.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

// A quantity that may be given in one of two units: returns the column and its factor to SI.
std::optional<StiffnessMeasurementReader::UnitColumn> find_column(const CsvReader& t, const std::string& stem,
                                                                  const std::string& unit_a, double factor_a,
                                                                  const std::string& unit_b, double factor_b) {
  const std::string a = stem + "_" + unit_a;
  const std::string b = stem + "_" + unit_b;
  if (t.has(a) && t.has(b)) {
    throw DataError(fmt::format("{}: both columns '{}' and '{}' are present; keep one", t.source(), a, b));
  }
  if (t.has(a)) {
    return StiffnessMeasurementReader::UnitColumn{a, t.column(a), factor_a};
  }
  if (t.has(b)) {
    return StiffnessMeasurementReader::UnitColumn{b, t.column(b), factor_b};
  }
  return std::nullopt;
}

}  // namespace

StiffnessMeasurementReader::StiffnessMeasurementReader(const std::string& csv_path)
    : reader_(std::make_unique<CsvReader>(csv_path)) {
  const CsvReader& t = *reader_;
  for (int j = 1; j <= kMaxJoints; ++j) {
    const auto c = find_column(t, fmt::format("q{}", j), "deg", kPi / 180.0, "rad", 1.0);
    if (!c) {
      break;
    }
    q_cols_.push_back(*c);
  }
  if (q_cols_.empty()) {
    throw DataError(fmt::format("{}: no joint columns (expected q1_deg, q2_deg, ...; have: {})", csv_path,
                                fmt::join(t.columns(), ", ")));
  }
  t.require({"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"});
  for (const char* c : {"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"}) {
    wrench_cols_.push_back(t.column(c));
  }
  for (const char* axis : {"dx", "dy", "dz"}) {
    const auto c = find_column(t, axis, "mm", 1e-3, "m", 1.0);
    if (!c) {
      throw DataError(fmt::format("{}: missing column '{}_mm' (TCP displacement, loaded minus unloaded; have: {})",
                                  csv_path, axis, fmt::join(t.columns(), ", ")));
    }
    d_cols_.push_back(*c);
  }
  const int rot_count =
      static_cast<int>(t.has("drx_rad")) + static_cast<int>(t.has("dry_rad")) + static_cast<int>(t.has("drz_rad"));
  if (rot_count != 0 && rot_count != 3) {
    throw DataError(fmt::format("{}: give all three of drx_rad, dry_rad, drz_rad or none", csv_path));
  }
  if (rot_count == 3) {
    rot_cols_ = {t.column("drx_rad"), t.column("dry_rad"), t.column("drz_rad")};
  }
  if (t.has("weight")) {
    weight_col_ = t.column("weight");
  }
}

StiffnessMeasurementReader::~StiffnessMeasurementReader() = default;

int StiffnessMeasurementReader::joints() const { return static_cast<int>(q_cols_.size()); }

const std::string& StiffnessMeasurementReader::source() const { return reader_->source(); }

bool StiffnessMeasurementReader::next(StiffnessMeasurement& m) {
  CsvReader& t = *reader_;
  if (!t.next()) {
    if (rows_ == 0) {
      throw DataError(fmt::format("{}: no measurement rows", t.source()));
    }
    return false;
  }
  ++rows_;
  m.line = t.line();
  m.q.resize(static_cast<Eigen::Index>(q_cols_.size()));
  for (std::size_t j = 0; j < q_cols_.size(); ++j) {
    const double v = t[q_cols_[j].index] * q_cols_[j].to_si;
    if (std::abs(v) > 4.0 * kPi) {
      t.fail(q_cols_[j].name, "joint value beyond +-720 deg; check the unit");
    }
    m.q[static_cast<Eigen::Index>(j)] = v;
  }
  for (int k = 0; k < 6; ++k) {
    m.wrench_base[k] = t[wrench_cols_[static_cast<std::size_t>(k)]];
  }
  for (int k = 0; k < 3; ++k) {
    const UnitColumn& c = d_cols_[static_cast<std::size_t>(k)];
    const double v = t[c.index] * c.to_si;
    if (std::abs(v) > 0.1) {
      t.fail(c.name, "displacement beyond 100 mm is not an elastic deflection; check the unit");
    }
    m.dp_m[k] = v;
  }
  m.drot_rad.reset();
  if (!rot_cols_.empty()) {
    const Vector3 d(t[rot_cols_[0]], t[rot_cols_[1]], t[rot_cols_[2]]);
    if (d.norm() > 0.1) {
      t.fail("drx_rad", "orientation change beyond 0.1 rad is not an elastic deflection; check the unit");
    }
    m.drot_rad = d;
  }
  m.weight = 1.0;
  if (weight_col_) {
    m.weight = t[*weight_col_];
    if (!(m.weight > 0.0)) {
      t.fail("weight", "weight must be > 0 (leave a row out to drop it)");
    }
  }
  return true;
}

std::vector<StiffnessMeasurement> read_stiffness_measurements(const std::string& csv_path) {
  StiffnessMeasurementReader reader(csv_path);
  std::vector<StiffnessMeasurement> out;
  for (StiffnessMeasurement m; reader.next(m);) {
    out.push_back(m);
  }
  return out;
}

void write_stiffness_measurements(const std::string& csv_path, const std::vector<StiffnessMeasurement>& data,
                                  const std::vector<std::string>& comments) {
  OutputFile out(csv_path, "measurement file");
  write_stiffness_measurements(out, data, comments);
  out.commit();
}

void write_stiffness_measurements(OutputFile& out, const std::vector<StiffnessMeasurement>& data,
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
  CsvWriter w(out, cols);
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
