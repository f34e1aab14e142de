// Robot description files: deflex YAML, URDF chains, the built-in IRB6700.
#include "deflex/robotfile/robot_io.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <urdf_parser/urdf_parser.h>

#include "deflex/robotfile/detail/urdf_tree.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/output_file.hpp"
#include "deflex/text/yaml_fields.hpp"

namespace deflex {

// Defined in the source generated from data/robots/abb_irb6700_300_270.yaml (module.cmake).
extern const char* const kBuiltinIrb6700Yaml;

namespace {

namespace fs = std::filesystem;

struct Units {
  double length = 1.0;  // to m
  double angle = 1.0;   // to rad
};

Units parse_units(const yaml::Field& root) {
  Units u;
  if (!root.has("units")) {
    root.fail("missing 'units' (say {length: m|mm, angle: deg|rad}, so no number is read in the wrong unit)");
  }
  const yaml::Field f = root.at("units");
  f.only_keys({"length", "angle"});
  const std::string len = f.at("length").as_string();
  const std::string ang = f.at("angle").as_string();
  if (len == "m") {
    u.length = 1.0;
  } else if (len == "mm") {
    u.length = 1e-3;
  } else {
    f.at("length").fail(fmt::format("unknown length unit '{}' (use m or mm)", len));
  }
  if (ang == "rad") {
    u.angle = 1.0;
  } else if (ang == "deg") {
    u.angle = kPi / 180.0;
  } else {
    f.at("angle").fail(fmt::format("unknown angle unit '{}' (use deg or rad)", ang));
  }
  return u;
}

Pose urdf_pose(const urdf::Pose& p) {
  Pose out = Pose::Identity();
  out.translation() = Vector3(p.position.x, p.position.y, p.position.z);
  out.linear() =
      Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  return out;
}

}  // namespace

RobotDescription load_urdf_chain(const std::string& path, const std::string& base_link, const std::string& tip_link) {
  std::string text;
  try {
    text = read_input_file(path, InputKind::kUrdf);
  } catch (const DataError& e) {
    throw ModelError(e.what());
  }
  // The structure first, with line numbers; urdfdom then gives the numbers of a tree known to be valid.
  const UrdfTree tree = read_urdf_tree(path, text);
  const UrdfChain chain = choose_urdf_chain(tree, base_link, tip_link);
  const urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDF(text);
  if (!urdf_model) {
    throw ModelError(fmt::format("{}: not a valid URDF document (urdfdom could not parse it)", path));
  }
  RobotDescription d;
  d.name = urdf_model->getName();
  d.source = path;
  d.urdf_file = fs::absolute(path).string();
  d.urdf_base_link = chain.base_link;
  d.urdf_tip_link = chain.tip_link;
  d.notes = chain.notes;
  Pose pending = Pose::Identity();
  for (const std::string& name : chain.joints) {
    const urdf::JointConstSharedPtr j = urdf_model->getJoint(name);
    if (!j) {
      throw ModelError(fmt::format("{}: joint '{}' not found by urdfdom", path, name));
    }
    const auto& xyz = j->parent_to_joint_origin_transform.position;
    for (const double v : {xyz.x, xyz.y, xyz.z}) {
      if (const auto bad = range_violation(v, range::kLengthM)) {
        throw ModelError(fmt::format("{}: joint '{}': origin xyz: {}", path, name, *bad));
      }
    }
    if (j->limits) {
      for (const double v : {j->limits->lower, j->limits->upper}) {
        if (const auto bad = range_violation(v, range::kAngleRad)) {
          throw ModelError(fmt::format("{}: joint '{}': limit: {}", path, name, *bad));
        }
      }
      if (const auto bad = range_violation(j->limits->velocity, {"joint speed", "rad/s", 0.0, 100.0})) {
        throw ModelError(fmt::format("{}: joint '{}': limit velocity: {}", path, name, *bad));
      }
    }
    const Pose origin = urdf_pose(j->parent_to_joint_origin_transform);
    if (j->type == urdf::Joint::FIXED) {
      pending = pending * origin;
      continue;
    }
    // choose_urdf_chain() let only revolute and continuous joints through.
    JointSpec s;
    s.name = j->name;
    s.parent_T_joint = pending * origin;
    s.axis = Vector3(j->axis.x, j->axis.y, j->axis.z);
    if (s.axis.norm() < 1e-9) {
      throw ModelError(fmt::format("{}: joint '{}': axis has zero length", path, j->name));
    }
    s.axis.normalize();
    // URDF gives the speed limit in rad/s; 0 (or none) means the file does not say.
    if (j->limits && j->limits->velocity > 0.0) {
      s.max_speed_rad_s = j->limits->velocity;
    }
    if (j->type == urdf::Joint::REVOLUTE && j->limits) {
      s.lower_rad = j->limits->lower;
      s.upper_rad = j->limits->upper;
    } else {
      s.lower_rad = -HUGE_VAL;
      s.upper_rad = HUGE_VAL;
    }
    d.joints.push_back(s);
    pending = Pose::Identity();
  }
  d.last_T_flange = pending;
  return d;
}

RobotModel load_robot_yaml_text(const std::string& text, const std::string& source, const std::string& base_dir) {
  const yaml::Field root = yaml::Field::load_string(text, source);
  if (!root.is_map()) {
    root.fail("a robot file is a YAML map (see docs/robot-file.md)");
  }
  root.only_keys({"deflex_robot", "name", "units", "kinematics", "joint_stiffness_Nm_per_rad", "stiffness_note",
                  "base_frame", "tool_frame", "wap_frame", "sources"});
  const int version = root.at("deflex_robot").as_int();
  if (version != 1) {
    root.at("deflex_robot").fail(fmt::format("format version {} is not known (this deflex reads 1)", version));
  }
  const Units u = parse_units(root);
  RobotDescription d;
  const yaml::Field kin = root.at("kinematics");
  const std::string convention = kin.at("convention").as_string();
  if (convention == "standard_dh" || convention == "modified_dh") {
    kin.only_keys({"convention", "joints"});
    const yaml::Field joints = kin.at("joints");
    if (!joints.is_sequence() || joints.size() == 0) {
      joints.fail("expected a list with one entry a joint");
    }
    std::vector<DhRow> rows;
    std::vector<double> lo;
    std::vector<double> hi;
    std::vector<double> speed;
    for (std::size_t i = 0; i < joints.size(); ++i) {
      const yaml::Field j = joints.at(i);
      j.only_keys({"a", "alpha", "d", "offset", "min", "max", "max_speed"});
      DhRow r;
      r.a_m = j.at("a").as_in(range::kLengthM, u.length);
      r.alpha_rad = j.at("alpha").as_in(range::kAngleRad, u.angle);
      r.d_m = j.at("d").as_in(range::kLengthM, u.length);
      r.theta_offset_rad = j.has("offset") ? j.at("offset").as_in(range::kAngleRad, u.angle) : 0.0;
      rows.push_back(r);
      lo.push_back(j.at("min").as_in(range::kAngleRad, u.angle));
      hi.push_back(j.at("max").as_in(range::kAngleRad, u.angle));
      if (!(lo.back() < hi.back())) {
        j.fail("'min' must be below 'max'");
      }
      // The file's angle unit per second (deg/s with angle: deg).
      speed.push_back(HUGE_VAL);
      if (j.has("max_speed")) {
        speed.back() = j.at("max_speed").as_in(range::kJointSpeedRadS, u.angle);
      }
    }
    set_dh_chain(d, convention == "standard_dh" ? DhConvention::kStandard : DhConvention::kModified, rows, lo, hi,
                 speed);
  } else if (convention == "urdf") {
    kin.only_keys({"convention", "file", "base_link", "tip_link"});
    fs::path file = kin.at("file").as_string();
    if (file.empty()) {
      kin.at("file").fail("empty: give the URDF's path (relative to this file's folder)");
    }
    if (file.is_relative()) {
      file = fs::path(base_dir) / file;
    }
    d = load_urdf_chain(file.string(), kin.get("base_link", std::string()), kin.get("tip_link", std::string()));
  } else {
    kin.at("convention").fail(fmt::format("unknown convention '{}' (standard_dh, modified_dh or urdf)", convention));
  }
  d.source = source;
  d.name = root.get("name", d.name.empty() ? std::string("unnamed robot") : d.name);
  if (root.has("joint_stiffness_Nm_per_rad")) {
    const yaml::Field k = root.at("joint_stiffness_Nm_per_rad");
    d.stiffness_nm_per_rad = k.as_doubles_in(range::kJointStiffness, d.joints.size());
  }
  d.stiffness_note = root.get("stiffness_note", std::string());
  if (root.has("base_frame")) {
    d.base_T_chain = yaml::parse_pose(root.at("base_frame"), u.length, u.angle);
  }
  if (root.has("tool_frame")) {
    d.flange_T_tcp = yaml::parse_pose(root.at("tool_frame"), u.length, u.angle);
  }
  if (root.has("wap_frame")) {
    d.flange_T_wap = yaml::parse_pose(root.at("wap_frame"), u.length, u.angle);
  }
  return RobotModel(std::move(d));
}

RobotModel load_robot(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".urdf") {
    return RobotModel(load_urdf_chain(path));
  }
  if (ext != ".yaml" && ext != ".yml") {
    throw ModelError(fmt::format("{}: unknown robot file type '{}' (use .yaml, .yml or .urdf)", path, ext));
  }
  std::string text;
  try {
    text = read_input_file(path, InputKind::kRobotFile);
  } catch (const DataError& e) {
    throw ModelError(e.what());
  }
  return load_robot_yaml_text(text, path, fs::path(path).parent_path().string());
}

