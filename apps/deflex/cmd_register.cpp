// `deflex register`: the tracker-to-base transform from points (and circles) measured in both frames.
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/evaluate/frame_registration.hpp"
#include "deflex/evaluate/tracker_files.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"
#include "tracker_options.hpp"

namespace deflex::cli {
namespace {

struct RegisterOpts {
  std::string tracker, base, out;
  std::vector<std::string> tracker_circles, base_circles;
  double max_rms_mm = kDefaultMaxRegistrationRmsM * 1e3;
  bool json = false;
  TrackerReadOptions read;
};

CircleFit circle_of(const std::string& path, const TrackerReadOptions& read) {
  const TrackerFile f = read_tracker_file(path, read);
  std::vector<Vector3> pts;
  for (const auto& p : f.points) pts.push_back(p.p_m);
  return fit_circle(pts, path);
}

void add_register_options(CLI::App& sub, RegisterOpts& o) {
  sub.add_option("--tracker", o.tracker,
                 "Points measured by the tracker, in its frame (SA export or CSV x_mm,y_mm,z_mm); named points pair "
                 "with --base by name, unnamed ones by order");
  sub.add_option("--base", o.base, "The same points in the robot's base frame (SA export or CSV)");
  sub.add_option("--tracker-circle", o.tracker_circles,
                 "Points measured in order along a circle (a joint turned alone, or the TCP on a commanded circle); "
                 "repeat for several circles");
  sub.add_option("--base-circle", o.base_circles,
                 "The same circle in the base frame, in the same direction of travel (e.g. the commanded path); one "
                 "per --tracker-circle, in the same order");
  sub.add_option("-o,--out", o.out, "Frame file to write (YAML), for deflex evaluate --tracker-frame")->required();
  sub.add_option("--max-rms-mm", o.max_rms_mm,
                 "The largest registration RMS accepted, mm: above it the frame is refused and not written (pairs "
                 "mixed up, a unit slip, a nest that moved); raise it for base points known only to a robot's "
                 "absolute accuracy")
      ->capture_default_str();
  add_tracker_format_options(sub, o.read);
  sub.add_flag("--json", o.json, "Print one JSON document on stdout");
}

// The points and circles of both frames, paired; the tracker file's frame name in tracker_frame.
RegistrationInput read_registration_input(const RegisterOpts& o, std::string& tracker_frame) {
  RegistrationInput in;
  in.max_rms_m = o.max_rms_mm * 1e-3;
  TrackerReadOptions base_read = o.read;
  base_read.expect_frame.clear();  // the base files are in the robot's frame, whatever they call it
  if (!o.tracker.empty()) {
    const TrackerFile t = read_tracker_file(o.tracker, o.read);
    const TrackerFile b = read_tracker_file(o.base, base_read);
    tracker_frame = t.frame;
    const RegistrationInput pairs = pair_tracker_points(t, b);
    in.tracker_m = pairs.tracker_m;
    in.base_m = pairs.base_m;
    in.names = pairs.names;
  }
  for (std::size_t k = 0; k < o.tracker_circles.size(); ++k) {
    in.tracker_circles.push_back(circle_of(o.tracker_circles[k], o.read));
    in.base_circles.push_back(circle_of(o.base_circles[k], base_read));
  }
  return in;
}

FrameRegistration register_or_name_files(const RegisterOpts& o, const RegistrationInput& in) {
  try {
    return register_frames(in);
  } catch (const InputError& e) {
    std::string files = o.tracker.empty() ? "" : o.tracker + " and " + o.base;
    for (std::size_t k = 0; k < o.tracker_circles.size(); ++k) {
      files += (files.empty() ? "" : ", ") + o.tracker_circles[k] + " and " + o.base_circles[k];
    }
    throw InputError(fmt::format("{}: {}", files, e.what()));
  }
}

void print_register_json(const RegisterOpts& o, const RegistrationInput& in, const FrameRegistration& r,
                         const std::string& tracker_frame) {
  const Eigen::Quaterniond q(r.base_T_tracker.linear());
  const Vector3 t = r.base_T_tracker.translation();
  nlohmann::json residuals = nlohmann::json::array();
  for (const auto& e : r.residuals) residuals.push_back({{"name", e.name}, {"distance_mm", e.distance_m * 1e3}});
  nlohmann::json circles = nlohmann::json::array();
  for (std::size_t k = 0; k < r.circles; ++k) {
    circles.push_back({{"tracker_radius_mm", in.tracker_circles[k].radius_m * 1e3},
                       {"base_radius_mm", in.base_circles[k].radius_m * 1e3},
                       {"tracker_fit_rms_mm", in.tracker_circles[k].rms_m * 1e3},
                       {"axis_error_mrad", r.circle_axis_error_rad[k] * 1e3}});
  }
  print_json({{"frame_file", o.out},
              {"tracker_frame", tracker_frame},
              {"position_mm", {t.x() * 1e3, t.y() * 1e3, t.z() * 1e3}},
              {"quaternion_wxyz", {q.w(), q.x(), q.y(), q.z()}},
              {"rms_mm", r.rms_m * 1e3},
              {"max_mm", r.max_m * 1e3},
              {"rms_limit_mm", in.max_rms_m * 1e3},
              {"residuals", residuals},
              {"circles", circles}});
}

void print_register_text(const RegisterOpts& o, const RegistrationInput& in, const FrameRegistration& r,
                         const std::string& tracker_frame) {
  const Eigen::Quaterniond q(r.base_T_tracker.linear());
  const Vector3 t = r.base_T_tracker.translation();
  std::cout << fmt::format("Tracker frame{} -> robot base: {} point pair(s), {} circle(s)\n",
                           tracker_frame.empty() ? "" : fmt::format(" '{}'", tracker_frame), r.points, r.circles);
  std::cout << fmt::format("  position {:.4f}, {:.4f}, {:.4f} mm; quaternion w x y z {:.9f}, {:.9f}, {:.9f}, {:.9f}\n",
                           t.x() * 1e3, t.y() * 1e3, t.z() * 1e3, q.w(), q.x(), q.y(), q.z());
  std::cout << "  residual per point, mm:\n";
  for (const auto& e : r.residuals) std::cout << fmt::format("    {:<28} {:.4f}\n", e.name, e.distance_m * 1e3);
  for (std::size_t k = 0; k < r.circles; ++k) {
    std::cout << fmt::format(
        "  circle {}: radius {:.4f} mm measured, {:.4f} mm in the base frame; fit RMS {:.4f} mm; "
        "axis {:.3f} mrad off after the transform\n",
        k + 1, in.tracker_circles[k].radius_m * 1e3, in.base_circles[k].radius_m * 1e3,
        in.tracker_circles[k].rms_m * 1e3, r.circle_axis_error_rad[k] * 1e3);
  }
  std::cout << fmt::format("  RMS {:.4f} mm (limit {:g} mm), max {:.4f} mm; written to {}\n", r.rms_m * 1e3,
                           in.max_rms_m * 1e3, r.max_m * 1e3, o.out);
}

void run_register(const RegisterOpts& o) {
  if (o.tracker.empty() != o.base.empty()) throw InputError("options --tracker and --base: give both or neither");
  if (o.tracker_circles.size() != o.base_circles.size()) {
    throw InputError(fmt::format("{} --tracker-circle and {} --base-circle: one base circle per tracker circle",
                                 o.tracker_circles.size(), o.base_circles.size()));
  }
  OutputFile out(o.out, "option --out");
  std::string tracker_frame;
  const RegistrationInput in = read_registration_input(o, tracker_frame);
  const FrameRegistration r = register_or_name_files(o, in);
  TrackerFrame frame;
  frame.base_T_tracker = r.base_T_tracker;
  frame.tracker_frame = tracker_frame;
  frame.rms_m = r.rms_m;
  frame.max_m = r.max_m;
  frame.rms_limit_m = in.max_rms_m;
  frame.points = r.points;
  frame.circles = r.circles;
  write_tracker_frame(frame, out);
  out.commit();
  if (o.json) {
    print_register_json(o, in, r, tracker_frame);
  } else {
    print_register_text(o, in, r, tracker_frame);
  }
}

void setup_register(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<RegisterOpts>();
  add_register_options(sub, *o);
  sub.callback([o, &exit_code] {
    run_register(*o);
    exit_code = 0;
  });
}

}  // namespace

DEFLEX_COMMAND("register",
               "The tracker-to-robot-base transform from points (and circles) measured in both frames, for "
               "deflex evaluate --tracker-frame: residual per point in mm",
               setup_register, 61);

}  // namespace deflex::cli
