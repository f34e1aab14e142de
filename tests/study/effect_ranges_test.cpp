// Every size of the simulated cell in the paper's case stays inside the physical range documented
// for it (data/cases/effect-ranges.yaml, docs/error-budget.md), no size goes without a range, the
// sizes set without a source of their own ("tuned") are the same in the case file, the ranges and the
// docs, and the true joints' band is the in-repository reference sheet's.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "deflex/cell/true_robot.hpp"
#include "deflex/study/case_config.hpp"

namespace deflex::study {
namespace {

const std::filesystem::path kSource(DEFLEX_SOURCE_DIR);
const char* const kHardware[] = {"true_robot", "tool", "sensor", "ldbb", "tracker", "controller", "drift"};

// The numbers of a size: a scalar or each element of a list; none for a word (a frame's name, a switch).
std::vector<double> numbers_of(const YAML::Node& value) {
  std::vector<double> out;
  auto add = [&](const YAML::Node& n) {
    double v = 0.0;
    if (YAML::convert<double>::decode(n, v)) out.push_back(v);
  };
  if (value.IsSequence()) {
    for (const auto& e : value) add(e);
  } else if (value.IsScalar() && value.as<std::string>() != "true" && value.as<std::string>() != "false") {
    add(value);
  }
  return out;
}

TEST(EffectRanges, EverySizeOfTheCellIsInsideItsDocumentedRange) {
  const YAML::Node paper = YAML::LoadFile((kSource / "data/cases/paper.yaml").string());
  const YAML::Node ranges = YAML::LoadFile((kSource / "data/cases/effect-ranges.yaml").string());
  int checked = 0;
  for (const char* section : kHardware) {
    ASSERT_TRUE(paper[section]) << section;
    for (const auto& kv : paper[section]) {
      const std::string key = kv.first.as<std::string>();
      const std::vector<double> values = numbers_of(kv.second);
      if (values.empty()) continue;
      const YAML::Node r = ranges[section][key];
      ASSERT_TRUE(r && r["range"] && r["source"]) << section << "." << key << " has no documented range and source";
      const double lo = r["range"][0].as<double>();
      const double hi = r["range"][1].as<double>();
      ASSERT_LE(lo, hi) << section << "." << key;
      EXPECT_FALSE(r["source"].as<std::string>().empty()) << section << "." << key;
      for (const double v : values) {
        EXPECT_GE(v, lo) << section << "." << key << " = " << v << " is below its range (" << r["source"] << ")";
        EXPECT_LE(v, hi) << section << "." << key << " = " << v << " is above its range (" << r["source"] << ")";
        ++checked;
      }
    }
    // And no range for a size the case no longer has.
    for (const auto& kv : ranges[section]) {
      EXPECT_TRUE(paper[section][kv.first.as<std::string>()])
          << section << "." << kv.first.as<std::string>() << " has a range but no size in paper.yaml";
    }
  }
  EXPECT_GT(checked, 80);
}

TEST(EffectRanges, TheTunedBarBiasIsGoneAndTheBarsErrorIsItsSealFriction) {
  // The bar's force error is one physical model shared by the calibration and the tests: no tuned
  // bias, no separate error at calibration time, and the calibration takes the bar's report.
  const YAML::Node paper = YAML::LoadFile((kSource / "data/cases/paper.yaml").string());
  EXPECT_FALSE(paper["ldbb"]["force_bias_pct"]);
  EXPECT_FALSE(paper["ldbb"]["force_bias_recalibrated_pct"]);
  EXPECT_FALSE(paper["calibration"]["ldbb_force_error_pct"]);
  EXPECT_FALSE(paper["calibration"]["ldbb_force_bias_pct"]);
  EXPECT_GT(paper["ldbb"]["seal_friction_pct"].as<double>(), 0.0);
  EXPECT_EQ(paper["calibration"]["force_from"].as<std::string>(), "ldbb");
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// "section.key" of each size of paper.yaml whose comment starts with "tuned", read from the text
// (a YAML parser drops comments).
std::set<std::string> tuned_in_case_file() {
  std::set<std::string> out;
  std::istringstream lines(read_text(kSource / "data/cases/paper.yaml"));
  const std::regex section_re(R"(^([a-z_]+):.*)");
  const std::regex tuned_re(R"(^\s+([A-Za-z0-9_]+):[^#]*#\s*tuned\b.*)");
  std::string line, section;
  std::smatch m;
  while (std::getline(lines, line)) {
    if (std::regex_match(line, m, section_re))
      section = m[1];
    else if (std::regex_match(line, m, tuned_re))
      out.insert(section + "." + std::string(m[1]));
  }
  return out;
}

std::set<std::string> tuned_in_ranges() {
  std::set<std::string> out;
  const YAML::Node ranges = YAML::LoadFile((kSource / "data/cases/effect-ranges.yaml").string());
  for (const auto& section : ranges) {
    for (const auto& kv : section.second) {
      if (kv.second["source"].as<std::string>().rfind("tuned", 0) == 0) {
        out.insert(section.first.as<std::string>() + "." + kv.first.as<std::string>());
      }
    }
  }
  return out;
}

std::string joined(const std::set<std::string>& s) {
  std::string out;
  for (const auto& e : s) out += e + " ";
  return out;
}

TEST(EffectRanges, TheTunedSizesAreTheSameInTheCaseFileTheRangesAndTheDocs) {
  const std::set<std::string> in_case = tuned_in_case_file();
  const std::set<std::string> in_ranges = tuned_in_ranges();
  EXPECT_EQ(in_case, in_ranges) << "paper.yaml: " << joined(in_case) << "\neffect-ranges.yaml: " << joined(in_ranges);
  EXPECT_GE(in_case.size(), 3U);  // the scale, the sensor's compliance, the seal friction at least

  // docs/error-budget.md names them in one paragraph, "**Tuned sizes** (<count>): `section.key`, ...".
  const std::string docs = read_text(kSource / "docs/error-budget.md");
  const std::size_t at = docs.find("**Tuned sizes** (");
  ASSERT_NE(at, std::string::npos) << "docs/error-budget.md has no \"**Tuned sizes** (N):\" paragraph";
  const std::string paragraph = docs.substr(at, docs.find("\n\n", at) - at);
  std::set<std::string> in_docs;
  const std::regex key_re(R"(`([a-z_]+\.[A-Za-z0-9_]+)`)");
  for (std::sregex_iterator it(paragraph.begin(), paragraph.end(), key_re), end; it != end; ++it) {
    in_docs.insert((*it)[1]);
  }
  EXPECT_EQ(in_docs, in_case) << "docs: " << joined(in_docs);
  const char* const words[] = {"zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten"};
  ASSERT_LT(in_case.size(), std::size(words));
  EXPECT_EQ(paragraph.find(std::string("**Tuned sizes** (") + words[in_case.size()] + ")"), 0U)
      << "the docs count the tuned sizes wrong: " << paragraph.substr(0, 40);
}

// The reference sheet's band, per joint (axes 1-3, then 4-6), Nm/rad.
void band_of_reference(std::vector<double>& lo, std::vector<double>& hi) {
  const YAML::Node ref = YAML::LoadFile((kSource / "data/reference/joint-stiffness-band.yaml").string());
  for (int i = 0; i < 6; ++i) {
    const YAML::Node b = ref[i < 3 ? "axes_1_3_Nm_per_rad" : "axes_4_6_Nm_per_rad"];
    lo.push_back(b[0].as<double>());
    hi.push_back(b[1].as<double>());
  }
}

TEST(EffectRanges, TheStiffnessBandIsTheReferenceSheetsAndTheScalesRangeFollowsFromIt) {
  std::vector<double> lo, hi;
  band_of_reference(lo, hi);
  const YAML::Node paper = YAML::LoadFile((kSource / "data/cases/paper.yaml").string());
  EXPECT_EQ(paper["true_robot"]["stiffness_band_min_Nm_per_rad"].as<std::vector<double>>(), lo);
  EXPECT_EQ(paper["true_robot"]["stiffness_band_max_Nm_per_rad"].as<std::vector<double>>(), hi);
  // The scale's range is where every joint of the built-in assumption stays inside the band:
  // from the band and the robot file, not from the scale's value.
  const YAML::Node robot = YAML::LoadFile((kSource / "data/robots/abb_irb6700_300_270.yaml").string());
  const auto k = robot["joint_stiffness_Nm_per_rad"].as<std::vector<double>>();
  ASSERT_EQ(k.size(), 6U);
  double scale_lo = 0.0, scale_hi = 1e300;
  for (std::size_t i = 0; i < 6; ++i) {
    scale_lo = std::max(scale_lo, lo[i] / k[i]);
    scale_hi = std::min(scale_hi, hi[i] / k[i]);
  }
  const YAML::Node ranges = YAML::LoadFile((kSource / "data/cases/effect-ranges.yaml").string());
  EXPECT_NEAR(ranges["true_robot"]["stiffness_scale"]["range"][0].as<double>(), scale_lo, 1e-3);
  EXPECT_NEAR(ranges["true_robot"]["stiffness_scale"]["range"][1].as<double>(), scale_hi, 1e-3);
}

TEST(EffectRanges, EverySeedsTrueJointsAreInsideTheReferenceBand) {
  std::vector<double> lo, hi;
  band_of_reference(lo, hi);
  const CaseConfig c = paper_case();
  int at_edge = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const cell::TrueRobot robot(c.cell, seed % 2 == 0, seed);
    const auto& k = robot.true_model().stiffness();
    for (int i = 0; i < 6; ++i) {
      const auto iu = static_cast<std::size_t>(i);
      EXPECT_GE(k[i], lo[iu] * (1.0 - 1e-12)) << "seed " << seed << " joint " << i + 1;
      EXPECT_LE(k[i], hi[iu] * (1.0 + 1e-12)) << "seed " << seed << " joint " << i + 1;
      at_edge += (k[i] == lo[iu] || k[i] == hi[iu]) ? 1 : 0;
    }
  }
  EXPECT_EQ(at_edge, 0) << "joints drawn inside the band, not clamped to its edge";
}

}  // namespace
}  // namespace deflex::study
