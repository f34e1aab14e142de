// format_g10 against the standard library's "%.10g" (std::to_chars, general, precision 10): the
// text must be byte for byte the same for every double, so these sweep every magnitude, the
// rounding ties and near-ties, the carries at powers of ten, and the numbers it hands over.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "deflex/text/format_number.hpp"

namespace deflex {
namespace {

std::string reference(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 10);
  return {buf, r.ptr};
}

std::string ours(double v) {
  char buf[kFormatG10MaxChars + 8];
  std::memset(buf, 'X', sizeof buf);
  char* end = format_g10(buf, v);
  EXPECT_LE(end - buf, kFormatG10MaxChars) << "wrote past the promised size for " << reference(v);
  return {buf, end};
}

// Counts mismatches and reports the first few by their exact bits, so a failure can be replayed.
struct Checker {
  int failures = 0;
  std::int64_t checked = 0;
  void operator()(double v) {
    ++checked;
    const std::string want = reference(v);
    const std::string got = ours(v);
    if (want != got && ++failures <= 10) {
      std::uint64_t bits = 0;
      std::memcpy(&bits, &v, sizeof bits);
      ADD_FAILURE() << "bits 0x" << std::hex << bits << ": std::to_chars gives '" << want << "', format_g10 '" << got
                    << "'";
    }
  }
};

TEST(FormatG10, SpecialValues) {
  EXPECT_EQ(ours(0.0), "0");
  EXPECT_EQ(ours(-0.0), "-0");
  EXPECT_EQ(ours(1.0), "1");
  EXPECT_EQ(ours(-2.5), "-2.5");
  EXPECT_EQ(ours(0.1), "0.1");
  EXPECT_EQ(ours(1e-5), "1e-05");
  EXPECT_EQ(ours(123456.7890123), "123456.789");
  EXPECT_EQ(ours(9999999999.6), "1e+10");
  Checker check;
  for (double v : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                   -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::max(),
                   std::numeric_limits<double>::min(), std::numeric_limits<double>::denorm_min(), 1e-13, 1e10, -1e10,
                   9.9999999995e9, 1e-4, 9.99999999995e-5, 0.0001, 1e9, 123456789012.0}) {
    check(v);
  }
  EXPECT_EQ(check.failures, 0);
}

TEST(FormatG10, RandomBitPatternsOfEveryMagnitude) {
  std::mt19937_64 rng(20261123);
  Checker check;
  for (int i = 0; i < 1000000; ++i) {
    std::uint64_t bits = rng();
    double v = 0.0;
    std::memcpy(&v, &bits, sizeof v);
    check(v);
  }
  EXPECT_EQ(check.failures, 0);
}

TEST(FormatG10, LogUniformOverTheFastRangeAndBeyond) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> exponent(-16.0, 12.0);
  Checker check;
  for (int i = 0; i < 2000000; ++i) {
    const double v = std::pow(10.0, exponent(rng));
    check(i % 2 == 0 ? v : -v);
  }
  EXPECT_EQ(check.failures, 0);
}

TEST(FormatG10, DecimalsWithFewDigitsAndTheirNeighbours) {
  // What deflex writes most: mm and degrees with a few decimals, quaternion parts, integers; and
  // the doubles next to them, whose 10th digit sits on either side of a rounding boundary.
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<std::int64_t> mantissa(0, 99999999999LL);
  std::uniform_int_distribution<int> scale(0, 20);
  Checker check;
  for (int i = 0; i < 500000; ++i) {
    const double v = static_cast<double>(mantissa(rng)) / std::pow(10.0, scale(rng));
    check(v);
    check(std::nextafter(v, 0.0));
    check(std::nextafter(v, HUGE_VAL));
  }
  EXPECT_EQ(check.failures, 0);
}

TEST(FormatG10, RoundingTiesAndTheirNeighbours) {
  // n + 0.5 at the 10th digit: exact ties (to even) and the doubles just beside them, where the
  // fast path must hand over because its product could land on either side.
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<std::int64_t> digits(1000000000LL, 9999999999LL);
  std::uniform_int_distribution<int> exponent(-14, 12);
  Checker check;
  for (int i = 0; i < 300000; ++i) {
    const int e = exponent(rng);
    const double v = (static_cast<double>(digits(rng)) + 0.5) * std::pow(10.0, e - 9);
    double w = std::nextafter(std::nextafter(v, 0.0), 0.0);
    for (int k = 0; k < 5; ++k, w = std::nextafter(w, HUGE_VAL)) {
      check(w);
    }
  }
  // Exact ties in binary: ten digits and a half with nothing after (e = 9: x.5 itself is a double).
  for (std::int64_t n = 1000000000LL; n < 1000000000LL + 20000; ++n) {
    check(static_cast<double>(n) + 0.5);
    check(static_cast<double>(n) / 2.0 + 0.25);
  }
  EXPECT_EQ(check.failures, 0);
}

TEST(FormatG10, CarriesAtEveryPowerOfTen) {
  Checker check;
  for (int e = -20; e <= 20; ++e) {
    const double p = std::pow(10.0, e);
    double w = p;
    for (int k = 0; k < 50; ++k) {
      w = std::nextafter(w, 0.0);
      check(w);
      check(-w);
    }
    w = p;
    for (int k = 0; k < 50; ++k) {
      check(w);
      w = std::nextafter(w, HUGE_VAL);
    }
    check(p * 0.99999999995);
    check(p * 0.999999999949);
    check(p * 0.999999999951);
  }
  EXPECT_EQ(check.failures, 0);
}

}  // namespace
}  // namespace deflex
