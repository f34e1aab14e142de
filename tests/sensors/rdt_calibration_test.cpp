// RDT calibration: the example netftapi2.xml page (examples/online/rdt_netftapi2.xml, fields of ATI
// manual 9620-05), pages in other units (converted by the exact definitions of lbf, kgf, in and ft,
// written out here by hand), and every bad page or option named by file, line and field.
#include "deflex/sensors/rdt_calibration.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <initializer_list>
#include <string>
#include <utility>

#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using test::error_of;

const std::string kExample = std::string(DEFLEX_SOURCE_DIR) + "/examples/online/rdt_netftapi2.xml";

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The example page with fields' text replaced (a null value removes the field).
std::string page_with(std::initializer_list<std::pair<std::string, const char*>> changes) {
  std::string xml = slurp(kExample);
  for (const auto& [field, value] : changes) {
    const std::string open = "<" + field + ">";
    const std::string close = "</" + field + ">";
    const auto a = xml.find(open);
    const auto b = xml.find(close, a);
    EXPECT_NE(a, std::string::npos) << field;
    if (a == std::string::npos || b == std::string::npos) continue;
    if (value == nullptr) {
      xml.erase(a, b + close.size() - a);
    } else {
      xml.replace(a + open.size(), b - a - open.size(), value);
    }
  }
  return xml;
}

// The line of the example page a field stands on (messages name it).
int line_of(const std::string& field) {
  const std::string xml = slurp(kExample);
  const auto at = xml.find("<" + field + ">");
  return 1 + static_cast<int>(std::count(xml.begin(), xml.begin() + static_cast<long>(at), '\n'));
}

TEST(RdtCalibration, TheExamplePageGivesCountsUnitsAndRates) {
  const RdtCalibration c = load_netft_xml(kExample);
  EXPECT_EQ(c.counts_per_force, 1000000.0);
  EXPECT_EQ(c.counts_per_torque, 1000000.0);
  EXPECT_EQ(c.force_unit, "N");
  EXPECT_EQ(c.torque_unit, "Nm");
  EXPECT_EQ(c.rate_hz, 1000.0);
  EXPECT_EQ(c.buffer_records, 10);
  EXPECT_EQ(c.internal_rate_hz, 7000.0);
  EXPECT_EQ(c.sensor_name, "Net F/T FT00000");
  EXPECT_EQ(c.source, kExample);
  EXPECT_DOUBLE_EQ(c.force_n_per_count(), 1e-6);
  EXPECT_DOUBLE_EQ(c.torque_nm_per_count(), 1e-6);
  EXPECT_NO_THROW(c.validate());
}

TEST(RdtCalibration, PoundForceAndPoundForceInchAreConverted) {
  // 80 counts per lbf and 2000 counts per lbf-in; codes 1 and 1 say the same units.
  const RdtCalibration c = parse_netft_xml(page_with({{"scfgfu", "lbf"},
                                                      {"cfgfu", "1"},
                                                      {"scfgtu", "lbf-in"},
                                                      {"cfgtu", "1"},
                                                      {"cfgcpf", "80"},
                                                      {"cfgcpt", "2000"}}),
                                           "imperial.xml");
  EXPECT_NEAR(c.force_n_per_count(), 4.4482216152605 / 80.0, 1e-15);
  EXPECT_NEAR(c.torque_nm_per_count(), 0.1129848290276167 / 2000.0, 1e-16);
}

TEST(RdtCalibration, EveryUnitOfTheManualIsKnownInItsSpellings) {
  EXPECT_DOUBLE_EQ(newtons_per_force_unit("N"), 1.0);
  EXPECT_DOUBLE_EQ(newtons_per_force_unit("kN"), 1000.0);
  EXPECT_DOUBLE_EQ(newtons_per_force_unit("KN"), 1000.0);
  EXPECT_DOUBLE_EQ(newtons_per_force_unit("klbf"), 4448.2216152605);
  EXPECT_DOUBLE_EQ(newtons_per_force_unit("kgf"), 9.80665);
  EXPECT_DOUBLE_EQ(newtons_per_force_unit("gf"), 0.00980665);
  EXPECT_DOUBLE_EQ(newton_metres_per_torque_unit("Nm"), 1.0);
  EXPECT_DOUBLE_EQ(newton_metres_per_torque_unit("N-m"), 1.0);
  EXPECT_DOUBLE_EQ(newton_metres_per_torque_unit("Nmm"), 0.001);
  EXPECT_DOUBLE_EQ(newton_metres_per_torque_unit("N-mm"), 0.001);
  EXPECT_DOUBLE_EQ(newton_metres_per_torque_unit("lbf-ft"), 1.3558179483314004);
  EXPECT_DOUBLE_EQ(newton_metres_per_torque_unit("kgf-cm"), 0.0980665);
  EXPECT_DOUBLE_EQ(newton_metres_per_torque_unit("kNm"), 1000.0);
  EXPECT_EQ(newtons_per_force_unit("dN"), 0.0);
  EXPECT_EQ(newtons_per_force_unit("Nm"), 0.0);  // a torque unit is no force unit
  EXPECT_EQ(newton_metres_per_torque_unit("N"), 0.0);
  EXPECT_EQ(newton_metres_per_torque_unit("in-lb"), 0.0);  // not the manual's spelling: refused, not guessed
  EXPECT_EQ(force_unit_of_code(2), "N");
  EXPECT_EQ(torque_unit_of_code(4), "N-mm");
  EXPECT_EQ(force_unit_of_code(7), "");
}

