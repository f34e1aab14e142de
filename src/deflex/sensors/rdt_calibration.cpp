// RDT sensor calibration: netftapi2.xml, explicit counts, the OnRobot HEX profile (see
// rdt_calibration.hpp). The page is read with TinyXML (Debian's libtinyxml-dev, already deflex's URDF
// reader), for its line numbers in every message.
#include "deflex/sensors/rdt_calibration.hpp"

#include <fmt/format.h>
#include <tinyxml.h>

#include <array>
#include <cctype>
#include <cmath>
#include <optional>
#include <utility>

#include "deflex/sensors/detail/http_fetch.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/key_value_spec.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {
namespace {

// Exact by definition: 1 lbf = 0.45359237 kg x 9.80665 m/s^2, 1 kgf = 9.80665 N, 1 in = 0.0254 m,
// 1 ft = 0.3048 m. The manuals' unit codes are the array positions + 1 (9620-05, config page).
constexpr double kLbfN = 0.45359237 * 9.80665;
constexpr double kKgfN = 9.80665;
struct UnitEntry {
  const char* name;  // as the manuals write it
  const char* key;   // lower case, separators removed
  double si;         // N or Nm of one unit
};
constexpr std::array<UnitEntry, 6> kForceUnits{{{"lbf", "lbf", kLbfN},
                                                {"N", "n", 1.0},
                                                {"klbf", "klbf", 1000.0 * kLbfN},
                                                {"kN", "kn", 1000.0},
                                                {"kgf", "kgf", kKgfN},
                                                {"gf", "gf", kKgfN / 1000.0}}};
constexpr std::array<UnitEntry, 6> kTorqueUnits{{{"lbf-in", "lbfin", kLbfN * 0.0254},
                                                 {"lbf-ft", "lbfft", kLbfN * 0.3048},
                                                 {"N-m", "nm", 1.0},
                                                 {"N-mm", "nmm", 0.001},
                                                 {"kgf-cm", "kgfcm", kKgfN * 0.01},
                                                 {"kN-m", "knm", 1000.0}}};

std::string unit_key(const std::string& unit) {
  std::string key;
  for (const char c : unit) {
    if (c == '-' || c == ' ' || c == '.' || c == '*' || c == '_') continue;
    key += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return key;
}

template <std::size_t N>
double lookup(const std::array<UnitEntry, N>& table, const std::string& unit) {
  const std::string key = unit_key(unit);
  for (const auto& e : table) {
    if (key == e.key) return e.si;
  }
  return 0.0;
}

template <std::size_t N>
std::string names(const std::array<UnitEntry, N>& table) {
  std::string out;
  for (const auto& e : table) out += (out.empty() ? "" : ", ") + std::string(e.name);
  return out;
}

// Why `counts` per unit (one unit: `si` N or Nm, named `unit`) is not a sensor's count, or nullopt:
// 1e300 counts per N would read every force as zero, 1e-300 every count as 1e300 N.
std::optional<std::string> count_problem(double counts, double si, const std::string& unit, const InputRange& r) {
  const double per_count = si / counts;
  if (per_count >= r.min && per_count <= r.max) return std::nullopt;
  return fmt::format(
      "{} counts per {} make one count {:g} {}, outside {:g}..{:g} {} a count (the range of every force/torque "
      "sensor deflex accepts): a typo, or not the active calibration's value",
      number_text(counts), unit, per_count, r.unit, r.min, r.max, r.unit);
}

[[noreturn]] void fail_at(const std::string& origin, int line, const std::string& what) {
  throw ModelError(line > 0 ? fmt::format("{}:{}: {}", origin, line, what) : fmt::format("{}: {}", origin, what));
}

// The page's fields: the direct children of its root element, each once.
struct Field {
  std::string text;
  int line = 0;
  bool present = false;
};

class Page {
 public:
  Page(const std::string& text, std::string origin) : origin_(std::move(origin)) {
    doc_.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
    if (doc_.Error()) {
      fail_at(origin_, doc_.ErrorRow(), fmt::format("not well-formed XML ({})", doc_.ErrorDesc()));
    }
    root_ = doc_.RootElement();
    if (root_ == nullptr) {
      fail_at(origin_, 0, "no root element (not a netftapi2.xml page)");
    }
  }
  Field field(const char* name) const {
    Field f;
    for (const TiXmlElement* e = root_->FirstChildElement(name); e != nullptr; e = e->NextSiblingElement(name)) {
      if (f.present) {
        fail_at(origin_, e->Row(), fmt::format("field '{}' given twice (also on line {})", name, f.line));
      }
      f.present = true;
      f.line = e->Row();
      f.text = std::string(trim_view(e->GetText() == nullptr ? "" : e->GetText()));
    }
    return f;
  }
  [[noreturn]] void fail(const Field& f, const char* name, const std::string& what) const {
    fail_at(origin_, f.present ? f.line : root_->Row(), fmt::format("field '{}': {}", name, what));
  }
  /// A required positive count.
  double positive(const char* name, const char* meaning) const {
    const Field f = field(name);
    if (!f.present || f.text.empty()) {
      fail(f, name, fmt::format("missing ({}); the sensor's page has it under its active calibration", meaning));
    }
    const auto v = parse_double(f.text);
    if (!v) fail(f, name, not_a_number(f.text));
    if (!(*v > 0.0)) fail(f, name, fmt::format("{} must be positive, not {}", meaning, f.text));
    return *v;
  }
  /// A count per unit (one unit: `si` N or Nm) within the range of a sensor's count, else an error at
  /// its field's line.
  void check_counts(const char* name, double counts, double si, const std::string& unit, const InputRange& r) const {
    if (const auto bad = count_problem(counts, si, unit, r)) fail(field(name), name, *bad);
  }
  /// An optional non-negative number (0 when absent).
  double optional_number(const char* name, const char* meaning) const {
    const Field f = field(name);
    if (!f.present || f.text.empty()) return 0.0;
    const auto v = parse_double(f.text);
    if (!v) fail(f, name, not_a_number(f.text));
    if (!(*v > 0.0)) fail(f, name, fmt::format("{} must be positive, not {}", meaning, f.text));
    return *v;
  }
  /// The unit from its name field (scfgfu) and/or its code field (cfgfu); they must agree.
  template <std::size_t N>
  std::string unit(const char* name_field, const char* code_field, const std::array<UnitEntry, N>& table,
                   const char* kind) const {
    const Field named = field(name_field);
    const Field coded = field(code_field);
    std::string from_code;
    if (coded.present && !coded.text.empty()) {
      const auto code = parse_int64(coded.text);
      if (!code || *code < 1 || *code > static_cast<std::int64_t>(N)) {
        fail(coded, code_field,
             fmt::format("unknown {} unit code '{}' (the manual's codes: 1..{} = {})", kind, coded.text, N,
                         names(table)));
      }
      from_code = table[static_cast<std::size_t>(*code - 1)].name;
    }
    if (!named.present || named.text.empty()) {
      if (from_code.empty()) {
        fail(named, name_field,
             fmt::format("missing: the {} unit the counts are in (and no '{}' code either)", kind, code_field));
      }
      return from_code;
    }
    const double si = lookup(table, named.text);
    if (si == 0.0) {
      fail(named, name_field, fmt::format("unknown {} unit '{}' (known: {})", kind, named.text, names(table)));
    }
    if (!from_code.empty() && lookup(table, from_code) != si) {
      fail(named, name_field,
           fmt::format("'{}' disagrees with '{}' = {} ({}) on line {}", named.text, code_field, coded.text, from_code,
                       coded.line));
    }
    return named.text;
  }

 private:
  std::string origin_;
  TiXmlDocument doc_;
  const TiXmlElement* root_ = nullptr;
};

bool same_rate(double a, double b) { return std::abs(a - b) <= 0.005 * std::max(a, b); }

}  // namespace

double newtons_per_force_unit(const std::string& unit) { return lookup(kForceUnits, unit); }
double newton_metres_per_torque_unit(const std::string& unit) { return lookup(kTorqueUnits, unit); }
std::string force_unit_of_code(int code) {
  return code >= 1 && code <= 6 ? kForceUnits[static_cast<std::size_t>(code - 1)].name : "";
}
std::string torque_unit_of_code(int code) {
  return code >= 1 && code <= 6 ? kTorqueUnits[static_cast<std::size_t>(code - 1)].name : "";
}

void RdtCalibration::validate() const {
  auto bad = [&](const std::string& field, const std::string& what) {
    throw InputError(fmt::format("{}: {}: {}", source, field, what));
  };
  if (!(counts_per_force > 0.0) || !std::isfinite(counts_per_force)) {
    bad("counts per force (cfgcpf)", fmt::format("must be a positive number, not {}", number_text(counts_per_force)));
  }
  if (!(counts_per_torque > 0.0) || !std::isfinite(counts_per_torque)) {
    bad("counts per torque (cfgcpt)", fmt::format("must be a positive number, not {}", number_text(counts_per_torque)));
  }
  if (newtons_per_force_unit(force_unit) == 0.0) {
    bad("force unit (scfgfu)", fmt::format("unknown unit '{}' (known: {})", force_unit, names(kForceUnits)));
  }
  if (newton_metres_per_torque_unit(torque_unit) == 0.0) {
    bad("torque unit (scfgtu)", fmt::format("unknown unit '{}' (known: {})", torque_unit, names(kTorqueUnits)));
  }
  // The same range for every source: the page (checked again with its line as it is read), counts:, a profile.
  if (const auto p =
          count_problem(counts_per_force, newtons_per_force_unit(force_unit), force_unit, range::kForcePerCountN)) {
    bad("counts per force (cfgcpf)", *p);
  }
  if (const auto p = count_problem(counts_per_torque, newton_metres_per_torque_unit(torque_unit), torque_unit,
                                   range::kTorquePerCountNm)) {
    bad("counts per torque (cfgcpt)", *p);
  }
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    bad("RDT rate (comrdtrate)",
        rate_hz == 0.0 ? "not known: give the sensor's RDT output rate (--rdt-rate-hz), or a page that states it"
                       : fmt::format("must be a positive number of Hz, not {}", number_text(rate_hz)));
  }
  if (buffer_records < 0 || buffer_records > 40) {
    bad("RDT buffer size (comrdtbsiz)", fmt::format("must be 1..40 records, not {}", buffer_records));
  }
}

