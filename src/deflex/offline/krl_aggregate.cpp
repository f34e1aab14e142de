// KRL files, aggregates and frames.
#include "deflex/offline/detail/krl_aggregate.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "deflex/offline/detail/program_text.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

KrlFile::KrlFile(std::string f, const std::string& t) : ProgramSource{std::move(f), t, {}} {
  tok = lex_krl(text, file);
  for (std::size_t i = 0; i < tok.size();) {
    std::size_t j = i;
    while (j < tok.size() && tok[j].line == tok[i].line) {
      ++j;
    }
    lines.emplace_back(i, j);
    i = j;
  }
}

const KrlComponent* KrlAggregate::find(const char* name) const {
  for (const KrlComponent& c : comps) {
    if (c.name == name) {
      return &c;
    }
  }
  return nullptr;
}

bool KrlAggregate::numbers(std::initializer_list<const char*> names) const {
  return std::all_of(names.begin(), names.end(), [&](const char* n) {
    const KrlComponent* c = find(n);
    return c != nullptr && c->kind != KrlComponent::Kind::kOther;
  });
}

namespace {

/// 'B0110' or 'H1F' at token i as a number; a malformed literal is an error.
double bits_value(const KrlFile& f, std::size_t i, KrlComponent& c) {
  const std::string s = f.str(i);
  const char base = static_cast<char>(std::toupper(static_cast<unsigned char>(s.size() > 1 ? s[1] : ' ')));
  const std::string digits = s.size() >= 3 ? s.substr(2, s.size() - 3) : std::string();
  long bits = 0;
  const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), bits, base == 'B' ? 2 : 16);
  if ((base != 'B' && base != 'H') || digits.empty() || r.ec != std::errc() || r.ptr != digits.data() + digits.size()) {
    f.fail(i, fmt::format("{} is not a KRL bit literal ('B0110' or 'H1F')", s));
  }
  c.bit_digits = base == 'B' ? static_cast<int>(digits.size()) : 0;
  return static_cast<double>(bits);
}

}  // namespace

std::optional<std::size_t> parse_krl_aggregate(const KrlFile& f, std::size_t i, std::size_t end, KrlAggregate& a) {
  if (!f.is_punct(i, "{")) {
    return std::nullopt;
  }
  a.begin = f.tok[i].begin;
  ++i;
  if (f.is_ident(i) && f.is_punct(i + 1, ":")) {
    a.type = to_upper(f.str(i));  // a typed aggregate {E6POS: X ...}
    i += 2;
  }
  while (i < end) {
    if (f.is_punct(i, "}")) {
      a.end = f.tok[i].end;
      return i + 1;
    }
    if (!f.is_ident(i)) {
      return std::nullopt;
    }
    KrlComponent c;
    c.name = to_upper(f.str(i));
    c.token = i;
    ++i;
    if (f.is_punct(i, "[") && f.is_punct(i + 1, "]")) {
      i += 2;  // POINT2[] "..."
    }
    double sign = 1.0;
    c.begin = i < f.tok.size() ? f.tok[i].begin : 0;
    if ((f.is_punct(i, "-") || f.is_punct(i, "+")) && i + 1 < end && f.tok[i + 1].kind == TokenKind::kNumber) {
      sign = f.is_punct(i, "-") ? -1.0 : 1.0;
      ++i;
    }
    if (i >= end) {
      return std::nullopt;
    }
    const Token& v = f.tok[i];
    c.end = v.end;
    if (v.kind == TokenKind::kNumber) {
      c.kind = KrlComponent::Kind::kNumber;
      c.number = sign * token_number(f, i);
      ++i;
    } else if (v.kind == TokenKind::kBitLiteral) {
      c.kind = KrlComponent::Kind::kBits;
      c.number = bits_value(f, i, c);
      ++i;
    } else if (f.is_punct(i, "{")) {
      KrlAggregate inner;
      const auto next = parse_krl_aggregate(f, i, end, inner);
      if (!next) {
        return std::nullopt;
      }
      c.end = inner.end;
      i = *next;
    } else {
      ++i;  // enum, string, name: kept as they are
    }
    a.comps.push_back(c);
    if (f.is_punct(i, ",")) {
      ++i;
    } else if (!f.is_punct(i, "}")) {
      return std::nullopt;
    }
  }
  return std::nullopt;
}

bool krl_cartesian_type(const std::string& t) { return t == "E6POS" || t == "POS" || t == "FRAME"; }
bool krl_axis_type(const std::string& t) { return t == "E6AXIS" || t == "AXIS"; }

