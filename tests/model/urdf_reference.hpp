// Test helper: forward kinematics of a URDF chain written independently of deflex's loader (no
// urdfdom, no TinyXML): the <joint> elements are read with regular expressions and the chain is
// T = prod(Trans(xyz) Rz(yaw) Ry(pitch) Rx(roll) [Rot(axis, q)]) from the base link to the tip.
#pragma once

#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace deflex::test {

struct ReferenceJoint {
  std::string name, type, parent, child;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // URDF's default axis
};

inline Eigen::Vector3d reference_triple(const std::string& text) {
  std::istringstream in(text);
  Eigen::Vector3d v;
  in >> v.x() >> v.y() >> v.z();
  return v;
}

/// The chain of joints from `base` to `tip` of the URDF file at `path`.
inline std::vector<ReferenceJoint> reference_chain(const std::string& path, const std::string& base,
                                                   const std::string& tip) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  text = std::regex_replace(text, std::regex("<!--[\\s\\S]*?-->"), "");
  std::map<std::string, ReferenceJoint> by_child;
  const std::regex joint_re(R"(<joint\s+([^>]*)>([\s\S]*?)</joint>)");
  const auto attr = [](const std::string& s, const std::string& name) {
    std::smatch m;
    const std::regex re(name + R"(\s*=\s*["']([^"']*)["'])");
    return std::regex_search(s, m, re) ? m[1].str() : std::string();
  };
  const auto element_attr = [&](const std::string& body, const std::string& element, const std::string& name) {
    std::smatch m;
    const std::regex re("<" + element + R"(\s+([^>]*)/?>)");
    return std::regex_search(body, m, re) ? attr(m[1].str(), name) : std::string();
  };
  for (auto it = std::sregex_iterator(text.begin(), text.end(), joint_re); it != std::sregex_iterator(); ++it) {
    ReferenceJoint j;
    const std::string head = (*it)[1].str();
    const std::string body = (*it)[2].str();
    j.name = attr(head, "name");
    j.type = attr(head, "type");
    j.parent = element_attr(body, "parent", "link");
    j.child = element_attr(body, "child", "link");
    if (const std::string xyz = element_attr(body, "origin", "xyz"); !xyz.empty()) {
      j.xyz = reference_triple(xyz);
    }
    if (const std::string rpy = element_attr(body, "origin", "rpy"); !rpy.empty()) {
      j.rpy = reference_triple(rpy);
    }
    if (const std::string axis = element_attr(body, "axis", "xyz"); !axis.empty()) {
      j.axis = reference_triple(axis).normalized();
    }
    by_child[j.child] = j;
  }
  std::vector<ReferenceJoint> chain;
  for (std::string l = tip; l != base;) {
    const auto it = by_child.find(l);
    if (it == by_child.end()) {
      throw std::runtime_error("reference_chain: no path from " + base + " to " + tip);
    }
    chain.insert(chain.begin(), it->second);
    l = it->second.parent;
  }
  return chain;
}

/// Pose of the tip for the movable joints' values `q` (in chain order), rad.
inline Eigen::Isometry3d reference_fk(const std::vector<ReferenceJoint>& chain, const std::vector<double>& q) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  std::size_t k = 0;
  for (const ReferenceJoint& j : chain) {
    Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
    origin.translation() = j.xyz;
    origin.linear() = (Eigen::AngleAxisd(j.rpy.z(), Eigen::Vector3d::UnitZ()) *
                       Eigen::AngleAxisd(j.rpy.y(), Eigen::Vector3d::UnitY()) *
                       Eigen::AngleAxisd(j.rpy.x(), Eigen::Vector3d::UnitX()))
                          .toRotationMatrix();
    T = T * origin;
    if (j.type != "fixed") {
      T = T * Eigen::AngleAxisd(q.at(k++), j.axis);
    }
  }
  return T;
}

}  // namespace deflex::test
