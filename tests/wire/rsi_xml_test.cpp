// KUKA RSI documents: deflex's allocation-free scanner against libxml2, an independent XML parser, on
// hand-written documents, on thousands of generated ones (random spacing, quoting, attribute and
// element order, declarations, comments, custom SEND elements, number styles) and on every
// truncation and many single-byte mutations of them. The rule checked: whatever deflex accepts,
// libxml2 finds well-formed and reads to the same values (numbers through strtod, not from_chars);
// whatever libxml2 refuses, deflex refuses. Plus the statuses of hand-made bad documents, the exact
// bytes of an answer, and no heap allocation on either side.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/wire/detail/xml_scanner.hpp"
#include "deflex/wire/rsi_xml.hpp"
#include "support/allocation_guard.hpp"
#include "wire/libxml2_reader.hpp"

// GCC 12 warns falsely on "literal" + std::string (its bug 105651); the generator below is full of them.
#pragma GCC diagnostic ignored "-Wrestrict"

namespace deflex {
namespace {

const unsigned char* bytes(const std::string& s) { return reinterpret_cast<const unsigned char*>(s.data()); }

RsiDecodeStatus decode(const std::string& doc, RsiRobotMessage& out, int axes = 6) {
  return decode_rsi_robot(bytes(doc), doc.size(), axes, out);
}

// What a full parser makes of a number or a count: strtod / strtoull on libxml2's text.
double c_number(const std::string& s) { return std::strtod(s.c_str(), nullptr); }
std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

bool scanner_accepts(const std::string& doc) {
  XmlScanner s(doc.data(), doc.size());
  for (int i = 0; i < 100000; ++i) {
    const XmlToken t = s.next();
    if (t == XmlToken::kDone) return true;
    if (t == XmlToken::kError) return false;
  }
  return false;
}

struct Verdicts {
  int both_accept = 0, both_refuse = 0, only_libxml2_accepts = 0;
};

// The rule, for one document (any bytes).
void expect_agreement(const std::string& doc, Verdicts& v, const std::string& what) {
  const test::XmlDocumentView lx = test::libxml2_read(doc);
  const bool scanned = scanner_accepts(doc);
  RsiRobotMessage m;
  const RsiDecodeStatus st = decode(doc, m);
  if (!lx.well_formed) {
    EXPECT_FALSE(scanned) << what << "\n" << doc;
    EXPECT_NE(st, RsiDecodeStatus::kOk) << what << "\n" << doc;
    ++v.both_refuse;
    return;
  }
  if (!scanned) {
    ++v.only_libxml2_accepts;
    EXPECT_NE(st, RsiDecodeStatus::kOk) << what;
    return;
  }
  ++v.both_accept;
  if (st != RsiDecodeStatus::kOk) return;  // well-formed but not a usable <Rob>: refusing is always allowed
  // Accepted: libxml2 must read the same document.
  EXPECT_EQ(lx.root.name, "Rob") << what;
  EXPECT_EQ(lx.root.attributes.at("Type"), "KUKA") << what;
  int aipos = 0, ipoc = 0, aspos = 0;
  for (const auto& c : lx.children) {
    if (c.name == "AIPos") {
      ++aipos;
      for (int j = 0; j < 6; ++j) {
        EXPECT_EQ(m.actual_deg[j], c_number(c.attributes.at("A" + std::to_string(j + 1)))) << what << "\n" << doc;
      }
    } else if (c.name == "ASPos") {
      ++aspos;
      ASSERT_TRUE(m.has_setpoint) << what;
      for (int j = 0; j < 6; ++j) {
        EXPECT_EQ(m.setpoint_deg[j], c_number(c.attributes.at("A" + std::to_string(j + 1)))) << what;
      }
    } else if (c.name == "IPOC") {
      ++ipoc;
      EXPECT_EQ(m.ipoc, std::strtoull(trimmed(c.text).c_str(), nullptr, 10)) << what << "\n" << doc;
    } else if (c.name == "Delay") {
      EXPECT_EQ(m.delay, std::strtoull(c.attributes.at("D").c_str(), nullptr, 10)) << what;
    }
  }
  EXPECT_EQ(aipos, 1) << what;
  EXPECT_EQ(ipoc, 1) << what;
  EXPECT_EQ(aspos, m.has_setpoint ? 1 : 0) << what;
}

// ---- a generator of <Rob> documents in every style a controller (or a hand) may write them ----

struct Generator {
  std::mt19937 rng;
  explicit Generator(unsigned seed) : rng(seed) {}
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }
  bool chance(double p) { return std::uniform_real_distribution<double>(0.0, 1.0)(rng) < p; }
  std::string space() {
    static const char* const kinds[] = {"", " ", "\n  ", "\t", "\r\n"};
    return kinds[pick(5)];
  }
  std::string number() {
    const double v = std::uniform_real_distribution<double>(-180.0, 180.0)(rng);
    char buf[64];
    switch (pick(6)) {
      case 0:
        std::snprintf(buf, sizeof(buf), "%.4f", v);
        break;
      case 1:
        std::snprintf(buf, sizeof(buf), "%.17g", v);
        break;
      case 2:
        std::snprintf(buf, sizeof(buf), "%e", v);
        break;
      case 3:
        std::snprintf(buf, sizeof(buf), "%d", static_cast<int>(v));
        break;
      case 4:
        std::snprintf(buf, sizeof(buf), "+%.3f", std::abs(v));
        break;
      default:
        std::snprintf(buf, sizeof(buf), "%.6E", v * 1e-3);
        break;
    }
    return buf;
  }
  std::string attribute(const std::string& name, const std::string& value) {
    const char q = chance(0.2) ? '\'' : '"';
    return name + (chance(0.1) ? " = " : "=") + q + value + q;
  }
  std::string element(const std::string& tag, std::vector<std::pair<std::string, std::string>> attrs) {
    std::shuffle(attrs.begin(), attrs.end(), rng);
    std::string s = "<" + tag;
    for (const auto& [k, v] : attrs) s += " " + std::string(chance(0.1) ? "\n " : "") + attribute(k, v);
    if (chance(0.8)) return s + (chance(0.2) ? " />" : "/>");
    return s + ">" + (chance(0.3) ? space() : "") + "</" + tag + ">";
  }
  std::vector<std::pair<std::string, std::string>> axes() {
    std::vector<std::pair<std::string, std::string>> a;
    for (int j = 1; j <= 6; ++j) a.emplace_back("A" + std::to_string(j), number());
    return a;
  }
  std::vector<std::pair<std::string, std::string>> pose() {
    std::vector<std::pair<std::string, std::string>> a;
    for (const char* k : {"X", "Y", "Z", "A", "B", "C"}) a.emplace_back(k, number());
    return a;
  }
  std::string ipoc() {
    std::uint64_t v = std::uniform_int_distribution<std::uint64_t>(0, ~std::uint64_t{0})(rng);
    if (chance(0.5)) v %= 10000000000ULL;
    std::string s = std::to_string(v);
    if (chance(0.1)) s = "000" + s;
    return (chance(0.2) ? space() : "") + s + (chance(0.2) ? space() : "");
  }
  std::string rob() {
    std::vector<std::string> children;
    children.push_back(element("AIPos", axes()));
    children.push_back("<IPOC>" + ipoc() + "</IPOC>");
    if (chance(0.5)) children.push_back(element("RIst", pose()));
    if (chance(0.5)) children.push_back(element("RSol", pose()));
    if (chance(0.7)) children.push_back(element("ASPos", axes()));
    if (chance(0.8)) children.push_back(element("Delay", {{"D", std::to_string(pick(100))}}));
    if (chance(0.3)) children.push_back(element("Tech", {{"C11", number()}, {"C12", number()}}));
    if (chance(0.2)) children.push_back("<Digout>" + std::to_string(pick(2)) + "</Digout>");
    if (chance(0.2)) children.push_back("<Custom>text <Inner a=\"1\"/> more</Custom>");
    std::shuffle(children.begin(), children.end(), rng);
    std::string doc;
    if (chance(0.3)) {
      doc += chance(0.5) ? "<?xml version=\"1.0\" encoding=\"UTF-8\"?>" : "<?xml version='1.0' standalone='yes' ?>";
      doc += space();
    }
    if (chance(0.1)) doc += "<!-- robot " + std::to_string(pick(1000)) + " -->" + space();
    doc += "<Rob " + attribute("Type", "KUKA") + (chance(0.1) ? " " + attribute("Ver", "3") : "") + ">";
    for (const auto& c : children) {
      doc += space() + c;
      if (chance(0.05)) doc += "<!--x-->";
    }
    doc += space() + "</Rob>" + (chance(0.2) ? "\n" : "");
    return doc;
  }
};

TEST(RsiXml, AHandWrittenRobotDocumentReadsAsWritten) {
  const std::string doc =
      "<Rob Type=\"KUKA\"><RIst X=\"1200.5\" Y=\"-3.25\" Z=\"980.0\" A=\"10.0\" B=\"-20.0\" C=\"180.0\"/>"
      "<RSol X=\"1200.4\" Y=\"-3.2\" Z=\"980.1\" A=\"10.0\" B=\"-20.0\" C=\"180.0\"/>"
      "<AIPos A1=\"0.0\" A2=\"-90.0\" A3=\"90.0\" A4=\"0.0\" A5=\"90.0\" A6=\"-0.5\"/>"
      "<ASPos A1=\"0.1\" A2=\"-90.1\" A3=\"90.2\" A4=\"0.0\" A5=\"89.9\" A6=\"-0.25\"/>"
      "<Delay D=\"3\"/><IPOC>4208163628</IPOC></Rob>";
  RsiRobotMessage m;
  ASSERT_EQ(decode(doc, m), RsiDecodeStatus::kOk);
  EXPECT_EQ(m.ipoc, 4208163628ULL);
  EXPECT_EQ(m.actual_deg[1], -90.0);
  EXPECT_EQ(m.actual_deg[5], -0.5);
  ASSERT_TRUE(m.has_setpoint);
  EXPECT_EQ(m.setpoint_deg[2], 90.2);
  EXPECT_EQ(m.setpoint_deg[5], -0.25);
  ASSERT_TRUE(m.has_delay);
  EXPECT_EQ(m.delay, 3u);
  ASSERT_TRUE(m.has_rist);
  EXPECT_EQ(m.rist[0], 1200.5);
  EXPECT_EQ(m.rist[5], 180.0);
  EXPECT_TRUE(m.has_rsol);
}

TEST(RsiXml, TheAnswerIsExactlyTheDocumentTheControllerExpects) {
  RsiSensorMessage a;
  a.ipoc = 123456789012ULL;
  a.correction_deg.resize(6);
  a.correction_deg << 0.1, -0.25, 0.0, -1e-9, 0.0000006, -0.0000004;
  unsigned char out[512];
  const std::size_t n = encode_rsi_sensor("ImFree", a, out, sizeof(out));
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(out), n),
            "<Sen Type=\"ImFree\"><AK A1=\"0.100000\" A2=\"-0.250000\" A3=\"0.000000\" A4=\"0.000000\" "
            "A5=\"0.000001\" A6=\"0.000000\"/><IPOC>123456789012</IPOC></Sen>");
  // libxml2 agrees it is well-formed and reads the same values.
  const auto lx = test::libxml2_read(std::string(reinterpret_cast<const char*>(out), n));
  ASSERT_TRUE(lx.well_formed);
  EXPECT_EQ(lx.root.attributes.at("Type"), "ImFree");
  ASSERT_EQ(lx.children.size(), 2u);
  EXPECT_EQ(lx.children[0].attributes.at("A2"), "-0.250000");
  EXPECT_EQ(lx.children[1].text, "123456789012");
  // Too small a buffer, a non-finite value or a Type the controller could not have configured: nothing.
  EXPECT_EQ(encode_rsi_sensor("ImFree", a, out, 60), 0u);
  EXPECT_EQ(encode_rsi_sensor("Im Free", a, out, sizeof(out)), 0u);
  EXPECT_EQ(encode_rsi_sensor("Im\"Free", a, out, sizeof(out)), 0u);
  a.correction_deg[3] = std::nan("");
  EXPECT_EQ(encode_rsi_sensor("ImFree", a, out, sizeof(out)), 0u);
}

