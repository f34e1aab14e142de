// Entry point of program compensation: which reader, the files, the summary.
#include "deflex/offline/program_compensation.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"
#include "deflex/offline/krl_program.hpp"
#include "deflex/offline/rapid_program.hpp"
#include "deflex/offline/program_text.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw DataError(fmt::format("{}: cannot read the program", path));
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  return fs::weakly_canonical(a, ec) == fs::weakly_canonical(b, ec);
}

}  // namespace

ProgramCompensation compensate_program(const RobotModel& model, const ForceModel& force, const std::string& input_path,
                                       const std::string& output_path, const ProgramOptions& options) {
  const std::string ext = to_upper(fs::path(input_path).extension().string());
  const std::string out_ext = to_upper(fs::path(output_path).extension().string());
  if (same_file(input_path, output_path)) {
    throw InputError(fmt::format("{}: the compensated program must go to another file than the input", output_path));
  }
  if (ext == ".MOD" || ext == ".MODX" || ext == ".PRG" || ext == ".SYS") {
    return compensate_rapid_module(model, force, input_path, read_text(input_path), output_path, options);
  }
  if (ext == ".SRC") {
    if (out_ext != ".SRC") {
      throw InputError(
          fmt::format("{}: a KRL program goes to a .src file (its .dat is written beside it)", output_path));
    }
    const std::string dat = fs::path(input_path).replace_extension(".dat").string();
    std::string dat_file;
    std::string dat_text;
    if (fs::exists(dat)) {
      dat_file = dat;
      dat_text = read_text(dat);
    } else if (const std::string upper = fs::path(input_path).replace_extension(".DAT").string(); fs::exists(upper)) {
      dat_file = upper;
      dat_text = read_text(upper);
    }
    if (!dat_file.empty() && same_file(dat_file, fs::path(output_path).replace_extension(".dat").string())) {
      throw InputError(fmt::format("{}: writing it would overwrite the input's data list {}", output_path, dat_file));
    }
    return compensate_krl_program(model, force, input_path, read_text(input_path), dat_file, dat_text, output_path,
                                  options);
  }
  if (ext == ".DAT") {
    throw InputError(fmt::format("{}: give the program's .src (its .dat is read from beside it)", input_path));
  }
  throw InputError(fmt::format("{}: unknown program type '{}' (ABB RAPID .mod/.modx/.prg/.sys, KUKA KRL .src)",
                               input_path, fs::path(input_path).extension().string()));
}

void write_program_outputs(const ProgramCompensation& result) {
  for (const ProgramFile& f : result.outputs) {
    std::ofstream out(f.path, std::ios::binary);
    if (!out) {
      throw Error(fmt::format("{}: cannot write the file", f.path));
    }
    out << f.text;
    if (!out) {
      throw Error(fmt::format("{}: write failed", f.path));
    }
  }
}

std::string program_summary(const ProgramCompensation& result) {
  std::string s = fmt::format("{} program, force: {}\n", result.language, result.force_description);
  s += fmt::format("targets compensated: {}\n", result.targets.size());
  double max_deflection = 0.0;
  double max_correction = 0.0;
  for (const ProgramTargetReport& t : result.targets) {
    s += fmt::format("  line {:4}: {} {}: deflection {:.4f} mm, correction {:.4f} mm ({:.5f} deg), {}\n", t.line,
                     t.instruction, t.target, t.deflection_m * 1e3, t.correction_m * 1e3,
                     rad_to_deg(t.joint_correction_rad), t.action);
    max_deflection = std::max(max_deflection, t.deflection_m);
    max_correction = std::max(max_correction, t.correction_m);
  }
  s += fmt::format("largest predicted deflection {:.4f} mm, largest correction {:.4f} mm\n", max_deflection * 1e3,
                   max_correction * 1e3);
  if (!result.unresolved.empty()) {
    s += fmt::format("left unchanged (not resolvable before the program runs): {}\n", result.unresolved.size());
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
