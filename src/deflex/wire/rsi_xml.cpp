// KUKA RSI documents (see rsi_xml.hpp).
#include "deflex/wire/rsi_xml.hpp"

#include <charconv>
#include <cmath>
#include <cstring>

#include "deflex/wire/detail/xml_scanner.hpp"

namespace deflex {

namespace {

constexpr std::array<std::string_view, kMaxJoints> kAxisNames = {"A1", "A2", "A3", "A4", "A5", "A6", "A7"};
constexpr std::array<std::string_view, 6> kPoseNames = {"X", "Y", "Z", "A", "B", "C"};

enum class Number { kOk, kBad, kOutOfRange };

// A decimal number as controllers write it: [+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)?
// No white space, no "inf"/"nan", no hexadecimal (std::from_chars alone would take some of those).
Number parse_decimal(std::string_view s, double& v) noexcept {
  const std::size_t n = s.size();
  if (n == 0) return Number::kBad;
  std::size_t i = 0;
  if (s[i] == '+' || s[i] == '-') ++i;
  const std::size_t first = s[0] == '+' ? 1 : 0;  // from_chars takes '-' but not '+'
  std::size_t digits = 0;
  while (i < n && s[i] >= '0' && s[i] <= '9') ++i, ++digits;
  if (i < n && s[i] == '.') {
    ++i;
    while (i < n && s[i] >= '0' && s[i] <= '9') ++i, ++digits;
  }
  if (digits == 0) return Number::kBad;
  if (i < n && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < n && (s[i] == '+' || s[i] == '-')) ++i;
    std::size_t exp_digits = 0;
    while (i < n && s[i] >= '0' && s[i] <= '9') ++i, ++exp_digits;
    if (exp_digits == 0) return Number::kBad;
  }
  if (i != n) return Number::kBad;
  const char* b = s.data() + first;
  const char* e = s.data() + n;
  const auto r = std::from_chars(b, e, v, std::chars_format::general);
  if (r.ec == std::errc::result_out_of_range) return Number::kOutOfRange;
  if (r.ec != std::errc() || r.ptr != e) return Number::kBad;
  return Number::kOk;
}

Number parse_unsigned(std::string_view s, std::uint64_t& v) noexcept {
  if (s.empty()) return Number::kBad;
  for (const char c : s) {
    if (c < '0' || c > '9') return Number::kBad;
  }
  while (s.size() > 1 && s[0] == '0') s.remove_prefix(1);  // leading zeros say nothing of the range
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v, 10);
  if (r.ec == std::errc::result_out_of_range) return Number::kOutOfRange;
  if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return Number::kBad;
  return Number::kOk;
}

bool all_space(std::string_view t) {
  for (const char c : t) {
    if (c != ' ' && c != '\t' && c != '\r' && c != '\n') return false;
  }
  return true;
}

std::string_view trim(std::string_view t) {
  while (!t.empty() && all_space(t.substr(0, 1))) t.remove_prefix(1);
  while (!t.empty() && all_space(t.substr(t.size() - 1))) t.remove_suffix(1);
  return t;
}

RsiDecodeStatus from_scanner(XmlError e) {
  return e == XmlError::kTruncated ? RsiDecodeStatus::kTruncated : RsiDecodeStatus::kMalformed;
}

/// What one attribute list gave: every named value found and parsed, or why not.
struct Values {
  bool complete = true;    // every name present
  bool bad = false;        // a value that is not a number
  bool too_large = false;  // a value beyond double's range
};

Values read_values(const XmlScanner& s, const std::string_view* names, int count, double* out) {
  Values r;
  for (int i = 0; i < count; ++i) {
    std::string_view text;
    if (!s.attribute(names[i], text)) {
      r.complete = false;
      continue;
    }
    const Number n = parse_decimal(text, out[i]);
    r.bad = r.bad || n == Number::kBad;
    r.too_large = r.too_large || n == Number::kOutOfRange;
  }
  return r;
}