TEST(RsiXml, GeneratedDocumentsReadAsLibxml2ReadsThem) {
  Generator g(20240914);
  Verdicts v;
  for (int i = 0; i < 3000; ++i) {
    const std::string doc = g.rob();
    RsiRobotMessage m;
    ASSERT_EQ(decode(doc, m), RsiDecodeStatus::kOk) << doc;  // every generated document is in the grammar
    expect_agreement(doc, v, "generated #" + std::to_string(i));
  }
  EXPECT_EQ(v.both_accept, 3000);
}

TEST(RsiXml, EveryTruncationAndManyMutationsAreRefusedWheneverLibxml2RefusesThem) {
  Generator g(7);
  Verdicts v;
  const std::string interesting = std::string("<>&\"'/= !?-\x01\x7f", 14) + std::string(1, '\0') + "\x80" + "A";
  std::mt19937 rng(11);
  for (int d = 0; d < 12; ++d) {
    const std::string doc = g.rob();
    for (std::size_t n = 0; n < doc.size(); ++n)
      expect_agreement(doc.substr(0, n), v, "truncated at " + std::to_string(n));
    for (std::size_t at = 0; at < doc.size(); ++at) {
      std::string deleted = doc;
      deleted.erase(at, 1);
      expect_agreement(deleted, v, "byte deleted at " + std::to_string(at));
      std::string doubled = doc;
      doubled.insert(at, 1, doc[at]);
      expect_agreement(doubled, v, "byte doubled at " + std::to_string(at));
      for (int k = 0; k < 3; ++k) {
        std::string replaced = doc;
        replaced[at] = interesting[std::uniform_int_distribution<std::size_t>(0, interesting.size() - 1)(rng)];
        expect_agreement(replaced, v, "byte replaced at " + std::to_string(at));
      }
    }
  }
  // The mutants are a real test: most of them are not well-formed, and deflex refused every one of those.
  EXPECT_GT(v.both_refuse, 10000);
  EXPECT_GT(v.both_accept, 1000);
  // Well-formed documents deflex leaves alone (a reference, a CDATA section ...) are few.
  EXPECT_LT(v.only_libxml2_accepts, v.both_accept);
}

