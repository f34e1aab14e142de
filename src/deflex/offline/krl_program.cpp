// KRL program reader and compensated writer. KRL is line-oriented: one statement a line, so the
// reader works line by line on tokens that keep their byte ranges (krl_aggregate.hpp). It is as
// strict as the controller loading the program: a malformed or repeated declaration in the .dat,
// a point component that is not a number, a declared point missing a component, a motion to a point
// of another type stop it with the file, the line and the name. Only points whose value is known
// only when the program runs (or that live in $config.dat, or motions deflex does not compensate)
// are listed and left unchanged.
#include "deflex/offline/detail/krl_program.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include <fmt/format.h>

#include "deflex/offline/detail/krl_aggregate.hpp"
#include "deflex/offline/detail/program_targets.hpp"
#include "deflex/offline/detail/program_text.hpp"
#include "deflex/offline/detail/program_write_back.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

using Range = KrlRange;

struct KrlDecl {
  std::string type;  // upper
  std::string name;
  int element = 0;  // 1-based element of an array, 0 for a scalar
  std::size_t name_tok = 0;
  std::size_t first_tok = 0;  // the line's first token
  bool literal = false;
  KrlAggregate value;
};

struct FrameState {
  enum class Kind { kUnset, kNamed, kLiteral, kUnknown } kind = Kind::kUnset;
  std::string name;  // TOOL_DATA[1], ...
  Pose frame = Pose::Identity();
  std::string why;
};

struct KrlUse {
  const KrlDecl* decl = nullptr;  // null: an inline aggregate in the .src
  const KrlAggregate* value = nullptr;
  std::size_t ref_b = 0, ref_e = 0;  // .src tokens of the reference
  bool joint = false;
  Pose base_frame = Pose::Identity();
  std::size_t use_index = 0;
  std::string instruction;
  std::string written;
  int line = 0;
  std::vector<std::pair<const KrlComponent*, std::string>> numbers;
};

const char* const kApproximation[] = {"C_PTP", "C_DIS", "C_VEL", "C_ORI", "C_SPL"};
const char* const kUnsupported[] = {"PTP_REL", "LIN_REL",  "CIRC_REL", "SPTP",      "SLIN",       "SCIRC",
                                    "SPL",     "SLIN_REL", "SPTP_REL", "SCIRC_REL", "PTP_SPLINE", "SPLINE"};
const char* const kAxes[6] = {"A1", "A2", "A3", "A4", "A5", "A6"};
const char* const kFrameNames[6] = {"X", "Y", "Z", "A", "B", "C"};
const char* const kBuiltinTypes[] = {"INT", "REAL", "BOOL", "CHAR", "FRAME", "POS", "E6POS", "AXIS", "E6AXIS"};

/// Fails unless the file holds `begin` ... `end` (DEF ... END, DEFDAT ... ENDDAT).
void check_frame(const KrlFile& f, const char* what, std::initializer_list<const char*> begin, const char* end) {
  if (f.tok.empty()) {
    throw DataError(fmt::format("{}: the {} is empty", f.file, what));
  }
  bool has_begin = false;
  bool has_end = false;
  for (std::size_t i = 0; i < f.tok.size(); ++i) {
    has_begin = has_begin || std::any_of(begin.begin(), begin.end(), [&](const char* b) { return f.is_ident(i, b); });
    has_end = has_end || f.is_ident(i, end);
  }
  if (!has_begin || !has_end) {
    f.fail(0, fmt::format("no {} ... {}: not a KRL {}", *begin.begin(), end, what));
  }
}

class KrlReader {
 public:
  KrlReader(const RobotModel& model, const ForceModel& force, const std::string& src_file, const std::string& src_text,
            const std::string& dat_file, const std::string& dat_text, const ProgramOptions& options)
      : model_(model), force_(force), src_(src_file, src_text), dat_(dat_file, dat_text), start_q_(options.start_q) {
    if (dat_file.empty()) {
      throw InputError(fmt::format("{}: a KRL program needs its .dat (the data list beside it)", src_file));
    }
    check_frame(src_, "program", {"DEF", "DEFFCT"}, "END");
    check_frame(dat_, "data list", {"DEFDAT"}, "ENDDAT");
    check_declaration_sections();
    read_frames(options.tooldata, "--tooldata");
    read_frames(options.wobjdata, "--wobjdata");
    read_data();
    read_references();
  }

