// Text and numbers worked out by the compiler (C++11 constexpr): the pieces the descriptor JSON is
// made of. Nothing here runs on the board; it is evaluated while the sketch compiles.
#ifndef HUBWIRE_CHANNELS_CONSTEXPR_TEXT_H
#define HUBWIRE_CHANNELS_CONSTEXPR_TEXT_H

#include <stddef.h>
#include <stdint.h>

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
constexpr size_t escapedLength(const char* s) { return *s ? escapedLength(*s) + escapedLength(s + 1) : 0; }
constexpr char escapedAt(const char* s, size_t i) {
  return i < escapedLength(*s) ? escapedAt(*s, i) : escapedAt(s + 1, i - escapedLength(*s));
}

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
// NaN and infinities (which JSON cannot carry) as 0. The float is taken apart by exact scaling by
// two (no bit casts in constexpr), then worked on as integers: on AVR the compiler's own double is
// only 32 bits, so decimal arithmetic in floating point would not be exact. ----

// Called only for values the descriptor cannot print; being non-constexpr, it stops the build.
float range_or_failsafe_beyond_1e12_is_not_supported(float v);

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
  return exponentOfAbs(v) >= 0
             ? (exponentOfAbs(v) > 16 ? (uint64_t)range_or_failsafe_beyond_1e12_is_not_supported(v)
                                      : (uint64_t)mantissaOf(v) << exponentOfAbs(v))
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

constexpr bool negative(float v) { return !printsAsZero(v) && v < 0; }
constexpr size_t floatLength(float v) {
  return printsAsZero(v) ? 1 : (negative(v) ? 1 : 0) + digits(wholePart(v)) + (decimalCount(v) ? 1 + decimalCount(v) : 0);
}
constexpr char decimalAt(float v, size_t i) {  // i-th of the six decimals
  return (char)('0' + decimals(v) / pow10(5 - i) % 10);
}
constexpr char floatAt(float v, size_t i) {
  return printsAsZero(v) ? '0'
         : negative(v)   ? (i == 0 ? '-' : floatAt(-v, i - 1))
         : i < digits(wholePart(v)) ? digitAt(wholePart(v), i)
         : i == digits(wholePart(v)) ? '.'
                                     : decimalAt(v, i - digits(wholePart(v)) - 1);
}

}  // namespace cx
}  // namespace hubwire

#endif