TEST(RsiXml, BadDocumentsGetTheStatusThatNamesTheirFault) {
  const std::string axes = "<AIPos A1=\"0\" A2=\"-90\" A3=\"90\" A4=\"0\" A5=\"90\" A6=\"0\"/>";
  const auto rob = [&](const std::string& body) { return "<Rob Type=\"KUKA\">" + body + "</Rob>"; };
  const std::vector<std::pair<std::string, RsiDecodeStatus>> cases = {
      {"", RsiDecodeStatus::kEmpty},
      {rob(axes + "<IPOC>12</IPOC>").substr(0, 40), RsiDecodeStatus::kTruncated},
      {"<Sen Type=\"ImFree\">" + axes + "<IPOC>12</IPOC></Sen>", RsiDecodeStatus::kForeign},
      {"<Rob Type=\"ABB\">" + axes + "<IPOC>12</IPOC></Rob>", RsiDecodeStatus::kForeign},
      {"<Rob>" + axes + "<IPOC>12</IPOC></Rob>", RsiDecodeStatus::kForeign},
      {rob(axes), RsiDecodeStatus::kMissingIpoc},
      {rob("<IPOC>12</IPOC>"), RsiDecodeStatus::kMissingAxes},
      {rob("<AIPos A1=\"0\" A2=\"-90\" A4=\"0\" A5=\"90\" A6=\"0\"/><IPOC>12</IPOC>"), RsiDecodeStatus::kMissingAxes},
      {rob("<AIPos A1=\"1e999\" A2=\"-90\" A3=\"90\" A4=\"0\" A5=\"90\" A6=\"0\"/><IPOC>12</IPOC>"),
       RsiDecodeStatus::kNonFinite},
      {rob("<AIPos A1=\"nan\" A2=\"-90\" A3=\"90\" A4=\"0\" A5=\"90\" A6=\"0\"/><IPOC>12</IPOC>"),
       RsiDecodeStatus::kMalformed},
      {rob("<AIPos A1=\" 1\" A2=\"-90\" A3=\"90\" A4=\"0\" A5=\"90\" A6=\"0\"/><IPOC>12</IPOC>"),
       RsiDecodeStatus::kMalformed},
      {rob(axes + "<IPOC>18446744073709551616</IPOC>"), RsiDecodeStatus::kIpocOutOfRange},
      {rob(axes + "<IPOC>-5</IPOC>"), RsiDecodeStatus::kMalformed},
      {rob(axes + "<IPOC>1<!-- -->2</IPOC>"), RsiDecodeStatus::kMalformed},
      {rob(axes + axes + "<IPOC>12</IPOC>"), RsiDecodeStatus::kMalformed},
      {rob(axes + "<IPOC>12</IPOC><IPOC>13</IPOC>"), RsiDecodeStatus::kMalformed},
      {rob("junk" + axes + "<IPOC>12</IPOC>"), RsiDecodeStatus::kMalformed},
      {rob(axes + "<IPOC>&#49;2</IPOC>"), RsiDecodeStatus::kMalformed},
      {"<!DOCTYPE Rob [<!ENTITY a \"1\">]>" + rob(axes + "<IPOC>12</IPOC>"), RsiDecodeStatus::kMalformed},
      {rob(axes + "<IPOC>12</IPOC>") + "<Rob/>", RsiDecodeStatus::kMalformed},
      {rob(axes + "<IPOC>12</IPOC>") + std::string(1, '\0'), RsiDecodeStatus::kMalformed},
  };
  for (const auto& [doc, expected] : cases) {
    RsiRobotMessage m;
    EXPECT_EQ(decode(doc, m), expected) << doc;
  }
  // The largest IPOC a 64-bit counter holds is read, not truncated.
  RsiRobotMessage m;
  ASSERT_EQ(decode(rob(axes + "<IPOC>18446744073709551615</IPOC>"), m), RsiDecodeStatus::kOk);
  EXPECT_EQ(m.ipoc, 18446744073709551615ULL);
  ASSERT_EQ(decode(rob(axes + "<IPOC>" + std::string(40, '0') + "42</IPOC>"), m), RsiDecodeStatus::kOk);
  EXPECT_EQ(m.ipoc, 42u);
}

