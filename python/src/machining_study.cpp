// The machining study (the simulated cell mills a part under each strategy; the part is probed) run
// from Python to a results object: the table as `deflex machining-study` writes its JSON, the table's
// text, the fitted coefficients against the cell's truth, and the HTML report.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/report/machining_report.hpp"
#include "deflex/study/machining_study.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::python {
using namespace pybind11::literals;

void bind_machining_study(py::module_& m) {
  py::class_<study::MachiningStudyOutput>(
      m, "MachiningStudyResult",
      "A machining study's figures: table (the dict of machining-study.json; lengths in um as its keys say), "
      "table_text, fit_text, and write_report().")
      .def_property_readonly(
          "table",
          [](const study::MachiningStudyOutput& r) {
            return json_to_python(nlohmann::json::parse(study::machining_json(r)));
          },
          "seeds, feeds_mm_min, probe_noise_um, published (coefficients), table (per strategy and feed: each "
          "column's mean, sd and n in um), fits (per seed: fitted and truth)")
      .def_property_readonly("table_text", &study::machining_table_text,
                             "the table as `deflex machining-study` prints it")
      .def_property_readonly("fit_text", &study::machining_fit_text, "the fitted coefficients as printed")
      .def_property_readonly("setup_paragraphs",
                             [](const study::MachiningStudyOutput& r) { return r.setup_paragraphs; })
      .def(
          "write_report",
          [](const study::MachiningStudyOutput& r, const PathArg& path) {
            OutputFile f(path_text(path), "write_report");
            f.write(machining_report_html(r));
            f.commit();
          },
          "path"_a, "The HTML report `--report FILE` writes.")
      .def("__repr__", [](const study::MachiningStudyOutput& r) {
        return fmt::format("<deflex.MachiningStudyResult: {} seeds, {} parts>", r.seeds, r.runs.size());
      });

  m.def(
      "run_machining_study",
      [](bool quick, int seeds, int threads) {
        if (seeds < 0 || threads < 0) throw InputError("arguments seeds and threads: must be >= 0 (0: the default)");
        study::MachiningStudyOptions options;
        options.quick = quick;
        options.seeds = seeds;
        options.threads = threads;
        py::gil_scoped_release release;
        return study::run_machining_study(options);
      },
      "quick"_a = false, "seeds"_a = 0, "threads"_a = 0,
      "The machining study (as `deflex machining-study` with --quick, --seeds, --threads): seeds 0 for 3 (2 with "
      "quick), threads 0 for every core. Writes no files (write_report() does).");
}

}  // namespace deflex::python
