// RAPID module reader and compensated writer.
#include "deflex/offline/rapid_program.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"
#include "deflex/offline/program_targets.hpp"
#include "deflex/offline/program_text.hpp"
#include "deflex/offline/program_tokens.hpp"
#include "deflex/offline/quaternion_sign.hpp"

namespace deflex {
namespace {

using Tokens = std::vector<Token>;

/// The source being read: text, tokens, file name for messages.
struct Source {
  std::string file;
  const std::string& text;
  Tokens tok;

  [[nodiscard]] std::string str(std::size_t i) const {
    return i < tok.size() ? text.substr(tok[i].begin, tok[i].end - tok[i].begin) : std::string();
  }
  [[nodiscard]] bool is_ident(std::size_t i, const char* word = nullptr) const {
    return i < tok.size() && tok[i].kind == TokenKind::kIdentifier && (word == nullptr || iequals(str(i), word));
  }
  [[nodiscard]] bool is_punct(std::size_t i, const char* p) const {
    return i < tok.size() && tok[i].kind == TokenKind::kPunct && str(i) == p;
  }
  /// The source text of tokens [b, e), on one line, for messages.
  [[nodiscard]] std::string span(std::size_t b, std::size_t e) const {
    if (b >= e || b >= tok.size()) {
      return {};
    }
    std::string s = text.substr(tok[b].begin, tok[e - 1].end - tok[b].begin);
    std::string out;
    bool blank = false;
    for (char c : s) {
      if (c == '\n' || c == '\r' || c == '\t' || c == ' ') {
        blank = true;
        continue;
      }
      if (blank && !out.empty()) {
        out += ' ';
      }
      blank = false;
      out += c;
    }
    return out.size() > 100 ? out.substr(0, 97) + "..." : out;
  }
  [[noreturn]] void fail(std::size_t i, const std::string& what) const {
    throw DataError(fmt::format("{}:{}: {}", file, i < tok.size() ? tok[i].line : 0, what));
  }
};

/// A literal RAPID value: aggregates [..], numbers (a sign included), strings, names (TRUE/FALSE).
struct Value {
  enum class Kind { kList, kNumber, kString, kName } kind = Kind::kNumber;
  double number = 0.0;
  std::size_t begin = 0, end = 0;  // bytes
  std::string name;
  std::vector<Value> items;
};

/// Parses a literal value at token i; returns the index after it, or nullopt when tokens there are
/// not a literal (an expression, a function call).
std::optional<std::size_t> parse_value(const Source& s, std::size_t i, std::size_t end, Value& v) {
  if (i >= end) {
    return std::nullopt;
  }
  const Token& t = s.tok[i];
  if (s.is_punct(i, "[")) {
    v.kind = Value::Kind::kList;
    v.begin = t.begin;
    ++i;
    if (s.is_punct(i, "]")) {
      v.end = s.tok[i].end;
      return i + 1;
    }
    while (true) {
      Value item;
      const auto next = parse_value(s, i, end, item);
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
  std::size_t begin = t.begin;
  if ((s.is_punct(i, "-") || s.is_punct(i, "+")) && i + 1 < end && s.tok[i + 1].kind == TokenKind::kNumber) {
    sign = s.is_punct(i, "-") ? -1.0 : 1.0;
    ++i;
  }
  const Token& u = s.tok[i];
  v.begin = begin;
  v.end = u.end;
  switch (u.kind) {
    case TokenKind::kNumber:
      v.kind = Value::Kind::kNumber;
      v.number = sign * token_number(s, i);
      return i + 1;
    case TokenKind::kString:
      v.kind = Value::Kind::kString;
      v.name = s.str(i);
      return i + 1;
    case TokenKind::kIdentifier:
      if (sign < 0.0 || begin != u.begin) {
        return std::nullopt;
      }
      v.kind = Value::Kind::kName;
      v.name = s.str(i);
      return i + 1;
    default:
      return std::nullopt;
  }
}

bool numbers(const Value& v, std::size_t n) {
  return v.kind == Value::Kind::kList && v.items.size() == n &&
         std::all_of(v.items.begin(), v.items.end(), [](const Value& x) { return x.kind == Value::Kind::kNumber; });
}

bool is_bool(const Value& v) {
  return v.kind == Value::Kind::kName && (iequals(v.name, "TRUE") || iequals(v.name, "FALSE"));
}

bool shape_robtarget(const Value& v) {
  return v.kind == Value::Kind::kList && v.items.size() == 4 && numbers(v.items[0], 3) && numbers(v.items[1], 4) &&
         numbers(v.items[2], 4) && numbers(v.items[3], 6);
}
bool shape_jointtarget(const Value& v) {
  return v.kind == Value::Kind::kList && v.items.size() == 2 && numbers(v.items[0], 6) && numbers(v.items[1], 6);
}
bool shape_pose(const Value& v) {
  return v.kind == Value::Kind::kList && v.items.size() == 2 && numbers(v.items[0], 3) && numbers(v.items[1], 4);
}
bool shape_tooldata(const Value& v) {
  return v.kind == Value::Kind::kList && v.items.size() == 3 && is_bool(v.items[0]) && shape_pose(v.items[1]);
}
bool shape_wobjdata(const Value& v) {
  return v.kind == Value::Kind::kList && v.items.size() == 5 && is_bool(v.items[0]) && is_bool(v.items[1]) &&
         v.items[2].kind == Value::Kind::kString && shape_pose(v.items[3]) && shape_pose(v.items[4]);
}

/// A RAPID orientation [q1, q2, q3, q4] = [w, x, y, z]; nullopt unless of unit length (1e-3).
std::optional<Eigen::Quaterniond> quaternion(const Value& v) {
  const Eigen::Quaterniond q(v.items[0].number, v.items[1].number, v.items[2].number, v.items[3].number);
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    return std::nullopt;
  }
  return q.normalized();
}

/// pose value [[x,y,z],[q1..q4]] in mm to a Pose in m.
std::optional<Pose> pose_of(const Value& v) {
  const auto q = quaternion(v.items[1]);
  if (!q) {
    return std::nullopt;
  }
  Pose p = Pose::Identity();
  p.linear() = q->toRotationMatrix();
  p.translation() = Vector3(v.items[0].items[0].number, v.items[0].items[1].number, v.items[0].items[2].number) * 1e-3;
  return p;
}

struct Decl {
  std::size_t first_tok = 0;  // LOCAL/TASK or the storage keyword
  std::string storage;        // CONST, PERS, VAR as written
  std::string type;           // lower case
  std::size_t name_tok = 0;
  std::string name;
  std::vector<int> dims;
  bool literal = false;
  std::size_t value_tok = 0;
  std::size_t end_tok = 0;  // the ';'
  Value value;
};

struct ExternalData {
  std::string name;
  Value value;
  std::string text;  // the value's text, which the Value's byte offsets index
};

struct Instruction {
  std::size_t tok = 0;
  std::string name;
  std::size_t end_tok = 0;
  std::vector<std::pair<std::size_t, std::size_t>> args;               // positional expressions [b, e)
  std::map<std::string, std::pair<std::size_t, std::size_t>> options;  // upper name -> value [b, e)
};

struct Motion {
  const char* name;
  std::size_t positional;
  std::vector<std::string> options;
  std::vector<const char*> argument_names;
};

const std::vector<Motion>& motions() {
  static const std::vector<Motion> m = {
      {"MoveL",
       4,
       {"CONC", "ID", "V", "T", "Z", "INPOS", "WOBJ", "CORR", "TLOAD"},
       {"ToPoint", "Speed", "Zone", "Tool"}},
      {"MoveJ",
       4,
       {"CONC", "ID", "V", "T", "Z", "INPOS", "WOBJ", "CORR", "TLOAD"},
       {"ToPoint", "Speed", "Zone", "Tool"}},
      {"MoveC",
       5,
       {"CONC", "ID", "V", "T", "Z", "INPOS", "WOBJ", "CORR", "TLOAD"},
       {"CirPoint", "ToPoint", "Speed", "Zone", "Tool"}},
      {"MoveAbsJ",
       4,
       {"CONC", "ID", "NOEOFFS", "V", "T", "Z", "INPOS", "WOBJ", "TLOAD"},
       {"ToJointPos", "Speed", "Zone", "Tool"}},
  };
  return m;
}

/// ABB's other motion instructions: deflex does not compensate them, so their targets are listed and
/// left unchanged (a user routine that merely starts with "Move" is not one of them).
bool other_motion(const std::string& name) {
  static const char* const kNames[] = {
      "MoveLDO",   "MoveJDO",   "MoveCDO", "MoveLSync", "MoveJSync",  "MoveCSync", "MoveExtJ", "MoveLAO",
      "MoveJAO",   "MoveCAO",   "MoveLGO", "MoveJGO",   "MoveCGO",    "TriggL",    "TriggJ",   "TriggC",
      "TriggLIOs", "TriggJIOs", "SearchL", "SearchC",   "SearchExtJ", "ArcL",      "ArcC",     "ArcLStart",
      "ArcLEnd",   "ArcCStart", "ArcCEnd", "ArcL1",     "ArcL2",      "ArcC1",     "ArcC2",    "SpotL",
      "SpotJ",     "SpotML",    "PaintL",  "PaintC",    "CapL",       "CapC",      "DispL",    "DispC"};
  return std::any_of(std::begin(kNames), std::end(kNames), [&](const char* n) { return iequals(name, n); });
}

/// A target reference the reader resolved: a literal in the instruction or a declared name.
struct TargetRef {
  bool literal = false;
  const Value* value = nullptr;  // the robtarget/jointtarget value node
  const Decl* decl = nullptr;
  int element = -1;                  // 0-based array element, -1 for scalars
  std::size_t ref_b = 0, ref_e = 0;  // tokens of the reference (name or name{i}) or of the literal
  enum class Offset { kNone, kOffs, kRelTool } offset = Offset::kNone;
  Vector3 d_mm = Vector3::Zero();
  Vector3 rot_deg = Vector3::Zero();  // RelTool \Rx, \Ry, \Rz
};

class RapidReader {
 public:
  RapidReader(const RobotModel& model, const ForceModel& force, std::string file, const std::string& text,
              const ProgramOptions& options)
      : model_(model), force_(force), src_{std::move(file), text, {}} {
    src_.tok = lex_rapid(text, src_.file);
    read_external(options.tooldata, "--tooldata", "tooldata", tools_);
    read_external(options.wobjdata, "--wobjdata", "wobjdata", wobjs_);
    read_declarations();
    read_references();
  }

  ProgramCompensation run(const std::string& output_path);

 private:
  void read_external(const std::vector<std::string>& specs, const char* option, const char* type,
                     std::map<std::string, ExternalData>& out) {
    for (const std::string& spec : specs) {
      const auto eq = spec.find('=');
      const std::string name = spec.substr(0, eq);
      ExternalData d;
      d.name = name;
      d.text = eq == std::string::npos ? std::string() : spec.substr(eq + 1);
      const std::string where = fmt::format("option {} '{}'", option, spec);
      if (eq == std::string::npos || name.empty()) {
        throw InputError(fmt::format("{}: give NAME=VALUE in RAPID syntax", where));
      }
      Source s{where, d.text, {}};
      try {
        s.tok = lex_rapid(d.text, where);
      } catch (const DataError& e) {
        throw InputError(e.what());
      }
      const auto end = parse_value(s, 0, s.tok.size(), d.value);
      const bool ok = end && *end == s.tok.size() &&
                      (std::string(type) == "tooldata" ? shape_tooldata(d.value) : shape_wobjdata(d.value));
      if (!ok) {
        throw InputError(
            fmt::format("{}: not a literal {} value ({})", where, type,
                        std::string(type) == "tooldata"
                            ? "[robhold,[[x,y,z],[q1,q2,q3,q4]],[mass,[cx,cy,cz],[a1,a2,a3,a4],ix,iy,iz]]"
                            : "[robhold,ufprog,\"ufmec\",[[x,y,z],[q1,q2,q3,q4]],[[x,y,z],[q1,q2,q3,q4]]]"));
      }
      out[to_upper(name)] = d;
    }
  }

  void read_declarations() {
    const Tokens& t = src_.tok;
    for (std::size_t i = 0; i + 2 < t.size(); ++i) {
      if (!(src_.is_ident(i, "CONST") || src_.is_ident(i, "PERS") || src_.is_ident(i, "VAR"))) {
        continue;
      }
      if (!src_.is_ident(i + 1) || !src_.is_ident(i + 2)) {
        continue;
      }
      // A routine parameter (VAR robtarget p) ends at ',' or ')', a declaration at ';'.
      std::size_t j = i + 3;
      int depth = 0;
      while (j < t.size() &&
             !(depth == 0 && (src_.is_punct(j, ";") || src_.is_punct(j, ",") || src_.is_punct(j, ")")))) {
        if (src_.is_punct(j, "[") || src_.is_punct(j, "(") || src_.is_punct(j, "{")) {
          ++depth;
        } else if (src_.is_punct(j, "]") || src_.is_punct(j, ")") || src_.is_punct(j, "}")) {
          --depth;
        }
        ++j;
      }
      if (!src_.is_punct(j, ";")) {
        continue;
      }
      Decl d;
      d.first_tok = i > 0 && (src_.is_ident(i - 1, "LOCAL") || src_.is_ident(i - 1, "TASK")) ? i - 1 : i;
      d.storage = src_.str(i);
      std::string type = src_.str(i + 1);
      std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return std::tolower(c); });
      d.type = type;
      d.name_tok = i + 2;
      d.name = src_.str(i + 2);
      d.end_tok = j;
      std::size_t k = i + 3;
      if (src_.is_punct(k, "{")) {
        ++k;
        while (k < j && !src_.is_punct(k, "}")) {
          if (t[k].kind == TokenKind::kNumber) {
            d.dims.push_back(token_index(src_, k));
          } else if (!src_.is_punct(k, ",")) {
            d.dims.push_back(-1);  // a dimension given by a name: unknown size
          }
          ++k;
        }
        ++k;
      }
      if (src_.is_punct(k, ":=")) {
        d.value_tok = k + 1;
        const auto end = parse_value(src_, k + 1, j, d.value);
        d.literal = end && *end == j;
      }
      decls_.push_back(d);
      i = j;
    }
    for (std::size_t n = 0; n < decls_.size(); ++n) {
      by_name_[to_upper(decls_[n].name)].push_back(n);
      decl_name_tokens_.insert(decls_[n].name_tok);
    }
  }