void check_krl_point(const KrlFile& f, const KrlAggregate& a, const std::string& type, const std::string& what) {
  static const std::vector<std::string> kFrame = {"X", "Y", "Z", "A", "B", "C"};
  static const std::vector<std::string> kPos = {"X", "Y", "Z", "A", "B", "C", "S", "T"};
  static const std::vector<std::string> kE6Pos = {"X", "Y",  "Z",  "A",  "B",  "C",  "S",
                                                  "T", "E1", "E2", "E3", "E4", "E5", "E6"};
  static const std::vector<std::string> kAxis = {"A1", "A2", "A3", "A4", "A5", "A6"};
  static const std::vector<std::string> kE6Axis = {"A1", "A2", "A3", "A4", "A5", "A6",
                                                   "E1", "E2", "E3", "E4", "E5", "E6"};
  const std::string t = type.empty() ? a.type : type;
  const bool axis = t.empty() ? a.find("A1") != nullptr : krl_axis_type(t);
  const std::vector<std::string>& allowed = t == "FRAME"  ? kFrame
                                            : t == "POS"  ? kPos
                                            : t == "AXIS" ? kAxis
                                            : axis        ? kE6Axis
                                                          : kE6Pos;
  const std::string type_name = t.empty() ? (axis ? "an axis point" : "a Cartesian point") : t;
  for (std::size_t k = 0; k < a.comps.size(); ++k) {
    const KrlComponent& c = a.comps[k];
    if (std::find(allowed.begin(), allowed.end(), c.name) == allowed.end()) {
      f.fail(c.token, fmt::format("{}: {} has no component '{}' (it has {})", what, type_name, c.name,
                                  fmt::join(allowed, ", ")));
    }
    for (std::size_t m = 0; m < k; ++m) {
      if (a.comps[m].name == c.name) {
        f.fail(c.token, fmt::format("{}: component '{}' is given twice", what, c.name));
      }
    }
    const bool status_turn = c.name == "S" || c.name == "T";
    if (c.kind == KrlComponent::Kind::kOther || (c.kind == KrlComponent::Kind::kBits && !status_turn)) {
      f.fail(c.token, fmt::format("{}: component '{}': '{}' is not a number", what, c.name,
                                  f.text.substr(c.begin, c.end - c.begin)));
    }
  }
}

Pose krl_frame(const KrlAggregate& a) {
  const auto v = [&](const char* n) {
    const KrlComponent* c = a.find(n);
    return c == nullptr ? 0.0 : c->number;
  };
  Pose p = Pose::Identity();
  p.translation() = Vector3(v("X"), v("Y"), v("Z")) * 1e-3;
  p.linear() = (Eigen::AngleAxisd(deg_to_rad(v("A")), Vector3::UnitZ()) *
                Eigen::AngleAxisd(deg_to_rad(v("B")), Vector3::UnitY()) *
                Eigen::AngleAxisd(deg_to_rad(v("C")), Vector3::UnitX()))
                   .toRotationMatrix();
  return p;
}

namespace {
double wrap_deg(double a) { return std::remainder(a, 360.0); }
}  // namespace

Vector3 krl_abc(const Matrix3& r, const Vector3& near) {
  const double b = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0)));
  const double a = std::atan2(r(1, 0), r(0, 0));
  const double c = std::atan2(r(2, 1), r(2, 2));
  const Vector3 first(rad_to_deg(a), rad_to_deg(b), rad_to_deg(c));
  const Vector3 second(wrap_deg(first.x() + 180.0), wrap_deg(180.0 - first.y()), wrap_deg(first.z() + 180.0));
  const auto distance = [&](const Vector3& x) {
    return std::abs(wrap_deg(x.x() - near.x())) + std::abs(wrap_deg(x.y() - near.y())) +
           std::abs(wrap_deg(x.z() - near.z()));
  };
  Vector3 best = distance(first) <= distance(second) ? first : second;
  for (int i = 0; i < 3; ++i) {
    best[i] = near[i] + wrap_deg(best[i] - near[i]);  // the same turn as the original angle
  }
  return best;
}

std::string krl_bits(int value, int digits) {
  std::string s;
  for (int v = value; v > 0; v /= 2) {
    s.insert(s.begin(), static_cast<char>('0' + v % 2));
  }
  while (static_cast<int>(s.size()) < std::max(digits, 1)) {
    s.insert(s.begin(), '0');
  }
  return "'B" + s + "'";
}

}  // namespace deflex
