// RAPID source text as the program reader sees it (tokens with lines, for messages) and its
// literal values: aggregates [..], numbers, strings and names, with the byte range of every number
// so a compensated value is written back in place. check_rapid_value() holds a literal against the
// layout of a RAPID data type as strictly as the controller loads a module: a robtarget with five
// external axes, a three-element confdata or a name that is not a number stops with the file, the
// line and the field.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "deflex/model/types.hpp"
#include "deflex/offline/detail/program_tokens.hpp"

namespace deflex {

/// A RAPID module being read (program_tokens.hpp).
using RapidSource = ProgramSource;

/// A literal RAPID value: aggregates [..], numbers (a sign included), strings, names (TRUE/FALSE).
struct RapidValue {
  enum class Kind { kList, kNumber, kString, kName } kind = Kind::kNumber;
  double number = 0.0;
  std::size_t begin = 0, end = 0;  ///< bytes of the value in the text
  std::size_t token = 0;           ///< its first token, for messages
  std::string name;                ///< a string's or a name's text
  std::vector<RapidValue> items;
};

/// Parses a literal value at token i (before `end`); the index after it, or nullopt when the tokens
/// there are not a literal (an expression, a function call).
[[nodiscard]] std::optional<std::size_t> parse_rapid_value(const RapidSource& s, std::size_t i, std::size_t end,
                                                           RapidValue& v);

/// What check_rapid_value() found.
enum class RapidValueState {
  kLiteral,  ///< every number known
  kRunTime,  ///< a field names a num the program may change: its value is known only when it runs
};

/// The value of a num a literal names in a number field: nullopt when the module declares no num of
/// that name, otherwise the value (kRunTime when it is a VAR or PERS the program assigns).
struct NamedNum {
  double value = 0.0;
  bool constant = true;
};
using NumLookup = std::function<std::optional<NamedNum>(const std::string& name)>;

/// Checks `v` against RAPID type `type` (robtarget, jointtarget, tooldata, wobjdata, loaddata, pose,
/// pos, orient, confdata, num; other types pass) and replaces every name in a number field by the
/// value `lookup` gives. `fail(token, message)` reports a field that does not fit, e.g. "field
/// 'extax': 5 values, an extjoint has 6 (eax_a..eax_f)" or "field 'rot' component 1: 'nan' is not a
/// number, and no num of that name is declared"; it must throw.
RapidValueState check_rapid_value(RapidValue& v, const std::string& type, const NumLookup& lookup,
                                  const std::function<void(std::size_t token, const std::string& what)>& fail);

/// True when check_rapid_value() knows the type's layout.
[[nodiscard]] bool is_checked_rapid_type(const std::string& type);

/// A RAPID orientation [q1, q2, q3, q4] = [w, x, y, z], normalised; nullopt unless of unit length (1e-3).
[[nodiscard]] std::optional<Eigen::Quaterniond> rapid_quaternion(const RapidValue& orient);

/// A pose value [[x,y,z],[q1..q4]] (mm) as a Pose (m); nullopt unless the quaternion is of unit length.
[[nodiscard]] std::optional<Pose> rapid_pose(const RapidValue& pose);

}  // namespace deflex
