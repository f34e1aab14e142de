// Sweep cases about measurement files and their set-up: tracker files (SA exports read in the wrong
// unit, CSV time going back, positions in two units), the registration (a mirror image, a residual
// far above a tracker's noise, a frame file whose registration failed), the commanded path of a clock
// alignment, and an RDT sensor's calibration page with counts no sensor has. Each must be refused
// with its file and line (or its option), exit 2, and leave every file as it was: the poses file a
// recording would have grown, the frame file a registration would have written.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>

#include "sweep/sweep_case.hpp"

namespace deflex::test {
namespace {

/// An SA export of `points` circle points in the given unit's numbers, under the given header unit.
std::string sa_circle(const std::string& header_unit, double scale) {
  std::string s = "// SA Version: 2023.1\n// Working Frame: AT960 Tracker\n// Units: " + header_unit +
                  "\n// Columns: Collection Group Target X Y Z Time\n";
  for (int i = 0; i < 100; ++i) {
    const double a = 2.0 * 3.14159265358979 * i / 100.0;
    char line[200];
    std::snprintf(line, sizeof line, "Job Run P%03d %.6f %.6f %.6f %.3f\n", i + 1, (1.5 + 0.1 * std::cos(a)) * scale,
                  0.1 * std::sin(a) * scale, 0.9 * scale, 0.01 * i);
    s += line;
  }
  return s;
}

void add_tracker_file_cases(std::vector<BadInput>& cases) {
  const std::string loaded = "{S}/examples/evaluate/loaded_uc.csv";
  // Millimetre numbers under a "Meters" header: 1500 m from the origin, refused at the first point.
  const std::string mm_as_m = sa_circle("Meters", 1000.0);
  cases.push_back({"tracker_sa_millimetres_under_meters",
                   "evaluate --unloaded {D}/u.txt --loaded " + loaded,
                   {{"u.txt", mm_as_m}},
                   {"{D}/u.txt:" + std::to_string(line_number_of(mm_as_m, "Job Run P001")) + ": field 4 (x)",
                    "outside -100..100 m", "the header, line 3"}});
  // The same file read with the unit it was written in is fine (as a check the case tests the unit).
  std::string back = "t_s,x_mm,y_mm,z_mm\n0,1930,0,900\n0.02,1931,1,900\n0.01,1932,2,900\n0.03,1933,3,900\n";
  cases.push_back({"tracker_csv_time_goes_back",
                   "evaluate --unloaded {D}/u.csv --loaded " + loaded,
                   {{"u.csv", back}},
                   {"{D}/u.csv:4: column 't_s': time goes backwards", "(0.01 s after 0.02 s on line 3)"}});
  cases.push_back({"tracker_csv_two_units",
                   "evaluate --unloaded {D}/u.csv --loaded " + loaded,
                   {{"u.csv", "t_s,x_mm,y_mm,z_mm,x_m\n0,1930,0,900,1.93\n0.02,1931,1,900,1.931\n"}},
                   {"{D}/u.csv", "columns 'x_mm' and 'x_m'"}});
  cases.push_back(
      {"align_to_two_units",
       "evaluate --unloaded {S}/examples/evaluate/unloaded.csv --loaded " + loaded + " --align-to {D}/command.csv",
       {{"command.csv",
         "t_s,x_mm,y_mm,z_mm,x_m,y_m,z_m\n0,1930,0,900,1.93,0,0.9\n"
         "0.02,1931,1,900,1.931,0.001,0.9\n"}},
       {"{D}/command.csv", "columns 'x_mm' and 'x_m'", "two units"}});
}

void add_registration_cases(std::vector<BadInput>& cases) {
  const std::string tracker = "{S}/examples/evaluate/session/tracker_points.txt";
  const std::string base = source_file("examples/evaluate/session/base_points.txt");
  // The base points with y negated: a mirror image of the tracker's (the 1052 mm case).
  std::string mirrored;
  for (std::size_t at = 0; at < base.size();) {
    const auto end = std::min(base.find('\n', at), base.size());
    std::string line = base.substr(at, end - at);
    if (line.rfind("REF", 0) == 0) {
      const auto a = line.find(' '), b = line.find(' ', a + 1);
      const std::string y = line.substr(a + 1, b - a - 1);
      line = line.substr(0, a + 1) + (y[0] == '-' ? y.substr(1) : "-" + y) + line.substr(b);
    }
    mirrored += line + "\n";
    at = end + 1;
  }
  cases.push_back({"register_mirror_image",
                   "register --tracker " + tracker + " --base {D}/base.txt -o {D}/frame.yaml --json",
                   {{"base.txt", mirrored}},
                   {"{D}/base.txt", "mirror image", "a reflection would fit them"}});
  // One nest 8 mm off: far above a tracker's noise, refused with the point named and no frame written.
  cases.push_back({"register_rms_above_the_limit",
                   "register --tracker " + tracker + " --base {D}/base.txt -o {D}/frame.yaml",
                   {{"base.txt", with(base, "REF3 1800.000 600.000", "REF3 1808.000 600.000")}},
                   {"above the limit of 1.0000 mm", "REF3", "--max-rms-mm"}});
  cases.push_back({"register_max_rms_zero",
                   "register --tracker " + tracker +
                       " --base {S}/examples/evaluate/session/base_points.txt -o "
                       "{D}/frame.yaml --max-rms-mm 0",
                   {},
                   {"--max-rms-mm"}});
  // A frame file whose registration failed (written by hand, or before registrations were checked).
  const std::string frame =
      "tracker_frame: \"AT960 Tracker\"\nbase_T_tracker:\n  position: [4.1, -2.3, 0.35]\n"
      "  quaternion_wxyz: [0.5, 0.0845, 0.169, 0.8452]\nregistration:\n  points: 6\n  circles: 0\n"
      "  rms_mm: 1052.0\n  max_mm: 1480.0\n";
  cases.push_back({"evaluate_failed_frame",
                   "evaluate --tracker-frame {D}/frame.yaml --unloaded "
                   "{S}/examples/evaluate/session/unloaded.sa.txt --loaded "
                   "{S}/examples/evaluate/session/loaded_uc.sa.txt",
                   {{"frame.yaml", frame}},
                   {"{D}/frame.yaml:8:", "field 'registration.rms_mm'", "the frame failed"}});
}

void add_rdt_calibration_cases(std::vector<BadInput>& cases) {
  const std::string page = source_file("examples/online/rdt_netftapi2.xml");
  const std::string record =
      "identify-payload --force-source rdt:127.0.0.1:1 --rdt-calibration {D}/page.xml "
      "--joints-deg 0,0,0,0,90,0 --record {D}/poses.csv";
  // A poses file as an earlier recording left it: a new pose would be added to it.
  const std::string poses =
      "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm\n0,0,0,0,90,0,1.5,-0.7,85.5,0.1,0,"
      "0\n";
  // 1e300 counts per N read the sensor's 10 N as zero force; 1e-300 wrote 1e307 N into the poses file.
  for (const auto& [tag, field, value] :
       {std::tuple{"force_1e300", "cfgcpf", "1e300"}, std::tuple{"force_1e-300", "cfgcpf", "1e-300"},
        std::tuple{"torque_1e-300", "cfgcpt", "1e-300"}}) {
    const std::string open = std::string("<") + field + ">";
    const std::string bad = with(page, open + "1000000<", open + value + "<");
    cases.push_back(
        {std::string("rdt_page_counts_") + tag,
         record,
         {{"page.xml", bad}, {"poses.csv", poses}},
         {"{D}/page.xml:" + std::to_string(line_number_of(bad, open)) + ": field '" + field + "'", "make one count"}});
  }
  cases.push_back({"rdt_counts_option_1e-300",
                   "identify-payload --force-source rdt:127.0.0.1:1 --rdt-rate-hz 1000 --rdt-calibration "
                   "counts:counts_per_force=1e-300,counts_per_torque=1000000,force_unit=N,torque_unit=Nm "
                   "--joints-deg 0,0,0,0,90,0 --record {D}/poses.csv",
                   {{"poses.csv", poses}},
                   {"--rdt-calibration counts:", "counts per force", "make one count"}});
}

}  // namespace

std::vector<BadInput> tracker_sensor_cases() {
  std::vector<BadInput> cases;
  add_tracker_file_cases(cases);
  add_registration_cases(cases);
  add_rdt_calibration_cases(cases);
  return cases;
}

}  // namespace deflex::test
