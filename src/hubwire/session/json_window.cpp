#include "json_window.h"

#include <string.h>

#include "protocol.h"

namespace hubwire {

void JsonWindow::put(char c) {
  if (out_ && pos_ >= start_ && pos_ - start_ < len_) out_[pos_ - start_] = (uint8_t)c;
  hash_ = fnv1a(hash_, (uint8_t)c);
  ++pos_;
}

namespace {
const uint8_t kFragmentStride = 8;
const char kFragments[] HUBWIRE_FLASH =
    "{\"p\":\0\0\0"
    ",\"n\":\0\0\0"
    ",\"fw\":\0\0"
    ",\"ch\":[\0"
    "{\"id\":\0\0"
    ",\"a\":\"\0\0"
    ",\"t\":\"\0\0"
    ",\"c\":\0\0\0"
    ",\"f\":[\0\0"
    ",\"rt\":\"\0"
    ",\"u\":\0\0\0"
    ",\"min\":\0"
    ",\"max\":\0"
    ",\"fs\":\0\0"
    ",\"d\":\0\0\0"
    "{\"n\":";
static_assert(sizeof(kFragments) == kFragField * kFragmentStride + 6, "fragments are kFragmentStride apart");
}  // namespace

void JsonWindow::flash(const char* s) {
  Text t = flashText(s);
  for (uint8_t i = 0; char c = t.at(i); ++i) put(c);
}

void JsonWindow::fragment(Fragment f) { flash(kFragments + f * kFragmentStride); }

void JsonWindow::text(Text t) {
  put('"');
  for (uint16_t i = 0; t.ptr; ++i) {
    char c = t.at(i);
    if (c == 0) break;
    if (c == '"' || c == '\\') {
      put('\\');
      put(c);
    } else if ((uint8_t)c < 0x20) {  // control characters: \u00XX
      put('\\');
      put('u');
      put('0');
      put('0');
      put((char)('0' + ((uint8_t)c >> 4)));  // c < 0x20: the high digit is 0 or 1
      put((char)((c & 15) < 10 ? '0' + (c & 15) : 'a' + (c & 15) - 10));
    } else {
      put(c);
    }
  }
  put('"');
}

void JsonWindow::uinteger(uint32_t v) {
  char digits[10];
  uint8_t n = 0;
  do {
    digits[n++] = (char)('0' + v % 10);
    v /= 10;
  } while (v);
  while (n) put(digits[--n]);
}

void JsonWindow::integer(int32_t v) {
  if (v < 0) put('-');
  uinteger(v < 0 ? 0u - (uint32_t)v : (uint32_t)v);
}

// Integers exactly (any size), other values with six rounded decimals, trailing zeros dropped. Only
// integer arithmetic on the float's bits: the soft-float add, multiply and divide routines this
// would otherwise pull in cost about 1 KB of flash on AVR.
void JsonWindow::number(float v) {
  uint32_t bits;
  memcpy(&bits, &v, sizeof(bits));
  uint8_t exp = (uint8_t)(bits >> 23);
  uint32_t mant = bits & 0x7FFFFFUL;
  if (exp == 0xFF || (bits << 1) == 0) {  // inf and NaN have no JSON form; +0 and -0 print as 0
    put('0');
    return;
  }
  if (bits & 0x80000000UL) put('-');
  if (exp == 0) {
    exp = 1;  // subnormal: no implicit leading 1
  } else {
    mant |= 0x800000UL;
  }
  int16_t e = (int16_t)(exp - 150);  // v = mant * 2^e
  if (e >= 0) {
    char d[40];  // decimal digits, least significant first: mant, then doubled e times
    uint8_t n = 0;
    do {
      d[n++] = (char)(mant % 10);
      mant /= 10;
    } while (mant);
    for (; e > 0; --e) {
      uint8_t carry = 0;
      for (uint8_t i = 0; i < n; ++i) {
        uint8_t x = (uint8_t)(d[i] * 2 + carry);
        d[i] = (char)(x % 10);
        carry = x / 10;
      }
      if (carry) d[n++] = (char)carry;
    }
    while (n) put((char)('0' + d[--n]));
    return;
  }
  uint8_t shift = (uint8_t)(-e);  // v = mant / 2^shift
  uint32_t ip = 0, frac;
  if (shift <= 28) {
    ip = shift < 24 ? mant >> shift : 0;
    frac = mant & ((1UL << shift) - 1);
  } else {
    // Below 2^-4: keep 28 fraction bits, plenty for 6 decimals. mant < 2^24, so from a shift of 24
    // on nothing is left (and shifting a 32-bit value by 32 or more is undefined).
    frac = shift - 28 < 24 ? mant >> (shift - 28) : 0;
    shift = 28;
  }
  char d[7];
  for (uint8_t i = 0; i < 7; ++i) {  // frac * 10 < 2^32 because frac < 2^28
    frac *= 10;
    d[i] = (char)(frac >> shift);
    frac &= (1UL << shift) - 1;
  }
  if (d[6] >= 5) {  // round to six decimals, carrying into the integer part if need be
    int8_t i = 5;
    while (i >= 0 && d[i] == 9) d[i--] = 0;
    if (i >= 0) {
      ++d[i];
    } else {
      ++ip;
    }
  }
  uinteger(ip);
  int8_t last = 5;
  while (last >= 0 && d[last] == 0) --last;
  if (last < 0) return;
  put('.');
  for (int8_t i = 0; i <= last; ++i) put((char)('0' + d[i]));
}

}  // namespace hubwire
