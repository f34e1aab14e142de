// NumPy arrays in and out of the deflex module: every array argument is checked here (numeric
// dtype, shape, finite values) and converted to C-contiguous float64, so a bad array is a
// deflex.InputError (a ValueError) naming the argument and the shape expected, never a crash.
#pragma once

#include <filesystem>
#include <initializer_list>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "deflex/model/tracker_trace.hpp"
#include "deflex/model/types.hpp"
#include "deflex/text/input_ranges.hpp"

namespace deflex::python {

namespace py = pybind11;

/// C-contiguous float64: what every array argument becomes and every array result is.
using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// An argument taken as any Python object and checked by the functions below, named in signatures,
/// docstrings and the .pyi stubs by `Tag::name` (e.g. numpy.typing.ArrayLike) rather than `handle`.
template <typename Tag>
struct Arg {
  py::object obj;
  operator py::handle() const { return obj; }  // NOLINT: passed on to the checks below
  [[nodiscard]] bool is_none() const { return obj.is_none(); }
};
struct ArrayLikeTag {
  static constexpr auto name = py::detail::const_name("numpy.typing.ArrayLike");
};
struct PathOrPosesTag {
  static constexpr auto name = py::detail::const_name("typing.Union[Circle, numpy.typing.ArrayLike]");
};
struct ForceTag {
  static constexpr auto name = py::detail::const_name("typing.Union[str, numpy.typing.ArrayLike]");
};
struct ConfigurationTag {
  static constexpr auto name = py::detail::const_name("typing.Optional[typing.Tuple[int, int, int, int]]");
};
struct DataTag {
  static constexpr auto name = py::detail::const_name("typing.Union[str, os.PathLike, numpy.typing.ArrayLike]");
};
struct TrackerPointsTag {
  static constexpr auto name =
      py::detail::const_name("typing.Union[typing.Dict[str, typing.Any], numpy.typing.ArrayLike]");
};
/// Points of a registration: what read_tracker_file returns, or an array.
using TrackerPointsArg = Arg<TrackerPointsTag>;
struct TracesTag {
  static constexpr auto name =
      py::detail::const_name("typing.Union[numpy.typing.ArrayLike, typing.Sequence[numpy.typing.ArrayLike]]");
};
/// One trace, or a list of traces.
using TracesArg = Arg<TracesTag>;
struct CaseTag {
  static constexpr auto name = py::detail::const_name("typing.Union[str, os.PathLike, dict]");
};
/// A case: a case file's path or a dict of its keys (None: the paper's case).
using CaseArg = Arg<CaseTag>;
struct OptionalFloatsTag {
  static constexpr auto name = py::detail::const_name("typing.Sequence[typing.Optional[float]]");
};
/// One entry a joint: a number or None.
using OptionalFloats = Arg<OptionalFloatsTag>;
/// A data file's path, or the first of the arrays that stand for it.
using DataArg = Arg<DataTag>;
/// ABB confdata (cf1, cf4, cf6, cfx) or None.
using ConfigurationArg = Arg<ConfigurationTag>;
/// Numbers: a sequence or an array (checked by to_array and the shape functions below).
using ArrayLike = Arg<ArrayLikeTag>;
/// A path: a Circle, or (N, 4, 4) poses.
using PathOrPoses = Arg<PathOrPosesTag>;
/// A force: a spec string as `deflex offline --force` takes it, or wrenches.
using ForceArg = Arg<ForceTag>;
/// A file path: str or any os.PathLike (pathlib.Path), as the C++ library's string. Its own type (not
/// std::filesystem::path, which the stubs would call os.PathLike alone) so the signatures say both.
struct PathArg : std::filesystem::path {
  using std::filesystem::path::path;
  PathArg(std::filesystem::path p) : std::filesystem::path(std::move(p)) {}  // NOLINT: a path is one
};
[[nodiscard]] inline std::string path_text(const PathArg& p) { return p.string(); }

/// A result whose Python type depends on the arguments (one pose or a batch), named in signatures
/// and stubs by `Tag::name` rather than `object`.
template <typename Tag>
using Returns = Arg<Tag>;
struct IkSolutionsTag {
  static constexpr auto name =
      py::detail::const_name("typing.Union[typing.List[IkResult], typing.List[typing.List[IkResult]]]");
};
struct IkResultsTag {
  static constexpr auto name = py::detail::const_name("typing.Union[IkResult, typing.List[IkResult]]");
};
struct BoolOrArrayTag {
  static constexpr auto name = py::detail::const_name("typing.Union[bool, numpy.ndarray]");
};

/// The array made read-only: what every array property returns, so that an edit in place
/// (`circle.centre_m[2] = 0.9`) raises ValueError instead of changing a copy the object never sees.
Array frozen(Array a);

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
/// A trace whose times matter (clock alignment, the time-synchronous error): (N, 4) only, refused for
/// (N, 3) naming the argument (row numbers are not seconds).
TrackerTrace timed_tracker_trace(const py::handle& obj, const char* name);

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

/// A read-write property of a fixed-size vector member (Vector3, Vector6), checked on assignment;
/// the array it returns is read-only (assign the whole vector to change it).
template <typename T, typename Vec>
void vector_property(py::class_<T>& c, const char* name, Vec T::*field, const char* doc = "") {
  c.def_property(
      name, [field](const T& t) { return frozen(from_vector(t.*field)); },
      [field, name](T& t, const py::handle& v) {
        t.*field = Eigen::Map<const Vec>(vector_array(v, name, Vec::RowsAtCompileTime).data());
      },
      doc);
}

/// A read-write property of a Pose member, as a 4x4 homogeneous matrix.
template <typename T>
void pose_property(py::class_<T>& c, const char* name, Pose T::*field, const char* doc = "") {
  c.def_property(
      name, [field](const T& t) { return frozen(from_pose(t.*field)); },
      [field, name](T& t, const py::handle& v) { t.*field = pose(v, name); }, doc);
}

}  // namespace deflex::python

namespace pybind11::detail {
/// Takes any object (None too: the function decides what None means) and keeps it for the checks.
/// PathArg: pybind11's own std::filesystem::path conversion (str, bytes, os.PathLike), named for both.
template <>
struct type_caster<deflex::python::PathArg> {
  PYBIND11_TYPE_CASTER(deflex::python::PathArg, const_name("typing.Union[str, os.PathLike]"));
  bool load(handle src, bool convert) {
    make_caster<std::filesystem::path> inner;
    if (!inner.load(src, convert)) return false;
    value = deflex::python::PathArg(cast_op<std::filesystem::path&&>(std::move(inner)));
    return true;
  }
  static handle cast(const deflex::python::PathArg& p, return_value_policy policy, handle parent) {
    return make_caster<std::filesystem::path>::cast(p, policy, parent);
  }
};

template <typename Tag>
struct type_caster<deflex::python::Arg<Tag>> {
  PYBIND11_TYPE_CASTER(deflex::python::Arg<Tag>, Tag::name);
  bool load(handle src, bool /*convert*/) {
    if (!src) return false;
    value.obj = reinterpret_borrow<object>(src);
    return true;
  }
  static handle cast(const deflex::python::Arg<Tag>& a, return_value_policy /*policy*/, handle /*parent*/) {
    return a.obj.inc_ref();
  }
};
}  // namespace pybind11::detail
