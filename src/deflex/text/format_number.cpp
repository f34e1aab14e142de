// "%.10g" without a big-number algorithm for the common range: see format_number.hpp.
#include "deflex/text/format_number.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace deflex {
namespace {

// Powers of ten that are exact doubles (10^22 is the largest).
constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                             1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

char* exact(char* out, double v) noexcept {
  return std::to_chars(out, out + kFormatG10MaxChars, v, std::chars_format::general, 10).ptr;
}

// The ten decimal digits of n < 10^10, leading zeros included.
void ten_digits(char* d, std::uint64_t n) noexcept {
  const auto hi = static_cast<unsigned>(n / 100000000U);  // 0..99
  auto lo = static_cast<unsigned>(n % 100000000U);
  std::memcpy(d, kDigitPairs + std::size_t{2} * hi, 2);
  for (int k = 8; k >= 2; k -= 2) {
    std::memcpy(d + k, kDigitPairs + std::size_t{2} * (lo % 100U), 2);
    lo /= 100U;
  }
}

// The `len` significant digits `d` of a number of decimal exponent `e` as %g writes them: with an
// exponent below 1e-4, else plain.
char* place_digits(char* p, const char* d, int len, int e) noexcept {
  if (e < -4) {  // d.ddde-XX; e >= -13 here, so two exponent digits
    *p++ = d[0];
    if (len > 1) {
      *p++ = '.';
      std::memcpy(p, d + 1, static_cast<std::size_t>(len - 1));
      p += len - 1;
    }
    const int x = -e;
    *p++ = 'e';
    *p++ = '-';
    *p++ = static_cast<char>('0' + x / 10);
    *p++ = static_cast<char>('0' + x % 10);
  } else if (e >= 0) {  // integer digits, then what is left of the ten
    const int whole_digits = e + 1;
    std::memcpy(p, d, static_cast<std::size_t>(whole_digits));
    p += whole_digits;
    if (len > whole_digits) {
      *p++ = '.';
      std::memcpy(p, d + whole_digits, static_cast<std::size_t>(len - whole_digits));
      p += len - whole_digits;
    }
  } else {  // 0.000ddd
    *p++ = '0';
    *p++ = '.';
    for (int k = 0; k < -e - 1; ++k) {
      *p++ = '0';
    }
    std::memcpy(p, d, static_cast<std::size_t>(len));
    p += len;
  }
  return p;
}

}  // namespace

char* format_g10(char* out, double v) noexcept {
  char* p = out;
  if (v == 0.0) {
    if (std::signbit(v)) {
      *p++ = '-';
    }
    *p++ = '0';
    return p;
  }
  const double a = std::fabs(v);
  if (!(a >= 1e-13 && a < 1e10)) {  // also NaN
    return exact(out, v);
  }
  // Decimal exponent e with 10^e <= a < 10^(e+1): floor(log2 a) * log10(2) is e or e - 1.
  std::uint64_t bits = 0;
  std::memcpy(&bits, &a, sizeof bits);
  const int b = static_cast<int>((bits >> 52) & 0x7FF) - 1023;
  int e = (b * 78913) >> 18;  // floor(b log10 2) for |b| < 1000
  // s = a 10^(9 - e), ten digits before the point. 10^(9 - e) is exact, so the product's one rounding
  // leaves s within half an ulp (< 1e-6, as s < 2^34) of the exact a 10^(9 - e).
  double s = 0.0;
  for (int attempt = 0;; ++attempt) {
    if (9 - e < 0 || 9 - e > 22 || attempt == 3) {
      return exact(out, v);
    }
    s = a * kPow10[9 - e];
    if (s >= 1e10) {
      ++e;
    } else if (s < 1e9) {
      --e;
    } else {
      break;
    }
  }
  const double whole = std::floor(s);
  const double frac = s - whole;  // exact: s and whole share their leading bits
  if (std::fabs(frac - 0.5) < 4e-6) {
    return exact(out, v);  // within the product's error of a rounding tie: only exact arithmetic decides
  }
  auto n = static_cast<std::uint64_t>(whole) + (frac > 0.5 ? 1U : 0U);
  if (n == 10000000000ULL) {  // 9.9999999996 -> 10.00000000
    n = 1000000000ULL;
    ++e;
  }
  if (e >= 10) {
    return exact(out, v);  // exponent form, rare here
  }
  char d[10];
  ten_digits(d, n);
  int len = 10;  // significant digits kept: trailing zeros are dropped, as %g does
  while (len > 1 && d[len - 1] == '0') {
    --len;
  }
  if (v < 0.0) {
    *p++ = '-';
  }
  return place_digits(p, d, len, e);
}

}  // namespace deflex