  ProgramCompensation run(const std::string& output_src);

 private:
  // --- reading ---------------------------------------------------------------------------------

  /// Where the controller takes declarations: in a DEF (or DEFFCT) before its first statement, and in
  /// the data list between DEFDAT and ENDDAT. It refuses to load a program with a declaration after a
  /// statement or outside DEFDAT ... ENDDAT, and so does deflex, naming the line.
  void check_declaration_sections() const {
    int first_statement = 0;  // the line of the current DEF's first statement, 0 before it
    for (const auto& [b, e] : src_.lines) {
      const std::string first = to_upper(src_.str(b));
      const std::string second = e > b + 1 ? to_upper(src_.str(b + 1)) : "";
      if (first == "DEF" || first == "DEFFCT" || (first == "GLOBAL" && (second == "DEF" || second == "DEFFCT")) ||
          first == "END" || first == "ENDFCT") {
        first_statement = 0;
      } else if (krl_declaration(src_, b, e)) {
        if (first_statement > 0) {
          src_.fail(b, fmt::format("a declaration after the routine's first statement (line {}): KRL declares "
                                   "before the statements, and the controller refuses the program",
                                   first_statement));
        }
      } else if (!src_.is_punct(b, "&") && first_statement == 0) {
        first_statement = src_.tok[b].line;
      }
    }
    int defdat = 0;
    int enddat = 0;
    for (const auto& [b, e] : dat_.lines) {
      if (enddat > 0) {
        dat_.fail(b, fmt::format("'{}' after ENDDAT (line {}): the data list ends there, and the controller "
                                 "refuses anything after it",
                                 dat_.span(b, e), enddat));
      }
      if (dat_.is_ident(b, "DEFDAT") || (dat_.is_ident(b, "PUBLIC") && dat_.is_ident(b + 1, "DEFDAT"))) {
        defdat = dat_.tok[b].line;
      } else if (dat_.is_ident(b, "ENDDAT")) {
        enddat = dat_.tok[b].line;
      } else if (defdat == 0 && krl_declaration(dat_, b, e)) {
        dat_.fail(b, "a declaration before DEFDAT: the data list's declarations go between DEFDAT and ENDDAT");
      }
    }
  }

