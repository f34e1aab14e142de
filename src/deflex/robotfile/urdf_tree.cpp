// URDF tree structure with line numbers (TinyXML) and the choice of the serial chain, in time linear
// in the number of links and joints.
#include "deflex/robotfile/detail/urdf_tree.hpp"

#include <algorithm>
#include <sstream>

#include <fmt/format.h>
#include <tinyxml.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/text/utf8_text.hpp"

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

/// Skips from `i` past `end`, counting lines; false when `end` never comes.
bool skip_past(const std::string& text, std::size_t& i, const char* end, int& line) {
  const std::size_t at = text.find(end, i);
  if (at == std::string::npos) {
    return false;
  }
  line += static_cast<int>(
      std::count(text.begin() + static_cast<std::ptrdiff_t>(i), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
  i = at + std::char_traits<char>::length(end);
  return true;
}

/// The XML parsers recurse once per nesting level, so a document nested 200,000 deep would overflow
/// the stack: the depth is measured here first, without recursion. Malformed XML is left to TinyXML.
void check_nesting(const std::string& file, const std::string& text) {
  int depth = 0;
  int line = 1;
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    }
    if (c != '<') {
      ++i;
      continue;
    }
    const auto starts = [&](const char* s) { return text.compare(i, std::char_traits<char>::length(s), s) == 0; };
    const char* end = starts("<!--") ? "-->" : starts("<![CDATA[") ? "]]>" : starts("<?") ? "?>" : nullptr;
    if (end != nullptr || starts("<!")) {
      if (!skip_past(text, i, end != nullptr ? end : ">", line)) {
        return;
      }
      continue;
    }
    const bool closing = starts("</");
    char quote = 0;
    std::size_t j = i + 1;
    for (; j < text.size() && (quote != 0 || text[j] != '>'); ++j) {
      line += text[j] == '\n' ? 1 : 0;
      if (quote == 0 && (text[j] == '"' || text[j] == '\'')) {
        quote = text[j];
      } else if (text[j] == quote) {
        quote = 0;
      }
    }
    if (j >= text.size()) {
      return;
    }
    if (closing) {
      --depth;
    } else if (text[j - 1] != '/') {
      ++depth;
      if (depth > kMaxUrdfDepth) {
        fail(file, line, fmt::format("XML nested deeper than {} elements: not a URDF", kMaxUrdfDepth));
      }
    }
    i = j + 1;
  }
}

/// The three numbers of an origin's or axis's attribute, each within `range`.
void check_triple(const std::string& file, const TiXmlElement* e, const char* attr, const InputRange& range,
                  const std::string& what) {
  const char* v = e->Attribute(attr);
  if (v == nullptr) {
    return;
  }
  std::istringstream in(v);
  std::string word;
  int n = 0;
  while (in >> word) {
    ++n;
    const std::optional<double> x = parse_double(word);
    if (!x) {
      fail(file, e->Row(), fmt::format("{} {}: {}", what, attr, not_a_number(word)));
    }
    if (const auto bad = range_violation(*x, range)) {
      fail(file, e->Row(), fmt::format("{} {}: {}", what, attr, *bad));
    }
  }
  if (n != 3) {
    fail(file, e->Row(), fmt::format("{} {}: '{}' is not three numbers", what, attr, v));
  }
}

void check_name(const std::string& file, int line, const std::string& what, const std::string& name) {
  if (const auto bad = utf8_problem(name)) {
    fail(file, line, fmt::format("{}: {}", what, *bad));
  }
}

