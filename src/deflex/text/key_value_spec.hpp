// The "key=value,key=value" option syntax of path and force specifications on the command line:
// keys carry their unit ("radius_mm", "force_N"), the components of one value are separated by ';'
// ("centre_mm=1500;0;1000"). Errors quote the whole spec and name the key.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace deflex {

/// Thread safety: immutable once parsed: any number of threads may share one.
class KeyValueSpec {
 public:
  /// Parses `body` (the part after "kind:"). `spec` is quoted in errors. Throws InputError on an
  /// item without '=', an unknown key (listing the allowed ones) or a key given twice.
  KeyValueSpec(std::string spec, const std::string& body, std::vector<std::string> allowed);

  [[noreturn]] void fail(const std::string& message) const;

  [[nodiscard]] bool has(const std::string& key) const { return values_.count(key) != 0; }
  [[nodiscard]] const std::string& text(const std::string& key) const { return values_.at(key); }
  /// The ';'-separated finite numbers of a key; `count` 0 accepts one or more.
  [[nodiscard]] std::vector<double> numbers(const std::string& key, std::size_t count) const;
  /// A single number, or `fallback` when the key is absent.
  [[nodiscard]] double number(const std::string& key, double fallback) const;
  /// A whole number (e.g. a point count), or `fallback`.
  [[nodiscard]] int integer(const std::string& key, int fallback) const;

 private:
  std::string spec_;
  std::vector<std::string> allowed_;
  std::map<std::string, std::string> values_;
};

/// Splits at `sep`, trimming blanks; "a,,b," gives {"a", "", "b", ""}.
[[nodiscard]] std::vector<std::string> split_trimmed(const std::string& text, char sep);
[[nodiscard]] std::string trim_blanks(const std::string& text);

}  // namespace deflex
