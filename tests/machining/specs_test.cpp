// The cutter and milling specs and the coefficient file: good ones read as written, every malformed
// one (one table each) refused naming the spec's key or the file's line and key; the shipped
// coefficient files read and hold the published sets.
#include <fstream>

#include <gtest/gtest.h>

#include "deflex/machining/cutter.hpp"
#include "deflex/machining/cutting_coefficients.hpp"
#include "deflex/model/types.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using test::error_of;

struct BadCase {
  std::string input;
  std::vector<std::string> says;
};

void expect_all(const std::string& message, const BadCase& c) {
  for (const std::string& s : c.says) {
    EXPECT_NE(message.find(s), std::string::npos) << "input: " << c.input << "\nmessage: " << message;
  }
}

TEST(CutterSpec, ReadsWhatItIsGiven) {
  const Cutter c = parse_cutter_spec("diameter_mm=12, flutes=4, helix_deg=35, corner_radius_mm=1.5");
  EXPECT_DOUBLE_EQ(c.diameter_m, 12e-3);
  EXPECT_EQ(c.flutes, 4);
  EXPECT_DOUBLE_EQ(c.helix_rad, deg_to_rad(35.0));
  EXPECT_DOUBLE_EQ(c.corner_radius_m, 1.5e-3);
  const Cutter flat = parse_cutter_spec("flutes=2,diameter_mm=6");
  EXPECT_EQ(flat.helix_rad, 0.0);
  EXPECT_EQ(flat.corner_radius_m, 0.0);
  EXPECT_EQ(describe_cutter(parse_cutter_spec("diameter_mm=10,flutes=2,corner_radius_mm=5")),
            "10 mm, 2 flutes, helix 0 deg, ball nose");
}

TEST(CutterSpec, EveryMalformedSpecIsRefusedNamingTheKey) {
  const BadCase cases[] = {
      {"", {"'diameter_mm' is required"}},
      {"diameter_mm=10", {"'flutes' is required"}},
      {"diameter_mm=10,flutes=0", {"flutes: 0 is not 1..32", "does not cut"}},
      {"diameter_mm=10,flutes=-2", {"flutes: -2"}},
      {"diameter_mm=10,flutes=40", {"flutes: 40"}},
      {"diameter_mm=10,flutes=2.5", {"'flutes'", "not a whole number"}},
      {"diameter_mm=-10,flutes=3", {"diameter_mm: -10 mm is outside 0.1..300 mm"}},
      {"diameter_mm=0,flutes=3", {"diameter_mm: 0 mm"}},
      {"diameter_mm=10000,flutes=3", {"diameter_mm: 10000 mm"}},
      {"diameter_mm=abc,flutes=3", {"'diameter_mm'", "'abc' is not a number"}},
      {"diameter_mm=nan,flutes=3", {"'diameter_mm'", "not a finite number"}},
      {"diameter_mm=10;12,flutes=3", {"'diameter_mm'", "expected 1"}},
      {"diameter_mm=10,flutes=3,helix_deg=75", {"helix_deg: 75 deg is outside 0..60 deg"}},
      {"diameter_mm=10,flutes=3,helix_deg=-30", {"helix_deg: -30"}},
      {"diameter_mm=10,flutes=3,corner_radius_mm=6", {"corner_radius_mm: 6 mm is outside 0..5 mm"}},
      {"diameter_mm=10,flutes=3,corner_radius_mm=-1", {"corner_radius_mm: -1"}},
      {"diameter_mm=10,flute=3", {"unknown key 'flute'", "flutes"}},
      {"diameter_mm=10,flutes=3,diameter_mm=12", {"'diameter_mm' given twice"}},
      {"diameter_mm=10,flutes", {"'flutes' is not key=value"}},
  };
  for (const BadCase& c : cases) {
    const std::string m = error_of([&] { (void)parse_cutter_spec(c.input); });
    expect_all(m, c);
    EXPECT_NE(m.find("spec '" + c.input + "'"), std::string::npos) << m;
  }
}

const char* const kAl7075 = "Ktc_N_mm2=767,Krc_N_mm2=168.8,Kac_N_mm2=222,Kte_N_mm=27.7,Kre_N_mm=26.6,Kae_N_mm=0.7";