TEST(RsiXml, TheControllersSideRoundTripsThroughLibxml2) {
  RsiRobotMessage r;
  r.ipoc = 987654321;
  r.actual_deg.resize(6);
  r.actual_deg << 1.5, -90.25, 90.125, 0.0, 45.0, -179.9999;
  r.setpoint_deg = r.actual_deg.array() + 0.01;
  r.has_setpoint = true;
  r.delay = 7;
  r.rist = {1500.0, 0.0, 900.0, 0.0, 90.0, 0.0};
  r.has_rist = true;
  unsigned char out[kRsiMaxEncodedBytes];
  const std::size_t n = encode_rsi_robot(r, 4, out, sizeof(out));
  ASSERT_GT(n, 0u);
  const std::string doc(reinterpret_cast<const char*>(out), n);
  const auto lx = test::libxml2_read(doc);
  ASSERT_TRUE(lx.well_formed) << doc;
  EXPECT_EQ(lx.root.name, "Rob");
  EXPECT_EQ(lx.children.at(1).name, "AIPos");
  EXPECT_EQ(lx.children.at(1).attributes.at("A6"), "-179.9999");
  EXPECT_EQ(lx.children.at(2).attributes.at("A2"), "-90.2400");
  EXPECT_EQ(lx.children.at(3).attributes.at("D"), "7");
  EXPECT_EQ(lx.children.at(4).text, "987654321");
  RsiRobotMessage back;
  ASSERT_EQ(decode(doc, back), RsiDecodeStatus::kOk);
  EXPECT_EQ(back.actual_deg[1], -90.25);

  // The controller reads an answer only of its own SENTYPE, with every axis.
  const std::string sen =
      "<Sen Type=\"ImFree\"><AK A1=\"0.1\" A2=\"0.2\" A3=\"0.3\" A4=\"0.4\" A5=\"0.5\" A6=\"-0.6\"/>"
      "<IPOC>987654321</IPOC></Sen>";
  RsiSensorMessage s;
  ASSERT_EQ(decode_rsi_sensor(bytes(sen), sen.size(), "ImFree", 6, s), RsiDecodeStatus::kOk);
  EXPECT_EQ(s.ipoc, 987654321u);
  EXPECT_EQ(s.correction_deg[5], -0.6);
  EXPECT_EQ(decode_rsi_sensor(bytes(sen), sen.size(), "Other", 6, s), RsiDecodeStatus::kForeign);
  const std::string five =
      "<Sen Type=\"ImFree\"><AK A1=\"0.1\" A2=\"0.2\" A3=\"0.3\" A4=\"0.4\" A5=\"0.5\"/>"
      "<IPOC>1</IPOC></Sen>";
  EXPECT_EQ(decode_rsi_sensor(bytes(five), five.size(), "ImFree", 6, s), RsiDecodeStatus::kMissingAxes);
}

TEST(RsiXml, DecodingAndEncodingDoNotAllocate) {
  Generator g(3);
  std::vector<std::string> docs;
  for (int i = 0; i < 50; ++i) docs.push_back(g.rob());
  RsiRobotMessage m;
  m.actual_deg.resize(6);
  m.setpoint_deg.resize(6);
  RsiSensorMessage a;
  a.correction_deg = JointVector::Constant(6, -0.0123456);
  unsigned char out[kRsiMaxEncodedBytes];
  test::AllocationGuard guard;
  std::size_t total = 0;
  for (const auto& d : docs) {
    EXPECT_EQ(decode(d, m), RsiDecodeStatus::kOk);
    a.ipoc = m.ipoc;
    total += encode_rsi_sensor("ImFree", a, out, sizeof(out));
    total += encode_rsi_robot(m, 4, out, sizeof(out));
  }
  EXPECT_EQ(guard.allocations(), 0u);
  EXPECT_GT(total, 0u);
}

}  // namespace
}  // namespace deflex