double RdtCalibration::force_n_per_count() const { return newtons_per_force_unit(force_unit) / counts_per_force; }
double RdtCalibration::torque_nm_per_count() const {
  return newton_metres_per_torque_unit(torque_unit) / counts_per_torque;
}

std::string RdtCalibration::describe() const {
  return fmt::format("{}{}{} counts/{}, {} counts/{}, {} Hz ({})", sensor_name, sensor_name.empty() ? "" : ": ",
                     number_text(counts_per_force), force_unit, number_text(counts_per_torque), torque_unit,
                     number_text(rate_hz), source);
}

RdtCalibration parse_netft_xml(const std::string& text, const std::string& origin) {
  const Page page(text, origin);
  RdtCalibration c;
  c.source = origin;
  c.counts_per_force = page.positive("cfgcpf", "counts per force unit");
  c.counts_per_torque = page.positive("cfgcpt", "counts per torque unit");
  c.force_unit = page.unit("scfgfu", "cfgfu", kForceUnits, "force");
  c.torque_unit = page.unit("scfgtu", "cfgtu", kTorqueUnits, "torque");
  page.check_counts("cfgcpf", c.counts_per_force, newtons_per_force_unit(c.force_unit), c.force_unit,
                    range::kForcePerCountN);
  page.check_counts("cfgcpt", c.counts_per_torque, newton_metres_per_torque_unit(c.torque_unit), c.torque_unit,
                    range::kTorquePerCountNm);
  c.rate_hz = page.optional_number("comrdtrate", "the RDT output rate (Hz)");
  c.internal_rate_hz = page.optional_number("runrate", "the internal sample rate (Hz)");
  const double buffer = page.optional_number("comrdtbsiz", "the RDT buffer size (records)");
  if (buffer != std::floor(buffer) || buffer > 40.0) {
    page.fail(page.field("comrdtbsiz"), "comrdtbsiz",
              fmt::format("the RDT buffer size must be 1..40 records, not {}", number_text(buffer)));
  }
  c.buffer_records = static_cast<int>(buffer);
  const Field product = page.field("prodname");
  const Field serial = page.field("cfgcalsn");
  c.sensor_name = product.text;
  if (!serial.text.empty()) {
    c.sensor_name += (c.sensor_name.empty() ? "" : " ") + serial.text;
  }
  return c;
}

