// KUKA KRL source text as the program reader sees it (tokens grouped by line) and its aggregates
// {X 1800.0,Y -300.0,...,S 'B110',T 10}: the value and byte range of every component, so a
// compensated point is written back number by number. check_krl_point() holds a point's components
// against its type (E6POS, POS, FRAME, E6AXIS, AXIS) as the controller does when it loads the .dat.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "deflex/model/types.hpp"
#include "deflex/offline/detail/program_tokens.hpp"

namespace deflex {

using KrlRange = std::pair<std::size_t, std::size_t>;  // tokens [first, last)

/// A .src or .dat file (program_tokens.hpp) and the tokens of each of its non-empty lines.
struct KrlFile : ProgramSource {
  std::vector<KrlRange> lines;
  KrlFile(std::string f, const std::string& t);
};

/// One component of an aggregate {NAME value, ...}.
struct KrlComponent {
  std::string name;  ///< upper case
  enum class Kind { kNumber, kBits, kOther } kind = Kind::kOther;
  double number = 0.0;
  std::size_t begin = 0, end = 0;  ///< bytes of the value, a sign included
  std::size_t token = 0;           ///< the component's name token, for messages
  int bit_digits = 0;              ///< 'B0110': 4
};

struct KrlAggregate {
  std::vector<KrlComponent> comps;
  std::size_t begin = 0, end = 0;  ///< bytes, braces included
  std::string type;                ///< "E6POS" of {E6POS: ...}, empty when untyped
  [[nodiscard]] const KrlComponent* find(const char* name) const;
  /// True when every name is a component with a number (or bit literal) value.
  [[nodiscard]] bool numbers(std::initializer_list<const char*> names) const;
};

/// {[TYPE:] NAME value, ...} at token i (before `end`); the index after it, or nullopt when the
/// tokens there are not a literal aggregate. A bit literal that is not one is an error.
[[nodiscard]] std::optional<std::size_t> parse_krl_aggregate(const KrlFile& f, std::size_t i, std::size_t end,
                                                             KrlAggregate& a);

/// The point types deflex reads.
[[nodiscard]] bool krl_cartesian_type(const std::string& type);  ///< E6POS, POS, FRAME
[[nodiscard]] bool krl_axis_type(const std::string& type);       ///< E6AXIS, AXIS

/// Checks a point's components against its type (`type` empty: an inline target, any point
/// component): a known name, given once, a number (Status and Turn may be bit literals). Throws
/// DataError naming the file, the line and the component.
void check_krl_point(const KrlFile& f, const KrlAggregate& a, const std::string& type, const std::string& what);

/// KRL frame {X, Y, Z (mm), A, B, C (deg)}: R = Rz(A) Ry(B) Rx(C); absent components are 0.
[[nodiscard]] Pose krl_frame(const KrlAggregate& a);

/// A, B, C (deg) of a rotation, of the two Euler triples the one nearest `near`, each on the same
/// turn as `near`'s angle.
[[nodiscard]] Vector3 krl_abc(const Matrix3& r, const Vector3& near);

/// A Status or Turn in KRL's bit notation, at least `digits` digits: 'B0110'.
[[nodiscard]] std::string krl_bits(int value, int digits);

}  // namespace deflex
