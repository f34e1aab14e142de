// RAPID literal values and the layouts of the data types the program reader takes.
#include "deflex/offline/detail/rapid_values.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/offline/detail/program_text.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

std::optional<std::size_t> parse_rapid_value(const RapidSource& s, std::size_t i, std::size_t end, RapidValue& v) {
  if (i >= end) {
    return std::nullopt;
  }
  v.token = i;
  if (s.is_punct(i, "[")) {
    v.kind = RapidValue::Kind::kList;
    v.begin = s.tok[i].begin;
    ++i;
    if (s.is_punct(i, "]")) {
      v.end = s.tok[i].end;
      return i + 1;
    }
    while (true) {
      RapidValue item;
      const auto next = parse_rapid_value(s, i, end, item);
      if (!next) {
        return std::nullopt;
      }
      v.items.push_back(std::move(item));
      i = *next;
      if (s.is_punct(i, ",")) {
        ++i;
        continue;
      }
      if (s.is_punct(i, "]")) {
        v.end = s.tok[i].end;
        return i + 1;
      }
      return std::nullopt;
    }
  }
  double sign = 1.0;
  const std::size_t begin = s.tok[i].begin;
  if ((s.is_punct(i, "-") || s.is_punct(i, "+")) && i + 1 < end && s.tok[i + 1].kind == TokenKind::kNumber) {
    sign = s.is_punct(i, "-") ? -1.0 : 1.0;
    ++i;
  }
  const Token& u = s.tok[i];
  v.begin = begin;
  v.end = u.end;
  switch (u.kind) {
    case TokenKind::kNumber:
      v.kind = RapidValue::Kind::kNumber;
      v.number = sign * token_number(s, i);
      return i + 1;
    case TokenKind::kString:
      v.kind = RapidValue::Kind::kString;
      v.name = s.str(i);
      return i + 1;
    case TokenKind::kIdentifier:
      if (begin != u.begin || s.is_punct(i + 1, "(") || s.is_punct(i + 1, "{") || s.is_punct(i + 1, ".")) {
        return std::nullopt;  // -name, a call, an element or a component: an expression
      }
      v.kind = RapidValue::Kind::kName;
      v.name = s.str(i);
      return i + 1;
    default:
      return std::nullopt;
  }
}

namespace {

struct Field {
  const char* name;
  const char* type;  // "num", "bool", "string" or a record below
};

struct Layout {
  const char* type;
  std::vector<Field> fields;
};

const std::vector<Layout>& layouts() {
  static const std::vector<Layout> l = {
      {"pos", {{"x", "num"}, {"y", "num"}, {"z", "num"}}},
      {"orient", {{"q1", "num"}, {"q2", "num"}, {"q3", "num"}, {"q4", "num"}}},
      {"confdata", {{"cf1", "num"}, {"cf4", "num"}, {"cf6", "num"}, {"cfx", "num"}}},
      {"extjoint",
       {{"eax_a", "num"}, {"eax_b", "num"}, {"eax_c", "num"}, {"eax_d", "num"}, {"eax_e", "num"}, {"eax_f", "num"}}},
      {"robjoint",
       {{"rax_1", "num"}, {"rax_2", "num"}, {"rax_3", "num"}, {"rax_4", "num"}, {"rax_5", "num"}, {"rax_6", "num"}}},
      {"pose", {{"trans", "pos"}, {"rot", "orient"}}},
      {"robtarget", {{"trans", "pos"}, {"rot", "orient"}, {"robconf", "confdata"}, {"extax", "extjoint"}}},
      {"jointtarget", {{"robax", "robjoint"}, {"extax", "extjoint"}}},
      {"loaddata", {{"mass", "num"}, {"cog", "pos"}, {"aom", "orient"}, {"ix", "num"}, {"iy", "num"}, {"iz", "num"}}},
      {"tooldata", {{"robhold", "bool"}, {"tframe", "pose"}, {"tload", "loaddata"}}},
      {"wobjdata",
       {{"robhold", "bool"}, {"ufprog", "bool"}, {"ufmec", "string"}, {"uframe", "pose"}, {"oframe", "pose"}}},
  };
  return l;
}

const Layout* layout_of(const std::string& type) {
  for (const Layout& l : layouts()) {
    if (type == l.type) {
      return &l;
    }
  }
  return nullptr;
}

std::string article(const std::string& type) {
  return std::string(std::string("aeiou").find(type.front()) == std::string::npos ? "a " : "an ") + type;
}

struct Checker {
  const NumLookup& lookup;
  const std::function<void(std::size_t, const std::string&)>& fail;
  RapidValueState state = RapidValueState::kLiteral;