TEST(RdtCalibration, NewtonMillimetresAndKilogramForceFromCodesAlone) {
  const RdtCalibration c = parse_netft_xml(page_with({{"scfgfu", nullptr},
                                                      {"scfgtu", nullptr},
                                                      {"cfgfu", "5"},
                                                      {"cfgtu", "4"},
                                                      {"cfgcpf", "1000"},
                                                      {"cfgcpt", "1000"}}),
                                           "codes.xml");
  EXPECT_EQ(c.force_unit, "kgf");
  EXPECT_EQ(c.torque_unit, "N-mm");
  EXPECT_NEAR(c.force_n_per_count(), 9.80665e-3, 1e-15);
  EXPECT_NEAR(c.torque_nm_per_count(), 1e-6, 1e-18);
}

TEST(RdtCalibration, MissingOrNonPositiveCountsAreNamedWithFileLineAndField) {
  EXPECT_EQ(error_of([] {
              (void)parse_netft_xml(page_with({{"cfgcpf", nullptr}}), "page.xml");
            }).rfind("page.xml:", 0),
            0u);
  const std::string missing = error_of([] { (void)parse_netft_xml(page_with({{"cfgcpf", nullptr}}), "page.xml"); });
  EXPECT_NE(missing.find("field 'cfgcpf'"), std::string::npos) << missing;
  EXPECT_NE(missing.find("missing"), std::string::npos) << missing;

  const std::string zero = error_of([] { (void)parse_netft_xml(page_with({{"cfgcpt", "0"}}), "page.xml"); });
  EXPECT_NE(zero.find("page.xml:" + std::to_string(line_of("cfgcpt")) + ": field 'cfgcpt'"), std::string::npos) << zero;
  EXPECT_NE(zero.find("must be positive"), std::string::npos) << zero;

  const std::string negative = error_of([] { (void)parse_netft_xml(page_with({{"cfgcpf", "-1000000"}}), "p.xml"); });
  EXPECT_NE(negative.find("field 'cfgcpf'"), std::string::npos) << negative;

  const std::string text = error_of([] { (void)parse_netft_xml(page_with({{"cfgcpf", "1e6 counts"}}), "p.xml"); });
  EXPECT_NE(text.find("field 'cfgcpf': '1e6 counts' is not a"), std::string::npos) << text;
}

// A count is an int32 on the wire: 1e300 counts per N would read the sensor's 10 N as 1e-299 N (zero
// force, the compensation silently off), 1e-300 counts per N every count as 1e300 N. Refused with the
// page's line and field, as the counts: option is, whatever the unit the counts are in.
TEST(RdtCalibration, CountsNoSensorHasAreRefusedWithTheirFieldAndLine) {
  for (const char* counts : {"1e300", "1e-300", "1e11"}) {
    const std::string e = error_of([&] { (void)parse_netft_xml(page_with({{"cfgcpf", counts}}), "page.xml"); });
    EXPECT_NE(e.find("page.xml:" + std::to_string(line_of("cfgcpf")) + ": field 'cfgcpf'"), std::string::npos) << e;
    EXPECT_NE(e.find("counts per N make one count"), std::string::npos) << e;
  }
  const std::string torque = error_of([] { (void)parse_netft_xml(page_with({{"cfgcpt", "1e-300"}}), "page.xml"); });
  EXPECT_NE(torque.find("page.xml:" + std::to_string(line_of("cfgcpt")) + ": field 'cfgcpt'"), std::string::npos)
      << torque;
  EXPECT_NE(torque.find("1e+300 Nm"), std::string::npos) << torque;  // 1 Nm / 1e-300 counts
  // The range is in N a count, so a unit's size counts: 0.2 counts per kN is 5000 N a count (refused),
  // 0.2 counts per gf 0.049 N a count (a coarse sensor, accepted).
  EXPECT_NE(error_of([] {
              (void)parse_netft_xml(page_with({{"cfgcpf", "0.2"}, {"scfgfu", "kN"}, {"cfgfu", "4"}}), "k.xml");
            }).find("field 'cfgcpf'"),
            std::string::npos);
  const RdtCalibration gf = parse_netft_xml(page_with({{"cfgcpf", "0.2"}, {"scfgfu", "gf"}, {"cfgfu", "6"}}), "g.xml");
  EXPECT_NEAR(gf.force_n_per_count(), 9.80665e-3 / 0.2, 1e-15);
  // The counts: option and a calibration built in code go through the same range.
  RdtCalibrationOptions o;
  o.rate_hz = 1000.0;
  o.spec = "counts:counts_per_force=1e-300,counts_per_torque=1000000,force_unit=N,torque_unit=Nm";
  const std::string option = error_of([&] { (void)resolve_rdt_calibration(o, ""); });
  EXPECT_NE(option.find("--rdt-calibration counts:"), std::string::npos) << option;
  EXPECT_NE(option.find("counts per force"), std::string::npos) << option;
  RdtCalibration c = load_netft_xml(kExample);
  c.counts_per_torque = 1e300;
  EXPECT_NE(error_of([&] { c.validate(); }).find("counts per torque (cfgcpt)"), std::string::npos);
}

