// Coefficient specs and files.
//
// Accepted ranges, and why. Published sets for the metals robots mill lie well inside them: Ktc of
// aluminium alloys 600-1000 N/mm^2, of steels 1500-3000, of titanium and nickel alloys 2000-4000;
// radial and axial coefficients are a fraction of the tangential one; edge coefficients are 10-50
// N/mm for aluminium and up to about 150 N/mm for hard alloys (reference/machining.md; Altintas,
// Manufacturing Automation, ch. 2). So:
// - Ktc 10..20000 N/mm^2: a set without a tangential cutting coefficient cuts nothing; 20000 is five
//   times the hardest alloy's, so a value above it is a unit slip (N/m^2 written as N/mm^2);
// - Krc, Kac 0..20000 N/mm^2 and every edge coefficient 0..1000 N/mm: a negative coefficient would
//   pull the tool into the cut (with this model's signs, see docs/machining.md), which no process does;
//   a fitted set that comes out slightly negative is the fit's business (coefficient_fit.hpp).
#include "deflex/machining/cutting_coefficients.hpp"

#include <array>
#include <cmath>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>  // Field::node()

#include "deflex/machining/cutter.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/key_value_spec.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/text/yaml_fields.hpp"

namespace deflex {
namespace {

constexpr InputRange kKtcRange{"tangential cutting coefficient", "N/mm^2", coefficient_limits::kMinKtcNmm2,
                               coefficient_limits::kMaxKcNmm2};
constexpr InputRange kKcRange{"cutting coefficient", "N/mm^2", 0.0, coefficient_limits::kMaxKcNmm2};
constexpr InputRange kKeRange{"edge coefficient", "N/mm", 0.0, coefficient_limits::kMaxKeNmm};
constexpr InputRange kKcErrorRange{"standard error", "N/mm^2", 0.0, coefficient_limits::kMaxKcNmm2};
constexpr InputRange kKeErrorRange{"standard error", "N/mm", 0.0, coefficient_limits::kMaxKeNmm};

const InputRange& coefficient_range(int index) {
  if (index == 0) return kKtcRange;
  return index < 3 ? kKcRange : kKeRange;
}

// The SI value of a coefficient given in its key's unit.
double to_si(int index, double value) { return index < 3 ? value * 1e6 : value * 1e3; }

// A coefficient from its YAML field: checked against its own range only (the name's unit suffix
// "_mm" would otherwise make the generic reader take an edge coefficient for a length).
double read_coefficient(const yaml::Field& f, const InputRange& range) {
  if (!f.node().IsScalar()) f.fail("expected a number");
  const std::optional<double> v = parse_double(trim_view(f.node().Scalar()));
  if (!v) f.fail(not_a_number(f.node().Scalar()));
  if (const auto bad = range_violation(*v, range)) f.fail(*bad);
  return *v;
}

std::array<double*, 6> fields(CuttingCoefficients& k) {
  return {&k.ktc_n_m2, &k.krc_n_m2, &k.kac_n_m2, &k.kte_n_m, &k.kre_n_m, &k.kae_n_m};
}

}  // namespace

double coefficient_in_user_units(const CuttingCoefficients& k, int index) {
  const std::array<double, 6> v = {k.ktc_n_m2, k.krc_n_m2, k.kac_n_m2, k.kte_n_m, k.kre_n_m, k.kae_n_m};
  return index < 3 ? v[index] * 1e-6 : v[index] * 1e-3;
}

void set_coefficient_from_user_units(CuttingCoefficients& k, int index, double value) {
  *fields(k)[index] = to_si(index, value);
}

void validate_coefficients(const CuttingCoefficients& k, const std::string& what) {
  for (int i = 0; i < 6; ++i) {
    if (const auto bad = range_violation(coefficient_in_user_units(k, i), coefficient_range(i))) {
      throw InputError(fmt::format("{}: {}: {}", what, kCoefficientKeys[i], *bad));
    }
  }
}

CoefficientSet read_coefficient_file(const std::string& path) {
  const yaml::Field root = yaml::Field::load_file(path, InputKind::kConfig);
  std::vector<std::string> allowed(std::begin(kCoefficientKeys), std::end(kCoefficientKeys));
  for (const char* meta : {"source", "material", "tool", "note", "standard_error"}) {
    allowed.emplace_back(meta);
  }
  root.only_keys(allowed);
  CoefficientSet set;
  for (int i = 0; i < 6; ++i) {
    set_coefficient_from_user_units(set.k, i, read_coefficient(root.at(kCoefficientKeys[i]), coefficient_range(i)));
  }
  set.source = root.at("source").as_string();
  if (trim_blanks(set.source).empty()) {
    root.at("source").fail("say where the coefficients come from (a publication, a fit's logs)");
  }
  set.material = root.get("material", std::string());
  set.tool = root.get("tool", std::string());
  set.note = root.get("note", std::string());
  if (root.has("standard_error")) {
    const yaml::Field se = root.at("standard_error");
    se.only_keys(std::vector<std::string>(std::begin(kCoefficientKeys), std::end(kCoefficientKeys)));
    CuttingCoefficients e;
    for (int i = 0; i < 6; ++i) {
      const InputRange& r = i < 3 ? kKcErrorRange : kKeErrorRange;
      set_coefficient_from_user_units(e, i, read_coefficient(se.at(kCoefficientKeys[i]), r));
    }
    set.standard_error = e;
  }
  return set;
}

std::string coefficient_file_text(const CoefficientSet& set, const std::string& comment) {
  std::string out;
  for (const std::string& line : split_trimmed(comment, '\n')) {
    if (!line.empty()) out += "# " + line + "\n";
  }
  out += "source: " + yaml::scalar_text(set.source) + "\n";
  if (!set.material.empty()) out += "material: " + yaml::scalar_text(set.material) + "\n";
  if (!set.tool.empty()) out += "tool: " + yaml::scalar_text(set.tool) + "\n";
  if (!set.note.empty()) out += "note: " + yaml::scalar_text(set.note) + "\n";
  for (int i = 0; i < 6; ++i) {
    out += fmt::format("{}: {:.6g}\n", kCoefficientKeys[i], coefficient_in_user_units(set.k, i));
  }
  if (set.standard_error) {
    out += "standard_error:\n";
    for (int i = 0; i < 6; ++i) {
      out += fmt::format("  {}: {:.4g}\n", kCoefficientKeys[i], coefficient_in_user_units(*set.standard_error, i));
    }
  }
  return out;
}

MillingSpec parse_milling_spec(const std::string& spec) {
  std::string body = spec;
  const std::string prefix = "milling:";
  if (trim_blanks(spec).rfind(prefix, 0) == 0) {
    body = trim_blanks(spec).substr(prefix.size());
  }
  std::vector<std::string> allowed(std::begin(kCoefficientKeys), std::end(kCoefficientKeys));
  for (const char* extra : {"file", "ae_mm", "ap_mm", "cut"}) {
    allowed.emplace_back(extra);
  }
  const KeyValueSpec keys(spec, body, allowed);
  MillingSpec out;
  int given = 0;
  for (const char* k : kCoefficientKeys) given += keys.has(k) ? 1 : 0;
  if (keys.has("file")) {
    if (given > 0) {
      keys.fail("give the coefficients either in the file or as keys, not both");
    }
    out.file = keys.text("file");
    if (out.file.empty()) keys.fail("key 'file': give the coefficient file (YAML)");
    out.coefficients = read_coefficient_file(out.file);
  } else {
    for (int i = 0; i < 6; ++i) {
      if (!keys.has(kCoefficientKeys[i])) {
        keys.fail(fmt::format("key '{}' is required (all six coefficients, or file=COEFFS.yaml)", kCoefficientKeys[i]));
      }
      const double v = keys.number(kCoefficientKeys[i], 0.0);
      if (const auto bad = range_violation(v, coefficient_range(i))) {
        keys.fail(fmt::format("key '{}': {}", kCoefficientKeys[i], *bad));
      }
      set_coefficient_from_user_units(out.coefficients.k, i, v);
    }
    out.coefficients.source = "the force spec";
  }
  constexpr InputRange kAe{"radial width", "mm", 1e-3, cutter_limits::kMaxDiameterMm};
  constexpr InputRange kAp{"axial depth", "mm", 1e-3, 1000.0};
  for (const auto& [key, range, target] : {std::tuple{"ae_mm", kAe, &out.ae_m}, std::tuple{"ap_mm", kAp, &out.ap_m}}) {
    if (keys.has(key)) {
      const double v = keys.number(key, 0.0);
      if (const auto bad = range_violation(v, range)) keys.fail(fmt::format("key '{}': {}", key, *bad));
      *target = v * 1e-3;
    }
  }
  if (keys.has("cut")) {
    if (!keys.has("ae_mm")) keys.fail("key 'cut' chooses the side of an ae_mm override: give ae_mm too");
    const std::string& c = keys.text("cut");
    if (c != "climb" && c != "conventional")
      keys.fail(fmt::format("key 'cut': '{}' is neither climb nor conventional", c));
    out.cut = c == "climb" ? OverrideCut::kClimb : OverrideCut::kConventional;
  }
  return out;
}

void check_overrides(const MillingSpec& spec, const Cutter& cutter) {
  if (spec.ae_m && *spec.ae_m > cutter.diameter_m * (1.0 + 1e-9)) {
    throw InputError(fmt::format("milling spec: ae_mm: {:g} mm is wider than the cutter's diameter, {:g} mm",
                                 *spec.ae_m * 1e3, cutter.diameter_m * 1e3));
  }
}

}  // namespace deflex
