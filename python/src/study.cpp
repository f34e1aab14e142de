// The case study (the paper's protocol on the simulated cell) run from Python to a results object:
// the tables as the dict `deflex case-study --json` prints, the links' figures, the run counts, the
// tracker traces `--write-traces` writes, and the report `--out` writes. The case is the paper's, a
// case file, or a dict of the case file's keys.
#include <mutex>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include "arrays.hpp"
#include "bindings.hpp"
#include "deflex/evaluate/tracker_csv.hpp"
#include "deflex/evaluate/tracker_files.hpp"
#include "deflex/report/case_report.hpp"
#include "deflex/report/html_report.hpp"
#include "deflex/study/case_study.hpp"
#include "deflex/study/study_tables.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::python {
using namespace pybind11::literals;
py::object json_to_python(const nlohmann::json& doc) { return py::module_::import("json").attr("loads")(doc.dump()); }

namespace {

py::list links_to_python(const std::vector<study::LinkSummary>& links) {
  py::list out;
  for (const auto& l : links) {
    out.append(py::dict("setup"_a = l.setup, "link"_a = l.link, "joint_commands"_a = l.joint_commands,
                        "cycles"_a = l.cycles, "rejected"_a = l.rejected, "guard_trips"_a = l.guard_trips,
                        "max_command_deviation_rad"_a = l.max_command_deviation_rad, "bound_rad"_a = l.bound_rad,
                        "max_tcp_correction_m"_a = l.max_tcp_correction_m, "measured_delay_s"_a = l.measured_delay_s,
                        "load_N"_a = l.load_n, "uc_mm"_a = l.uc_mm, "c_mm"_a = l.c_mm,
                        "compensation"_a = l.compensation, "controller_note"_a = l.controller_note));
  }
  return out;
}

/// A case study's output with what its report needs: the case, its text, the traces.
struct CaseStudyRun {
  study::CaseStudyOutput out;
  study::CaseConfig config;
  std::string case_text;
  std::vector<std::pair<std::string, TrackerTrace>> traces;  ///< sorted by name
};

/// `over`'s keys merged into `base`: a map into a map key by key (so {"protocol": {"laps_cw": 1}} keeps
/// the other protocol keys), anything else (a number, a list such as setups) replacing what was there.
void merge_into(YAML::Node base, const YAML::Node& over) {
  for (const auto& kv : over) {
    const std::string key = kv.first.as<std::string>();
    if (kv.second.IsMap() && base[key].IsMap()) {
      merge_into(base[key], kv.second);
    } else {
      base[key] = kv.second;
    }
  }
}

/// The paper's case file with a (partial) case dict's keys, as JSON text, merged over it.
std::string case_over_paper(const std::string& json_text) {
  YAML::Node over;
  try {
    over = YAML::Load(json_text);
  } catch (const YAML::Exception& e) {
    throw InputError(fmt::format("argument case: not a case dict ({})", e.what()));
  }
  if (!over.IsMap()) throw InputError("argument case: a dict of the case file's keys");
  YAML::Node base = YAML::Load(study::paper_case_yaml());
  merge_into(base, over);
  YAML::Emitter out;
  out << base;
  return std::string(out.c_str()) + "\n";
}

}  // namespace

