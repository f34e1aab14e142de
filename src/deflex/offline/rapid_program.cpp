// RAPID module reader and compensated writer. The reader is as strict as the controller loading the
// module: a malformed declaration, motion or value stops it with the file, the line and the field;
// only targets whose value is known only when the program runs (or that live in another module, or
// that deflex does not compensate) are listed and left unchanged. Data are looked up the way RAPID
// scopes them: a routine's own data first, then the module's.
#include "deflex/offline/detail/rapid_program.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include <fmt/format.h>

#include "deflex/offline/detail/program_targets.hpp"
#include "deflex/offline/detail/program_text.hpp"
#include "deflex/offline/detail/program_write_back.hpp"
#include "deflex/offline/detail/quaternion_sign.hpp"
#include "deflex/offline/detail/rapid_values.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

using Tokens = std::vector<Token>;
using Span = std::pair<std::size_t, std::size_t>;  // tokens [first, last)

struct Decl {
  std::size_t first_tok = 0;  // LOCAL/TASK or the storage keyword
  std::string storage;        // CONST, PERS, VAR as written
  std::string type;           // lower case
  std::size_t name_tok = 0;
  std::string name;
  int routine = -1;  // the routine declaring it, -1: the module
  std::vector<int> dims;
  bool literal = false;
  bool run_time = false;    // a literal that names a num the program changes
  std::size_t end_tok = 0;  // the ';'
  RapidValue value;
};

struct ExternalData {
  std::string name;
  RapidValue value;
  std::string text;  // the value's text, which the value's byte offsets index
};

struct Instruction {
  std::size_t tok = 0;
  std::string name;
  std::size_t end_tok = 0;
  std::vector<Span> args;               // positional expressions
  std::map<std::string, Span> options;  // upper name -> value
};

struct Motion {
  const char* name;
  std::size_t positional;
  std::vector<std::string> options;
  std::vector<const char*> argument_names;
  char conf;  // the configuration instruction that governs it: 'J' (ConfJ), 'L' (ConfL), 0 (none)
};

