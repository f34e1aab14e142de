// The input layer: the one number parser, the range table, name suggestions, and what the CSV and
// YAML readers do with byte order marks, line endings, separators and repeated keys.
#include <gtest/gtest.h>

#include <clocale>
#include <string>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/nearest_name.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/text/utf8_text.hpp"
#include "deflex/text/yaml_fields.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using test::error_of;

TEST(ParseNumber, DecimalNumbersOnlyWholeTextFinite) {
  EXPECT_EQ(parse_double("12"), 12.0);
  EXPECT_EQ(parse_double("-1.5e3"), -1500.0);
  EXPECT_EQ(parse_double("+0.25"), 0.25);
  EXPECT_EQ(parse_double(".5"), 0.5);
  for (const char* bad : {"", "+", "++1", "+-1", "1.5x", " 1", "1 ", "nan", "NaN", "inf", "-inf", "infinity", "0x10",
                          "1e999", "-1e999", "1,5", "abc"}) {
    EXPECT_FALSE(parse_double(bad).has_value()) << bad;
  }
  EXPECT_EQ(parse_int64("42"), 42);
  EXPECT_EQ(parse_int64("+7"), 7);
  EXPECT_FALSE(parse_int64("4.2").has_value());
  EXPECT_FALSE(parse_int64("99999999999999999999").has_value());
  EXPECT_EQ(not_a_number("abc"), "'abc' is not a number");
  EXPECT_EQ(not_a_number("nan"), "'nan' is not a finite number");
}

TEST(ParseNumber, IndependentOfTheProcessLocale) {
  // A locale whose decimal separator is a comma changes strtod, not deflex.
  const char* set = std::setlocale(LC_NUMERIC, "de_DE.UTF-8");
  if (set == nullptr) {
    GTEST_SKIP() << "no de_DE.UTF-8 locale on this machine (from_chars ignores the locale by definition)";
  }
  EXPECT_EQ(parse_double("1.5"), 1.5);
  EXPECT_FALSE(parse_double("1,5").has_value());
  const CsvTable t = CsvTable::parse("x_mm\n2.25\n", "t.csv");
  EXPECT_EQ(t.at(0, "x_mm"), 2.25);
  std::setlocale(LC_NUMERIC, "C");
}

TEST(InputRanges, ByTheUnitTheNameCarries) {
  EXPECT_EQ(range_for_name("fx_N").unit, "N");
  EXPECT_EQ(range_for_name("mx_Nm").unit, "Nm");
  EXPECT_EQ(range_for_name("joint_stiffness_Nm_per_rad").unit, "Nm/rad");
  EXPECT_EQ(range_for_name("servo_period_ms").quantity, "period");
  EXPECT_EQ(range_for_name("x_mm").unit, "mm");
  EXPECT_EQ(range_for_name("rate_Hz").unit, "Hz");
  EXPECT_EQ(range_for_name("qw").quantity, "quaternion component");
  EXPECT_EQ(range_for_name("something").quantity, "value");
  EXPECT_FALSE(range_violation(3.5e6, range::kJointStiffness).has_value());
  const auto bad = range_violation(1e308, range::kJointStiffness);
  ASSERT_TRUE(bad.has_value());
  EXPECT_EQ(*bad, "1e+308 Nm/rad is outside 1..1e+10 Nm/rad (the joint stiffness range deflex accepts)");
  EXPECT_NE(range_violation(-5.0, range::kJointStiffness)->find("must be positive"), std::string::npos);
}

TEST(NearestName, SuggestsTyposOnly) {
  const std::vector<std::string> options = {"--joints-deg", "--robot", "--json"};
  EXPECT_EQ(nearest_name("--jionts-deg", options), "--joints-deg");
  EXPECT_EQ(nearest_name("--robt", options), "--robot");
  EXPECT_EQ(nearest_name("Index", {"index", "fx_N"}), "index");
  EXPECT_EQ(nearest_name("--completely-else", options), "");
}

TEST(CsvInput, ByteOrderMarkAndLineEndings) {
  const std::string rows = "index,fx_N\n0,1\n1,2\n";
  const CsvTable bom = CsvTable::parse("\xEF\xBB\xBF" + rows, "bom.csv");
  EXPECT_TRUE(bom.has("index"));  // not "\xEF\xBB\xBFindex"
  for (const std::string eol : {"\r\n", "\r"}) {
    std::string text = rows;
    for (std::size_t p = text.find('\n'); p != std::string::npos; p = text.find('\n', p + eol.size())) {
      text.replace(p, 1, eol);
    }
    const CsvTable t = CsvTable::parse(text, "eol.csv");
    EXPECT_EQ(t.rows(), 2U);
    EXPECT_EQ(t.at(1, "fx_N"), 2.0);
  }
}