  /// A line that declares (DECL, SIGNAL, ENUM, STRUC, EXT, EXTFCT, or a built-in type then a name, which
  /// KRL declares without DECL); INTERRUPT DECL is a statement.
  static bool krl_declaration(const KrlFile& f, std::size_t b, std::size_t e) {
    std::size_t i = b;
    if (f.is_ident(i, "GLOBAL")) ++i;
    if (i >= e) return false;
    for (const char* k : {"DECL", "SIGNAL", "ENUM", "STRUC", "EXT", "EXTFCT"}) {
      if (f.is_ident(i, k)) return true;
    }
    const bool builtin = std::any_of(std::begin(kBuiltinTypes), std::end(kBuiltinTypes),
                                     [&](const char* t) { return f.is_ident(i, t); });
    return builtin && i + 1 < e && f.is_ident(i + 1);
  }

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
      if (frames_.count(to_upper(name)) != 0) {
        throw InputError(fmt::format("{}: {} is given twice", where, name));
      }
      const std::string value = spec.substr(eq + 1);
      try {
        const KrlFile f(where, value);
        KrlAggregate a;
        const auto end = parse_krl_aggregate(f, 0, f.tok.size(), a);
        if (!end || *end != f.tok.size() || !a.numbers({"X", "Y", "Z", "A", "B", "C"})) {
          throw InputError(fmt::format("{}: the value is not a frame {{X ..,Y ..,Z ..,A ..,B ..,C ..}}", where));
        }
        check_krl_point(f, a, "FRAME", "the frame");
        frames_[to_upper(name)] = krl_frame(a);
      } catch (const DataError& e) {
        throw InputError(e.what());
      }
    }
  }

  /// The declarations of the .dat: points (arrays included) and FDATs; a point's value checked
  /// against its type, a name declared twice refused.
  void read_data() {
    const KrlFile& f = dat_;
    std::map<std::string, std::string> array_type;
    for (const auto& [b, e] : f.lines) {
      KrlDecl d;
      if (!declaration(b, e, d, array_type)) {
        continue;
      }
      const std::string key = to_upper(d.name) + (d.element > 0 ? fmt::format("[{}]", d.element) : "");
      if (const auto it = by_key_.find(key); it != by_key_.end()) {
        f.fail(d.name_tok, fmt::format("'{}' is declared twice in the data list (also on line {})", d.name,
                                       f.tok[decls_[it->second].name_tok].line));
      }
      by_key_[key] = decls_.size();
      decl_name_tokens_.insert(d.name_tok);
      decls_.push_back(std::move(d));
    }
  }

  /// One line of the .dat: false when it declares nothing deflex reads.
  bool declaration(std::size_t b, std::size_t e, KrlDecl& d, std::map<std::string, std::string>& array_type) {
    const KrlFile& f = dat_;
    std::size_t i = b;
    bool decl = false;
    while (i < e && (f.is_ident(i, "DECL") || f.is_ident(i, "GLOBAL"))) {
      decl = true;
      ++i;
    }
    d.first_tok = b;
    if (f.is_ident(i) && f.is_ident(i + 1)) {  // TYPE NAME ...
      d.type = to_upper(f.str(i));
      d.name_tok = i + 1;
      d.name = f.str(i + 1);
      i += 2;
      if (f.is_punct(i, "[")) {  // an array declaration: its elements come on later lines
        array_type[to_upper(d.name)] = d.type;
        decl_name_tokens_.insert(d.name_tok);
        return false;
      }
    } else if (!decl && f.is_ident(i) && f.is_punct(i + 1, "[") && i + 2 < e &&
               f.tok[i + 2].kind == TokenKind::kNumber && f.is_punct(i + 3, "]")) {  // NAME[i]=...
      const auto t = array_type.find(to_upper(f.str(i)));
      if (t == array_type.end()) {
        return false;
      }
      d.type = t->second;
      d.name_tok = i;
      d.name = f.str(i);
      d.element = token_index(f, i + 2);
      i += 4;
    } else {
      return false;
    }
    if (!f.is_punct(i, "=")) {
      return false;
    }
    const auto end = parse_krl_aggregate(f, i + 1, e, d.value);
    d.literal = end && *end == e;
    const bool point = krl_cartesian_type(d.type) || krl_axis_type(d.type);
    if ((point || d.type == "FDAT") && !d.literal) {
      f.fail(i + 1, fmt::format("{} '{}': the value is not an aggregate {{...}} closed on its line", d.type, d.name));
    }
    if (point) {
      check_krl_point(f, d.value, d.type, fmt::format("{} '{}'", d.type, d.name));
    }
    return true;
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
        if (f != &src_) {
          continue;
        }
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

  /// The point a name (NAME or NAME[i]) declares in the .dat; null with `why` when it is declared
  /// elsewhere or assigned while the program runs.
  const KrlDecl* find_point(const std::string& key, const std::string& name, std::string& why) const {
    const auto it = by_key_.find(key);
    if (it == by_key_.end()) {
      why = fmt::format("'{}' is not declared in {} (in $config.dat or another module's data list)", name, dat_.file);
      return nullptr;
    }
    const KrlDecl& d = decls_[it->second];
    if (assigned_.count(to_upper(d.name)) != 0) {
      why = fmt::format("'{}' is assigned while the program runs", d.name);
      return nullptr;
    }
    if (!d.literal) {
      why = fmt::format("the value of '{}' is not a literal aggregate", name);
      return nullptr;
    }
    return &d;
  }

  // --- $TOOL and $BASE ------------------------------------------------------------------------

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
    KrlAggregate a;
    const auto end = parse_krl_aggregate(src_, b, e, a);
    if (end && *end == e && a.numbers({"X", "Y", "Z", "A", "B", "C"})) {
      check_krl_point(src_, a, "FRAME", "the frame");
      s.kind = FrameState::Kind::kLiteral;
      s.frame = krl_frame(a);
      return s;
    }
    // A FRAME the program's .dat declares (and nothing assigns).
    if (e == b + 1 && src_.is_ident(b)) {
      std::string why;
      const KrlDecl* d = find_point(to_upper(src_.str(b)), src_.str(b), why);
      if (d != nullptr && d->value.numbers({"X", "Y", "Z", "A", "B", "C"})) {
        s.kind = FrameState::Kind::kLiteral;
        s.frame = krl_frame(d->value);
        return s;
      }
    }
    s.kind = FrameState::Kind::kUnknown;
    s.why = fmt::format("set from an expression on line {} ({})", src_.tok[b].line, src_.span(b, e));
    return s;
  }

  static FrameState numbered(const char* table, int n) {
    FrameState s;
    if (n == 0) {
      s.kind = FrameState::Kind::kLiteral;  // tool 0 is the flange, base 0 the world
      return s;
    }
    s.kind = FrameState::Kind::kNamed;
    s.name = fmt::format("{}[{}]", table, n);
    return s;
  }

  /// A line that sets $TOOL or $BASE ($TOOL=, FDAT_ACT=, BAS(#TOOL, n)); false for any other line.
  bool frame_statement(std::size_t b, std::size_t e, FrameState& tool, FrameState& base) const {
    const KrlFile& f = src_;
    const std::string first = to_upper(f.str(b));
    if ((first == "$TOOL" || first == "$BASE") && f.is_punct(b + 1, "=")) {
      (first == "$TOOL" ? tool : base) = assigned_frame(b + 2, e, first == "$TOOL" ? "TOOL_DATA" : "BASE_DATA");
      return true;
    }
    if (first == "FDAT_ACT" && f.is_punct(b + 1, "=") && e == b + 3) {
      const auto it = by_key_.find(to_upper(f.str(b + 2)));
      const KrlDecl* d = it != by_key_.end() && decls_[it->second].type == "FDAT" ? &decls_[it->second] : nullptr;
      const KrlComponent* t = d != nullptr ? d->value.find("TOOL_NO") : nullptr;
      const KrlComponent* bn = d != nullptr ? d->value.find("BASE_NO") : nullptr;
      const KrlComponent* ipo = d != nullptr ? d->value.find("IPO_FRAME") : nullptr;
      if (t == nullptr || bn == nullptr || t->kind != KrlComponent::Kind::kNumber ||
          bn->kind != KrlComponent::Kind::kNumber) {
        tool.kind = base.kind = FrameState::Kind::kUnknown;
        tool.why = base.why = fmt::format("FDAT_ACT = {} on line {}: no literal FDAT with TOOL_NO and BASE_NO in {}",
                                          f.str(b + 2), f.tok[b].line, dat_.file);
        return true;
      }
      tool = numbered("TOOL_DATA", static_cast<int>(t->number));
      base = numbered("BASE_DATA", static_cast<int>(bn->number));
      if (ipo != nullptr && iequals(dat_.text.substr(ipo->begin, ipo->end - ipo->begin), "#TCP")) {
        tool.kind = FrameState::Kind::kUnknown;
        tool.why = fmt::format("{} on line {} has IPO_FRAME #TCP (a stationary tool): not supported", f.str(b + 2),
                               f.tok[b].line);
      }
      return true;
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
      return true;
    }
    return false;
  }

  // --- motions ---------------------------------------------------------------------------------

  /// The target pieces of a PTP/LIN/CIRC line: split at depth-0 commas, approximation keywords and
  /// CIRC's CA angle dropped.
  std::vector<Range> motion_targets(std::size_t b, std::size_t e, const std::string& first) const {
    const KrlFile& f = src_;
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
    if (depth != 0) {
      f.fail(b, fmt::format("{}: its brackets do not close on the line", first));
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
    for (const auto& [tb, te] : pieces) {
      if (tb == te) {
        f.fail(b, fmt::format("{}: a target is missing", first));
      }
    }
    return pieces;
  }

  /// The point a motion's target names, checked; null with `why` (listed) when it is not static.
  const KrlAggregate* target_point(Range target, const std::string& first, const KrlDecl*& decl, std::string& why) {
    const KrlFile& f = src_;
    const auto [tb, te] = target;
    const std::string written = f.span(tb, te);
    std::size_t after = tb + 1;
    std::string key;
    KrlAggregate inline_value;
    if (f.is_punct(tb, "{")) {
      const auto end = parse_krl_aggregate(f, tb, te, inline_value);
      if (!end) {
        f.fail(tb, fmt::format("{}: the inline target {} is not an aggregate {{...}}", first, written));
      }
      check_krl_point(f, inline_value, "", fmt::format("{} {}", first, "inline target"));
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
      why = "the target is computed at run time";
      return nullptr;
    }
    const KrlAggregate* value = nullptr;
    if (key.empty()) {
      inlines_.push_back(std::make_unique<KrlAggregate>(inline_value));
      value = inlines_.back().get();
    } else {
      decl = find_point(key, written, why);
      if (decl == nullptr) {
        return nullptr;
      }
      if (!(krl_cartesian_type(decl->type) || krl_axis_type(decl->type))) {
        f.fail(tb, fmt::format("{}: '{}' is a {} ({} line {}), not a point", first, written, decl->type, dat_.file,
                               dat_.tok[decl->name_tok].line));
      }
      value = &decl->value;
    }
    const bool joint = value->find("A1") != nullptr;
    const bool complete =
        joint ? value->numbers({"A1", "A2", "A3", "A4", "A5", "A6"}) : value->numbers({"X", "Y", "Z", "A", "B", "C"});
    if (!complete && decl != nullptr) {
      f.fail(tb, fmt::format("{}: the point '{}' ({} line {}) does not give every component ({}): the controller "
                             "stops here",
                             first, written, dat_.file, dat_.tok[decl->name_tok].line,
                             joint ? "A1..A6" : "X, Y, Z, A, B, C"));
    }
    if (!complete) {
      why = "a partial inline target: its other components are the arm's when the program runs";
      return nullptr;
    }
    return value;
  }

  /// One PTP/LIN/CIRC line: every target resolved into `uses`/`info`, or listed.
  void motion(std::size_t b, std::size_t e, const std::string& first, const FrameState& tool, const FrameState& base,
              std::size_t& force_index, ProgramCompensation& result, std::vector<ProgramTargetUse>& uses,
              std::vector<KrlUse>& info) {
    const KrlFile& f = src_;
    for (const Range& target : motion_targets(b, e, first)) {
      const std::size_t index = force_index++;
      const auto [tb, te] = target;
      const std::string written = f.span(tb, te);
      std::string why;
      const KrlDecl* decl = nullptr;
      const KrlAggregate* value = target_point(target, first, decl, why);
      if (value == nullptr) {
        result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e), why});
        continue;
      }
      const bool joint = value->find("A1") != nullptr;
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
        for (int j = 0; j < 6; ++j) {
          u.q[j] = deg_to_rad(value->find(kAxes[j])->number);
        }
      } else {
        u.base_T_tcp = *base_frame * krl_frame(*value);
        const KrlComponent* s = value->find("S");
        const KrlComponent* t = value->find("T");
        if (s != nullptr && t != nullptr) {
          u.ik.kuka_configuration =
              KukaConfiguration{static_cast<int>(s->number) & 7, static_cast<int>(t->number) & 63};
        } else if (uses.empty() && !start_q_) {
          result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e),
                                       "no Status and Turn, and no earlier target: the configuration is the arm's "
                                       "when the program runs (give its joints at the start with --seed-deg)"});
          continue;
        } else {
          u.continue_from_previous = true;
        }
      }
      KrlUse x;
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

  /// Walks the .src line by line: frames followed, every motion resolved or listed.
  void collect(ProgramCompensation& result, std::vector<ProgramTargetUse>& uses, std::vector<KrlUse>& info) {
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
    std::size_t force_index = 0;
    std::size_t motions = 0;
    const KrlFile& f = src_;
    for (const auto& [b, e] : f.lines) {
      if (frame_statement(b, e, tool, base)) {
        continue;
      }
      const std::string first = to_upper(f.str(b));
      if (std::any_of(std::begin(kUnsupported), std::end(kUnsupported), [&](const char* k) { return first == k; })) {
        ++motions;
        result.unresolved.push_back({f.file, f.tok[b].line, f.span(b, e),
                                     fmt::format("{} is not compensated by deflex (PTP, LIN and CIRC are)", first)});
        continue;
      }
      if (first == "PTP" || first == "LIN" || first == "CIRC") {
        ++motions;
        motion(b, e, first, tool, base, force_index, result, uses, info);
      }
    }
    if (motions == 0) {
      throw DataError(fmt::format("{}: no motion instruction (PTP, LIN, CIRC): nothing to compensate", src_.file));
    }
    if (uses.empty()) {
      std::string list;
      for (const UnresolvedConstruct& c : result.unresolved) {
        list += fmt::format("\n  {}:{}: {}: {}", c.file, c.line, c.text, c.reason);
      }
      throw DataError(
          fmt::format("{}: none of its motion targets can be compensated before the program runs:{}", src_.file, list));
    }
  }

  /// The new numbers of every use, from its compensated result.
  static void compute_numbers(std::vector<KrlUse>& info, const std::vector<ProgramTargetResult>& results) {
    for (KrlUse& x : info) {
      const ProgramTargetResult& r = results[x.use_index];
      const KrlAggregate& v = *x.value;
      if (x.joint) {
        for (int j = 0; j < 6; ++j) {
          x.numbers.emplace_back(v.find(kAxes[j]), program_number(rad_to_deg(r.q_command[j]), 4));
        }
        continue;
      }
      const Pose in_base = x.base_frame.inverse() * r.tcp_command;
      const Vector3 p = in_base.translation() * 1e3;
      const Vector3 abc =
          krl_abc(in_base.linear(), Vector3(v.find("A")->number, v.find("B")->number, v.find("C")->number));
      for (int j = 0; j < 6; ++j) {
        x.numbers.emplace_back(v.find(kFrameNames[j]), program_number(j < 3 ? p[j] : abc[j - 3], 4));
      }
      for (const auto& [name, value] : {std::pair{"S", r.kuka.status}, std::pair{"T", r.kuka.turn}}) {
        const KrlComponent* c = v.find(name);
        if (c != nullptr) {
          x.numbers.emplace_back(
              c, c->kind == KrlComponent::Kind::kBits ? krl_bits(value, c->bit_digits) : std::to_string(value));
        }
      }
    }
  }

  /// A compensated copy of declaration `d` named `name`, as a line of the .dat.
  std::string copy_line(const KrlDecl& d, const KrlUse& y, const std::string& name, const std::string& eol) const {
    if (d.element == 0) {
      // The declaration's line, renamed, with the new numbers.
      const std::size_t line_begin =
          dat_.tok[d.first_tok].begin - indentation_of(dat_.text, dat_.tok[d.first_tok].begin).size();
      const std::size_t at = end_of_line(dat_.text, dat_.tok[d.name_tok].begin);
      std::vector<TextEdit> rel{
          {dat_.tok[d.name_tok].begin - line_begin, dat_.tok[d.name_tok].end - dat_.tok[d.name_tok].begin, name}};
      for (const auto& [c, value] : y.numbers) {
        rel.push_back({c->begin - line_begin, c->end - c->begin, value});
      }
      std::string line = apply_edits(dat_.text.substr(line_begin, at - line_begin), rel);
      if (line.empty() || (line.back() != '\n' && line.back() != '\r')) {
        line += eol;
      }
      return line;
    }
    std::vector<TextEdit> rel;
    for (const auto& [c, value] : y.numbers) {
      rel.push_back({c->begin - d.value.begin, c->end - c->begin, value});
    }
    return indentation_of(dat_.text, dat_.tok[d.first_tok].begin) + "DECL " + d.type + " " + name + "=" +
           apply_edits(dat_.text.substr(d.value.begin, d.value.end - d.value.begin), rel) + eol;
  }

  /// The new numbers written back (program_write_back.hpp): literals into the .src, points and their
  /// copies into the .dat, a copy's name into the .src.
  void write_back(const std::vector<KrlUse>& info, std::vector<std::string>& actions, std::vector<TextEdit>& src_edits,
                  std::vector<TextEdit>& dat_edits) const {
    const KrlFile& f = src_;
    std::vector<WriteBackUse> uses;
    for (const KrlUse& x : info) {
      WriteBackUse u;
      u.target = x.decl;
      u.name = x.decl == nullptr ? std::string() : to_upper(x.decl->name);
      for (const auto& [c, text] : x.numbers) {
        u.numbers.push_back(text);
      }
      uses.push_back(std::move(u));
    }
    const std::vector<WriteBackStep> steps = plan_write_back(uses, references_);
    std::set<std::string> taken;
    add_identifiers(src_, taken);
    add_identifiers(dat_, taken);
    const std::string eol = line_terminator(dat_.text);
    actions.assign(info.size(), {});
    std::vector<std::string> names(info.size());  // the copy each use declares
    for (std::size_t a = 0; a < info.size(); ++a) {
      const KrlUse& x = info[a];
      const WriteBackStep& step = steps[a];
      if (step.kind != WriteBackStep::Kind::kCopy) {
        if (step.kind == WriteBackStep::Kind::kLiteral || step.first) {
          for (const auto& [c, text] : x.numbers) {
            (x.decl == nullptr ? src_edits : dat_edits).push_back({c->begin, c->end - c->begin, text});
          }
        }
        actions[a] = step.kind == WriteBackStep::Kind::kLiteral ? "literal edited" : "edited in place";
        continue;
      }
      if (step.first) {
        const KrlDecl& d = *x.decl;
        names[a] = copy_name(d.element > 0 ? fmt::format("{}{}", d.name, d.element) : d.name, "_C", 24, taken);
        const std::size_t at = end_of_line(dat_.text, dat_.tok[d.name_tok].begin);
        const bool unterminated = at == dat_.text.size() && dat_.text.back() != '\n' && dat_.text.back() != '\r';
        dat_edits.push_back({at, 0, (unterminated ? eol : "") + copy_line(d, x, names[a], eol)});
      }
      const std::string& name = names[step.source];
      src_edits.push_back({f.tok[x.ref_b].begin, f.tok[x.ref_e - 1].end - f.tok[x.ref_b].begin, name});
      actions[a] = "copy " + name;
    }
  }

  const RobotModel& model_;
  const ForceModel& force_;
  KrlFile src_;
  KrlFile dat_;
  std::vector<KrlDecl> decls_;
  std::map<std::string, std::size_t> by_key_;
  std::set<std::size_t> decl_name_tokens_;
  std::map<std::string, int> references_;
  std::set<std::string> assigned_;
  std::map<std::string, Pose> frames_;
  std::vector<std::unique_ptr<KrlAggregate>> inlines_;  // inline targets, at stable addresses
  std::optional<JointVector> start_q_;                  // the arm's joints at the start (--seed-deg)
};