TEST(MillingSpec, ReadsCoefficientsAndOverrides) {
  const MillingSpec s = parse_milling_spec(std::string("milling:") + kAl7075 + ",ae_mm=2.5,ap_mm=4,cut=conventional");
  EXPECT_DOUBLE_EQ(s.coefficients.k.ktc_n_m2, 767e6);
  EXPECT_DOUBLE_EQ(s.coefficients.k.kre_n_m, 26.6e3);
  EXPECT_DOUBLE_EQ(*s.ae_m, 2.5e-3);
  EXPECT_DOUBLE_EQ(*s.ap_m, 4e-3);
  EXPECT_EQ(s.cut, OverrideCut::kConventional);
  const MillingSpec plain = parse_milling_spec(kAl7075);
  EXPECT_FALSE(plain.ae_m.has_value());
  EXPECT_EQ(plain.cut, OverrideCut::kClimb);
}

TEST(MillingSpec, EveryMalformedSpecIsRefusedNamingTheKey) {
  const std::string all = kAl7075;
  auto with = [&](const std::string& key, const std::string& value) {
    std::string s = all;
    const auto p = s.find(key + "=");
    const auto e = s.find(',', p);
    return s.replace(p, (e == std::string::npos ? s.size() : e) - p, key + "=" + value);
  };
  const BadCase cases[] = {
      {"milling:Ktc_N_mm2=767", {"'Krc_N_mm2' is required"}},
      {"milling:", {"'Ktc_N_mm2' is required"}},
      {"milling:" + with("Kte_N_mm", "-3"), {"'Kte_N_mm': -3 N/mm is outside 0..1000 N/mm"}},
      {"milling:" + with("Krc_N_mm2", "-1"), {"'Krc_N_mm2': -1 N/mm^2 is outside 0..20000"}},
      {"milling:" + with("Ktc_N_mm2", "767e6"), {"'Ktc_N_mm2': 7.67e+08 N/mm^2 is outside 10..20000"}},
      {"milling:" + with("Ktc_N_mm2", "0"), {"'Ktc_N_mm2'", "must be positive"}},
      {"milling:" + with("Kae_N_mm", "5000"), {"'Kae_N_mm': 5000 N/mm"}},
      {"milling:" + with("Kac_N_mm2", "x"), {"'Kac_N_mm2'", "'x' is not a number"}},
      {"milling:" + all + ",ktc_N_mm2=3", {"unknown key 'ktc_N_mm2'", "Ktc_N_mm2"}},
      {"milling:file=coeffs.yaml," + all, {"either in the file or as keys"}},
      {"milling:file=", {"key 'file': give the coefficient file"}},
      {"milling:" + all + ",ae_mm=0", {"'ae_mm'", "0 mm is outside 0.001..300 mm"}},
      {"milling:" + all + ",ap_mm=-4", {"'ap_mm'", "-4 mm is outside"}},
      {"milling:" + all + ",ap_mm=5000", {"'ap_mm': 5000 mm"}},
      {"milling:" + all + ",cut=climb", {"'cut' chooses the side of an ae_mm override"}},
      {"milling:" + all + ",ae_mm=2,cut=sideways", {"'sideways' is neither climb nor conventional"}},
      {"milling:" + all + ",Kte_N_mm=5", {"'Kte_N_mm' given twice"}},
  };
  for (const BadCase& c : cases) expect_all(error_of([&] { (void)parse_milling_spec(c.input); }), c);
  const MillingSpec wide = parse_milling_spec(all + ",ae_mm=12");
  Cutter cutter;
  cutter.diameter_m = 10e-3;
  cutter.flutes = 3;
  EXPECT_NE(error_of([&] { check_overrides(wide, cutter); }).find("ae_mm: 12 mm is wider than the cutter's diameter"),
            std::string::npos);
}

