// URDF tree structure with line numbers (TinyXML) and the choice of the serial chain.
#include "deflex/model/urdf_tree.hpp"

#include <algorithm>
#include <map>

#include <fmt/format.h>
#include <tinyxml.h>

#include "deflex/model/errors.hpp"

namespace deflex {
namespace {

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
  throw ModelError(line > 0 ? fmt::format("{}:{}: {}", file, line, what) : fmt::format("{}: {}", file, what));
}

std::string attribute(const TiXmlElement* e, const char* name) {
  const char* v = e->Attribute(name);
  return v == nullptr ? std::string() : std::string(v);
}

std::string child_link(const TiXmlElement* joint, const char* tag) {
  const TiXmlElement* e = joint->FirstChildElement(tag);
  return e == nullptr ? std::string() : attribute(e, "link");
}

bool is_revolute(const UrdfJointEntry& j) { return j.type == "revolute" || j.type == "continuous"; }

/// Movable joints that can be an independent axis of the chain (a mimic joint only follows another).
bool counts_as_axis(const UrdfJointEntry& j) { return j.movable() && j.mimics.empty(); }

std::string describe_joint(const UrdfJointEntry& j) {
  std::string s = fmt::format("{} ({}", j.name, j.type);
  if (!j.mimics.empty()) {
    s += fmt::format(", mimics {}", j.mimics);
  }
  return s + ")";
}

}  // namespace

bool UrdfTree::has_link(const std::string& name) const {
  return std::find(links.begin(), links.end(), name) != links.end();
}

int UrdfTree::parent_joint(const std::string& link) const {
  for (std::size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].child == link) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

bool UrdfTree::is_below(const std::string& link, const std::string& ancestor) const {
  std::string l = link;
  for (std::size_t guard = 0; guard <= joints.size(); ++guard) {
    if (l == ancestor) {
      return true;
    }
    const int j = parent_joint(l);
    if (j < 0) {
      return false;
    }
    l = joints[static_cast<std::size_t>(j)].parent;
  }
  return false;
}