// The echoed IPOC, which both documents carry as the text of one <IPOC> child.
struct Ipoc {
  bool have = false;
  bool out_of_range = false;
};

// Walks the children of the root element (its kStart just read) to the end of the document, reading
// the <IPOC> child into `ipoc` (once, as nothing but one run of digits, trimmed). on_start(scanner)
// sees every other child's start tag with its attributes and returns kOk or a status that rejects the
// document. White space between children is allowed, other text is not.
template <class OnStart>
RsiDecodeStatus walk(XmlScanner& s, std::uint64_t& ipoc_value, Ipoc& ipoc, OnStart&& on_start) {
  std::string_view child;
  std::string_view child_text;
  int child_texts = 0;
  bool child_nested = false;
  for (;;) {
    const XmlToken t = s.next();
    switch (t) {
      case XmlToken::kError:
        return from_scanner(s.error());
      case XmlToken::kDone:
        return RsiDecodeStatus::kMalformed;  // cannot happen before the root's end
      case XmlToken::kText:
        if (child.empty()) {
          if (!all_space(s.text())) return RsiDecodeStatus::kMalformed;
        } else {
          child_text = s.text();
          ++child_texts;
        }
        break;
      case XmlToken::kStart:
        if (s.depth() == 2) {
          child = s.name();
          child_texts = 0;
          child_nested = false;
          child_text = {};
          if (child == "IPOC") {
            if (ipoc.have) return RsiDecodeStatus::kMalformed;  // twice
          } else {
            const RsiDecodeStatus st = on_start(s);
            if (st != RsiDecodeStatus::kOk) return st;
          }
        } else {
          child_nested = true;
        }
        break;
      case XmlToken::kEnd:
        if (s.depth() == 1) {  // the root closed: only the epilogue may follow
          const XmlToken after = s.next();
          if (after == XmlToken::kError) return from_scanner(s.error());
          return after == XmlToken::kDone ? RsiDecodeStatus::kOk : RsiDecodeStatus::kMalformed;
        }
        if (s.depth() == 2) {
          if (child == "IPOC") {
            if (child_nested || child_texts > 1) return RsiDecodeStatus::kMalformed;
            const Number n = parse_unsigned(trim(child_text), ipoc_value);
            if (n == Number::kBad) return RsiDecodeStatus::kMalformed;
            ipoc.out_of_range = n == Number::kOutOfRange;
            ipoc.have = true;
          }
          child = {};
        }
        break;
    }
  }
}

// The status of a document whose walk ended with `walked`: the first thing missing or out of range.
RsiDecodeStatus verdict(RsiDecodeStatus walked, const Ipoc& ipoc, bool axes_complete, bool too_large) {
  if (walked != RsiDecodeStatus::kOk) return walked;
  if (ipoc.out_of_range) return RsiDecodeStatus::kIpocOutOfRange;
  if (!ipoc.have) return RsiDecodeStatus::kMissingIpoc;
  if (!axes_complete) return RsiDecodeStatus::kMissingAxes;
  if (too_large) return RsiDecodeStatus::kNonFinite;
  return RsiDecodeStatus::kOk;
}

// A bounded writer into the caller's buffer.
struct Writer {
  unsigned char* out;
  std::size_t capacity;
  std::size_t size = 0;
  bool ok = true;
  void put(std::string_view s) {
    if (!ok || s.size() > capacity - size) {
      ok = false;
      return;
    }
    std::memcpy(out + size, s.data(), s.size());
    size += s.size();
  }
  void number(double v, int decimals) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::fixed, decimals);
    if (r.ec != std::errc()) {
      ok = false;
      return;
    }
    std::string_view text(buf, static_cast<std::size_t>(r.ptr - buf));
    // "-0.000000" says the same as "0.000000", less plainly.
    if (text.size() > 1 && text[0] == '-' && text.find_first_not_of("0.", 1) == std::string_view::npos) {
      text.remove_prefix(1);
    }
    put(text);
  }
  void integer(std::uint64_t v) {
    char buf[24];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    put(std::string_view(buf, static_cast<std::size_t>(r.ptr - buf)));
  }
  void element(std::string_view tag, const std::string_view* names, int count, const double* values, int decimals) {
    put("<");
    put(tag);
    for (int i = 0; i < count; ++i) {
      put(" ");
      put(names[i]);
      put("=\"");
      number(values[i], decimals);
      put("\"");
    }
    put("/>");
  }
};

}  // namespace