UrdfJointEntry read_joint(const std::string& file, const TiXmlElement* e) {
  UrdfJointEntry j;
  j.line = e->Row();
  j.name = attribute(e, "name");
  j.type = attribute(e, "type");
  j.parent = child_link(e, "parent");
  j.child = child_link(e, "child");
  if (j.name.empty()) {
    fail(file, j.line, "<joint> without a name");
  }
  check_name(file, j.line, "joint name", j.name);
  if (const TiXmlElement* m = e->FirstChildElement("mimic")) {
    j.mimics = attribute(m, "joint");
    if (j.mimics.empty()) {
      fail(file, m->Row(), fmt::format("joint '{}': <mimic> without a joint name", j.name));
    }
  }
  static const char* const kTypes[] = {"revolute", "continuous", "prismatic", "fixed", "floating", "planar"};
  if (std::none_of(std::begin(kTypes), std::end(kTypes), [&](const char* t) { return j.type == t; })) {
    fail(file, j.line, fmt::format("joint '{}': unknown type '{}'", j.name, j.type));
  }
  const std::string what = fmt::format("joint '{}': origin", j.name);
  if (const TiXmlElement* o = e->FirstChildElement("origin")) {
    check_triple(file, o, "xyz", range::kLengthM, what);
    check_triple(file, o, "rpy", range::kAngleRad, what);
  }
  if (const TiXmlElement* a = e->FirstChildElement("axis")) {
    check_triple(file, a, "xyz", range::kAnyValue, fmt::format("joint '{}': axis", j.name));
  }
  return j;
}

void read_links(const std::string& file, const TiXmlElement* robot, UrdfTree& tree) {
  for (const TiXmlElement* e = robot->FirstChildElement("link"); e != nullptr; e = e->NextSiblingElement("link")) {
    const std::string name = attribute(e, "name");
    if (name.empty()) {
      fail(file, e->Row(), "<link> without a name");
    }
    check_name(file, e->Row(), "link name", name);
    const auto [it, fresh] = tree.link_index.emplace(name, static_cast<int>(tree.links.size()));
    if (!fresh) {
      fail(file, e->Row(),
           fmt::format("link '{}' is defined twice (also on line {})", name,
                       tree.link_lines[static_cast<std::size_t>(it->second)]));
    }
    tree.links.push_back(name);
    tree.link_lines.push_back(e->Row());
  }
  if (tree.links.empty()) {
    fail(file, robot->Row(), "the robot has no <link>");
  }
}

void read_joints(const std::string& file, const TiXmlElement* robot, UrdfTree& tree) {
  std::unordered_map<std::string, int> joint_index;
  for (const TiXmlElement* e = robot->FirstChildElement("joint"); e != nullptr; e = e->NextSiblingElement("joint")) {
    UrdfJointEntry j = read_joint(file, e);
    for (const auto& [what, link] : {std::pair{"parent", &j.parent}, std::pair{"child", &j.child}}) {
      if (link->empty()) {
        fail(file, j.line, fmt::format("joint '{}': missing <{} link=...>", j.name, what));
      }
      if (!tree.has_link(*link)) {
        fail(file, j.line, fmt::format("joint '{}': {} link '{}' is not defined", j.name, what, *link));
      }
    }
    if (const auto it = joint_index.find(j.name); it != joint_index.end()) {
      fail(file, j.line,
           fmt::format("joint '{}' is defined twice (also on line {})", j.name,
                       tree.joints[static_cast<std::size_t>(it->second)].line));
    }
    if (const auto it = tree.parent_joint_of.find(j.child); it != tree.parent_joint_of.end()) {
      const UrdfJointEntry& first = tree.joints[static_cast<std::size_t>(it->second)];
      fail(file, j.line,
           fmt::format("link '{}' has two parents: joint '{}' (line {}) and joint '{}' (line {}); a URDF is a tree",
                       j.child, first.name, first.line, j.name, j.line));
    }
    joint_index.emplace(j.name, static_cast<int>(tree.joints.size()));
    tree.parent_joint_of.emplace(j.child, static_cast<int>(tree.joints.size()));
    tree.joints.push_back(std::move(j));
  }
}