  void field_fail(const RapidValue& v, const std::string& path, const std::string& what) const {
    fail(v.token, path.empty() ? what : fmt::format("field '{}': {}", path, what));
  }

  void check(RapidValue& v, const std::string& type, const std::string& path) {
    if (type == "num") {
      number(v, path);
      return;
    }
    if (type == "bool") {
      if (!(v.kind == RapidValue::Kind::kName && (iequals(v.name, "TRUE") || iequals(v.name, "FALSE")))) {
        field_fail(v, path, "TRUE or FALSE expected");
      }
      return;
    }
    if (type == "string") {
      if (v.kind != RapidValue::Kind::kString) {
        field_fail(v, path, "a string \"...\" expected");
      }
      return;
    }
    const Layout& l = *layout_of(type);
    std::string names;
    for (const Field& f : l.fields) {
      names += (names.empty() ? "" : ", ") + std::string(f.name);
    }
    if (v.kind != RapidValue::Kind::kList) {
      field_fail(v, path, fmt::format("{} [{}] expected", article(type), names));
    }
    if (v.items.size() != l.fields.size()) {
      field_fail(v, path,
                 fmt::format("{} value{}, {} has {} ({})", v.items.size(), v.items.size() == 1 ? "" : "s",
                             article(type), l.fields.size(), names));
    }
    for (std::size_t k = 0; k < l.fields.size(); ++k) {
      check(v.items[k], l.fields[k].type, path.empty() ? l.fields[k].name : path + "." + l.fields[k].name);
    }
  }

  void number(RapidValue& v, const std::string& path) {
    if (v.kind == RapidValue::Kind::kNumber) {
      return;
    }
    if (v.kind != RapidValue::Kind::kName) {
      field_fail(v, path, "a number expected");
    }
    const std::optional<NamedNum> n = lookup(v.name);
    if (!n) {
      field_fail(v, path,
                 fmt::format("'{}' is not a number, and no num of that name is declared in this module", v.name));
    }
    if (!n->constant) {
      state = RapidValueState::kRunTime;
      return;
    }
    v.kind = RapidValue::Kind::kNumber;  // a CONST num: its value, written back as a number
    v.number = n->value;
  }
};

}  // namespace

bool is_checked_rapid_type(const std::string& type) { return type == "num" || layout_of(type) != nullptr; }

RapidValueState check_rapid_value(RapidValue& v, const std::string& type, const NumLookup& lookup,
                                  const std::function<void(std::size_t token, const std::string& what)>& fail) {
  if (!is_checked_rapid_type(type)) {
    return RapidValueState::kLiteral;
  }
  Checker c{lookup, fail};
  c.check(v, type, "");
  return c.state;
}

std::optional<Eigen::Quaterniond> rapid_quaternion(const RapidValue& orient) {
  const Eigen::Quaterniond q(orient.items[0].number, orient.items[1].number, orient.items[2].number,
                             orient.items[3].number);
  if (!(std::abs(q.norm() - 1.0) <= 1e-3)) {
    return std::nullopt;
  }
  return q.normalized();
}

std::optional<Pose> rapid_pose(const RapidValue& pose) {
  const auto q = rapid_quaternion(pose.items[1]);
  if (!q) {
    return std::nullopt;
  }
  Pose p = Pose::Identity();
  p.linear() = q->toRotationMatrix();
  const auto& t = pose.items[0].items;
  p.translation() = Vector3(t[0].number, t[1].number, t[2].number) * 1e-3;
  return p;
}

}  // namespace deflex
