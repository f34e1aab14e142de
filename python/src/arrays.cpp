// Array checks and conversions of the deflex module (see arrays.hpp).
#include "arrays.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/paths/circle_path.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::python {
namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) {
    s += fmt::format("{}{}", i ? ", " : "", a.shape(i));
  }
  return s + (a.ndim() == 1 ? ",)" : ")");
}

[[noreturn]] void wrong_shape(const Array& a, const char* name, const std::string& expected) {
  throw InputError(fmt::format("argument {}: expected shape {}, got {}", name, expected, shape_text(a)));
}

}  // namespace

Array to_array(const py::handle& obj, const char* name, int ndim) {
  if (obj.is_none()) {
    throw InputError(fmt::format("argument {}: expected an array of numbers, got None", name));
  }
  py::array any = py::array::ensure(obj);
  if (!any) {
    throw InputError(fmt::format("argument {}: expected an array of numbers, got {}", name,
                                 py::str(py::type::of(obj).attr("__name__")).cast<std::string>()));
  }
  const char kind = any.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u') {
    throw InputError(fmt::format("argument {}: expected real numbers (float64), got dtype {}", name,
                                 py::str(any.dtype()).cast<std::string>()));
  }
  Array a = Array::ensure(any);
  if (!a) {
    throw InputError(fmt::format("argument {}: cannot convert to float64", name));
  }
  if (ndim > 0 && a.ndim() != ndim) {
    throw InputError(
        fmt::format("argument {}: expected a {}-dimensional array, got shape {}", name, ndim, shape_text(a)));
  }
  return a;
}

void require_finite(const Array& a, const char* name) {
  const double* d = a.data();
  const py::ssize_t n = a.size();
  for (py::ssize_t i = 0; i < n; ++i) {
    if (std::isfinite(d[i])) continue;
    if (a.ndim() >= 2) {
      const py::ssize_t row_size = n / a.shape(0);
      throw InputError(fmt::format("argument {}: row {} has a non-finite value ({} at column {})", name, i / row_size,
                                   d[i], i % row_size));
    }
    throw InputError(fmt::format("argument {}: element {} is not finite ({})", name, i, d[i]));
  }
}

void require_in_ranges(const Array& a, const char* name, std::initializer_list<const InputRange*> columns) {
  const double* d = a.data();
  const py::ssize_t n = a.size();
  const py::ssize_t width = a.ndim() == 0 ? 1 : a.shape(a.ndim() - 1);
  for (py::ssize_t i = 0; i < n; ++i) {
    const py::ssize_t column = width > 0 ? i % width : 0;
    const InputRange& r =
        *(columns.size() == 1 ? *columns.begin() : *(columns.begin() + static_cast<std::ptrdiff_t>(column)));
    if (const auto bad = range_violation(d[i], r)) {
      if (a.ndim() >= 2) {
        throw InputError(fmt::format("argument {}: row {}, column {}: {}", name, i / width, column, *bad));
      }
      throw InputError(fmt::format("argument {}: element {}: {}", name, i, *bad));
    }
  }
}

Array vector_array(const py::handle& obj, const char* name, py::ssize_t n) {
  Array a = to_array(obj, name);
  if (a.ndim() != 1 || a.shape(0) != n) wrong_shape(a, name, fmt::format("({},)", n));
  require_finite(a, name);
  return a;
}

Array matrix_array(const py::handle& obj, const char* name, py::ssize_t rows, py::ssize_t cols) {
  Array a = to_array(obj, name);
  if (a.ndim() != 2 || a.shape(1) != cols || (rows >= 0 && a.shape(0) != rows)) {
    wrong_shape(a, name, rows >= 0 ? fmt::format("({}, {})", rows, cols) : fmt::format("(N, {})", cols));
  }
  require_finite(a, name);
  return a;
}

Array single_or_batch(const py::handle& obj, const char* name, py::ssize_t n, bool& batch) {
  Array a = to_array(obj, name);
  batch = a.ndim() == 2;
  if (!((a.ndim() == 1 && a.shape(0) == n) || (batch && a.shape(1) == n))) {
    wrong_shape(a, name, fmt::format("({},) or (N, {})", n, n));
  }
  require_finite(a, name);
  return a;
}

JointVector joint_vector(const py::handle& obj, const char* name, int dof) {
  const Array a = vector_array(obj, name, dof);
  require_in_ranges(a, name, {&range::kAngleRad});
  return Eigen::Map<const Eigen::VectorXd>(a.data(), dof);
}

Array joint_rows(const py::handle& obj, const char* name, int dof, bool& batch) {
  Array a = single_or_batch(obj, name, dof, batch);
  require_in_ranges(a, name, {&range::kAngleRad});
  return a;
}

namespace {
const std::initializer_list<const InputRange*> kWrenchRanges = {
    &range::kForceN, &range::kForceN, &range::kForceN, &range::kMomentNm, &range::kMomentNm, &range::kMomentNm};
}  // namespace

Vector6 wrench_vector(const py::handle& obj, const char* name) {
  const Array a = vector_array(obj, name, 6);
  require_in_ranges(a, name, kWrenchRanges);
  return Eigen::Map<const Vector6>(a.data());
}

Array wrench_rows(const py::handle& obj, const char* name, bool& batch) {
  Array a = single_or_batch(obj, name, 6, batch);
  require_in_ranges(a, name, kWrenchRanges);
  return a;
}

