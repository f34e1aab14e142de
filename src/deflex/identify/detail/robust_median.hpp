// The median of many non-negative values (the identification's residual norms, a million of them) without a
// copy of them all.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace deflex {

/// The median of value(i) over i < m, each value >= 0 and not NaN: the middle value, for an even m
/// 0.5 * (the two middle values' sum), the same bits as std::nth_element on a copy gives, without the
/// copy (8 bytes a value: 8 MB of a million-row identification's peak). Non-negative doubles order like
/// their bit patterns, so a histogram of the top 16 bits finds the bucket(s) of the middle rank(s); only
/// the values in those buckets are copied and selected among (a few percent of them for values spread
/// over a few octaves; all of them at worst, when they share their top 16 bits). Two calls of value(i)
/// per i. Thread safety: no state of its own.
template <typename Value>
double median_of_nonnegative(std::size_t m, Value&& value) {
  if (m == 0) {
    return 0.0;
  }
  const auto top = [](double v) { return static_cast<std::size_t>(std::bit_cast<std::uint64_t>(v) >> 48); };
  std::vector<std::uint32_t> count(std::size_t{1} << 16, 0);
  for (std::size_t i = 0; i < m; ++i) {
    ++count[top(value(i))];
  }
  const std::size_t hi_rank = m / 2;
  const std::size_t lo_rank = m % 2 == 0 ? hi_rank - 1 : hi_rank;
  // The buckets of the two ranks, and the rank of the first value of the lower bucket.
  std::size_t below = 0, b = 0;
  while (below + count[b] <= lo_rank) {
    below += count[b++];
  }
  const std::size_t lo_bucket = b, lo_start = below;
  while (below + count[b] <= hi_rank) {
    below += count[b++];
  }
  const std::size_t hi_bucket = b;
  std::vector<double> v;
  v.reserve(below + count[hi_bucket] - lo_start);
  for (std::size_t i = 0; i < m; ++i) {
    const double x = value(i);
    const std::size_t t = top(x);
    if (t >= lo_bucket && t <= hi_bucket) {
      v.push_back(x);
    }
  }
  const auto at = [&](std::size_t rank) {
    const auto it = v.begin() + static_cast<std::ptrdiff_t>(rank - lo_start);
    std::nth_element(v.begin(), it, v.end());
    return *it;
  };
  const double hi = at(hi_rank);
  if (m % 2 != 0) {
    return hi;
  }
  // An even count: the mean of the middle value and the largest value below it.
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(hi_rank - lo_start)));
}

}  // namespace deflex
