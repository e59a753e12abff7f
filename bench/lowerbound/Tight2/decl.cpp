#include "decl.h"

uint16_t twDescLength;
uint32_t twDescHash;

namespace {
uint16_t jPos, jStart;
uint8_t jLen;
uint8_t* jOut;

__attribute__((noinline)) void put(char c) {
  uint16_t at = jPos - jStart;
  if (jOut && jPos >= jStart && at < jLen) jOut[at] = (uint8_t)c;
  twDescHash = (twDescHash ^ (uint8_t)c) * 0x01000193UL;
  ++jPos;
}
__attribute__((noinline)) void flash(const char* p) {
  for (char c; (c = pgm_read_byte(p)); ++p) put(c);
}
// A quoted string from flash, with " and \ escaped.
__attribute__((noinline)) void text(const __FlashStringHelper* t) {
  const char* p = (const char*)t;
  put('"');
  for (char c; (c = pgm_read_byte(p)); ++p) {
    if (c == '"' || c == '\\') put('\\');
    put(c);
  }
  put('"');
}
__attribute__((noinline)) void uinteger(uint32_t v) {
  char d[10];
  uint8_t n = 0;
  do {
    d[n++] = (char)('0' + v % 10);
    v /= 10;
  } while (v);
  while (n) put(d[--n]);
}
void integer(int32_t v) {
  if (v < 0) {
    put('-');
    v = -v;
  }
  uinteger((uint32_t)v);
}
const char kTypes[] PROGMEM = "void\0bool\0u8\0\0\0i8\0\0\0u16\0\0i16\0\0u32\0\0i32\0\0f32";
}  // namespace

TwHub& TwHub::declare(const __FlashStringHelper* n, TwType t, uint8_t access) {
  finish();
  ++id_;
  chName_ = n;
  type_ = t;
  access_ = access;
  unit_ = nullptr;
  hasRange_ = false;
  pending_ = true;
  return *this;
}

void TwHub::finish() {
  if (!pending_) return;
  pending_ = false;
  if (id_ > 1) put(',');
  flash(PSTR("{\"id\":"));
  uinteger(id_);
  flash(PSTR(",\"n\":"));
  text(chName_);
  flash(PSTR(",\"a\":\""));
  uint8_t a = access_;
  for (const char* l = PSTR("rwces"); a; ++l, a >>= 1)
    if (a & 1) put(pgm_read_byte(l));
  flash(PSTR("\",\"t\":\""));
  flash(kTypes + type_ * 5);
  put('"');
  if (unit_) {
    flash(PSTR(",\"u\":"));
    text(unit_);
  }
  if (hasRange_) {
    flash(PSTR(",\"min\":"));
    integer(min_);
    flash(PSTR(",\"max\":"));
    integer(max_);
  }
  put('}');
}

void TwHub::describe() {
  flash(PSTR("{\"p\":1,\"n\":"));
  text(name_);
  flash(PSTR(",\"ch\":["));
  id_ = 0;
  pending_ = false;
  decls_();
  finish();
  put(']');
  put('}');
}

void twDescribe(uint16_t start, uint8_t len, uint8_t* out) {
  jPos = 0;
  jStart = start;
  jLen = len;
  jOut = out;
  twDescHash = 0x811C9DC5UL;  // every pass hashes the whole descriptor: always the same value
  hub.describe();
  if (!out) twDescLength = jPos;
}