Vector3 vector3(const py::handle& obj, const char* name) {
  return Eigen::Map<const Vector3>(vector_array(obj, name, 3).data());
}

Vector6 vector6(const py::handle& obj, const char* name) {
  return Eigen::Map<const Vector6>(vector_array(obj, name, 6).data());
}

Eigen::Quaterniond unit_quaternion(const py::handle& obj, const char* name) {
  const Array q = vector_array(obj, name, 4);
  return checked_unit_quaternion(Eigen::Quaterniond(q.data()[0], q.data()[1], q.data()[2], q.data()[3]),
                                 (std::string("argument ") + name).c_str());
}

namespace {

Pose pose_at(const double* d, const char* name, const std::string& where) {
  const Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>> m(d);
  const Matrix3 r = m.topLeftCorner<3, 3>();
  if ((r * r.transpose() - Matrix3::Identity()).norm() > 1e-6 || r.determinant() < 0.0) {
    throw InputError(fmt::format("argument {}{}: the top-left 3x3 block is not a rotation matrix", name, where));
  }
  if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0) {
    throw InputError(
        fmt::format("argument {}{}: the last row of a homogeneous transform must be 0 0 0 1", name, where));
  }
  Pose p = Pose::Identity();
  p.linear() = r;
  p.translation() = m.topRightCorner<3, 1>();
  return p;
}

}  // namespace

Pose pose(const py::handle& obj, const char* name) {
  Array a = to_array(obj, name);
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) wrong_shape(a, name, "(4, 4)");
  require_finite(a, name);
  return pose_at(a.data(), name, "");
}

std::vector<Pose> poses(const py::handle& obj, const char* name) {
  Array a = to_array(obj, name);
  if (a.ndim() == 2) return {pose(a, name)};
  if (a.ndim() != 3 || a.shape(1) != 4 || a.shape(2) != 4) wrong_shape(a, name, "(N, 4, 4)");
  require_finite(a, name);
  std::vector<Pose> out;
  out.reserve(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    out.push_back(pose_at(a.data() + 16 * i, name, fmt::format(" [{}]", i)));
  }
  return out;
}

TrackerTrace tracker_trace(const py::handle& obj, const char* name) {
  Array a = to_array(obj, name);
  if (a.ndim() != 2 || (a.shape(1) != 3 && a.shape(1) != 4)) wrong_shape(a, name, "(N, 3) or (N, 4)");
  require_finite(a, name);
  const bool timed = a.shape(1) == 4;
  TrackerTrace t(static_cast<std::size_t>(a.shape(0)));
  const double* d = a.data();
  for (std::size_t i = 0; i < t.size(); ++i) {
    t[i].t_s = timed ? *d++ : static_cast<double>(i);
    t[i].p_m = Vector3(d[0], d[1], d[2]);
    if (t[i].p_m.cwiseAbs().maxCoeff() > range::kLengthM.max) {
      throw InputError(
          fmt::format("argument {}: row {}: a position of {:g} is beyond {:g} m: positions are in m (a "
                      "trace in mm divided by 1000)",
                      name, i, t[i].p_m.cwiseAbs().maxCoeff(), range::kLengthM.max));
    }
    d += 3;
  }
  return t;
}

TrackerTrace timed_tracker_trace(const py::handle& obj, const char* name) {
  const Array a = to_array(obj, name);
  if (a.ndim() == 2 && a.shape(1) == 3) {
    throw InputError(fmt::format(
        "argument {}: (N, 3) positions carry no times, and row numbers are not seconds: give (N, 4) [t_s, x_m, y_m, "
        "z_m] (read_tracker_file(...)['points'] of a file with time stamps)",
        name));
  }
  if (a.ndim() != 2 || a.shape(1) != 4) wrong_shape(a, name, "(N, 4) [t_s, x_m, y_m, z_m]");
  return tracker_trace(obj, name);
}

Array new_array(std::vector<py::ssize_t> shape) { return Array(std::move(shape)); }

Array frozen(Array a) {
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

Array from_vector(const Eigen::Ref<const Eigen::VectorXd>& v) {
  Array out = new_array({v.size()});
  Eigen::Map<Eigen::VectorXd>(out.mutable_data(), v.size()) = v;
  return out;
}

Array from_vector(const std::vector<double>& v) {
  return from_vector(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
}

Array from_matrix(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  Array out = new_array({m.rows(), m.cols()});
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(out.mutable_data(), m.rows(),
                                                                                     m.cols()) = m;
  return out;
}

void write_pose(const Pose& p, double* out16) {
  Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>> out(out16);
  out = p.matrix();
}

Array from_pose(const Pose& p) {
  Array out = new_array({4, 4});
  write_pose(p, out.mutable_data());
  return out;
}

Array from_poses(const std::vector<Pose>& p) {
  Array out = new_array({static_cast<py::ssize_t>(p.size()), 4, 4});
  for (std::size_t i = 0; i < p.size(); ++i) {
    write_pose(p[i], out.mutable_data() + 16 * i);
  }
  return out;
}

Array from_trace(const TrackerTrace& t) {
  Array out = new_array({static_cast<py::ssize_t>(t.size()), 4});
  double* d = out.mutable_data();
  for (const auto& s : t) {
    *d++ = s.t_s;
    for (int k = 0; k < 3; ++k) *d++ = s.p_m[k];
  }
  return out;
}

}  // namespace deflex::python
