#include "json_window.h"

#include "protocol.h"

namespace hubwire {

void JsonWindow::put(char c) {
  if (out_ && pos_ >= start_ && pos_ - start_ < len_) out_[pos_ - start_] = (uint8_t)c;
  hash_ = fnv1a(hash_, (uint8_t)c);
  ++pos_;
}

void JsonWindow::raw(const char* s) {
  while (*s) put(*s++);
}

void JsonWindow::text(Text t) {
  put('"');
  for (uint16_t i = 0; t.ptr; ++i) {
    char c = t.at(i);
    if (c == 0) break;
    if (c == '"' || c == '\\') {
      put('\\');
      put(c);
    } else if ((uint8_t)c < 0x20) {  // control characters: \u00XX
      static const char kHex[] = "0123456789abcdef";
      raw("\\u00");
      put(kHex[(uint8_t)c >> 4]);
      put(kHex[c & 15]);
    } else {
      put(c);
    }
  }
  put('"');
}

void JsonWindow::key(Text k) {
  if (needComma_) put(',');
  needComma_ = true;
  text(k);  // keys are plain letters: quoting is all the escaping they need
  put(':');
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

// Up to 6 decimals, trailing zeros dropped: exact for integers and for the short decimal constants
// sketches use as ranges (0.5, -1, 3.3). Magnitudes of 4e9 and more are written in exponent form.
void JsonWindow::number(double v) {
  if (v != v) v = 0;  // NaN has no JSON form
  if (v < 0) {
    put('-');
    v = -v;
  }
  int exp10 = 0;
  while (v >= 4e9) {
    v /= 10;
    ++exp10;
  }
  uint32_t ip = (uint32_t)v;
  uint32_t frac = (uint32_t)((v - ip) * 1e6 + 0.5);
  if (frac >= 1000000UL) {
    ++ip;
    frac -= 1000000UL;
  }
  uinteger(ip);
  if (frac) {
    put('.');
    char d[6];
    for (int i = 5; i >= 0; --i) {
      d[i] = (char)('0' + frac % 10);
      frac /= 10;
    }
    int last = 5;
    while (d[last] == '0') --last;
    for (int i = 0; i <= last; ++i) put(d[i]);
  }
  if (exp10) {
    put('e');
    uinteger((uint32_t)exp10);
  }
}

}  // namespace hubwire
