// Every size of the simulated cell in the paper's case stays inside the physical range documented
// for it (data/cases/effect-ranges.yaml, docs/error-budget.md), and no size goes without a range.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>
#include <vector>

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

}  // namespace