/// Loops: walking up from any link must end at a link without a parent. Every link is walked over
/// once (a walk stops at a link an earlier walk finished).
void refuse_loops(const std::string& file, const UrdfTree& tree) {
  const auto parent_link = [&](int l) {
    const auto p = tree.parent_joint_of.find(tree.links[static_cast<std::size_t>(l)]);
    return p == tree.parent_joint_of.end()
               ? -1
               : tree.link_index.at(tree.joints[static_cast<std::size_t>(p->second)].parent);
  };
  std::vector<char> state(tree.links.size(), 0);  // 0 not seen, 1 on the current walk, 2 reaches a root
  for (const UrdfJointEntry& start : tree.joints) {
    std::vector<int> walk;
    int l = tree.link_index.at(start.child);
    while (l >= 0 && state[static_cast<std::size_t>(l)] == 0) {
      state[static_cast<std::size_t>(l)] = 1;
      walk.push_back(l);
      l = parent_link(l);
    }
    if (l >= 0 && state[static_cast<std::size_t>(l)] == 1) {
      // Back at a link of this walk: the loop runs from there to the walk's end.
      std::string cycle;
      for (auto it = std::find(walk.begin(), walk.end(), l); it != walk.end(); ++it) {
        cycle += tree.links[static_cast<std::size_t>(*it)] + " -> ";
      }
      const UrdfJointEntry& closing = tree.joints[static_cast<std::size_t>(
          tree.parent_joint_of.at(tree.links[static_cast<std::size_t>(walk.back())]))];
      fail(file, closing.line,
           fmt::format("joint '{}' closes a loop ({}{}); a URDF is a tree", closing.name, cycle,
                       tree.links[static_cast<std::size_t>(l)]));
    }
    for (const int w : walk) {
      state[static_cast<std::size_t>(w)] = 2;
    }
  }
}

/// The one top-level element, <robot>.
const TiXmlElement* robot_element(const std::string& file, const TiXmlDocument& doc) {
  const TiXmlElement* robot = doc.RootElement();
  if (robot == nullptr || std::string(robot->Value()) != "robot") {
    fail(file, robot == nullptr ? 0 : robot->Row(), "the root element must be <robot> (not a URDF file)");
  }
  if (const TiXmlElement* second = robot->NextSiblingElement()) {
    fail(file, second->Row(),
         fmt::format("a second root element <{}> after <robot> (line {}): a URDF has one", second->Value(),
                     robot->Row()));
  }
  return robot;
}

}  // namespace

bool UrdfTree::has_link(const std::string& name) const { return link_index.count(name) != 0; }