UrdfTree read_urdf_tree(const std::string& file, const std::string& text) {
  TiXmlDocument doc;
  doc.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (doc.Error()) {
    fail(file, doc.ErrorRow(), fmt::format("not well-formed XML ({})", doc.ErrorDesc()));
  }
  const TiXmlElement* robot = doc.RootElement();
  if (robot == nullptr || std::string(robot->Value()) != "robot") {
    fail(file, robot == nullptr ? 0 : robot->Row(), "the root element must be <robot> (not a URDF file)");
  }
  UrdfTree tree;
  tree.file = file;
  tree.robot_name = attribute(robot, "name");
  for (const TiXmlElement* e = robot->FirstChildElement("link"); e != nullptr; e = e->NextSiblingElement("link")) {
    const std::string name = attribute(e, "name");
    if (name.empty()) {
      fail(file, e->Row(), "<link> without a name");
    }
    if (tree.has_link(name)) {
      const auto k =
          static_cast<std::size_t>(std::find(tree.links.begin(), tree.links.end(), name) - tree.links.begin());
      fail(file, e->Row(), fmt::format("link '{}' is defined twice (also on line {})", name, tree.link_lines[k]));
    }
    tree.links.push_back(name);
    tree.link_lines.push_back(e->Row());
  }
  if (tree.links.empty()) {
    fail(file, robot->Row(), "the robot has no <link>");
  }
  std::map<std::string, int> child_of;  // link -> joint index that has it as child
  for (const TiXmlElement* e = robot->FirstChildElement("joint"); e != nullptr; e = e->NextSiblingElement("joint")) {
    UrdfJointEntry j;
    j.line = e->Row();
    j.name = attribute(e, "name");
    j.type = attribute(e, "type");
    j.parent = child_link(e, "parent");
    j.child = child_link(e, "child");
    if (const TiXmlElement* m = e->FirstChildElement("mimic")) {
      j.mimics = attribute(m, "joint");
      if (j.mimics.empty()) {
        fail(file, m->Row(), fmt::format("joint '{}': <mimic> without a joint name", j.name));
      }
    }
    if (j.name.empty()) {
      fail(file, j.line, "<joint> without a name");
    }
    static const char* const kTypes[] = {"revolute", "continuous", "prismatic", "fixed", "floating", "planar"};
    if (std::none_of(std::begin(kTypes), std::end(kTypes), [&](const char* t) { return j.type == t; })) {
      fail(file, j.line, fmt::format("joint '{}': unknown type '{}'", j.name, j.type));
    }
    for (const auto& [what, link] : {std::pair{"parent", &j.parent}, std::pair{"child", &j.child}}) {
      if (link->empty()) {
        fail(file, j.line, fmt::format("joint '{}': missing <{} link=...>", j.name, what));
      }
      if (!tree.has_link(*link)) {
        fail(file, j.line, fmt::format("joint '{}': {} link '{}' is not defined", j.name, what, *link));
      }
    }
    for (const UrdfJointEntry& other : tree.joints) {
      if (other.name == j.name) {
        fail(file, j.line, fmt::format("joint '{}' is defined twice (also on line {})", j.name, other.line));
      }
    }
    if (const auto it = child_of.find(j.child); it != child_of.end()) {
      const UrdfJointEntry& first = tree.joints[static_cast<std::size_t>(it->second)];
      fail(file, j.line,
           fmt::format("link '{}' has two parents: joint '{}' (line {}) and joint '{}' (line {}); a URDF is a tree",
                       j.child, first.name, first.line, j.name, j.line));
    }
    child_of[j.child] = static_cast<int>(tree.joints.size());
    tree.joints.push_back(j);
  }
  // Loops: walking up from any link must end at a link without a parent.
  for (const UrdfJointEntry& j : tree.joints) {
    std::vector<std::string> seen{j.child};
    std::string l = j.parent;
    while (true) {
      if (std::find(seen.begin(), seen.end(), l) != seen.end()) {
        std::string cycle;
        for (const auto& s : seen) {
          cycle += s + " -> ";
        }
        fail(file, j.line, fmt::format("joint '{}' closes a loop ({}{}); a URDF is a tree", j.name, cycle, l));
      }
      seen.push_back(l);
      const auto it = child_of.find(l);
      if (it == child_of.end()) {
        break;
      }
      l = tree.joints[static_cast<std::size_t>(it->second)].parent;
    }
  }
  std::vector<std::size_t> roots;
  for (std::size_t i = 0; i < tree.links.size(); ++i) {
    if (child_of.count(tree.links[i]) == 0) {
      roots.push_back(i);
    }
  }
  if (roots.size() != 1) {
    std::string list;
    for (const std::size_t r : roots) {
      list += fmt::format("{}'{}' (line {})", list.empty() ? "" : ", ", tree.links[r], tree.link_lines[r]);
    }
    fail(file, roots.size() < 2 ? 0 : tree.link_lines[roots[1]],
         fmt::format("{} root links ({}): every link but one needs a parent joint", roots.size(), list));
  }
  tree.root = tree.links[roots.front()];
  return tree;
}

