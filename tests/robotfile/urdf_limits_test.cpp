// URDF files at and past their limits: a chain of thousands of joints reads in time linear in its
// size (the reader once walked the tree cubically: 33 s for 4,000 links), a document nested 200,000
// deep is refused before the recursive XML parsers see it (it overflowed the stack), and origins,
// root elements and names are held to the rules every other input follows.
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "deflex/robotfile/detail/urdf_tree.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using test::error_of;

/// A serial chain of `n` revolute joints, each 10 mm above the last, turning about z.
std::string chain_urdf(int n) {
  std::string s = "<?xml version=\"1.0\"?>\n<robot name=\"chain\">\n";
  for (int i = 0; i <= n; ++i) {
    s += fmt::format("  <link name=\"l{}\"/>\n", i);
  }
  for (int i = 0; i < n; ++i) {
    s += fmt::format(
        "  <joint name=\"j{}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{}\"/><origin xyz=\"0 0 "
        "0.01\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n",
        i, i, i + 1);
  }
  return s + "</robot>\n";
}

TEST(UrdfLimits, LongChainsAreReadWhole) {
  // The sizes the issue timed (1,000 to 5,000 links); each must read in well under a second now.
  for (const int n : {1000, 2000, 4000, 5000}) {
    const UrdfTree tree = read_urdf_tree("chain.urdf", chain_urdf(n));
    const UrdfChain chain = choose_urdf_chain(tree);
    ASSERT_EQ(chain.joints.size(), static_cast<std::size_t>(n));
    EXPECT_EQ(chain.base_link, "l0");
    EXPECT_EQ(chain.tip_link, fmt::format("l{}", n));
    EXPECT_EQ(chain.joints.front(), "j0");
    EXPECT_EQ(chain.joints.back(), fmt::format("j{}", n - 1));
  }
}

TEST(UrdfLimits, ADocumentNestedDeeperThanTheLimitIsRefusedWithoutRecursion) {
  std::string deep = "<?xml version=\"1.0\"?>\n<robot name=\"deep\">\n<link name=\"a\"/>\n";
  for (int i = 0; i < 200000; ++i) deep += "<x>";
  for (int i = 0; i < 200000; ++i) deep += "</x>";
  deep += "</robot>\n";
  const std::string msg = error_of([&] { (void)read_urdf_tree("deep.urdf", deep); });
  EXPECT_NE(msg.find("deep.urdf:4: XML nested deeper than 100 elements"), std::string::npos) << msg;
  // Comments, CDATA and quoted '>' do not count as elements; 100 levels are fine.
  std::string ok = "<?xml version=\"1.0\"?>\n<!-- <a><b> -->\n<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>";
  ok +=
      "<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/>"
      "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
  for (int i = 0; i < 98; ++i) ok += "<x note=\"a > b\">";
  ok += "<![CDATA[<y><y><y>]]>";
  for (int i = 0; i < 98; ++i) ok += "</x>";
  ok += "</robot>\n";
  EXPECT_EQ(read_urdf_tree("ok.urdf", ok).joints.size(), 1u);
}

std::string one_joint(const std::string& origin, const std::string& robot_name = "r") {
  return "<?xml version=\"1.0\"?>\n<robot name=\"" + robot_name +
         "\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n"
         "<joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>" +
         origin +
         "<axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n</robot>\n";
}

TEST(UrdfLimits, OriginsRootsAndNamesFollowTheInputRules) {
  EXPECT_NE(error_of([] {
              (void)read_urdf_tree("r.urdf", one_joint("<origin xyz=\"0 0 0\" rpy=\"0 1e300 0\"/>"));
            }).find("r.urdf:5: joint 'j1': origin rpy: 1e+300 rad is outside -63..63 rad"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)read_urdf_tree("r.urdf", one_joint("<origin xyz=\"0 1e9 0\"/>"));
            }).find("origin xyz: 1e+09 m is outside"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)read_urdf_tree("r.urdf", one_joint("<origin xyz=\"0 nan 0\"/>"));
            }).find("origin xyz: 'nan' is not a finite number"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)read_urdf_tree("r.urdf", one_joint("<origin xyz=\"0 0\"/>"));
            }).find("origin xyz: '0 0' is not three numbers"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)read_urdf_tree("r.urdf", one_joint("") + "<robot name=\"second\"/>\n");
            }).find("r.urdf:7: a second root element <robot>"),
            std::string::npos);
  // A byte TinyXML lets through (an overlong '/'), and one it refuses itself (Latin-1 e-acute).
  EXPECT_NE(error_of([] {
              (void)read_urdf_tree("r.urdf", one_joint("", "arm\xC0\xAF"));
            }).find("r.urdf:2: robot name: byte 0xC0 at position 4 is not UTF-8"),
            std::string::npos);
  EXPECT_NE(error_of([] { (void)read_urdf_tree("r.urdf", one_joint("", "arm\xE9")); }).find("not well-formed XML"),
            std::string::npos);
  EXPECT_EQ(read_urdf_tree("r.urdf", one_joint("<origin xyz=\"0 0 0.5\" rpy=\"0 1.5 0\"/>", "arm\xC3\xA9")).robot_name,
            "arm\xC3\xA9");
}

}  // namespace
}  // namespace deflex
