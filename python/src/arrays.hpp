// NumPy arrays in and out of the deflex module: every array argument is checked here (numeric
// dtype, shape, finite values) and converted to C-contiguous float64, so a bad array is a
// deflex.InputError (a ValueError) naming the argument and the shape expected, never a crash.
#pragma once

#include <initializer_list>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "deflex/evaluate/tracker_trace.hpp"
#include "deflex/model/input_ranges.hpp"
#include "deflex/model/types.hpp"

namespace deflex::python {

namespace py = pybind11;

/// C-contiguous float64: what every array argument becomes and every array result is.
using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// Any sequence or array of real numbers (float, int, uint dtypes) as C-contiguous float64, with
/// `ndim` dimensions (0: any). Throws InputError "argument NAME: ..." otherwise.
Array to_array(const py::handle& obj, const char* name, int ndim = 0);

/// Throws InputError naming `name` and the first non-finite value (its row when 2-D).
void require_finite(const Array& a, const char* name);

/// Throws InputError naming `name`, the row and the column of the first value outside its column's
/// range (input_ranges.hpp, the table the command-line program and the files use). `columns`: one
/// range a column of the last dimension, or a single range for every column.
void require_in_ranges(const Array& a, const char* name, std::initializer_list<const InputRange*> columns);

/// Shape (n,) exactly; finite.
Array vector_array(const py::handle& obj, const char* name, py::ssize_t n);
/// Shape (rows, cols) with `rows` any (-1) or fixed; finite.
Array matrix_array(const py::handle& obj, const char* name, py::ssize_t rows, py::ssize_t cols);
/// Shape (n,) or (N, n): a single point or a batch. `batch` says which. Finite, row named on failure.
Array single_or_batch(const py::handle& obj, const char* name, py::ssize_t n, bool& batch);

/// Joint values (rad), each within the angle range (+-63 rad).
JointVector joint_vector(const py::handle& obj, const char* name, int dof);
/// Joint values (dof,) or (N, dof), rad, each within the angle range.
Array joint_rows(const py::handle& obj, const char* name, int dof, bool& batch);
/// A wrench [Fx Fy Fz Mx My Mz] (N, Nm) within the force and moment ranges (+-1e6 N, +-1e6 Nm).
Vector6 wrench_vector(const py::handle& obj, const char* name);
/// Wrenches (6,) or (N, 6), each within the force and moment ranges.
Array wrench_rows(const py::handle& obj, const char* name, bool& batch);
Vector3 vector3(const py::handle& obj, const char* name);
Vector6 vector6(const py::handle& obj, const char* name);
/// A unit quaternion (w, x, y, z) within 1e-6, normalised.
Eigen::Quaterniond unit_quaternion(const py::handle& obj, const char* name);
/// A 4x4 homogeneous transform (rotation orthonormal within 1e-6, last row 0 0 0 1).
Pose pose(const py::handle& obj, const char* name);
/// (N, 4, 4) transforms, or one (4, 4) as a list of one.
std::vector<Pose> poses(const py::handle& obj, const char* name);
/// A tracker trace from (N, 3) positions (m; time = sample index, s) or (N, 4) [t_s, x_m, y_m, z_m].
TrackerTrace tracker_trace(const py::handle& obj, const char* name);

/// New arrays, shape given, C order.
Array new_array(std::vector<py::ssize_t> shape);
Array from_vector(const Eigen::Ref<const Eigen::VectorXd>& v);
Array from_vector(const std::vector<double>& v);
/// Row-major copy of a matrix.
Array from_matrix(const Eigen::Ref<const Eigen::MatrixXd>& m);
/// The 4x4 homogeneous matrix of a pose.
Array from_pose(const Pose& p);
void write_pose(const Pose& p, double* out16);
/// (N, 4, 4) of poses.
Array from_poses(const std::vector<Pose>& p);
/// (N, n) of equally sized vectors (joint vectors, wrenches, displacements).
template <typename Vec>
Array from_rows(const std::vector<Vec>& rows, py::ssize_t n) {
  Array out = new_array({static_cast<py::ssize_t>(rows.size()), n});
  double* d = out.mutable_data();
  for (const auto& r : rows) {
    for (py::ssize_t j = 0; j < n; ++j) {
      *d++ = r[j];
    }
  }
  return out;
}
/// (N, 4) [t_s, x_m, y_m, z_m].
Array from_trace(const TrackerTrace& t);

/// (N, n) of a vector member of each item (e.g. the joints of each path point).
template <typename T, typename Vec>
Array rows_of(const std::vector<T>& items, Vec T::*field, py::ssize_t n) {
  Array out = new_array({static_cast<py::ssize_t>(items.size()), n});
  double* d = out.mutable_data();
  for (const T& item : items) {
    for (py::ssize_t j = 0; j < n; ++j) {
      *d++ = (item.*field)[j];
    }
  }
  return out;
}

/// (N, 4, 4) of a Pose member of each item.
template <typename T>
Array poses_of(const std::vector<T>& items, Pose T::*field) {
  Array out = new_array({static_cast<py::ssize_t>(items.size()), 4, 4});
  for (std::size_t i = 0; i < items.size(); ++i) {
    write_pose(items[i].*field, out.mutable_data() + 16 * i);
  }
  return out;
}

/// A read-write property of a fixed-size vector member (Vector3, Vector6), checked on assignment.
template <typename T, typename Vec>
void vector_property(py::class_<T>& c, const char* name, Vec T::*field, const char* doc = "") {
  c.def_property(
      name, [field](const T& t) { return from_vector(t.*field); },
      [field, name](T& t, const py::handle& v) {
        t.*field = Eigen::Map<const Vec>(vector_array(v, name, Vec::RowsAtCompileTime).data());
      },
      doc);
}

/// A read-write property of a Pose member, as a 4x4 homogeneous matrix.
template <typename T>
void pose_property(py::class_<T>& c, const char* name, Pose T::*field, const char* doc = "") {
  c.def_property(
      name, [field](const T& t) { return from_pose(t.*field); },
      [field, name](T& t, const py::handle& v) { t.*field = pose(v, name); }, doc);
}

}  // namespace deflex::python