const std::string& builtin_irb6700_yaml() {
  static const std::string text(kBuiltinIrb6700Yaml);
  return text;
}

RobotModel builtin_irb6700() { return load_robot_yaml_text(builtin_irb6700_yaml(), "<built-in IRB6700>"); }

RobotModel load_robot_or_builtin(const std::string& path) {
  return path.empty() ? builtin_irb6700() : load_robot(path);
}

namespace {
std::string pose_yaml(const Pose& p) {
  const Eigen::Quaterniond q(p.linear());
  const Vector3 t = p.translation();
  return fmt::format("{{position: [{:.9g}, {:.9g}, {:.9g}], quaternion_wxyz: [{:.12g}, {:.12g}, {:.12g}, {:.12g}]}}",
                     t.x(), t.y(), t.z(), q.w(), q.x(), q.y(), q.z());
}
}  // namespace

std::string robot_to_yaml(const RobotModel& model) {
  const RobotDescription& d = model.description();
  std::string out = "# deflex robot description (docs/robot-file.md)\ndeflex_robot: 1\n";
  out += fmt::format("name: {}\nunits: {{length: m, angle: deg}}\nkinematics:\n", yaml::scalar_text(d.name));
  if (d.dh_convention) {
    out += fmt::format("  convention: {}\n  joints:\n",
                       *d.dh_convention == DhConvention::kStandard ? "standard_dh" : "modified_dh");
    for (std::size_t i = 0; i < d.dh.size(); ++i) {
      const DhRow& r = d.dh[i];
      const double speed = d.joints[i].max_speed_rad_s;
      out += fmt::format("    - {{a: {:.9g}, alpha: {:.9g}, d: {:.9g}, offset: {:.9g}, min: {:.9g}, max: {:.9g}{}}}\n",
                         r.a_m, rad_to_deg(r.alpha_rad), r.d_m, rad_to_deg(r.theta_offset_rad),
                         rad_to_deg(d.joints[i].lower_rad), rad_to_deg(d.joints[i].upper_rad),
                         std::isfinite(speed) ? fmt::format(", max_speed: {:.9g}", rad_to_deg(speed)) : "");
    }
  } else if (!d.urdf_file.empty()) {
    out +=
        fmt::format("  convention: urdf\n  file: {}\n  base_link: {}\n  tip_link: {}\n", yaml::scalar_text(d.urdf_file),
                    yaml::scalar_text(d.urdf_base_link), yaml::scalar_text(d.urdf_tip_link));
  } else {
    throw InputError("robot_to_yaml: the chain was built in code (neither DH nor URDF) and has no file form");
  }
  if (model.has_stiffness()) {
    out += "joint_stiffness_Nm_per_rad: [";
    for (int i = 0; i < model.dof(); ++i) {
      out += fmt::format("{}{:.9g}", i ? ", " : "", model.stiffness()[i]);
    }
    out += "]\n";
  }
  if (!d.stiffness_note.empty()) {
    out += fmt::format("stiffness_note: {}\n", yaml::scalar_text(d.stiffness_note));
  }
  out += "base_frame: " + pose_yaml(d.base_T_chain) + "\n";
  out += "tool_frame: " + pose_yaml(d.flange_T_tcp) + "\n";
  if (d.flange_T_wap) {
    out += "wap_frame: " + pose_yaml(*d.flange_T_wap) + "\n";
  }
  return out;
}

void write_robot_yaml(const RobotModel& model, const std::string& path) {
  write_output_file(path, robot_to_yaml(model), "robot file");
}

}  // namespace deflex
