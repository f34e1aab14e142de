// The one way deflex writes a number into a data file: printf's "%.10g" (10 significant digits,
// trailing zeros dropped, exponent form below 1e-4 and from 1e10), locale-free, into a caller's
// buffer with no allocation.
//
// Written here rather than calling std::to_chars(general, 10) for every number because a CSV row of
// offline compensation holds 46 numbers, and to_chars with a precision (an exact big-number
// printf algorithm) costs about 50 ns a number on our machines: 2.3 us a row, more than the
// compensation itself. format_g10 takes the common range (1e-13 <= |v| < 1e10) by one exact power
// of ten and one rounding in double, which is provably correct away from a rounding tie, and hands
// every other number (ties within the product's error, zero-adjacent magnitudes, huge ones, NaN,
// infinities) to std::to_chars, so the text is always exactly std::to_chars'. The tests hold it to
// std::to_chars over millions of numbers of every magnitude; bench/io_bench measures both.
#pragma once

namespace deflex {

/// Longest text format_g10 writes ("-1.234567891e-100"), with room to spare.
inline constexpr int kFormatG10MaxChars = 24;

/// Writes v as "%.10g" would (std::to_chars(first, last, v, std::chars_format::general, 10)) at
/// `out`, which must hold kFormatG10MaxChars chars; returns one past the last char written. No NUL.
char* format_g10(char* out, double v) noexcept;

}  // namespace deflex