const char* to_string(RsiDecodeStatus s) {
  switch (s) {
    case RsiDecodeStatus::kOk:
      return "ok";
    case RsiDecodeStatus::kMalformed:
      return "malformed";
    case RsiDecodeStatus::kTruncated:
      return "truncated";
    case RsiDecodeStatus::kMissingIpoc:
      return "missing_ipoc";
    case RsiDecodeStatus::kMissingAxes:
      return "missing_axes";
    case RsiDecodeStatus::kNonFinite:
      return "non_finite";
    case RsiDecodeStatus::kEmpty:
      return "empty";
    case RsiDecodeStatus::kForeign:
      return "foreign";
    case RsiDecodeStatus::kIpocOutOfRange:
      return "ipoc_out_of_range";
  }
  return "unknown";
}

bool valid_rsi_sentype(std::string_view name) noexcept {
  if (name.empty() || name.size() > 32) return false;
  if (!((name[0] >= 'A' && name[0] <= 'Z') || (name[0] >= 'a' && name[0] <= 'z'))) return false;
  for (const char c : name) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

RsiDecodeStatus decode_rsi_robot(const unsigned char* data, std::size_t size, int axes, RsiRobotMessage& out) noexcept {
  if (size == 0) return RsiDecodeStatus::kEmpty;
  if (axes < 1 || axes > kMaxJoints) return RsiDecodeStatus::kMissingAxes;
  XmlScanner s(reinterpret_cast<const char*>(data), size);
  if (s.next() == XmlToken::kError) return from_scanner(s.error());
  std::string_view type;
  if (s.name() != "Rob" || !s.attribute("Type", type) || type != "KUKA") return RsiDecodeStatus::kForeign;

  out.actual_deg.resize(axes);
  out.setpoint_deg.resize(axes);
  out.has_setpoint = out.has_delay = out.has_rist = out.has_rsol = false;
  bool have_actual = false, too_large = false, actual_complete = false;
  int seen_delay = 0;
  Ipoc ipoc;
  const RsiDecodeStatus walked = walk(s, out.ipoc, ipoc, [&](const XmlScanner& c) {
    const std::string_view name = c.name();
    if (name == "AIPos" || name == "ASPos") {
      const bool actual = name == "AIPos";
      if (actual ? have_actual : out.has_setpoint) return RsiDecodeStatus::kMalformed;  // twice
      JointVector& q = actual ? out.actual_deg : out.setpoint_deg;
      const Values v = read_values(c, kAxisNames.data(), axes, q.data());
      if (v.bad) return RsiDecodeStatus::kMalformed;
      too_large = too_large || v.too_large;
      if (actual) {
        have_actual = true;
        actual_complete = v.complete;
      } else {
        out.has_setpoint = v.complete;  // an incomplete setpoint is not used
        if (!v.complete) return RsiDecodeStatus::kMissingAxes;
      }
    } else if (name == "RIst" || name == "RSol") {
      const bool ist = name == "RIst";
      bool& has = ist ? out.has_rist : out.has_rsol;
      if (has) return RsiDecodeStatus::kMalformed;
      const Values v = read_values(c, kPoseNames.data(), 6, ist ? out.rist.data() : out.rsol.data());
      if (v.bad) return RsiDecodeStatus::kMalformed;
      too_large = too_large || v.too_large;
      has = v.complete;
    } else if (name == "Delay") {
      std::string_view d;
      if (++seen_delay > 1 || !c.attribute("D", d) || parse_unsigned(d, out.delay) != Number::kOk) {
        return RsiDecodeStatus::kMalformed;
      }
      out.has_delay = true;
    }
    return RsiDecodeStatus::kOk;  // elements of other SEND entries are the controller's business
  });
  return verdict(walked, ipoc, have_actual && actual_complete, too_large);
}

RsiDecodeStatus decode_rsi_sensor(const unsigned char* data, std::size_t size, std::string_view sentype, int axes,
                                  RsiSensorMessage& out) noexcept {
  if (size == 0) return RsiDecodeStatus::kEmpty;
  if (axes < 1 || axes > kMaxJoints) return RsiDecodeStatus::kMissingAxes;
  XmlScanner s(reinterpret_cast<const char*>(data), size);
  if (s.next() == XmlToken::kError) return from_scanner(s.error());
  std::string_view type;
  if (s.name() != "Sen" || !s.attribute("Type", type) || type != sentype) return RsiDecodeStatus::kForeign;
  out.correction_deg.resize(axes);
  bool have_ak = false, ak_complete = false, too_large = false;
  Ipoc ipoc;
  const RsiDecodeStatus walked = walk(s, out.ipoc, ipoc, [&](const XmlScanner& c) {
    if (c.name() == "AK") {
      if (have_ak) return RsiDecodeStatus::kMalformed;
      const Values v = read_values(c, kAxisNames.data(), axes, out.correction_deg.data());
      if (v.bad) return RsiDecodeStatus::kMalformed;
      too_large = too_large || v.too_large;
      have_ak = true;
      ak_complete = v.complete;
    }
    return RsiDecodeStatus::kOk;
  });
  return verdict(walked, ipoc, have_ak && ak_complete, too_large);
}

std::size_t encode_rsi_sensor(std::string_view sentype, const RsiSensorMessage& msg, unsigned char* out,
                              std::size_t capacity) noexcept {
  const auto n = static_cast<int>(msg.correction_deg.size());
  if (!valid_rsi_sentype(sentype) || n < 1 || n > kMaxJoints || !msg.correction_deg.allFinite()) return 0;
  Writer w{out, capacity};
  w.put("<Sen Type=\"");
  w.put(sentype);
  w.put("\">");
  w.element("AK", kAxisNames.data(), n, msg.correction_deg.data(), 6);
  w.put("<IPOC>");
  w.integer(msg.ipoc);
  w.put("</IPOC></Sen>");
  return w.ok ? w.size : 0;
}

std::size_t encode_rsi_robot(const RsiRobotMessage& msg, int decimals, unsigned char* out,
                             std::size_t capacity) noexcept {
  const auto n = static_cast<int>(msg.actual_deg.size());
  if (n < 1 || n > kMaxJoints || decimals < 0 || decimals > 12) return 0;
  if (msg.has_setpoint && msg.setpoint_deg.size() != n) return 0;
  Writer w{out, capacity};
  w.put("<Rob Type=\"KUKA\">");
  if (msg.has_rist) w.element("RIst", kPoseNames.data(), 6, msg.rist.data(), decimals);
  if (msg.has_rsol) w.element("RSol", kPoseNames.data(), 6, msg.rsol.data(), decimals);
  w.element("AIPos", kAxisNames.data(), n, msg.actual_deg.data(), decimals);
  if (msg.has_setpoint) w.element("ASPos", kAxisNames.data(), n, msg.setpoint_deg.data(), decimals);
  w.put("<Delay D=\"");
  w.integer(msg.delay);
  w.put("\"/><IPOC>");
  w.integer(msg.ipoc);
  w.put("</IPOC></Rob>");
  return w.ok ? w.size : 0;
}

}  // namespace deflex