  /// Every use of every name, and the names code assigns to (their values are not static).
  void read_references() {
    const Tokens& t = src_.tok;
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (t[i].kind != TokenKind::kIdentifier || decl_name_tokens_.count(i) != 0) {
        continue;
      }
      if (i > 0 && (src_.is_punct(i - 1, "\\") || src_.is_punct(i - 1, "."))) {
        continue;  // an optional argument's or a record component's name
      }
      const std::string key = to_upper(src_.str(i));
      ++references_[key];
      std::size_t j = i + 1;
      if (src_.is_punct(j, "{")) {
        int depth = 0;
        do {
          depth += src_.is_punct(j, "{") ? 1 : (src_.is_punct(j, "}") ? -1 : 0);
          ++j;
        } while (j < t.size() && depth > 0);
      }
      while (src_.is_punct(j, ".") && src_.is_ident(j + 1)) {
        j += 2;
      }
      if (src_.is_punct(j, ":=")) {
        assigned_.insert(key);
      }
    }
  }

  /// The one literal declaration of `name` of `type`, or the reason there is none.
  const Decl* find_decl(const std::string& name, const std::string& type, std::string& why) const {
    const auto it = by_name_.find(to_upper(name));
    if (it == by_name_.end()) {
      why = fmt::format("'{}' is not declared in this module", name);
      return nullptr;
    }
    if (it->second.size() > 1) {
      why = fmt::format("'{}' is declared {} times in this module", name, it->second.size());
      return nullptr;
    }
    const Decl& d = decls_[it->second.front()];
    if (d.type != type) {
      why = fmt::format("'{}' is a {}, not a {}", name, d.type, type);
      return nullptr;
    }
    if (assigned_.count(to_upper(name)) != 0) {
      why = fmt::format("'{}' is assigned while the program runs", name);
      return nullptr;
    }
    if (!d.literal) {
      why = fmt::format("the value of '{}' is not a literal", name);
      return nullptr;
    }
    return &d;
  }

