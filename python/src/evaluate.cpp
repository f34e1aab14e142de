// Path metrics: the paper's mean distance from the unloaded path and its companions, the
// time-synchronous error, ISO 9283 path accuracy and repeatability. A trace is (N, 3) positions in m
// or (N, 4) [t_s, x_m, y_m, z_m] (tracker CSV files: read_tracker_csv).
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/path_metrics.hpp"

namespace deflex::python {
using namespace pybind11::literals;
namespace {

std::vector<TrackerTrace> traces(const py::handle& list, const char* name) {
  std::vector<TrackerTrace> out;
  int i = 0;
  for (const py::handle item : list) {
    const std::string item_name = fmt::format("{}[{}]", name, i++);
    out.push_back(tracker_trace(item, item_name.c_str()));
  }
  return out;
}

}  // namespace

void bind_evaluate(py::module_& m) {
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

  m.def("read_tracker_csv", [](const std::string& path) { return from_trace(read_tracker_csv(path)); }, "path"_a,
        "A tracker CSV (t_s,x_mm,y_mm,z_mm) as an (N, 4) array [t_s, x_m, y_m, z_m].");
  m.def(
      "mean_distance_to_path_m",
      [](const py::handle& loaded, const py::handle& reference) {
        const TrackerTrace l = tracker_trace(loaded, "loaded"), r = tracker_trace(reference, "reference");
        py::gil_scoped_release release;
        return mean_distance_to_path_m(l, r);
      },
      "loaded"_a, "reference"_a,
      "The paper's figure of merit: mean distance (m) of the loaded points from the reference polyline.");
  m.def(
      "path_deviation",
      [](const py::handle& loaded, const py::handle& reference) {
        if (py::isinstance<py::list>(loaded) || py::isinstance<py::tuple>(loaded)) {
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
      [](const py::handle& loaded, const py::handle& reference) {
        const TrackerTrace l = tracker_trace(loaded, "loaded"), r = tracker_trace(reference, "reference");
        return time_synchronous_deviation(l, r);
      },
      "loaded"_a, "reference"_a,
      "Distances (m) between loaded and reference positions at the same time ((N, 4) traces stamped from the same "
      "start): sees lag along the path.");
  m.def(
      "iso9283_path",
      [](const py::handle& runs, const py::handle& reference, int evaluation_points, double max_offset_m) {
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

}  // namespace deflex::python
