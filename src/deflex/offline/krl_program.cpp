// KRL program reader and compensated writer. KRL is line-oriented: one statement a line, so the
// reader works line by line on tokens that keep their byte ranges.
#include "deflex/offline/krl_program.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"
#include "deflex/offline/program_targets.hpp"
#include "deflex/offline/program_text.hpp"
#include "deflex/offline/program_tokens.hpp"

namespace deflex {
namespace {

using Tokens = std::vector<Token>;
using Range = std::pair<std::size_t, std::size_t>;  // tokens [first, last)

struct KrlFile {
  std::string file;
  const std::string& text;
  Tokens tok;
  std::vector<Range> lines;  // the tokens of each non-empty line

  KrlFile(std::string f, const std::string& t) : file(std::move(f)), text(t), tok(lex_krl(t, file)) {
    for (std::size_t i = 0; i < tok.size();) {
      std::size_t j = i;
      while (j < tok.size() && tok[j].line == tok[i].line) {
        ++j;
      }
      lines.emplace_back(i, j);
      i = j;
    }
  }
  [[nodiscard]] std::string str(std::size_t i) const {
    return i < tok.size() ? text.substr(tok[i].begin, tok[i].end - tok[i].begin) : std::string();
  }
  [[nodiscard]] bool is_ident(std::size_t i, const char* word = nullptr) const {
    return i < tok.size() && tok[i].kind == TokenKind::kIdentifier && (word == nullptr || iequals(str(i), word));
  }
  [[nodiscard]] bool is_punct(std::size_t i, const char* p) const {
    return i < tok.size() && tok[i].kind == TokenKind::kPunct && str(i) == p;
  }
  [[nodiscard]] std::string span(std::size_t b, std::size_t e) const {
    if (b >= e) {
      return {};
    }
    std::string s = text.substr(tok[b].begin, tok[e - 1].end - tok[b].begin);
    return s.size() > 100 ? s.substr(0, 97) + "..." : s;
  }
  [[noreturn]] void fail(std::size_t i, const std::string& what) const {
    throw DataError(fmt::format("{}:{}: {}", file, i < tok.size() ? tok[i].line : 0, what));
  }
};

/// One component of an aggregate {NAME value, ...}.
struct Component {
  std::string name;  // upper case
  enum class Kind { kNumber, kBits, kOther } kind = Kind::kOther;
  double number = 0.0;
  std::size_t begin = 0, end = 0;  // bytes of the value, a sign included
  int bit_digits = 0;              // 'B0110': 4
};

struct Aggregate {
  std::vector<Component> comps;
  std::size_t begin = 0, end = 0;  // bytes, braces included
  [[nodiscard]] const Component* find(const char* name) const {
    for (const Component& c : comps) {
      if (c.name == name) {
        return &c;
      }
    }
    return nullptr;
  }
  [[nodiscard]] bool numbers(std::initializer_list<const char*> names) const {
    return std::all_of(names.begin(), names.end(), [&](const char* n) {
      const Component* c = find(n);
      return c != nullptr && c->kind != Component::Kind::kOther;
    });
  }
};

/// {[TYPE:] NAME value, ...} at token i; the index after it, or nullopt when not a literal aggregate.
std::optional<std::size_t> parse_aggregate(const KrlFile& f, std::size_t i, std::size_t end, Aggregate& a) {
  if (!f.is_punct(i, "{")) {
    return std::nullopt;
  }
  a.begin = f.tok[i].begin;
  ++i;
  if (f.is_ident(i) && f.is_punct(i + 1, ":")) {
    i += 2;  // a typed aggregate {E6POS: X ...}
  }
  while (i < end) {
    if (f.is_punct(i, "}")) {
      a.end = f.tok[i].end;
      return i + 1;
    }
    if (!f.is_ident(i)) {
      return std::nullopt;
    }
    Component c;
    c.name = to_upper(f.str(i));
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
      c.kind = Component::Kind::kNumber;
      c.number = sign * token_number(f, i);
      ++i;
    } else if (v.kind == TokenKind::kBitLiteral) {
      const std::string s = f.str(i);  // 'B0110' or 'H1F'
      const char base = static_cast<char>(std::toupper(static_cast<unsigned char>(s.size() > 1 ? s[1] : ' ')));
      if (base != 'B' && base != 'H') {
        return std::nullopt;
      }
      c.kind = Component::Kind::kBits;
      c.bit_digits = base == 'B' ? static_cast<int>(s.size()) - 3 : 0;
      const std::string digits = s.size() >= 3 ? s.substr(2, s.size() - 3) : std::string();
      long bits = 0;
      const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), bits, base == 'B' ? 2 : 16);
      if (digits.empty() || r.ec != std::errc() || r.ptr != digits.data() + digits.size()) {
        f.fail(i, fmt::format("{} is not a KRL bit literal ('B0110' or 'H1F')", s));
      }
      c.number = static_cast<double>(bits);
      ++i;
    } else if (v.kind == TokenKind::kPunct && f.is_punct(i, "{")) {
      Aggregate inner;
      const auto next = parse_aggregate(f, i, end, inner);
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

/// KRL frame {X, Y, Z (mm), A, B, C (deg)}: R = Rz(A) Ry(B) Rx(C).
Pose frame_of(const Aggregate& a) {
  const auto v = [&](const char* n) {
    const Component* c = a.find(n);
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

double wrap_deg(double a) { return std::remainder(a, 360.0); }

/// A, B, C (deg) of a rotation, of the two Euler triples the one nearest `near`.
Vector3 abc_of(const Matrix3& R, const Vector3& near) {
  const double b = std::atan2(-R(2, 0), std::hypot(R(0, 0), R(1, 0)));
  const double a = std::atan2(R(1, 0), R(0, 0));
  const double c = std::atan2(R(2, 1), R(2, 2));
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

std::string bits_text(int value, int digits) {
  std::string s;
  for (int v = value; v > 0; v /= 2) {
    s.insert(s.begin(), static_cast<char>('0' + v % 2));
  }
  while (static_cast<int>(s.size()) < std::max(digits, 1)) {
    s.insert(s.begin(), '0');
  }
  return "'B" + s + "'";
}

struct KrlDecl {
  std::string type;  // upper
  std::string name;
  int element = 0;  // 1-based element of an array, 0 for a scalar
  std::size_t name_tok = 0;
  std::size_t first_tok = 0;  // the line's first token
  std::size_t agg_tok = 0;
  bool literal = false;
  Aggregate value;
};

bool cartesian_type(const std::string& t) { return t == "E6POS" || t == "POS" || t == "FRAME"; }
bool axis_type(const std::string& t) { return t == "E6AXIS" || t == "AXIS"; }

struct FrameState {
  enum class Kind { kUnset, kNamed, kLiteral, kUnknown } kind = Kind::kUnset;
  std::string name;  // TOOL_DATA[1], ...
  Pose frame = Pose::Identity();
  std::string why;
};

struct Use {
  const KrlDecl* decl = nullptr;  // null: an inline aggregate in the .src
  const Aggregate* value = nullptr;
  std::size_t ref_b = 0, ref_e = 0;  // .src tokens of the reference
  bool joint = false;
  Pose base_frame = Pose::Identity();
  std::size_t use_index = 0;
  std::string instruction;
  std::string written;
  int line = 0;
  std::vector<std::pair<const Component*, std::string>> numbers;
};

class KrlReader {
 public:
  KrlReader(const RobotModel& model, const ForceModel& force, const std::string& src_file, const std::string& src_text,
            const std::string& dat_file, const std::string& dat_text, const ProgramOptions& options)
      : model_(model), force_(force), src_(src_file, src_text), dat_(dat_file, dat_text) {
    read_frames(options.tooldata, "--tooldata");
    read_frames(options.wobjdata, "--wobjdata");
    read_data();
    read_references();
  }

  ProgramCompensation run(const std::string& output_src);

 private:
  void read_frames(const std::vector<std::string>& specs, const char* option) {
    for (const std::string& spec : specs) {
      const auto eq = spec.find('=');
      const std::string where = fmt::format("option {} '{}'", option, spec);
      if (eq == std::string::npos || eq == 0) {
        throw InputError(fmt::format("{}: give NAME={{X ..,Y ..,Z ..,A ..,B ..,C ..}} (mm, deg)", where));
      }
      std::string name;
      for (char c : spec.substr(0, eq)) {
        if (c != ' ') {
          name += c;
        }
      }
      const std::string value = spec.substr(eq + 1);
      try {
        const KrlFile f(where, value);
        Aggregate a;
        const auto end = parse_aggregate(f, 0, f.tok.size(), a);
        if (!end || *end != f.tok.size() || !a.numbers({"X", "Y", "Z", "A", "B", "C"})) {
          throw InputError(fmt::format("{}: the value is not a frame {{X ..,Y ..,Z ..,A ..,B ..,C ..}}", where));
        }
        frames_[to_upper(name)] = frame_of(a);
      } catch (const DataError& e) {
        throw InputError(e.what());
      }
    }
  }

  void read_data() {
    const KrlFile& f = dat_;
    std::map<std::string, std::string> array_type;
    for (const auto& [b, e] : f.lines) {
      std::size_t i = b;
      bool decl = false;
      while (i < e && (f.is_ident(i, "DECL") || f.is_ident(i, "GLOBAL"))) {
        decl = true;
        ++i;
      }
      KrlDecl d;
      d.first_tok = b;
      if (f.is_ident(i) && f.is_ident(i + 1)) {  // TYPE NAME ...
        d.type = to_upper(f.str(i));
        d.name_tok = i + 1;
        d.name = f.str(i + 1);
        i += 2;
        if (f.is_punct(i, "[")) {  // an array declaration: its elements come on later lines
          array_type[to_upper(d.name)] = d.type;
          decl_name_tokens_.insert(d.name_tok);
          continue;
        }
      } else if (!decl && f.is_ident(i) && f.is_punct(i + 1, "[") && i + 2 < e &&
                 f.tok[i + 2].kind == TokenKind::kNumber && f.is_punct(i + 3, "]")) {  // NAME[i]=...
        const auto t = array_type.find(to_upper(f.str(i)));
        if (t == array_type.end()) {
          continue;
        }
        d.type = t->second;
        d.name_tok = i;
        d.name = f.str(i);
        d.element = token_index(f, i + 2);
        i += 4;
      } else {
        continue;
      }
      if (!f.is_punct(i, "=")) {
        continue;
      }
      d.agg_tok = i + 1;
      const auto end = parse_aggregate(f, i + 1, e, d.value);
      d.literal = end && *end == e;
      decls_.push_back(d);
    }
    for (std::size_t n = 0; n < decls_.size(); ++n) {
      const KrlDecl& d = decls_[n];
      const std::string key = to_upper(d.name) + (d.element > 0 ? fmt::format("[{}]", d.element) : "");
      by_key_[key].push_back(n);
      decl_name_tokens_.insert(d.name_tok);
    }
  }

  void read_references() {
    for (const KrlFile* f : {&src_, &dat_}) {
      for (std::size_t i = 0; i < f->tok.size(); ++i) {
        if (f->tok[i].kind != TokenKind::kIdentifier || (f == &dat_ && decl_name_tokens_.count(i) != 0)) {
          continue;
        }
        if (i > 0 && f->is_punct(i - 1, ".")) {
          continue;
        }
        const std::string key = to_upper(f->str(i));
        ++references_[key];
        if (f == &src_) {
          std::size_t j = i + 1;
          if (f->is_punct(j, "[")) {
            while (j < f->tok.size() && !f->is_punct(j, "]")) {
              ++j;
            }
            ++j;
          }
          while (f->is_punct(j, ".") && f->is_ident(j + 1)) {
            j += 2;
          }
          const bool starts_line = i == 0 || f->tok[i - 1].line != f->tok[i].line;
          if (starts_line && f->is_punct(j, "=")) {
            assigned_.insert(key);
          }
        }
      }
    }
  }

  /// The point a name (NAME or NAME[i]) declares in the .dat; null with `why` otherwise.
  const KrlDecl* find_point(const std::string& key, const std::string& name, std::string& why) const {
    const auto it = by_key_.find(key);
    if (it == by_key_.end()) {
      why = fmt::format("'{}' is not declared in {}", name, dat_.file);
      return nullptr;
    }
    if (it->second.size() > 1) {
      why = fmt::format("'{}' is declared {} times", name, it->second.size());
      return nullptr;
    }
    const KrlDecl& d = decls_[it->second.front()];
    const std::string base = to_upper(d.name);
    if (assigned_.count(base) != 0) {
      why = fmt::format("'{}' is assigned while the program runs", d.name);
      return nullptr;
    }
    if (!d.literal) {
      why = fmt::format("the value of '{}' is not a literal aggregate", name);
      return nullptr;
    }
    return &d;
  }

  /// The frame a $TOOL/$BASE state stands for at a motion; throws for a name given nowhere.
  std::optional<Pose> frame(const FrameState& s, const char* variable, const char* option, std::size_t at,
                            std::string& why) const {
    switch (s.kind) {
      case FrameState::Kind::kLiteral:
        return s.frame;
      case FrameState::Kind::kUnknown:
        why = s.why;
        return std::nullopt;
      case FrameState::Kind::kNamed: {
        const auto it = frames_.find(s.name);
        if (it == frames_.end()) {
          src_.fail(at, fmt::format("{} is {} here, which is not in the program: give it with {} \"{}={{X ..,Y ..,Z "
                                    "..,A ..,B ..,C ..}}\" (mm, deg)",
                                    variable, s.name, option, s.name));
        }
        return it->second;
      }
      case FrameState::Kind::kUnset:
        break;
    }
    src_.fail(at, fmt::format("no {} is set before this motion: set it in the program or give it with {} "
                              "\"{}={{X ..,Y ..,Z ..,A ..,B ..,C ..}}\"",
                              variable, option, variable));
  }

  /// $TOOL/$BASE := tokens [b, e).
  FrameState assigned_frame(std::size_t b, std::size_t e, const char* table) const {
    FrameState s;
    if (e == b + 1 && src_.is_ident(b, "$NULLFRAME")) {
      s.kind = FrameState::Kind::kLiteral;
      return s;
    }
    if (e == b + 4 && src_.is_ident(b, table) && src_.is_punct(b + 1, "[") &&
        src_.tok[b + 2].kind == TokenKind::kNumber && src_.is_punct(b + 3, "]")) {
      s.kind = FrameState::Kind::kNamed;
      s.name = fmt::format("{}[{}]", table, token_index(src_, b + 2));
      return s;
    }
    Aggregate a;
    const auto end = parse_aggregate(src_, b, e, a);
    if (end && *end == e && a.numbers({"X", "Y", "Z", "A", "B", "C"})) {
      s.kind = FrameState::Kind::kLiteral;
      s.frame = frame_of(a);
      return s;
    }
    // A FRAME the program's .dat declares (and nothing assigns).
    if (e == b + 1 && src_.is_ident(b)) {
      std::string why;
      const KrlDecl* d = find_point(to_upper(src_.str(b)), src_.str(b), why);
      if (d != nullptr && d->value.numbers({"X", "Y", "Z", "A", "B", "C"})) {
        s.kind = FrameState::Kind::kLiteral;
        s.frame = frame_of(d->value);
        return s;
      }
    }
    s.kind = FrameState::Kind::kUnknown;
    s.why = fmt::format("set from an expression on line {} ({})", src_.tok[b].line, src_.span(b, e));
    return s;
  }

  FrameState numbered(const char* table, int n) const {
    FrameState s;
    if (n == 0) {
      s.kind = FrameState::Kind::kLiteral;  // tool 0 is the flange, base 0 the world
      return s;
    }
    s.kind = FrameState::Kind::kNamed;
    s.name = fmt::format("{}[{}]", table, n);
    return s;
  }

  const RobotModel& model_;
  const ForceModel& force_;
  KrlFile src_;
  KrlFile dat_;
  std::vector<KrlDecl> decls_;
  std::map<std::string, std::vector<std::size_t>> by_key_;
  std::set<std::size_t> decl_name_tokens_;
  std::map<std::string, int> references_;
  std::set<std::string> assigned_;
  std::map<std::string, Pose> frames_;
  std::vector<std::unique_ptr<Aggregate>> inlines_;  // inline targets, at stable addresses
};

const char* const kApproximation[] = {"C_PTP", "C_DIS", "C_VEL", "C_ORI", "C_SPL"};
const char* const kUnsupported[] = {"PTP_REL", "LIN_REL",  "CIRC_REL", "SPTP",      "SLIN",       "SCIRC",
                                    "SPL",     "SLIN_REL", "SPTP_REL", "SCIRC_REL", "PTP_SPLINE", "SPLINE"};

ProgramCompensation KrlReader::run(const std::string& output_src) {
  ProgramCompensation result;
  result.language = "KRL";
  result.force_description = force_.describe();
  FrameState tool;
  FrameState base;
  if (frames_.count("$TOOL") != 0) {
    tool.kind = FrameState::Kind::kLiteral;
    tool.frame = frames_.at("$TOOL");
  }
  if (frames_.count("$BASE") != 0) {
    base.kind = FrameState::Kind::kLiteral;
    base.frame = frames_.at("$BASE");
  }
  std::vector<ProgramTargetUse> uses;
  std::vector<Use> info;
  std::size_t force_index = 0;
  const KrlFile& f = src_;
  for (const auto& [b, e] : f.lines) {
    const std::string first = to_upper(f.str(b));
    if ((first == "$TOOL" || first == "$BASE") && f.is_punct(b + 1, "=")) {
      (first == "$TOOL" ? tool : base) = assigned_frame(b + 2, e, first == "$TOOL" ? "TOOL_DATA" : "BASE_DATA");
      continue;
    }
    if (first == "FDAT_ACT" && f.is_punct(b + 1, "=") && e == b + 3) {
      std::string why;
      const KrlDecl* d = nullptr;
      const auto it = by_key_.find(to_upper(f.str(b + 2)));
      if (it != by_key_.end() && it->second.size() == 1 && decls_[it->second.front()].type == "FDAT") {
        d = &decls_[it->second.front()];
      }
      const Component* t = d != nullptr ? d->value.find("TOOL_NO") : nullptr;
      const Component* bn = d != nullptr ? d->value.find("BASE_NO") : nullptr;
      const Component* ipo = d != nullptr ? d->value.find("IPO_FRAME") : nullptr;
      if (t == nullptr || bn == nullptr || t->kind != Component::Kind::kNumber ||
          bn->kind != Component::Kind::kNumber) {
        tool.kind = base.kind = FrameState::Kind::kUnknown;
        tool.why = base.why = fmt::format("FDAT_ACT = {} on line {}: no literal FDAT with TOOL_NO and BASE_NO in {}",
                                          f.str(b + 2), f.tok[b].line, dat_.file);
        continue;
      }
      tool = numbered("TOOL_DATA", static_cast<int>(t->number));
      base = numbered("BASE_DATA", static_cast<int>(bn->number));
      if (ipo != nullptr && iequals(dat_.text.substr(ipo->begin, ipo->end - ipo->begin), "#TCP")) {
        tool.kind = FrameState::Kind::kUnknown;
        tool.why = fmt::format("{} on line {} has IPO_FRAME #TCP (a stationary tool): not supported", f.str(b + 2),
                               f.tok[b].line);
      }
      continue;
    }
    if (first == "BAS" && f.is_punct(b + 1, "(") && b + 5 < e && f.tok[b + 2].kind == TokenKind::kEnum &&
        f.is_punct(b + 3, ",") && f.tok[b + 4].kind == TokenKind::kNumber) {
      const std::string what = to_upper(f.str(b + 2));
      const int n = token_index(f, b + 4);
      if (what == "#TOOL") {
        tool = numbered("TOOL_DATA", n);
      } else if (what == "#BASE") {
        base = numbered("BASE_DATA", n);
      }
      continue;
    }
    if (std::any_of(std::begin(kUnsupported), std::end(kUnsupported), [&](const char* k) { return first == k; })) {
      result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e),
                                   fmt::format("{} is not compensated by deflex (PTP, LIN and CIRC are)", first)});
      continue;
    }
    if (first != "PTP" && first != "LIN" && first != "CIRC") {
      continue;
    }
    // Arguments: split at depth-0 commas; the last one may end with approximation keywords.
    std::vector<Range> pieces;
    int depth = 0;
    std::size_t start = b + 1;
    for (std::size_t i = b + 1; i < e; ++i) {
      depth += (f.is_punct(i, "{") || f.is_punct(i, "[") || f.is_punct(i, "(")) ? 1 : 0;
      depth -= (f.is_punct(i, "}") || f.is_punct(i, "]") || f.is_punct(i, ")")) ? 1 : 0;
      if (depth == 0 && f.is_punct(i, ",")) {
        pieces.emplace_back(start, i);
        start = i + 1;
      }
    }
    pieces.emplace_back(start, e);
    while (pieces.back().second > pieces.back().first) {
      const std::size_t last = pieces.back().second - 1;
      if (!std::any_of(std::begin(kApproximation), std::end(kApproximation),
                       [&](const char* k) { return f.is_ident(last, k); })) {
        break;
      }
      --pieces.back().second;
    }
    const bool circ = first == "CIRC";
    if (circ && pieces.size() == 3 && f.is_ident(pieces[2].first, "CA")) {
      pieces.pop_back();  // CIRC's angle: the targets are what counts here
    }
    const std::size_t wanted = circ ? 2 : 1;
    if (pieces.size() != wanted) {
      f.fail(b, fmt::format("{}: {} target{} expected, then only {}{}", first, wanted, circ ? "s" : "",
                            circ ? "', CA angle' and " : "", "C_PTP, C_DIS, C_VEL, C_ORI or C_SPL"));
    }
    for (std::size_t k = 0; k < wanted; ++k) {
      const auto [tb, te] = pieces[k];
      const std::size_t index = force_index++;
      const std::string written = f.span(tb, te);
      if (tb == te) {
        f.fail(b, fmt::format("{}: a target is missing", first));
      }
      // The target: NAME, NAME[i] or an inline aggregate; anything after it is an unknown keyword.
      std::size_t after = tb + 1;
      std::string key;
      const Aggregate* value = nullptr;
      const KrlDecl* decl = nullptr;
      Aggregate inline_value;
      std::string why;
      if (f.is_punct(tb, "{")) {
        const auto end = parse_aggregate(f, tb, te, inline_value);
        if (!end) {
          result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e), "the inline target is not a literal"});
          continue;
        }
        after = *end;
      } else if (f.is_ident(tb)) {
        key = to_upper(f.str(tb));
        if (f.is_punct(tb + 1, "[") && tb + 3 < te && f.tok[tb + 2].kind == TokenKind::kNumber &&
            f.is_punct(tb + 3, "]")) {
          key += fmt::format("[{}]", token_index(f, tb + 2));
          after = tb + 4;
        }
      } else {
        f.fail(tb, fmt::format("{}: '{}' is not a target", first, f.str(tb)));
      }
      if (after != te) {
        if (f.is_ident(after)) {
          f.fail(after, fmt::format("{}: unknown '{}' in the motion (after the target only C_PTP, C_DIS, C_VEL, "
                                    "C_ORI or C_SPL may follow)",
                                    first, f.str(after)));
        }
        result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e), "the target is computed at run time"});
        continue;
      }
      if (key.empty()) {
        inlines_.push_back(std::make_unique<Aggregate>(inline_value));
        value = inlines_.back().get();
      } else {
        decl = find_point(key, written, why);
        if (decl == nullptr) {
          result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e), why});
          continue;
        }
        value = &decl->value;
      }
      const bool joint = value->find("A1") != nullptr;
      const bool cartesian = value->find("X") != nullptr;
      if (decl != nullptr && !(cartesian_type(decl->type) || axis_type(decl->type))) {
        result.unresolved.push_back(
            {f.file, f.tok[b].line, f.span(b, e), fmt::format("'{}' is a {}, not a point", written, decl->type)});
        continue;
      }
      if (joint ? !value->numbers({"A1", "A2", "A3", "A4", "A5", "A6"})
                : !(cartesian && value->numbers({"X", "Y", "Z", "A", "B", "C"}))) {
        result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e), "the target's components are not all given"});
        continue;
      }
      if (joint && first != "PTP") {
        f.fail(tb, fmt::format("{} to an axis target: KRL moves to axis targets with PTP only", first));
      }
      const auto tool_frame = frame(tool, "$TOOL", "--tooldata", b, why);
      const auto base_frame = tool_frame ? frame(base, "$BASE", "--wobjdata", b, why) : std::nullopt;
      if (!tool_frame || !base_frame) {
        result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e), why});
        continue;
      }
      ProgramTargetUse u;
      u.file = f.file;
      u.line = f.tok[b].line;
      u.instruction = first;
      u.target = written;
      u.joint = joint;
      u.flange_T_tcp = *tool_frame;
      u.force_index = index;
      if (joint) {
        if (model_.dof() != 6) {
          f.fail(tb, fmt::format("{}: an axis target has six axes, the robot {}", first, model_.dof()));
        }
        u.q.resize(6);
        const char* const axes[6] = {"A1", "A2", "A3", "A4", "A5", "A6"};
        for (int j = 0; j < 6; ++j) {
          u.q[j] = deg_to_rad(value->find(axes[j])->number);
        }
      } else {
        u.base_T_tcp = *base_frame * frame_of(*value);
        const Component* s = value->find("S");
        const Component* t = value->find("T");
        if (s != nullptr && t != nullptr && s->kind != Component::Kind::kOther && t->kind != Component::Kind::kOther) {
          u.ik.kuka_configuration =
              KukaConfiguration{static_cast<int>(s->number) & 7, static_cast<int>(t->number) & 63};
        } else if (uses.empty()) {
          result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e),
                                       "no Status and Turn, and no earlier target to take the configuration from"});
          continue;
        } else {
          u.continue_from_previous = true;
        }
      }
      Use x;
      x.decl = decl;
      x.value = value;
      x.ref_b = tb;
      x.ref_e = te;
      x.joint = joint;
      x.base_frame = *base_frame;
      x.use_index = uses.size();
      x.instruction = first;
      x.written = written;
      x.line = f.tok[b].line;
      info.push_back(x);
      uses.push_back(u);
    }
  }

  const std::vector<ProgramTargetResult> results = compensate_program_targets(model_, uses, force_);

  for (Use& x : info) {
    const ProgramTargetResult& r = results[x.use_index];
    const Aggregate& v = *x.value;
    if (x.joint) {
      const char* const axes[6] = {"A1", "A2", "A3", "A4", "A5", "A6"};
      for (int j = 0; j < 6; ++j) {
        x.numbers.emplace_back(v.find(axes[j]), program_number(rad_to_deg(r.q_command[j]), 4));
      }
      continue;
    }
    const Pose in_base = x.base_frame.inverse() * r.tcp_command;
    const Vector3 p = in_base.translation() * 1e3;
    const Vector3 abc =
        abc_of(in_base.linear(), Vector3(v.find("A")->number, v.find("B")->number, v.find("C")->number));
    const char* const names[6] = {"X", "Y", "Z", "A", "B", "C"};
    for (int j = 0; j < 6; ++j) {
      x.numbers.emplace_back(v.find(names[j]), program_number(j < 3 ? p[j] : abc[j - 3], 4));
    }
    for (const auto& [name, value] : {std::pair{"S", r.kuka.status}, std::pair{"T", r.kuka.turn}}) {
      const Component* c = v.find(name);
      if (c != nullptr && c->kind != Component::Kind::kOther) {
        x.numbers.emplace_back(
            c, c->kind == Component::Kind::kBits ? bits_text(value, c->bit_digits) : std::to_string(value));
      }
    }
  }

  // Write back, as for RAPID: inline targets and agreeing, otherwise unreferenced points in place;
  // a copy per use otherwise.
  std::vector<TextEdit> src_edits;
  std::vector<TextEdit> dat_edits;
  std::set<std::string> taken;
  for (const KrlFile* file : {&src_, &dat_}) {
    for (const Token& tk : file->tok) {
      if (tk.kind == TokenKind::kIdentifier) {
        taken.insert(to_upper(file->text.substr(tk.begin, tk.end - tk.begin)));
      }
    }
  }
  std::map<std::string, int> resolved_refs;
  for (const Use& x : info) {
    if (x.decl != nullptr) {
      ++resolved_refs[to_upper(x.decl->name)];
    }
  }
  const std::string eol = line_terminator(dat_.text.empty() ? src_.text : dat_.text);
  std::vector<std::string> actions(info.size());
  std::set<std::size_t> done;
  for (std::size_t a = 0; a < info.size(); ++a) {
    const Use& x = info[a];
    if (x.decl == nullptr) {
      for (const auto& [c, text] : x.numbers) {
        src_edits.push_back({c->begin, c->end - c->begin, text});
      }
      actions[a] = "literal edited";
      continue;
    }
    if (done.count(a) != 0) {
      continue;
    }
    std::vector<std::size_t> group;
    for (std::size_t b = a; b < info.size(); ++b) {
      if (info[b].decl == x.decl) {
        group.push_back(b);
        done.insert(b);
      }
    }
    const std::string key = to_upper(x.decl->name);
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
      for (const auto& [c, text] : x.numbers) {
        dat_edits.push_back({c->begin, c->end - c->begin, text});
      }
      for (const std::size_t b : group) {
        actions[b] = "edited in place";
      }
      continue;
    }
    const KrlDecl& d = *x.decl;
    const std::size_t line_begin =
        dat_.tok[d.first_tok].begin - indentation_of(dat_.text, dat_.tok[d.first_tok].begin).size();
    const std::size_t at = end_of_line(dat_.text, dat_.tok[d.name_tok].begin);
    const std::string lead = at == dat_.text.size() && !dat_.text.empty() && dat_.text.back() != '\n' ? eol : "";
    const std::string base_name = d.element > 0 ? fmt::format("{}{}", d.name, d.element) : d.name;
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
        src_edits.push_back({f.tok[y.ref_b].begin, f.tok[y.ref_e - 1].end - f.tok[y.ref_b].begin, same->second});
        actions[b] = "copy " + same->second;
        continue;
      }
      std::string name;
      for (;; ++k) {
        const std::string suffix = fmt::format("_C{}", k);
        name = base_name.substr(0, std::min(base_name.size(), 24 - suffix.size())) + suffix;
        if (taken.count(to_upper(name)) == 0) {
          break;
        }
      }
      taken.insert(to_upper(name));
      made.emplace_back(b, name);
      std::string line;
      if (d.element == 0) {
        // The declaration's line, renamed, with the new numbers.
        std::string text = dat_.text.substr(line_begin, at - line_begin);
        std::vector<TextEdit> rel{
            {dat_.tok[d.name_tok].begin - line_begin, dat_.tok[d.name_tok].end - dat_.tok[d.name_tok].begin, name}};
        for (const auto& [c, value] : y.numbers) {
          rel.push_back({c->begin - line_begin, c->end - c->begin, value});
        }
        line = apply_edits(text, rel);
        if (line.empty() || line.back() != '\n') {
          line += eol;
        }
      } else {
        std::vector<TextEdit> rel;
        for (const auto& [c, value] : y.numbers) {
          rel.push_back({c->begin - d.value.begin, c->end - c->begin, value});
        }
        line = indentation_of(dat_.text, dat_.tok[d.first_tok].begin) + "DECL " + d.type + " " + name + "=" +
               apply_edits(dat_.text.substr(d.value.begin, d.value.end - d.value.begin), rel) + eol;
      }
      dat_edits.push_back({at, 0, lead + line});
      src_edits.push_back({f.tok[y.ref_b].begin, f.tok[y.ref_e - 1].end - f.tok[y.ref_b].begin, name});
      actions[b] = "copy " + name;
    }
  }

  for (std::size_t a = 0; a < info.size(); ++a) {
    const Use& x = info[a];
    result.targets.push_back(
        target_report(results[x.use_index], src_.file, x.line, x.instruction, x.written, actions[a]));
  }
  result.outputs.push_back({output_src, apply_edits(src_.text, src_edits)});
  if (!dat_.file.empty()) {
    result.outputs.push_back(
        {std::filesystem::path(output_src).replace_extension(".dat").string(), apply_edits(dat_.text, dat_edits)});
  }
  return result;
}

}  // namespace

ProgramCompensation compensate_krl_program(const RobotModel& model, const ForceModel& force,
                                           const std::string& src_file, const std::string& src_text,
                                           const std::string& dat_file, const std::string& dat_text,
                                           const std::string& output_src, const ProgramOptions& options) {
  KrlReader reader(model, force, src_file, src_text, dat_file, dat_text, options);
  return reader.run(output_src);
}

}  // namespace deflex