  /// A number argument: a literal (with sign) or a CONST num.
  std::optional<double> number_arg(std::size_t b, std::size_t e) const {
    Value v;
    const auto end = parse_value(src_, b, e, v);
    if (end && *end == e && v.kind == Value::Kind::kNumber) {
      return v.number;
    }
    if (e == b + 1 && src_.is_ident(b)) {
      std::string why;
      const Decl* d = find_decl(src_.str(b), "num", why);
      if (d != nullptr && d->value.kind == Value::Kind::kNumber) {
        return d->value.number;
      }
    }
    return std::nullopt;
  }

  /// Splits tokens [b, e) at depth-0 occurrences of `sep`.
  std::vector<std::pair<std::size_t, std::size_t>> split(std::size_t b, std::size_t e, const char* sep) const {
    std::vector<std::pair<std::size_t, std::size_t>> out;
    int depth = 0;
    std::size_t start = b;
    for (std::size_t i = b; i < e; ++i) {
      if (src_.is_punct(i, "[") || src_.is_punct(i, "(") || src_.is_punct(i, "{")) {
        ++depth;
      } else if (src_.is_punct(i, "]") || src_.is_punct(i, ")") || src_.is_punct(i, "}")) {
        --depth;
      } else if (depth == 0 && src_.is_punct(i, sep)) {
        out.emplace_back(start, i);
        start = i + 1;
      }
    }
    out.emplace_back(start, e);
    return out;
  }