RdtCalibration load_netft_xml(const std::string& path) {
  return parse_netft_xml(read_input_file(path, InputKind::kConfig), path);
}

RdtCalibration fetch_netft_xml(const std::string& url, double timeout_s) {
  return parse_netft_xml(http_get_text(url, timeout_s), url);
}

RdtCalibration onrobot_hex_calibration(double rate_hz) {
  // The Compute Box streams at 1000 / n Hz for a whole n (command 0x0082).
  const double n = 1000.0 / rate_hz;
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz) || std::abs(n - std::round(n)) > 1e-6 * n || std::round(n) < 1.0 ||
      std::round(n) > 65535.0) {
    throw InputError(
        fmt::format("profile onrobot-hex: rate {} Hz is not one the Compute Box streams at "
                    "(1000 / n Hz for a whole n: 1000, 500, 250, 200, 125, 100 ...)",
                    number_text(rate_hz)));
  }
  RdtCalibration c;
  c.source = "profile onrobot-hex";
  c.sensor_name = "OnRobot HEX (Compute Box)";
  c.counts_per_force = 10000.0;
  c.counts_per_torque = 100000.0;
  c.rate_hz = rate_hz;  // the units stay the defaults, N and Nm
  c.onrobot = true;
  return c;
}

RdtCalibration resolve_rdt_calibration(const RdtCalibrationOptions& options, const std::string& sensor_host) {
  const std::string& spec = options.spec;
  const std::string choices =
      "sensor (fetch http://HOST/netftapi2.xml), FILE.xml (a saved netftapi2.xml), http://URL, onrobot-hex, "
      "or counts:counts_per_force=C,counts_per_torque=C,force_unit=U,torque_unit=U";
  if (spec.empty()) {
    throw InputError(
        "an rdt force source needs the sensor's calibration (counts per unit are never assumed): "
        "give --rdt-calibration " +
        choices);
  }
  if (options.rate_hz != 0.0 && (!(options.rate_hz > 0.0) || !std::isfinite(options.rate_hz))) {
    throw InputError(
        fmt::format("--rdt-rate-hz: must be a positive number of Hz, not {}", number_text(options.rate_hz)));
  }
  RdtCalibration c;
  if (spec == "onrobot-hex") {
    c = onrobot_hex_calibration(options.rate_hz > 0.0 ? options.rate_hz : 1000.0);
  } else if (spec.rfind("counts:", 0) == 0) {
    const KeyValueSpec kv(spec, spec.substr(7), {"counts_per_force", "counts_per_torque", "force_unit", "torque_unit"});
    for (const char* key : {"counts_per_force", "counts_per_torque", "force_unit", "torque_unit"}) {
      if (!kv.has(key)) kv.fail(fmt::format("key '{}' is missing", key));
    }
    c.source = "--rdt-calibration " + spec;
    c.counts_per_force = kv.number("counts_per_force", 0.0);
    c.counts_per_torque = kv.number("counts_per_torque", 0.0);
    c.force_unit = kv.text("force_unit");
    c.torque_unit = kv.text("torque_unit");
    c.rate_hz = options.rate_hz;
  } else {
    if (spec == "sensor") {
      c = fetch_netft_xml(fmt::format("http://{}/netftapi2.xml", sensor_host), options.http_timeout_s);
    } else if (spec.rfind("http://", 0) == 0 || spec.rfind("https://", 0) == 0) {
      c = fetch_netft_xml(spec, options.http_timeout_s);
    } else {
      c = load_netft_xml(spec);
    }
    if (options.rate_hz > 0.0) {
      if (c.rate_hz > 0.0 && !same_rate(c.rate_hz, options.rate_hz)) {
        throw InputError(
            fmt::format("--rdt-rate-hz {} disagrees with the sensor's comrdtrate {} Hz in {}: the "
                        "page is the sensor's own setting; change the setting or the option",
                        number_text(options.rate_hz), number_text(c.rate_hz), c.source));
      }
      c.rate_hz = options.rate_hz;
    }
  }
  c.validate();
  return c;
}

}  // namespace deflex