TEST(RdtCalibration, UnknownOrContradictoryUnitsAreRefused) {
  const std::string unknown = error_of([] {
    (void)parse_netft_xml(page_with({{"scfgfu", "dN"}, {"cfgfu", nullptr}}), "p.xml");
  });
  EXPECT_NE(unknown.find("p.xml:" + std::to_string(line_of("scfgfu")) + ": field 'scfgfu': unknown force unit 'dN'"),
            std::string::npos)
      << unknown;
  EXPECT_NE(unknown.find("lbf, N, klbf, kN, kgf, gf"), std::string::npos) << unknown;

  // The name says lbf, the code says N (2): one of them is wrong, and deflex cannot know which.
  const std::string contradiction = error_of([] { (void)parse_netft_xml(page_with({{"scfgfu", "lbf"}}), "p.xml"); });
  EXPECT_NE(contradiction.find("field 'scfgfu': 'lbf' disagrees with 'cfgfu' = 2 (N)"), std::string::npos)
      << contradiction;

  const std::string code = error_of([] {
    (void)parse_netft_xml(page_with({{"scfgtu", nullptr}, {"cfgtu", "9"}}), "p.xml");
  });
  EXPECT_NE(code.find("field 'cfgtu': unknown torque unit code '9'"), std::string::npos) << code;

  const std::string none = error_of([] {
    (void)parse_netft_xml(page_with({{"scfgtu", nullptr}, {"cfgtu", nullptr}}), "p.xml");
  });
  EXPECT_NE(none.find("field 'scfgtu': missing"), std::string::npos) << none;
}

TEST(RdtCalibration, MalformedPagesAndFilesAreNamed) {
  const std::string broken = error_of([] { (void)parse_netft_xml("<netft>\n<cfgcpf>1</cfgcpf>\n<cfgcpt>", "b.xml"); });
  EXPECT_EQ(broken.rfind("b.xml:", 0), 0u) << broken;
  EXPECT_NE(broken.find("not well-formed XML"), std::string::npos) << broken;
  const std::string twice =
      error_of([] { (void)parse_netft_xml("<netft>\n<cfgcpf>1</cfgcpf>\n<cfgcpf>2</cfgcpf>\n</netft>", "t.xml"); });
  EXPECT_NE(twice.find("t.xml:3: field 'cfgcpf' given twice (also on line 2)"), std::string::npos) << twice;
  // A folder of the test's own that it never makes (a path under / could exist on a shared machine).
  const std::string missing = ::testing::TempDir() + "/rdt-calibration-no-such-folder";
  const std::string file = error_of([&] { (void)load_netft_xml(missing + "/netftapi2.xml"); });
  EXPECT_NE(file.find("does not exist: there is no folder '" + missing + "'"), std::string::npos) << file;
  const std::string rate = error_of([] { (void)parse_netft_xml(page_with({{"comrdtrate", "-7000"}}), "r.xml"); });
  EXPECT_NE(rate.find("field 'comrdtrate'"), std::string::npos) << rate;
  const std::string buffer = error_of([] { (void)parse_netft_xml(page_with({{"comrdtbsiz", "41"}}), "r.xml"); });
  EXPECT_NE(buffer.find("field 'comrdtbsiz'"), std::string::npos) << buffer;
}