UrdfChain choose_urdf_chain(const UrdfTree& tree, const std::string& base_link, const std::string& tip_link) {
  const std::string& file = tree.file;
  UrdfChain c;
  for (const auto& [what, name] : {std::pair{"base link", &base_link}, std::pair{"tip link", &tip_link}}) {
    if (!name->empty() && !tree.has_link(*name)) {
      fail(file, 0, fmt::format("{} '{}' not found", what, *name));
    }
  }
  const bool ros_industrial =
      tree.has_link("base_link") && tree.has_link("tool0") && tree.is_below("tool0", "base_link");
  if (!base_link.empty()) {
    c.base_link = base_link;
  } else if (ros_industrial && (tip_link.empty() || tree.is_below(tip_link, "base_link"))) {
    c.base_link = "base_link";
  } else {
    c.base_link = tree.root;
  }
  if (!tip_link.empty()) {
    c.tip_link = tip_link;
    c.notes.push_back(fmt::format("chain {} -> {} (as named)", c.base_link, c.tip_link));
  } else if (ros_industrial && tree.is_below("tool0", c.base_link)) {
    c.tip_link = "tool0";
    c.notes.push_back(
        fmt::format("chain {} -> tool0 (the ROS-Industrial convention; name another with tip_link)", c.base_link));
  } else {
    // Every leaf below the base, scored by the independent axes on its path; the tip must be unique.
    std::vector<std::pair<std::string, int>> leaves;  // leaf, last axis joint index
    int best = 0;
    for (const std::string& l : tree.links) {
      const bool leaf =
          std::none_of(tree.joints.begin(), tree.joints.end(), [&](const auto& j) { return j.parent == l; });
      if (!leaf || !tree.is_below(l, c.base_link)) {
        continue;
      }
      int axes = 0;
      int last_axis = -1;
      for (std::string k = l; k != c.base_link;) {
        const int j = tree.parent_joint(k);
        const UrdfJointEntry& je = tree.joints[static_cast<std::size_t>(j)];
        if (counts_as_axis(je)) {
          ++axes;
          if (last_axis < 0) {
            last_axis = j;
          }
        }
        k = je.parent;
      }
      if (axes > best) {
        best = axes;
        leaves.clear();
      }
      if (axes == best && axes > 0) {
        leaves.emplace_back(l, last_axis);
      }
    }
    if (leaves.empty()) {
      fail(file, 0, fmt::format("no movable joint below link '{}': nothing to model", c.base_link));
    }
    if (leaves.size() > 1) {
      std::string list;
      for (const auto& [l, j] : leaves) {
        list += fmt::format("{}'{}'", list.empty() ? "" : ", ", l);
      }
      const bool same_arm =
          std::all_of(leaves.begin(), leaves.end(), [&](const auto& p) { return p.second == leaves[0].second; });
      fail(file, 0,
           fmt::format("{} leaves end a chain of {} movable joints below '{}' ({}); {}: name the chain's end with "
                       "tip_link (a YAML robot file, docs/robot-file.md)",
                       leaves.size(), best, c.base_link, list,
                       same_arm ? "they hang off the same last joint" : "the tree branches into several arms"));
    }
    c.tip_link = leaves.front().first;
    c.notes.push_back(
        fmt::format("chain {} -> {} (the only leaf at the end of {} movable joints)", c.base_link, c.tip_link, best));
  }
  if (!tree.is_below(c.tip_link, c.base_link)) {
    fail(file, 0, fmt::format("tip link '{}' is not below base link '{}'", c.tip_link, c.base_link));
  }
  for (std::string k = c.tip_link; k != c.base_link;) {
    const UrdfJointEntry& je = tree.joints[static_cast<std::size_t>(tree.parent_joint(k))];
    c.joints.insert(c.joints.begin(), je.name);
    k = je.parent;
  }
  int axes = 0;
  for (const std::string& name : c.joints) {
    const auto& je =
        *std::find_if(tree.joints.begin(), tree.joints.end(), [&](const auto& j) { return j.name == name; });
    if (!je.mimics.empty()) {
      fail(file, je.line,
           fmt::format("joint '{}' on the chain {} -> {} mimics joint '{}': a mimic joint is not an independent axis "
                       "(name a chain without it with base_link/tip_link)",
                       je.name, c.base_link, c.tip_link, je.mimics));
    }
    if (je.movable() && !is_revolute(je)) {
      fail(file, je.line,
           fmt::format("joint '{}' on the chain {} -> {} is {}: deflex models revolute and continuous joints only",
                       je.name, c.base_link, c.tip_link, je.type));
    }
    axes += je.movable() ? 1 : 0;
  }
  if (axes == 0) {
    fail(file, 0, fmt::format("the chain {} -> {} has no movable joint", c.base_link, c.tip_link));
  }
  std::string ignored;
  for (const UrdfJointEntry& j : tree.joints) {
    if (std::find(c.joints.begin(), c.joints.end(), j.name) == c.joints.end()) {
      ignored += (ignored.empty() ? "" : ", ") + describe_joint(j);
    }
  }
  if (!ignored.empty()) {
    c.notes.push_back("joints off the chain, ignored: " + ignored);
  }
  return c;
}

}  // namespace deflex
