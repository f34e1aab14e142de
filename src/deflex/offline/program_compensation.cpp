// Entry point of program compensation: which reader, the files, the summary.
#include "deflex/offline/program_compensation.hpp"

#include <filesystem>

#include <sys/stat.h>

#include <fmt/format.h>

#include "deflex/offline/detail/krl_program.hpp"
#include "deflex/offline/detail/program_text.hpp"
#include "deflex/offline/detail/rapid_program.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

/// Both name one existing file (device and inode: through links and hard links).
bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {};
  struct stat sb {};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

bool is_rapid(const std::string& ext) { return ext == ".MOD" || ext == ".MODX" || ext == ".PRG" || ext == ".SYS"; }

/// The .dat beside a KRL .src (".dat" or ".DAT"); refused naming it when there is none.
std::string krl_data_list(const std::string& src) {
  for (const char* ext : {".dat", ".DAT"}) {
    std::string dat = fs::path(src).replace_extension(ext).string();
    struct stat st {};
    if (::lstat(dat.c_str(), &st) == 0) {
      return dat;
    }
  }
  throw InputError(
      fmt::format("{}: its data list {} does not exist: a KRL program's points are declared in the "
                  ".dat beside the .src (give both, as the controller has them)",
                  src, fs::path(src).replace_extension(".dat").string()));
}

}  // namespace

std::vector<std::string> program_output_paths(const std::string& input_path, const std::string& output_path) {
  const std::string ext = to_upper(fs::path(input_path).extension().string());
  if (is_rapid(ext)) {
    return {output_path};
  }
  if (ext == ".SRC") {
    if (to_upper(fs::path(output_path).extension().string()) != ".SRC") {
      throw InputError(
          fmt::format("{}: a KRL program goes to a .src file (its .dat is written beside it)", output_path));
    }
    return {output_path, fs::path(output_path).replace_extension(".dat").string()};
  }
  if (ext == ".DAT") {
    throw InputError(fmt::format("{}: give the program's .src (its .dat is read from beside it)", input_path));
  }
  throw InputError(fmt::format("{}: unknown program type '{}' (ABB RAPID .mod/.modx/.prg/.sys, KUKA KRL .src)",
                               input_path, fs::path(input_path).extension().string()));
}

ProgramCompensation compensate_program(const RobotModel& model, const ForceModel& force, const std::string& input_path,
                                       const std::string& output_path, const ProgramOptions& options) {
  const std::vector<std::string> outputs = program_output_paths(input_path, output_path);
  const bool krl = outputs.size() == 2;
  const auto refuse_same = [&](const std::string& in) {
    for (const std::string& out : outputs) {
      if (same_file(in, out)) {
        throw InputError(
            fmt::format("{}: the compensated program must go to another file than the input {} (it is "
                        "the same file)",
                        out, in));
      }
    }
  };
  refuse_same(input_path);  // before anything is read
  const std::string text = read_input_file(input_path, InputKind::kProgram);
  const std::string dat = krl ? krl_data_list(input_path) : std::string();
  if (krl) {
    refuse_same(dat);
  }
  if (!krl) {
    return compensate_rapid_module(model, force, input_path, text, output_path, options);
  }
  return compensate_krl_program(model, force, input_path, text, dat, read_input_file(dat, InputKind::kProgram),
                                output_path, options);
}

void write_program_outputs(const ProgramCompensation& result) {
  OutputTransaction outputs;
  for (const ProgramFile& f : result.outputs) {
    outputs.add(f.path, "program output").write(f.text);
  }
  outputs.commit();  // all or none: a KRL .src never without its .dat
}

std::string program_summary(const ProgramCompensation& result) {
  std::string s = fmt::format("{} program, force: {}\n", result.language, result.force_description);
  s += fmt::format("targets compensated: {}\n", result.targets.size());
  double max_deflection = 0.0;
  double max_correction = 0.0;
  std::size_t configured = 0;
  for (const ProgramTargetReport& t : result.targets) {
    s += fmt::format("  line {:4}: {} {}: deflection {:.4f} mm, correction {:.4f} mm ({:.5f} deg), {}{}\n", t.line,
                     t.instruction, t.target, t.deflection_m * 1e3, t.correction_m * 1e3,
                     rad_to_deg(t.joint_correction_rad), t.action,
                     t.configuration_note.empty() ? "" : "; configuration: " + t.configuration_note);
    max_deflection = std::max(max_deflection, t.deflection_m);
    max_correction = std::max(max_correction, t.correction_m);
    configured += t.configuration_note.empty() ? 0 : 1;
  }
  s += fmt::format("largest predicted deflection {:.4f} mm, largest correction {:.4f} mm\n", max_deflection * 1e3,
                   max_correction * 1e3);
  if (configured > 0) {
    s += fmt::format("targets whose arm configuration is not their own (ConfJ\\Off, ConfL\\Off, no Status/Turn): {}\n",
                     configured);
  }
  if (!result.unresolved.empty()) {
    s += fmt::format(
        "left unchanged (computed at run time, declared in another module, or an instruction deflex does "
        "not compensate): {}\n",
        result.unresolved.size());
    for (const UnresolvedConstruct& u : result.unresolved) {
      s += fmt::format("  {}:{}: {}: {}\n", u.file, u.line, u.text, u.reason);
    }
  }
  for (const ProgramFile& f : result.outputs) {
    s += fmt::format("wrote {}\n", f.path);
  }
  return s;
}

}  // namespace deflex
