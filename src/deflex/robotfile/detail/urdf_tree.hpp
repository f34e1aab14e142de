// The link/joint tree of a URDF file, read with its line numbers, and the choice of the serial chain
// deflex models. urdfdom gives the numbers but neither line numbers nor a reason when the tree is
// broken, so the structure is checked here first: every error names the file, the line and the
// joint or link. The reading takes time linear in the size of the file (names are looked up in
// hash maps, the tree is walked once) and the XML's nesting is measured before the XML parsers,
// which recurse per level, see it: a document nested deeper than kMaxUrdfDepth is refused.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

namespace deflex {

/// One <joint> element.
struct UrdfJointEntry {
  std::string name;
  std::string type;  ///< revolute, continuous, prismatic, fixed, floating, planar
  std::string parent;
  std::string child;
  std::string mimics;  ///< the joint named by <mimic joint=...>, empty when none
  int line = 0;
  [[nodiscard]] bool movable() const { return type != "fixed"; }
};

/// The deepest element nesting deflex reads (a URDF nests four levels: robot, joint, origin).
inline constexpr int kMaxUrdfDepth = 100;

/// The tree: links with their lines, joints, the root. Built only from a valid tree.
struct UrdfTree {
  std::string file;
  std::string robot_name;
  std::vector<std::string> links;
  std::vector<int> link_lines;
  std::vector<UrdfJointEntry> joints;
  std::string root;
  std::unordered_map<std::string, int> link_index;       ///< link name -> index into links
  std::unordered_map<std::string, int> parent_joint_of;  ///< link name -> index of the joint whose child it is

  [[nodiscard]] bool has_link(const std::string& name) const;
  /// Index into `joints` of the joint whose child is `link`, or -1 (the root).
  [[nodiscard]] int parent_joint(const std::string& link) const;
  /// True when `link` is `ancestor` or lies below it.
  [[nodiscard]] bool is_below(const std::string& link, const std::string& ancestor) const;
};

/// Parses the XML and checks the structure. Throws ModelError "FILE:LINE: ..." for malformed XML, XML
/// nested deeper than kMaxUrdfDepth, a root element other than <robot> or a second root element, a
/// name that is not UTF-8, a joint without name/parent/child, duplicate names, a joint naming an
/// unknown link, a link with two parent joints, a loop, several roots or no link, and a joint's
/// origin or axis outside its range (xyz +-100 m, rpy +-63 rad, axis +-1e12).
[[nodiscard]] UrdfTree read_urdf_tree(const std::string& file, const std::string& text);

/// The chain chosen in a tree, with the reason for every joint left out.
struct UrdfChain {
  std::string base_link;
  std::string tip_link;
  std::vector<std::string> joints;  ///< from base to tip, fixed ones included
  std::vector<std::string> notes;   ///< how the chain was chosen, which joints were ignored and why
};

/// Chooses the serial chain: `base_link` and `tip_link` when given; otherwise base_link -> tool0
/// when the tree has both (the ROS-Industrial convention), else the root and the one leaf that
/// ends the longest chain of movable, non-mimic joints. Throws ModelError naming the file, the
/// line and the joint for: an unknown or unrelated base/tip, no movable joint, a branching that
/// leaves the tip ambiguous, and a mimic, prismatic, floating or planar joint on the chain.
[[nodiscard]] UrdfChain choose_urdf_chain(const UrdfTree& tree, const std::string& base_link = "",
                                          const std::string& tip_link = "");

}  // namespace deflex