const std::vector<Motion>& motions() {
  static const std::vector<Motion> m = {
      {"MoveL",
       4,
       {"CONC", "ID", "V", "T", "Z", "INPOS", "WOBJ", "CORR", "TLOAD"},
       {"ToPoint", "Speed", "Zone", "Tool"},
       'L'},
      {"MoveJ",
       4,
       {"CONC", "ID", "V", "T", "Z", "INPOS", "WOBJ", "CORR", "TLOAD"},
       {"ToPoint", "Speed", "Zone", "Tool"},
       'J'},
      {"MoveC",
       5,
       {"CONC", "ID", "V", "T", "Z", "INPOS", "WOBJ", "CORR", "TLOAD"},
       {"CirPoint", "ToPoint", "Speed", "Zone", "Tool"},
       'L'},
      {"MoveAbsJ",
       4,
       {"CONC", "ID", "NOEOFFS", "V", "T", "Z", "INPOS", "WOBJ", "TLOAD"},
       {"ToJointPos", "Speed", "Zone", "Tool"},
       0},
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
  const RapidValue* value = nullptr;  // the robtarget/jointtarget value node
  const Decl* decl = nullptr;
  int element = -1;                  // 0-based array element, -1 for scalars
  std::size_t ref_b = 0, ref_e = 0;  // tokens of the reference (name or name{i}) or of the literal
  enum class Offset { kNone, kOffs, kRelTool } offset = Offset::kNone;
  Vector3 d_mm = Vector3::Zero();
  Vector3 rot_deg = Vector3::Zero();  // RelTool \Rx, \Ry, \Rz
};

struct ToolWobj {
  Pose tool = Pose::Identity();
  Pose wobj = Pose::Identity();
};

/// ConfJ and ConfL as the program sets them, in the order of its text (both \On when it starts).
struct ConfState {
  int joint_off_line = 0;   // the line of the ConfJ\Off in force, 0: \On
  int linear_off_line = 0;  // the same for ConfL
};

/// One resolved use and what writing it back needs.
struct RapidUse {
  TargetRef ref;
  std::string type;
  Pose base_T_wobj = Pose::Identity();
  std::size_t use_index = 0;  // into the ProgramTargetUse list
  std::string instruction;
  int line = 0;
  std::string written;
  std::string conf_note;
  // Filled after compensation: the new numbers, parallel to the value's number nodes.
  std::vector<std::pair<const RapidValue*, std::string>> numbers;
};

/// Number nodes of a robtarget (trans, rot, robconf) or jointtarget (robax) value, in order.
std::vector<const RapidValue*> target_numbers(const RapidValue& v, const std::string& type) {
  std::vector<const RapidValue*> out;
  const std::size_t lists = type == "robtarget" ? 3 : 1;
  for (std::size_t l = 0; l < lists; ++l) {
    for (const RapidValue& x : v.items[l].items) {
      out.push_back(&x);
    }
  }
  return out;
}

Matrix3 reltool_rotation(const Vector3& rot_deg) {
  return (Eigen::AngleAxisd(deg_to_rad(rot_deg.x()), Vector3::UnitX()) *
          Eigen::AngleAxisd(deg_to_rad(rot_deg.y()), Vector3::UnitY()) *
          Eigen::AngleAxisd(deg_to_rad(rot_deg.z()), Vector3::UnitZ()))
      .toRotationMatrix();
}

class RapidReader {
 public:
  RapidReader(const RobotModel& model, const ForceModel& force, std::string file, const std::string& text,
              const ProgramOptions& options)
      : model_(model), force_(force), src_{std::move(file), text, {}}, start_q_(options.start_q) {
    src_.tok = lex_rapid(text, src_.file);
    check_module();
    read_external(options.tooldata, "--tooldata", "tooldata", tools_);
    read_external(options.wobjdata, "--wobjdata", "wobjdata", wobjs_);
    read_routines();
    read_declarations();
    read_references();
    check_declarations();
  }

  ProgramCompensation run(const std::string& output_path);

 private:
  // --- reading the module ----------------------------------------------------------------------

  void check_module() const {
    if (src_.tok.empty()) {
      throw DataError(fmt::format("{}: the program is empty", src_.file));
    }
    const auto module = std::find_if(src_.tok.begin(), src_.tok.end(), [&](const Token& t) {
      return t.kind == TokenKind::kIdentifier && iequals(src_.text.substr(t.begin, t.end - t.begin), "MODULE");
    });
    const bool ends = std::any_of(src_.tok.begin(), src_.tok.end(), [&](const Token& t) {
      return t.kind == TokenKind::kIdentifier && iequals(src_.text.substr(t.begin, t.end - t.begin), "ENDMODULE");
    });
    if (module == src_.tok.end() || !ends) {
      src_.fail(0, fmt::format("no MODULE ... ENDMODULE: not a RAPID module"));
    }
  }

  void read_external(const std::vector<std::string>& specs, const char* option, const char* type,
                     std::map<std::string, ExternalData>& out) const {
    for (const std::string& spec : specs) {
      const auto eq = spec.find('=');
      const std::string name = spec.substr(0, eq);
      const std::string where = fmt::format("option {} '{}'", option, spec);
      if (eq == std::string::npos || name.empty()) {
        throw InputError(fmt::format("{}: give NAME=VALUE in RAPID syntax", where));
      }
      if (out.count(to_upper(name)) != 0) {
        throw InputError(fmt::format("{}: {} '{}' is given twice", where, type, name));
      }
      ExternalData& d = out[to_upper(name)];
      d.name = name;
      d.text = spec.substr(eq + 1);
      RapidSource s{where, d.text, {}};
      try {
        s.tok = lex_rapid(d.text, where);
        const auto end = parse_rapid_value(s, 0, s.tok.size(), d.value);
        if (!end || *end != s.tok.size()) {
          throw InputError(
              fmt::format("{}: not a literal {} value ({})", where, type,
                          std::string(type) == "tooldata"
                              ? "[robhold,[[x,y,z],[q1,q2,q3,q4]],[mass,[cx,cy,cz],[a1,a2,a3,a4],ix,iy,iz]]"
                              : "[robhold,ufprog,\"ufmec\",[[x,y,z],[q1,q2,q3,q4]],[[x,y,z],[q1,q2,q3,q4]]]"));
        }
        check_rapid_value(
            d.value, type, [](const std::string&) { return std::nullopt; },
            [&](std::size_t, const std::string& what) { throw InputError(fmt::format("{}: {}", where, what)); });
      } catch (const DataError& e) {
        throw InputError(e.what());
      }
      for (const std::size_t frame :
           std::string(type) == "tooldata" ? std::vector<std::size_t>{1} : std::vector<std::size_t>{3, 4}) {
        if (!rapid_pose(d.value.items[frame])) {
          throw InputError(fmt::format("{}: the quaternion of its frame is not of unit length", where));
        }
      }
    }
  }

  /// Which routine (PROC, FUNC, TRAP) every token belongs to; -1 for the module's data. Every routine
  /// must end with its own ENDPROC, ENDFUNC or ENDTRAP before the next begins and before ENDMODULE:
  /// the controller refuses to load a module that does not (and a routine would run on into the next).
  void read_routines() {
    routine_of_.assign(src_.tok.size(), -1);
    int current = -1;
    int count = 0;
    std::size_t opened = 0;  // the token that began the current routine
    const auto end_of = [](const std::string& kind) { return "END" + kind; };
    for (std::size_t i = 0; i < src_.tok.size(); ++i) {
      const bool begins = src_.is_ident(i, "PROC") || src_.is_ident(i, "FUNC") || src_.is_ident(i, "TRAP");
      const bool ends = src_.is_ident(i, "ENDPROC") || src_.is_ident(i, "ENDFUNC") || src_.is_ident(i, "ENDTRAP");
      if (begins && current >= 0) {
        src_.fail(i,
                  fmt::format("{} begins inside the {} of line {}: its {} is missing", to_upper(src_.str(i)),
                              to_upper(src_.str(opened)), src_.tok[opened].line, end_of(to_upper(src_.str(opened)))));
      }
      if (src_.is_ident(i, "ENDMODULE") && current >= 0) {
        src_.fail(opened, fmt::format("{} has no {} before ENDMODULE (line {})", to_upper(src_.str(opened)),
                                      end_of(to_upper(src_.str(opened))), src_.tok[i].line));
      }
      if (begins) {
        current = count++;
        opened = i;
      }
      routine_of_[i] = current;
      if (ends) {
        if (current < 0 || !iequals(src_.str(i), end_of(to_upper(src_.str(opened))))) {
          src_.fail(i, current < 0 ? fmt::format("{} without a routine it ends", to_upper(src_.str(i)))
                                   : fmt::format("{} ends the {} of line {} (it needs {})", to_upper(src_.str(i)),
                                                 to_upper(src_.str(opened)), src_.tok[opened].line,
                                                 end_of(to_upper(src_.str(opened)))));
        }
        current = -1;
      }
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
      // A declaration ends at ';' (never inside brackets), a routine parameter (VAR robtarget p) at ','
      // or ')' outside them.
      std::size_t j = i + 3;
      int depth = 0;
      while (j < t.size() && !src_.is_punct(j, ";") &&
             !(depth == 0 && (src_.is_punct(j, ",") || src_.is_punct(j, ")")))) {
        depth += (src_.is_punct(j, "[") || src_.is_punct(j, "(") || src_.is_punct(j, "{")) ? 1 : 0;
        depth -= (src_.is_punct(j, "]") || src_.is_punct(j, ")") || src_.is_punct(j, "}")) ? 1 : 0;
        ++j;
      }
      if (!src_.is_punct(j, ";")) {
        continue;
      }
      if (depth != 0) {
        src_.fail(i, fmt::format("declaration of '{}': its brackets do not close before the ';'", src_.str(i + 2)));
      }
      decls_.push_back(declaration(i, j));
      i = j;
    }
    for (std::size_t n = 0; n < decls_.size(); ++n) {
      by_name_[to_upper(decls_[n].name)].push_back(n);
      decl_name_tokens_.insert(decls_[n].name_tok);
    }
  }

  Decl declaration(std::size_t i, std::size_t j) const {
    Decl d;
    d.first_tok = i > 0 && (src_.is_ident(i - 1, "LOCAL") || src_.is_ident(i - 1, "TASK")) ? i - 1 : i;
    d.storage = src_.str(i);
    std::string type = src_.str(i + 1);
    std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return std::tolower(c); });
    d.type = type;
    d.name_tok = i + 2;
    d.name = src_.str(i + 2);
    d.routine = routine_of_[i];
    d.end_tok = j;
    std::size_t k = i + 3;
    if (src_.is_punct(k, "{")) {
      ++k;
      while (k < j && !src_.is_punct(k, "}")) {
        if (src_.tok[k].kind == TokenKind::kNumber) {
          d.dims.push_back(token_index(src_, k));
        } else if (!src_.is_punct(k, ",")) {
          d.dims.push_back(-1);  // a dimension given by a name: unknown size
        }
        ++k;
      }
      ++k;
    }
    if (src_.is_punct(k, ":=")) {
      const auto end = parse_rapid_value(src_, k + 1, j, d.value);
      d.literal = end && *end == j;
      if (end && *end != j && src_.tok[*end].kind == TokenKind::kIdentifier) {
        // A value followed by a name, not an operator: the ';' is missing (the next line's declaration
        // would otherwise be swallowed into this one).
        src_.fail(d.name_tok, fmt::format("';' expected after the value of '{}'", d.name));
      }
    } else if (k != j) {
      src_.fail(k, fmt::format("declaration of '{}': ':=' or ';' expected after the name", d.name));
    }
    return d;
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

  /// Every literal of a type deflex knows holds its layout; one name declared twice in one scope is
  /// refused (the controller loads neither).
  void check_declarations() {
    std::map<std::pair<std::string, int>, const Decl*> seen;
    for (Decl& d : decls_) {
      const auto [it, fresh] = seen.emplace(std::pair{to_upper(d.name), d.routine}, &d);
      if (!fresh) {
        src_.fail(d.name_tok, fmt::format("'{}' is declared twice in the same {} (also on line {})", d.name,
                                          d.routine < 0 ? "module" : "routine", src_.tok[it->second->name_tok].line));
      }
      if (!d.literal || !is_checked_rapid_type(d.type)) {
        continue;
      }
      const auto lookup = [&](const std::string& n) { return named_num(n, d.routine); };
      const auto fail = [&](std::size_t token, const std::string& what) {
        src_.fail(token, fmt::format("{} '{}': {}", d.type, d.name, what));
      };
      if (d.dims.empty()) {
        d.run_time = check_rapid_value(d.value, d.type, lookup, fail) == RapidValueState::kRunTime;
        continue;
      }
      if (d.dims.size() != 1 || d.dims[0] < 0) {
        continue;  // several dimensions or a size given by a name: not resolved (see plain_ref)
      }
      if (d.value.kind != RapidValue::Kind::kList || d.value.items.size() != static_cast<std::size_t>(d.dims[0])) {
        src_.fail(d.value.token,
                  fmt::format("{} '{}{{{}}}': {} values for {} elements", d.type, d.name, d.dims[0],
                              d.value.kind == RapidValue::Kind::kList ? d.value.items.size() : 1, d.dims[0]));
      }
      for (std::size_t e = 0; e < d.value.items.size(); ++e) {
        const auto element_fail = [&](std::size_t token, const std::string& what) {
          src_.fail(token, fmt::format("{} '{}{{{}}}': {}", d.type, d.name, e + 1, what));
        };
        d.run_time = check_rapid_value(d.value.items[e], d.type, lookup, element_fail) == RapidValueState::kRunTime ||
                     d.run_time;
      }
    }
  }

  // --- looking names up --------------------------------------------------------------------------

  /// The declaration of `name` in `routine`'s scope (its own first, then the module's), or null.
  const Decl* scoped(const std::string& name, int routine) const {
    const auto it = by_name_.find(to_upper(name));
    if (it == by_name_.end()) {
      return nullptr;
    }
    const Decl* module_level = nullptr;
    for (const std::size_t n : it->second) {
      if (decls_[n].routine == routine && routine >= 0) {
        return &decls_[n];
      }
      if (decls_[n].routine < 0) {
        module_level = &decls_[n];
      }
    }
    return module_level;
  }

  /// A num a literal names: its value, and whether the program may change it.
  std::optional<NamedNum> named_num(const std::string& name, int routine) const {
    const Decl* d = scoped(name, routine);
    if (d == nullptr || (d->type != "num" && d->type != "dnum")) {
      return std::nullopt;
    }
    const bool constant = d->literal && d->value.kind == RapidValue::Kind::kNumber && d->dims.empty() &&
                          (iequals(d->storage, "CONST") || assigned_.count(to_upper(name)) == 0);
    return NamedNum{constant ? d->value.number : 0.0, constant};
  }

  /// The one literal declaration of `name` of `type` seen from `routine`, or null with the reason
  /// (declared in another module, assigned while the program runs). A name of another type is an
  /// error at token `at`.
  const Decl* find_decl(const std::string& name, const std::string& type, int routine, std::size_t at,
                        std::string& why) const {
    const Decl* d = scoped(name, routine);
    if (d == nullptr) {
      why = fmt::format("'{}' is not declared in this module (another module of the task declares it)", name);
      return nullptr;
    }
    if (d->type != type) {
      src_.fail(at, fmt::format("'{}' is a {} (line {}), not a {}", name, d->type, src_.tok[d->name_tok].line, type));
    }
    if (assigned_.count(to_upper(name)) != 0) {
      why = fmt::format("'{}' is assigned while the program runs", name);
      return nullptr;
    }
    if (!d->literal) {
      why = fmt::format("the value of '{}' is given at run time or by an expression deflex does not evaluate", name);
      return nullptr;
    }
    if (d->run_time) {
      why = fmt::format("the value of '{}' uses a num the program changes while it runs", name);
      return nullptr;
    }
    return d;
  }

  /// A number argument: a literal (with sign) or a num whose value is known before the program runs.
  std::optional<double> number_arg(std::size_t b, std::size_t e, int routine) const {
    RapidValue v;
    const auto end = parse_rapid_value(src_, b, e, v);
    if (end && *end == e && v.kind == RapidValue::Kind::kNumber) {
      return v.number;
    }
    if (e == b + 1 && src_.is_ident(b)) {
      const auto n = named_num(src_.str(b), routine);
      if (n && n->constant) {
        return n->value;
      }
    }
    return std::nullopt;
  }

  /// Splits tokens [b, e) at depth-0 occurrences of `sep`.
  std::vector<Span> split(std::size_t b, std::size_t e, const char* sep) const {
    std::vector<Span> out;
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

  // --- the targets, tools and work objects of a motion --------------------------------------------

  /// A reference (name, name{i}) or a literal of `type`; nullopt with `why` when it is computed at
  /// run time or declared elsewhere. Malformed references are errors.
  std::optional<TargetRef> plain_ref(std::size_t b, std::size_t e, const std::string& type, int routine,
                                     std::string& why) const {
    TargetRef r;
    r.ref_b = b;
    r.ref_e = e;
    if (src_.is_punct(b, "[")) {
      auto* v = new RapidValue();  // owned by literals_ (stable addresses)
      literals_.emplace_back(v);
      const auto end = parse_rapid_value(src_, b, e, *v);
      if (!end || *end != e) {
        why = fmt::format("the {} is an expression evaluated at run time", type);
        return std::nullopt;
      }
      const auto state = check_rapid_value(
          *v, type, [&](const std::string& n) { return named_num(n, routine); },
          [&](std::size_t token, const std::string& what) { src_.fail(token, fmt::format("{}: {}", type, what)); });
      if (state == RapidValueState::kRunTime) {
        why = fmt::format("the {} uses a num the program changes while it runs", type);
        return std::nullopt;
      }
      r.literal = true;
      r.value = v;
      return r;
    }
    if (!src_.is_ident(b)) {
      src_.fail(b, fmt::format("'{}' is not a {}", src_.span(b, e), type));
    }
    if (src_.is_punct(b + 1, "(")) {
      why = fmt::format("{}() is computed at run time", src_.str(b));
      return std::nullopt;
    }
    // name{N}, name{+N} or name{-N}: a literal index (1-based), checked against the array below;
    // anything else in the braces is computed when the program runs.
    int index = 0;
    const bool indexed = e != b + 1;
    if (indexed) {
      const bool sign = e == b + 5 && (src_.is_punct(b + 2, "-") || src_.is_punct(b + 2, "+"));
      if (!((e == b + 4 || sign) && src_.is_punct(b + 1, "{") && src_.is_punct(e - 1, "}") &&
            src_.tok[e - 2].kind == TokenKind::kNumber)) {
        why = "computed at run time (an expression or a variable index)";
        return std::nullopt;
      }
      index = token_index(src_, e - 2) * (src_.is_punct(b + 2, "-") ? -1 : 1);
    }
    const Decl* d = find_decl(src_.str(b), type, routine, b, why);
    if (d == nullptr) {
      return std::nullopt;
    }
    const RapidValue* v = &d->value;
    if (indexed || !d->dims.empty()) {
      if (!indexed) {
        why = fmt::format("'{}' is an array used whole", d->name);
        return std::nullopt;
      }
      if (d->dims.empty()) {
        src_.fail(b, fmt::format("'{}' is not an array: {} has no element", d->name, src_.span(b, e)));
      }
      if (index < 1) {  // whatever the size: RAPID arrays are numbered from 1
        src_.fail(b + 2, fmt::format("index {} is outside {}{{...}}: RAPID numbers an array's elements from 1 "
                                     "(the controller stops here)",
                                     index, d->name));
      }
      if (d->dims.size() != 1 || d->dims[0] < 0) {
        why = fmt::format("'{}' has several dimensions or a size given by a name: not resolved", d->name);
        return std::nullopt;
      }
      if (index > d->dims[0]) {
        src_.fail(b + 2, fmt::format("index {} is outside {}{{{}}} (1..{})", index, d->name, d->dims[0], d->dims[0]));
      }
      v = &v->items[static_cast<std::size_t>(index - 1)];
    }
    r.decl = d;
    r.element = indexed ? index - 1 : -1;
    r.value = v;
    return r;
  }

  /// A target argument: plain reference, or Offs()/RelTool() of one with constant displacements.
  std::optional<TargetRef> target_ref(std::size_t b, std::size_t e, const std::string& type, int routine,
                                      std::string& why) const {
    const bool offs = src_.is_ident(b, "Offs");
    const bool reltool = src_.is_ident(b, "RelTool");
    if (!(type == "robtarget" && (offs || reltool) && src_.is_punct(b + 1, "("))) {
      return plain_ref(b, e, type, routine, why);
    }
    const std::string fn = src_.str(b);
    if (!src_.is_punct(e - 1, ")")) {
      src_.fail(b, fmt::format("{}(...): the call does not end with ')'", fn));
    }
    const auto args = split(b + 2, e - 1, ",");
    auto last = split(args.back().first, args.back().second, "\\");
    if (args.size() != 4) {
      src_.fail(b, fmt::format("{} takes 4 arguments (Point, XOffset, YOffset, ZOffset), {} given", fn, args.size()));
    }
    if (offs && last.size() != 1) {
      src_.fail(last[1].first, "Offs takes no optional argument");
    }
    std::vector<std::pair<int, Span>> rotations;
    for (std::size_t k = 1; k < last.size(); ++k) {
      const auto [ob, oe] = last[k];
      const std::string opt = to_upper(src_.str(ob));
      const int axis = opt == "RX" ? 0 : opt == "RY" ? 1 : opt == "RZ" ? 2 : -1;
      if (axis < 0 || !src_.is_punct(ob + 1, ":=")) {
        src_.fail(ob, fmt::format("RelTool: unknown optional argument '\\{}' (it takes \\Rx:=, \\Ry:=, \\Rz:=)",
                                  src_.str(ob)));
      }
      rotations.emplace_back(axis, Span{ob + 2, oe});
    }
    auto base = plain_ref(args[0].first, args[0].second, type, routine, why);
    if (!base) {
      return std::nullopt;
    }
    const auto dx = number_arg(args[1].first, args[1].second, routine);
    const auto dy = number_arg(args[2].first, args[2].second, routine);
    const auto dz = number_arg(last.front().first, last.front().second, routine);
    if (!dx || !dy || !dz) {
      why = fmt::format("the displacement of {} is computed at run time", fn);
      return std::nullopt;
    }
    base->d_mm = Vector3(*dx, *dy, *dz);
    base->offset = offs ? TargetRef::Offset::kOffs : TargetRef::Offset::kRelTool;
    for (const auto& [axis, span] : rotations) {
      const auto v = number_arg(span.first, span.second, routine);
      if (!v) {
        why = "the rotation of RelTool is computed at run time";
        return std::nullopt;
      }
      base->rot_deg[axis] = *v;
    }
    return base;
  }

  /// tooldata or wobjdata by name: declared here, given on the command line, or an error.
  std::optional<RapidValue> data_value(const Instruction& ins, Span at, const char* type, const char* option,
                                       const std::map<std::string, ExternalData>& external, int routine,
                                       std::string& why) const {
    const auto [b, e] = at;
    if (!(e == b + 1 && src_.is_ident(b))) {
      why = fmt::format("the {} is an expression evaluated at run time", type);
      return std::nullopt;
    }
    const std::string name = src_.str(b);
    if (scoped(name, routine) != nullptr) {
      const Decl* d = find_decl(name, type, routine, b, why);
      if (d != nullptr && !d->dims.empty()) {
        src_.fail(b, fmt::format("{} '{}' is an array: give one element", type, name));
      }
      return d == nullptr ? std::nullopt : std::optional<RapidValue>(d->value);
    }
    if (const auto ext = external.find(to_upper(name)); ext != external.end()) {
      return ext->second.value;
    }
    src_.fail(b, fmt::format("{}: {} '{}' is declared neither in this module nor with {} {}=[...]", ins.name, type,
                             name, option, name));
  }

  /// The tool and work object of a motion; nullopt with `why` when they cannot be used statically.
  std::optional<ToolWobj> tool_and_wobj(const Instruction& ins, int routine, std::string& why) const {
    ToolWobj tw;
    const auto [tb, te] = ins.args.back();
    // tool0 and wobj0 are predefined (the flange, the base frame) unless the module declares its own.
    if (!(te == tb + 1 && iequals(src_.str(tb), "tool0") && scoped("tool0", routine) == nullptr)) {
      const auto v = data_value(ins, ins.args.back(), "tooldata", "--tooldata", tools_, routine, why);
      if (!v) {
        return std::nullopt;
      }
      if (iequals(v->items[0].name, "FALSE")) {
        why = fmt::format("tool '{}' is stationary (robhold FALSE): not supported", src_.str(tb));
        return std::nullopt;
      }
      const auto p = rapid_pose(v->items[1]);
      if (!p) {
        src_.fail(tb, fmt::format("tooldata '{}': its quaternion is not of unit length", src_.str(tb)));
      }
      tw.tool = *p;
    }
    const auto it = ins.options.find("WOBJ");
    if (it == ins.options.end()) {
      return tw;
    }
    const auto [wb, we] = it->second;
    if (we == wb + 1 && iequals(src_.str(wb), "wobj0") && scoped("wobj0", routine) == nullptr) {
      return tw;
    }
    const auto v = data_value(ins, it->second, "wobjdata", "--wobjdata", wobjs_, routine, why);
    if (!v) {
      return std::nullopt;
    }
    if (iequals(v->items[0].name, "TRUE") || iequals(v->items[1].name, "FALSE") || v->items[2].name != "\"\"") {
      why = fmt::format("work object '{}' is held by the robot or moved by a mechanical unit: not supported",
                        src_.str(wb));
      return std::nullopt;
    }
    const auto uf = rapid_pose(v->items[3]);
    const auto of = rapid_pose(v->items[4]);
    if (!uf || !of) {
      src_.fail(wb, fmt::format("wobjdata '{}': a quaternion is not of unit length", src_.str(wb)));
    }
    tw.wobj = *uf * *of;
    return tw;
  }

  Instruction parse_instruction(std::size_t i, const Motion& m) const {
    Instruction ins;
    ins.tok = i;
    ins.name = m.name;
    std::size_t j = i + 1;
    while (j < src_.tok.size() && !src_.is_punct(j, ";")) {
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
      } else if (parts.size() == 1 && j > i + 1) {
        src_.fail(pb < j ? pb : i, fmt::format("{}: an empty argument", m.name));
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
        ins.options[opt] = src_.is_punct(ob + 1, ":=") ? Span{ob + 2, oe} : Span{oe, oe};
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

  /// ConfJ \On|\Off; and ConfL \On|\Off; at token i: the state they set. The controller refuses any
  /// other form, and so does deflex.
  std::size_t conf_instruction(std::size_t i, ConfState& state) const {
    const std::string name = src_.str(i);
    if (!(src_.is_punct(i + 1, "\\") && (src_.is_ident(i + 2, "On") || src_.is_ident(i + 2, "Off")) &&
          src_.is_punct(i + 3, ";"))) {
      src_.fail(i, fmt::format("{} takes one switch, \\On or \\Off: '{} \\On;' or '{} \\Off;'", name, name, name));
    }
    const int line = src_.is_ident(i + 2, "Off") ? src_.tok[i].line : 0;
    (iequals(name, "ConfJ") ? state.joint_off_line : state.linear_off_line) = line;
    return i + 3;
  }

  bool starts_statement(std::size_t i) const {
    return i == 0 || src_.is_punct(i - 1, ";") || src_.is_ident(i - 1, "THEN") || src_.is_ident(i - 1, "ELSE") ||
           src_.is_ident(i - 1, "DO") || src_.tok[i - 1].line != src_.tok[i].line;
  }

  // --- the walk over the program ---------------------------------------------------------------

  /// A resolved use of a motion's k-th target; false with the reason listed when it is not resolvable.
  bool resolve_use(const Instruction& ins, const Motion& m, std::size_t k, std::size_t force_index, const ToolWobj& tw,
                   const ConfState& conf, bool first_use, ProgramCompensation& result, ProgramTargetUse& u,
                   RapidUse& x) const {
    const auto [b, e] = ins.args[k];
    const int routine = routine_of_[ins.tok];
    const int line = src_.tok[ins.tok].line;
    const bool joint = iequals(m.name, "MoveAbsJ");
    const std::string written = src_.span(b, e);
    std::string why;
    const std::string type = joint ? "jointtarget" : "robtarget";
    const auto ref = target_ref(b, e, type, routine, why);
    if (!ref) {
      result.unresolved.push_back({src_.file, line, fmt::format("{} {}", m.name, written), why});
      return false;
    }
    u.file = src_.file;
    u.line = line;
    u.instruction = m.name;
    u.target = written;
    u.joint = joint;
    u.flange_T_tcp = tw.tool;
    u.force_index = force_index;
    const RapidValue& v = *ref->value;
    if (joint) {
      if (model_.dof() != 6) {
        src_.fail(b, fmt::format("{}: a jointtarget has 6 robot axes, the robot {}", m.name, model_.dof()));
      }
      u.q.resize(6);
      for (int j = 0; j < 6; ++j) {
        u.q[j] = deg_to_rad(v.items[0].items[static_cast<std::size_t>(j)].number);
      }
    } else {
      const auto q = rapid_quaternion(v.items[1]);
      if (!q) {
        src_.fail(b, fmt::format("{} {}: the orientation is not a unit quaternion", m.name, written));
      }
      Pose obj = Pose::Identity();
      obj.linear() = q->toRotationMatrix();
      obj.translation() =
          Vector3(v.items[0].items[0].number, v.items[0].items[1].number, v.items[0].items[2].number) * 1e-3;
      if (ref->offset == TargetRef::Offset::kOffs) {
        obj.translation() += ref->d_mm * 1e-3;
      } else if (ref->offset == TargetRef::Offset::kRelTool) {
        obj.translation() += obj.linear() * ref->d_mm * 1e-3;
        obj.linear() = obj.linear() * reltool_rotation(ref->rot_deg);
      }
      u.base_T_tcp = tw.wobj * obj;
      const auto& c = v.items[2].items;
      u.ik.configuration =
          ArmConfiguration{static_cast<int>(std::lround(c[0].number)), static_cast<int>(std::lround(c[1].number)),
                           static_cast<int>(std::lround(c[2].number)), static_cast<int>(std::lround(c[3].number))};
      u.ik.match_quadrants = true;
      const int off_line = m.conf == 'J' ? conf.joint_off_line : m.conf == 'L' ? conf.linear_off_line : 0;
      if (off_line > 0) {
        u.nearest_previous = true;
        u.configuration_rule = fmt::format("Conf{}\\Off (line {})", m.conf, off_line);
        x.conf_note =
            !first_use ? fmt::format("{}: the configuration nearest the previous target's", u.configuration_rule)
            : start_q_
                ? fmt::format("{}: the configuration nearest --seed-deg (the arm at the start)", u.configuration_rule)
                : fmt::format("{}, no earlier target and no --seed-deg: its own confdata", u.configuration_rule);
      }
    }
    x.ref = *ref;
    x.type = type;
    x.base_T_wobj = tw.wobj;
    x.instruction = m.name;
    x.line = line;
    x.written = written;
    return true;
  }

  /// Walks the program in the order of its text: every motion's targets resolved or listed.
  void collect(ProgramCompensation& result, std::vector<ProgramTargetUse>& uses, std::vector<RapidUse>& info) const {
    std::size_t force_index = 0;
    std::size_t motion_count = 0;
    ConfState conf;
    const Tokens& t = src_.tok;
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (t[i].kind != TokenKind::kIdentifier || decl_name_tokens_.count(i) != 0 ||
          (i > 0 && (src_.is_punct(i - 1, "\\") || src_.is_punct(i - 1, ".")))) {
        continue;
      }
      const std::string word = src_.str(i);
      if ((iequals(word, "ConfJ") || iequals(word, "ConfL")) && starts_statement(i)) {
        i = conf_instruction(i, conf);
        continue;
      }
      const auto m =
          std::find_if(motions().begin(), motions().end(), [&](const Motion& x) { return iequals(word, x.name); });
      if (m == motions().end()) {
        // Other motion instructions: their targets stay as they are, said so.
        if (other_motion(word) && !src_.is_punct(i + 1, ":=") && !src_.is_punct(i + 1, "(") && starts_statement(i)) {
          std::size_t j = i;
          while (j < t.size() && !src_.is_punct(j, ";")) {
            ++j;
          }
          ++motion_count;
          result.unresolved.push_back(
              {src_.file, t[i].line, src_.span(i, std::min(j + 1, t.size())),
               fmt::format("{} is not compensated by deflex (MoveL, MoveJ, MoveC and MoveAbsJ are)", word)});
          i = j;
        }
        continue;
      }
      const Instruction ins = parse_instruction(i, *m);
      ++motion_count;
      const std::size_t n_targets = iequals(m->name, "MoveC") ? 2 : 1;
      std::string why;
      const auto tw = tool_and_wobj(ins, routine_of_[i], why);
      for (std::size_t k = 0; k < n_targets; ++k) {
        const std::size_t index = force_index++;
        if (!tw) {
          result.unresolved.push_back({src_.file, t[i].line,
                                       fmt::format("{} {}", m->name, src_.span(ins.args[k].first, ins.args[k].second)),
                                       why});
          continue;
        }
        ProgramTargetUse u;
        RapidUse x;
        if (resolve_use(ins, *m, k, index, *tw, conf, uses.empty(), result, u, x)) {
          x.use_index = uses.size();
          info.push_back(x);
          uses.push_back(u);
        }
      }
      i = ins.end_tok;
    }
    if (motion_count == 0) {
      throw DataError(
          fmt::format("{}: no motion instruction (MoveL, MoveJ, MoveC, MoveAbsJ): nothing to compensate", src_.file));
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
  void compute_numbers(std::vector<RapidUse>& info, const std::vector<ProgramTargetResult>& results) const {
    for (RapidUse& x : info) {
      const ProgramTargetResult& r = results[x.use_index];
      const RapidValue& v = *x.ref.value;
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
          obj.linear() = obj.linear() * reltool_rotation(x.ref.rot_deg).transpose();
          obj.translation() -= obj.linear() * x.ref.d_mm * 1e-3;
        }
        const auto& q0v = v.items[1].items;
        const Eigen::Quaterniond q0(q0v[0].number, q0v[1].number, q0v[2].number, q0v[3].number);
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
  }

  /// The module with the new numbers written back (program_write_back.hpp).
  std::string write_back(const std::vector<RapidUse>& info, std::vector<std::string>& actions) const {
    const Tokens& t = src_.tok;
    std::vector<WriteBackUse> uses;
    for (const RapidUse& x : info) {
      WriteBackUse u;
      u.target = x.ref.literal ? nullptr : x.ref.value;  // a declaration's value node: one per element
      u.name = x.ref.literal ? std::string() : to_upper(x.ref.decl->name);
      for (const auto& [node, text] : x.numbers) {
        u.numbers.push_back(text);
      }
      uses.push_back(std::move(u));
    }
    const std::vector<WriteBackStep> steps = plan_write_back(uses, references_);
    std::set<std::string> taken;
    add_identifiers(src_, taken);
    const std::string eol = line_terminator(src_.text);
    std::vector<TextEdit> edits;
    actions.assign(info.size(), {});
    std::vector<std::string> names(info.size());  // the copy each use declares
    for (std::size_t a = 0; a < info.size(); ++a) {
      const RapidUse& x = info[a];
      const WriteBackStep& step = steps[a];
      if (step.kind != WriteBackStep::Kind::kCopy) {
        if (step.kind == WriteBackStep::Kind::kLiteral || step.first) {
          for (const auto& [node, text] : x.numbers) {
            edits.push_back({node->begin, node->end - node->begin, text});
          }
        }
        actions[a] = step.kind == WriteBackStep::Kind::kLiteral ? "literal edited" : "edited in place";
        continue;
      }
      if (step.first) {
        const Decl& d = *x.ref.decl;
        names[a] =
            copy_name(x.ref.element >= 0 ? fmt::format("{}{}", d.name, x.ref.element + 1) : d.name, "_c", 32, taken);
        const std::size_t at = end_of_line(src_.text, t[d.end_tok].end);
        const bool unterminated = at == src_.text.size() && src_.text.back() != '\n' && src_.text.back() != '\r';
        const RapidValue& v = *x.ref.value;
        std::vector<TextEdit> rel;
        for (const auto& [node, text] : x.numbers) {
          rel.push_back({node->begin - v.begin, node->end - node->begin, text});
        }
        edits.push_back({at, 0,
                         (unterminated ? eol : "") + indentation_of(src_.text, t[d.first_tok].begin) +
                             src_.text.substr(t[d.first_tok].begin, t[d.name_tok].begin - t[d.first_tok].begin) +
                             names[a] + ":=" + apply_edits(src_.text.substr(v.begin, v.end - v.begin), rel) + ";" +
                             eol});
      }
      const std::string& name = names[step.source];
      edits.push_back({t[x.ref.ref_b].begin, t[x.ref.ref_e - 1].end - t[x.ref.ref_b].begin, name});
      actions[a] = "copy " + name;
    }
    return apply_edits(src_.text, edits);
  }

  const RobotModel& model_;
  const ForceModel& force_;
  RapidSource src_;
  std::vector<int> routine_of_;
  std::vector<Decl> decls_;
  std::map<std::string, std::vector<std::size_t>> by_name_;
  std::set<std::size_t> decl_name_tokens_;
  std::map<std::string, int> references_;
  std::set<std::string> assigned_;
  std::map<std::string, ExternalData> tools_, wobjs_;
  mutable std::vector<std::unique_ptr<RapidValue>> literals_;
  std::optional<JointVector> start_q_;  // the arm's joints at the start (--seed-deg)
};

ProgramCompensation RapidReader::run(const std::string& output_path) {
  ProgramCompensation result;
  result.language = "RAPID";
  result.force_description = force_.describe();
  std::vector<ProgramTargetUse> uses;
  std::vector<RapidUse> info;
  collect(result, uses, info);
  const std::vector<ProgramTargetResult> results = compensate_program_targets(model_, uses, force_, start_q_);
  compute_numbers(info, results);
  std::vector<std::string> actions;
  const std::string text = write_back(info, actions);
  for (std::size_t a = 0; a < info.size(); ++a) {
    const RapidUse& x = info[a];
    result.targets.push_back(
        target_report(results[x.use_index], src_.file, x.line, x.instruction, x.written, actions[a]));
    result.targets.back().configuration_note = x.conf_note;
  }
  result.outputs.push_back({output_path, text});
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