TEST(RdtCalibration, AnRdtSourceWithoutACalibrationIsRefused) {
  const std::string none = error_of([] { (void)resolve_rdt_calibration({}, "192.168.1.1"); });
  EXPECT_NE(none.find("needs the sensor's calibration"), std::string::npos) << none;
  EXPECT_NE(none.find("--rdt-calibration"), std::string::npos) << none;
  const std::string empty = error_of([] { RdtCalibration{}.validate(); });
  EXPECT_NE(empty.find("counts per force (cfgcpf)"), std::string::npos) << empty;
}

TEST(RdtCalibration, TheRateComesFromThePageOrTheOptionAndBothMustAgree) {
  RdtCalibrationOptions o;
  o.spec = kExample;
  EXPECT_EQ(resolve_rdt_calibration(o, "").rate_hz, 1000.0);
  o.rate_hz = 1000.0;
  EXPECT_EQ(resolve_rdt_calibration(o, "").rate_hz, 1000.0);
  o.rate_hz = 7000.0;
  const std::string clash = error_of([&] { (void)resolve_rdt_calibration(o, ""); });
  EXPECT_NE(clash.find("--rdt-rate-hz 7000 disagrees with the sensor's comrdtrate 1000 Hz"), std::string::npos)
      << clash;

  // A page without the rate needs the option.
  const std::string path = ::testing::TempDir() + "/norate_netftapi2.xml";
  std::ofstream(path) << page_with({{"comrdtrate", nullptr}});
  o.spec = path;
  o.rate_hz = 0.0;
  const std::string missing = error_of([&] { (void)resolve_rdt_calibration(o, ""); });
  EXPECT_NE(missing.find(path + ": RDT rate (comrdtrate): not known"), std::string::npos) << missing;
  o.rate_hz = 500.0;
  EXPECT_EQ(resolve_rdt_calibration(o, "").rate_hz, 500.0);
}

TEST(RdtCalibration, ExplicitCountsAndTheOnRobotProfile) {
  RdtCalibrationOptions o;
  o.spec = "counts:counts_per_force=1000000,counts_per_torque=1000,force_unit=N,torque_unit=N-mm";
  o.rate_hz = 2000.0;
  const RdtCalibration c = resolve_rdt_calibration(o, "");
  EXPECT_DOUBLE_EQ(c.force_n_per_count(), 1e-6);
  EXPECT_DOUBLE_EQ(c.torque_nm_per_count(), 1e-6);
  o.rate_hz = 0.0;
  EXPECT_NE(error_of([&] { (void)resolve_rdt_calibration(o, ""); }).find("comrdtrate"), std::string::npos);
  o.rate_hz = 2000.0;
  o.spec = "counts:counts_per_force=1000000,force_unit=N,torque_unit=Nm";
  EXPECT_NE(error_of([&] { (void)resolve_rdt_calibration(o, ""); }).find("key 'counts_per_torque' is missing"),
            std::string::npos);
  o.spec = "counts:counts_per_force=1000000,counts_per_torque=1000000,force_unit=N,torque_unit=ozf-in";
  EXPECT_NE(error_of([&] { (void)resolve_rdt_calibration(o, ""); }).find("unknown unit 'ozf-in'"), std::string::npos);

  // OnRobot HEX: force counts / 10000 N, torque counts / 100000 Nm (OnRobot's highspeed_udp.c).
  o.spec = "onrobot-hex";
  o.rate_hz = 0.0;
  const RdtCalibration hex = resolve_rdt_calibration(o, "");
  EXPECT_DOUBLE_EQ(hex.force_n_per_count(), 1e-4);
  EXPECT_DOUBLE_EQ(hex.torque_nm_per_count(), 1e-5);
  EXPECT_EQ(hex.rate_hz, 1000.0);
  EXPECT_TRUE(hex.onrobot);
  o.rate_hz = 250.0;
  EXPECT_EQ(resolve_rdt_calibration(o, "").rate_hz, 250.0);
  o.rate_hz = 300.0;  // 1000 / 300 is not whole: the Compute Box cannot stream at 300 Hz
  EXPECT_NE(error_of([&] { (void)resolve_rdt_calibration(o, ""); }).find("rate 300 Hz is not one the Compute Box"),
            std::string::npos);
}

TEST(RdtCalibration, AnUnreachableSensorPageIsNamed) {
  RdtCalibrationOptions o;
  o.spec = "http://127.0.0.1:1/netftapi2.xml";  // port 1: nothing listens, refused at once
  const std::string e = error_of([&] { (void)resolve_rdt_calibration(o, ""); });
  EXPECT_EQ(e.rfind("http://127.0.0.1:1/netftapi2.xml: ", 0), 0u) << e;
}

}  // namespace
}  // namespace deflex