TEST(CsvInput, SeparatorsRangesAndUnknownColumnsAreNamed) {
  EXPECT_NE(error_of([] { (void)CsvTable::parse("t_s;x_mm\n0;1\n", "semi.csv"); }).find("semi.csv:1"),
            std::string::npos);
  EXPECT_NE(error_of([] { (void)CsvTable::parse("t_s;x_mm\n0;1\n", "semi.csv"); }).find("commas"), std::string::npos);
  const std::string huge = error_of([] { (void)CsvTable::parse("# c\nt_s,fx_N\n0,1e308\n", "w.csv"); });
  EXPECT_NE(huge.find("w.csv:3: column 'fx_N': 1e+308 N is outside"), std::string::npos) << huge;
  const CsvTable t = CsvTable::parse("Index,fx_N\n0,1\n", "w.csv");
  const std::string unknown = error_of([&] { t.allow_only({"index", "fx_N"}); });
  EXPECT_NE(unknown.find("unknown column 'Index' (did you mean 'index'?)"), std::string::npos) << unknown;
  EXPECT_EQ(csv_text_cell("plain"), "plain");
  EXPECT_EQ(csv_text_cell("a,b"), "\"a,b\"");
  EXPECT_EQ(csv_text_cell("say \"hi\""), "\"say \"\"hi\"\"\"");
}

TEST(YamlInput, RepeatedKeysAreRefusedWithTheirLine) {
  const std::string msg = error_of([] { (void)yaml::Field::load_string("a: 1\nb:\n  c: 2\n  c: 3\n", "f.yaml"); });
  EXPECT_NE(msg.find("f.yaml:4:3: field 'b.c': key given twice (first at line 3)"), std::string::npos) << msg;
  EXPECT_NO_THROW(
      (void)yaml::Field::load_string("\xEF\xBB\xBF"
                                     "a: 1\n",
                                     "bom.yaml"));
}

TEST(YamlInput, OneDocumentPlainKeysAndUtf8Text) {
  // A second document would be dropped by yaml-cpp's Load: refused with its line.
  const std::string second = error_of([] { (void)yaml::Field::load_string("a: 1\n---\na: 2\n", "f.yaml"); });
  EXPECT_NE(second.find("f.yaml:3: a second YAML document"), std::string::npos) << second;
  EXPECT_NO_THROW((void)yaml::Field::load_string("---\na: 1\n", "start_marker.yaml"));
  // A key that is a list (YAML's "? [a, b]") was an internal error.
  const std::string key = error_of([] { (void)yaml::Field::load_string("name: x\n? [a, b]\n: 1\n", "f.yaml"); });
  EXPECT_NE(key.find("f.yaml:2:3: field '<document>': a key must be a plain name"), std::string::npos) << key;
  // A Latin-1 byte in a name: named with its field, not found later by the JSON writer.
  const std::string latin1 = error_of([] { (void)yaml::Field::load_string("name: \"Bras \xE9l\"\n", "f.yaml"); });
  EXPECT_NE(latin1.find("f.yaml:1:7: field 'name': byte 0xE9 at position 6 is not UTF-8"), std::string::npos) << latin1;
  EXPECT_EQ(yaml::Field::load_string("name: \"Bras \xC3\xA9l\"\n", "f.yaml").at("name").as_string(), "Bras \xC3\xA9l");
}

TEST(Utf8Text, ValidSequencesOnly) {
  EXPECT_FALSE(invalid_utf8_at("ascii, \xC3\xA9, \xE2\x82\xAC, \xF0\x9F\x98\x80"));
  EXPECT_EQ(invalid_utf8_at("a\xC3"), 1u);             // cut short
  EXPECT_EQ(invalid_utf8_at("\xC0\xAF"), 0u);          // overlong '/'
  EXPECT_EQ(invalid_utf8_at("ab\xED\xA0\x80"), 2u);    // a surrogate
  EXPECT_EQ(invalid_utf8_at("\xF4\x90\x80\x80"), 0u);  // past U+10FFFF
  EXPECT_EQ(invalid_utf8_at("x\x80"), 1u);             // a continuation byte alone
}

TEST(YamlInput, KeysWithUnitsAreRangeChecked) {
  const auto root = yaml::Field::load_string("rate_Hz: 1e12\nname: x\n", "f.yaml");
  const std::string msg = error_of([&] { (void)root.at("rate_Hz").as_double(); });
  EXPECT_NE(msg.find("f.yaml:1: field 'rate_Hz': 1e+12 Hz is outside"), std::string::npos) << msg;
  const std::string unknown = error_of([&] { root.only_keys({"rate_Hz", "names"}); });
  EXPECT_NE(unknown.find("did you mean 'names'"), std::string::npos) << unknown;
}

TEST(YamlOutput, EmitterQuotesAnyText) {
  for (const std::string& text : {std::string("plain"), std::string("a \"quoted\" name"), std::string("back\\slash"),
                                  std::string("colon: and # hash"), std::string("line\nbreak")}) {
    const auto back = yaml::Field::load_string("name: " + yaml::scalar_text(text) + "\n", "t.yaml");
    EXPECT_EQ(back.at("name").as_string(), text);
  }
}

}  // namespace
}  // namespace deflex
