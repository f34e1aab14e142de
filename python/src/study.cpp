// The case study (the paper's protocol on the simulated cell) run from Python to a results object:
// the tables as the dict `deflex case-study --json` prints, the links' figures, the run counts.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/evaluate/study_tables.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/study/case_study.hpp"

namespace deflex::python {
using namespace pybind11::literals;
py::object json_to_python(const nlohmann::json& doc) {
  return py::module_::import("json").attr("loads")(doc.dump());
}

namespace {

py::list links_to_python(const std::vector<study::LinkSummary>& links) {
  py::list out;
  for (const auto& l : links) {
    out.append(py::dict("setup"_a = l.setup, "link"_a = l.link, "joint_commands"_a = l.joint_commands,
                        "cycles"_a = l.cycles, "rejected"_a = l.rejected, "guard_trips"_a = l.guard_trips,
                        "max_command_deviation_rad"_a = l.max_command_deviation_rad, "bound_rad"_a = l.bound_rad,
                        "max_tcp_correction_m"_a = l.max_tcp_correction_m, "measured_delay_s"_a = l.measured_delay_s));
  }
  return out;
}

}  // namespace

void bind_study(py::module_& m) {
  py::class_<study::CaseStudyOutput>(m, "CaseStudyResult",
                                     "A case study's figures: tables (the dict of `deflex case-study --json`; lengths "
                                     "in mm as its keys say), links, counts.")
      .def_property_readonly("tables", [](const study::CaseStudyOutput& o) { return json_to_python(study_to_json(o.study)); },
                             "setups -> loads -> uc_mm / c_mm / compensation by speed (mm/s), speeds_mm_s, seeds, "
                             "speed_sweep, error_budget, paper")
      .def_property_readonly("tables_text", [](const study::CaseStudyOutput& o) { return study_tables_text(o.study); },
                             "Tables 1 and 2 as `deflex case-study` prints them")
      .def_property_readonly("links", [](const study::CaseStudyOutput& o) { return links_to_python(o.links); })
      .def_readonly("setup_paragraphs", &study::CaseStudyOutput::setup_paragraphs)
      .def_readonly("simulated_s", &study::CaseStudyOutput::simulated_s, "robot time simulated, s")
      .def_property_readonly("wall_time_s", [](const study::CaseStudyOutput& o) { return o.study.wall_time_s; })
      .def_readonly("runs", &study::CaseStudyOutput::runs)
      .def_readonly("calibrations", &study::CaseStudyOutput::calibrations)
      .def("__repr__", [](const study::CaseStudyOutput& o) {
        return fmt::format("<deflex.CaseStudyResult: {} runs, {} calibrations, {} setups>", o.runs, o.calibrations,
                           o.study.setups.size());
      });

  m.def(
      "run_case_study",
      [](const std::string& case_file, int seeds, std::optional<long long> seed, bool quick, bool speed_sweep,
         bool error_budget, int threads) {
        study::CaseConfig config = case_file.empty() ? study::paper_case() : study::load_case(case_file);
        if (seed) {
          if (*seed < 0) throw InputError(fmt::format("argument seed: must be >= 0 (got {})", *seed));
          config.seed = static_cast<std::uint64_t>(*seed);
        }
        if (seeds < 0 || threads < 0) throw InputError("arguments seeds and threads: must be >= 0 (0: the default)");
        study::CaseStudyOptions options;
        options.quick = quick;
        options.seeds = seeds;
        options.speed_sweep = speed_sweep;
        options.error_budget = error_budget;
        options.threads = threads;
        py::gil_scoped_release release;
        return study::run_case_study(config, options);
      },
      "case_file"_a = "", "seeds"_a = 0, "seed"_a = py::none(), "quick"_a = false, "speed_sweep"_a = true,
      "error_budget"_a = true, "threads"_a = 0,
      "The case study (as `deflex case-study` with --case, --seeds, --seed, --quick, --no-sweep, --no-budget, "
      "--threads): case_file empty for the paper's case, seeds 0 for the case's own count, threads 0 for every core. "
      "Writes no files.");
}

}  // namespace deflex::python
