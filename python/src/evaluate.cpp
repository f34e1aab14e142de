// Path metrics: the paper's mean distance from the unloaded path and its companions, the
// time-synchronous error, ISO 9283 path accuracy and repeatability. A trace is (N, 3) positions in m
// or (N, 4) [t_s, x_m, y_m, z_m] (tracker CSV files: read_tracker_csv).
#include <algorithm>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/evaluate/frame_registration.hpp"
#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/evaluate/time_alignment.hpp"
#include "deflex/evaluate/tracker_csv.hpp"
#include "deflex/evaluate/tracker_files.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

// (N, 3) points in m.
std::vector<TrackerTrace> traces(const py::handle& list, const char* name) {
  std::vector<TrackerTrace> out;
  int i = 0;
  for (const py::handle item : list) {
    const std::string item_name = fmt::format("{}[{}]", name, i++);
    out.push_back(tracker_trace(item, item_name.c_str()));
  }
  return out;
}

/// One side of a registration as the pairing reads it: the dict read_tracker_file returns (its points,
/// names, file and lines), or an (N, 3) or (N, 4) array ([t_s,] x, y, z in m; t_s may be NaN) with
/// optional names.
TrackerFile registration_side(const py::handle& obj, const py::handle& names_arg, const char* name) {
  TrackerFile f;
  f.source = fmt::format("argument {}", name);
  py::object points = py::reinterpret_borrow<py::object>(obj);
  py::object names = py::reinterpret_borrow<py::object>(names_arg);
  std::vector<int> lines;
  if (py::isinstance<py::dict>(obj)) {
    const auto d = py::reinterpret_borrow<py::dict>(obj);
    if (!d.contains("points")) throw InputError(fmt::format("argument {}: a dict without 'points'", name));
    points = d["points"];
    if (names.is_none() && d.contains("names")) names = d["names"];
    if (d.contains("source")) f.source = d["source"].cast<std::string>();
    if (d.contains("lines")) lines = d["lines"].cast<std::vector<int>>();
  }
  const Array a = to_array(points, name, 2);
  const py::ssize_t n = a.shape(0), cols = a.shape(1);
  if (cols != 3 && cols != 4) {
    throw InputError(fmt::format("argument {}: expected shape (N, 3) [x, y, z] or (N, 4) [t_s, x, y, z], got ({}, {})",
                                 name, n, cols));
  }
  std::vector<std::string> labels;
  if (!names.is_none()) {
    labels = names.cast<std::vector<std::string>>();
    if (static_cast<py::ssize_t>(labels.size()) != n) {
      throw InputError(fmt::format("argument {}: {} names for {} points", name, labels.size(), n));
    }
  }
  f.has_names = !labels.empty() && std::none_of(labels.begin(), labels.end(), [](const auto& s) { return s.empty(); });
  for (py::ssize_t i = 0; i < n; ++i) {
    TrackerPoint p;
    p.p_m = Eigen::Map<const Vector3>(a.data() + i * cols + (cols - 3));
    if (!p.p_m.allFinite())
      throw InputError(fmt::format("argument {}: row {}: a position that is not finite", name, i));
    if (f.has_names) p.name = labels[static_cast<std::size_t>(i)];
    p.line = static_cast<std::size_t>(i) < lines.size() ? lines[static_cast<std::size_t>(i)] : 0;
    f.points.push_back(p);
  }
  return f;
}

/// One trace ((N, 3) or (N, 4) numbers), rather than a list of traces.
bool is_one_trace(const py::handle& obj) {
  try {
    const py::object a = py::module_::import("numpy").attr("asarray")(obj, "dtype"_a = "float64");
    return a.attr("ndim").cast<int>() == 2;
  } catch (const py::error_already_set&) {
    return false;  // ragged: traces of different lengths
  }
}

}  // namespace