  /// A reference (name, name{i}) or a literal of `type`; nullopt with `why` otherwise.
  std::optional<TargetRef> plain_ref(std::size_t b, std::size_t e, const std::string& type, std::string& why) const {
    TargetRef r;
    r.ref_b = b;
    r.ref_e = e;
    if (src_.is_punct(b, "[")) {
      auto* v = new Value();  // owned by literals_ (stable addresses)
      literals_.emplace_back(v);
      const auto end = parse_value(src_, b, e, *v);
      const bool ok = end && *end == e && (type == "robtarget" ? shape_robtarget(*v) : shape_jointtarget(*v));
      if (!ok) {
        why = fmt::format("the literal is not a constant {}", type);
        return std::nullopt;
      }
      r.literal = true;
      r.value = v;
      return r;
    }
    if (!src_.is_ident(b)) {
      why = "computed at run time";
      return std::nullopt;
    }
    int index = -1;
    if (e != b + 1) {
      if (!(e == b + 4 && src_.is_punct(b + 1, "{") && src_.tok[b + 2].kind == TokenKind::kNumber &&
            src_.is_punct(b + 3, "}"))) {
        why = "computed at run time (an expression or a variable index)";
        return std::nullopt;
      }
      index = token_index(src_, b + 2) - 1;
    }
    const Decl* d = find_decl(src_.str(b), type, why);
    if (d == nullptr) {
      return std::nullopt;
    }
    const Value* v = &d->value;
    if (index >= 0 || !d->dims.empty()) {
      if (index < 0 || d->dims.size() != 1 || v->kind != Value::Kind::kList ||
          static_cast<std::size_t>(index) >= v->items.size()) {
        why = fmt::format("'{}' is an array: only a literal index within its one dimension resolves", d->name);
        return std::nullopt;
      }
      v = &v->items[static_cast<std::size_t>(index)];
    }
    if (!(type == "robtarget" ? shape_robtarget(*v) : shape_jointtarget(*v))) {
      why = fmt::format("the value of '{}' is not a {}", src_.str(b), type);
      return std::nullopt;
    }
    r.decl = d;
    r.element = index;
    r.value = v;
    return r;
  }

