// key=value specification parser shared by the path and force specs.
#include "deflex/text/key_value_spec.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/nearest_name.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {

std::string trim_blanks(const std::string& text) {
  const auto b = text.find_first_not_of(" \t");
  if (b == std::string::npos) {
    return "";
  }
  const auto e = text.find_last_not_of(" \t");
  return text.substr(b, e - b + 1);
}

std::vector<std::string> split_trimmed(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, sep)) {
    out.push_back(trim_blanks(item));
  }
  if (!text.empty() && text.back() == sep) {
    out.emplace_back();
  }
  return out;
}

KeyValueSpec::KeyValueSpec(std::string spec, const std::string& body, std::vector<std::string> allowed)
    : spec_(std::move(spec)), allowed_(std::move(allowed)) {
  if (trim_blanks(body).empty()) {
    return;
  }
  for (const std::string& item : split_trimmed(body, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) {
      fail(fmt::format("'{}' is not key=value", item));
    }
    const std::string key = trim_blanks(item.substr(0, eq));
    bool known = false;
    for (const auto& a : allowed_) {
      known = known || a == key;
    }
    if (!known) {
      fail(
          fmt::format("unknown key '{}'{} (allowed: {})", key, did_you_mean(key, allowed_), fmt::join(allowed_, ", ")));
    }
    if (values_.count(key) != 0) {
      fail(fmt::format("key '{}' given twice", key));
    }
    values_[key] = trim_blanks(item.substr(eq + 1));
  }
}

void KeyValueSpec::fail(const std::string& message) const {
  throw InputError(fmt::format("spec '{}': {}", spec_, message));
}

std::vector<double> KeyValueSpec::numbers(const std::string& key, std::size_t count) const {
  std::vector<double> out;
  for (const std::string& part : split_trimmed(text(key), ';')) {
    const std::optional<double> v = parse_double(part);
    if (!v) {
      fail(fmt::format("key '{}': {}", key, not_a_number(part)));
    }
    if (const auto bad = range_violation(*v, range::kAnyValue)) {
      fail(fmt::format("key '{}': {}", key, *bad));
    }
    out.push_back(*v);
  }
  if (out.empty() || (count != 0 && out.size() != count)) {
    fail(fmt::format("key '{}': expected {} ';'-separated numbers, got {}", key,
                     count == 0 ? std::string("one or more") : std::to_string(count), out.size()));
  }
  return out;
}

double KeyValueSpec::number(const std::string& key, double fallback) const {
  return has(key) ? numbers(key, 1)[0] : fallback;
}

int KeyValueSpec::integer(const std::string& key, int fallback) const {
  if (!has(key)) {
    return fallback;
  }
  const double v = numbers(key, 1)[0];
  if (v != std::floor(v) || std::abs(v) > 1e9) {
    fail(fmt::format("key '{}': {} is not a whole number", key, v));
  }
  return static_cast<int>(v);
}

}  // namespace deflex