std::string write(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

const char* const kFile =
    "source: \"test\"\nmaterial: Al\nKtc_N_mm2: 767\nKrc_N_mm2: 168.8\nKac_N_mm2: 222\nKte_N_mm: 27.7\n"
    "Kre_N_mm: 26.6\nKae_N_mm: 0.7\n";

TEST(CoefficientFile, EveryMalformedFileIsRefusedNamingTheLineAndKey) {
  const std::string good = kFile;
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    return s.replace(s.find(from), from.size(), to);
  };
  const BadCase cases[] = {
      {replace("Ktc_N_mm2: 767", "Ktc_N_mm: 767"), {":3: field 'Ktc_N_mm': unknown field", "Ktc_N_mm2"}},
      {replace("Kae_N_mm: 0.7\n", ""), {"field 'Kae_N_mm': missing"}},
      {replace("Kre_N_mm: 26.6", "Kre_N_mm: -26.6"), {":7: field 'Kre_N_mm': -26.6 N/mm is outside 0..1000 N/mm"}},
      {replace("Ktc_N_mm2: 767", "Ktc_N_mm2: 767000000"), {":3: field 'Ktc_N_mm2': 7.67e+08 N/mm^2 is outside"}},
      {replace("Kac_N_mm2: 222", "Kac_N_mm2: .nan"), {":5: field 'Kac_N_mm2'", "not a finite number"}},
      {replace("Kac_N_mm2: 222", "Kac_N_mm2: [222]"), {":5: field 'Kac_N_mm2': expected a number"}},
      {replace("source: \"test\"\n", ""), {"field 'source': missing"}},
      {replace("source: \"test\"", "source: \"  \""), {":1: field 'source': say where the coefficients come from"}},
      {good + "standard_error:\n  Ktc_N_mm2: 5\n", {"field 'standard_error.Krc_N_mm2': missing"}},
      {good + "standard_error: {Ktc_N_mm2: -1, Krc_N_mm2: 1, Kac_N_mm2: 1, Kte_N_mm: 1, Kre_N_mm: 1, Kae_N_mm: 1}\n",
       {"field 'standard_error.Ktc_N_mm2': -1 N/mm^2 is outside 0..20000"}},
      {good + "Ktc_N_mm2: 700\n", {"key given twice"}},
      {good + "  - broken: [\n", {"YAML syntax error"}},
      {"- 767\n- 168\n", {"expected a map"}},
  };
  int n = 0;
  for (const BadCase& c : cases) {
    const std::string path = write("coeffs" + std::to_string(n++) + ".yaml", c.input);
    const std::string m = error_of([&] { (void)read_coefficient_file(path); });
    expect_all(m, c);
    EXPECT_NE(m.find(path), std::string::npos) << m;
    // The same file through the spec.
    EXPECT_NE(error_of([&] { (void)parse_milling_spec("milling:file=" + path); }).find(path), std::string::npos);
  }
  EXPECT_NE(error_of([] { (void)read_coefficient_file("/nonexistent/coeffs.yaml"); }).find("/nonexistent/coeffs.yaml"),
            std::string::npos);
}

TEST(CoefficientFile, WrittenFilesReadBack) {
  CoefficientSet set;
  set.source = "a \"quoted\" source";
  set.material = "Al6082-T6";
  set.k = {631e6, 99e6, 273e6, 13e3, 10e3, 2.8e3};
  set.standard_error = CuttingCoefficients{5e6, 2e6, 3e6, 0.5e3, 0.4e3, 0.3e3};
  const std::string path = write("back.yaml", coefficient_file_text(set, "fitted\nfrom four cuts"));
  const CoefficientSet back = read_coefficient_file(path);
  EXPECT_EQ(back.source, set.source);
  EXPECT_EQ(back.material, set.material);
  EXPECT_DOUBLE_EQ(back.k.krc_n_m2, 99e6);
  EXPECT_DOUBLE_EQ(back.k.kae_n_m, 2.8e3);
  ASSERT_TRUE(back.standard_error.has_value());
  EXPECT_DOUBLE_EQ(back.standard_error->kte_n_m, 0.5e3);
}

TEST(CoefficientFile, TheShippedSetsAreThePublishedOnes) {
  // reference/machining.md: Chinese J. Mech. Eng., doi 10.1186/s10033-021-00536-9, Table 5.
  const CoefficientSet a = read_coefficient_file(std::string(DEFLEX_SOURCE_DIR) + "/data/machining/al7075-t6.yaml");
  EXPECT_DOUBLE_EQ(a.k.ktc_n_m2, 767e6);
  EXPECT_DOUBLE_EQ(a.k.kte_n_m, 27.7e3);
  EXPECT_DOUBLE_EQ(a.k.krc_n_m2, 168.8e6);
  EXPECT_DOUBLE_EQ(a.k.kre_n_m, 26.6e3);
  EXPECT_DOUBLE_EQ(a.k.kac_n_m2, 222e6);
  EXPECT_DOUBLE_EQ(a.k.kae_n_m, 0.7e3);
  EXPECT_NE(a.source.find("10.1186/s10033-021-00536-9"), std::string::npos);
  const CoefficientSet b = read_coefficient_file(std::string(DEFLEX_SOURCE_DIR) + "/data/machining/al6082-t6.yaml");
  EXPECT_DOUBLE_EQ(b.k.ktc_n_m2, 631e6);
  EXPECT_DOUBLE_EQ(b.k.kte_n_m, 13e3);
  EXPECT_DOUBLE_EQ(b.k.krc_n_m2, 99e6);
  EXPECT_DOUBLE_EQ(b.k.kre_n_m, 10e3);
  EXPECT_DOUBLE_EQ(b.k.kac_n_m2, 273e6);
  EXPECT_DOUBLE_EQ(b.k.kae_n_m, 2.8e3);
}

}  // namespace
}  // namespace deflex