  /// A target argument: plain reference, or Offs()/RelTool() of one with constant displacements.
  std::optional<TargetRef> target_ref(std::size_t b, std::size_t e, const std::string& type, std::string& why) const {
    const bool offs = src_.is_ident(b, "Offs");
    const bool reltool = src_.is_ident(b, "RelTool");
    if (type == "robtarget" && (offs || reltool) && src_.is_punct(b + 1, "(") && src_.is_punct(e - 1, ")")) {
      const auto args = split(b + 2, e - 1, ",");
      if (args.size() != 4) {
        why = fmt::format("{} takes 4 arguments", src_.str(b));
        return std::nullopt;
      }
      auto base = plain_ref(args[0].first, args[0].second, type, why);
      if (!base) {
        return std::nullopt;
      }
      auto last = split(args[3].first, args[3].second, "\\");
      if (offs && last.size() != 1) {
        why = "Offs takes no optional arguments";
        return std::nullopt;
      }
      std::pair<std::size_t, std::size_t> dz = last.front();
      const auto dx = number_arg(args[1].first, args[1].second);
      const auto dy = number_arg(args[2].first, args[2].second);
      const auto dzv = number_arg(dz.first, dz.second);
      if (!dx || !dy || !dzv) {
        why = fmt::format("the displacement of {} is computed at run time", src_.str(b));
        return std::nullopt;
      }
      base->d_mm = Vector3(*dx, *dy, *dzv);
      base->offset = offs ? TargetRef::Offset::kOffs : TargetRef::Offset::kRelTool;
      for (std::size_t k = 1; k < last.size(); ++k) {
        const auto [ob, oe] = last[k];
        const std::string opt = to_upper(src_.str(ob));
        const auto v = src_.is_punct(ob + 1, ":=") ? number_arg(ob + 2, oe) : std::nullopt;
        const int axis = opt == "RX" ? 0 : opt == "RY" ? 1 : opt == "RZ" ? 2 : -1;
        if (axis < 0 || !v) {
          why = fmt::format("RelTool argument '\\{}' is not a constant \\Rx, \\Ry or \\Rz", src_.str(ob));
          return std::nullopt;
        }
        base->rot_deg[axis] = *v;
      }
      return base;
    }
    return plain_ref(b, e, type, why);
  }

  struct ToolWobj {
    Pose tool = Pose::Identity();
    Pose wobj = Pose::Identity();
  };

  /// The tool and work object of a motion; nullopt with `why` when they cannot be used statically.
  /// Throws for a name declared nowhere.
  std::optional<ToolWobj> tool_and_wobj(const Instruction& ins, std::string& why) const {
    ToolWobj tw;
    const auto [tb, te] = ins.args.back();
    const auto data = [&](std::size_t b, std::size_t e, const char* type, const char* option,
                          const std::map<std::string, ExternalData>& external) -> std::optional<Value> {
      if (!(e == b + 1 && src_.is_ident(b))) {
        why = fmt::format("the {} is an expression", type);
        return std::nullopt;
      }
      const std::string name = src_.str(b);
      const std::string key = to_upper(name);
      const auto it = by_name_.find(key);
      if (it != by_name_.end()) {
        const Decl* d = find_decl(name, type, why);
        if (d == nullptr) {
          return std::nullopt;
        }
        return d->value;
      }
      if (const auto ext = external.find(key); ext != external.end()) {
        return ext->second.value;
      }
      src_.fail(b, fmt::format("{}: {} '{}' is declared neither in this module nor with {} {}=[...]", ins.name, type,
                               name, option, name));
    };
    // tool0 and wobj0 are predefined (the flange, the base frame) unless the module declares its own.
    const std::string tool_name = to_upper(src_.str(tb));
    if (!(te == tb + 1 && tool_name == "TOOL0" && by_name_.count("TOOL0") == 0)) {
      const auto v = data(tb, te, "tooldata", "--tooldata", tools_);
      if (!v) {
        return std::nullopt;
      }
      if (!shape_tooldata(*v)) {
        why = "the tooldata is not a literal [robhold,[[x,y,z],[q]],...]";
        return std::nullopt;
      }
      if (iequals(v->items[0].name, "FALSE")) {
        why = fmt::format("tool '{}' is stationary (robhold FALSE): not supported", src_.str(tb));
        return std::nullopt;
      }
      const auto p = pose_of(v->items[1]);
      if (!p) {
        src_.fail(tb, fmt::format("tooldata '{}': its quaternion is not of unit length", src_.str(tb)));
      }
      tw.tool = *p;
    }
    if (const auto it = ins.options.find("WOBJ"); it != ins.options.end()) {
      const auto [wb, we] = it->second;
      if (!(we == wb + 1 && iequals(src_.str(wb), "wobj0") && by_name_.count("WOBJ0") == 0)) {
        const auto v = data(wb, we, "wobjdata", "--wobjdata", wobjs_);
        if (!v) {
          return std::nullopt;
        }
        if (!shape_wobjdata(*v)) {
          why = "the wobjdata is not a literal [robhold,ufprog,\"ufmec\",uframe,oframe]";
          return std::nullopt;
        }
        if (iequals(v->items[0].name, "TRUE") || iequals(v->items[1].name, "FALSE") || v->items[2].name != "\"\"") {
          why = fmt::format("work object '{}' is held by the robot or moved by a mechanical unit: not supported",
                            src_.str(wb));
          return std::nullopt;
        }
        const auto uf = pose_of(v->items[3]);
        const auto of = pose_of(v->items[4]);
        if (!uf || !of) {
          src_.fail(wb, fmt::format("wobjdata '{}': a quaternion is not of unit length", src_.str(wb)));
        }
        tw.wobj = *uf * *of;
      }
    }
    return tw;
  }