namespace {

// CaseStudyRun: a case study's tables, figures, report and pickle.
void bind_study_case_run(py::module_& m) {
  py::class_<CaseStudyRun>(
      m, "CaseStudyResult",
      "A case study's figures: tables (the dict of `deflex case-study --json`; lengths in mm as its "
      "keys say), links, counts, traces (with traces=True), and write_report().")
      .def_property_readonly(
          "tables", [](const CaseStudyRun& r) { return json_to_python(study_to_json(r.out.study)); },
          "setups -> loads -> uc_mm / c_mm / compensation by speed (mm/s), speeds_mm_s, seeds, "
          "speed_sweep, error_budget, paper")
      .def_property_readonly(
          "tables_text", [](const CaseStudyRun& r) { return study_tables_text(r.out.study); },
          "Tables 1 and 2 as `deflex case-study` prints them")
      .def_property_readonly("links", [](const CaseStudyRun& r) { return links_to_python(r.out.links); })
      .def_property_readonly("setup_paragraphs", [](const CaseStudyRun& r) { return r.out.setup_paragraphs; })
      .def_property_readonly(
          "notes", [](const CaseStudyRun& r) { return study::honest_notes(r.config, r.out.study); },
          "Where the figures differ from the paper's, as the report says it")
      .def_property_readonly(
          "simulated_s", [](const CaseStudyRun& r) { return r.out.simulated_s; }, "robot time simulated, s")
      .def_property_readonly("wall_time_s", [](const CaseStudyRun& r) { return r.out.study.wall_time_s; })
      .def_property_readonly("runs", [](const CaseStudyRun& r) { return r.out.runs; })
      .def_property_readonly("calibrations", [](const CaseStudyRun& r) { return r.out.calibrations; })
      .def_property_readonly(
          "traces",
          [](const CaseStudyRun& r) {
            py::dict d;
            for (const auto& [name, trace] : r.traces) d[py::str(name)] = frozen(from_trace(trace));
            return d;
          },
          "With traces=True: the simulated tracker's runs `deflex case-study --write-traces` writes (the first seed "
          "at the error budget's speed and each setup's highest load: unloaded, UC, C), name -> (N, 4) [t_s, x_m, "
          "y_m, z_m] in the robot base frame; empty otherwise.")
      .def(
          "write_report",
          [](const CaseStudyRun& r, const PathArg& out_dir) {
            write_report(study::case_report(r.config, r.out, r.case_text), path_text(out_dir));
          },
          "out_dir"_a,
          "The report `deflex case-study --out DIR` writes (report.html, the SVG figures, tables.md/.csv, "
          "results.json), all files or none; creates the folder.")
      .def(
          "write_traces",
          [](const CaseStudyRun& r, const PathArg& out_dir) {
            if (r.traces.empty()) throw InputError("write_traces: no traces (run_case_study(..., traces=True))");
            std::error_code ec;
            std::filesystem::create_directories(out_dir, ec);
            if (ec) throw Error(fmt::format("{}: cannot create the directory: {}", path_text(out_dir), ec.message()));
            OutputTransaction outputs;
            for (const auto& [name, trace] : r.traces) {
              write_tracker_csv(trace, outputs.add((out_dir / (name + ".csv")).string(), "write_traces"));
              SaExportOptions sa;
              sa.frame = "Robot Base";
              sa.group = name;
              write_sa_export(trace, outputs.add((out_dir / (name + ".sa.txt")).string(), "write_traces"), sa);
            }
            outputs.commit();
          },
          "out_dir"_a, "The traces as `--write-traces DIR` writes them (CSV and Spatial Analyzer export).")
      .def("__repr__", [](const CaseStudyRun& r) {
        return fmt::format("<deflex.CaseStudyResult '{}': {} runs, {} calibrations, {} setups, {} traces>",
                           r.config.name, r.out.runs, r.out.calibrations, r.out.study.setups.size(), r.traces.size());
      });
}

void bind_study_run(py::module_& m) {
  m.def(
      "run_case_study",
      [](const CaseArg& case_in, int seeds, std::optional<long long> seed, bool quick, bool speed_sweep,
         bool error_budget, int threads, bool traces, bool exact) {
        CaseStudyRun run;
        const py::object& case_arg = case_in.obj;
        if (case_arg.is_none() || (py::isinstance<py::str>(case_arg) && case_arg.cast<std::string>().empty())) {
          run.config = study::paper_case();
          run.case_text = study::paper_case_yaml();
        } else if (py::isinstance<py::dict>(case_arg)) {
          // JSON is YAML: the dict's keys are the case file's, merged over the paper's case and checked by
          // the same reader.
          const std::string text = py::module_::import("json").attr("dumps")(case_arg).cast<std::string>();
          run.case_text = case_over_paper(text);
          run.config = study::load_case_text(run.case_text, "<case dict over the paper's case>");
        } else if (py::isinstance<py::str>(case_arg) || py::hasattr(case_arg, "__fspath__")) {
          run.config = study::load_case(case_arg.cast<PathArg>().string());
        } else {
          throw InputError("argument case: a case file's path, a dict of its keys, or None for the paper's case");
        }
        if (seed) {
          if (*seed < 0) throw InputError(fmt::format("argument seed: must be >= 0 (got {})", *seed));
          run.config.seed = static_cast<std::uint64_t>(*seed);
        }
        if (seeds < 0 || threads < 0) throw InputError("arguments seeds and threads: must be >= 0 (0: the default)");
        study::CaseStudyOptions options;
        options.quick = quick;
        options.seeds = seeds;
        options.speed_sweep = speed_sweep;
        options.error_budget = error_budget;
        options.threads = threads;
        options.exact = exact;
        std::mutex trace_mutex;
        if (traces) {
          options.trace_sink = [&](const std::string& name, const TrackerTrace& trace) {
            const std::lock_guard lock(trace_mutex);
            run.traces.emplace_back(name, trace);
          };
        }
        {
          py::gil_scoped_release release;
          run.out = study::run_case_study(run.config, options);
        }
        std::sort(run.traces.begin(), run.traces.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        return run;
      },
      "case"_a = py::none(), "seeds"_a = 0, "seed"_a = py::none(), "quick"_a = false, "speed_sweep"_a = true,
      "error_budget"_a = true, "threads"_a = 0, "traces"_a = false, "exact"_a = false,
      "The case study (as `deflex case-study` with --case, --seeds, --seed, --quick, --no-sweep, --no-budget, "
      "--threads, --write-traces, --exact): case None for the paper's case, a case file's path, or a dict of its keys "
      "(data/cases/paper.yaml's) merged over the paper's case (a nested dict key by key, a list such as setups "
      "whole); seeds 0 for the case's own count, threads 0 for every core. Writes no files "
      "(write_report() and write_traces() do).");
}

}  // namespace

void bind_study(py::module_& m) {
  bind_study_case_run(m);
  bind_study_run(m);
}

}  // namespace deflex::python