ProgramCompensation KrlReader::run(const std::string& output_src) {
  ProgramCompensation result;
  result.language = "KRL";
  result.force_description = force_.describe();
  std::vector<ProgramTargetUse> uses;
  std::vector<KrlUse> info;
  collect(result, uses, info);
  const std::vector<ProgramTargetResult> results = compensate_program_targets(model_, uses, force_, start_q_);
  compute_numbers(info, results);
  std::vector<std::string> actions;
  std::vector<TextEdit> src_edits;
  std::vector<TextEdit> dat_edits;
  write_back(info, actions, src_edits, dat_edits);
  for (std::size_t a = 0; a < info.size(); ++a) {
    const KrlUse& x = info[a];
    result.targets.push_back(
        target_report(results[x.use_index], src_.file, x.line, x.instruction, x.written, actions[a]));
    if (!uses[x.use_index].joint && uses[x.use_index].continue_from_previous) {
      result.targets.back().configuration_note =
          x.use_index == 0 ? "no Status and Turn: the configuration of --seed-deg (the arm at the start)"
                           : "no Status and Turn: continues from the previous target";
    }
  }
  result.outputs.push_back({output_src, apply_edits(src_.text, src_edits)});
  result.outputs.push_back(
      {std::filesystem::path(output_src).replace_extension(".dat").string(), apply_edits(dat_.text, dat_edits)});
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
