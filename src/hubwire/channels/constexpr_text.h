// Text and numbers worked out by the compiler (C++11 constexpr): the pieces the descriptor JSON is
// made of. Nothing here runs on the board; it is evaluated while the sketch compiles.
#ifndef HUBWIRE_CHANNELS_CONSTEXPR_TEXT_H
#define HUBWIRE_CHANNELS_CONSTEXPR_TEXT_H

#include <stddef.h>
#include <stdint.h>

// Which of two ways to work text out: GCC before 10 remembers the value of every constexpr call
// (avr-gcc 5.4, the Debian Arduino compiler, also copies a constant whole at every read of any part
// of it), so there a character is found by a few remembered calls. clang remembers no call, and GCC
// from 10 on only calls nested less than -fconstexpr-cache-depth (8) deep: there the walks from the
// start of a text, and reads of the arrays already made, cost less.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ < 10
#define HUBWIRE_CX_REMEMBERS 1
#else
#define HUBWIRE_CX_REMEMBERS 0
#endif

namespace hubwire {
namespace cx {

// Index sequences (C++11 has none), built in log depth so that a 2 KB descriptor stays well inside
// the compiler's template depth.
template <size_t... I>
struct Seq {};
template <typename A, typename B>
struct Join;
template <size_t... A, size_t... B>
struct Join<Seq<A...>, Seq<B...> > {
  typedef Seq<A..., (sizeof...(A) + B)...> type;
};
template <size_t N>
struct MakeSeq {
  typedef typename Join<typename MakeSeq<N / 2>::type, typename MakeSeq<N - N / 2>::type>::type type;
};
template <>
struct MakeSeq<0> {
  typedef Seq<> type;
};
template <>
struct MakeSeq<1> {
  typedef Seq<0> type;
};

constexpr size_t length(const char* s) { return *s ? 1 + length(s + 1) : 0; }
constexpr bool equal(const char* a, const char* b) { return *a == *b && (*a == 0 || equal(a + 1, b + 1)); }

// ---- JSON strings: the characters between the quotes, escaped ----
constexpr const char* hexDigits() { return "0123456789abcdef"; }
constexpr size_t escapedLength(char c) { return c == '"' || c == '\\' ? 2 : (uint8_t)c < 0x20 ? 6 : 1; }
constexpr char escapedAt(char c, size_t i) {
  return escapedLength(c) == 1   ? c
         : escapedLength(c) == 2 ? (i == 0 ? '\\' : c)
                                 : (i == 0 ? '\\' : i == 1 ? 'u' : i < 4 ? '0' : i == 4 ? hexDigits()[(uint8_t)c >> 4] : hexDigits()[c & 15]);
}
// A text's escaped characters. Where calls are remembered, where the escaped text of s[j] starts is
// worked out once for each j, and character i found by a binary search over j (walking the text
// from its start for each character made a text cost the square of its length); elsewhere the walk
// takes fewer steps.
#if !HUBWIRE_CX_REMEMBERS
constexpr size_t escapedLength(const char* s) { return *s ? escapedLength(*s) + escapedLength(s + 1) : 0; }
constexpr char escapedAt(const char* s, size_t i) {
  return i < escapedLength(*s) ? escapedAt(*s, i) : escapedAt(s + 1, i - escapedLength(*s));
}
#else
constexpr size_t escapedBefore(const char* s, size_t j) { return j == 0 ? 0 : escapedBefore(s, j - 1) + escapedLength(s[j - 1]); }
// The length of a text that needs no escape (most texts), else kNotPlain: one walk, one call a
// character, where length() and escapedBefore() took two (avr-g++ 5.4, 32 channels with 60-character
// descriptions: their lengths 1.5 MB less).
const size_t kNotPlain = (size_t)-1;
constexpr size_t plainLength(const char* s) {
  return !*s ? 0 : escapedLength(*s) != 1 || plainLength(s + 1) == kNotPlain ? kNotPlain : plainLength(s + 1) + 1;
}
constexpr size_t escapedLength(const char* s) { return plainLength(s) != kNotPlain ? plainLength(s) : escapedBefore(s, length(s)); }
// The j of output character i: escapedBefore(s, lo) <= i < escapedBefore(s, hi).
constexpr size_t escapedSource(const char* s, size_t i, size_t lo, size_t hi) {
  return hi - lo == 1 ? lo
       : i < escapedBefore(s, (lo + hi) / 2) ? escapedSource(s, i, lo, (lo + hi) / 2)
                                             : escapedSource(s, i, (lo + hi) / 2, hi);
}
constexpr char escapedAt(const char* s, size_t i, size_t j) { return escapedAt(s[j], i - escapedBefore(s, j)); }
constexpr char escapedAt(const char* s, size_t i) {  // most texts need no escape: s[i] itself
  return plainLength(s) != kNotPlain ? s[i] : escapedAt(s, i, escapedSource(s, i, 0, length(s)));
}
#endif

// ---- integers ----
constexpr size_t digits(uint64_t v) { return v < 10 ? 1 : 1 + digits(v / 10); }
constexpr uint64_t pow10(size_t n) { return n ? 10 * pow10(n - 1) : 1; }
constexpr char digitAt(uint64_t v, size_t i) { return (char)('0' + v / pow10(digits(v) - 1 - i) % 10); }
constexpr uint64_t magnitude(int64_t v) { return v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v; }
constexpr size_t integerLength(int64_t v) { return (v < 0 ? 1 : 0) + digits(magnitude(v)); }
constexpr char integerAt(int64_t v, size_t i) {
  return v < 0 ? (i == 0 ? '-' : digitAt(magnitude(v), i - 1)) : digitAt(magnitude(v), i);
}

// ---- floats: integers exactly, other values with six rounded decimals, trailing zeros dropped;
// from 2^40 on (where six decimals mean nothing), nine significant digits and an exponent, which
// reads back as the same float: 1e20, -340282347e30. NaN and infinities (which JSON cannot carry)
// print as 0. The float is taken apart by exact scaling by two (no bit casts in constexpr), then
// worked on as integers: on AVR the compiler's own double is only 32 bits, so decimal arithmetic
// in floating point would not be exact. ----

constexpr bool printsAsZero(float v) { return v != v || v == 0 || v > 3.4028235e38f || v < -3.4028235e38f; }
constexpr float absolute(float v) { return v < 0 ? -v : v; }
// e such that 2^23 <= v / 2^e < 2^24 (v > 0, finite).
constexpr int exponentOf(float v, int e) {
  return v >= 16777216.0f ? exponentOf(v / 2, e + 1) : v < 8388608.0f ? exponentOf(v * 2, e - 1) : e;
}
constexpr float scaled(float v, int e) { return e > 0 ? scaled(v / 2, e - 1) : e < 0 ? scaled(v * 2, e + 1) : v; }
// v = mantissa * 2^exponent, mantissa < 2^24.
constexpr int exponentOfAbs(float v) { return exponentOf(absolute(v), 0); }
constexpr uint32_t mantissaOf(float v) { return (uint32_t)scaled(absolute(v), exponentOfAbs(v)); }

// Fraction bits kept below the point: at most 40, so that fraction * 10^7 fits 64 bits.
constexpr int fractionShift(float v) { return -exponentOfAbs(v) > 40 ? 40 : -exponentOfAbs(v); }
constexpr uint64_t integerPart(float v) {
  return exponentOfAbs(v) >= 0 ? (uint64_t)mantissaOf(v) << exponentOfAbs(v)  // only below 2^40
         : (-exponentOfAbs(v) >= 32 ? 0 : (uint64_t)(mantissaOf(v) >> -exponentOfAbs(v)));
}
constexpr uint64_t fractionBits(float v) {  // the fraction as a number of 2^-fractionShift units
  return exponentOfAbs(v) >= 0 ? 0
         : -exponentOfAbs(v) >= 104 ? 0  // below 2^-80: nothing left at 40 bits
         : -exponentOfAbs(v) > 40
             ? (uint64_t)mantissaOf(v) >> (-exponentOfAbs(v) - 40)
             : (uint64_t)mantissaOf(v) & (((uint64_t)1 << -exponentOfAbs(v)) - 1);
}
// Six decimals, rounded half up from the seventh (truncated), as the number 0..1000000.
constexpr uint64_t sixDecimals(float v) {
  return exponentOfAbs(v) >= 0 ? 0 : ((fractionBits(v) * 10000000) >> fractionShift(v)) / 10 + (((fractionBits(v) * 10000000) >> fractionShift(v)) % 10 >= 5 ? 1 : 0);
}
constexpr uint64_t wholePart(float v) { return integerPart(v) + (sixDecimals(v) == 1000000 ? 1 : 0); }
constexpr uint64_t decimals(float v) { return sixDecimals(v) == 1000000 ? 0 : sixDecimals(v); }
// Decimals after trailing zeros are dropped, and how many remain.
constexpr uint64_t trimmed(uint64_t d) { return d != 0 && d % 10 == 0 ? trimmed(d / 10) : d; }
constexpr size_t trailingZeros(uint64_t d) { return d != 0 && d % 10 == 0 ? 1 + trailingZeros(d / 10) : 0; }
constexpr size_t decimalCount(float v) { return decimals(v) == 0 ? 0 : 6 - trailingZeros(decimals(v)); }

// From 2^40 on: v = x * 10^k, x kept between 2^60 and 2^63 while the powers of two are multiplied
// in (each division by ten drops less than 2^-59 of the value), then rounded to nine digits.
struct Decimal {
  uint64_t x;
  int k;
};
constexpr Decimal toDecimal(uint64_t x, int twos, int k) {
  return twos == 0 ? Decimal{x, k} : x < ((uint64_t)1 << 62) ? toDecimal(x * 2, twos - 1, k) : toDecimal(x / 10, twos, k + 1);
}
constexpr bool large(float v) { return !printsAsZero(v) && exponentOfAbs(v) > 16; }
constexpr Decimal bigDecimal(float v) { return toDecimal(mantissaOf(v), exponentOfAbs(v), 0); }
constexpr uint64_t nineDigits(Decimal d) {  // rounded half up from the tenth digit
  return (d.x / pow10(digits(d.x) - 10) + 5) / 10;
}
constexpr Decimal rounded(Decimal d) {  // nine digits; 999999999.5 rounds up to 100000000 x 10
  return nineDigits(d) == 1000000000 ? Decimal{100000000, d.k + (int)digits(d.x) - 8}
                                     : Decimal{nineDigits(d), d.k + (int)digits(d.x) - 9};
}
constexpr Decimal significand(float v) {  // trailing zeros moved into the exponent
  return Decimal{trimmed(rounded(bigDecimal(v)).x), rounded(bigDecimal(v)).k + (int)trailingZeros(rounded(bigDecimal(v)).x)};
}
constexpr size_t largeLength(float v) {
  return digits(significand(v).x) + 1 + digits((uint64_t)significand(v).k);
}
constexpr char largeAt(float v, size_t i) {
  return i < digits(significand(v).x) ? digitAt(significand(v).x, i)
         : i == digits(significand(v).x) ? 'e'
                                         : digitAt((uint64_t)significand(v).k, i - digits(significand(v).x) - 1);
}

constexpr bool negative(float v) { return !printsAsZero(v) && v < 0; }
constexpr size_t floatLength(float v) {
  return printsAsZero(v) ? 1
         : (negative(v) ? 1 : 0) + (large(v) ? largeLength(v)
                                             : digits(wholePart(v)) + (decimalCount(v) ? 1 + decimalCount(v) : 0));
}
constexpr char decimalAt(float v, size_t i) {  // i-th of the six decimals
  return (char)('0' + decimals(v) / pow10(5 - i) % 10);
}
constexpr char floatAt(float v, size_t i) {
  return printsAsZero(v) ? '0'
         : negative(v)   ? (i == 0 ? '-' : floatAt(-v, i - 1))
         : large(v)      ? largeAt(v, i)
         : i < digits(wholePart(v)) ? digitAt(wholePart(v), i)
         : i == digits(wholePart(v)) ? '.'
                                     : decimalAt(v, i - digits(wholePart(v)) - 1);
}

}  // namespace cx
}  // namespace hubwire

#endif