  Instruction parse_instruction(std::size_t i, const Motion& m) const {
    Instruction ins;
    ins.tok = i;
    ins.name = m.name;
    std::size_t j = i + 1;
    int depth = 0;
    while (j < src_.tok.size() && !(depth == 0 && src_.is_punct(j, ";"))) {
      depth += (src_.is_punct(j, "[") || src_.is_punct(j, "(") || src_.is_punct(j, "{")) ? 1 : 0;
      depth -= (src_.is_punct(j, "]") || src_.is_punct(j, ")") || src_.is_punct(j, "}")) ? 1 : 0;
      ++j;
    }
    if (j >= src_.tok.size()) {
      src_.fail(i, fmt::format("{}: no ';' ends the instruction", m.name));
    }
    ins.end_tok = j;
    for (const auto& [pb, pe] : split(i + 1, j, ",")) {
      const auto parts = split(pb, pe, "\\");
      if (parts.front().first != parts.front().second) {
        ins.args.push_back(parts.front());
      }
      for (std::size_t k = 1; k < parts.size(); ++k) {
        const auto [ob, oe] = parts[k];
        if (!src_.is_ident(ob)) {
          src_.fail(ob, fmt::format("{}: '\\' not followed by an optional argument's name", m.name));
        }
        const std::string opt = to_upper(src_.str(ob));
        if (std::find(m.options.begin(), m.options.end(), opt) == m.options.end()) {
          std::string known;
          for (const auto& o : m.options) {
            known += (known.empty() ? "\\" : ", \\") + o;
          }
          src_.fail(ob, fmt::format("{}: unknown optional argument '\\{}' (it takes {})", m.name, src_.str(ob), known));
        }
        ins.options[opt] = src_.is_punct(ob + 1, ":=") ? std::pair{ob + 2, oe} : std::pair{oe, oe};
      }
    }
    if (ins.args.size() != m.positional) {
      std::string names;
      for (const char* n : m.argument_names) {
        names += (names.empty() ? "" : ", ") + std::string(n);
      }
      src_.fail(i,
                fmt::format("{}: {} arguments ({}) expected, {} given", m.name, m.positional, names, ins.args.size()));
    }
    return ins;
  }

  const RobotModel& model_;
  const ForceModel& force_;
  Source src_;
  std::vector<Decl> decls_;
  std::map<std::string, std::vector<std::size_t>> by_name_;
  std::set<std::size_t> decl_name_tokens_;
  std::map<std::string, int> references_;
  std::set<std::string> assigned_;
  std::map<std::string, ExternalData> tools_, wobjs_;
  mutable std::vector<std::unique_ptr<Value>> literals_;
};

/// One resolved use and what writing it back needs.
struct Use {
  TargetRef ref;
  std::string type;
  Pose base_T_wobj = Pose::Identity();
  std::size_t use_index = 0;  // into the ProgramTargetUse list
  std::string instruction;
  int line = 0;
  std::string written;
  // Filled after compensation: the new numbers, parallel to the value's number nodes.
  std::vector<std::pair<const Value*, std::string>> numbers;
};

/// Number nodes of a robtarget (trans, rot, robconf) or jointtarget (robax) value, in order.
std::vector<const Value*> target_numbers(const Value& v, const std::string& type) {
  std::vector<const Value*> out;
  const std::size_t lists = type == "robtarget" ? 3 : 1;
  for (std::size_t l = 0; l < lists; ++l) {
    for (const Value& x : v.items[l].items) {
      out.push_back(&x);
    }
  }
  return out;
}

std::string valid_identifier(const std::string& base, int k, const std::set<std::string>& taken) {
  for (;; ++k) {
    const std::string suffix = fmt::format("_c{}", k);
    std::string name = base.substr(0, std::min(base.size(), 32 - suffix.size())) + suffix;
    if (taken.count(to_upper(name)) == 0) {
      return name;
    }
  }
}