namespace {

// The figures the path measures return.
void bind_evaluate_result_types(py::module_& m) {
  py::class_<PathDeviationStats>(m, "PathDeviationStats", "Distances of a loaded path from a reference, m.")
      .def_readonly("mean_m", &PathDeviationStats::mean_m, "the paper's mean deformation")
      .def_readonly("max_m", &PathDeviationStats::max_m)
      .def_readonly("rms_m", &PathDeviationStats::rms_m)
      .def_readonly("std_m", &PathDeviationStats::std_m)
      .def_readonly("samples", &PathDeviationStats::samples)
      .def("__repr__", [](const PathDeviationStats& s) {
        return fmt::format("PathDeviationStats(mean_m={:.6g}, max_m={:.6g}, rms_m={:.6g}, std_m={:.6g}, samples={})",
                           s.mean_m, s.max_m, s.rms_m, s.std_m, s.samples);
      });
  py::class_<Iso9283Path>(m, "Iso9283Path", "ISO 9283 7.2 path accuracy AT_p and repeatability RT_p, m.")
      .def_readonly("accuracy_m", &Iso9283Path::accuracy_m, "AT_p")
      .def_readonly("repeatability_m", &Iso9283Path::repeatability_m, "RT_p (0 for one run)")
      .def_readonly("mean_accuracy_m", &Iso9283Path::mean_accuracy_m)
      .def_readonly("evaluation_points", &Iso9283Path::evaluation_points)
      .def_readonly("skipped_points", &Iso9283Path::skipped_points)
      .def_readonly("runs", &Iso9283Path::runs)
      .def("__repr__", [](const Iso9283Path& s) {
        return fmt::format("Iso9283Path(accuracy_m={:.6g}, repeatability_m={:.6g}, evaluation_points={}, runs={})",
                           s.accuracy_m, s.repeatability_m, s.evaluation_points, s.runs);
      });
}

// Tracker traces: reading, laps and the reference path.
void bind_evaluate_traces(py::module_& m) {
  m.def(
      "read_tracker_csv", [](const PathArg& path) { return from_trace(read_tracker_csv(path_text(path))); }, "path"_a,
      "A tracker CSV (t_s,x_mm,y_mm,z_mm) as an (N, 4) array [t_s, x_m, y_m, z_m].");
  m.def(
      "split_laps",
      [](const ArrayLike& trace, double min_turn_rad, double reversal_rad) {
        const TrackerTrace t = tracker_trace(trace, "trace");
        LapSplit s;
        {
          py::gil_scoped_release release;
          s = split_laps(t, min_turn_rad, reversal_rad);
        }
        py::list laps;
        for (const TrackerTrace& lap : s.laps) laps.append(from_trace(lap));
        return laps;
      },
      "trace"_a, "min_turn_rad"_a = 0.9 * 2.0 * kPi, "reversal_rad"_a = deg_to_rad(5.0),
      "The laps of a trace that goes round a closed path ((N, 4) [t_s, x_m, y_m, z_m] or (N, 3)), as `deflex "
      "evaluate --split-laps` and the case study find them: by the angle turned about the centroid in the plane of "
      "best fit, a lap ending after a full turn or where the direction reverses (by more than reversal_rad); pieces "
      "that turn less than min_turn_rad (the approach, a partial lap) are dropped. A list of (M, 4) arrays.");
  m.def(
      "mean_reference",
      [](const TracesArg& given, int bins) {
        TrackerTrace all;
        if (is_one_trace(given)) {
          all = tracker_trace(given, "traces");
        } else {
          for (const TrackerTrace& t : traces(given, "traces")) all.insert(all.end(), t.begin(), t.end());
        }
        TrackerTrace mean;
        {
          py::gil_scoped_release release;
          mean = mean_closed_path(all, bins);
        }
        Array out = new_array({static_cast<py::ssize_t>(mean.size()), 3});
        for (std::size_t i = 0; i < mean.size(); ++i) {
          for (int k = 0; k < 3; ++k) out.mutable_data()[3 * i + static_cast<std::size_t>(k)] = mean[i].p_m[k];
        }
        return out;
      },
      "traces"_a, "bins"_a = 3600,
      "The mean of a closed path's laps as one closed polyline (M, 3) in m, the reference the case study measures "
      "its loaded runs against (a nearest-point distance to a dense, noisy reference is biased low by the "
      "reference's noise; to the laps' mean it is not): the samples of one trace, or of a list of traces (laps or "
      "runs), binned by their angle about the centroid in the plane of best fit (bins equal sectors; `deflex "
      "evaluate --mean-reference` takes about two samples a lap a bin, 36..3600), each bin's positions averaged. "
      "Refuses fewer than 90 % of the bins holding a sample.");
}

// Distances from a path: the paper's mean, ISO 9283 and the compensation ratio.
void bind_evaluate_deviation(py::module_& m) {
  m.def(
      "mean_distance_to_path_m",
      [](const ArrayLike& loaded, const ArrayLike& reference) {
        const TrackerTrace l = tracker_trace(loaded, "loaded"), r = tracker_trace(reference, "reference");
        py::gil_scoped_release release;
        return mean_distance_to_path_m(l, r);
      },
      "loaded"_a, "reference"_a,
      "The paper's figure of merit: mean distance (m) of the loaded points from the reference polyline.");
  m.def(
      "path_deviation",
      [](const ArrayLike& loaded, const ArrayLike& reference) {
        if (py::isinstance<py::list>(loaded.obj) || py::isinstance<py::tuple>(loaded.obj)) {
          const auto l = traces(loaded, "loaded"), r = traces(reference, "reference");
          py::gil_scoped_release release;
          return path_deviation(l, r);
        }
        const TrackerTrace l = tracker_trace(loaded, "loaded"), r = tracker_trace(reference, "reference");
        py::gil_scoped_release release;
        return path_deviation(l, r);
      },
      "loaded"_a, "reference"_a,
      "Mean, max, RMS and standard deviation (m) of the distances of the loaded points from the reference; lists of "
      "traces for several laps (each reference lap its own polyline).");
  m.def(
      "time_synchronous_deviation",
      [](const ArrayLike& loaded, const ArrayLike& reference) {
        const TrackerTrace l = timed_tracker_trace(loaded, "loaded"), r = timed_tracker_trace(reference, "reference");
        return time_synchronous_deviation(l, r);
      },
      "loaded"_a, "reference"_a,
      "Distances (m) between loaded and reference positions at the same time ((N, 4) traces stamped from the same "
      "start): sees lag along the path.");
  m.def(
      "iso9283_path",
      [](const ArrayLike& runs, const ArrayLike& reference, int evaluation_points, double max_offset_m) {
        const auto r = traces(runs, "runs");
        const TrackerTrace ref = tracker_trace(reference, "reference");
        py::gil_scoped_release release;
        return iso9283_path(r, ref, evaluation_points, max_offset_m);
      },
      "runs"_a, "reference"_a, "evaluation_points"_a = 81, "max_offset_m"_a = 0.01,
      "ISO 9283 path accuracy and repeatability of repeated runs (a list of traces) against the commanded or "
      "unloaded reference.");
  m.def("compensation_ratio", &compensation_ratio, "uc"_a, "c"_a, "1 - C/UC (NaN when UC is not positive).");
}

void bind_evaluate_tracker_files(py::module_& m) {
  // Tracker sessions: SA exports and unit-named CSV, registration, time alignment (docs/evaluation.md).
  m.def(
      "read_tracker_file",
      [](const PathArg& path, const std::string& length_unit, const std::string& angle_unit, const std::string& columns,
         const std::string& expect_frame) {
        TrackerReadOptions o{length_unit, angle_unit, columns, expect_frame};
        const TrackerFile f = read_tracker_file(path_text(path), o);
        Array a = new_array({static_cast<py::ssize_t>(f.points.size()), 4});
        auto v = a.mutable_unchecked<2>();
        py::list names;
        for (std::size_t i = 0; i < f.points.size(); ++i) {
          const auto& p = f.points[i];
          v(static_cast<py::ssize_t>(i), 0) = p.t_s;
          for (int k = 0; k < 3; ++k) v(static_cast<py::ssize_t>(i), k + 1) = p.p_m[k];
          names.append(p.name);
        }
        py::dict d;
        d["points"] = a;
        d["names"] = names;
        d["frame"] = f.frame;
        d["format"] = f.format;
        d["coordinates"] = f.coordinates;
        d["length_unit"] = f.length_unit;
        d["has_time"] = f.has_time;
        d["encoding"] = f.encoding;
        d["source"] = f.source;
        std::vector<int> lines;
        for (const auto& p : f.points) lines.push_back(p.line);
        d["lines"] = lines;
        return d;
      },
      "path"_a, "length_unit"_a = "", "angle_unit"_a = "", "columns"_a = "", "expect_frame"_a = "",
      "A Spatial Analyzer ASCII export or a CSV with the unit in its header (x_mm or x_m): a dict with 'points' "
      "(N, 4) [t_s (NaN without stamps), x_m, y_m, z_m] in the file's frame, 'names', 'frame', 'format', "
      "'coordinates', 'length_unit', 'has_time', 'encoding' ('windows-1252' for a file that is not UTF-8, read as "
      "SA's ANSI export). Units are never guessed: give length_unit when the header names none.");
  m.def(
      "write_sa_export",
      [](const PathArg& path, const ArrayLike& trace, const std::string& frame) {
        SaExportOptions o;
        o.frame = frame;
        write_sa_export(tracker_trace(trace, "trace"), path_text(path), o);
      },
      "path"_a, "trace"_a, "frame"_a = "Robot Base",
      "Writes an (N, 4) trace [t_s, x_m, y_m, z_m] as a Spatial Analyzer ASCII export (mm, named working frame).");
}

// The tracker frame and clock against the robot's.
void bind_evaluate_registration(py::module_& m) {
  m.def(
      "register_frames",
      [](const TrackerPointsArg& tracker_points, const TrackerPointsArg& base_points, double max_rms_m,
         const std::optional<std::vector<std::string>>& tracker_names,
         const std::optional<std::vector<std::string>>& base_names) {
        const py::object none = py::none();
        const TrackerFile t =
            registration_side(tracker_points, tracker_names ? py::cast(*tracker_names) : none, "tracker_points");
        const TrackerFile b = registration_side(base_points, base_names ? py::cast(*base_names) : none, "base_points");
        RegistrationInput in = pair_tracker_points(t, b);
        in.max_rms_m = max_rms_m;
        const FrameRegistration r = register_frames(in);
        std::vector<double> res;
        py::list names;
        for (const auto& e : r.residuals) {
          res.push_back(e.distance_m);
          names.append(e.name);
        }
        py::dict d;
        d["base_T_tracker"] = from_pose(r.base_T_tracker);
        d["rms_m"] = r.rms_m;
        d["max_m"] = r.max_m;
        d["residuals_m"] = from_vector(res);
        d["names"] = names;
        return d;
      },
      "tracker_points"_a, "base_points"_a, "max_rms_m"_a = kDefaultMaxRegistrationRmsM, "tracker_names"_a = py::none(),
      "base_names"_a = py::none(),
      "The tracker-to-base transform (4x4, p_base = T p_tracker) by Horn's closed form, with the residual of each "
      "point (residuals_m, in the order of names). Each side is what read_tracker_file returns, or (N, 3) [x, y, z] "
      "or (N, 4) [t_s, x, y, z] points in m with optional names (tracker_names, base_names). Points pair as `deflex "
      "register` pairs them: by name when both sides name theirs (the whole name, else the target's own: "
      "'Job::Reference::REF1' with 'REF1'), else by order. Refuses a name without a partner, fewer than 3 points, "
      "points on a line, a mirror image (no rotation fits it) and an RMS above max_rms_m (default 1 mm: pairs that "
      "do not belong together).");
  m.def(
      "align_time",
      [](const ArrayLike& measured, const ArrayLike& commanded, bool fit_drift, double search_s, double centre_s) {
        const TrackerTrace mt = timed_tracker_trace(measured, "measured");
        const TrackerTrace ct = timed_tracker_trace(commanded, "commanded");
        TimeAlignmentOptions o;
        o.fit_drift = fit_drift;
        o.search_s = search_s;
        o.centre_s = centre_s;
        TimeAlignment a;
        {
          py::gil_scoped_release release;
          a = align_time(mt, ct, o);
        }
        py::dict d;
        d["offset_s"] = a.offset_s;
        d["offset_std_s"] = a.offset_std_s;
        d["drift"] = a.drift;
        d["reference_t_s"] = a.reference_t_s;
        d["rms_m"] = a.rms_m;
        d["samples"] = a.samples;
        return d;
      },
      "measured"_a, "commanded"_a, "fit_drift"_a = false, "search_s"_a = 0.0, "centre_s"_a = 0.0,
      "The clock offset (program time = tracker time + offset_s [+ drift (t - reference_t_s)]; reference_t_s the "
      "tracker time of the run's middle) that best puts the measured (N, 4) trace on the commanded one, with its "
      "uncertainty from the spread over the run's blocks. Both traces need times: (N, 3) is refused.");
}

}  // namespace

void bind_evaluate(py::module_& m) {
  bind_evaluate_result_types(m);
  bind_evaluate_traces(m);
  bind_evaluate_deviation(m);
  bind_evaluate_tracker_files(m);
  bind_evaluate_registration(m);
}

}  // namespace deflex::python
