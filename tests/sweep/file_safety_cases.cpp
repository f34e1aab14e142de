// Sweep cases about files themselves: every output option given a path that is an input (the same
// name, a hard link, a symbolic link), a link to a user's file while the run fails, a missing folder
// while the run fails (made, then removed again), a file where a folder should be, a folder, a link to nothing, a FIFO
// nobody reads, /dev/full, two outputs naming one file, and a closed or full stdout; every input option given a FIFO, a
// device, a folder or a file over its kind's size limit. The runner checks after each case that no file of its folder
// was deleted, truncated, changed or added.
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "sweep/sweep_case.hpp"

namespace deflex::test {
namespace {

namespace fs = std::filesystem;

/// An output option of a command, run in a form that succeeds when the output is fine.
struct OutputUse {
  std::string tag;
  std::string command;  ///< {O}: the output under test
  std::string option;   ///< as named in messages: "option -o"
  std::string input;    ///< an input file of the command, in {D} (written by `files`)
  std::vector<std::pair<std::string, std::string>> files;
  std::string failing;  ///< the same command made to fail on its input ({O} kept), "" when none
  std::string extension = "csv";
};

std::vector<OutputUse> output_uses() {
  const std::string path = source_file("examples/offline/square_path.csv");
  // The square path with a point 9 m away: unreachable, the run fails after its outputs are prepared.
  const std::string unreachable = path + "9000,0,1000,0,0,1,0\n";
  const std::string robot = source_file("examples/robots/kuka_kr210_r2700.yaml");
  const std::string measurements = source_file("examples/identify/kr210_synthetic_measurements.csv");
  const std::string module = source_file("examples/programs/deburr_housing.mod");
  const std::string offline = "offline --path {D}/path.csv --force constant:fz_N=-100 ";
  const std::string plan =
      "plan-calibration --robot {D}/robot.yaml --region-mm 1300,1900,-400,400,500,1100 "
      "--load-N 800 --poses 3 --grid 2 ";
  return {
      {"offline_csv",
       offline + "-o {O}",
       "option -o",
       "path.csv",
       {{"path.csv", path}, {"bad.csv", unreachable}},
       replace_all(offline, "path.csv", "bad.csv") + "-o {O}"},
      {"offline_rapid",
       offline + "--rapid {O}",
       "option --rapid",
       "path.csv",
       {{"path.csv", path}, {"bad.csv", unreachable}},
       replace_all(offline, "path.csv", "bad.csv") + "--rapid {O}",
       "mod"},
      {"offline_trajectory",
       offline + "--joint-trajectory {O}",
       "option --joint-trajectory",
       "path.csv",
       {{"path.csv", path}, {"bad.csv", unreachable}},
       replace_all(offline, "path.csv", "bad.csv") + "--joint-trajectory {O}"},
      {"offline_nominal",
       offline + "--nominal-trajectory {O}",
       "option --nominal-trajectory",
       "path.csv",
       {{"path.csv", path}, {"bad.csv", unreachable}},
       replace_all(offline, "path.csv", "bad.csv") + "--nominal-trajectory {O}"},
      {"program_out",
       "offline --program-in {D}/in.mod --force tool:fz_N=-150 --program-out {O}",
       "option --program-out",
       "in.mod",
       {{"in.mod", module}, {"bad.mod", with(module, "MoveL Target_20,", "MoveL Target_20\\Speed:=3,")}},
       "offline --program-in {D}/bad.mod --force tool:fz_N=-150 --program-out {O}",
       "mod"},
      {"write_robot",
       "identify --robot {D}/robot.yaml --data {D}/m.csv --write-robot {O}",
       "option --write-robot",
       "m.csv",
       {{"robot.yaml", robot}, {"m.csv", measurements}, {"bad.csv", with(measurements, "\n", "\n#\n") + "1,2\n"}},
       "identify --robot {D}/robot.yaml --data {D}/bad.csv --write-robot {O}",
       "yaml"},
      {"plan",
       plan + "-o {O}",
       "option -o",
       "robot.yaml",
       {{"robot.yaml", robot}},
       replace_all(plan, "--load-N 800", "--load-N 800 --quaternion-wxyz 2,0,0,0") + "-o {O}"},
      {"plan_synthetic",
       plan + "-o {D}/plan.csv --synthetic-measurements {O}",
       "option --synthetic-measurements",
       "robot.yaml",
       {{"robot.yaml", robot}},
       replace_all(plan, "--load-N 800", "--load-N 800 --quaternion-wxyz 2,0,0,0") +
           "-o {D}/plan.csv --synthetic-measurements {O}"},
      {"payload",
       "identify-payload --data {D}/pl.csv -o {O}",
       "option -o",
       "pl.csv",
       {{"pl.csv", source_file("examples/online/payload_poses.csv")}},
       "identify-payload --data {D}/pl.csv --sensor-config {D}/none.yaml -o {O}",
       "yaml"},
  };
}

void add_output_cases(const OutputUse& u, std::vector<BadInput>& cases) {
  const auto cmd = [&](const std::string& out) { return replace_all(u.command, "{O}", out); };
  const std::string name = "out_" + u.tag + "_";
  const std::string o = "out." + u.extension;
  cases.push_back({name + "same_file", cmd("{D}/" + u.input), u.files, {"{D}/" + u.input, "the same file"}});
  cases.push_back({name + "hard_link",
                   cmd("{D}/hard." + u.extension),
                   u.files,
                   {"the same file"},
                   2,
                   [input = u.input, ext = u.extension](const fs::path& d) {
                     fs::create_hard_link(d / input, d / ("hard." + ext));
                   }});
  cases.push_back(
      {name + "link_to_input", cmd("{D}/" + o), u.files, {"the same file"}, 2, [input = u.input, o](const fs::path& d) {
         fs::create_symlink(input, d / o);
       }});
  // A missing folder is made for the output (every command alike), and removed again when the run
  // fails: the scratch folder holds what it held. A file where a folder should be is named.
  cases.push_back(
      {name + "missing_folder_run_fails", replace_all(u.failing, "{O}", "{D}/nodir/deeper/" + o), u.files, {}, 2});
  cases.push_back({name + "file_on_the_way",
                   cmd("{D}/afile/" + o),
                   [&] {
                     auto f = u.files;
                     f.emplace_back("afile", "a user's file\n");
                     return f;
                   }(),
                   {u.option, "'{D}/afile' is not a directory"}});
  cases.push_back({name + "folder", cmd("{D}/sub"), u.files, {u.option, "is a directory"}, 2, [](const fs::path& d) {
                     fs::create_directories(d / "sub");
                   }});
  cases.push_back({name + "dangling_link",
                   cmd("{D}/" + o),
                   u.files,
                   {u.option, "symbolic link to nothing"},
                   2,
                   [o](const fs::path& d) { fs::create_symlink("nowhere", d / o); }});
  cases.push_back(
      {name + "fifo_no_reader", cmd("{D}/pipe"), u.files, {u.option, "no process reads"}, 2, [](const fs::path& d) {
         ::mkfifo((d / "pipe").c_str(), 0600);
       }});
  // /dev/full takes no byte: the job failed (exit 1), the device stays (checked at the sweep's end).
  if (u.tag != "program_out") {
    cases.push_back({name + "dev_full", cmd("/dev/full"), u.files, {"'/dev/full'", "No space left on device"}, 1});
  }
  if (!u.failing.empty()) {
    // The case: the output a link to a user's file, the run failing: link and file untouched.
    cases.push_back({name + "link_kept_on_failure",
                     replace_all(u.failing, "{O}", "{D}/" + o),
                     [&] {
                       auto f = u.files;
                       f.emplace_back("user_file.txt", "a user's file, not deflex's\n");
                       return f;
                     }(),
                     {},
                     2,
                     [o](const fs::path& d) { fs::create_symlink("user_file.txt", d / o); }});
  }
}

}  // namespace

std::vector<BadInput> output_cases() {
  std::vector<BadInput> cases;
  for (const OutputUse& u : output_uses()) {
    add_output_cases(u, cases);
  }
  const std::string offline = "offline --circle default --force constant:fz_N=-100 ";
  cases.push_back({"out_two_outputs_one_file", offline + "-o {D}/o.csv --rapid {D}/o.csv", {}, {"are the same file"}});
  cases.push_back({"out_two_outputs_through_a_link",
                   offline + "-o {D}/o.csv --joint-trajectory {D}/sub/../o.csv",
                   {},
                   {"are the same file"},
                   2,
                   [](const fs::path& d) { fs::create_directories(d / "sub"); }});
  cases.push_back({"out_two_loads_two_outputs_one_name",
                   "offline --circle default --force 'constant:fz_N=-100' "
                   "--force 'constant:fz_N=-200' -o {D}/o.mod --rapid {D}/o.mod",
                   {},
                   {"are the same file"}});
  cases.push_back({"out_krl_dat_is_the_input_dat",
                   "offline --robot {S}/examples/robots/kuka_kr210_r3100_2_flange.yaml --program-in {D}/p.src "
                   "--force tool:fx_N=-150 --tooldata 'TOOL_DATA[1]={X 250,Y 0,Z 0,A 0,B 0,C 0}' --tooldata "
                   "'TOOL_DATA[2]={X 320,Y 0,Z 40,A 0,B -10,C 0}' --wobjdata 'BASE_DATA[1]={X 1800,Y -300,Z 500,A 0,B "
                   "0,C 0}' --program-out {D}/q.src",
                   {{"p.src", source_file("examples/programs/deburr_bracket.src")},
                    {"p.dat", source_file("examples/programs/deburr_bracket.dat")}},
                   {"the same file"},
                   2,
                   [](const fs::path& d) { fs::create_hard_link(d / "p.dat", d / "q.dat"); }});
  // One output that cannot be written must stop the others too: the o.csv was left behind.
  const std::string square = "offline --path {S}/examples/offline/square_path.csv --force constant:fz_N=-100 ";
  cases.push_back({"out_all_or_none_rapid_under_a_file",
                   square + "-o {D}/o.csv --rapid {D}/afile/o.mod",
                   {{"afile", "x\n"}},
                   {"option --rapid", "is not a directory"}});
  cases.push_back({"out_all_or_none_trajectory_under_a_file",
                   square + "-o {D}/o.csv --joint-trajectory {D}/afile/t.csv",
                   {{"afile", "x\n"}},
                   {"option --joint-trajectory"}});
  // The folder made for one output goes again when another cannot be written: all or none.
  cases.push_back({"out_all_or_none_new_folder_removed",
                   square + "-o {D}/new/deeper/o.csv --rapid /dev/full",
                   {},
                   {"'/dev/full'", "No space left on device"},
                   1});
  cases.push_back({"out_all_or_none_rapid_to_dev_full",
                   square + "-o {D}/o.csv --rapid /dev/full",
                   {},
                   {"'/dev/full'", "No space left on device"},
                   1});
  cases.push_back({"out_all_or_none_synthetic_under_a_file",
                   "plan-calibration --robot builtin --region-mm 1300,1900,-400,400,500,1100 --load-N 800 --poses 3 "
                   "--grid 2 -o {D}/p.csv --synthetic-measurements {D}/afile/s.csv",
                   {{"afile", "x\n"}},
                   {"option --synthetic-measurements", "is not a directory"}});
  cases.push_back({"out_all_or_none_krl_dat_unwritable",
                   "offline --robot {S}/examples/robots/kuka_kr210_r3100_2_flange.yaml --program-in "
                   "{S}/examples/programs/deburr_bracket.src --force tool:fx_N=-150 --tooldata 'TOOL_DATA[1]={X 250,Y "
                   "0,Z 0,A 0,B 0,C 0}' --tooldata 'TOOL_DATA[2]={X 320,Y 0,Z 40,A 0,B -10,C 0}' --wobjdata "
                   "'BASE_DATA[1]={X 1800,Y -300,Z 500,A 0,B 0,C 0}' --program-out {D}/out.src",
                   {},
                   {"{D}/out.dat", "is a directory"},
                   2,
                   [](const fs::path& d) { fs::create_directories(d / "out.dat"); }});
  cases.push_back({"out_case_study_out_is_a_file",
                   "case-study --quick --seeds 1 --no-sweep --no-budget --no-progress "
                   "--out {D}/report.txt",
                   {{"report.txt", "a user's file\n"}},
                   {"option --out", "report.txt' is not a directory"}});
  // stdout that cannot be written: the job failed, said on stderr.
  for (const auto& [tag, args] : std::vector<std::pair<std::string, std::string>>{
           {"fk", "fk --joints-deg 0,30,10,0,50,0"},
           {"fk_json", "fk --joints-deg 0,30,10,0,50,0 --json"},
           {"deflect", "deflect --joints-deg 0,30,10,0,50,0 --wrench 0,0,-125,0,0,0"},
           {"robot", "robot"},
           {"offline_summary", offline + "--json"}}) {
    cases.push_back({"stdout_closed_" + tag, args, {}, {"writing to stdout failed"}, 1, {}, "-"});
    cases.push_back(
        {"stdout_full_" + tag, args, {}, {"writing to stdout failed", "No space left"}, 1, {}, "/dev/full"});
  }
  cases.push_back({"stdout_closed_as_output", offline + "-o /dev/stdout", {}, {"stdout is closed"}, 2, {}, "-"});
  return cases;
}

std::vector<BadInput> input_file_cases() {
  struct InputUse {
    std::string tag;
    std::string command;  ///< {I}: the input under test
    std::string name;     ///< the file's name, its extension chooses the reader
    std::uint64_t over;   ///< a size over its kind's limit
  };
  const std::uint64_t mib = std::uint64_t{1} << 20;
  const std::string robot = "{S}/examples/robots/kuka_kr210_r2700.yaml";
  const std::vector<InputUse> uses = {
      {"fk_robot_yaml", "fk --robot {I} --joints-deg 0,30,10,0,50,0", "r.yaml", 16 * mib + 1},
      {"fk_robot_urdf", "fk --robot {I} --joints-deg 0,30,10,0,50,0", "r.urdf", 64 * mib + 1},
      {"offline_path", "offline --path {I} --force constant:fz_N=-1 -o {D}/o.csv", "p.csv", 16384 * mib + 1},
      {"offline_table", "offline --path {S}/examples/offline/square_path.csv --force table:{I} -o {D}/o.csv", "w.csv",
       1024 * mib + 1},
      {"offline_rapid", "offline --program-in {I} --force tool:fz_N=-1 --program-out {D}/o.mod", "p.mod", 64 * mib + 1},
      {"offline_krl", "offline --program-in {I} --force tool:fz_N=-1 --program-out {D}/o.src", "p.src", 64 * mib + 1},
      {"identify_data", "identify --robot " + robot + " --data {I}", "m.csv", 16384 * mib + 1},
      {"identify_robot", "identify --robot {I} --data {S}/examples/identify/kr210_synthetic_measurements.csv", "r.yaml",
       16 * mib + 1},
      {"plan_synthetic_robot",
       "plan-calibration --robot " + robot +
           " --region-mm 1300,1900,-400,400,500,1100 --load-N 800 --poses 3 --grid 2 -o {D}/p.csv "
           "--synthetic-measurements {D}/s.csv --synthetic-robot {I}",
       "t.yaml", 16 * mib + 1},
      {"payload_data", "identify-payload --data {I} -o {D}/p.yaml", "pl.csv", 1024 * mib + 1},
      {"payload_sensor",
       "identify-payload --data {S}/examples/online/payload_poses.csv --sensor-config {I} -o {D}/p.yaml", "s.yaml",
       16 * mib + 1},
      {"evaluate_unloaded", "evaluate --unloaded {I} --loaded {S}/examples/evaluate/loaded_uc.csv", "u.csv",
       1024 * mib + 1},
      {"evaluate_commanded",
       "evaluate --unloaded {S}/examples/evaluate/unloaded.csv --loaded {S}/examples/evaluate/loaded_uc.csv "
       "--commanded {I}",
       "c.csv", 1024 * mib + 1},
      {"case_study_case", "case-study --case {I} --quick --seeds 1 --no-progress --out {D}/cs", "case.yaml",
       16 * mib + 1},
  };
  std::vector<BadInput> cases;
  for (const InputUse& u : uses) {
    const auto cmd = [&](const std::string& in) { return replace_all(u.command, "{I}", in); };
    const std::string file = u.name;
    cases.push_back(
        {"in_" + u.tag + "_fifo", cmd("{D}/" + file), {}, {"{D}/" + file, "is a FIFO"}, 2, [file](const fs::path& d) {
           ::mkfifo((d / file).c_str(), 0600);
         }});
    cases.push_back({"in_" + u.tag + "_dev_zero",
                     cmd("{D}/" + file),
                     {},
                     {"{D}/" + file, "is a character device"},
                     2,
                     [file](const fs::path& d) { fs::create_symlink("/dev/zero", d / file); }});
    cases.push_back({"in_" + u.tag + "_folder",
                     cmd("{D}/" + file),
                     {},
                     {"{D}/" + file, "is a directory"},
                     2,
                     [file](const fs::path& d) { fs::create_directories(d / file); }});
    // A sparse file one byte over the limit: refused from its size before a byte is read.
    cases.push_back({"in_" + u.tag + "_oversize",
                     cmd("{D}/" + file),
                     {},
                     {"{D}/" + file, std::to_string(u.over) + " bytes; deflex reads"},
                     2,
                     [file, size = u.over](const fs::path& d) {
                       std::ofstream(d / file).close();
                       fs::resize_file(d / file, size);
                     }});
  }
  // The URDF a robot YAML names, and the .dat beside a KRL program, are inputs too.
  cases.push_back({"in_urdf_named_by_yaml_fifo",
                   "fk --robot {D}/r.yaml --joints-deg 0,30,10,0,50,0",
                   {{"r.yaml",
                     "deflex_robot: 1\nunits: {length: m, angle: deg}\nkinematics: {convention: urdf, file: "
                     "arm.urdf}\n"}},
                   {"{D}/arm.urdf", "is a FIFO"},
                   2,
                   [](const fs::path& d) { ::mkfifo((d / "arm.urdf").c_str(), 0600); }});
  cases.push_back({"in_krl_dat_fifo",
                   "offline --program-in {D}/p.src --force tool:fz_N=-1 --program-out {D}/o.src",
                   {{"p.src", source_file("examples/programs/deburr_bracket.src")}},
                   {"{D}/p.dat", "is a FIFO"},
                   2,
                   [](const fs::path& d) { ::mkfifo((d / "p.dat").c_str(), 0600); }});
  return cases;
}

std::string with(const std::string& text, const std::string& from, const std::string& to) {
  const auto p = text.find(from);
  if (p == std::string::npos) {
    throw std::runtime_error("sweep: anchor not found: " + from);
  }
  std::string out = text;
  out.replace(p, from.size(), to);
  return out;
}

}  // namespace deflex::test