ProgramCompensation RapidReader::run(const std::string& output_path) {
  ProgramCompensation result;
  result.language = "RAPID";
  result.force_description = force_.describe();
  std::vector<ProgramTargetUse> uses;
  std::vector<Use> info;
  std::size_t force_index = 0;
  const Tokens& t = src_.tok;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i].kind != TokenKind::kIdentifier || decl_name_tokens_.count(i) != 0 ||
        (i > 0 && (src_.is_punct(i - 1, "\\") || src_.is_punct(i - 1, ".")))) {
      continue;
    }
    const std::string word = src_.str(i);
    const auto m =
        std::find_if(motions().begin(), motions().end(), [&](const Motion& x) { return iequals(word, x.name); });
    if (m == motions().end()) {
      // Other motion instructions: their targets stay as they are, said so.
      if (other_motion(word) && !src_.is_punct(i + 1, ":=") && !src_.is_punct(i + 1, "(") &&
          (i == 0 || src_.is_punct(i - 1, ";") || src_.tok[i - 1].line != t[i].line)) {
        std::size_t j = i;
        while (j < t.size() && !src_.is_punct(j, ";")) {
          ++j;
        }
        result.unresolved.push_back(
            {src_.file, t[i].line, src_.span(i, std::min(j + 1, t.size())),
             fmt::format("{} is not compensated by deflex (MoveL, MoveJ, MoveC and MoveAbsJ are)", word)});
        i = j;
      }
      continue;
    }
    const Instruction ins = parse_instruction(i, *m);
    const bool joint = iequals(m->name, "MoveAbsJ");
    const std::size_t n_targets = iequals(m->name, "MoveC") ? 2 : 1;
    std::string why;
    const auto tw = tool_and_wobj(ins, why);
    for (std::size_t k = 0; k < n_targets; ++k) {
      const auto [b, e] = ins.args[k];
      const std::size_t index = force_index++;
      const std::string written = src_.span(b, e);
      if (!tw) {
        result.unresolved.push_back({src_.file, t[i].line, fmt::format("{} {}", m->name, written), why});
        continue;
      }
      std::string why_target;
      const std::string type = joint ? "jointtarget" : "robtarget";
      const auto ref = target_ref(b, e, type, why_target);
      if (!ref) {
        result.unresolved.push_back({src_.file, t[i].line, fmt::format("{} {}", m->name, written), why_target});
        continue;
      }
      ProgramTargetUse u;
      u.file = src_.file;
      u.line = t[i].line;
      u.instruction = m->name;
      u.target = written;
      u.joint = joint;
      u.flange_T_tcp = tw->tool;
      u.force_index = index;
      const Value& v = *ref->value;
      if (joint) {
        u.q.resize(6);
        for (int j = 0; j < 6; ++j) {
          u.q[j] = deg_to_rad(v.items[0].items[static_cast<std::size_t>(j)].number);
        }
        if (model_.dof() != 6) {
          src_.fail(b, fmt::format("{}: a jointtarget has 6 robot axes, the robot {}", m->name, model_.dof()));
        }
      } else {
        const auto q = quaternion(v.items[1]);
        if (!q) {
          src_.fail(b, fmt::format("{} {}: the orientation is not a unit quaternion", m->name, written));
        }
        Pose obj = Pose::Identity();
        obj.linear() = q->toRotationMatrix();
        obj.translation() =
            Vector3(v.items[0].items[0].number, v.items[0].items[1].number, v.items[0].items[2].number) * 1e-3;
        if (ref->offset == TargetRef::Offset::kOffs) {
          obj.translation() += ref->d_mm * 1e-3;
        } else if (ref->offset == TargetRef::Offset::kRelTool) {
          obj.translation() += obj.linear() * ref->d_mm * 1e-3;
          obj.linear() = obj.linear() * Eigen::AngleAxisd(deg_to_rad(ref->rot_deg.x()), Vector3::UnitX()) *
                         Eigen::AngleAxisd(deg_to_rad(ref->rot_deg.y()), Vector3::UnitY()) *
                         Eigen::AngleAxisd(deg_to_rad(ref->rot_deg.z()), Vector3::UnitZ());
        }
        u.base_T_tcp = tw->wobj * obj;
        const auto& c = v.items[2].items;
        u.ik.configuration =
            ArmConfiguration{static_cast<int>(std::lround(c[0].number)), static_cast<int>(std::lround(c[1].number)),
                             static_cast<int>(std::lround(c[2].number)), static_cast<int>(std::lround(c[3].number))};
        u.ik.match_quadrants = true;
      }
      Use x;
      x.ref = *ref;
      x.type = type;
      x.base_T_wobj = tw->wobj;
      x.use_index = uses.size();
      x.instruction = m->name;
      x.line = t[i].line;
      x.written = written;
      info.push_back(x);
      uses.push_back(u);
    }
    i = ins.end_tok;
  }

  const std::vector<ProgramTargetResult> results = compensate_program_targets(model_, uses, force_);

  // New numbers per use.
  for (Use& x : info) {
    const ProgramTargetResult& r = results[x.use_index];
    const Value& v = *x.ref.value;
    const auto nodes = target_numbers(v, x.type);
    std::vector<std::string> texts;
    if (x.type == "jointtarget") {
      for (int j = 0; j < 6; ++j) {
        texts.push_back(program_number(rad_to_deg(r.q_command[j]), 4));
      }
    } else {
      Pose obj = x.base_T_wobj.inverse() * r.tcp_command;
      if (x.ref.offset == TargetRef::Offset::kOffs) {
        obj.translation() -= x.ref.d_mm * 1e-3;
      } else if (x.ref.offset == TargetRef::Offset::kRelTool) {
        const Matrix3 rel = (Eigen::AngleAxisd(deg_to_rad(x.ref.rot_deg.x()), Vector3::UnitX()) *
                             Eigen::AngleAxisd(deg_to_rad(x.ref.rot_deg.y()), Vector3::UnitY()) *
                             Eigen::AngleAxisd(deg_to_rad(x.ref.rot_deg.z()), Vector3::UnitZ()))
                                .toRotationMatrix();
        obj.linear() = obj.linear() * rel.transpose();
        obj.translation() -= obj.linear() * x.ref.d_mm * 1e-3;
      }
      const Eigen::Quaterniond q0(v.items[1].items[0].number, v.items[1].items[1].number, v.items[1].items[2].number,
                                  v.items[1].items[3].number);
      const Eigen::Quaterniond q = quaternion_near(obj, q0.normalized());
      const Vector3 p = obj.translation() * 1e3;
      for (int j = 0; j < 3; ++j) {
        texts.push_back(program_number(p[j], 4));
      }
      for (const double c : {q.w(), q.x(), q.y(), q.z()}) {
        texts.push_back(program_number(c, 8));
      }
      for (const int c : {r.configuration.cf1, r.configuration.cf4, r.configuration.cf6, r.configuration.cfx}) {
        texts.push_back(std::to_string(c));
      }
    }
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      x.numbers.emplace_back(nodes[k], texts[k]);
    }
  }

  // Write back: literals in place; a declaration in place when every reference to it is a resolved
  // use and all its uses agree; otherwise a copy per use.
  std::vector<TextEdit> edits;
  std::set<std::string> taken;
  for (const Token& tk : t) {
    if (tk.kind == TokenKind::kIdentifier) {
      taken.insert(to_upper(src_.text.substr(tk.begin, tk.end - tk.begin)));
    }
  }
  std::map<std::string, int> resolved_refs;  // per declaration name
  for (const Use& x : info) {
    if (!x.ref.literal) {
      ++resolved_refs[to_upper(x.ref.decl->name)];
    }
  }
  const std::string eol = line_terminator(src_.text);
  std::vector<std::string> actions(info.size());
  std::set<std::size_t> done;
  for (std::size_t a = 0; a < info.size(); ++a) {
    const Use& x = info[a];
    if (x.ref.literal) {
      for (const auto& [node, text] : x.numbers) {
        edits.push_back({node->begin, node->end - node->begin, text});
      }
      actions[a] = "literal edited";
      continue;
    }
    if (done.count(a) != 0) {
      continue;
    }
    std::vector<std::size_t> group;
    for (std::size_t b = a; b < info.size(); ++b) {
      if (!info[b].ref.literal && info[b].ref.decl == x.ref.decl && info[b].ref.element == x.ref.element) {
        group.push_back(b);
        done.insert(b);
      }
    }
    const std::string key = to_upper(x.ref.decl->name);
    const bool only_resolved_uses = references_[key] == resolved_refs[key];
    const bool agree = std::all_of(group.begin(), group.end(), [&](std::size_t b) {
      for (std::size_t k = 0; k < x.numbers.size(); ++k) {
        if (info[b].numbers[k].second != x.numbers[k].second) {
          return false;
        }
      }
      return true;
    });
    if (only_resolved_uses && agree) {
      for (const auto& [node, text] : x.numbers) {
        edits.push_back({node->begin, node->end - node->begin, text});
      }
      for (const std::size_t b : group) {
        actions[b] = "edited in place";
      }
      continue;
    }
    const Decl& d = *x.ref.decl;
    const std::size_t at = end_of_line(src_.text, t[d.end_tok].end);
    const std::string lead = at == src_.text.size() && !src_.text.empty() && src_.text.back() != '\n' ? eol : "";
    const std::string indent = indentation_of(src_.text, t[d.first_tok].begin);
    const std::string prefix = src_.text.substr(t[d.first_tok].begin, t[d.name_tok].begin - t[d.first_tok].begin);
    const std::string base = x.ref.element >= 0 ? fmt::format("{}{}", d.name, x.ref.element + 1) : d.name;
    int k = 1;
    std::vector<std::pair<std::size_t, std::string>> made;  // a use that got a copy, and the copy's name
    for (const std::size_t b : group) {
      const Use& y = info[b];
      // Uses that need the same values share one copy.
      const auto same = std::find_if(made.begin(), made.end(), [&](const auto& m) {
        for (std::size_t n = 0; n < y.numbers.size(); ++n) {
          if (info[m.first].numbers[n].second != y.numbers[n].second) {
            return false;
          }
        }
        return true;
      });
      if (same != made.end()) {
        edits.push_back({t[y.ref.ref_b].begin, t[y.ref.ref_e - 1].end - t[y.ref.ref_b].begin, same->second});
        actions[b] = "copy " + same->second;
        continue;
      }
      const std::string name = valid_identifier(base, k++, taken);
      taken.insert(to_upper(name));
      made.emplace_back(b, name);
      const Value& v = *y.ref.value;
      std::vector<TextEdit> rel;
      for (const auto& [node, text] : y.numbers) {
        rel.push_back({node->begin - v.begin, node->end - node->begin, text});
      }
      const std::string value = apply_edits(src_.text.substr(v.begin, v.end - v.begin), rel);
      edits.push_back({at, 0, lead + indent + prefix + name + ":=" + value + ";" + eol});
      edits.push_back({t[y.ref.ref_b].begin, t[y.ref.ref_e - 1].end - t[y.ref.ref_b].begin, name});
      actions[b] = "copy " + name;
    }
  }

  for (std::size_t a = 0; a < info.size(); ++a) {
    const Use& x = info[a];
    result.targets.push_back(
        target_report(results[x.use_index], src_.file, x.line, x.instruction, x.written, actions[a]));
  }
  result.outputs.push_back({output_path, apply_edits(src_.text, edits)});
  return result;
}

}  // namespace

ProgramCompensation compensate_rapid_module(const RobotModel& model, const ForceModel& force, const std::string& file,
                                            const std::string& text, const std::string& output_path,
                                            const ProgramOptions& options) {
  RapidReader reader(model, force, file, text, options);
  return reader.run(output_path);
}

}  // namespace deflex