int UrdfTree::parent_joint(const std::string& link) const {
  const auto it = parent_joint_of.find(link);
  return it == parent_joint_of.end() ? -1 : it->second;
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
  check_nesting(file, text);
  TiXmlDocument doc;
  doc.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (doc.Error()) {
    fail(file, doc.ErrorRow(), fmt::format("not well-formed XML ({})", doc.ErrorDesc()));
  }
  const TiXmlElement* robot = robot_element(file, doc);
  UrdfTree tree;
  tree.file = file;
  tree.robot_name = attribute(robot, "name");
  check_name(file, robot->Row(), "robot name", tree.robot_name);
  read_links(file, robot, tree);
  read_joints(file, robot, tree);
  refuse_loops(file, tree);
  std::vector<std::size_t> roots;
  for (std::size_t i = 0; i < tree.links.size(); ++i) {
    if (tree.parent_joint_of.count(tree.links[i]) == 0) {
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

namespace {

/// Every leaf below `base` with the number of independent axes on its path from `base` and the last
/// of those joints, in one pass down the tree.
std::vector<std::pair<std::string, int>> leaves_with_most_axes(const UrdfTree& tree, const std::string& base,
                                                               int& best) {
  std::vector<std::vector<int>> children(tree.links.size());  // joint indices by parent link
  for (std::size_t j = 0; j < tree.joints.size(); ++j) {
    children[static_cast<std::size_t>(tree.link_index.at(tree.joints[j].parent))].push_back(static_cast<int>(j));
  }
  struct Visit {
    int link, axes, last_axis;
  };
  std::vector<std::pair<std::string, int>> leaves;
  best = 0;
  std::vector<Visit> stack{{tree.link_index.at(base), 0, -1}};
  std::vector<std::pair<int, Visit>> found;  // leaf visits, in the order of the links for stable messages
  while (!stack.empty()) {
    const Visit v = stack.back();
    stack.pop_back();
    const auto& kids = children[static_cast<std::size_t>(v.link)];
    if (kids.empty()) {
      found.emplace_back(v.link, v);
      continue;
    }
    for (const int j : kids) {
      const UrdfJointEntry& je = tree.joints[static_cast<std::size_t>(j)];
      const bool axis = counts_as_axis(je);
      stack.push_back({tree.link_index.at(je.child), v.axes + (axis ? 1 : 0), axis ? j : v.last_axis});
    }
  }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [link, v] : found) {
    if (v.axes > best) {
      best = v.axes;
      leaves.clear();
    }
    if (v.axes == best && v.axes > 0) {
      leaves.emplace_back(tree.links[static_cast<std::size_t>(link)], v.last_axis);
    }
  }
  return leaves;
}

/// The tip when none is named: tool0 below base_link (ROS-Industrial), else the one leaf that ends
/// the longest chain of independent axes.
std::string choose_tip(const UrdfTree& tree, const UrdfChain& c, bool ros_industrial, std::vector<std::string>& notes) {
  if (ros_industrial && tree.is_below("tool0", c.base_link)) {
    notes.push_back(
        fmt::format("chain {} -> tool0 (the ROS-Industrial convention; name another with tip_link)", c.base_link));
    return "tool0";
  }
  int best = 0;
  const auto leaves = leaves_with_most_axes(tree, c.base_link, best);
  if (leaves.empty()) {
    fail(tree.file, 0, fmt::format("no movable joint below link '{}': nothing to model", c.base_link));
  }
  if (leaves.size() > 1) {
    std::string list;
    for (const auto& [l, j] : leaves) {
      list += fmt::format("{}'{}'", list.empty() ? "" : ", ", l);
    }
    const bool same_arm =
        std::all_of(leaves.begin(), leaves.end(), [&](const auto& p) { return p.second == leaves[0].second; });
    fail(tree.file, 0,
         fmt::format("{} leaves end a chain of {} movable joints below '{}' ({}); {}: name the chain's end with "
                     "tip_link (a YAML robot file, docs/robot-file.md)",
                     leaves.size(), best, c.base_link, list,
                     same_arm ? "they hang off the same last joint" : "the tree branches into several arms"));
  }
  notes.push_back(fmt::format("chain {} -> {} (the only leaf at the end of {} movable joints)", c.base_link,
                              leaves.front().first, best));
  return leaves.front().first;
}

}  // namespace

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
  } else {
    c.tip_link = choose_tip(tree, c, ros_industrial, c.notes);
  }
  if (!tree.is_below(c.tip_link, c.base_link)) {
    fail(file, 0, fmt::format("tip link '{}' is not below base link '{}'", c.tip_link, c.base_link));
  }
  std::vector<int> chain;  // joint indices, tip first
  for (std::string k = c.tip_link; k != c.base_link;) {
    const int j = tree.parent_joint(k);
    chain.push_back(j);
    k = tree.joints[static_cast<std::size_t>(j)].parent;
  }
  std::reverse(chain.begin(), chain.end());
  std::vector<char> on_chain(tree.joints.size(), 0);
  int axes = 0;
  for (const int j : chain) {
    const UrdfJointEntry& je = tree.joints[static_cast<std::size_t>(j)];
    on_chain[static_cast<std::size_t>(j)] = 1;
    c.joints.push_back(je.name);
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
  for (std::size_t j = 0; j < tree.joints.size(); ++j) {
    if (on_chain[j] == 0) {
      ignored += (ignored.empty() ? "" : ", ") + describe_joint(tree.joints[j]);
    }
  }
  if (!ignored.empty()) {
    c.notes.push_back("joints off the chain, ignored: " + ignored);
  }
  return c;
}

}  // namespace deflex
